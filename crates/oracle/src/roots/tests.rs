//! Tests of the in-space finders (`illinois`, `newton_bracketed`) of section 6.4.2's bipolar
//! oracle, in the vocabulary of [`super`].

use super::{Ends, illinois, newton_bracketed};
use glam::DVec3;
use std::cell::Cell;

/// The test segment, across the unit sphere at `x = 1`, with an evaluation counter.
fn segment() -> (DVec3, DVec3, Cell<usize>) {
    (
        DVec3::new(-1.0, 0.2, 0.0),
        DVec3::new(2.0, 0.2, 0.0),
        Cell::new(0),
    )
}

#[test]
fn illinois_converges_on_smooth_and_sign_only_functions() {
    let (a, b, calls) = segment();
    let smooth = |x: DVec3| {
        calls.set(calls.get() + 1);
        x.length() - 1.0
    };
    let x = illinois(smooth, Ends::new(a, smooth(a), b, smooth(b)), 1e-12);
    assert!((x.length() - 1.0).abs() < 1e-12);
    assert!(calls.get() < 20, "{} evaluations", calls.get());
    // A sign-only function: the bisection safeguard still closes the bracket.
    let step = |x: DVec3| if x.x < 0.3 { -1.0 } else { 1.0 };
    let x = illinois(step, Ends::new(a, -1.0, b, 1.0), 1e-9);
    assert!((x.x - 0.3).abs() < 1e-8, "{x}");
}

#[test]
fn newton_bracketed_converges_with_exact_wrong_and_missing_gradients() {
    let (a, b, calls) = segment();
    // Distance to the unit sphere with its exact gradient: quadratic convergence.
    let exact = |x: DVec3| {
        calls.set(calls.get() + 1);
        (x.length() - 1.0, x.normalize())
    };
    let x = newton_bracketed(
        exact,
        Ends::new(a, a.length() - 1.0, b, b.length() - 1.0),
        1e-12,
    );
    assert!((x.length() - 1.0).abs() < 1e-12, "{x}");
    assert!(calls.get() <= 8, "{} evaluations", calls.get());
    // A wrong gradient (pointing the other way): the bracket and bisection still win.
    let wrong = |x: DVec3| (x.length() - 1.0, -x.normalize());
    let x = newton_bracketed(
        wrong,
        Ends::new(a, a.length() - 1.0, b, b.length() - 1.0),
        1e-10,
    );
    assert!((x.length() - 1.0).abs() < 1e-9, "{x}");
    // Sign only, no gradient.
    let step = |x: DVec3| (if x.x < 0.3 { -1.0 } else { 1.0 }, DVec3::NAN);
    let x = newton_bracketed(step, Ends::new(a, -1.0, b, 1.0), 1e-9);
    assert!((x.x - 0.3).abs() < 1e-8, "{x}");
    // A degenerate segment returns its point.
    assert_eq!(newton_bracketed(exact, Ends::new(a, -1.0, a, 1.0), 1e-9), a);
}
