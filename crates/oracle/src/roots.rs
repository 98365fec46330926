//! Root finding shared by the backends: bisection, subdivision, random-line seeds, projection.

use crate::Surface;
use glam::DVec3;

/// Bisection on `[a, b]` where `fa` and `fb` have opposite signs, until the bracket is shorter
/// than `tol`. Returns the midpoint of the final bracket. Works for sign-only functions.
pub fn bisect(f: impl Fn(DVec3) -> f64, a: DVec3, fa: f64, b: DVec3, fb: f64, tol: f64) -> DVec3 {
    let (mut a, mut b) = (a, b);
    let a_neg = fa < 0.0;
    debug_assert!(a_neg != (fb < 0.0));
    let _ = fb;
    let tol2 = tol * tol;
    for _ in 0..200 {
        if (b - a).length_squared() <= tol2 {
            break;
        }
        let m = 0.5 * (a + b);
        let fm = f(m);
        if (fm < 0.0) == a_neg {
            a = m;
        } else {
            b = m;
        }
    }
    0.5 * (a + b)
}

/// All sign changes of `f` on `[a, b]` sampled at steps of at most `step`, each refined by
/// bisection, pushed in order from `a`.
pub fn all_crossings(
    f: impl Fn(DVec3) -> f64,
    a: DVec3,
    b: DVec3,
    step: f64,
    tol: f64,
    out: &mut Vec<DVec3>,
) {
    let len = (b - a).length();
    let n = ((len / step).ceil() as usize).clamp(1, 1 << 20);
    let mut p0 = a;
    let mut f0 = f(a);
    for i in 1..=n {
        let p1 = a + (b - a) * (i as f64 / n as f64);
        let f1 = f(p1);
        if (f0 < 0.0) != (f1 < 0.0) {
            out.push(bisect(&f, p0, f0, p1, f1, tol));
        }
        p0 = p1;
        f0 = f1;
    }
}

/// Deterministic SplitMix64 generator: small, seedable, enough for seeds and BRIO rounds.
#[derive(Clone, Debug)]
pub struct SplitMix64(pub u64);

impl SplitMix64 {
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

/// Newton-like projection of `p` onto S along the gradient (a few steps), checked: returns
/// `None` if it does not converge to a point with |value| small relative to the gradient.
pub fn project_newton<S: Surface + ?Sized>(s: &S, p: DVec3) -> Option<DVec3> {
    let mut x = p;
    let tol = s.tolerance();
    for _ in 0..30 {
        let f = s.value(x);
        let g = s.gradient(x);
        let g2 = g.length_squared();
        if !f.is_finite() || !(g2 > 0.0) {
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
