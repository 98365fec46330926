//! Exact segment-triangle predicates with a symbolic perturbation of the segment.
//!
//! The query segment's end points are perturbed symbolically,
//! `A = a + ε e_x + ε² e_y + ε³ e_z` and `B = b + ε⁴ e_x + ε⁸ e_y + ε¹² e_z` (ε → 0+), so that
//! every orientation sign is non-zero. Each determinant is a polynomial in ε whose coefficients
//! are exact orient3d / orient2d signs or coordinate differences (see the derivation in the
//! comments), so the answers are those of a *generic* segment infinitesimally close to `[a, b]`:
//! a crossing through a shared edge or vertex is counted exactly once, whatever the orientation
//! of the triangles, and a segment lying in a triangle's plane never crosses it.

use glam::DVec3;
use robust::{Coord, Coord3D, orient2d, orient3d};

#[inline]
fn c3(p: DVec3) -> Coord3D<f64> {
    Coord3D {
        x: p.x,
        y: p.y,
        z: p.z,
    }
}

#[inline]
fn c2(x: f64, y: f64) -> Coord<f64> {
    Coord { x, y }
}

/// Shewchuk's orient3d: `det[a-d; b-d; c-d]`, positive when `d` is below the plane of `abc`
/// (`abc` counter-clockwise seen from above). Sign exact.
#[inline]
pub(crate) fn o3(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> f64 {
    orient3d(c3(a), c3(b), c3(c), c3(d))
}

/// Exact signs (as f64 whose sign is exact) of the components of `(b-a)×(c-a)`.
/// `n_x` is the orient2d of the (y, z) projection, `n_y` of (z, x), `n_z` of (x, y).
#[inline]
pub(crate) fn normal_signs(a: DVec3, b: DVec3, c: DVec3) -> [f64; 3] {
    [
        orient2d(c2(a.y, a.z), c2(b.y, b.z), c2(c.y, c.z)),
        orient2d(c2(a.z, a.x), c2(b.z, b.x), c2(c.z, c.x)),
        orient2d(c2(a.x, a.y), c2(b.x, b.y), c2(c.x, c.y)),
    ]
}

/// Whether triangle `abc` is degenerate (its three points are collinear or coincide), exactly.
pub(crate) fn is_degenerate(a: DVec3, b: DVec3, c: DVec3) -> bool {
    normal_signs(a, b, c).iter().all(|&s| s == 0.0)
}

/// `+1` if the (perturbed) point is above the plane of `pqr` (on the side of `(q-p)×(r-p)`),
/// `-1` if below. `d` is perturbed along `+e_x`, then `+e_y`, then `+e_z` (the order of the
/// powers of ε is the same for both end points, so one rule serves both).
/// Precondition: `pqr` is not degenerate (then the sign is never 0).
#[inline]
fn plane_side(p: DVec3, q: DVec3, r: DVec3, d: DVec3, o: f64) -> i8 {
    // orient3d(p,q,r,d) = -(d - p)·n with n = (q-p)×(r-p).
    if o < 0.0 {
        return 1;
    }
    if o > 0.0 {
        return -1;
    }
    let _ = d;
    // d(orient)/d(d_i) = -n_i, so "above" (orient < 0) <=> n_i > 0 for the first nonzero n_i.
    for s in normal_signs(p, q, r) {
        if s > 0.0 {
            return 1;
        }
        if s < 0.0 {
            return -1;
        }
    }
    0
}

/// Sign of `orient3d(A, B, u, v)` for the perturbed `A`, `B`; never 0 when `u != v`.
///
/// With `w = u - v`: `orient3d(A,B,u,v) = det[A-v; B-v; w]`, whose expansion is
/// `D + Σ_i α_i A'_i + Σ_j β_j B'_j + Σ_ij γ_ij A'_i B'_j`, where `A'`, `B'` are the
/// perturbations, `α = (b-v)×(u-v)` = normal of triangle `(b,u,v)`, `β = (u-v)×(a-v)` =
/// −normal of `(a,u,v)`, and `γ_ij = ε_ijk w_k` (Levi-Civita). With `A'` at ε¹, ε², ε³ and `B'`
/// at ε⁴, ε⁸, ε¹² all coefficients fall on distinct powers:
/// 1:α_x 2:α_y 3:α_z 4:β_x 6:γ_yx 7:γ_zx 8:β_y 9:γ_xy 11:γ_zy 12:β_z 13:γ_xz 14:γ_yz.
#[inline]
fn edge_sign(a: DVec3, b: DVec3, u: DVec3, v: DVec3) -> i8 {
    let d = o3(a, b, u, v);
    if d != 0.0 {
        return if d > 0.0 { 1 } else { -1 };
    }
    let alpha = normal_signs(b, u, v);
    let nb = normal_signs(a, u, v);
    let w = u - v; // coordinate differences: sign exact (Sterbenz not needed, IEEE subtraction is sign-exact)
    let seq = [
        alpha[0], alpha[1], alpha[2], -nb[0], -w.z, w.y, -nb[1], w.z, -w.x, -nb[2], -w.y, w.x,
    ];
    for s in seq {
        if s > 0.0 {
            return 1;
        }
        if s < 0.0 {
            return -1;
        }
    }
    0
}

/// Exact crossing test of the (perturbed) segment `[a, b]` with the non-degenerate triangle
/// `pqr`. Returns the f64 parameter `t ∈ [0, 1]` of the crossing point `a + t (b - a)` if the
/// perturbed segment crosses the triangle.
#[inline]
pub(crate) fn segment_triangle(a: DVec3, b: DVec3, p: DVec3, q: DVec3, r: DVec3) -> Option<f64> {
    let oa = o3(p, q, r, a);
    let ob = o3(p, q, r, b);
    // Fast reject: strictly on the same side.
    if (oa > 0.0 && ob > 0.0) || (oa < 0.0 && ob < 0.0) {
        return None;
    }
    let sa = plane_side(p, q, r, a, oa);
    let sb = plane_side(p, q, r, b, ob);
    if sa == sb {
        return None;
    }
    let e0 = edge_sign(a, b, p, q);
    let e1 = edge_sign(a, b, q, r);
    if e0 != e1 {
        return None;
    }
    let e2 = edge_sign(a, b, r, p);
    if e0 != e2 {
        return None;
    }
    let den = oa - ob;
    let t = if den != 0.0 && den.is_finite() {
        (oa / den).clamp(0.0, 1.0)
    } else if oa == 0.0 {
        0.0
    } else {
        1.0
    };
    Some(t)
}

/// Closest point of triangle `abc` to `p` (Ericson, Real-Time Collision Detection, 5.1.5)
/// and the feature it lies on: 0 the interior,
/// 1, 2, 3 the vertices `a`, `b`, `c`, 4, 5, 6 the edges `ab`, `bc`, `ca`.
pub(crate) fn closest_point_triangle_feature(
    p: DVec3,
    a: DVec3,
    b: DVec3,
    c: DVec3,
) -> (DVec3, u8) {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return (a, 1);
    }
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return (b, 2);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (a + ab * v, 4);
    }
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return (c, 3);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (a + ac * w, 6);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (b + (c - b) * w, 5);
    }
    let denom = 1.0 / (va + vb + vc);
    let v = vb * denom;
    let w = vc * denom;
    (a + ab * v + ac * w, 0)
}

/// Closest point of segment `[a, b]` to `p`.
pub(crate) fn closest_point_segment(p: DVec3, a: DVec3, b: DVec3) -> DVec3 {
    let d = b - a;
    let dd = d.length_squared();
    if dd.is_nan() || dd <= 0.0 {
        return a;
    }
    let t = ((p - a).dot(d) / dd).clamp(0.0, 1.0);
    a + d * t
}

/// Solid angle of triangle `abc` seen from `p` (Van Oosterom & Strackee 1983), positive when
/// `p` is behind the triangle (on the side opposite to `(b-a)×(c-a)`).
#[inline]
pub(crate) fn solid_angle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let a = a - p;
    let b = b - p;
    let c = c - p;
    let la = a.length();
    let lb = b.length();
    let lc = c.length();
    let num = a.dot(b.cross(c));
    let den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
    2.0 * num.atan2(den)
}
