//! The oracle interface (sections 6.4.2 and 6.6): the [`Surface`] trait through which the
//! mesher, the seeding and `verify` reach a surface, and the
//! surface-generic algorithms behind the trait's provided methods: P1 by random lines
//! (section 6.4.3's last remark) and the projection `verify` uses. (They live in this file
//! because the trait's defaults call them and they call the trait.)

use crate::BoundingSphere;
use crate::roots::Ends;
use crate::roots::bisect::bisect;
use crate::roots::rng::SplitMix64;
use crate::roots::scan::all_crossings;
use glam::DVec3;

/// A surface known through an oracle. Implementations are `Send + Sync` so that bulk
/// evaluations (seeding, verification) can run in parallel.
///
/// Two methods are required; everything else has a default built on them (as parry's shape
/// queries: one required method, provided helpers), which a backend overrides when it knows
/// better. The methods come in four groups:
///
/// | group | methods | used by |
/// |---|---|---|
/// | required | [`bounding_sphere`](Surface::bounding_sphere), [`value`](Surface::value) | everything |
/// | oracles (section 6.4.2) | [`crossing`](Surface::crossing) (bipolar), [`crossings`](Surface::crossings) (intersection), [`tolerance`](Surface::tolerance), [`crossing_step`](Surface::crossing_step), [`gradient`](Surface::gradient) | the mesher |
/// | hints P1 / P2 (section 6.4.3) | [`seed_points`](Surface::seed_points), [`dm_inf_hint`](Surface::dm_inf_hint) | initialization, default sizing |
/// | verification support | [`project`](Surface::project), [`normal_uncertainty_deg`](Surface::normal_uncertainty_deg), [`data_defined`](Surface::data_defined) | `verify` only |
///
/// ```
/// use glam::DVec3;
/// use oracle::{BoundingSphere, Surface};
/// // The unit sphere: the two required methods are enough.
/// struct Sphere;
/// impl Surface for Sphere {
///     fn bounding_sphere(&self) -> BoundingSphere {
///         BoundingSphere { center: DVec3::ZERO, radius: 2.0 }
///     }
///     fn value(&self, p: DVec3) -> f64 { p.length() - 1.0 }
/// }
/// let (a, b) = (DVec3::ZERO, DVec3::new(2.0, 0.0, 0.0));
/// let c = Sphere.crossing(a, Sphere.value(a), b, Sphere.value(b));
/// assert!((c.x - 1.0).abs() <= Sphere.tolerance());
/// ```
pub trait Surface: Send + Sync {
    // ----- Required -----

    /// Bounding sphere: the value is positive on it and outside it.
    fn bounding_sphere(&self) -> BoundingSphere;

    /// Signed value: negative inside the solid, positive outside, zero on S.
    /// Only the sign is required to be meaningful (sign-only functions must work).
    /// May return NaN; callers turn NaN into [`OracleError::NaN`](crate::OracleError::NaN).
    fn value(&self, p: DVec3) -> f64;

    // ----- Oracles (section 6.4.2) -----

    /// Precision of crossing points (absolute length). Default: 1e-7 of the bounding radius.
    fn tolerance(&self) -> f64 {
        1e-7 * self.bounding_sphere().radius
    }

    /// Bipolar oracle: `fa = value(a)` and `fb = value(b)` have opposite signs; return a point
    /// of S on `[a, b]` within [`Surface::tolerance`]. Default: safeguarded bisection
    /// ([`roots::bisect`](crate::roots::bisect)).
    fn crossing(&self, a: DVec3, fa: f64, b: DVec3, fb: f64) -> DVec3 {
        bisect(|p| self.value(p), Ends::new(a, fa, b, fb), self.tolerance())
    }

    /// Intersection oracle: push every point of `[a, b]` on S into `out` (sorted from `a`).
    /// Default: sample the segment at steps of at most [`Surface::crossing_step`] and refine
    /// every sign change ([`roots::all_crossings`](crate::roots::all_crossings)), so crossings
    /// closer than the step may be
    /// missed, as the paper's Θ(1/Δ) oracle.
    fn crossings(&self, a: DVec3, b: DVec3, out: &mut Vec<DVec3>) {
        all_crossings(self, a, b, out)
    }

    /// Subdivision step of the default intersection oracle. Default: 1e-3 of the bounding radius.
    fn crossing_step(&self) -> f64 {
        1e-3 * self.bounding_sphere().radius
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

    // ----- Hints P1 and P2 (section 6.4.3) -----

    /// P1: points on S, at least one on every component the backend can find.
    /// Deterministic for a given seed. Default: crossings of random lines through the
    /// bounding sphere ([`random_line_seeds`]).
    fn seed_points(&self, seed: u64) -> Vec<DVec3> {
        random_line_seeds(self, 64, seed)
    }

    /// P2: a positive lower bound (or estimate) of the smallest distance from S to its medial
    /// axis, d_M^inf, if the backend knows one.
    fn dm_inf_hint(&self) -> Option<f64> {
        None
    }

    // ----- Verification support (used by `verify` only) -----

    /// Closest point of S to `p`, if the backend can compute it (used by `verify`). The
    /// default: gradient steps from `p`, else the nearest crossing on rays from `p`
    /// ([`project_robust`]).
    fn project(&self, p: DVec3) -> Option<DVec3> {
        project_robust(self, p)
    }

    /// Whether [`Surface::project`] is the exact closest point of what `verify` measures the
    /// mesh against (the input triangles of a polyhedron, smoothed or not), so that no search
    /// along rays can find a nearer one. Default: false (a projection by gradient steps may stop at
    /// a point that is not the nearest, and `verify` checks it by rays).
    fn exact_projection(&self) -> bool {
        false
    }

    /// How far (degrees) the direction of [`Surface::gradient`] at `p` may be from the normal
    /// of the surface the data stands for, because of the data's own rounding. 0 (the
    /// default) for exact backends; images with integer voxels bound it from the rounding of
    /// the corner values (see `ImageSurface`). `verify` allows it on top of lemma 3.1.
    fn normal_uncertainty_deg(&self, _p: DVec3) -> f64 {
        0.0
    }

    /// Whether S near `p` is the surface the input data shows: `None` (the default) for
    /// backends where S is given everywhere (functions, images, meshes). A point set answers
    /// `Some(true)` where its value is the IMLS quotient of the data alone and `Some(false)`
    /// beyond (an extrapolation, the far field's sign boundary), where no theorem speaks of
    /// S. `verify` measures the theorems' figures (normals, theorem 4.7) where it holds.
    fn data_defined(&self, _p: DVec3) -> Option<bool> {
        None
    }

    /// The image behind the surface, when it is one: its value is a trilinear interpolant
    /// of grid values, so `verify` measures distances to S exactly, cell by cell, instead of
    /// trusting [`Surface::project`]. Default `None`.
    fn as_image(&self) -> Option<&crate::image::ImageSurface> {
        None
    }
}

/// A reference to a surface is the surface (every method forwards, overrides included).
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
    fn gradient(&self, p: DVec3) -> DVec3 {
        (**self).gradient(p)
    }
    fn seed_points(&self, seed: u64) -> Vec<DVec3> {
        (**self).seed_points(seed)
    }
    fn dm_inf_hint(&self) -> Option<f64> {
        (**self).dm_inf_hint()
    }
    fn project(&self, p: DVec3) -> Option<DVec3> {
        (**self).project(p)
    }
    fn exact_projection(&self) -> bool {
        (**self).exact_projection()
    }
    fn normal_uncertainty_deg(&self, p: DVec3) -> f64 {
        (**self).normal_uncertainty_deg(p)
    }
    fn data_defined(&self, p: DVec3) -> Option<bool> {
        (**self).data_defined(p)
    }
    fn as_image(&self) -> Option<&crate::image::ImageSurface> {
        (**self).as_image()
    }
}

/// P1 by random lines (section 6.4.3's last remark): shoot `lines` random chords of the
/// bounding sphere and keep every crossing found by the intersection oracle.
pub fn random_line_seeds<S: Surface + ?Sized>(s: &S, lines: usize, seed: u64) -> Vec<DVec3> {
    let bs = s.bounding_sphere();
    let mut rng = SplitMix64(seed ^ 0x5EED_5EED);
    let mut out = Vec::new();
    for _ in 0..lines {
        let a = bs.center + rng.unit_vector() * bs.radius;
        let b = bs.center + rng.unit_vector() * bs.radius;
        s.crossings(a, b, &mut out);
    }
    out
}

/// A point of S near `p`: [`project_newton`], else (a flat or noisy value function, where the
/// gradient steps stall) the nearest crossing found on rays from `p`
/// ([`nearest_crossing_on_rays`]). The fallback's point is on S but maybe not the closest, so
/// the distance it gives is an upper bound: a check built on it errs on the safe side.
///
/// ```
/// use glam::DVec3;
/// use oracle::{BoundingSphere, Surface, roots};
/// // The unit sphere with a value that is flat (clamped) away from it: gradient steps stall.
/// struct Flat;
/// impl Surface for Flat {
///     fn bounding_sphere(&self) -> BoundingSphere {
///         BoundingSphere { center: DVec3::ZERO, radius: 2.0 }
///     }
///     fn value(&self, p: DVec3) -> f64 { (p.length() - 1.0).clamp(-0.05, 0.05) }
/// }
/// let p = DVec3::new(0.0, 0.0, 1.5);
/// assert!(roots::project_newton(&Flat, p).is_none());
/// let q = roots::project_robust(&Flat, p).unwrap();
/// assert!((q.length() - 1.0).abs() < 1e-6); // on S
/// assert!((q - p).length() < 0.51); // about the true distance 0.5, never below it
/// ```
pub fn project_robust<S: Surface + ?Sized>(s: &S, p: DVec3) -> Option<DVec3> {
    project_newton(s, p).or_else(|| nearest_crossing_on_rays(s, p))
}

/// Directions of [`nearest_crossing_on_rays`]: the 6 axes and 58 points of a Fibonacci
/// sphere.
fn ray_directions() -> Vec<DVec3> {
    let mut d = vec![
        DVec3::X,
        DVec3::NEG_X,
        DVec3::Y,
        DVec3::NEG_Y,
        DVec3::Z,
        DVec3::NEG_Z,
    ];
    let n = 58;
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    for i in 0..n {
        let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = golden * i as f64;
        d.push(DVec3::new(r * phi.cos(), r * phi.sin(), z));
    }
    d
}

/// The nearest point of S found on rays from `p` (see [`Surface::crossings`]): 64 rays
/// searched in shells of doubling radius, from 4 [`Surface::crossing_step`]s up to the
/// bounding sphere's diameter, until one meets S; then 4 rounds of 16 rays in narrowing cones
/// around the best ray (half-angles 0.35 to 0.044 rad), each as long as the best distance so
/// far. Rays are clipped to the bounding sphere (S lies inside it), so the work is at most
/// about 64 rays across it, wherever `p` is; non-finite crossings (a NaN value on the way)
/// are skipped. `None` if no ray meets S (or `p` is not finite).
pub fn nearest_crossing_on_rays<S: Surface + ?Sized>(s: &S, p: DVec3) -> Option<DVec3> {
    if !p.is_finite() {
        return None;
    }
    let bs = s.bounding_sphere();
    let step = s.crossing_step();
    if !(step > 0.0 && step.is_finite()) {
        return None;
    }
    let far = 2.0 * bs.radius + (p - bs.center).length();
    let mut buf = Vec::new();
    let mut nearest = |dirs: &[DVec3], r0: f64, r1: f64, best: &mut Option<(f64, DVec3)>| {
        for d in dirs {
            let Some((a, b)) = bs.clip_segment(p + *d * r0, p + *d * r1) else {
                continue;
            };
            buf.clear();
            s.crossings(a, b, &mut buf);
            for &q in &buf {
                let dist = (q - p).length();
                if q.is_finite() && best.is_none_or(|b| dist < b.0) {
                    *best = Some((dist, q));
                }
            }
        }
    };
    let dirs = ray_directions();
    let mut best: Option<(f64, DVec3)> = None;
    let (mut r0, mut r1) = (0.0, 4.0 * step);
    while best.is_none() {
        nearest(&dirs, r0, r1, &mut best);
        if best.is_none() && r1 >= far {
            return None;
        }
        (r0, r1) = (r1, (2.0 * r1).min(far));
    }
    let (mut dist, mut q) = best?;
    // Narrowing cones around the best ray.
    let mut half = 0.35f64;
    for _ in 0..4 {
        let axis = (q - p) / dist;
        if !axis.is_finite() {
            break;
        }
        let (u, v) = axis.any_orthonormal_pair();
        let mut cone = Vec::with_capacity(16);
        for ring in [0.5, 1.0] {
            let (sa, ca) = (half * ring).sin_cos();
            for k in 0..8 {
                let (sb, cb) = (k as f64 * std::f64::consts::FRAC_PI_4).sin_cos();
                cone.push(axis * ca + (u * cb + v * sb) * sa);
            }
        }
        let mut b = Some((dist, q));
        nearest(&cone, 0.0, dist * (1.0 + 1e-9), &mut b);
        (dist, q) = b?;
        half *= 0.5;
    }
    Some(q)
}

/// Newton-like projection of `p` onto S along the gradient (a few steps), checked: returns
/// `None` if it does not converge to a point with |value| small relative to the gradient.
pub fn project_newton<S: Surface + ?Sized>(s: &S, p: DVec3) -> Option<DVec3> {
    let mut x = p;
    let tol = s.tolerance();
    for _ in 0..30 {
        let f = s.value(x);
        let g = s.gradient(x);
        let g2 = g.length_squared();
        if !f.is_finite() || g2.is_nan() || g2 <= 0.0 {
            return None;
        }
        let step = g * (f / g2);
        x -= step;
        if step.length() < tol {
            return Some(x);
        }
    }
    None
}
