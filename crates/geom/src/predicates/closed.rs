//! Exact intersection tests of closed segments and triangles (ours; what `verify`'s
//! self-intersection check decides): touching counts as meeting, coplanar configurations
//! included. Only signs of [`super`]'s predicates are compared, so the orientation
//! convention never matters here.

use glam::DVec3;

use super::{Sign, orient2d, orient3d, projection_axis};

/// Is `r` (collinear with `p, q` in projection `k`) within the closed segment's box?
fn within(p: DVec3, q: DVec3, r: DVec3, k: usize) -> bool {
    (0..3)
        .filter(|&i| i != k)
        .all(|i| r[i] >= p[i].min(q[i]) && r[i] <= p[i].max(q[i]))
}

/// Closed segments `[p, q]` and `[r, s]` intersect in projection `k` (points coplanar).
fn segments_2d(p: DVec3, q: DVec3, r: DVec3, s: DVec3, k: usize) -> bool {
    let d1 = orient2d(p, q, r, k);
    let d2 = orient2d(p, q, s, k);
    let d3 = orient2d(r, s, p, k);
    let d4 = orient2d(r, s, q, k);
    if d1 * d2 == Sign::Negative && d3 * d4 == Sign::Negative {
        return true;
    }
    (d1.is_zero() && within(p, q, r, k))
        || (d2.is_zero() && within(p, q, s, k))
        || (d3.is_zero() && within(r, s, p, k))
        || (d4.is_zero() && within(r, s, q, k))
}

/// Do the signs take both strict values?
fn mixed(s: &[Sign; 3]) -> bool {
    s.contains(&Sign::Positive) && s.contains(&Sign::Negative)
}

/// `p` lies in the closed triangle `abc` (coplanar, projection `k` non-degenerate).
fn point_in_triangle_2d(p: DVec3, a: DVec3, b: DVec3, c: DVec3, k: usize) -> bool {
    !mixed(&[
        orient2d(a, b, p, k),
        orient2d(b, c, p, k),
        orient2d(c, a, p, k),
    ])
}

/// Exact test: does the closed segment `[p, q]` (p != q) meet the closed, non-degenerate
/// triangle `abc`? Coplanar configurations included.
pub fn segment_meets_triangle(p: DVec3, q: DVec3, a: DVec3, b: DVec3, c: DVec3) -> bool {
    let sp = orient3d(a, b, c, p);
    let sq = orient3d(a, b, c, q);
    if sp * sq == Sign::Positive {
        return false;
    }
    if sp.is_zero() && sq.is_zero() {
        let Some((k, _)) = projection_axis(a, b, c) else {
            return false;
        };
        return point_in_triangle_2d(p, a, b, c, k)
            || point_in_triangle_2d(q, a, b, c, k)
            || segments_2d(p, q, a, b, k)
            || segments_2d(p, q, b, c, k)
            || segments_2d(p, q, c, a, k);
    }
    // The line pq crosses the plane at a single point X inside [p, q]. X is in the closed
    // triangle iff the three Plücker-type orientations do not take both strict signs.
    !mixed(&[
        orient3d(p, q, a, b),
        orient3d(p, q, b, c),
        orient3d(p, q, c, a),
    ])
}

/// Exact test: do the closed, non-degenerate triangles `t` and `u` intersect?
/// (Two closed triangles meet iff an edge of one meets the other.)
pub fn triangles_intersect(t: [DVec3; 3], u: [DVec3; 3]) -> bool {
    let one_side = |s: [Sign; 3]| {
        s.iter().all(|&x| x == Sign::Positive) || s.iter().all(|&x| x == Sign::Negative)
    };
    if one_side(u.map(|p| orient3d(t[0], t[1], t[2], p))) {
        return false;
    }
    if one_side(t.map(|p| orient3d(u[0], u[1], u[2], p))) {
        return false;
    }
    (0..3).any(|i| segment_meets_triangle(t[i], t[(i + 1) % 3], u[0], u[1], u[2]))
        || (0..3).any(|i| segment_meets_triangle(u[i], u[(i + 1) % 3], t[0], t[1], t[2]))
}

/// Triangles `(v, a1, a2)` and `(v, b1, b2)` share exactly the vertex `v`: do they meet
/// anywhere else? (Their intersection is convex and contains v; if it has another point,
/// the nearer of the two exit points along that direction lies on an opposite edge.)
pub fn shared_vertex_overlap(v: DVec3, a: [DVec3; 2], b: [DVec3; 2]) -> bool {
    segment_meets_triangle(a[0], a[1], v, b[0], b[1])
        || segment_meets_triangle(b[0], b[1], v, a[0], a[1])
}

/// Triangles `(u, w, a)` and `(u, w, b)` share exactly the edge `uw`: do they overlap beyond
/// it? Only when coplanar with `a` and `b` on the same side of `uw` (a fold-over).
pub fn shared_edge_overlap(u: DVec3, w: DVec3, a: DVec3, b: DVec3) -> bool {
    if !orient3d(u, w, a, b).is_zero() {
        return false;
    }
    let Some((k, sa)) = projection_axis(u, w, a) else {
        return false;
    };
    orient2d(u, w, b, k) == sa
}

#[cfg(test)]
mod tests {
    use super::*;
    const O: DVec3 = DVec3::ZERO;

    #[test]
    fn segment_triangle_cases() {
        let (a, b, c) = (O, DVec3::X, DVec3::Y);
        let z = |x, y, z0, z1| (DVec3::new(x, y, z0), DVec3::new(x, y, z1));
        let (p, q) = z(0.2, 0.2, -1.0, 1.0);
        assert!(segment_meets_triangle(p, q, a, b, c));
        let (p, q) = z(0.6, 0.6, -1.0, 1.0);
        assert!(!segment_meets_triangle(p, q, a, b, c));
        let (p, q) = z(0.5, 0.5, -1.0, 1.0); // through the hypotenuse
        assert!(segment_meets_triangle(p, q, a, b, c));
        let (p, q) = z(0.2, 0.2, 0.0, 1.0); // touches with an endpoint
        assert!(segment_meets_triangle(p, q, a, b, c));
        let (p, q) = z(0.2, 0.2, 1e-300, 1.0); // just above
        assert!(!segment_meets_triangle(p, q, a, b, c));
        // Coplanar: crossing an edge, inside, outside, touching a vertex.
        let (p, q) = (DVec3::new(-1.0, 0.5, 0.0), DVec3::new(0.1, 0.5, 0.0));
        assert!(segment_meets_triangle(p, q, a, b, c));
        let (p, q) = (DVec3::new(0.1, 0.1, 0.0), DVec3::new(0.2, 0.1, 0.0));
        assert!(segment_meets_triangle(p, q, a, b, c));
        let (p, q) = (DVec3::new(-1.0, -1.0, 0.0), DVec3::new(-1.0, 2.0, 0.0));
        assert!(!segment_meets_triangle(p, q, a, b, c));
        let (p, q) = (DVec3::new(1.0, 0.0, 0.0), DVec3::new(2.0, 0.0, 0.0));
        assert!(segment_meets_triangle(p, q, a, b, c));
    }

    #[test]
    fn shared_cases() {
        // Opposite sectors around the origin: only the vertex in common.
        assert!(!shared_vertex_overlap(
            O,
            [DVec3::X, DVec3::Y],
            [-DVec3::X, -DVec3::Y]
        ));
        // Sectors sharing a ray (the second triangle's edge lies on the first's): overlap.
        assert!(shared_vertex_overlap(
            O,
            [DVec3::X, DVec3::Y],
            [DVec3::Y, -DVec3::X]
        ));
        // Non-coplanar fans, as around a mesh vertex: no overlap.
        assert!(!shared_vertex_overlap(
            O,
            [DVec3::X, DVec3::Y],
            [-DVec3::X, DVec3::Z]
        ));
        // Overlapping sectors in the same plane.
        let d = DVec3::new(1.0, 1.0, 0.0);
        assert!(shared_vertex_overlap(
            O,
            [DVec3::X, DVec3::Y],
            [d, DVec3::new(2.0, 0.5, 0.0)]
        ));
        // Piercing: second triangle pokes through the first.
        let t2 = [DVec3::new(0.3, 0.3, -1.0), DVec3::new(0.3, 0.3, 1.0)];
        assert!(shared_vertex_overlap(
            DVec3::new(-1.0, -1.0, 0.0),
            [DVec3::X, DVec3::Y],
            t2
        ));
        // Shared edge: folded over vs flat.
        assert!(shared_edge_overlap(O, DVec3::X, DVec3::Y, d));
        assert!(!shared_edge_overlap(O, DVec3::X, DVec3::Y, -DVec3::Y));
        assert!(!shared_edge_overlap(O, DVec3::X, DVec3::Y, DVec3::Z));
    }
}
