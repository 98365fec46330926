//! Exact predicates (ours; Shewchuk's adaptive arithmetic through `robust`): the one [`Sign`]
//! type of the workspace, orient2d / orient3d / insphere, and the exact intersection tests
//! built on them ([`closed`] for `verify`, [`perturbed`] for the polyhedron oracle).
//!
//! # Sign conventions (those of Shewchuk's predicates, which `robust` transcribes)
//! - [`orient3d`]`(a, b, c, d)` is the sign of `det[a - d; b - d; c - d]`. It is
//!   [`Sign::Positive`] when `d` lies on the side of the plane `abc` *opposite* to the normal
//!   `(b - a) × (c - a)`, i.e. *below* `abc` when `abc` is seen counter-clockwise from above.
//! - [`orient2d`]`(a, b, c, k)` is the orientation of the projections that drop coordinate
//!   `k`: positive when they turn counter-clockwise in the planes (y, z), (z, x), (x, y) for
//!   `k` = 0, 1, 2. These three signs are those of the components of `(b - a) × (c - a)`
//!   ([`normal_signs`]).
//! - [`insphere`]`(a, b, c, d, e)` requires `orient3d(a, b, c, d)` positive and is
//!   [`Sign::Positive`] when `e` is strictly inside the sphere through `a, b, c, d`.
//!
//! Every sign is exact for finite inputs within Shewchuk's exponent range; `Zero` means
//! exactly degenerate. Nothing here reads a determinant through `f64::signum`
//! (`0.0_f64.signum()` is 1). Symbolic perturbation for the Delaunay triangulation stays in
//! `delaunay3`; the segment perturbation of the polyhedron oracle is in [`perturbed`].

use glam::DVec3;
use robust::{Coord, Coord3D};

pub mod closed;
pub mod perturbed;

pub use closed::{
    segment_meets_triangle, shared_edge_overlap, shared_vertex_overlap, triangles_intersect,
};
pub use perturbed::segment_crosses_triangle;

/// The sign of a predicate.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Sign {
    /// Strictly negative.
    Negative,
    /// Exactly zero (degenerate configuration).
    Zero,
    /// Strictly positive.
    Positive,
}

impl Sign {
    /// The sign of `x` (`0.0` and `-0.0` are [`Sign::Zero`]; NaN is `Zero` too, which
    /// exact predicates never return).
    #[inline]
    pub fn of(x: f64) -> Sign {
        if x > 0.0 {
            Sign::Positive
        } else if x < 0.0 {
            Sign::Negative
        } else {
            Sign::Zero
        }
    }

    /// `-1`, `0` or `1`.
    #[inline]
    pub fn as_i8(self) -> i8 {
        match self {
            Sign::Negative => -1,
            Sign::Zero => 0,
            Sign::Positive => 1,
        }
    }

    /// Is this [`Sign::Zero`]?
    #[inline]
    pub fn is_zero(self) -> bool {
        self == Sign::Zero
    }
}

impl std::ops::Neg for Sign {
    type Output = Sign;
    #[inline]
    fn neg(self) -> Sign {
        match self {
            Sign::Negative => Sign::Positive,
            Sign::Zero => Sign::Zero,
            Sign::Positive => Sign::Negative,
        }
    }
}

impl std::ops::Mul for Sign {
    type Output = Sign;
    /// The sign of a product.
    #[inline]
    fn mul(self, o: Sign) -> Sign {
        match (self, o) {
            (Sign::Zero, _) | (_, Sign::Zero) => Sign::Zero,
            (a, b) if a == b => Sign::Positive,
            _ => Sign::Negative,
        }
    }
}

#[inline]
fn c3(p: DVec3) -> Coord3D<f64> {
    Coord3D {
        x: p.x,
        y: p.y,
        z: p.z,
    }
}

/// `robust::orient3d(a, b, c, d)`: the determinant `det[a - d; b - d; c - d]` computed
/// adaptively. Its *sign* is exact; its magnitude is only an approximation (used by
/// [`perturbed::segment_crosses_triangle`] for the crossing parameter).
#[inline]
pub fn orient3d_det(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> f64 {
    robust::orient3d(c3(a), c3(b), c3(c), c3(d))
}

/// Exact orientation of `d` against the plane of `a, b, c` (see the module docs for the
/// sign: positive when `d` is below the counter-clockwise `abc`).
#[inline]
pub fn orient3d(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> Sign {
    Sign::of(orient3d_det(a, b, c, d))
}

/// Exact 2D orientation of the projections of `a, b, c` that drop coordinate `drop`
/// (0, 1 or 2; planes (y, z), (z, x), (x, y)). Dropping a coordinate is exact, so this is.
#[inline]
pub fn orient2d(a: DVec3, b: DVec3, c: DVec3, drop: usize) -> Sign {
    let (i, j) = match drop {
        0 => (1, 2),
        1 => (2, 0),
        _ => (0, 1),
    };
    let p = |v: DVec3| Coord { x: v[i], y: v[j] };
    Sign::of(robust::orient2d(p(a), p(b), p(c)))
}

/// Exact signs of the components `(x, y, z)` of the normal `(b - a) × (c - a)`: the
/// orient2d of the (y, z), (z, x) and (x, y) projections.
#[inline]
pub fn normal_signs(a: DVec3, b: DVec3, c: DVec3) -> [Sign; 3] {
    [
        orient2d(a, b, c, 0),
        orient2d(a, b, c, 1),
        orient2d(a, b, c, 2),
    ]
}

/// Exact in-sphere test; requires `orient3d(a, b, c, d) == Positive`. Positive: `e` is
/// strictly inside the sphere through `a, b, c, d`.
#[inline]
pub fn insphere(a: DVec3, b: DVec3, c: DVec3, d: DVec3, e: DVec3) -> Sign {
    Sign::of(robust::insphere(c3(a), c3(b), c3(c), c3(d), c3(e)))
}

/// True if `a, b, c` are exactly collinear (or coincide), i.e. the triangle `abc` is
/// degenerate: every coordinate-plane projection is collinear.
pub fn collinear(a: DVec3, b: DVec3, c: DVec3) -> bool {
    normal_signs(a, b, c).iter().all(|s| s.is_zero())
}

/// A coordinate to drop such that the projection of the (non-degenerate) triangle is
/// non-degenerate, with its 2D orientation sign; the largest normal component is tried
/// first. `None` for a degenerate triangle.
pub fn projection_axis(a: DVec3, b: DVec3, c: DVec3) -> Option<(usize, Sign)> {
    let n = (b - a).cross(c - a).abs();
    let first = if n.x >= n.y && n.x >= n.z {
        0
    } else if n.y >= n.z {
        1
    } else {
        2
    };
    [first, (first + 1) % 3, (first + 2) % 3]
        .into_iter()
        .find_map(|k| {
            let s = orient2d(a, b, c, k);
            (!s.is_zero()).then_some((k, s))
        })
}

/// What is wrong with a point given to the exact predicates (see [`first_bad_point`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BadPoint {
    /// A coordinate is NaN or infinite (the coordinates, in order).
    NonFinite([f64; 3]),
    /// This coordinate's magnitude is above the bound.
    TooLarge(f64),
}

/// The first point (index and reason) with a non-finite coordinate or one of magnitude above
/// `max_abs`: the oracles check their input with it so that the exact predicates' products
/// stay in range.
///
/// ```
/// use geom::predicates::{BadPoint, first_bad_point};
/// use glam::DVec3;
/// let pts = [DVec3::ZERO, DVec3::new(0.0, 2e60, 0.0), DVec3::splat(f64::NAN)];
/// assert_eq!(first_bad_point(&pts, 1e60), Some((1, BadPoint::TooLarge(2e60))));
/// assert_eq!(first_bad_point(&pts[..1], 1e60), None);
/// ```
pub fn first_bad_point(points: &[DVec3], max_abs: f64) -> Option<(usize, BadPoint)> {
    points.iter().enumerate().find_map(|(i, p)| {
        if !p.is_finite() {
            return Some((i, BadPoint::NonFinite(p.to_array())));
        }
        let big = p.to_array().into_iter().find(|c| c.abs() > max_abs);
        big.map(|c| (i, BadPoint::TooLarge(c)))
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_util::{RIGHT_TRIANGLE, pt_within};
    use proptest::prelude::*;

    #[test]
    fn convention_below_is_positive() {
        let (a, b, c) = RIGHT_TRIANGLE;
        assert_eq!(
            orient3d(a, b, c, DVec3::new(0.1, 0.1, -1.0)),
            Sign::Positive
        );
        assert_eq!(orient3d(a, b, c, DVec3::new(0.1, 0.1, 1.0)), Sign::Negative);
        assert_eq!(orient3d(a, b, c, DVec3::new(5.0, -3.0, 0.0)), Sign::Zero);
        assert_eq!(
            normal_signs(a, b, c),
            [Sign::Zero, Sign::Zero, Sign::Positive]
        );
        // insphere with a positively oriented tetrahedron.
        let d = -DVec3::Z;
        assert_eq!(orient3d(a, b, c, d), Sign::Positive);
        assert_eq!(insphere(a, b, c, d, DVec3::splat(0.2)), Sign::Positive);
        assert_eq!(insphere(a, b, c, d, DVec3::splat(5.0)), Sign::Negative);
        assert_eq!(insphere(a, b, c, d, DVec3::new(1.0, 1.0, 0.0)), Sign::Zero);
        assert_eq!(Sign::of(-0.0), Sign::Zero);
    }

    #[test]
    fn sign_algebra() {
        use Sign::*;
        for s in [Negative, Zero, Positive] {
            assert_eq!((-s).as_i8(), -s.as_i8());
            for t in [Negative, Zero, Positive] {
                assert_eq!((s * t).as_i8(), s.as_i8() * t.as_i8());
            }
        }
    }

    proptest! {
        #[test]
        fn orient3d_is_antisymmetric(a in pt_within(1e3), b in pt_within(1e3), c in pt_within(1e3), d in pt_within(1e3)) {
            let s = orient3d(a, b, c, d);
            prop_assert_eq!(orient3d(b, a, c, d), -s);
            prop_assert_eq!(orient3d(a, c, b, d), -s);
            prop_assert_eq!(orient3d(b, c, a, d), s);
            // Swapping the query with a corner is an odd permutation of the four points.
            prop_assert_eq!(orient3d(d, b, c, a), -s);
            // Degenerate when the query is a corner.
            prop_assert_eq!(orient3d(a, b, c, a), Sign::Zero);
        }

        #[test]
        fn orient2d_matches_normal_and_swaps(a in pt_within(1e3), b in pt_within(1e3), c in pt_within(1e3)) {
            let n = normal_signs(a, b, c);
            for (k, &nk) in n.iter().enumerate() {
                prop_assert_eq!(orient2d(b, a, c, k), -nk);
                prop_assert_eq!(orient2d(b, c, a, k), nk);
            }
            // Integer-valued inputs: the cross product is exact, compare with it.
            let (ai, bi, ci) = (a.round(), b.round(), c.round());
            let cr = (bi - ai).cross(ci - ai);
            prop_assert_eq!(normal_signs(ai, bi, ci), [Sign::of(cr.x), Sign::of(cr.y), Sign::of(cr.z)]);
        }
    }
}
