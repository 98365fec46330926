//! Semi-static filter of the in-sphere determinant (ours; the bound is of the kind of CGAL's
//! static filters, Meyer & Pion, "FPG: a code generator for fast and certified geometric
//! predicates", 2008): an error bound from the largest absolute coordinate differences, much
//! cheaper than Shewchuk's permanent. It decides almost every test on non-degenerate input;
//! what it leaves goes to the existing exact stages ([`crate::predicates::insphere`]).
//!
//! # The bound
//! Let `u = 2^-53`. The determinant is evaluated by [`insphere_det`] from the rounded
//! differences `x~ = fl(p.x - e.x)` (same for y, z; p = a, b, c, d). With the exact
//! differences `x = p.x - e.x`, the exact determinant `D` is a sum of 72 monomials
//! `x_i y_j z_k w_l^2` (24 permutation terms of the 4x4 determinant times the three squares
//! of the lifted coordinate). Along the evaluation tree, every monomial meets at most 16
//! roundings: 5 for its factors' differences, then 2x2 product and subtraction (2), times z
//! (1), the 3x3 minor's two additions (2), the lift's square and two additions (3), the final
//! product (1) and the final two additions (2). In the standard model each rounding is a factor
//! `1 + delta`, `|delta| <= u`, so (Higham, "Accuracy and stability of numerical algorithms",
//! lemma 3.1) `|fl(D) - D| <= gamma_16 * A` with `gamma_16 = 16u / (1 - 16u)` and `A` the sum of
//! the monomials' absolute values. With `X, Y, Z` the largest `|x~|, |y~|, |z~|` and
//! `L = X^2 + Y^2 + Z^2`, `A <= 24 X Y Z L / (1 - u)^5` (`|x| <= |x~| / (1 - u)`). Hence
//! `|fl(D) - D| < 384.1 u X Y Z L`, and the computed `eps = fl(385 u * X * Y * Z * L)`, whose
//! seven roundings (four products; in `L`, a square and two additions) lose at
//! most a factor `(1 - u)^7`, exceeds it. If `|fl(D)| > eps`, `D` has the sign of `fl(D)`.
//!
//! # Range (no overflow, underflow accounted for)
//! Points are checked by [`crate::triangulation::check_point`]: coordinates are 0 or of
//! magnitude in `[2^-140, 2^200]`. So differences are below `2^201` and `A <= 72 * 2^1005`:
//! nothing overflows. Every coordinate is a multiple of `2^-192`, hence so is every difference,
//! and every nonzero difference is at least `2^-192`. Following quanta through the tree: 2x2
//! products are 0 or `>= 2^-384`, 2x2 minors multiples of `2^-436`, the z products 0 or
//! `>= 2^-628`, 3x3 minors multiples of `2^-680`, lifts 0 or `>= 2^-384`: all normal, so the
//! standard model holds for them. Only the four final products may be subnormal, each adding
//! at most `2^-1075` of absolute error (additions with a subnormal result are exact). If
//! `X Y Z` is zero, a whole column of differences is zero and `fl(D)` is exactly 0: the
//! filter declines. Otherwise `X Y Z L >= 2^-960`, and the slack `(385 - 384.1) u X Y Z L >=
//! 2^-1014` covers the `4 * 2^-1075`. Computing `eps` itself stays normal (`>= 2^-1005`).

use glam::DVec3;

/// `385 u` (exact in binary): the constant of the bound above.
const INSPHERE_EPS: f64 = 385.0 / 9_007_199_254_740_992.0;

/// The in-sphere determinant of the differences `p - e` (the evaluation order analysed
/// above: Laplace on the lifted column, the 3x3 minors on z, 2x2 minors on x, y).
#[inline(always)]
pub(crate) fn insphere_det(ae: DVec3, be: DVec3, ce: DVec3, de: DVec3) -> f64 {
    let ab = ae.x * be.y - be.x * ae.y;
    let bc = be.x * ce.y - ce.x * be.y;
    let cd = ce.x * de.y - de.x * ce.y;
    let da = de.x * ae.y - ae.x * de.y;
    let ac = ae.x * ce.y - ce.x * ae.y;
    let bd = be.x * de.y - de.x * be.y;
    let abc = ae.z * bc - be.z * ac + ce.z * ab;
    let bcd = be.z * cd - ce.z * bd + de.z * bc;
    let cda = ce.z * da + de.z * ac + ae.z * cd;
    let dab = de.z * ab + ae.z * bd + be.z * da;
    let lift = |p: DVec3| p.x * p.x + p.y * p.y + p.z * p.z;
    let (al, bl, cl, dl) = (lift(ae), lift(be), lift(ce), lift(de));
    (dl * abc - cl * dab) + (bl * cda - al * bcd)
}

/// The error bound `eps` of `insphere_det(ae, be, ce, de)` (see the module docs), for points
/// in the checked range.
#[inline(always)]
pub(crate) fn insphere_eps(ae: DVec3, be: DVec3, ce: DVec3, de: DVec3) -> f64 {
    let m = ae.abs().max(be.abs()).max(ce.abs().max(de.abs()));
    let l = m.x * m.x + m.y * m.y + m.z * m.z;
    INSPHERE_EPS * m.x * m.y * m.z * l
}

/// The semi-static decision for the in-sphere test of `e` against the points of `v` (all
/// finite): `Some(true)` if `D > 0` (inside for a positive cell), `Some(false)` if `D < 0`,
/// `None` if undecided. Scalar code on the coordinates read in place (the same operations as
/// [`insphere_det`] and [`insphere_eps`], so the bound holds): no vector copies through the
/// stack in the conflict search's hot loop.
#[inline(always)]
pub(crate) fn insphere_decide(points: &[DVec3], v: [u32; 4], e: DVec3) -> Option<bool> {
    let p = |i: usize| {
        let q = &points[v[i] as usize];
        (q.x - e.x, q.y - e.y, q.z - e.z)
    };
    let (ax, ay, az) = p(0);
    let (bx, by, bz) = p(1);
    let (cx, cy, cz) = p(2);
    let (dx, dy, dz) = p(3);
    let ab = ax * by - bx * ay;
    let bc = bx * cy - cx * by;
    let cd = cx * dy - dx * cy;
    let da = dx * ay - ax * dy;
    let ac = ax * cy - cx * ay;
    let bd = bx * dy - dx * by;
    let abc = az * bc - bz * ac + cz * ab;
    let bcd = bz * cd - cz * bd + dz * bc;
    let cda = cz * da + dz * ac + az * cd;
    let dab = dz * ab + az * bd + bz * da;
    let al = ax * ax + ay * ay + az * az;
    let bl = bx * bx + by * by + bz * bz;
    let cl = cx * cx + cy * cy + cz * cz;
    let dl = dx * dx + dy * dy + dz * dz;
    let det = (dl * abc - cl * dab) + (bl * cda - al * bcd);
    let mx = max4(ax.abs(), bx.abs(), cx.abs(), dx.abs());
    let my = max4(ay.abs(), by.abs(), cy.abs(), dy.abs());
    let mz = max4(az.abs(), bz.abs(), cz.abs(), dz.abs());
    let eps = INSPHERE_EPS * mx * my * mz * (mx * mx + my * my + mz * mz);
    if det > eps {
        Some(true)
    } else if -det > eps {
        Some(false)
    } else {
        None
    }
}

/// The largest of four numbers that are not NaN (the differences of checked points): a
/// plain compare and select each, where `f64::max` adds the handling of NaN.
#[inline(always)]
fn max4(a: f64, b: f64, c: f64, d: f64) -> f64 {
    let max = |x: f64, y: f64| if x > y { x } else { y };
    max(max(a, b), max(c, d))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::predicates::Sign;
    use proptest::prelude::*;

    fn exact(q: &[DVec3; 5]) -> Sign {
        let c = |p: DVec3| robust::Coord3D {
            x: p.x,
            y: p.y,
            z: p.z,
        };
        Sign::of(robust::insphere(
            c(q[0]),
            c(q[1]),
            c(q[2]),
            c(q[3]),
            c(q[4]),
        ))
    }

    /// The filter's decision, if any.
    fn filtered(q: &[DVec3; 5]) -> Option<Sign> {
        let [a, b, c, d, e] = *q;
        let (ae, be, ce, de) = (a - e, b - e, c - e, d - e);
        let det = insphere_det(ae, be, ce, de);
        let eps = insphere_eps(ae, be, ce, de);
        (det > eps || -det > eps).then(|| Sign::of(det))
    }

    /// Checks one configuration; returns whether the filter decided it.
    fn check(q: &[DVec3; 5]) -> bool {
        let scalar = insphere_decide(&q[..4], [0, 1, 2, 3], q[4]);
        assert_eq!(
            scalar.map(|b| Sign::of(if b { 1.0 } else { -1.0 })),
            filtered(q)
        );
        match filtered(q) {
            Some(s) => {
                assert_eq!(s, exact(q), "{q:?}");
                true
            }
            None => false,
        }
    }

    #[test]
    fn bound_constant_is_385_u() {
        assert_eq!(INSPHERE_EPS, 385.0 * f64::EPSILON / 2.0);
    }

    #[test]
    fn decides_random_points_and_never_lies_on_degenerate_ones() {
        let mut r = geom::SplitMix64(11);
        let mut decided = 0;
        for k in 0..200_000 {
            let mut q = [DVec3::ZERO; 5];
            for p in q.iter_mut() {
                *p = DVec3::new(r.next_f64(), r.next_f64(), r.next_f64());
            }
            match k % 4 {
                // Cospherical up to rounding: points of one sphere.
                1 => {
                    let c = q[0];
                    for p in q.iter_mut() {
                        *p = c + r.unit_vector() * 0.5;
                    }
                }
                // Grid points (exact ties) at a tiny or a huge scale.
                2 => {
                    let s = if k % 8 == 2 {
                        2f64.powi(-130)
                    } else {
                        2f64.powi(190)
                    };
                    for p in q.iter_mut() {
                        *p = (DVec3::new(r.next_f64(), r.next_f64(), r.next_f64()) * 4.0).floor()
                            * s;
                    }
                }
                // A tiny perturbation of a point on the others' sphere (one ulp away).
                3 => {
                    let c = q[0];
                    for p in q.iter_mut() {
                        *p = c + r.unit_vector();
                    }
                    q[4].x = f64::from_bits(q[4].x.to_bits() + 1);
                }
                _ => {}
            }
            decided += check(&q) as usize;
        }
        assert!(decided > 60_000, "{decided}"); // the random quarter and some others
    }

    fn coord() -> impl Strategy<Value = f64> {
        prop_oneof![
            -1e3..1e3f64,
            (-8i32..8).prop_map(f64::from),
            (-8i32..8, -140i32..190).prop_map(|(m, e)| f64::from(m) * 2f64.powi(e)),
            (1u64..64).prop_map(|k| 1.0 + k as f64 * f64::EPSILON),
        ]
    }

    fn point() -> impl Strategy<Value = DVec3> {
        (coord(), coord(), coord()).prop_map(|(x, y, z)| DVec3::new(x, y, z))
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(20_000))]
        #[test]
        fn filter_agrees_with_robust(a in point(), b in point(), c in point(), d in point(),
                                     e in point()) {
            check(&[a, b, c, d, e]);
        }
    }
}
