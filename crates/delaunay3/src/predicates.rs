//! Exact geometric predicates: the only module that calls `robust`.
//!
//! Every function returns a [`Sign`]; nothing here reads a predicate through `f64::signum`.
//!
//! Conventions (those of Shewchuk's predicates, which `robust` transcribes):
//! - [`orient3d`]`(a, b, c, d)` is [`Sign::Positive`] when `d` lies on the side of the plane
//!   `abc` *opposite* to the normal `(b - a) x (c - a)` (i.e. "below" `abc` when `abc` is seen
//!   counter-clockwise from above).
//! - [`insphere`]`(a, b, c, d, e)` requires `orient3d(a, b, c, d)` positive and is
//!   [`Sign::Positive`] when `e` is strictly inside the sphere through `a, b, c, d`.
//!
//! The symbolic perturbation used to break ties follows Devillers & Teillaud ("Perturbations
//! for Delaunay and weighted Delaunay 3D triangulations", as implemented in CGAL's
//! `Delaunay_triangulation_3::side_of_oriented_sphere(..., perturb = true)`): points are
//! ordered lexicographically by `(x, y, z)` and a tie is resolved by the orientation of a
//! tetrahedron in which the lexicographically largest point is replaced by the query.

use glam::DVec3;
use robust::Coord3D;

/// The sign of a predicate: the workspace's one [`geom::Sign`].
pub use geom::Sign;

#[inline(always)]
fn c3(p: DVec3) -> Coord3D<f64> {
    Coord3D {
        x: p.x,
        y: p.y,
        z: p.z,
    }
}

/// Exact orientation of `d` with respect to the plane `abc` (see module docs for the sign).
/// Shewchuk's static filter inline, then `robust::orient3d` (adaptive, exact).
#[inline(always)]
pub fn orient3d(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> Sign {
    let (ad, bd, cd) = (a - d, b - d, c - d);
    let bdxcdy = bd.x * cd.y;
    let cdxbdy = cd.x * bd.y;
    let cdxady = cd.x * ad.y;
    let adxcdy = ad.x * cd.y;
    let adxbdy = ad.x * bd.y;
    let bdxady = bd.x * ad.y;
    let det = ad.z * (bdxcdy - cdxbdy) + bd.z * (cdxady - adxcdy) + cd.z * (adxbdy - bdxady);
    let permanent = (bdxcdy.abs() + cdxbdy.abs()) * ad.z.abs()
        + (cdxady.abs() + adxcdy.abs()) * bd.z.abs()
        + (adxbdy.abs() + bdxady.abs()) * cd.z.abs();
    const O3DERRBOUND_A: f64 = (7.0 + 56.0 * f64::EPSILON / 2.0) * f64::EPSILON / 2.0;
    let errbound = O3DERRBOUND_A * permanent;
    if det > errbound || -det > errbound {
        return Sign::of(det);
    }
    orient3d_exact(a, b, c, d)
}

#[inline(never)]
fn orient3d_exact(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> Sign {
    Sign::of(robust::orient3d(c3(a), c3(b), c3(c), c3(d)))
}

/// `m` over the six pairs of `[a, b, c, d]` in the order ab, bc, cd, da, ac, bd (the 2x2
/// minors of the in-sphere determinant's expansion).
#[inline(always)]
fn six_pairs<P: Copy, T>([a, b, c, d]: [P; 4], m: impl Fn(P, P) -> T) -> (T, T, T, T, T, T) {
    (m(a, b), m(b, c), m(c, d), m(d, a), m(a, c), m(b, d))
}

/// Exact in-sphere test; requires `orient3d(a, b, c, d) == Positive`. Positive: `e` inside.
/// Exact for coordinates in the range of [`crate::validate_point`] (0 or of magnitude in
/// `[2^-140, 2^200]`: the filters' bounds assume no overflow and bounded underflow).
///
/// Four stages: the semi-static filter of [`crate::semi_static`] (an error bound from the
/// largest coordinate differences), then in [`insphere_slow`] Shewchuk's tighter static
/// filter on the permanent, a double-double evaluation with a rigorous error bound (decides
/// nearly-cospherical inputs, e.g. rounded sphere samples, ~20x faster than the adaptive
/// expansions), an exact `i128` stage for grid-like inputs, and `robust::insphere` (exact).
#[inline(always)]
pub fn insphere(a: DVec3, b: DVec3, c: DVec3, d: DVec3, e: DVec3) -> Sign {
    use crate::semi_static::{insphere_det, insphere_eps};
    let (ae, be, ce, de) = (a - e, b - e, c - e, d - e);
    let det = insphere_det(ae, be, ce, de);
    let eps = insphere_eps(ae, be, ce, de);
    if det > eps || -det > eps {
        return Sign::of(det);
    }
    insphere_slow(a, b, c, d, e, det)
}

/// [`insphere`] for inputs the semi-static filter did not decide (its check is not repeated).
#[inline(always)]
pub(crate) fn insphere_undecided(a: DVec3, b: DVec3, c: DVec3, d: DVec3, e: DVec3) -> Sign {
    let det = crate::semi_static::insphere_det(a - e, b - e, c - e, d - e);
    insphere_slow(a, b, c, d, e, det)
}

/// Shewchuk's static filter: `det` within `ISPERRBOUND_A` times the permanent of the
/// minors (his `insphere` fast path) is undecided; returns the permanent then.
fn insphere_static(ae: DVec3, be: DVec3, ce: DVec3, de: DVec3, det: f64) -> Result<Sign, f64> {
    let m = |p: DVec3, q: DVec3| (p.x * q.y).abs() + (q.x * p.y).abs();
    let (pab, pbc, pcd, pda, pac, pbd) = six_pairs([ae, be, ce, de], m);
    let (az, bz, cz, dz) = (ae.z.abs(), be.z.abs(), ce.z.abs(), de.z.abs());
    let (al, bl, cl, dl) = (
        ae.length_squared(),
        be.length_squared(),
        ce.length_squared(),
        de.length_squared(),
    );
    let permanent = (pcd * bz + pbd * cz + pbc * dz) * al
        + (pda * cz + pac * dz + pcd * az) * bl
        + (pab * dz + pbd * az + pda * bz) * cl
        + (pbc * az + pac * bz + pab * cz) * dl;
    const ISPERRBOUND_A: f64 = (16.0 + 224.0 * f64::EPSILON / 2.0) * f64::EPSILON / 2.0;
    let errbound = ISPERRBOUND_A * permanent;
    if det > errbound || -det > errbound {
        return Ok(Sign::of(det));
    }
    Err(permanent)
}

/// The stages after the semi-static filter (`det`: the f64 determinant, from the same
/// evaluation as Shewchuk's).
#[inline(never)]
fn insphere_slow(a: DVec3, b: DVec3, c: DVec3, d: DVec3, e: DVec3, det: f64) -> Sign {
    let permanent = match insphere_static(a - e, b - e, c - e, d - e, det) {
        Ok(s) => return s,
        Err(p) => p,
    };
    if let Some(s) = insphere_int(a, b, c, d, e) {
        return s;
    }
    // Double-double stage: every difference is exact; each DD operation has relative error
    // below 8 u^2 (u = 2^-53), the evaluation tree has depth 8, so the absolute error is
    // below ~64 u^2 * permanent. We require 2^-96 = 1024 u^2. Skipped near underflow.
    if permanent > 1e-240 {
        let ddet = insphere_dd(a, b, c, d, e);
        let bound = permanent * (1.0 / (1u128 << 96) as f64);
        if ddet > bound || -ddet > bound {
            return Sign::of(ddet);
        }
    }
    Sign::of(robust::insphere(c3(a), c3(b), c3(c), c3(d), c3(e)))
}

/// Exact evaluation in `i128` when the twelve differences `p - e` are exact and, scaled by
/// one power of two, integers of magnitude at most 2^20 (grids, integer inputs). Then the
/// minors are below 2^63 and the determinant below 2^108.
fn insphere_int(a: DVec3, b: DVec3, c: DVec3, d: DVec3, e: DVec3) -> Option<Sign> {
    use crate::dd_arith::two_sum;
    // Quick reject: integer-like inputs have short mantissas (low 32 bits zero).
    let short = |p: DVec3| (p.x.to_bits() | p.y.to_bits() | p.z.to_bits()) & 0xFFFF_FFFF == 0;
    if !(short(a) && short(b) && short(c) && short(d) && short(e)) {
        return None;
    }
    let mut diffs = [0.0f64; 12];
    let mut max = 0.0f64;
    for (k, p) in [a, b, c, d].into_iter().enumerate() {
        for (i, (x, y)) in [(p.x, e.x), (p.y, e.y), (p.z, e.z)].into_iter().enumerate() {
            let t = two_sum(x, -y);
            if t.1 != 0.0 {
                return None;
            }
            diffs[3 * k + i] = t.0;
            max = max.max(t.0.abs());
        }
    }
    if max == 0.0 {
        return None;
    }
    // Power of two s with max * s in (2^19, 2^20]; scaling by s is exact (coordinates are
    // within 2^-140..2^201, so no overflow or underflow).
    let exp = max.log2().ceil() as i32;
    let s = 2f64.powi(20 - exp);
    let mut v = [0i128; 12];
    for (k, &x) in diffs.iter().enumerate() {
        let y = x * s;
        if y != y.trunc() || y.abs() > (1u64 << 20) as f64 {
            return None;
        }
        v[k] = y as i128;
    }
    let p = |k: usize| (v[3 * k], v[3 * k + 1], v[3 * k + 2]);
    let (ae, be, ce, de) = (p(0), p(1), p(2), p(3));
    let m = |p: (i128, i128, i128), q: (i128, i128, i128)| p.0 * q.1 - q.0 * p.1;
    let (ab, bc, cd, da, ac, bd) = six_pairs([ae, be, ce, de], m);
    let abc = ae.2 * bc - be.2 * ac + ce.2 * ab;
    let bcd = be.2 * cd - ce.2 * bd + de.2 * bc;
    let cda = ce.2 * da + de.2 * ac + ae.2 * cd;
    let dab = de.2 * ab + ae.2 * bd + be.2 * da;
    let l = |p: (i128, i128, i128)| p.0 * p.0 + p.1 * p.1 + p.2 * p.2;
    let det = (l(de) * abc - l(ce) * dab) + (l(be) * cda - l(ae) * bcd);
    Some(match det.cmp(&0) {
        std::cmp::Ordering::Greater => Sign::Positive,
        std::cmp::Ordering::Less => Sign::Negative,
        std::cmp::Ordering::Equal => Sign::Zero,
    })
}

/// [`insphere_dd_with`], with a hardware FMA when the CPU has one (runtime detection).
#[inline(never)]
#[allow(unsafe_code)]
fn insphere_dd(a: DVec3, b: DVec3, c: DVec3, d: DVec3, e: DVec3) -> f64 {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("fma") {
        // SAFETY: `insphere_dd_fma` only requires the `fma` CPU feature, detected just above.
        return unsafe { insphere_dd_fma(a, b, c, d, e) };
    }
    insphere_dd_with::<{ cfg!(target_feature = "fma") }>(a, b, c, d, e)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "fma")]
fn insphere_dd_fma(a: DVec3, b: DVec3, c: DVec3, d: DVec3, e: DVec3) -> f64 {
    insphere_dd_with::<true>(a, b, c, d, e)
}

/// The in-sphere determinant in double-double arithmetic (see the bound in
/// [`insphere_slow`]). When every difference `p - e` is exact in f64 (neighbouring points:
/// Sterbenz), the same evaluation skips the products by their zero low parts.
#[inline(always)]
fn insphere_dd_with<const FMA: bool>(a: DVec3, b: DVec3, c: DVec3, d: DVec3, e: DVec3) -> f64 {
    use crate::dd_arith::two_sum;
    let diff = |p: DVec3| [two_sum(p.x, -e.x), two_sum(p.y, -e.y), two_sum(p.z, -e.z)];
    let q = [diff(a), diff(b), diff(c), diff(d)];
    if q.iter().flatten().all(|t| t.1 == 0.0) {
        insphere_dd_det::<FMA, true>(&q)
    } else {
        insphere_dd_det::<FMA, false>(&q)
    }
}

/// The double-double determinant of the differences `q` (`EXACT`: all their low parts are
/// zero). With `EXACT`, a product of two differences is `two_prod` of their high parts and
/// a difference times a double-double is `mul_f64`: these are the values `mul` computes
/// when the low parts are zero (`quick(P, e)` of an exact product `P + e` is `(P, e)`, and
/// `a * o.1 + 0 * o.0 = a * o.1`), up to the sign of a zero, so the result is the same.
#[inline(always)]
fn insphere_dd_det<const FMA: bool, const EXACT: bool>(q: &[[crate::dd_arith::D; 3]; 4]) -> f64 {
    use crate::dd_arith::{D, mul, mul_f64, two_prod_with};
    let x = |p: D, q: D| mul::<FMA>(p, q);
    // A product of two differences, and a difference times a double-double.
    let x1 = |p: D, q: D| {
        if EXACT {
            two_prod_with::<FMA>(p.0, q.0)
        } else {
            x(p, q)
        }
    };
    let xz = |p: D, q: D| {
        if EXACT {
            mul_f64::<FMA>(p.0, q)
        } else {
            x(p, q)
        }
    };
    let [ae, be, ce, de] = q;
    let m = |p: &[D; 3], q: &[D; 3]| x1(p[0], q[1]) - x1(q[0], p[1]);
    let (ab, bc, cd, da, ac, bd) = (
        m(ae, be),
        m(be, ce),
        m(ce, de),
        m(de, ae),
        m(ae, ce),
        m(be, de),
    );
    let abc = xz(ae[2], bc) - xz(be[2], ac) + xz(ce[2], ab);
    let bcd = xz(be[2], cd) - xz(ce[2], bd) + xz(de[2], bc);
    let cda = xz(ce[2], da) + xz(de[2], ac) + xz(ae[2], cd);
    let dab = xz(de[2], ab) + xz(ae[2], bd) + xz(be[2], da);
    let lift = |p: &[D; 3]| x1(p[0], p[0]) + x1(p[1], p[1]) + x1(p[2], p[2]);
    let det = (x(lift(de), abc) - x(lift(ce), dab)) + (x(lift(be), cda) - x(lift(ae), bcd));
    det.0 + det.1
}

/// Exact test: are the three points collinear (all three coordinate projections collinear)?
pub use geom::predicates::collinear;

/// Strict lexicographic order on `(x, y, z)`: the fixed total order of the perturbation.
#[inline]
pub fn lex_less(a: DVec3, b: DVec3) -> bool {
    (a.x, a.y, a.z) < (b.x, b.y, b.z)
}

/// Perturbed in-sphere test for a positively oriented tetrahedron `q` (no two points equal):
/// `true` when `p` is inside the perturbed circumsphere. Never undecided.
#[inline(always)]
pub fn insphere_perturbed(q: &[DVec3; 4], p: DVec3) -> bool {
    match insphere(q[0], q[1], q[2], q[3], p) {
        Sign::Positive => true,
        Sign::Negative => false,
        Sign::Zero => insphere_tie(q, p),
    }
}

/// The perturbed decision when `p` is exactly on the circumsphere of `q`.
#[inline(never)]
pub(crate) fn insphere_tie(q: &[DVec3; 4], p: DVec3) -> bool {
    let mut idx = [0usize, 1, 2, 3, 4];
    sort_lexicographic(&mut idx, q, p);
    // Two iterations suffice (Devillers & Teillaud) since q is not flat.
    replace_largest(q, p, &idx[3..], "insphere perturbation undecided")
}

/// Perturbed "inside the circumcircle of a facet" test for a point `p` lying exactly on the
/// plane of the facet of the positively oriented tetrahedron `m` opposite its vertex `j`.
/// `true` when `p` is inside the perturbed circumcircle. The circle test is exact: any sphere
/// through the facet meets its plane in the facet's circumcircle.
pub fn incircle_facet_perturbed(m: &[DVec3; 4], j: usize, p: DVec3) -> bool {
    match insphere(m[0], m[1], m[2], m[3], p) {
        Sign::Positive => true,
        Sign::Negative => false,
        Sign::Zero => {
            let mut idx = [0usize; 4];
            let mut n = 0;
            for k in 0..4 {
                if k != j {
                    idx[n] = k;
                    n += 1;
                }
            }
            idx[3] = 4;
            sort_lexicographic(&mut idx, m, p);
            replace_largest(m, p, &idx[1..], "incircle perturbation undecided")
        }
    }
}

/// Sorts indices into `q` (index 4 standing for `p`) by lexicographic order of their points.
fn sort_lexicographic(idx: &mut [usize], q: &[DVec3; 4], p: DVec3) {
    let pt = |k: usize| if k == 4 { p } else { q[k] };
    idx.sort_unstable_by(|&a, &b| {
        let (a, b) = (pt(a), pt(b));
        (a.x, a.y, a.z).partial_cmp(&(b.x, b.y, b.z)).unwrap()
    });
}

/// The symbolic perturbation's decision: from the lexicographically largest of `candidates`
/// down, the first nonzero orientation of `q` with that vertex replaced by `p` (`false` when
/// `p` itself, index 4, comes first).
fn replace_largest(q: &[DVec3; 4], p: DVec3, candidates: &[usize], undecided: &str) -> bool {
    for &k in candidates.iter().rev() {
        if k == 4 {
            return false;
        }
        let mut r = *q;
        r[k] = p;
        match orient3d(r[0], r[1], r[2], r[3]) {
            Sign::Positive => return true,
            Sign::Negative => return false,
            Sign::Zero => {}
        }
    }
    debug_assert!(false, "{undecided}");
    false
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn orientation_convention() {
        let o = DVec3::ZERO;
        let (x, y, z) = (DVec3::X, DVec3::Y, DVec3::Z);
        // z is above the plane (o, x, y) whose normal x * y = +z: robust says Negative.
        assert_eq!(orient3d(o, x, y, z), Sign::Negative);
        assert_eq!(orient3d(o, x, y, -z), Sign::Positive);
        assert_eq!(orient3d(o, x, y, x + y), Sign::Zero);
        // (o, y, x, z) is positive; the centroid is inside, far points are outside.
        assert_eq!(insphere(o, y, x, z, DVec3::splat(0.25)), Sign::Positive);
        assert_eq!(insphere(o, y, x, z, DVec3::splat(5.0)), Sign::Negative);
        assert_eq!(insphere(o, y, x, z, x + y), Sign::Zero);
        assert!(collinear(o, x, 2.0 * x));
        assert!(!collinear(o, x, y));
        assert_eq!(Sign::of(-0.0), Sign::Zero);
    }

    #[test]
    fn perturbation_is_consistent_across_a_facet() {
        // o, x, y, z, w = (1,1,1) are cospherical and o, w lie on both sides of xyz: the
        // perturbation must choose either {oxyz, wxyz} (both tests false) or the three
        // tetrahedra around edge ow (both tests true).
        let o = DVec3::ZERO;
        let (x, y, z) = (DVec3::X, DVec3::Y, DVec3::Z);
        let w = DVec3::ONE;
        let q = [o, y, x, z];
        assert_eq!(orient3d(q[0], q[1], q[2], q[3]), Sign::Positive);
        let q2 = [w, x, y, z];
        assert_eq!(orient3d(q2[0], q2[1], q2[2], q2[3]), Sign::Positive);
        assert_eq!(insphere(q[0], q[1], q[2], q[3], w), Sign::Zero);
        assert_eq!(insphere_perturbed(&q, w), insphere_perturbed(&q2, o));
    }

    #[test]
    fn insphere_matches_fixture_and_robust() {
        let text = include_str!("../fixtures/insphere.txt");
        let mut n = 0;
        for line in text.lines() {
            let v: Vec<f64> = line
                .split_whitespace()
                .skip(1)
                .map(|s| s.parse().unwrap())
                .collect();
            let p = |k: usize| DVec3::new(v[3 * k], v[3 * k + 1], v[3 * k + 2]);
            let want = Sign::of(v[15]);
            assert_eq!(insphere(p(0), p(1), p(2), p(3), p(4)), want, "{line}");
            n += 1;
        }
        assert_eq!(n, 1000);
        // Nearly cospherical points (rounded sphere samples, tiny perturbations): the DD
        // stage must agree with the exact expansion arithmetic.
        let mut s = 12345u64;
        let mut next = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let mut decided_by_dd = 0;
        let mut exact_diffs = 0;
        for k in 0..20000 {
            let mut q = [DVec3::ZERO; 5];
            let (center, radius) = (
                DVec3::new(next(), next(), next()) * 100.0,
                1.0 + next().abs() * 1e3,
            );
            for p in q.iter_mut() {
                *p = DVec3::new(next(), next(), next()).normalize() * radius + center;
            }
            if k % 3 == 0 {
                q[4].x += q[4].x * f64::EPSILON * next();
            }
            if orient3d(q[0], q[1], q[2], q[3]) == Sign::Negative {
                q.swap(0, 1);
            }
            let exact = robust_insphere(&q);
            assert_eq!(insphere(q[0], q[1], q[2], q[3], q[4]), exact, "{q:?}");
            let dd = insphere_dd(q[0], q[1], q[2], q[3], q[4]);
            if Sign::of(dd) == exact {
                decided_by_dd += 1;
            }
            // Dekker splitting (no FMA) computes the same double-double value.
            assert_eq!(dd, insphere_dd_with::<false>(q[0], q[1], q[2], q[3], q[4]));
            // So does the general evaluation where the exact-differences one applies.
            let diffs = [0, 1, 2, 3].map(|k| {
                let t = |x: f64, y: f64| crate::dd_arith::two_sum(x, -y);
                [t(q[k].x, q[4].x), t(q[k].y, q[4].y), t(q[k].z, q[4].z)]
            });
            if diffs.iter().flatten().all(|t| t.1 == 0.0) {
                exact_diffs += 1;
                for f in [
                    insphere_dd_det::<true, true>,
                    insphere_dd_det::<false, true>,
                ] {
                    assert_eq!(f(&diffs), insphere_dd_det::<true, false>(&diffs));
                }
            }
        }
        assert!(decided_by_dd > 19000);
        assert!(exact_diffs > 100, "{exact_diffs}");
    }

    /// `robust`'s exact in-sphere sign of `q[4]` against `q[0..4]`, the reference.
    fn robust_insphere(q: &[DVec3]) -> Sign {
        let [a, b, c, d, e] = [0, 1, 2, 3, 4].map(|k| c3(q[k]));
        Sign::of(robust::insphere(a, b, c, d, e))
    }

    #[test]
    fn integer_path_matches_robust() {
        let mut st = 99u64;
        let mut next = |m: u64| {
            st = st
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((st >> 33) % m) as f64
        };
        let mut zeros = 0;
        for k in 0..20000 {
            let s = [1.0, 0.25, 1024.0, 3.0][k % 4];
            let mut q: Vec<DVec3> = (0..5)
                .map(|_| DVec3::new(next(5), next(5), next(5)) * s)
                .collect();
            if k % 7 == 0 {
                q[4] = DVec3::new(next(1 << 20), next(1 << 20), next(1 << 20));
            }
            if orient3d(q[0], q[1], q[2], q[3]) != Sign::Positive {
                q.swap(0, 1);
                if orient3d(q[0], q[1], q[2], q[3]) != Sign::Positive {
                    continue;
                }
            }
            let exact = robust_insphere(&q);
            let fast = insphere_int(q[0], q[1], q[2], q[3], q[4]);
            if let Some(f) = fast {
                assert_eq!(f, exact, "{q:?}");
            }
            assert_eq!(insphere(q[0], q[1], q[2], q[3], q[4]), exact);
            zeros += (exact == Sign::Zero) as usize;
        }
        assert!(zeros > 100);
    }
}
