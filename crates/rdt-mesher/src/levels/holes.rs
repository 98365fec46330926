//! Closing a boundary loop (ours, for the topological repair after section 6.6.1's patch): of
//! the triangulations of the loop that add no edge already in the mesh (so every edge keeps
//! two triangles), the one whose smallest angle is largest (then the least area), by dynamic
//! programming; or a fan from the loop's centroid (a new vertex) when its smallest angle is
//! larger, when no such triangulation exists, or when the loop is long.

use glam::DVec3;
use rustc_hash::FxHashSet as HashSet;

/// Loops longer than this are closed by the centroid fan (the program is cubic).
const MAX_DP: usize = 200;

/// The triangles closing `poly` (vertex indices into `pts`, in the order whose consecutive
/// pairs p_i -> p_{i+1} the new triangles must contain), none of whose new edges is in
/// `edges` (sorted pairs). May push a new vertex onto `pts`. The new edges are added to
/// `edges`.
pub(crate) fn close_loop(
    poly: &[u32],
    pts: &mut Vec<DVec3>,
    edges: &mut HashSet<[u32; 2]>,
) -> Vec<[u32; 3]> {
    let n = poly.len();
    let key = |a: u32, b: u32| [a.min(b), a.max(b)];
    let dp = if n <= MAX_DP {
        best_triangulation(poly, pts, &|a, b| edges.contains(&key(a, b)))
    } else {
        None
    };
    let c = poly.iter().map(|&v| pts[v as usize]).sum::<DVec3>() / n as f64;
    let fan_angle = (0..n)
        .map(|i| min_angle([pts[poly[i] as usize], pts[poly[(i + 1) % n] as usize], c]))
        .fold(f64::INFINITY, f64::min);
    let out = match dp {
        Some((angle, t)) if angle >= fan_angle => t,
        _ => {
            let m = pts.len() as u32;
            pts.push(c);
            (0..n).map(|i| [poly[i], poly[(i + 1) % n], m]).collect()
        }
    };
    for t in &out {
        for i in 0..3 {
            edges.insert(key(t[i], t[(i + 1) % 3]));
        }
    }
    out
}

/// The smallest angle of a triangle (radians; 0 if degenerate).
fn min_angle(p: [DVec3; 3]) -> f64 {
    (0..3)
        .map(|i| {
            let (a, b) = (p[(i + 1) % 3] - p[i], p[(i + 2) % 3] - p[i]);
            let c = a.cross(b).length().atan2(a.dot(b));
            if c.is_finite() { c } else { 0.0 }
        })
        .fold(f64::INFINITY, f64::min)
}

/// The triangulation of the polygon `poly` whose diagonals avoid `taken` with the largest
/// smallest angle, then the least area, with that angle; `None` if every triangulation uses
/// a taken diagonal.
fn best_triangulation(
    poly: &[u32],
    pts: &[DVec3],
    taken: &dyn Fn(u32, u32) -> bool,
) -> Option<(f64, Vec<[u32; 3]>)> {
    let n = poly.len();
    if n < 3 {
        return None;
    }
    let p = |i: usize| pts[poly[i] as usize];
    let area = |i: usize, j: usize, k: usize| 0.5 * (p(j) - p(i)).cross(p(k) - p(i)).length();
    // w[i][k]: (smallest angle, -area) of the best triangulation of the sub-polygon i..=k
    // (k - i >= 1), compared lexicographically; choice[i][k] its apex.
    let idx = |i: usize, k: usize| i * n + k;
    let none = (f64::NEG_INFINITY, f64::NEG_INFINITY);
    let mut w = vec![none; n * n];
    let mut choice = vec![usize::MAX; n * n];
    for i in 0..n - 1 {
        w[idx(i, i + 1)] = (f64::INFINITY, 0.0);
    }
    for len in 2..n {
        for i in 0..n - len {
            let k = i + len;
            // The chord (i, k) is a new edge unless it is the loop edge (0, n - 1).
            if !(i == 0 && k == n - 1) && taken(poly[i], poly[k]) {
                continue;
            }
            let mut best = (none, usize::MAX);
            for j in i + 1..k {
                let (a, b) = (w[idx(i, j)], w[idx(j, k)]);
                if a.0 == f64::NEG_INFINITY || b.0 == f64::NEG_INFINITY {
                    continue;
                }
                let c = (
                    a.0.min(b.0).min(min_angle([p(i), p(j), p(k)])),
                    a.1 + b.1 - area(i, j, k),
                );
                if c.0 > best.0.0 || (c.0 == best.0.0 && c.1 > best.0.1) {
                    best = (c, j);
                }
            }
            (w[idx(i, k)], choice[idx(i, k)]) = best;
        }
    }
    let angle = w[idx(0, n - 1)].0;
    if angle == f64::NEG_INFINITY {
        return None;
    }
    let mut out = Vec::with_capacity(n - 2);
    let mut stack = vec![(0usize, n - 1)];
    while let Some((i, k)) = stack.pop() {
        if k - i < 2 {
            continue;
        }
        let j = choice[idx(i, k)];
        out.push([poly[i], poly[j], poly[k]]);
        stack.push((i, j));
        stack.push((j, k));
    }
    Some((angle, out))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_square_gets_two_triangles_and_a_taken_diagonal_is_avoided() {
        let mut pts = vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
        let mut edges = HashSet::default();
        let t = close_loop(&[0, 1, 2, 3], &mut pts, &mut edges);
        assert_eq!(t.len(), 2);
        // Both diagonals taken: the centroid fan.
        let mut edges: HashSet<[u32; 2]> = [[0, 2], [1, 3]].into_iter().collect();
        let t = close_loop(&[0, 1, 2, 3], &mut pts, &mut edges);
        assert_eq!((t.len(), pts.len()), (4, 5));
        // Every triangle keeps the polygon's direction on its polygon edge.
        for (i, tri) in t.iter().enumerate() {
            assert_eq!([tri[0], tri[1]], [i as u32, (i as u32 + 1) % 4]);
        }
    }
}
