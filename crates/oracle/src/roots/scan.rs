//! The intersection oracle by sampling (section 6.4.2's Θ(1/Δ) oracle): sample a segment,
//! refine every sign change with a root finder.

use super::bracket::{Ends, nan_at};
use super::illinois::try_find_root;
use crate::OracleError;
use crate::Surface;
use glam::DVec3;

/// The default intersection oracle of a surface ([`Surface::crossings`]): every sign change
/// of its value on `[a, b]`, sampled at steps of at most [`Surface::crossing_step`] and refined
/// to [`Surface::tolerance`] by [`try_all_crossings`], pushed in order from `a`. If the value
/// is NaN, pushes one point with NaN coordinates and stops.
pub fn all_crossings<S: Surface + ?Sized>(s: &S, a: DVec3, b: DVec3, out: &mut Vec<DVec3>) {
    let f = |p| s.value(p);
    if try_all_crossings(f, a, b, s.crossing_step(), s.tolerance(), out).is_err() {
        out.push(DVec3::NAN);
    }
}

/// All sign changes of `f` on `[a, b]` sampled at steps of at most `step`, pushed in order
/// from `a`, NaN reported as an error (crossings found before it stay in `out`). Each sign
/// change is refined to `tol` by [`try_find_root`] (bisection for sign-only values).
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
            out.push(try_find_root(&f, Ends::new(p0, f0, p1, f1), tol)?);
        }
        p0 = p1;
        f0 = f1;
    }
    Ok(())
}

/// The sampling loop of the point-set and smoothed-polyhedron intersection oracles: the value
/// of `s` sampled at `n = ⌈|b − a| / step⌉` points `a.lerp(b, i / n)` (`step` its
/// [`Surface::crossing_step`], at most 2^20 samples), and every sign change between
/// consecutive samples refined by its bipolar oracle [`Surface::crossing`], pushed in order
/// from `a`. Nothing for a segment of non-finite length.
pub(crate) fn sample_crossings<S: Surface + ?Sized>(
    s: &S,
    a: DVec3,
    b: DVec3,
    out: &mut Vec<DVec3>,
) {
    let len = (b - a).length();
    if !len.is_finite() {
        return;
    }
    let n = ((len / s.crossing_step()).ceil() as usize).clamp(1, 1 << 20);
    let (mut p0, mut f0) = (a, s.value(a));
    for i in 1..=n {
        let p1 = a.lerp(b, i as f64 / n as f64);
        let f1 = s.value(p1);
        if (f0 < 0.0) != (f1 < 0.0) {
            out.push(s.crossing(p0, f0, p1, f1));
        }
        (p0, f0) = (p1, f1);
    }
}
