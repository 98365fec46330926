//! Exact segment-triangle crossing with a symbolic perturbation of the segment (ours; the
//! intersection oracle of the polyhedron backend, where every crossing through a shared edge
//! or vertex must be counted exactly once).
//!
//! The query segment's end points are perturbed symbolically,
//! `A = a + ε e_x + ε² e_y + ε³ e_z` and `B = b + ε⁴ e_x + ε⁸ e_y + ε¹² e_z` (ε → 0+), so that
//! every orientation sign is non-zero. Each determinant is a polynomial in ε whose coefficients
//! are exact orient3d / orient2d signs or coordinate differences (see the derivation in the
//! comments), so the answers are those of a *generic* segment infinitesimally close to `[a, b]`:
//! a crossing through a shared edge or vertex is counted exactly once, whatever the orientation
//! of the triangles, and a segment lying in a triangle's plane never crosses it.

use glam::DVec3;

use super::{Sign, normal_signs, orient3d_det};

/// The first non-zero sign of `seq`, or `Zero`.
#[inline]
fn first_nonzero(seq: impl IntoIterator<Item = Sign>) -> Sign {
    seq.into_iter().find(|s| !s.is_zero()).unwrap_or(Sign::Zero)
}

/// `Positive` if the (perturbed) point with `o = orient3d(p, q, r, d)` is above the plane of
/// `pqr` (on the side of `(q-p)×(r-p)`), `Negative` if below. `d` is perturbed along `+e_x`,
/// then `+e_y`, then `+e_z` (the order of the powers of ε is the same for both end points, so
/// one rule serves both). Precondition: `pqr` is not degenerate (then the sign is never 0).
#[inline]
fn plane_side(p: DVec3, q: DVec3, r: DVec3, o: f64) -> Sign {
    // orient3d(p,q,r,d) = -(d - p)·n with n = (q-p)×(r-p).
    if o < 0.0 {
        return Sign::Positive;
    }
    if o > 0.0 {
        return Sign::Negative;
    }
    // d(orient)/d(d_i) = -n_i, so "above" (orient < 0) <=> n_i > 0 for the first nonzero n_i.
    first_nonzero(normal_signs(p, q, r))
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
fn edge_sign(a: DVec3, b: DVec3, u: DVec3, v: DVec3) -> Sign {
    let d = orient3d_det(a, b, u, v);
    if d != 0.0 {
        return Sign::of(d);
    }
    let alpha = normal_signs(b, u, v);
    let nb = normal_signs(a, u, v);
    // Coordinate differences: IEEE subtraction is sign-exact.
    let w = u - v;
    let s = Sign::of;
    first_nonzero([
        alpha[0],
        alpha[1],
        alpha[2],
        -nb[0],
        s(-w.z),
        s(w.y),
        -nb[1],
        s(w.z),
        s(-w.x),
        -nb[2],
        s(-w.y),
        s(w.x),
    ])
}

/// Exact crossing test of the (perturbed) segment `[a, b]` with the non-degenerate triangle
/// `pqr`. Returns the f64 parameter `t ∈ [0, 1]` of the crossing point `a + t (b - a)` if the
/// perturbed segment crosses the triangle (the decision is exact, `t` is rounded).
#[inline]
pub fn segment_crosses_triangle(a: DVec3, b: DVec3, p: DVec3, q: DVec3, r: DVec3) -> Option<f64> {
    let oa = orient3d_det(p, q, r, a);
    let ob = orient3d_det(p, q, r, b);
    // Fast reject: strictly on the same side.
    if (oa > 0.0 && ob > 0.0) || (oa < 0.0 && ob < 0.0) {
        return None;
    }
    let sa = plane_side(p, q, r, oa);
    let sb = plane_side(p, q, r, ob);
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

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A fan of triangles around the origin in the plane z = 0 (a closed disk); consecutive
    /// triangles share an edge exactly.
    fn fan(n: usize) -> Vec<[DVec3; 3]> {
        let v = |k: usize| {
            let t = std::f64::consts::TAU * (k % n) as f64 / n as f64;
            DVec3::new(t.cos(), t.sin(), 0.0)
        };
        (0..n).map(|k| [DVec3::ZERO, v(k), v(k + 1)]).collect()
    }

    /// The square |x| + |y| <= 1 as four triangles around the origin (exact corners).
    fn square() -> Vec<[DVec3; 3]> {
        let r = [DVec3::X, DVec3::Y, -DVec3::X, -DVec3::Y];
        (0..4)
            .map(|k| [DVec3::ZERO, r[k], r[(k + 1) % 4]])
            .collect()
    }

    #[test]
    fn crossing_through_a_vertex_or_edge_counts_once() {
        let tris = fan(8);
        let count = |a: DVec3, b: DVec3| {
            tris.iter()
                .filter(|t| segment_crosses_triangle(a, b, t[0], t[1], t[2]).is_some())
                .count()
        };
        // Through the shared centre vertex, and through shared edges.
        assert_eq!(
            count(DVec3::new(0.0, 0.0, -1.0), DVec3::new(0.0, 0.0, 1.0)),
            1
        );
        assert_eq!(
            count(DVec3::new(0.5, 0.0, 1.0), DVec3::new(0.5, 0.0, -1.0)),
            1
        );
        // Outside the disk, and lying in its plane.
        assert_eq!(
            count(DVec3::new(2.0, 0.0, -1.0), DVec3::new(2.0, 0.0, 1.0)),
            0
        );
        assert_eq!(
            count(DVec3::new(-2.0, 0.1, 0.0), DVec3::new(2.0, 0.1, 0.0)),
            0
        );
        let t = segment_crosses_triangle(
            DVec3::new(0.2, 0.1, -1.0),
            DVec3::new(0.2, 0.1, 3.0),
            tris[0][0],
            tris[0][1],
            tris[0][2],
        );
        assert!((t.unwrap() - 0.25).abs() < 1e-15, "{t:?}");
    }

    proptest! {
        /// A segment crossing a closed fan from one side to the other crosses it exactly once,
        /// wherever it hits (vertex, edge or interior), at any grid point.
        #[test]
        fn closed_disk_is_crossed_once(x in -6i32..=6, y in -6i32..=6, dz in 1i32..4) {
            let tris = square();
            let (xf, yf) = (x as f64 / 8.0, y as f64 / 8.0);
            let a = DVec3::new(xf, yf, -(dz as f64));
            let b = DVec3::new(xf, yf, dz as f64);
            let n = tris.iter()
                .filter(|t| segment_crosses_triangle(a, b, t[0], t[1], t[2]).is_some())
                .count();
            let inside = xf.abs() + yf.abs() < 1.0;
            if inside {
                prop_assert_eq!(n, 1);
            } else if xf.abs() + yf.abs() > 1.0 {
                prop_assert_eq!(n, 0);
            }
        }
    }
}
