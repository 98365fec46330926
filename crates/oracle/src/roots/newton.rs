//! Newton steps inside a sign-change bracket (ours), in the vocabulary of [`super`]: the
//! point-set backend's bipolar oracle, whose IMLS value has an exact gradient.

use super::bracket::shrink_bracket;
use glam::DVec3;

/// Root finding on `[a, b]` (`fa`, `fb` of opposite signs) for `f` returning the value and
/// its gradient (NaN where unknown): a Newton step along the segment whenever the gradient
/// is known and the step stays strictly inside the bracket, an Illinois step otherwise (`shrink_bracket`), and
/// bisection every third step if the bracket did not halve. Returns a point within `tol` of
/// a sign change: where `|f| < tol`, the Newton update of a point whose step is below `tol`
/// / 2 (functions close to a distance), or the middle of a bracket shorter than `tol`.
pub(crate) fn newton_bracketed(
    f: impl Fn(DVec3) -> (f64, DVec3),
    a: DVec3,
    fa: f64,
    b: DVec3,
    fb: f64,
    tol: f64,
) -> DVec3 {
    let (mut a, mut fa, mut b, mut fb) = (a, fa, b, fb);
    let len0 = (b - a).length();
    if !(len0 > 0.0 && len0.is_finite()) {
        return a.lerp(b, 0.5);
    }
    // Unit direction and origin of the parameter `s` along the segment.
    let (o, u) = (a, (b - a) / len0);
    let mut side = 0i8;
    let mut prev_len = len0;
    let mut newton: Option<DVec3> = None;
    for it in 0..200 {
        let len = (b - a).length();
        if len <= tol {
            break;
        }
        let bisect = it % 3 == 2 && len > 0.5 * prev_len;
        if it % 3 == 2 {
            prev_len = len;
        }
        let m = match newton.take() {
            Some(p) if !bisect => p,
            _ => {
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
        };
        let (fm, g) = f(m);
        if fm.is_nan() || fm.abs() < tol {
            return m;
        }
        shrink_bracket(m, fm, (&mut a, &mut fa), (&mut b, &mut fb), &mut side);
        let slope = g.dot(u);
        if slope.is_finite() && slope != 0.0 {
            let step = -fm / slope;
            let p = m + u * step;
            let (sa, sb, sp) = ((a - o).dot(u), (b - o).dot(u), (p - o).dot(u));
            if sp > sa.min(sb) && sp < sa.max(sb) {
                if step.abs() <= 0.5 * tol {
                    return p;
                }
                newton = Some(p);
            }
        }
    }
    a.lerp(b, 0.5)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::cell::Cell;

    #[test]
    fn newton_bracketed_converges_with_exact_wrong_and_missing_gradients() {
        let (a, b) = (DVec3::new(-1.0, 0.2, 0.0), DVec3::new(2.0, 0.2, 0.0));
        let calls = Cell::new(0);
        // Distance to the unit sphere with its exact gradient: quadratic convergence.
        let exact = |x: DVec3| {
            calls.set(calls.get() + 1);
            (x.length() - 1.0, x.normalize())
        };
        let x = newton_bracketed(exact, a, a.length() - 1.0, b, b.length() - 1.0, 1e-12);
        assert!((x.length() - 1.0).abs() < 1e-12, "{x}");
        assert!(calls.get() <= 8, "{} evaluations", calls.get());
        // A wrong gradient (pointing the other way): the bracket and bisection still win.
        let wrong = |x: DVec3| (x.length() - 1.0, -x.normalize());
        let x = newton_bracketed(wrong, a, a.length() - 1.0, b, b.length() - 1.0, 1e-10);
        assert!((x.length() - 1.0).abs() < 1e-9, "{x}");
        // Sign only, no gradient.
        let step = |x: DVec3| (if x.x < 0.3 { -1.0 } else { 1.0 }, DVec3::NAN);
        let x = newton_bracketed(step, a, -1.0, b, 1.0, 1e-9);
        assert!((x.x - 0.3).abs() < 1e-8, "{x}");
        // A degenerate segment returns its point.
        assert_eq!(newton_bracketed(exact, a, -1.0, a, 1.0, 1e-9), a);
    }
}
