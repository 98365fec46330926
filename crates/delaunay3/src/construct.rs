//! Constructions (ours): the circumcenter of a tetrahedron (a Voronoi vertex), in f64 with a
//! double-double fallback for nearly flat cells. Not a predicate: the result is rounded.

use glam::DVec3;

/// Circumcenter of a non-flat tetrahedron, relative to `p0`; falls back to double-double
/// arithmetic when the determinant is small relative to the edge lengths.
pub fn circumcenter(p0: DVec3, p1: DVec3, p2: DVec3, p3: DVec3) -> DVec3 {
    let a = p1 - p0;
    let b = p2 - p0;
    let c = p3 - p0;
    let bc = b.cross(c);
    let ca = c.cross(a);
    let ab = a.cross(b);
    let det = a.dot(bc);
    let scale = a.length() * b.length() * c.length();
    if det.abs() > 1e-4 * scale {
        let num = bc * a.length_squared() + ca * b.length_squared() + ab * c.length_squared();
        return p0 + num / (2.0 * det);
    }
    dd::circumcenter(p0, p1, p2, p3).unwrap_or_else(|| {
        let num = bc * a.length_squared() + ca * b.length_squared() + ab * c.length_squared();
        p0 + num / (2.0 * det)
    })
}

mod dd {
    use crate::dd_arith::{D, two_sum};
    use glam::DVec3;

    type V = [D; 3];
    fn cross(a: V, b: V) -> V {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    }
    fn dot(a: V, b: V) -> D {
        a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
    }
    fn diff(p: DVec3, q: DVec3) -> V {
        let d = |x: f64, y: f64| two_sum(x, -y);
        [d(p.x, q.x), d(p.y, q.y), d(p.z, q.z)]
    }

    pub fn circumcenter(p0: DVec3, p1: DVec3, p2: DVec3, p3: DVec3) -> Option<DVec3> {
        let (a, b, c) = (diff(p1, p0), diff(p2, p0), diff(p3, p0));
        let (bc, ca, ab) = (cross(b, c), cross(c, a), cross(a, b));
        let det = dot(a, bc);
        let den = det + det;
        if den.0 == 0.0 || !den.0.is_finite() {
            return None;
        }
        let (la, lb, lc) = (dot(a, a), dot(b, b), dot(c, c));
        let mut out = [0.0; 3];
        for k in 0..3 {
            let num = bc[k] * la + ca[k] * lb + ab[k] * lc;
            let q = num.0 / den.0;
            let r = num - D(q, 0.0) * den;
            out[k] = q + r.0 / den.0;
        }
        Some(p0 + DVec3::from_array(out))
    }
}
