//! Choice of sigma (section 6.5): a d_M estimate from the lambda-medial axis of a uniform sample
//! (Chazal & Lieutier), and the two-pass mesher built on it.

use crate::refine::{MeshError, MeshOptions, MeshResult, mesh_with_progress};
use crate::{Criteria, Progress, Sizing};
use delaunay3::{Insertion, Triangulation};
use glam::DVec3;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
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

/// The lambda-medial axis M_lambda(E) of a sample E, approximated by the Voronoi vertices of E
/// whose nearest sample points (the vertices of their Delaunay cell) have a smallest enclosing
/// ball of radius >= lambda. The distance to it estimates d_M (section 6.5).
///
/// The kept vertices are thinned to one per cell of a grid of step h = lambda / 25 (the first
/// in cell order), which changes the distance by at most h sqrt(3) < 0.07 lambda and makes
/// the nearest-vertex queries of the second pass several times faster (the Voronoi vertices
/// of a dense sample cluster along the medial axis). The distance to a set is 1-Lipschitz
/// whatever the set.
pub struct MedialAxisEstimate {
    vertices: Vec<DVec3>,
    tree: ImmutableKdTree<f64, 3>,
    /// Lambda used.
    pub lambda: f64,
}

impl MedialAxisEstimate {
    /// Build from a sample of S (points on S), keeping Voronoi vertices within `keep` (the
    /// bounding sphere enlarged three times: the outer medial axis matters too).
    pub fn new(sample: &[DVec3], lambda: f64, keep: BoundingSphere) -> Result<Self, MeshError> {
        let mut tri = Triangulation::new();
        for p in sample {
            match tri.insert(*p)? {
                Insertion::New(_) | Insertion::Duplicate(_) => {}
            }
        }
        let far = BoundingSphere {
            center: keep.center,
            radius: keep.radius * 3.0,
        };
        let mut vertices = Vec::new();
        let h = lambda / 25.0;
        let mut seen = rustc_hash::FxHashSet::default();
        let cells: Vec<_> = tri.finite_cells().collect();
        for c in cells {
            let vs = tri.cell_vertices(c).map(|v| tri.point(v));
            let cc = tri.circumcenter(c);
            if !cc.is_finite() || !far.contains(cc) {
                continue;
            }
            if smallest_enclosing_radius(&vs) >= lambda
                && (h <= 0.0 || seen.insert((cc / h).floor().as_i64vec3().to_array()))
            {
                vertices.push(cc);
            }
        }
        if vertices.is_empty() {
            // No medial vertex kept: fall back to the bounding-sphere center so that the
            // estimate is finite (it is then an over-estimate; the caller bounds sigma below).
            vertices.push(keep.center);
        }
        let arr: Vec<[f64; 3]> = vertices.iter().map(|v| v.to_array()).collect();
        let tree = ImmutableKdTree::new_from_slice(&arr).expect("finite points");
        Ok(MedialAxisEstimate {
            vertices,
            tree,
            lambda,
        })
    }

    /// Estimated distance from `p` to the medial axis.
    pub fn distance(&self, p: DVec3) -> f64 {
        let r = self
            .tree
            .query(&p.to_array())
            .nearest_one::<SquaredEuclidean<f64>>()
            .execute();
        r.distance.sqrt()
    }

    /// min over `pts` of [`MedialAxisEstimate::distance`] (+inf for no points): the estimate
    /// of d_M^inf from a sample of S.
    pub fn min_distance(&self, pts: &[DVec3]) -> f64 {
        pts.iter()
            .map(|&p| self.distance(p))
            .fold(f64::INFINITY, f64::min)
    }

    /// Number of Voronoi vertices kept.
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
}

/// eps' / eps in the second pass (section 6.5: "some eps' slightly smaller than eps").
pub const EPS_PRIME_FACTOR: f64 = 0.9;
/// lambda / sigma_0 for the lambda-medial axis of the first-pass sample. Measured (tests/sizing.rs):
/// at 2.5, d_{M_lambda} is within 7% of the true d_M on the sphere, torus and ellipsoid sampled
/// at sigma_0 = 0.09 d_M^inf; at 1, sample noise keeps spurious Voronoi vertices near S.
pub const LAMBDA_FACTOR: f64 = 2.5;
/// Control points per component of the first-pass mesh (farthest-point spread).
pub const CONTROL_PER_COMPONENT: usize = 8;

/// The second pass's size field sigma(x) = max(sigma_0, eps' * d_{M_lambda}(x)).
///
/// It is 1-Lipschitz: d_{M_lambda} (a distance to a set) is 1-Lipschitz, so eps' d_{M_lambda} is
/// eps'-Lipschitz with eps' < 1, and the max of an eps'-Lipschitz function and a constant is
/// eps'-Lipschitz. It is positive (>= sigma_0), as lemma 6.2 needs.
pub fn adaptive_field(
    medial: Arc<MedialAxisEstimate>,
    eps_prime: f64,
    sigma0: f64,
) -> Arc<dyn Fn(DVec3) -> f64 + Send + Sync> {
    Arc::new(move |p: DVec3| (eps_prime * medial.distance(p)).max(sigma0))
}

fn check_eps(eps: f64) -> Result<(), MeshError> {
    if !(eps > 0.0 && eps < 1.0) {
        return Err(MeshError::InvalidSize(eps));
    }
    Ok(())
}

/// Two-pass sizing of section 6.5: a uniform pass with sigma_0 = eps * dm_inf, then the
/// lambda-medial axis (lambda = [`LAMBDA_FACTOR`] sigma_0) of its vertices, then a pass with the
/// 1-Lipschitz [`adaptive_field`] (eps' = 0.9 eps), with control points taken from the first
/// pass's mesh ([`CONTROL_PER_COMPONENT`] spread vertices of every component). `eps` must be in
/// (0, 1) and `dm_inf` positive. `base` gives everything else (oracle, angle, budgets, seed).
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
/// ```
pub fn two_pass(
    surface: &dyn Surface,
    eps: f64,
    dm_inf: f64,
    base: &MeshOptions,
    progress: &mut dyn FnMut(Progress),
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
    let first = mesh_with_progress(surface, &o1, progress)?;
    let (second, medial, eps_prime) = second_pass(surface, &first, eps, sigma0, base, progress)?;
    Ok(TwoPass {
        first,
        second,
        sigma0,
        eps_prime,
        medial,
    })
}

/// The second pass of [`two_pass`] from a given first pass (sampled at constant `sigma0`).
pub fn second_pass(
    surface: &dyn Surface,
    first: &MeshResult,
    eps: f64,
    sigma0: f64,
    base: &MeshOptions,
    progress: &mut dyn FnMut(Progress),
) -> Result<(MeshResult, Arc<MedialAxisEstimate>, f64), MeshError> {
    check_eps(eps)?;
    let medial = Arc::new(MedialAxisEstimate::new(
        &first.mesh.vertices,
        LAMBDA_FACTOR * sigma0,
        surface.bounding_sphere(),
    )?);
    let eps_prime = EPS_PRIME_FACTOR * eps;
    let mut o2 = base.clone();
    o2.criteria = Criteria {
        size: Some(Sizing::Field(adaptive_field(
            medial.clone(),
            eps_prime,
            sigma0,
        ))),
        ..base.criteria.clone()
    };
    o2.control_points = Some(crate::topology::component_representatives(
        &first.mesh,
        CONTROL_PER_COMPONENT,
    ));
    let second = mesh_with_progress(surface, &o2, progress)?;
    Ok((second, medial, eps_prime))
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
/// mesh S uniformly at sigma = bounding radius / 20, take m = min over the sample of
/// d_{M_lambda} (lambda = 2.5 sigma); while sigma > 0.1 m, mesh again at sigma = 0.1 m, or at
/// the smallest sigma expected to fit in 80% of `base.max_vertices` if larger (at most 6
/// passes; a pass stopped by the budget is discarded).
///
/// Since every kept Voronoi vertex is at distance >= lambda from the sample, m >= 2.5 sigma: a
/// coarse sample cannot see a smaller d_M, hence the refinement down to sigma = 0.1 m, where
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
