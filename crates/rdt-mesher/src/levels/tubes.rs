//! Tubes between two boundary loops (ours; the repair's joined necks, rule 3', and the
//! bridges between the pieces of a split component, both on images after section 6.6.1's
//! patch): the zipper of two loops into an oriented annulus, the choice of zipper against
//! the size bound, and the circumballs that stand for the new triangles' surface Delaunay
//! balls.
//!
//! Invariant kept: a tube is an oriented annulus whose boundary is the two loops, each loop
//! edge in one triangle in its order (no diagonal is taken twice).

use crate::stats::SurfaceBall;
use glam::DVec3;
use meshio::TriMesh;
use rustc_hash::FxHashSet as HashSet;

/// The tube of the loops `p` and `q` ([`tube`]) of the zipper on the positions as they are or
/// with `p` moved onto `q`'s centroid (along a tube longer than its loops are wide the raw
/// lengths can twist it): the first whose triangles' circumballs are all within the size bound
/// of `criteria`, else the raw one (the neck is joined either way; the loose epsilon-sample
/// certificate then reports the triangle over the bound).
pub(super) fn tube_within(
    p: &[u32],
    q: &[u32],
    mesh: &TriMesh,
    criteria: Option<&crate::Criteria>,
) -> Vec<[u32; 3]> {
    let at = |v: &u32| mesh.vertices[*v as usize];
    let centroid = |l: &[u32]| l.iter().map(at).sum::<DVec3>() / l.len() as f64;
    let shift = centroid(q) - centroid(p);
    let mut raw = None;
    for superimposed in [false, true] {
        let mut moved;
        let pts = if superimposed {
            moved = mesh.vertices.clone();
            p.iter().for_each(|&v| moved[v as usize] += shift);
            &moved
        } else {
            &mesh.vertices
        };
        let t = tube(p, q, pts, &mut HashSet::default());
        let over = |t: &[u32; 3]| {
            let b = circumball(t.map(|v| mesh.vertices[v as usize]));
            criteria
                .and_then(|c| c.sigma_at(b.center))
                .is_some_and(|s| b.radius > s)
        };
        if !t.iter().any(over) {
            return t;
        }
        raw.get_or_insert(t);
    }
    raw.expect("the raw zipper was tried")
}

/// The tube joining the loops `p` and `q` (each in the order whose consecutive pairs the new
/// triangles must contain, as for [`super::holes::close_loop`]): a zipper that walks `p` forwards and `q`
/// backwards from their closest pair of vertices, taking the shorter diagonal first. Every
/// loop edge is in one triangle, in its order, and the diagonals pair up oppositely, so the
/// tube is an oriented annulus, provided no diagonal is taken twice: a step onto a pair of
/// vertices already joined is not taken (the other step is), and where both are, the zipper
/// that alternates the two loops' steps (always valid: its diagonals are distinct) is used.
/// Its edges are added to `edges`.
pub(super) fn tube(
    p: &[u32],
    q: &[u32],
    pts: &[DVec3],
    edges: &mut HashSet<[u32; 2]>,
) -> Vec<[u32; 3]> {
    let at = |v: u32| pts[v as usize];
    let (mut i, mut j) = (0usize, 0usize);
    let mut best = f64::INFINITY;
    for (a, &u) in p.iter().enumerate() {
        for (b, &w) in q.iter().enumerate() {
            let d = at(u).distance_squared(at(w));
            if d < best {
                (best, i, j) = (d, a, b);
            }
        }
    }
    let out = zipper(p, q, i, j, Some(&at))
        .unwrap_or_else(|| zipper(p, q, i, j, None).expect("the alternating zipper is valid"));
    let key = |a: u32, b: u32| [a.min(b), a.max(b)];
    for t in &out {
        for k in 0..3 {
            edges.insert(key(t[k], t[(k + 1) % 3]));
        }
    }
    out
}

/// The zipper of [`tube`] from `p[i]`, `q[j]`: shorter diagonal first with `at`, alternating
/// steps (P first) without; `None` when every step left would repeat a diagonal.
fn zipper(
    p: &[u32],
    q: &[u32],
    i: usize,
    j: usize,
    at: Option<&dyn Fn(u32) -> DVec3>,
) -> Option<Vec<[u32; 3]>> {
    let (m, n) = (p.len(), q.len());
    let pv = |k: usize| p[(i + k) % m];
    // q walked backwards: the k-th step back from j.
    let qv = |k: usize| q[(j + n * (k / n + 1) - k % n) % n];
    let mut seen: HashSet<(usize, usize)> = HashSet::default();
    seen.insert((0, 0));
    let (mut a, mut b) = (0usize, 0usize);
    let mut out = Vec::with_capacity(m + n);
    while a < m || b < n {
        let last = a + b + 1 == m + n;
        let free = |x: usize, y: usize| last || !seen.contains(&(x % m, y % n));
        let can_p = a < m && free(a + 1, b);
        let can_q = b < n && free(a, b + 1);
        let step_p = match (can_p, can_q) {
            (false, false) => return None,
            (true, false) => true,
            (false, true) => false,
            (true, true) => match at {
                Some(at) => {
                    at(pv(a + 1)).distance_squared(at(qv(b)))
                        <= at(qv(b + 1)).distance_squared(at(pv(a)))
                }
                None => a <= b,
            },
        };
        if step_p {
            out.push([pv(a), pv(a + 1), qv(b)]);
            a += 1;
        } else {
            out.push([qv(b + 1), qv(b), pv(a)]);
            b += 1;
        }
        seen.insert((a % m, b % n));
    }
    Some(out)
}

/// The ball circumscribing the triangle `p`: its circumcircle's center (the centroid if
/// degenerate) and the largest distance from there to a corner.
pub(super) fn circumball(p: [DVec3; 3]) -> SurfaceBall {
    let center = verify::certificate::circumcircle(p[0], p[1], p[2])
        .map_or((p[0] + p[1] + p[2]) / 3.0, |(c, _)| c);
    SurfaceBall {
        center,
        radius: p.iter().map(|q| q.distance(center)).fold(0.0, f64::max),
    }
}
