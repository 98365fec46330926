//! Bisection (ours): the safe root finder of the bipolar oracle (section 6.4.2), exact for
//! sign-only functions.

use super::bracket::{Ends, nan_at};
use crate::OracleError;
use glam::DVec3;

/// Bisection on `[a, b]` (the [`Ends`] `e`) where `fa` and `fb` have opposite signs, until the bracket is shorter
/// than `tol`. Returns the midpoint of the final bracket, which is within `tol / 2` of a sign
/// change. Works for sign-only functions. Signs follow the bipolar convention: `f < 0` is inside,
/// `f >= 0` (zero included) outside, so a zero at an end is found as the limit of the bracket.
///
/// If `f` returns NaN at a probe, returns a point with NaN coordinates (never a silently wrong
/// point); use [`try_bisect`] to get the offending point as an error.
pub fn bisect(f: impl Fn(DVec3) -> f64, e: Ends, tol: f64) -> DVec3 {
    try_bisect(f, e, tol).unwrap_or(DVec3::NAN)
}

/// [`bisect`] reporting a NaN value (at an end or at a probe) as [`OracleError::NaN`] with the
/// point. If `fa` and `fb` have the same sign (a violated precondition), returns the end with the
/// smaller |value|.
pub fn try_bisect(f: impl Fn(DVec3) -> f64, e: Ends, tol: f64) -> Result<DVec3, OracleError> {
    if let Some(end) = e.precheck()? {
        return Ok(end);
    }
    let a_neg = e.fa < 0.0;
    let (mut a, mut b) = (e.a, e.b);
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
