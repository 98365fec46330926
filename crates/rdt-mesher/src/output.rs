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

/// A facet's measures: smallest angle, r / sigma (and whether it is exact, or an upper bound
/// from `crate::restricted::vertex_sizes`), distance ratio, bad.
type Measure = (f64, Option<(f64, bool)>, Option<f64>, bool);

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
        // r / sigma: an upper bound r / lb where the vertices give one, else exact; the
        // bounded facets whose bound exceeds the largest exact value are then evaluated
        // exactly, so the maximum is exact.
        let r_over_sigma = |rf: &RFacet| -> Option<(f64, bool)> {
            match self.sigma_bounds(rf.oriented, rf.center) {
                Some((lb, _)) => Some((rf.radius / lb, false)),
                None => criteria.sigma_at(rf.center).map(|s| (rf.radius / s, true)),
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
        let mut bounded = Vec::new();
        for (i, &(angle, rs, dist, bad)) in measures.iter().enumerate() {
            ext.min_angle = ext.min_angle.min(angle);
            match rs {
                Some((v, true)) => ext.max_rs = max_opt(ext.max_rs, Some(v)),
                Some((v, false)) => bounded.push((i, v)),
                None => {}
            }
            ext.max_dist = max_opt(ext.max_dist, dist);
            ext.all_good &= !bad;
        }
        let above = |v: f64| ext.max_rs.is_none_or(|m| v > m);
        let exact: Vec<usize> = bounded
            .into_iter()
            .filter(|&(_, v)| above(v))
            .map(|(i, _)| i)
            .collect();
        let values = self.policy.field(exact.len()).map(&exact, |&i| {
            let rf = &facets[i];
            criteria.sigma_at(rf.center).map(|s| rf.radius / s)
        });
        for v in values {
            ext.max_rs = max_opt(ext.max_rs, v);
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
