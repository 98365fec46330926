//! Closest points (ours; Ericson, *Real-Time Collision Detection*, 5.1.2 and 5.1.5): on a
//! triangle, with the feature (face, edge or vertex) it lies on, and on a segment. The
//! polyhedron oracle's projection, signed distance and pseudonormals, and `verify`'s exact
//! nearest-triangle distances, all come from [`closest_point_triangle_feature`].

use glam::DVec3;

/// The feature of a triangle `abc` a closest point lies on. The discriminant (`as usize`)
/// indexes per-feature tables such as angle-weighted pseudonormals `[face, a, b, c, ab, bc,
/// ca]`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum Feature {
    /// The open face.
    Face = 0,
    /// Vertex `a`.
    A = 1,
    /// Vertex `b`.
    B = 2,
    /// Vertex `c`.
    C = 3,
    /// The open edge `ab`.
    Ab = 4,
    /// The open edge `bc`.
    Bc = 5,
    /// The open edge `ca`.
    Ca = 6,
}

/// Closest point of triangle `abc` to `p` and the feature it lies on (Ericson 5.1.5, Voronoi
/// regions of the features tested in order a, b, ab, c, ca, bc, face).
///
/// For a degenerate triangle (collinear corners) the face branch divides by zero and the
/// point may be non-finite; [`closest_point_triangle`] handles that case.
pub fn closest_point_triangle_feature(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> (DVec3, Feature) {
    let ab = b - a;
    let ac = c - a;
    // The projections of `p - corner` on the two edges from `a`.
    let dots = |corner: DVec3| {
        let v = p - corner;
        (ab.dot(v), ac.dot(v))
    };
    let (d1, d2) = dots(a);
    if d1 <= 0.0 && d2 <= 0.0 {
        return (a, Feature::A);
    }
    let (d3, d4) = dots(b);
    if d3 >= 0.0 && d4 <= d3 {
        return (b, Feature::B);
    }
    // The point of edge `start + t dir` when `p` is in the edge's Voronoi region: `v` is the
    // barycentric weight of the opposite corner, `s` and `e` the projections of `p` from the
    // edge's two ends.
    let edge = |v: f64, s: f64, e: f64, start: DVec3, dir: DVec3| {
        (v <= 0.0 && s >= 0.0 && e <= 0.0).then(|| start + dir * (s / (s - e)))
    };
    let vc = d1 * d4 - d3 * d2;
    if let Some(q) = edge(vc, d1, d3, a, ab) {
        return (q, Feature::Ab);
    }
    let (d5, d6) = dots(c);
    if d6 >= 0.0 && d5 <= d6 {
        return (c, Feature::C);
    }
    let vb = d5 * d2 - d1 * d6;
    if let Some(q) = edge(vb, d2, d6, a, ac) {
        return (q, Feature::Ca);
    }
    let va = d3 * d6 - d5 * d4;
    // (d4 - d3) / ((d4 - d3) - (d6 - d5)) is Ericson's (d4 - d3) / ((d4 - d3) + (d5 - d6)):
    // negation is exact.
    if let Some(q) = edge(va, d4 - d3, d6 - d5, b, c - b) {
        return (q, Feature::Bc);
    }
    let denom = 1.0 / (va + vb + vc);
    let v = vb * denom;
    let w = vc * denom;
    (a + ab * v + ac * w, Feature::Face)
}

/// Closest point of triangle `abc` to `p`; works for degenerate triangles too (then the
/// closest point of the three edges, the first on ties).
pub fn closest_point_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    let (q, f) = closest_point_triangle_feature(p, a, b, c);
    if f != Feature::Face || q.is_finite() {
        return q;
    }
    [
        closest_point_segment(p, a, b),
        closest_point_segment(p, b, c),
        closest_point_segment(p, c, a),
    ]
    .into_iter()
    .min_by(|x, y| {
        (*x - p)
            .length_squared()
            .total_cmp(&(*y - p).length_squared())
    })
    .unwrap_or(a)
}

/// Closest point of segment `[a, b]` to `p` (`a` for a degenerate segment).
pub fn closest_point_segment(p: DVec3, a: DVec3, b: DVec3) -> DVec3 {
    let d = b - a;
    let dd = d.length_squared();
    if dd.is_nan() || dd <= 0.0 {
        return a;
    }
    let t = ((p - a).dot(d) / dd).clamp(0.0, 1.0);
    a + d * t
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_util::{RIGHT_TRIANGLE, pt_within};
    use proptest::prelude::*;

    #[test]
    fn features_of_a_right_triangle() {
        let (a, b, c) = RIGHT_TRIANGLE;
        let f = |x: f64, y: f64| closest_point_triangle_feature(DVec3::new(x, y, 1.0), a, b, c);
        let (q, face) = f(0.2, 0.2);
        assert_eq!(face, Feature::Face);
        assert!((q - DVec3::new(0.2, 0.2, 0.0)).length() < 1e-15);
        assert_eq!(f(-1.0, -1.0), (a, Feature::A));
        assert_eq!(f(2.0, -1.0), (b, Feature::B));
        assert_eq!(f(-1.0, 2.0), (c, Feature::C));
        assert_eq!(f(0.5, -1.0), (DVec3::new(0.5, 0.0, 0.0), Feature::Ab));
        assert_eq!(f(-1.0, 0.5), (DVec3::new(0.0, 0.5, 0.0), Feature::Ca));
        assert_eq!(f(1.0, 1.0), (DVec3::new(0.5, 0.5, 0.0), Feature::Bc));
        // Degenerate triangle: the nearest edge point.
        let q = closest_point_triangle(DVec3::new(0.5, 1.0, 0.0), a, b, DVec3::splat(0.0));
        assert_eq!(q, DVec3::new(0.5, 0.0, 0.0));
        assert_eq!(closest_point_segment(DVec3::Y, a, a), a);
    }

    proptest! {
        /// The closest point is on the triangle's plane and no farther than any vertex or any
        /// sampled point of the triangle.
        #[test]
        fn no_farther_than_any_point_of_the_triangle(
            p in pt_within(10.0), a in pt_within(10.0), b in pt_within(10.0), c in pt_within(10.0), u in 0.0f64..1.0, v in 0.0f64..1.0,
        ) {
            let q = closest_point_triangle(p, a, b, c);
            let d = (q - p).length();
            let tol = 1e-9 * (1.0 + p.length() + a.length() + b.length() + c.length());
            let (u, v) = if u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) };
            for x in [a, b, c, a + (b - a) * u + (c - a) * v] {
                prop_assert!(d <= (x - p).length() + tol);
            }
            let n = (b - a).cross(c - a);
            if n.length() > 1e-6 {
                prop_assert!(((q - a).dot(n) / n.length()).abs() <= tol);
            }
        }
    }
}
