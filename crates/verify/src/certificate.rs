//! The paper's conditions: the loose epsilon-sample certificate (definition 2.2, condition 1),
//! vertices on every component of S (condition 2) and theorem 4.7's Hausdorff bound.

use glam::DVec3;
use meshio::TriMesh;
use oracle::Surface;
use rayon::prelude::*;
use serde::Serialize;

use crate::distance::MeshDistance;

/// A surface Delaunay ball of a restricted facet (the kernel's type, [`geom::SurfaceBall`]).
///
/// ```
/// use verify::SurfaceBall;
/// let b = SurfaceBall::per_facet([(glam::DVec3::ZERO, 0.5)]);
/// assert_eq!((b[0].facet, b[0].radius), (0, 0.5));
/// ```
pub use geom::SurfaceBall;

/// Condition 1 of definition 2.2: every surface Delaunay ball B(c, r) has r <= eps d_M(c).
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct EpsilonCertificate {
    /// max over balls of r / d_M(c).
    pub eps_achieved: f64,
    /// The facet where it is attained.
    pub worst_facet: Option<usize>,
    pub requested_eps: Option<f64>,
    /// Facets whose ball exceeds the requested eps (capped), and their count.
    pub exceeding: Vec<usize>,
    pub exceeding_total: usize,
    pub balls: usize,
    /// Facets for which no surface Delaunay ball was found (counted as failures).
    pub facets_without_ball: usize,
    /// Balls where d_M(c) was not positive and finite (counted as failures).
    pub undefined_dm: usize,
    /// How d_M was obtained.
    pub dm_source: String,
}

impl EpsilonCertificate {
    /// Every facet has a ball, d_M was defined everywhere and no ball exceeds the request
    /// (or, without a request, the achieved eps is finite).
    pub fn passed(&self) -> bool {
        self.facets_without_ball == 0
            && self.undefined_dm == 0
            && match self.requested_eps {
                Some(_) => self.exceeding_total == 0,
                None => self.eps_achieved.is_finite(),
            }
    }
}

/// The loose epsilon-sample certificate for the given balls.
///
/// `dm` gives (an estimate of) d_M at a point of S; `num_facets` is the number of restricted
/// facets (facets without a ball count as failures).
pub fn loose_epsilon(
    balls: &[SurfaceBall],
    num_facets: usize,
    dm: &(dyn Fn(DVec3) -> f64 + Sync),
    requested_eps: Option<f64>,
    dm_source: &str,
    max_listed: usize,
) -> EpsilonCertificate {
    let ratios: Vec<Option<f64>> = balls
        .par_iter()
        .map(|b| {
            let d = dm(b.center);
            (d > 0.0 && d.is_finite()).then(|| b.radius / d)
        })
        .collect();
    let mut cert = EpsilonCertificate {
        eps_achieved: 0.0,
        worst_facet: None,
        requested_eps,
        exceeding: Vec::new(),
        exceeding_total: 0,
        balls: balls.len(),
        facets_without_ball: 0,
        undefined_dm: 0,
        dm_source: dm_source.to_owned(),
    };
    let mut has_ball = vec![false; num_facets];
    for (b, r) in balls.iter().zip(&ratios) {
        if let Some(h) = has_ball.get_mut(b.facet) {
            *h = true;
        }
        let Some(r) = *r else {
            cert.undefined_dm += 1;
            continue;
        };
        if r > cert.eps_achieved || cert.worst_facet.is_none() {
            cert.eps_achieved = r;
            cert.worst_facet = Some(b.facet);
        }
        if let Some(e) = requested_eps
            && r > e
        {
            cert.exceeding_total += 1;
            if cert.exceeding.len() < max_listed {
                cert.exceeding.push(b.facet);
            }
        }
    }
    cert.facets_without_ball = has_ball.iter().filter(|&&h| !h).count();
    if cert.undefined_dm > 0 {
        cert.eps_achieved = f64::INFINITY;
    }
    cert
}

/// Surface Delaunay balls of the mesh's facets, computed from the mesh alone: the dual
/// Voronoi edge of a Delaunay facet lies on the line through the facet's circumcentre,
/// orthogonal to the facet, so the ball centre is taken as the crossing of that line with S
/// closest to the circumcentre (searched within twice the circumradius, plus the surface
/// tolerance). The radius is the largest distance from the centre to the three vertices.
/// Facets with zero area or no crossing get no ball.
///
/// This matches the mesher's balls when the mesh is a restricted Delaunay triangulation and
/// the dual edge is long enough to contain that crossing; pass the mesher's own balls when
/// available.
pub fn surface_delaunay_balls(mesh: &TriMesh, surface: &dyn Surface) -> Vec<SurfaceBall> {
    let per: Vec<Option<SurfaceBall>> = mesh
        .triangles
        .par_iter()
        .enumerate()
        .map(|(f, t)| {
            let [a, b, c] = t.map(|i| mesh.vertices[i as usize]);
            let (cc, r) = circumcircle(a, b, c)?;
            let n = (b - a).cross(c - a).normalize_or_zero();
            if n == DVec3::ZERO {
                return None;
            }
            let reach = 2.0 * r + 10.0 * surface.tolerance();
            let (p, q) = (cc - n * reach, cc + n * reach);
            let mut out = Vec::new();
            surface.crossings(p, q, &mut out);
            if out.is_empty() {
                // The default intersection oracle samples the segment; a crossing closer
                // than its step to an endpoint can be missed: try the bipolar oracle.
                let (fp, fq) = (surface.value(p), surface.value(q));
                if (fp < 0.0) != (fq < 0.0) && fp.is_finite() && fq.is_finite() {
                    out.push(surface.crossing(p, fp, q, fq));
                }
            }
            let center = out.into_iter().min_by(|x, y| {
                (*x - cc)
                    .length_squared()
                    .total_cmp(&(*y - cc).length_squared())
            })?;
            let radius = [a, b, c]
                .iter()
                .map(|v| (*v - center).length())
                .fold(0.0, f64::max);
            Some(SurfaceBall {
                facet: f,
                center,
                radius,
            })
        })
        .collect();
    per.into_iter().flatten().collect()
}

/// Circumcentre and circumradius of a triangle in 3D (`None` if degenerate).
pub fn circumcircle(a: DVec3, b: DVec3, c: DVec3) -> Option<(DVec3, f64)> {
    let (u, v) = (b - a, c - a);
    let w = u.cross(v);
    let d = 2.0 * w.length_squared();
    if d.is_nan() || d <= 0.0 {
        return None;
    }
    let off = (v.length_squared() * w.cross(u) + u.length_squared() * v.cross(w)) / d;
    off.is_finite().then(|| (a + off, off.length()))
}

/// Condition 2 of definition 2.2 for one seed point of S.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct SeedCoverage {
    pub seed: [f64; 3],
    /// Distance to the nearest triangle.
    pub distance: f64,
    pub nearest_triangle: Option<usize>,
    /// The threshold used for this seed.
    pub tolerance: f64,
    pub covered: bool,
}

/// Condition 2 of definition 2.2: the mesh has vertices on every component of S.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct ComponentCoverage {
    pub seeds: Vec<SeedCoverage>,
    /// The largest per-seed threshold.
    pub tolerance: f64,
    pub uncovered: usize,
}

/// Check that every seed (a point on a component of S; one or more per component) is within
/// `tolerance(nearest triangle)` of the mesh.
pub fn component_coverage(
    dist: &MeshDistance<'_>,
    seeds: &[DVec3],
    tolerance: &(dyn Fn(usize) -> f64 + Sync),
) -> ComponentCoverage {
    let seeds: Vec<SeedCoverage> = seeds
        .par_iter()
        .map(|&s| {
            let n = dist.nearest(s);
            let d = n.map_or(f64::INFINITY, |x| x.1);
            let tol = n.map_or(0.0, |x| tolerance(x.0));
            SeedCoverage {
                seed: s.to_array(),
                distance: d,
                nearest_triangle: n.map(|x| x.0),
                tolerance: tol,
                covered: d <= tol,
            }
        })
        .collect();
    let uncovered = seeds.iter().filter(|s| !s.covered).count();
    ComponentCoverage {
        tolerance: seeds.iter().map(|s| s.tolerance).fold(0.0, f64::max),
        seeds,
        uncovered,
    }
}

/// Theorem 4.7: a loose eps-sample with eps < 0.096 is within 4.5 eps^2 d_M^sup of S.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct HausdorffBound {
    pub eps: f64,
    pub dm_sup: f64,
    /// 4.5 eps^2 d_M^sup.
    pub bound: f64,
    pub hausdorff: f64,
    /// eps < 0.096 (epsilon_1): the theorem applies.
    pub applicable: bool,
    pub holds: bool,
    /// The measured figure is over the bound by less than its precision (the true figure
    /// may be on either side): neither PASS nor FAIL.
    pub undecided: bool,
}

/// Lemma 3.1's bound, in degrees, on the angle between the line normal to a restricted
/// facet and the normal to S at any of its vertices, when every surface Delaunay ball
/// B(c, r) has r <= rho d_M(c) with rho < 1/7: 2 rho / (1 - 7 rho) + asin(rho sqrt(3) / (1 - rho))
/// (the bound for vertices of any inner angle). `None` when rho is not in [0, 1/7).
///
/// ```
/// let b = verify::certificate::normal_bound_deg(0.09).unwrap();
/// assert!((b - 37.7).abs() < 0.1);
/// assert!(verify::certificate::normal_bound_deg(0.15).is_none());
/// ```
pub fn normal_bound_deg(rho: f64) -> Option<f64> {
    if !(0.0..1.0 / 7.0).contains(&rho) {
        return None;
    }
    let a = 2.0 * rho / (1.0 - 7.0 * rho) + (rho * 3f64.sqrt() / (1.0 - rho)).asin();
    Some(a.to_degrees())
}

/// Epsilon_1 of theorem 4.4 (approximately 0.096).
pub const EPSILON_1: f64 = 0.096;

/// Compare the measured Hausdorff distance with theorem 4.7's bound 4.5 eps^2 d_M^sup.
pub fn hausdorff_bound(eps: f64, dm_sup: f64, hausdorff: f64) -> HausdorffBound {
    let bound = 4.5 * eps * eps * dm_sup;
    HausdorffBound {
        eps,
        dm_sup,
        bound,
        hausdorff,
        applicable: eps < EPSILON_1,
        holds: hausdorff <= bound,
        undecided: false,
    }
}
