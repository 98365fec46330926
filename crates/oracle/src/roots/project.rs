//! Projection onto S (ours): what `verify` uses to measure distances to the surface.

use crate::Surface;
use glam::DVec3;

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
