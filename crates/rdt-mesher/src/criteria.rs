//! Refinement criteria: when is a surface Delaunay ball *bad* (paper, sections 6.1 and 6.4.1).

use glam::DVec3;
use std::fmt;
use std::sync::Arc;

/// The size function sigma of the paper: positive and (for the guarantees) 1-Lipschitz on S.
#[derive(Clone)]
pub enum Sizing {
    /// A constant sigma_0 (uniform epsilon-sample when sigma_0 <= eps * d_M^inf).
    Constant(f64),
    /// Any positive function of the point, e.g. `eps * d_M(x)` made 1-Lipschitz (section 6.5).
    Field(Arc<dyn Fn(DVec3) -> f64 + Send + Sync>),
}

impl Sizing {
    /// sigma(c).
    #[inline]
    pub fn at(&self, c: DVec3) -> f64 {
        match self {
            Sizing::Constant(s) => *s,
            Sizing::Field(f) => f(c),
        }
    }
}

impl fmt::Debug for Sizing {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Sizing::Constant(s) => write!(f, "Constant({s})"),
            Sizing::Field(_) => write!(f, "Field(..)"),
        }
    }
}

/// When a surface Delaunay ball B(c, r) circumscribing a restricted facet is bad.
/// Every criterion is optional; they combine by "bad if any is violated".
///
/// Names as CGAL / pygalmesh users know them:
///
/// | rdt-mesher | CGAL `Surface_mesh_default_criteria_3` | pygalmesh |
/// |---|---|---|
/// | `size` (sigma) | `radius_bound` | `max_radius_surface_delaunay_ball` |
/// | `min_angle_deg` | `angular_bound` | `min_facet_angle` |
/// | `max_distance` | `distance_bound` | `max_facet_distance` |
#[derive(Clone, Debug)]
pub struct Criteria {
    /// Bad if r > sigma(c). `None` disables the size criterion.
    pub size: Option<Sizing>,
    /// Bad if the facet has an angle below this bound, in degrees; 0 disables it.
    /// 30 degrees is the bound with a termination proof (lemma 6.5).
    pub min_angle_deg: f64,
    /// Bad if the distance between the facet's circumcenter and the ball center c exceeds
    /// this bound (CGAL's approximation criterion).
    pub max_distance: Option<f64>,
}

impl Default for Criteria {
    fn default() -> Self {
        Criteria {
            size: None,
            min_angle_deg: 30.0,
            max_distance: None,
        }
    }
}

impl Criteria {
    /// Size criterion only, with a constant sigma, plus the default 30 degree angle bound.
    pub fn uniform(sigma: f64) -> Self {
        Criteria {
            size: Some(Sizing::Constant(sigma)),
            ..Default::default()
        }
    }

    /// How bad the ball is: a value > 1 means bad (the larger the worse), <= 1 good.
    /// `tri` are the facet's vertices, `c` the ball center, `r` its radius.
    pub fn badness(&self, tri: [DVec3; 3], c: DVec3, r: f64) -> f64 {
        self.badness_with_sigma(tri, c, r, self.size.as_ref().map(|s| s.at(c)))
    }

    /// [`Criteria::badness`] with sigma(c) already evaluated (`None` without a size
    /// criterion): a sizing field is then evaluated once per ball.
    pub fn badness_with_sigma(&self, tri: [DVec3; 3], c: DVec3, r: f64, sigma: Option<f64>) -> f64 {
        let mut bad: f64 = 0.0;
        if let Some(sigma) = sigma {
            bad = bad.max(r / sigma);
        }
        let circle = (self.min_angle_deg > 0.0 || self.max_distance.is_some())
            .then(|| triangle_circumcircle(tri));
        if let (true, Some((_, rc))) = (self.min_angle_deg > 0.0, circle) {
            // radius-edge ratio: R / l_min = 1 / (2 sin(theta_min)).
            let lmin = (tri[1] - tri[0])
                .length()
                .min((tri[2] - tri[1]).length())
                .min((tri[0] - tri[2]).length());
            let bound = 1.0 / (2.0 * self.min_angle_deg.to_radians().sin());
            if lmin > 0.0 && rc.is_finite() {
                // Slightly relaxed so that facets at exactly the bound are not refined forever.
                let ratio = (rc / lmin) / bound;
                if ratio > 1.0 + 1e-12 {
                    bad = bad.max(ratio);
                }
            } else {
                bad = bad.max(f64::MAX / 4.0);
            }
        }
        if let (Some(d), Some((cc, _))) = (self.max_distance, circle) {
            let dist = (cc - c).length();
            if dist.is_finite() {
                bad = bad.max(dist / d);
            }
        }
        bad
    }
}

/// Circumcenter and circumradius of a triangle in 3D (f64 construction, relative to `a`).
pub fn triangle_circumcircle(t: [DVec3; 3]) -> (DVec3, f64) {
    let a = t[1] - t[0];
    let b = t[2] - t[0];
    let axb = a.cross(b);
    let d = 2.0 * axb.length_squared();
    if d.is_nan() || d <= 0.0 {
        return (t[0], f64::INFINITY);
    }
    let v = (b * a.length_squared() - a * b.length_squared()).cross(axb) / d;
    (t[0] + v, v.length())
}

/// Smallest angle of a triangle, in degrees (0 for a degenerate triangle).
pub fn min_angle_deg(t: [DVec3; 3]) -> f64 {
    let mut m = f64::INFINITY;
    for i in 0..3 {
        let p = t[i];
        let u = t[(i + 1) % 3] - p;
        let v = t[(i + 2) % 3] - p;
        let ang = u.cross(v).length().atan2(u.dot(v)).to_degrees();
        m = m.min(ang);
    }
    if m.is_finite() { m } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn circumcircle_of_right_triangle() {
        let (c, r) = triangle_circumcircle([DVec3::ZERO, DVec3::X * 2.0, DVec3::Y * 2.0]);
        assert!((c - DVec3::new(1.0, 1.0, 0.0)).length() < 1e-12);
        assert!((r - 2f64.sqrt()).abs() < 1e-12);
    }

    #[test]
    fn angle_criterion_flags_skinny_only() {
        let c = Criteria::default();
        let eq = [
            DVec3::ZERO,
            DVec3::X,
            DVec3::new(0.5, 3f64.sqrt() / 2.0, 0.0),
        ];
        assert!(c.badness(eq, DVec3::ZERO, 0.5) <= 1.0);
        assert!((min_angle_deg(eq) - 60.0).abs() < 1e-9);
        let skinny = [DVec3::ZERO, DVec3::X, DVec3::new(0.5, 0.1, 0.0)];
        assert!(c.badness(skinny, DVec3::ZERO, 0.5) > 1.0);
        assert!(min_angle_deg(skinny) < 30.0);
    }

    #[test]
    fn size_criterion() {
        let c = Criteria {
            size: Some(Sizing::Constant(0.1)),
            min_angle_deg: 0.0,
            max_distance: None,
        };
        let t = [DVec3::ZERO, DVec3::X, DVec3::Y];
        assert!(c.badness(t, DVec3::ZERO, 0.2) > 1.0);
        assert!(c.badness(t, DVec3::ZERO, 0.05) <= 1.0);
    }
}
