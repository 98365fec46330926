//! Newton steps inside a sign-change bracket (ours), in the vocabulary of [`super`]: the
//! point-set backend's bipolar oracle, whose IMLS value has an exact gradient.

use super::bracket::{Ends, SpaceBracket};
use glam::DVec3;

/// Root finding on `[a, b]` (`fa`, `fb` of opposite signs) for `f` returning the value and
/// its gradient (NaN where unknown): a Newton step along the segment whenever the gradient
/// is known and the step stays strictly inside the bracket, an Illinois step otherwise (`shrink_bracket`), and
/// bisection every third step if the bracket did not halve. Returns a point within `tol` of
/// a sign change: where `|f| < tol`, the Newton update of a point whose step is below `tol`
/// / 2 (functions close to a distance), or the middle of a bracket shorter than `tol`.
pub(crate) fn newton_bracketed(f: impl Fn(DVec3) -> (f64, DVec3), e: Ends, tol: f64) -> DVec3 {
    let mut br = SpaceBracket::new(e);
    let len0 = br.len();
    if !(len0 > 0.0 && len0.is_finite()) {
        return br.mid();
    }
    // Unit direction and origin of the parameter `s` along the segment.
    let (o, u) = (e.a, (e.b - e.a) / len0);
    let mut newton: Option<DVec3> = None;
    for it in 0..200 {
        let len = br.len();
        if len <= tol {
            break;
        }
        let bisect = br.bisect_due(it, len);
        let m = match newton.take() {
            Some(p) if !bisect => p,
            _ => br.falsi_probe(bisect),
        };
        let (fm, g) = f(m);
        if br.accept_or_shrink(m, fm, tol) {
            return m;
        }
        let slope = g.dot(u);
        if slope.is_finite() && slope != 0.0 {
            let step = -fm / slope;
            let p = m + u * step;
            let (a, b) = (br.e.a, br.e.b);
            let (sa, sb, sp) = ((a - o).dot(u), (b - o).dot(u), (p - o).dot(u));
            if sp > sa.min(sb) && sp < sa.max(sb) {
                if step.abs() <= 0.5 * tol {
                    return p;
                }
                newton = Some(p);
            }
        }
    }
    br.mid()
}
