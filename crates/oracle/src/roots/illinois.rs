//! Illinois (modified regula falsi) root finders (ours), in the vocabulary of [`super`].

use super::bisect::try_bisect;
use super::bracket::{Ends, ParamBracket, SpaceBracket, is_sign_value, nan_at};
use crate::OracleError;
use glam::DVec3;

/// Safeguarded root finding on `[a, b]` (the [`Ends`] `e`; same contract as [`try_bisect`]: the result is within
/// `tol / 2` of a sign change of `f`, with `f < 0` inside and `f >= 0` outside).
///
/// Uses the Illinois variant of regula falsi, which converges superlinearly on smooth functions,
/// with three safeguards: bisection when the values are sign-only (-1, 0, 1) or an end value is
/// exactly 0; a bisection step whenever the bracket has not halved within three steps (so the
/// cost is at most about four times that of bisection); and interpolated probes kept about
/// `tol` inside the bracket, so the bracket closes on the root from both sides.
pub fn try_find_root(f: impl Fn(DVec3) -> f64, e: Ends, tol: f64) -> Result<DVec3, OracleError> {
    if let Some(end) = e.precheck()? {
        return Ok(end);
    }
    let Ends { a, fa, b, fb } = e;
    let neg0 = fa < 0.0;
    let d = b - a;
    let len = d.length();
    if len.is_nan() || len <= tol {
        return Ok(0.5 * (a + b));
    }
    if is_sign_value(fa) && is_sign_value(fb) {
        return try_bisect(f, e, tol);
    }
    let tt = tol / len; // tolerance in parameter units
    let mut br = ParamBracket::new(fa, fb);
    debug_assert_eq!(br.neg0, neg0);
    let mut last_side = 0i8;
    let mut w_ref = 1.0;
    let mut stall = 0;
    for _ in 0..400 {
        let w = br.t1 - br.t0;
        if w <= tt {
            break;
        }
        if w <= 0.5 * w_ref {
            w_ref = w;
            stall = 0;
        } else {
            stall += 1;
        }
        let mid = 0.5 * (br.t0 + br.t1);
        let t = if stall >= 3 || br.f0 == 0.0 || br.f1 == 0.0 {
            stall = 0;
            w_ref = w;
            mid
        } else {
            let s = br.t0 - br.f0 * (br.t1 - br.t0) / (br.f1 - br.f0);
            // Keep probes about `tol` inside the bracket: when the estimate is within `tol` of
            // an end, the probe lands just past the root and closes the bracket.
            let (lo, hi) = (br.t0 + 0.99 * tt, br.t1 - 0.99 * tt);
            if s.is_finite() && lo < hi {
                s.clamp(lo, hi)
            } else {
                mid
            }
        };
        if t <= br.t0 || t >= br.t1 {
            break; // adjacent floats
        }
        let p = a + d * t;
        let g = f(p);
        if g.is_nan() {
            return Err(nan_at(p));
        }
        br.illinois_step(t, g, &mut last_side);
    }
    Ok(a + d * (0.5 * (br.t0 + br.t1)))
}

/// Illinois on `[a, b]` in space (`fa`, `fb` on opposite sides), safeguarded by a bisection
/// every third step if the bracket did not halve. Returns a point within `tol` of a sign
/// change: a probe where `|f| < tol` (for functions close to a distance) or the midpoint of a
/// bracket shorter than `tol`.
pub(crate) fn illinois(f: impl Fn(DVec3) -> f64, e: Ends, tol: f64) -> DVec3 {
    let mut br = SpaceBracket::new(e);
    for it in 0..200 {
        let len = br.len();
        if len <= tol {
            break;
        }
        let bisect = br.bisect_due(it, len);
        let m = br.falsi_probe(bisect);
        let fm = f(m);
        if br.accept_or_shrink(m, fm, tol) {
            return m;
        }
    }
    br.mid()
}
