//! The bounding sphere of P1's setting (section 6.4.2): the value is positive on and outside
//! it, so the mesher clips Voronoi edges and rays to it.

use glam::DVec3;

/// A sphere holding the whole surface; the value is positive on and outside it.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BoundingSphere {
    /// The center.
    pub center: DVec3,
    /// The radius (positive).
    pub radius: f64,
}

impl BoundingSphere {
    /// The sphere of radius `radius` centred at the origin.
    ///
    /// ```
    /// let b = oracle::BoundingSphere::at_origin(2.0);
    /// assert!(b.contains(glam::DVec3::X) && !b.contains(glam::DVec3::splat(2.0)));
    /// ```
    pub const fn at_origin(radius: f64) -> BoundingSphere {
        BoundingSphere {
            center: DVec3::ZERO,
            radius,
        }
    }

    /// Whether `p` is in the closed ball.
    pub fn contains(&self, p: DVec3) -> bool {
        (p - self.center).length_squared() <= self.radius * self.radius
    }
    /// Clip the segment `[a, b]` to the ball; `None` if it misses the ball (or an end is not
    /// finite). Robust to ends far away (e.g. circumcenters of nearly flat tetrahedra at
    /// 1e200): the line is parametrized by arc length along a unit direction, so nothing
    /// overflows. Unclipped ends are returned exactly, so `clip_segment(b, a)` gives the same
    /// ends swapped.
    pub fn clip_segment(&self, a: DVec3, b: DVec3) -> Option<(DVec3, DVec3)> {
        if !(a.is_finite() && b.is_finite()) {
            return None;
        }
        let ia = self.contains(a);
        let ib = self.contains(b);
        if ia && ib {
            return Some((a, b));
        }
        let d = b - a;
        let scale = d.abs().max_element();
        if scale.is_nan() || scale <= 0.0 || scale.is_infinite() {
            return None;
        }
        let ds = d / scale;
        let len = ds.length() * scale;
        let u = ds.normalize();
        let (s0, s1) = self.line_params_unit(a, u)?;
        let (s0, s1) = (s0.max(0.0), s1.min(len));
        if s0 > s1 {
            return None;
        }
        let pa = if ia { a } else { a + u * s0 };
        let pb = if ib { b } else { a + u * s1 };
        Some((pa, pb))
    }
    /// Clip the ray from `origin` along `dir` to the ball; `None` if it misses the ball.
    pub fn clip_ray(&self, origin: DVec3, dir: DVec3) -> Option<(DVec3, DVec3)> {
        let u = dir.normalize_or_zero();
        if !(origin.is_finite() && u != DVec3::ZERO) {
            return None;
        }
        let (s0, s1) = self.line_params_unit(origin, u)?;
        let s0 = s0.max(0.0);
        (s0 <= s1).then(|| (origin + u * s0, origin + u * s1))
    }
    /// Parameters (arc length along the unit vector `u`) where the line `a + s u` enters and
    /// leaves the ball.
    fn line_params_unit(&self, a: DVec3, u: DVec3) -> Option<(f64, f64)> {
        let m = a - self.center;
        let tc = -m.dot(u);
        // Squared distance from the center to the line, computed from the closest point
        // (no cancellation of two huge squares).
        let closest = m + u * tc;
        let h2 = self.radius * self.radius - closest.length_squared();
        if h2.is_nan() || h2 < 0.0 {
            return None;
        }
        let h = h2.sqrt();
        Some((tc - h, tc + h))
    }
}
