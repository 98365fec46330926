//! Refinement criteria: when is a surface Delaunay ball *bad* (paper, sections 6.1 and 6.4.1).
//!
//! The size bound sigma is read only through this module ([`Criteria::sigma_at`] and the
//! crate-internal helpers beside it), and validated here once ([`Criteria::validate`]).

use crate::error::MeshError;
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
    /// A positive function with a known Lipschitz constant `L >= 0`: |sigma(x) - sigma(y)| <=
    /// L |x - y| (the fields of section 6.5 have L = eps' < 1). The mesher then decides most
    /// size tests from sigma at the facet's vertices (sigma(c) >= sigma(v) - L |c - v|)
    /// without evaluating sigma at the ball's center. Every facet is judged good or bad as
    /// [`Sizing::Field`] with the same function judges it; a facet proven bad is queued with an
    /// estimate of its badness, so the refinement order, and the mesh, can differ slightly
    /// (see `crate::restricted::vertex_sizes`).
    Lipschitz(Arc<dyn Fn(DVec3) -> f64 + Send + Sync>, f64),
}

impl Sizing {
    /// sigma(c).
    #[inline]
    pub fn at(&self, c: DVec3) -> f64 {
        match self {
            Sizing::Constant(s) => *s,
            Sizing::Field(f) | Sizing::Lipschitz(f, _) => f(c),
        }
    }

    /// The Lipschitz constant, when the field states one.
    #[inline]
    pub fn lipschitz(&self) -> Option<f64> {
        match self {
            Sizing::Lipschitz(_, l) => Some(*l),
            _ => None,
        }
    }

    /// Whether sigma varies (a function rather than a constant).
    #[inline]
    pub fn is_field(&self) -> bool {
        !matches!(self, Sizing::Constant(_))
    }
}

impl fmt::Debug for Sizing {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Sizing::Constant(s) => write!(f, "Constant({s})"),
            Sizing::Field(_) => write!(f, "Field(..)"),
            Sizing::Lipschitz(_, l) => write!(f, "Lipschitz(.., {l})"),
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

    /// Criteria with their bounds checked ([`Criteria::validate`]).
    ///
    /// ```
    /// use rdt_mesher::{Criteria, Sizing};
    /// assert!(Criteria::new(Some(Sizing::Constant(0.05)), 30.0, None).is_ok());
    /// assert!(Criteria::new(Some(Sizing::Constant(-1.0)), 30.0, None).is_err());
    /// assert!(Criteria::new(None, 40.0, None).is_err());
    /// ```
    pub fn new(
        size: Option<Sizing>,
        min_angle_deg: f64,
        max_distance: Option<f64>,
    ) -> Result<Self, MeshError> {
        let c = Criteria {
            size,
            min_angle_deg,
            max_distance,
        };
        c.validate()?;
        Ok(c)
    }

    /// Check the bounds: a constant sigma and the distance bound positive and finite, the
    /// angle bound in [0, 35) degrees. (A sizing field is checked where it is evaluated.)
    pub fn validate(&self) -> Result<(), MeshError> {
        if let Some(Sizing::Constant(s)) = &self.size
            && !(*s > 0.0 && s.is_finite())
        {
            return Err(MeshError::InvalidSize(*s));
        }
        if let Some(Sizing::Lipschitz(_, l)) = &self.size
            && !(*l >= 0.0 && l.is_finite())
        {
            return Err(MeshError::InvalidLipschitz(*l));
        }
        if !(self.min_angle_deg >= 0.0 && self.min_angle_deg < 35.0) {
            return Err(MeshError::InvalidAngle(self.min_angle_deg));
        }
        if let Some(d) = self.max_distance
            && !(d > 0.0 && d.is_finite())
        {
            return Err(MeshError::InvalidDistance(d));
        }
        Ok(())
    }

    /// sigma(c), or `None` without a size criterion.
    #[inline]
    pub fn sigma_at(&self, c: DVec3) -> Option<f64> {
        self.size.as_ref().map(|s| s.at(c))
    }

    /// [`Criteria::sigma_at`], with an error where a sizing field is not positive and finite
    /// (a constant was checked by [`Criteria::validate`]).
    pub(crate) fn sigma_checked(&self, c: DVec3) -> Result<Option<f64>, MeshError> {
        let sigma = self.sigma_at(c);
        if let (Some(field), Some(s)) = (&self.size, sigma)
            && field.is_field()
            && !(s > 0.0 && s.is_finite())
        {
            return Err(MeshError::InvalidSizeField { value: s, at: c });
        }
        Ok(sigma)
    }

    /// The length scale of the criteria at `c`: sigma(c), else the distance bound, else
    /// `default` (the radius bound of section 6.2's persistent balls).
    pub(crate) fn scale_at(&self, c: DVec3, default: f64) -> f64 {
        match self.sigma_at(c) {
            Some(s) => s,
            None => self.max_distance.unwrap_or(default),
        }
    }

    /// The distance criterion's ratio for the triangle `pts` and a ball centered at `c`:
    /// distance(circumcenter, c) over the bound (`None` without a distance bound).
    pub(crate) fn distance_ratio(&self, pts: [DVec3; 3], c: DVec3) -> Option<f64> {
        self.max_distance.map(|d| {
            let (cc, _) = triangle_circumcircle(pts);
            (cc - c).length() / d
        })
    }

    /// How bad the ball is: a value > 1 means bad (the larger the worse), <= 1 good.
    /// `tri` are the facet's vertices, `c` the ball center, `r` its radius.
    pub fn badness(&self, tri: [DVec3; 3], c: DVec3, r: f64) -> f64 {
        self.badness_with_sigma(tri, c, r, self.sigma_at(c))
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
        if let Some((_, rc)) = circle {
            bad = bad.max(self.angle_badness(tri, rc, self.two_sin_min_angle()));
        }
        if let (Some(d), Some((cc, _))) = (self.max_distance, circle) {
            let dist = (cc - c).length();
            if dist.is_finite() {
                bad = bad.max(dist / d);
            }
        }
        bad
    }

    /// A lower bound of [`Criteria::badness`] over every ball circumscribing the triangle
    /// `tri`, known without the ball: the angle criterion (a property of the triangle), and
    /// with a constant sigma the triangle's circumradius over sigma (a circumscribing ball
    /// is at least as large as the circumcircle). The mesher uses it to delay the oracle's
    /// crossing for facets that are bad anyway.
    ///
    /// ```
    /// use glam::DVec3;
    /// use rdt_mesher::Criteria;
    /// let c = Criteria::uniform(0.1);
    /// let tri = [DVec3::ZERO, DVec3::X, DVec3::Y];
    /// // Circumradius sqrt(2)/2 over sigma 0.1, whatever the ball's center.
    /// let lb = c.badness_lower_bound(tri);
    /// assert!((lb - 0.5f64.sqrt() / 0.1).abs() < 1e-12);
    /// assert!(c.badness(tri, DVec3::new(0.5, 0.5, 0.3), 0.5f64.sqrt().hypot(0.3)) >= lb);
    /// ```
    pub fn badness_lower_bound(&self, tri: [DVec3; 3]) -> f64 {
        self.facet_bound(tri, self.two_sin_min_angle()).0
    }

    /// 2 sin(min_angle_deg): the angle criterion holds when R / l_min <= 1 / (2 sin(theta)).
    pub(crate) fn two_sin_min_angle(&self) -> f64 {
        2.0 * self.min_angle_deg.to_radians().sin()
    }

    /// [`Criteria::badness_lower_bound`] and the triangle's circumcenter (when the angle or
    /// distance criterion needs it, else NaN): the part of the badness that does not depend
    /// on the ball, for [`Criteria::badness_from_bound`]. `two_sin` is
    /// [`Criteria::two_sin_min_angle`] (computed once by the caller).
    pub(crate) fn facet_bound(&self, tri: [DVec3; 3], two_sin: f64) -> (f64, DVec3) {
        let constant = match self.size {
            Some(Sizing::Constant(s)) => Some(s),
            _ => None,
        };
        if self.min_angle_deg <= 0.0 && self.max_distance.is_none() && constant.is_none() {
            return (0.0, DVec3::NAN);
        }
        let (cc, rc) = triangle_circumcircle(tri);
        let mut bad: f64 = 0.0;
        if let Some(s) = constant
            && rc.is_finite()
        {
            bad = rc / s;
        }
        (bad.max(self.angle_badness(tri, rc, two_sin)), cc)
    }

    /// [`Criteria::badness_with_sigma`] from the facet's [`Criteria::facet_bound`] `(lb, cc)`:
    /// the same value, up to rounding, when `r` is the radius of a ball through the triangle
    /// (with a constant sigma the bound's rc / sigma is at most r / sigma). The public
    /// `badness` keeps its own formula: it takes any `r` as given, even one below the
    /// circumradius.
    pub(crate) fn badness_from_bound(
        &self,
        (lb, cc): (f64, DVec3),
        c: DVec3,
        r: f64,
        sigma: Option<f64>,
    ) -> f64 {
        let mut bad = lb;
        if let Some(sigma) = sigma {
            bad = bad.max(r / sigma);
        }
        if let Some(d) = self.max_distance {
            let dist = (cc - c).length();
            if dist.is_finite() {
                bad = bad.max(dist / d);
            }
        }
        bad
    }

    /// The angle criterion's badness of `tri` with circumradius `rc` (0 when it holds or is
    /// off): the radius-edge ratio over its bound, R / l_min = 1 / (2 sin(theta_min)).
    fn angle_badness(&self, tri: [DVec3; 3], rc: f64, two_sin: f64) -> f64 {
        if self.min_angle_deg <= 0.0 {
            return 0.0;
        }
        let lmin = (tri[1] - tri[0])
            .length()
            .min((tri[2] - tri[1]).length())
            .min((tri[0] - tri[2]).length());
        if lmin > 0.0 && rc.is_finite() {
            // Slightly relaxed so that facets at exactly the bound are not refined forever.
            let ratio = (rc / lmin) * two_sin;
            if ratio > 1.0 + 1e-12 { ratio } else { 0.0 }
        } else {
            f64::MAX / 4.0
        }
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

/// Smallest angle of a triangle, in degrees (0 for a degenerate triangle): the angle
/// opposite the shortest edge.
pub fn min_angle_deg(t: [DVec3; 3]) -> f64 {
    // Edge i is opposite vertex i.
    let len2 = |i: usize| (t[(i + 2) % 3] - t[(i + 1) % 3]).length_squared();
    let (l0, l1, l2) = (len2(0), len2(1), len2(2));
    let i = if l0 <= l1 && l0 <= l2 {
        0
    } else if l1 <= l2 {
        1
    } else {
        2
    };
    let p = t[i];
    let u = t[(i + 1) % 3] - p;
    let v = t[(i + 2) % 3] - p;
    let ang = u.cross(v).length().atan2(u.dot(v)).to_degrees();
    if ang.is_finite() { ang } else { 0.0 }
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

    proptest::proptest! {
        /// The angle opposite the shortest edge is the smallest of the three.
        #[test]
        fn min_angle_is_the_smallest_of_the_three(
            a in proptest::array::uniform3(-1.0f64..1.0),
            b in proptest::array::uniform3(-1.0f64..1.0),
            c in proptest::array::uniform3(-1.0f64..1.0),
        ) {
            let t = [DVec3::from(a), DVec3::from(b), DVec3::from(c)];
            let reference = (0..3)
                .map(|i| {
                    let u = t[(i + 1) % 3] - t[i];
                    let v = t[(i + 2) % 3] - t[i];
                    u.cross(v).length().atan2(u.dot(v)).to_degrees()
                })
                .fold(f64::INFINITY, f64::min);
            proptest::prop_assert!((min_angle_deg(t) - reference).abs() < 1e-9, "{} vs {reference}", min_angle_deg(t));
        }


        /// For any triangle and any ball through its vertices (centered on the line through
        /// its circumcenter, normal to its plane), the lower bound is at most the badness, and
        /// the badness from the bound equals the direct one, up to rounding.
        #[test]
        fn lower_bound_holds_for_every_circumscribing_ball(
            a in proptest::array::uniform3(-1.0f64..1.0),
            b in proptest::array::uniform3(-1.0f64..1.0),
            c in proptest::array::uniform3(-1.0f64..1.0),
            h in -3.0f64..3.0,
            sigma in 0.01f64..2.0,
            angle in proptest::sample::select(vec![0.0, 20.0, 30.0]),
            dist in proptest::option::of(0.01f64..1.0),
        ) {
            let tri = [DVec3::from(a), DVec3::from(b), DVec3::from(c)];
            let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
            proptest::prop_assume!(n.length() > 1e-6);
            let (cc, _) = triangle_circumcircle(tri);
            let center = cc + n.normalize() * h;
            let r = tri.iter().map(|v| v.distance(center)).fold(0.0, f64::max);
            let crit = Criteria {
                size: Some(Sizing::Constant(sigma)),
                min_angle_deg: angle,
                max_distance: dist,
            };
            let direct = crit.badness(tri, center, r);
            let lb = crit.badness_lower_bound(tri);
            proptest::prop_assert!(lb <= direct * (1.0 + 1e-12), "{lb} > {direct}");
            let bound = crit.facet_bound(tri, crit.two_sin_min_angle());
            let via = crit.badness_from_bound(bound, center, r, Some(sigma));
            proptest::prop_assert!((via - direct).abs() <= 1e-12 * direct.max(1.0), "{via} vs {direct}");
        }
    }
}
