//! Sign-change brackets and the Illinois step (ours), in the vocabulary of [`super`], with
//! the checks every finder makes on its ends.
//!
//! Invariant of both forms: the two ends' values are on opposite sides (`< 0` and `>= 0`), so a
//! sign change stays between them; [`ParamBracket`] also keeps `t0 < t1`.

use crate::OracleError;
use glam::DVec3;

/// A bracket `[t0, t1]` in the parameter of a segment, with the values at its ends (maybe
/// Illinois-halved, or NaN where unknown: a NaN end value makes the next step a bisection).
#[derive(Clone, Copy, Debug)]
pub(crate) struct ParamBracket {
    pub t0: f64,
    pub f0: f64,
    pub t1: f64,
    pub f1: f64,
    /// Side of the `t0` end (`f < 0`); the `t1` end is on the other side.
    pub neg0: bool,
}

impl ParamBracket {
    /// The whole segment `[0, 1]`, with end values `fa`, `fb`.
    pub fn new(fa: f64, fb: f64) -> ParamBracket {
        ParamBracket {
            t0: 0.0,
            f0: fa,
            t1: 1.0,
            f1: fb,
            neg0: fa < 0.0,
        }
    }

    /// The Illinois step: the probe `t` (value `v`) replaces the end on its side; if that end
    /// also moved on the previous step (`last_side`: -1 for `t0`, 1 for `t1`, 0 for none), the
    /// value kept at the other end is halved.
    #[inline]
    pub fn illinois_step(&mut self, t: f64, v: f64, last_side: &mut i8) {
        if (v < 0.0) == self.neg0 {
            self.t0 = t;
            self.f0 = v;
            if *last_side == -1 {
                self.f1 *= 0.5;
            }
            *last_side = -1;
        } else {
            self.t1 = t;
            self.f1 = v;
            if *last_side == 1 {
                self.f0 *= 0.5;
            }
            *last_side = 1;
        }
    }

    /// Illinois on `f` (a function of the parameter) until the bracket is shorter than
    /// `ttol`: each probe lands at least `ttol / 4` inside the bracket, and the safeguard
    /// bisects when two steps did not halve it. Stops early on NaN.
    // `!(x > y)` is used on purpose: it is true for NaN, which must take the safe branch.
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    pub fn solve(mut self, f: impl Fn(f64) -> f64, ttol: f64) -> ParamBracket {
        let mut last_side = 0i8;
        let mut width_two_ago = f64::INFINITY;
        let mut width_one_ago = self.t1 - self.t0;
        for _ in 0..200 {
            let w = self.t1 - self.t0;
            if w <= ttol {
                break;
            }
            let m = 0.25 * ttol;
            let denom = self.f1 - self.f0;
            let mut t = if w > 0.5 * width_two_ago || !(denom != 0.0 && denom.is_finite()) {
                0.5 * (self.t0 + self.t1)
            } else {
                self.t0 - self.f0 * w / denom
            };
            if !(t > self.t0 + m) {
                t = self.t0 + m;
            }
            if !(t < self.t1 - m) {
                t = self.t1 - m;
            }
            let v = f(t);
            if v.is_nan() {
                break;
            }
            self.illinois_step(t, v, &mut last_side);
            width_two_ago = width_one_ago;
            width_one_ago = w;
        }
        self
    }
}

/// The Illinois step on a bracket `[a, b]` in space: `m` (value `fm`) replaces the end with
/// the same sign as `fm`, and the value kept at the other end is halved when the same end
/// moved twice in a row (`side` remembers which end moved last: -1 for a, 1 for b).
pub(crate) fn shrink_bracket(
    m: DVec3,
    fm: f64,
    (a, fa): (&mut DVec3, &mut f64),
    (b, fb): (&mut DVec3, &mut f64),
    side: &mut i8,
) {
    if (fm < 0.0) == (*fa < 0.0) {
        (*a, *fa) = (m, fm);
        if *side == -1 {
            *fb *= 0.5;
        }
        *side = -1;
    } else {
        (*b, *fb) = (m, fm);
        if *side == 1 {
            *fa *= 0.5;
        }
        *side = 1;
    }
}

/// The state of the in-space finders (`illinois`, `newton_bracketed`): the bracket, the end
/// that moved last (for the Illinois step), and the bracket's length at the last safeguard
/// check (every third step).
pub(crate) struct SpaceBracket {
    pub e: Ends,
    side: i8,
    prev_len: f64,
}

impl SpaceBracket {
    pub fn new(e: Ends) -> SpaceBracket {
        SpaceBracket {
            e,
            side: 0,
            prev_len: (e.b - e.a).length(),
        }
    }

    /// The bracket's length.
    pub fn len(&self) -> f64 {
        (self.e.b - self.e.a).length()
    }

    /// The safeguard on step `it` with bracket length `len`: true when a bisection is due
    /// (every third step, if the bracket did not halve since the last check).
    pub fn bisect_due(&mut self, it: usize, len: f64) -> bool {
        let due = it % 3 == 2 && len > 0.5 * self.prev_len;
        if it % 3 == 2 {
            self.prev_len = len;
        }
        due
    }

    /// The regula falsi probe (the bracket's middle if `bisect`, or if the estimate is not
    /// finite), clamped to the bracket.
    pub fn falsi_probe(&self, bisect: bool) -> DVec3 {
        let Ends { a, fa, b, fb } = self.e;
        let t = if bisect { 0.5 } else { fa / (fa - fb) };
        a.lerp(
            b,
            if t.is_finite() {
                t.clamp(0.0, 1.0)
            } else {
                0.5
            },
        )
    }

    /// The probe `m` with value `fm`: true if it is accepted as the answer (`|fm| < tol`, or
    /// NaN), else the Illinois step ([`shrink_bracket`]) and false.
    pub fn accept_or_shrink(&mut self, m: DVec3, fm: f64, tol: f64) -> bool {
        if fm.is_nan() || fm.abs() < tol {
            return true;
        }
        let e = &mut self.e;
        shrink_bracket(
            m,
            fm,
            (&mut e.a, &mut e.fa),
            (&mut e.b, &mut e.fb),
            &mut self.side,
        );
        false
    }

    /// The bracket's middle.
    pub fn mid(&self) -> DVec3 {
        self.e.a.lerp(self.e.b, 0.5)
    }
}

/// True if `v` is -1, 0 or 1: a value of a sign-only function, on which interpolation
/// (secant, regula falsi, Newton) is meaningless and bisection must be used.
#[inline]
pub fn is_sign_value(v: f64) -> bool {
    v == 0.0 || v == 1.0 || v == -1.0
}

/// The error for a NaN value at `p`.
pub(crate) fn nan_at(p: DVec3) -> OracleError {
    OracleError::NaN(p.x, p.y, p.z)
}

/// `Err` naming the first end whose value is NaN.
/// A sign-change bracket in space: ends `a`, `b` with their values `fa`, `fb`, the input of
/// every finder here (the vocabulary of [`super`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ends {
    /// The first end.
    pub a: DVec3,
    /// The value at `a`.
    pub fa: f64,
    /// The second end.
    pub b: DVec3,
    /// The value at `b`.
    pub fb: f64,
}

impl Ends {
    /// The bracket `[a, b]` with values `fa` at `a` and `fb` at `b`.
    pub fn new(a: DVec3, fa: f64, b: DVec3, fb: f64) -> Ends {
        Ends { a, fa, b, fb }
    }

    /// The checks of the checked finders: `Err` naming the first end whose value is NaN, else
    /// the end with the smaller |value| when both ends are on the same side (a violated
    /// precondition, which the finders answer with that end), else `None`.
    pub(crate) fn precheck(&self) -> Result<Option<DVec3>, OracleError> {
        let Ends { a, fa, b, fb } = *self;
        if fa.is_nan() {
            return Err(nan_at(a));
        }
        if fb.is_nan() {
            return Err(nan_at(b));
        }
        Ok(((fa < 0.0) == (fb < 0.0)).then_some(if fa.abs() <= fb.abs() { a } else { b }))
    }
}
