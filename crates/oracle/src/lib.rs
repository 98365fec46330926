//! Surface oracles for restricted Delaunay meshing (Boissonnat & Oudot, sections 6.4.2 and 6.6).
//!
//! A surface S is the zero set of a value function (negative inside the solid, positive outside).
//! The mesher reaches S only through the [`Surface`] trait:
//! - the **bipolar oracle** ([`Surface::crossing`]): a segment whose end values have opposite
//!   signs crosses S an odd number of times; return one crossing;
//! - the **intersection oracle** ([`Surface::crossings`]): all points of a segment on S;
//! - P1 ([`Surface::seed_points`]): points on every component;
//! - a bounding sphere outside which the value is positive.

use glam::DVec3;

pub mod catalog;
pub mod expr;
pub mod image;
mod imls;
pub mod implicit;
pub mod pointset;
pub mod polyhedron;
pub mod roots;

/// A sphere holding the whole surface; the value is positive on and outside it.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BoundingSphere {
    pub center: DVec3,
    pub radius: f64,
}

impl BoundingSphere {
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

/// Errors raised by oracles at query time.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum OracleError {
    #[error("the surface function returned NaN at ({0}, {1}, {2}); fix the function or its domain")]
    NaN(f64, f64, f64),
}

/// A surface known through an oracle. Implementations are `Send + Sync` so that bulk
/// evaluations (seeding, verification) can run in parallel.
pub trait Surface: Send + Sync {
    /// Bounding sphere: the value is positive on it and outside it.
    fn bounding_sphere(&self) -> BoundingSphere;

    /// Signed value: negative inside the solid, positive outside, zero on S.
    /// Only the sign is required to be meaningful (sign-only functions must work).
    /// May return NaN; callers turn NaN into [`OracleError::NaN`].
    fn value(&self, p: DVec3) -> f64;

    /// Precision of crossing points (absolute length). Default: 1e-7 of the bounding radius.
    fn tolerance(&self) -> f64 {
        1e-7 * self.bounding_sphere().radius
    }

    /// Bipolar oracle: `fa = value(a)` and `fb = value(b)` have opposite signs; return a point
    /// of S on `[a, b]` within [`Surface::tolerance`]. Default: safeguarded bisection.
    fn crossing(&self, a: DVec3, fa: f64, b: DVec3, fb: f64) -> DVec3 {
        roots::bisect(|p| self.value(p), a, fa, b, fb, self.tolerance())
    }

    /// Intersection oracle: push every point of `[a, b]` on S into `out` (sorted from `a`).
    /// Default: sample the segment at steps of at most [`Surface::crossing_step`] and bisect every
    /// sign change (so crossings closer than the step may be missed, as the paper's Θ(1/Δ) oracle).
    fn crossings(&self, a: DVec3, b: DVec3, out: &mut Vec<DVec3>) {
        roots::all_crossings(
            |p| self.value(p),
            a,
            b,
            self.crossing_step(),
            self.tolerance(),
            out,
        )
    }

    /// Subdivision step of the default intersection oracle. Default: 1e-3 of the bounding radius.
    fn crossing_step(&self) -> f64 {
        1e-3 * self.bounding_sphere().radius
    }

    /// P1: points on S, at least one on every component the backend can find.
    /// Deterministic for a given seed. Default: crossings of random lines through the
    /// bounding sphere.
    fn seed_points(&self, seed: u64) -> Vec<DVec3> {
        roots::random_line_seeds(self, 64, seed)
    }

    /// Gradient of the value (outward normal direction on S), if available.
    /// Default: central differences.
    fn gradient(&self, p: DVec3) -> DVec3 {
        let h = 1e-6 * self.bounding_sphere().radius;
        let dx = DVec3::X * h;
        let dy = DVec3::Y * h;
        let dz = DVec3::Z * h;
        DVec3::new(
            self.value(p + dx) - self.value(p - dx),
            self.value(p + dy) - self.value(p - dy),
            self.value(p + dz) - self.value(p - dz),
        ) / (2.0 * h)
    }

    /// Closest point of S to `p`, if the backend can compute it (used by `verify`). The
    /// default: gradient steps from `p`, else the nearest crossing on rays from `p`
    /// ([`roots::project_robust`]).
    fn project(&self, p: DVec3) -> Option<DVec3> {
        roots::project_robust(self, p)
    }

    /// How far (degrees) the direction of [`Surface::gradient`] at `p` may be from the normal
    /// of the surface the data stands for, because of the data's own rounding. 0 (the
    /// default) for exact backends; images with integer voxels bound it from the rounding of
    /// the corner values (see `ImageSurface`). `verify` allows it on top of lemma 3.1.
    fn normal_uncertainty_deg(&self, _p: DVec3) -> f64 {
        0.0
    }

    /// P2: a positive lower bound (or estimate) of the smallest distance from S to its medial
    /// axis, d_M^inf, if the backend knows one.
    fn dm_inf_hint(&self) -> Option<f64> {
        None
    }
}

impl<S: Surface + ?Sized> Surface for &S {
    fn bounding_sphere(&self) -> BoundingSphere {
        (**self).bounding_sphere()
    }
    fn value(&self, p: DVec3) -> f64 {
        (**self).value(p)
    }
    fn tolerance(&self) -> f64 {
        (**self).tolerance()
    }
    fn crossing(&self, a: DVec3, fa: f64, b: DVec3, fb: f64) -> DVec3 {
        (**self).crossing(a, fa, b, fb)
    }
    fn crossings(&self, a: DVec3, b: DVec3, out: &mut Vec<DVec3>) {
        (**self).crossings(a, b, out)
    }
    fn crossing_step(&self) -> f64 {
        (**self).crossing_step()
    }
    fn seed_points(&self, seed: u64) -> Vec<DVec3> {
        (**self).seed_points(seed)
    }
    fn gradient(&self, p: DVec3) -> DVec3 {
        (**self).gradient(p)
    }
    fn project(&self, p: DVec3) -> Option<DVec3> {
        (**self).project(p)
    }
    fn normal_uncertainty_deg(&self, p: DVec3) -> f64 {
        (**self).normal_uncertainty_deg(p)
    }
    fn dm_inf_hint(&self) -> Option<f64> {
        (**self).dm_inf_hint()
    }
}
