//! Choice of sigma (section 6.5): a d_M estimate from the lambda-medial axis of a uniform sample
//! (Chazal & Lieutier), and the two-pass mesher built on it.

use crate::{Criteria, Progress, Sizing};
use crate::{MeshError, MeshOptions, MeshResult, mesh_with_progress};
use delaunay3::Triangulation;
use geom::kdtree::PointTree;
use glam::DVec3;
use oracle::{BoundingSphere, Surface};
use std::sync::Arc;

/// Radius of the smallest enclosing ball of up to four points.
pub fn smallest_enclosing_radius(p: &[DVec3]) -> f64 {
    // Try every subset's circumscribed ball (diametral for 2, circumcircle for 3, circumsphere
    // for 4); the smallest one containing all points is the answer.
    let n = p.len();
    let contains = |c: DVec3, r: f64| p.iter().all(|q| q.distance(c) <= r * (1.0 + 1e-9) + 1e-300);
    let mut best = f64::INFINITY;
    if n == 1 {
        return 0.0;
    }
    for i in 0..n {
        for j in i + 1..n {
            let c = 0.5 * (p[i] + p[j]);
            let r = 0.5 * p[i].distance(p[j]);
            if r < best && contains(c, r) {
                best = r;
            }
            for k in j + 1..n {
                let (c, r) = crate::criteria::triangle_circumcircle([p[i], p[j], p[k]]);
                if r < best && contains(c, r) {
                    best = r;
                }
            }
        }
    }
    if best.is_finite() {
        return best;
    }
    if n == 4
        && let Some(c) = tet_circumcenter(p[0], p[1], p[2], p[3])
    {
        return c.distance(p[0]);
    }
    best
}

fn tet_circumcenter(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> Option<DVec3> {
    let (u, v, w) = (b - a, c - a, d - a);
    let det = 2.0 * u.dot(v.cross(w));
    if det.abs() < 1e-300 {
        return None;
    }
    let x = (v.cross(w) * u.length_squared()
        + w.cross(u) * v.length_squared()
        + u.cross(v) * w.length_squared())
        / det;
    Some(a + x)
}

/// An estimate of the medial axis M of S from a dense sample E of S, and the distance to it,
/// an estimate of d_M (section 6.5). The point set is the union of
///
/// - the lambda-medial axis M_lambda(E) (Chazal & Lieutier), approximated by the Voronoi
///   vertices of E whose nearest sample points (the vertices of their Delaunay cell) have a
///   smallest enclosing ball of radius >= lambda, and
/// - the Voronoi poles of E (Amenta & Bern): for each sample, the farthest vertex of its Voronoi
///   cell, and the farthest one on the other side of the sample.
///
/// Why both: M_lambda is a subset of M that leaves out the parts of M near its boundary, where
/// the nearest points of S are close together (the tips of M, at the centers of the largest
/// curvature, which is where d_M is smallest). With lambda = [`LAMBDA_FACTOR`] sigma_0 close to
/// d_M^inf, as at eps >= 0.2, those tips are lost and d_{M_lambda} over-estimates d_M by up to a
/// third at the chair's tight corners (measured against shrinking-ball radii). The poles reach
/// the tips. The distance to the union is <= both distances.
///
/// The points are thinned to one per cell of a grid of step h = lambda / [`THINNING_CELLS`]
/// (the first in a deterministic order), which makes the nearest-point queries of the second
/// pass faster (the Voronoi vertices of a dense sample cluster along M). Thinning removes
/// points, so it could only increase the distance, by at most h sqrt(3):
/// [`MedialAxisEstimate::distance`] subtracts that bound, so it is <= the distance to the
/// unthinned union. A distance to a set minus a constant, clamped at 0, is 1-Lipschitz.
pub struct MedialAxisEstimate {
    vertices: Vec<DVec3>,
    tree: PointTree,
    /// Lambda used.
    pub lambda: f64,
    /// Bound on the distance increase due to thinning, subtracted from every distance.
    pub thinning_error: f64,
    /// Smallest distance from a medial point (before thinning) to the sample: an estimate of
    /// d_M^inf = min over M of the distance to S (+inf if no medial point was found).
    pub min_radius: f64,
    /// Voronoi vertices of M_lambda(E) and poles kept before thinning.
    pub lambda_vertices: usize,
    pub poles: usize,
}

impl MedialAxisEstimate {
    /// Build from a sample of S (points on S), keeping Voronoi vertices within `keep` (the
    /// bounding sphere enlarged three times: the outer medial axis matters too).
    pub fn new(sample: &[DVec3], lambda: f64, keep: BoundingSphere) -> Result<Self, MeshError> {
        let mut tri = Triangulation::new();
        // Spatially sorted insertion (BRIO + Hilbert): several times faster than the mesh's order.
        tri.insert_bulk(sample)?;
        Ok(Self::of_triangulation(&tri, Some(lambda), lambda, keep))
    }

    /// The poles alone (no lambda-medial vertices) of the vertices of `tri`, a Delaunay
    /// triangulation of a sample of S, thinned at the scale `lambda` (see the type's docs),
    /// for a sample whose spacing varies (`crate::adaptive`): a lambda-medial axis with one
    /// lambda keeps spurious Voronoi vertices near S where the spacing exceeds lambda (the
    /// chair: minimum 0.013 for a true 0.066), and with a lambda following the spacing it
    /// adds little to the poles (the chair, 222k samples: minimum 0.0664 against 0.0688,
    /// mean equal within 0.5%) for three times the points.
    pub fn poles_of(tri: &Triangulation, lambda: f64, keep: BoundingSphere) -> Self {
        Self::of_triangulation(tri, None, lambda, keep)
    }

    /// [`MedialAxisEstimate::poles_of`] from the poles of every vertex of the triangulation,
    /// computed by the caller (`poles[i]`: vertex `i`'s; e.g. some reused from an earlier
    /// estimate where the stars did not change): the same estimate for the same poles.
    pub fn from_poles(poles: &[delaunay3::VertexPoles], lambda: f64, keep: BoundingSphere) -> Self {
        Self::from_candidates(Vec::new(), poles, lambda, keep)
    }

    /// From Del(E): the lambda-medial vertices (with `medial_lambda`) and the poles,
    /// thinned at `lambda` / [`THINNING_CELLS`].
    fn of_triangulation(
        tri: &Triangulation,
        medial_lambda: Option<f64>,
        lambda: f64,
        keep: BoundingSphere,
    ) -> Self {
        let far = far_sphere(keep);
        let (cells, centers) = verify::medial::circumcenters(tri);
        let mut candidates: Vec<(DVec3, f64)> = Vec::new();
        // The lambda-medial vertices.
        for (&c, &cc) in cells
            .iter()
            .zip(&centers)
            .filter(|_| medial_lambda.is_some())
        {
            let pts = tri.cell_vertices(c).map(|v| tri.point(v));
            if cc.is_finite()
                && far.contains(cc)
                && Some(smallest_enclosing_radius(&pts)) >= medial_lambda
            {
                candidates.push((cc, cc.distance(pts[0])));
            }
        }
        let poles = verify::medial::poles_in_parallel(tri, &cells, &centers, |_| None);
        Self::from_candidates(candidates, &poles, lambda, keep)
    }

    /// The estimate from the lambda-medial `candidates` (point, radius) and the poles of
    /// every vertex, in vertex order (a hull sample's Voronoi cell is unbounded: only its
    /// inner pole is finite), those within three times `keep`, thinned at `lambda` /
    /// [`THINNING_CELLS`].
    fn from_candidates(
        mut candidates: Vec<(DVec3, f64)>,
        vertex_poles: &[delaunay3::VertexPoles],
        lambda: f64,
        keep: BoundingSphere,
    ) -> Self {
        let far = far_sphere(keep);
        let lambda_vertices = candidates.len();
        let mut poles = 0;
        for vp in vertex_poles {
            for pole in [vp.plus, vp.minus].into_iter().flatten() {
                if far.contains(pole.point) {
                    candidates.push((pole.point, pole.distance_squared.sqrt()));
                    poles += 1;
                }
            }
        }
        let min_radius = candidates.iter().map(|c| c.1).fold(f64::INFINITY, f64::min);
        let h = lambda / THINNING_CELLS;
        let mut vertices = Vec::new();
        if h > 0.0 {
            let mut seen = rustc_hash::FxHashSet::default();
            for (cc, _) in candidates {
                if seen.insert((cc / h).floor().as_i64vec3().to_array()) {
                    vertices.push(cc);
                }
            }
        } else {
            vertices = candidates.into_iter().map(|c| c.0).collect();
        }
        if vertices.is_empty() {
            // No medial point kept: fall back to the bounding-sphere center so that the
            // estimate is finite (it is then an over-estimate; the caller bounds sigma below).
            vertices.push(keep.center);
        }
        let tree = PointTree::new(&vertices);
        MedialAxisEstimate {
            vertices,
            tree,
            lambda,
            thinning_error: if h > 0.0 { h * 3f64.sqrt() } else { 0.0 },
            min_radius,
            lambda_vertices,
            poles,
        }
    }

    /// Estimated distance from `p` to the medial axis (>= 0).
    pub fn distance(&self, p: DVec3) -> f64 {
        let d2 = self.tree.nearest(p).map_or(f64::INFINITY, |(_, d2)| d2);
        (d2.sqrt() - self.thinning_error).max(0.0)
    }

    /// [`MedialAxisEstimate::distance`] at each of `pts`, in parallel, the queries run in
    /// Z-order (cache-friendly; the values do not depend on the order).
    pub fn distances(&self, pts: &[DVec3]) -> Vec<f64> {
        use rayon::prelude::*;
        let b = geom::bvh::Aabb::from_points(pts);
        let half = 0.5 * (b.max - b.min).max_element();
        let mut order: Vec<(u64, u32)> = pts
            .par_iter()
            .enumerate()
            .map(|(i, &p)| (geom::morton::morton_key(p, b.center(), half), i as u32))
            .collect();
        order.par_sort_unstable();
        let got: Vec<f64> = order
            .par_iter()
            .map(|&(_, i)| self.distance(pts[i as usize]))
            .collect();
        let mut out = vec![0.0; pts.len()];
        for (&(_, i), d) in order.iter().zip(got) {
            out[i as usize] = d;
        }
        out
    }

    /// min over `pts` of [`MedialAxisEstimate::distance`] (+inf for no points): the estimate
    /// of d_M^inf from a sample of S.
    pub fn min_distance(&self, pts: &[DVec3]) -> f64 {
        pts.iter()
            .map(|&p| self.distance(p))
            .fold(f64::INFINITY, f64::min)
    }

    /// Number of medial points kept (after thinning).
    pub fn len(&self) -> usize {
        self.vertices.len()
    }

    pub fn is_empty(&self) -> bool {
        self.vertices.is_empty()
    }
}

/// Result of [`two_pass`]: both passes and the d_M estimate used by the second.
pub struct TwoPass {
    pub first: MeshResult,
    pub second: MeshResult,
    /// The constant size of the first pass, eps * d_M^inf.
    pub sigma0: f64,
    /// The second pass's factor eps' = [`EPS_PRIME_FACTOR`] * eps.
    pub eps_prime: f64,
    pub medial: Arc<MedialAxisEstimate>,
    /// [`MedialAxisEstimate::min_radius`]: an estimate of d_M^inf from the first pass. When it
    /// is well below the d_M^inf given, the first pass was not a uniform eps-sample.
    pub dm_inf_estimate: f64,
    /// Lower bound of the second pass's size field (see [`second_pass`]).
    pub floor: f64,
    /// The second pass did not run: the first spent the time limit (or was cancelled), and
    /// `second` is the first pass's mesh, the mesh so far.
    pub second_skipped: bool,
}

/// Result of [`second_pass`].
pub struct SecondPass {
    pub result: MeshResult,
    pub medial: Arc<MedialAxisEstimate>,
    pub eps_prime: f64,
    /// See [`TwoPass::dm_inf_estimate`].
    pub dm_inf_estimate: f64,
    /// See [`TwoPass::floor`].
    pub floor: f64,
    /// See [`TwoPass::second_skipped`].
    pub skipped: bool,
}

/// eps' / eps in the second pass (section 6.5: "some eps' slightly smaller than eps").
pub const EPS_PRIME_FACTOR: f64 = 0.9;
/// lambda / sigma_0 for the lambda-medial axis of the first-pass sample. Measured (tests/sizing.rs):
/// at 2.5, d_{M_lambda} is within 7% of the true d_M on the sphere, torus and ellipsoid sampled
/// at sigma_0 = 0.09 d_M^inf; at 1, sample noise keeps spurious Voronoi vertices near S.
pub const LAMBDA_FACTOR: f64 = 2.5;
/// lambda / (thinning grid step) in [`MedialAxisEstimate`]: the distance is at most
/// sqrt(3) lambda / 25 = 0.17 sigma_0 below the distance to the unthinned point set. (A
/// distance-relative step, a max(lambda, D_v), was tried: a = 0.03 halves the query time on
/// the chair but under-estimates d_M by 5% more everywhere: 6% on the sphere.)
pub const THINNING_CELLS: f64 = 25.0;
/// Control points per component of the first-pass mesh (farthest-point spread).
pub const CONTROL_PER_COMPONENT: usize = 8;

/// The second pass's size field sigma(x) = max(floor, eps' * d(x)), d the
/// [`MedialAxisEstimate::distance`].
///
/// It is 1-Lipschitz: d is 1-Lipschitz, so eps' d is eps'-Lipschitz with eps' < 1, and the max
/// of an eps'-Lipschitz function and a constant is eps'-Lipschitz. It is positive (>= floor >
/// 0), as lemma 6.2 needs. The last value computed on each thread is memoized (the mesher asks
/// for sigma twice at the same ball center); the function is unchanged by it.
pub fn adaptive_field(
    medial: Arc<MedialAxisEstimate>,
    eps_prime: f64,
    floor: f64,
) -> Arc<dyn Fn(DVec3) -> f64 + Send + Sync> {
    use std::cell::Cell;
    use std::sync::atomic::{AtomicU64, Ordering};
    static IDS: AtomicU64 = AtomicU64::new(1);
    thread_local! {
        static LAST: Cell<(u64, [u64; 3], f64)> = const { Cell::new((0, [0; 3], 0.0)) };
    }
    let id = IDS.fetch_add(1, Ordering::Relaxed);
    Arc::new(move |p: DVec3| {
        let key = [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
        LAST.with(|last| {
            let (i, k, v) = last.get();
            if i == id && k == key {
                return v;
            }
            let v = (eps_prime * medial.distance(p)).max(floor);
            last.set((id, key, v));
            v
        })
    })
}

fn check_eps(eps: f64) -> Result<(), MeshError> {
    if !(eps > 0.0 && eps < 1.0) {
        return Err(MeshError::InvalidSize(eps));
    }
    Ok(())
}

/// Two-pass sizing of section 6.5: a uniform pass with sigma_0 = eps * dm_inf, then the
/// medial-axis estimate ([`MedialAxisEstimate`], lambda = [`LAMBDA_FACTOR`] sigma_0) of its
/// vertices, then a pass with the 1-Lipschitz [`adaptive_field`] (eps' = 0.9 eps), with control
/// points taken from the first pass's mesh ([`CONTROL_PER_COMPONENT`] spread vertices of every
/// component). `eps` must be in (0, 1) and `dm_inf` positive. `base` gives everything else
/// (oracle, angle, budgets, seed); its `time_limit` bounds the two passes together.
///
/// ```
/// use rdt_mesher::{sizing::two_pass, MeshOptions};
/// use oracle::{BoundingSphere, Surface};
/// use glam::DVec3;
/// // Ellipsoid with semi-axes 1, 0.6, 0.4: d_M ranges from 0.16 to 0.4.
/// struct Ellipsoid;
/// impl Surface for Ellipsoid {
///     fn bounding_sphere(&self) -> BoundingSphere {
///         BoundingSphere { center: DVec3::ZERO, radius: 2.0 }
///     }
///     fn value(&self, p: DVec3) -> f64 {
///         p.x * p.x + (p.y / 0.6).powi(2) + (p.z / 0.4).powi(2) - 1.0
///     }
/// }
/// let tp = two_pass(&Ellipsoid, 0.3, 0.16, &MeshOptions::default(), &mut |_| {}).unwrap();
/// assert!(tp.second.stats.criteria_met);
/// assert!(tp.second.mesh.vertices.len() < tp.first.mesh.vertices.len());
/// assert!((tp.dm_inf_estimate - 0.16).abs() < 0.03);
/// ```
pub fn two_pass(
    surface: &dyn Surface,
    eps: f64,
    dm_inf: f64,
    base: &MeshOptions,
    progress: &mut (dyn FnMut(Progress) + Send),
) -> Result<TwoPass, MeshError> {
    check_eps(eps)?;
    if !(dm_inf > 0.0 && dm_inf.is_finite()) {
        return Err(MeshError::InvalidSize(dm_inf));
    }
    let sigma0 = eps * dm_inf;
    let mut o1 = base.clone();
    o1.criteria = Criteria {
        size: Some(Sizing::Constant(sigma0)),
        ..base.criteria.clone()
    };
    let start = std::time::Instant::now();
    let first = mesh_with_progress(surface, &o1, progress)?;
    // `time_limit` bounds both passes: the second gets the time left, and a stop there
    // reports the limit given.
    let mut o2 = base.clone();
    o2.time_limit = base.time_limit.map(|t| t.saturating_sub(start.elapsed()));
    let mut sp = second_pass(surface, &first, eps, sigma0, &o2, progress)?;
    let stop = &mut sp.result.stats.stopped_by;
    *stop = stop.take().map(|r| r.with_time_limit(base.time_limit));
    Ok(TwoPass {
        first,
        second: sp.result,
        sigma0,
        eps_prime: sp.eps_prime,
        medial: sp.medial,
        dm_inf_estimate: sp.dm_inf_estimate,
        floor: sp.floor,
        second_skipped: sp.skipped,
    })
}

/// The second pass of [`two_pass`] from a given first pass (sampled at constant `sigma0`).
///
/// The size field is [`adaptive_field`] with floor = min(sigma_0, eps' m), m =
/// [`MedialAxisEstimate::min_radius`] (the estimate of d_M^inf): positive, and where the
/// estimate confirms the d_M^inf given (m >= d_M^inf), sigma_0 = eps d_M^inf <= eps d_M, so a
/// surface of constant d_M gets the first pass's size. A floor at sigma_0 alone is wrong when
/// the d_M^inf given is too large (the chair at --dm-inf 0.1, whose d_M^inf is about 0.077):
/// sigma_0 > eps d_M where d_M is smallest, and the second pass stayed that coarse there.
///
/// With no time left (`base.time_limit` zero) or `base.cancel` cancelled, the pass is not
/// run: its result is `first`'s and its estimate empty (see [`SecondPass::skipped`]).
pub fn second_pass(
    surface: &dyn Surface,
    first: &MeshResult,
    eps: f64,
    sigma0: f64,
    base: &MeshOptions,
    progress: &mut (dyn FnMut(Progress) + Send),
) -> Result<SecondPass, MeshError> {
    check_eps(eps)?;
    // No time left (a `time_limit` of zero) or cancelled: the first pass's mesh stands, and
    // no estimate is made (an empty one: no medial point, minimum +inf).
    let skipped = base.time_limit == Some(std::time::Duration::ZERO)
        || base.cancel.as_ref().is_some_and(|c| c.is_cancelled());
    let (lambda, keep) = (LAMBDA_FACTOR * sigma0, surface.bounding_sphere());
    let medial = Arc::new(if skipped {
        MedialAxisEstimate::from_poles(&[], lambda, keep)
    } else {
        MedialAxisEstimate::new(&first.mesh.vertices, lambda, keep)?
    });
    let eps_prime = EPS_PRIME_FACTOR * eps;
    let m = medial.min_radius;
    let floor = if m > 0.0 {
        sigma0.min(eps_prime * m)
    } else {
        0.5 * eps_prime * sigma0
    };
    let mut o2 = base.clone();
    o2.criteria = Criteria {
        // eps'-Lipschitz (see `adaptive_field`).
        size: Some(Sizing::Lipschitz(
            adaptive_field(medial.clone(), eps_prime, floor),
            eps_prime,
        )),
        ..base.criteria.clone()
    };
    o2.control_points = Some(crate::topology::component_representatives(
        &first.mesh,
        CONTROL_PER_COMPONENT,
    ));
    let result = if skipped {
        first.clone()
    } else {
        mesh_with_progress(surface, &o2, progress)?
    };
    Ok(SecondPass {
        result,
        medial,
        eps_prime,
        dm_inf_estimate: m,
        floor,
        skipped,
    })
}

/// Result of [`estimate_dm_inf`].
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct DmInfEstimate {
    /// min over the last complete sample of d_{M_lambda}.
    pub value: f64,
    /// Constant size of that sample.
    pub sigma: f64,
    /// Its number of vertices.
    pub vertices: usize,
    /// `sigma <= DM_INF_SIGMA_RATIO * value` held (else the vertex budget stopped the
    /// refinement first, and `value` is only an upper estimate: d_{M_lambda} >= lambda always).
    pub converged: bool,
}

/// sigma / estimate at which [`estimate_dm_inf`] stops refining.
pub const DM_INF_SIGMA_RATIO: f64 = 0.1;

/// An estimate of d_M^inf for a surface without a known value (section 6.5 applied to itself):
/// mesh S uniformly at sigma = bounding radius / 20, take m = min over the sample of the
/// [`MedialAxisEstimate`] distance (lambda = 2.5 sigma); while sigma > 0.1 m, mesh again at
/// sigma = 0.1 m, or at the smallest sigma expected to fit in 80% of `base.max_vertices` if
/// larger (at most 6 passes; a pass stopped by the budget is discarded).
///
/// A coarse sample cannot see a d_M much below its spacing (its Voronoi vertices near the
/// medial axis are blurred over that scale), hence the refinement down to sigma = 0.1 m, where
/// the estimate is within 7% on the sphere, torus and ellipsoid (tests/sizing.rs). An estimate,
/// not a bound; meaningless on singular surfaces (d_M^inf = 0 there: it decreases with sigma).
pub fn estimate_dm_inf(
    surface: &dyn Surface,
    base: &MeshOptions,
) -> Result<DmInfEstimate, MeshError> {
    let mut sigma = surface.bounding_sphere().radius / 20.0;
    let mut best: Option<DmInfEstimate> = None;
    for _ in 0..6 {
        let mut o = base.clone();
        o.criteria = Criteria {
            size: Some(Sizing::Constant(sigma)),
            ..base.criteria.clone()
        };
        let r = mesh_with_progress(surface, &o, &mut |_| {})?;
        if r.stats.stopped_by.is_some() && best.is_some() {
            break;
        }
        let m = MedialAxisEstimate::new(
            &r.mesh.vertices,
            LAMBDA_FACTOR * sigma,
            surface.bounding_sphere(),
        )?;
        let value = m.min_distance(&r.mesh.vertices);
        if !(value > 0.0 && value.is_finite()) {
            return Err(MeshError::InvalidSize(value));
        }
        let converged = sigma <= DM_INF_SIGMA_RATIO * value * 1.000_001;
        best = Some(DmInfEstimate {
            value,
            sigma,
            vertices: r.mesh.vertices.len(),
            converged,
        });
        if converged || r.stats.stopped_by.is_some() {
            break;
        }
        // Next size: 0.1 m, or the smallest that should fit in 80% of the vertex budget
        // (vertex count ~ area / sigma^2); stop when that is no finer than this pass.
        let mut next = DM_INF_SIGMA_RATIO * value;
        if let Some(m) = base.max_vertices {
            let fit = sigma * (r.mesh.vertices.len() as f64 / (0.8 * m as f64)).sqrt();
            if fit >= 0.95 * sigma {
                break;
            }
            next = next.max(fit);
        }
        sigma = next;
    }
    Ok(best.expect("at least one pass"))
}

/// The sphere within which medial points are kept: `keep` enlarged three times (the outer
/// medial axis matters too).
fn far_sphere(keep: BoundingSphere) -> BoundingSphere {
    BoundingSphere {
        center: keep.center,
        radius: keep.radius * 3.0,
    }
}
