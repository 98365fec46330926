//! The output of section 6.1's algorithm: the facets of Del_S(E) as an oriented mesh, with
//! their surface Delaunay balls, the figures of the run and the criteria that do not hold.

use crate::criteria::min_angle_deg;
use crate::error::MeshError;
use crate::restricted::RFacet;
use crate::state::Mesher;
use crate::stats::{MeshResult, SurfaceBall, Unmet};
use delaunay3::VertexId;
use glam::DVec3;
use meshio::TriMesh;

/// A facet's measures: smallest angle, r / sigma, distance ratio, bad.
type Measure = (f64, Option<RoverSigma>, Option<f64>, bool);

/// A facet's r / sigma(c): exact, or bounds from sigma at its vertices
/// (`crate::restricted::vertex_sizes`).
#[derive(Clone, Copy, Debug)]
enum RoverSigma {
    Exact(f64),
    Bounded { lower: f64, upper: f64 },
}

/// Facets whose r / sigma is evaluated exactly at a time when the maximum is made exact
/// (large enough to run in parallel, small enough to stop soon after the bounds decide).
const EXACT_CHUNK: usize = 4096;

/// The extreme measures over the output facets.
struct Extremes {
    min_angle: f64,
    max_rs: Option<f64>,
    max_dist: Option<f64>,
    all_good: bool,
}

impl Mesher<'_> {
    /// The mesh of Del_S(E) and the run's figures (lazy balls resolved; facets at scaffold
    /// points, left only by a budget stop, left out and reported).
    pub(crate) fn finish(mut self) -> Result<MeshResult, MeshError> {
        // Lazy facets are left only by a budget stop: they are in the mesh, with their balls.
        self.resolve_all_lazy()?;
        self.stats.memory = self.memory();
        // What the output does not read is freed before it is built (the peak of a run is
        // here: the structures and the output at once).
        self.voronoi = Default::default();
        self.queue = Default::default();
        // The figures that read Del_S(E)'s indexes, before its facets are moved out of it.
        let nonmanifold = match self.manifold.last.take() {
            Some((n, r)) if n == self.tri.num_vertices() => r,
            _ => self.nonmanifold_elements(),
        };
        let missing = self
            .control
            .vertices
            .iter()
            .filter(|&&v| self.restricted.facets_at(v) == 0)
            .count();
        // Moved, not copied (a copy of the facets was the run's peak), sorted by key.
        let mut facets = self.restricted.take_sorted();
        // A run stopped by a budget may still have facets at scaffold points: not part of
        // the mesh of S (the stop is reported; the criteria are unmet anyway).
        let before = facets.len();
        if self.scaffold.count() > 0 {
            facets.retain(|rf| !rf.oriented.iter().any(|&v| self.scaffold.contains(v)));
        }
        let scaffold_dropped = before - facets.len();
        let mesh = self.mesh_of(&facets);
        let balls: Vec<SurfaceBall> = facets
            .iter()
            .map(|rf| SurfaceBall {
                center: rf.center,
                radius: rf.radius,
            })
            .collect();
        self.fill_vertex_sizes(facets.iter().flat_map(|rf| rf.oriented));
        let ext = self.extremes(&facets);
        self.fill_stats(&mesh, &ext, scaffold_dropped, nonmanifold, missing);
        let sample = (0..self.tri.num_vertices())
            .map(VertexId::from_index)
            .filter(|&v| !self.scaffold.contains(v))
            .map(|v| self.tri.point(v))
            .collect();
        Ok(MeshResult {
            mesh,
            balls,
            sample,
            stats: self.stats,
        })
    }

    /// The facets as a mesh on their vertices, in id order.
    fn mesh_of(&self, facets: &[RFacet]) -> TriMesh {
        let mut remap = vec![u32::MAX; self.tri.num_vertices()];
        for rf in facets {
            for &v in &rf.oriented {
                remap[v.index()] = 0;
            }
        }
        let mut used: Vec<VertexId> = Vec::new();
        for (v, r) in remap.iter_mut().enumerate() {
            if *r == 0 {
                *r = used.len() as u32;
                used.push(VertexId::from_index(v));
            }
        }
        let vertices: Vec<DVec3> = used.iter().map(|&v| self.tri.point(v)).collect();
        let triangles: Vec<[u32; 3]> = facets
            .iter()
            .map(|rf| rf.oriented.map(|v| remap[v.index()]))
            .collect();
        TriMesh {
            vertices,
            triangles,
        }
    }

    /// Per-facet measures (in parallel when the tuner says it pays), then min / max
    /// (order-independent).
    fn extremes(&self, facets: &[RFacet]) -> Extremes {
        let (tri, criteria) = (&self.tri, &self.opts.criteria);
        // r / sigma: bounds [r / ub, r / lb] where the vertices give them, else exact. The
        // maximum is then made exact by evaluating the bounded facets in decreasing order of
        // their upper bound r / lb, in chunks, until the next upper bound is not above the
        // largest value known (exact values, and the lower bounds r / ub, each of which some
        // exact value reaches). The result is the exact maximum, whatever the chunking.
        let r_over_sigma = |rf: &RFacet| -> Option<RoverSigma> {
            match self.sigma_bounds(rf.oriented, rf.center) {
                Some((lb, ub)) => Some(RoverSigma::Bounded {
                    lower: rf.radius / ub,
                    upper: rf.radius / lb,
                }),
                None => criteria
                    .sigma_at(rf.center)
                    .map(|s| RoverSigma::Exact(rf.radius / s)),
            }
        };
        let measure = |rf: &RFacet| -> Measure {
            let pts = rf.oriented.map(|v| tri.point(v));
            let rs = r_over_sigma(rf);
            let dist = criteria.distance_ratio(pts, rf.center);
            (min_angle_deg(pts), rs, dist, rf.bad > 1.0)
        };
        let measures = self.policy.batch().map(facets, measure);
        let max_opt = |a: Option<f64>, b: Option<f64>| match (a, b) {
            (Some(x), Some(y)) => Some(x.max(y)),
            (x, None) | (None, x) => x,
        };
        let mut ext = Extremes {
            min_angle: f64::INFINITY,
            max_rs: None,
            max_dist: None,
            all_good: true,
        };
        // Largest exact value or lower bound: the maximum is at least this.
        let mut known: Option<f64> = None;
        let mut bounded = Vec::new();
        for (i, &(angle, rs, dist, bad)) in measures.iter().enumerate() {
            ext.min_angle = ext.min_angle.min(angle);
            match rs {
                Some(RoverSigma::Exact(v)) => {
                    ext.max_rs = max_opt(ext.max_rs, Some(v));
                    known = max_opt(known, Some(v));
                }
                Some(RoverSigma::Bounded { lower, upper }) => {
                    known = max_opt(known, Some(lower));
                    bounded.push((upper, i));
                }
                None => {}
            }
            ext.max_dist = max_opt(ext.max_dist, dist);
            ext.all_good &= !bad;
        }
        // Those that may exceed what is known, by decreasing upper bound (then index: a
        // total order).
        bounded.retain(|b| known.is_none_or(|m| b.0 > m));
        bounded.sort_unstable_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        let mut next = 0;
        while next < bounded.len() && known.is_none_or(|m| bounded[next].0 > m) {
            let end = (next + EXACT_CHUNK).min(bounded.len());
            let chunk: Vec<usize> = bounded[next..end]
                .iter()
                .take_while(|b| known.is_none_or(|m| b.0 > m))
                .map(|b| b.1)
                .collect();
            next += chunk.len();
            let values = self.policy.field(chunk.len()).map(&chunk, |&i| {
                let rf = &facets[i];
                criteria.sigma_at(rf.center).map(|s| rf.radius / s)
            });
            for v in values {
                ext.max_rs = max_opt(ext.max_rs, v);
                known = max_opt(known, v);
            }
        }
        ext
    }

    /// The figures of the run and the unmet criteria, into `self.stats`.
    fn fill_stats(
        &mut self,
        mesh: &TriMesh,
        ext: &Extremes,
        scaffold_dropped: usize,
        (bad_edges, bad_vertices): (Vec<[VertexId; 2]>, Vec<VertexId>),
        missing: usize,
    ) {
        let sample_points = self.sample_points();
        let st = &mut self.stats;
        st.vertices = mesh.vertices.len();
        st.facets = mesh.triangles.len();
        st.sample_points = sample_points;
        st.control_points_missing = missing;
        st.oracle_value_calls = self.values;
        st.oracle_crossing_calls = self.crossing_calls;
        st.parallel_oracle_batches = self.policy.parallel_oracle_batches;
        [st.sequential_batches, st.parallel_batches] = self.policy.tuner.batches;
        st.time_total_s = self.start.elapsed().as_secs_f64();
        st.time_delaunay_s = self.t_delaunay.as_secs_f64();
        st.time_oracle_s = self.t_oracle.as_secs_f64();
        st.time_queue_s = (st.time_total_s - st.time_delaunay_s - st.time_oracle_s).max(0.0);
        st.max_r_over_sigma = ext.max_rs;
        st.max_distance_ratio = ext.max_dist;
        st.min_angle_deg = if ext.min_angle.is_finite() {
            ext.min_angle
        } else {
            0.0
        };
        st.nonmanifold_edges = bad_edges.len();
        st.nonmanifold_vertices = bad_vertices.len();
        let mut unmet = Vec::new();
        if let Some(m) = ext.max_rs.filter(|&m| m > 1.0) {
            unmet.push(Unmet::Size {
                max_r_over_sigma: m,
            });
        }
        let a = self.opts.criteria.min_angle_deg;
        if a > 0.0 && !ext.all_good && st.min_angle_deg < a {
            unmet.push(Unmet::Angle {
                min_angle_deg: st.min_angle_deg,
                bound_deg: a,
            });
        }
        if let Some(m) = ext.max_dist.filter(|&m| m > 1.0) {
            unmet.push(Unmet::Distance { max_ratio: m });
        }
        if scaffold_dropped > 0 {
            unmet.push(Unmet::Scaffold {
                facets: scaffold_dropped,
            });
        }
        if self.opts.manifold && (!bad_edges.is_empty() || !bad_vertices.is_empty()) {
            unmet.push(Unmet::Manifold {
                edges: bad_edges.len(),
                vertices: bad_vertices.len(),
            });
        }
        if missing > 0 {
            unmet.push(Unmet::ControlPoints { missing });
        }
        st.criteria_met = ext.all_good && unmet.is_empty();
        st.unmet = unmet;
    }
}
