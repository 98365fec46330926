//! Root finding shared by the backends: bisection, subdivision, random-line seeds, projection.

use crate::{OracleError, Surface};
use glam::DVec3;

/// True if `v` is -1, 0 or 1: a value of a sign-only function, on which interpolation
/// (secant, regula falsi, Newton) is meaningless and bisection must be used.
#[inline]
pub fn is_sign_value(v: f64) -> bool {
    v == 0.0 || v == 1.0 || v == -1.0
}

/// Bisection on `[a, b]` where `fa` and `fb` have opposite signs, until the bracket is shorter
/// than `tol`. Returns the midpoint of the final bracket, which is within `tol / 2` of a sign
/// change. Works for sign-only functions. Signs follow the bipolar convention: `f < 0` is inside,
/// `f >= 0` (zero included) outside, so a zero at an end is found as the limit of the bracket.
///
/// If `f` returns NaN at a probe, returns a point with NaN coordinates (never a silently wrong
/// point); use [`try_bisect`] to get the offending point as an error.
pub fn bisect(f: impl Fn(DVec3) -> f64, a: DVec3, fa: f64, b: DVec3, fb: f64, tol: f64) -> DVec3 {
    try_bisect(f, a, fa, b, fb, tol).unwrap_or(DVec3::NAN)
}

/// [`bisect`] reporting a NaN value (at an end or at a probe) as [`OracleError::NaN`] with the
/// point. If `fa` and `fb` have the same sign (a violated precondition), returns the end with the
/// smaller |value|.
pub fn try_bisect(
    f: impl Fn(DVec3) -> f64,
    a: DVec3,
    fa: f64,
    b: DVec3,
    fb: f64,
    tol: f64,
) -> Result<DVec3, OracleError> {
    check_ends(a, fa, b, fb)?;
    let a_neg = fa < 0.0;
    if a_neg == (fb < 0.0) {
        return Ok(if fa.abs() <= fb.abs() { a } else { b });
    }
    let (mut a, mut b) = (a, b);
    let tol2 = tol * tol;
    for _ in 0..2100 {
        if (b - a).length_squared() <= tol2 {
            break;
        }
        let m = 0.5 * (a + b);
        if m == a || m == b {
            break; // the bracket is down to adjacent floats
        }
        let fm = f(m);
        if fm.is_nan() {
            return Err(nan_at(m));
        }
        if (fm < 0.0) == a_neg {
            a = m;
        } else {
            b = m;
        }
    }
    Ok(0.5 * (a + b))
}

fn nan_at(p: DVec3) -> OracleError {
    OracleError::NaN(p.x, p.y, p.z)
}

fn check_ends(a: DVec3, fa: f64, b: DVec3, fb: f64) -> Result<(), OracleError> {
    if fa.is_nan() {
        return Err(nan_at(a));
    }
    if fb.is_nan() {
        return Err(nan_at(b));
    }
    Ok(())
}

/// Safeguarded root finding on `[a, b]` (same contract as [`try_bisect`]: the result is within
/// `tol / 2` of a sign change of `f`, with `f < 0` inside and `f >= 0` outside).
///
/// Uses the Illinois variant of regula falsi, which converges superlinearly on smooth functions,
/// with three safeguards: bisection when the values are sign-only (-1, 0, 1) or an end value is
/// exactly 0; a bisection step whenever the bracket has not halved within three steps (so the
/// cost is at most about four times that of bisection); and interpolated probes kept about
/// `tol` inside the bracket, so the bracket closes on the root from both sides.
pub fn try_find_root(
    f: impl Fn(DVec3) -> f64,
    a: DVec3,
    fa: f64,
    b: DVec3,
    fb: f64,
    tol: f64,
) -> Result<DVec3, OracleError> {
    check_ends(a, fa, b, fb)?;
    let neg0 = fa < 0.0;
    if neg0 == (fb < 0.0) {
        return Ok(if fa.abs() <= fb.abs() { a } else { b });
    }
    let d = b - a;
    let len = d.length();
    if len.is_nan() || len <= tol {
        return Ok(0.5 * (a + b));
    }
    if is_sign_value(fa) && is_sign_value(fb) {
        return try_bisect(f, a, fa, b, fb, tol);
    }
    let tt = tol / len; // tolerance in parameter units
    let (mut t0, mut g0, mut t1, mut g1) = (0.0_f64, fa, 1.0_f64, fb);
    let mut last_replaced = 2u8; // 0: t0, 1: t1, 2: none yet
    let mut w_ref = 1.0;
    let mut stall = 0;
    for _ in 0..400 {
        let w = t1 - t0;
        if w <= tt {
            break;
        }
        if w <= 0.5 * w_ref {
            w_ref = w;
            stall = 0;
        } else {
            stall += 1;
        }
        let mid = 0.5 * (t0 + t1);
        let t = if stall >= 3 || g0 == 0.0 || g1 == 0.0 {
            stall = 0;
            w_ref = w;
            mid
        } else {
            let s = t0 - g0 * (t1 - t0) / (g1 - g0);
            // Keep probes about `tol` inside the bracket: when the estimate is within `tol` of
            // an end, the probe lands just past the root and closes the bracket.
            let (lo, hi) = (t0 + 0.99 * tt, t1 - 0.99 * tt);
            if s.is_finite() && lo < hi {
                s.clamp(lo, hi)
            } else {
                mid
            }
        };
        if t <= t0 || t >= t1 {
            break; // adjacent floats
        }
        let p = a + d * t;
        let g = f(p);
        if g.is_nan() {
            return Err(nan_at(p));
        }
        if (g < 0.0) == neg0 {
            t0 = t;
            g0 = g;
            if last_replaced == 0 {
                g1 *= 0.5; // Illinois: the retained end keeps its sign, its weight halves
            }
            last_replaced = 0;
        } else {
            t1 = t;
            g1 = g;
            if last_replaced == 1 {
                g0 *= 0.5;
            }
            last_replaced = 1;
        }
    }
    Ok(a + d * (0.5 * (t0 + t1)))
}

/// All sign changes of `f` on `[a, b]` sampled at steps of at most `step`, each refined by
/// bisection, pushed in order from `a`. If `f` returns NaN, pushes one point with NaN
/// coordinates and stops (see [`try_all_crossings`]).
pub fn all_crossings(
    f: impl Fn(DVec3) -> f64,
    a: DVec3,
    b: DVec3,
    step: f64,
    tol: f64,
    out: &mut Vec<DVec3>,
) {
    if try_all_crossings(f, a, b, step, tol, out).is_err() {
        out.push(DVec3::NAN);
    }
}

/// [`all_crossings`] reporting NaN as an error (crossings found before it stay in `out`). Each
/// sign change is refined by [`try_find_root`] (bisection for sign-only values).
pub fn try_all_crossings(
    f: impl Fn(DVec3) -> f64,
    a: DVec3,
    b: DVec3,
    step: f64,
    tol: f64,
    out: &mut Vec<DVec3>,
) -> Result<(), OracleError> {
    let len = (b - a).length();
    let n = if step > 0.0 && (len / step).is_finite() {
        ((len / step).ceil() as usize).clamp(1, 1 << 20)
    } else {
        1
    };
    let mut p0 = a;
    let mut f0 = f(a);
    if f0.is_nan() {
        return Err(nan_at(a));
    }
    for i in 1..=n {
        let p1 = if i == n {
            b
        } else {
            a + (b - a) * (i as f64 / n as f64)
        };
        let f1 = f(p1);
        if f1.is_nan() {
            return Err(nan_at(p1));
        }
        if (f0 < 0.0) != (f1 < 0.0) {
            out.push(try_find_root(&f, p0, f0, p1, f1, tol)?);
        }
        p0 = p1;
        f0 = f1;
    }
    Ok(())
}

/// Deterministic SplitMix64 generator: small, seedable, enough for seeds and BRIO rounds.
#[derive(Clone, Debug)]
pub struct SplitMix64(pub u64);

impl SplitMix64 {
    /// The next 64 random bits (SplitMix64, deterministic for a given state).
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
    /// Uniform on the unit sphere.
    pub fn unit_vector(&mut self) -> DVec3 {
        loop {
            let v = DVec3::new(
                2.0 * self.next_f64() - 1.0,
                2.0 * self.next_f64() - 1.0,
                2.0 * self.next_f64() - 1.0,
            );
            let l2 = v.length_squared();
            if l2 > 1e-6 && l2 <= 1.0 {
                return v / l2.sqrt();
            }
        }
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
