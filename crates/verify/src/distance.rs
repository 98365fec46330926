//! Distances between a mesh and a surface: point-triangle distance, exact nearest triangle
//! through the BVH, one- and two-sided Hausdorff estimates, normal deviation.

use glam::DVec3;
use meshio::TriMesh;
use oracle::Surface;
use rayon::prelude::*;
use serde::Serialize;

use geom::bvh::TriangleBvh;

use crate::level_set::{LevelSet, Precision};

/// Exact nearest-triangle queries on a mesh (branch and bound on the BVH).
///
/// Distances come from [`geom::closest::closest_point_triangle`] (degenerate triangles
/// included).
pub struct MeshDistance<'a> {
    bvh: &'a TriangleBvh,
}

impl<'a> MeshDistance<'a> {
    /// Queries on `mesh` through `bvh` (built by [`crate::intersect::triangle_bvh`]).
    pub fn new(mesh: &'a TriMesh, bvh: &'a TriangleBvh) -> Self {
        debug_assert_eq!(bvh.len(), mesh.triangles.len(), "bvh built on another mesh");
        MeshDistance { bvh }
    }
    /// Nearest triangle to `p` and the distance (smallest index on ties).
    pub fn nearest(&self, p: DVec3) -> Option<(usize, f64)> {
        self.bvh.nearest(p).map(|(t, d2)| (t as usize, d2.sqrt()))
    }
}

/// Statistics of a set of distances.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct DistanceStats {
    pub samples: usize,
    pub max: f64,
    pub mean: f64,
    pub rms: f64,
    /// Where the maximum is attained.
    pub argmax: Option<[f64; 3]>,
}

/// Running statistics; merged in a fixed order so results do not depend on threads.
#[derive(Clone, Copy, Debug, Default)]
struct Acc {
    n: usize,
    max: f64,
    argmax: Option<DVec3>,
    sum: f64,
    sumsq: f64,
}

impl Acc {
    fn add(&mut self, p: DVec3, d: f64) {
        if self.argmax.is_none() || d > self.max {
            self.max = d;
            self.argmax = Some(p);
        }
        self.n += 1;
        self.sum += d;
        self.sumsq += d * d;
    }
    /// Append `o` (which comes after `self` in sample order).
    fn merge(&mut self, o: &Acc) {
        if let Some(p) = o.argmax
            && (self.argmax.is_none() || o.max > self.max)
        {
            self.max = o.max;
            self.argmax = Some(p);
        }
        self.n += o.n;
        self.sum += o.sum;
        self.sumsq += o.sumsq;
    }
    fn stats(&self) -> DistanceStats {
        let n = self.n.max(1) as f64;
        DistanceStats {
            samples: self.n,
            max: self.max,
            mean: self.sum / n,
            rms: (self.sumsq / n).sqrt(),
            argmax: self.argmax.map(|p| p.to_array()),
        }
    }
}

/// Geometry of the mesh against the surface.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Geometry {
    /// Mesh -> S: samples on the triangles, each to a point of S (see
    /// `mesh_to_surface_method`).
    pub mesh_to_surface: DistanceStats,
    /// How the mesh -> S distances were measured.
    pub mesh_to_surface_method: String,
    /// The reported mesh -> S maximum is at most this much above the true one (images: the
    /// branch and bound's tolerance there; 0 where the distances are exact).
    pub mesh_to_surface_precision: f64,
    /// Samples for which no point of S was found: not measured (excluded from the figures;
    /// the `hausdorff` check FAILs on them).
    pub projection_failures: usize,
    /// Samples whose projection landed farther than a point of S found by rays (the nearer
    /// point is used).
    pub corrected_projections: usize,
    /// Image samples whose search stopped on its work budget: their figure is an upper bound
    /// with a gap above the tolerance.
    pub bounded_only: usize,
    /// S -> mesh: samples of S to their nearest triangle (exact).
    pub surface_to_mesh: DistanceStats,
    /// Where the S samples came from.
    pub surface_samples_source: String,
    /// Every point of S is within this distance of an S sample (when known: images), so the
    /// true S -> mesh distance is at most `surface_to_mesh.max` plus this.
    pub surface_covering_radius: Option<f64>,
    /// max of the two one-sided distances.
    pub hausdorff: f64,
    pub bounding_radius: f64,
    /// hausdorff / bounding radius.
    pub hausdorff_relative: f64,
    /// On a surface that tells where it is the data's ([`Surface::data_defined`]): the
    /// facets measured, those whose corners and centroid lie there. Every figure above, and
    /// `normals`, is then of these facets only: beyond the data S is an extrapolation or the
    /// far field's sign boundary, and a distance to it means nothing (not measured).
    pub trusted: Option<TrustedPart>,
    pub normals: NormalDeviation,
}

/// The facets where S is the data's surface (see [`Geometry::trusted`]).
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct TrustedPart {
    /// Facets measured, and all facets.
    pub facets: usize,
    pub of: usize,
}

/// Angle between each facet's normal and the surface gradient at its three vertices.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct NormalDeviation {
    /// Largest angle between an oriented facet normal and the gradient at one of its vertices.
    pub max_deg: f64,
    /// Largest angle between the *lines* of the two (min(a, 180 - a)): lemma 3.1's quantity.
    pub max_line_deg: f64,
    /// Largest excess of that line angle over the surface's own normal uncertainty at the
    /// vertex ([`oracle::Surface::normal_uncertainty_deg`]); equals `max_line_deg` for exact
    /// backends. What the normals check compares with lemma 3.1's bound.
    pub max_excess_line_deg: f64,
    /// Largest normal uncertainty of the surface at a vertex (0 for exact backends).
    pub max_uncertainty_deg: f64,
    pub mean_deg: f64,
    /// Facets with an angle above 90 degrees at some vertex (facing inward).
    pub inverted_facets: usize,
    /// (facet, vertex) pairs where the gradient was zero or not finite (skipped).
    pub undefined: usize,
}

/// Barycentric grid with `n` subdivisions per edge: (n+1)(n+2)/2 points per triangle.
pub fn triangle_samples(a: DVec3, b: DVec3, c: DVec3, n: usize, out: &mut Vec<DVec3>) {
    let n = n.max(1);
    for i in 0..=n {
        for j in 0..=n - i {
            let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
            out.push(a + (b - a) * u + (c - a) * v);
        }
    }
}

/// How mesh samples are measured against S.
pub(crate) enum Measure<'a> {
    /// An image: exact distance to the trilinear level set ([`LevelSet::nearest`]).
    LevelSet(Box<LevelSet<'a>>),
    /// Any other surface: [`Surface::project`], checked by rays where it lands farther than
    /// half the sample's triangle's longest edge (a projection that ran to a far sheet).
    Project(&'a dyn Surface),
}

impl<'a> Measure<'a> {
    pub(crate) fn new(surface: &'a dyn Surface) -> Measure<'a> {
        match surface.as_image() {
            Some(img) => Measure::LevelSet(Box::new(LevelSet::new(img))),
            None => Measure::Project(surface),
        }
    }

    /// What the mesh -> S figures are, for the report.
    pub(crate) fn describe(&self) -> String {
        match self {
            Measure::LevelSet(ls) => format!(
                "exact distance to the trilinear level set of the image (branch and bound over \
                 voxel cells): the maximum within max(1e-2 d, {:.1e}), the mean and rms of \
                 upper bounds within max(1e-1 d, {:.1e})",
                ls.tolerance_at(Precision::Fine, 0.0),
                ls.tolerance_at(Precision::Coarse, 0.0)
            ),
            Measure::Project(s) if s.exact_projection() => {
                "distance to the exact closest point of the input triangles".into()
            }
            Measure::Project(_) => "distance to the surface's projection of the sample, checked \
                 by rays from the sample where it is farther than half the triangle's longest \
                 edge (an upper bound: a point of S)"
                .into(),
        }
    }

    /// A point of S near `p`, its distance, and whether the distance was corrected (rays found
    /// a nearer point than the projection) or only bounded (the search stopped with a gap
    /// larger than its tolerance). `None`: not measured.
    /// The last item is a lower bound of the distance (the distance itself, but for images).
    fn measure(&self, p: DVec3, edge: f64, prec: Precision) -> Option<(DVec3, f64, Flag, f64)> {
        match self {
            Measure::LevelSet(ls) => {
                let n = ls.nearest_with(p, prec);
                let q = n.point?;
                let exact = n.upper - n.lower <= 2.0 * ls.tolerance_at(prec, n.upper);
                let flag = if exact { Flag::Exact } else { Flag::Bounded };
                Some((q, n.upper, flag, n.lower))
            }
            Measure::Project(s) => {
                let q = s.project(p).filter(|q| q.is_finite());
                let d = q.map(|q| (p - q).length());
                // An exact closest point needs no check (rays would measure another surface:
                // a smoothed mesh's IMLS fit instead of its input triangles).
                if d.is_some_and(|d| d <= 0.5 * edge || s.exact_projection()) {
                    return Some((q?, d?, Flag::Exact, d?));
                }
                let r = oracle::roots::nearest_crossing_on_rays(*s, p)
                    .filter(|r| r.is_finite())
                    .map(|r| (r, (p - r).length()));
                let (q, d, flag) = match (q.zip(d), r) {
                    (Some((_, d)), Some((r, dr))) if dr < d => (r, dr, Flag::Corrected),
                    (Some((q, d)), _) => (q, d, Flag::Exact),
                    (None, Some((r, dr))) => (r, dr, Flag::Corrected),
                    (None, None) => return None,
                };
                Some((q, d, flag, d))
            }
        }
    }
}

#[derive(Clone, Copy, PartialEq)]
enum Flag {
    Exact,
    Corrected,
    Bounded,
}

/// Counts of a mesh -> S pass.
#[derive(Clone, Copy, Debug, Default)]
struct Counts {
    fails: usize,
    corrected: usize,
    bounded: usize,
}

/// Mesh -> S statistics of samples on the triangles (see [`Measure`]), the counts of samples
/// not measured, corrected or only bounded and, when `dist` is given, S -> mesh statistics
/// of the points of S found. Memory is O(number of triangles).
///
/// Every sample is measured at [`Precision::Coarse`] (its upper bound goes into the mean and
/// rms); the samples whose upper bound reaches the largest lower bound of all, the only ones
/// that may hold the maximum, are measured again at [`Precision::Fine`], and the maximum is
/// theirs. Invariant: the reported maximum is within the fine tolerance of the true one.
fn mesh_samples(
    mesh: &TriMesh,
    measure: &Measure<'_>,
    per_edge: usize,
    dist: Option<&MeshDistance<'_>>,
    trusted: Option<&[bool]>,
) -> (Acc, Acc, Counts) {
    const CHUNK: usize = 1024;
    struct Chunk {
        m2s: Acc,
        s2m: Acc,
        n: Counts,
        /// Largest lower bound of the chunk's samples.
        floor: f64,
        /// Samples whose upper bound reaches `floor`, in sample order.
        candidates: Vec<DVec3>,
    }
    let per_chunk: Vec<Chunk> = mesh
        .triangles
        .par_chunks(CHUNK)
        .enumerate()
        .map(|(k, tris)| {
            let (mut m2s, mut s2m, mut n) = (Acc::default(), Acc::default(), Counts::default());
            let mut pts = Vec::new();
            let mut measured: Vec<(DVec3, f64)> = Vec::new();
            let mut floor = f64::NEG_INFINITY;
            for (i, t) in tris.iter().enumerate() {
                if trusted.is_some_and(|m| m.get(k * CHUNK + i) != Some(&true)) {
                    continue;
                }
                let [a, b, c] = t.map(|i| mesh.vertices[i as usize]);
                let edge = (b - a).length().max((c - b).length()).max((a - c).length());
                pts.clear();
                triangle_samples(a, b, c, per_edge, &mut pts);
                for &p in &pts {
                    match measure.measure(p, edge, Precision::Coarse) {
                        Some((q, d, flag, lower)) => {
                            m2s.add(p, d);
                            measured.push((p, d));
                            floor = floor.max(lower);
                            n.corrected += (flag == Flag::Corrected) as usize;
                            n.bounded += (flag == Flag::Bounded) as usize;
                            if let Some(dd) = dist {
                                s2m.add(q, dd.nearest(q).map_or(f64::INFINITY, |x| x.1));
                            }
                        }
                        None => n.fails += 1,
                    }
                }
            }
            let candidates = measured
                .into_iter()
                .filter(|&(_, d)| d >= floor)
                .map(|(p, _)| p)
                .collect();
            Chunk {
                m2s,
                s2m,
                n,
                floor,
                candidates,
            }
        })
        .collect();
    let (mut m2s, mut s2m, mut n) = (Acc::default(), Acc::default(), Counts::default());
    let floor = per_chunk
        .iter()
        .map(|c| c.floor)
        .fold(f64::NEG_INFINITY, f64::max);
    for c in &per_chunk {
        m2s.merge(&c.m2s);
        s2m.merge(&c.s2m);
        n.fails += c.n.fails;
        n.corrected += c.n.corrected;
        n.bounded += c.n.bounded;
    }
    // The maximum, measured finely over the samples that may hold it (in sample order).
    let candidates: Vec<DVec3> = per_chunk
        .iter()
        .flat_map(|c| c.candidates.iter().copied())
        .collect();
    if let Measure::LevelSet(_) = measure
        && !candidates.is_empty()
    {
        let fine: Vec<Option<f64>> = candidates
            .par_iter()
            .map(|&p| measure.measure(p, 0.0, Precision::Fine).map(|m| m.1))
            .collect();
        let mut best: Option<(DVec3, f64)> = None;
        for (&p, d) in candidates.iter().zip(fine) {
            if let Some(d) = d
                && d >= floor
                && best.is_none_or(|(_, b)| d > b)
            {
                best = Some((p, d));
            }
        }
        if let Some((p, d)) = best {
            m2s.max = d;
            m2s.argmax = Some(p);
        }
    }
    (m2s, s2m, n)
}

/// S -> mesh statistics of the given samples of S (exact nearest triangle).
pub fn surface_to_mesh(dist: &MeshDistance<'_>, samples: &[DVec3]) -> DistanceStats {
    surface_to_mesh_acc(dist, samples).stats()
}

fn surface_to_mesh_acc(dist: &MeshDistance<'_>, samples: &[DVec3]) -> Acc {
    let per_chunk: Vec<Acc> = samples
        .par_chunks(4096)
        .map(|ps| {
            let mut acc = Acc::default();
            for &p in ps {
                acc.add(p, dist.nearest(p).map_or(f64::INFINITY, |x| x.1));
            }
            acc
        })
        .collect();
    let mut acc = Acc::default();
    for a in &per_chunk {
        acc.merge(a);
    }
    acc
}

/// Mesh -> S statistics of samples on the triangles and the number of failed projections.
pub fn mesh_to_surface(
    mesh: &TriMesh,
    surface: &dyn Surface,
    per_edge: usize,
) -> (DistanceStats, usize) {
    let (m2s, _, n) = mesh_samples(mesh, &Measure::new(surface), per_edge, None, None);
    (m2s.stats(), n.fails)
}

/// Normal deviation of the facets against the surface gradient.
pub fn normal_deviation(mesh: &TriMesh, surface: &dyn Surface) -> NormalDeviation {
    normal_deviation_on(mesh, surface, None)
}

/// [`normal_deviation`] on the facets `facets` marks (all when `None`).
pub fn normal_deviation_on(
    mesh: &TriMesh,
    surface: &dyn Surface,
    facets: Option<&[bool]>,
) -> NormalDeviation {
    // Per facet: (angle, the surface's normal uncertainty) at each vertex, and "faces inward".
    type PerFacet = ([Option<(f64, f64)>; 3], bool);
    let per: Vec<PerFacet> = mesh
        .triangles
        .par_iter()
        .enumerate()
        .filter(|(i, _)| facets.is_none_or(|m| m.get(*i) == Some(&true)))
        .map(|(_, t)| {
            let [a, b, c] = t.map(|i| mesh.vertices[i as usize]);
            let n = (b - a).cross(c - a).normalize_or_zero();
            let mut out = [None; 3];
            let mut inverted = false;
            for (k, v) in [a, b, c].into_iter().enumerate() {
                let g = surface.gradient(v).normalize_or_zero();
                if n == DVec3::ZERO || g == DVec3::ZERO || !g.is_finite() {
                    continue;
                }
                let ang = n.cross(g).length().atan2(n.dot(g)).to_degrees();
                inverted |= ang > 90.0;
                out[k] = Some((ang, surface.normal_uncertainty_deg(v)));
            }
            (out, inverted)
        })
        .collect();
    let mut nd = NormalDeviation {
        max_deg: 0.0,
        max_line_deg: 0.0,
        max_excess_line_deg: 0.0,
        max_uncertainty_deg: 0.0,
        mean_deg: 0.0,
        inverted_facets: 0,
        undefined: 0,
    };
    let mut n = 0usize;
    for (angles, inv) in &per {
        nd.inverted_facets += *inv as usize;
        for a in angles {
            match a {
                Some((a, u)) => {
                    let line = a.min(180.0 - a);
                    nd.max_deg = nd.max_deg.max(*a);
                    nd.max_line_deg = nd.max_line_deg.max(line);
                    nd.max_excess_line_deg = nd.max_excess_line_deg.max(line - u);
                    nd.max_uncertainty_deg = nd.max_uncertainty_deg.max(*u);
                    nd.mean_deg += a;
                    n += 1;
                }
                None => nd.undefined += 1,
            }
        }
    }
    if n > 0 {
        nd.mean_deg /= n as f64;
    }
    nd
}

/// The facets where S is the surface the data shows ([`Surface::data_defined`] at their
/// corners and centroid); `None` when the surface makes no such distinction or every facet
/// is one.
fn data_defined_facets(mesh: &TriMesh, surface: &dyn Surface) -> Option<Vec<bool>> {
    let first = mesh.vertices.first()?;
    surface.data_defined(*first)?;
    let ok = |p: DVec3| surface.data_defined(p) == Some(true);
    let at_vertex: Vec<bool> = mesh.vertices.par_iter().map(|&p| ok(p)).collect();
    let mask: Vec<bool> = mesh
        .triangles
        .par_iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| mesh.vertices[i as usize]);
            t.iter().all(|&i| at_vertex[i as usize]) && ok((a + b + c) / 3.0)
        })
        .collect();
    mask.iter().any(|&t| !t).then_some(mask)
}

/// Compute [`Geometry`]. `surface_samples`: dense samples of S; if `None`, the points of S on
/// the voxel edges for an image ([`LevelSet::edge_crossings`]), else the points of S found
/// for the mesh samples (they cover only the parts of S near the mesh).
pub fn geometry(
    mesh: &TriMesh,
    bvh: &TriangleBvh,
    surface: &dyn Surface,
    per_edge: usize,
    surface_samples: Option<&[DVec3]>,
) -> Geometry {
    geometry_labelled(mesh, bvh, surface, per_edge, surface_samples, None, None)
}

/// [`geometry`] with a description of the given samples for the report.
pub(crate) fn geometry_labelled(
    mesh: &TriMesh,
    bvh: &TriangleBvh,
    surface: &dyn Surface,
    per_edge: usize,
    surface_samples: Option<&[DVec3]>,
    label: Option<&str>,
    scan: Option<&[DVec3]>,
) -> Geometry {
    let trusted = data_defined_facets(mesh, surface);
    let trusted = trusted.as_deref();
    let dist = MeshDistance::new(mesh, bvh);
    let measure = Measure::new(surface);
    let own = match (&measure, surface_samples) {
        (Measure::LevelSet(ls), None) => Some(ls.edge_crossings()),
        _ => None,
    };
    let given = surface_samples.or(own.as_deref());
    let (m2s, s2m, n) = mesh_samples(
        mesh,
        &measure,
        per_edge,
        given.is_none().then_some(&dist),
        trusted,
    );
    let (surface_to_mesh, source, covering) = match (given, &measure) {
        (Some(s), Measure::LevelSet(ls)) if surface_samples.is_none() => (
            surface_to_mesh(&dist, s),
            format!(
                "{} points of S on the voxel edges (the marching-cubes vertices); every point of \
                 S is within {:.3e} of one",
                s.len(),
                ls.covering_radius()
            ),
            Some(ls.covering_radius()),
        ),
        (Some(s), _) => (
            surface_to_mesh(&dist, s),
            match label {
                Some(l) => format!("{} {l}", s.len()),
                None => format!("{} given samples", s.len()),
            },
            None,
        ),
        (None, _) => match scan {
            None => (
                s2m.stats(),
                format!(
                    "{} points of S found for the mesh samples (only the parts of S near the \
                     mesh)",
                    s2m.n
                ),
                None,
            ),
            // The grid scan's points reach the parts of S away from the mesh too.
            Some(pts) => {
                let mut all = s2m;
                all.merge(&surface_to_mesh_acc(&dist, pts));
                (
                    all.stats(),
                    format!(
                        "{} points of S found for the mesh samples and {} from the grid scan of \
                         f (its fine grid's crossings projected onto S)",
                        s2m.n,
                        pts.len()
                    ),
                    None,
                )
            }
        },
    };
    let mesh_to_surface = m2s.stats();
    let m2s_max = mesh_to_surface.max;
    let hausdorff = mesh_to_surface.max.max(surface_to_mesh.max);
    let bounding_radius = surface.bounding_sphere().radius;
    Geometry {
        mesh_to_surface,
        mesh_to_surface_method: measure.describe(),
        mesh_to_surface_precision: match &measure {
            Measure::LevelSet(ls) => ls.tolerance_at(Precision::Fine, m2s_max),
            Measure::Project(_) => 0.0,
        },
        projection_failures: n.fails,
        corrected_projections: n.corrected,
        bounded_only: n.bounded,
        surface_to_mesh,
        surface_samples_source: source,
        surface_covering_radius: covering,
        hausdorff,
        bounding_radius,
        hausdorff_relative: hausdorff / bounding_radius,
        trusted: trusted.map(|m| TrustedPart {
            facets: m.iter().filter(|&&t| t).count(),
            of: mesh.triangles.len(),
        }),
        normals: normal_deviation_on(mesh, surface, trusted),
    }
}
