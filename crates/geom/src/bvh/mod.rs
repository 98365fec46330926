//! Bounding volume hierarchies (ours): one median-split construction ([`split`]: median on
//! the longest axis of the centroid box, leaves of at most [`LEAF_SIZE`] items, ties by
//! index, so the same input always gives the same tree) serving two trees:
//! - [`TriangleBvh`]: triangles stored by value in leaf order, with exact nearest-triangle
//!   queries, perturbed segment crossings, box overlaps and the fast generalized winding
//!   number (Barill et al. 2018) - the polyhedron and point-set oracles and `verify`;
//! - [`Bvh`]: items known only by their boxes (points, e.g. Voronoi poles): box overlaps and
//!   branch-and-bound nearest item.

use glam::DVec3;

mod boxes;
mod triangle;

pub use boxes::Bvh;
pub use triangle::{TriangleBvh, solid_angle};

/// Maximum number of items in a leaf.
pub const LEAF_SIZE: usize = 4;

/// An axis-aligned box (closed).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Lower corner.
    pub min: DVec3,
    /// Upper corner.
    pub max: DVec3,
}

impl Aabb {
    /// The empty box (min = +inf, max = -inf); the identity of `union`.
    pub const EMPTY: Aabb = Aabb {
        min: DVec3::INFINITY,
        max: DVec3::NEG_INFINITY,
    };

    /// Smallest box holding the points.
    pub fn from_points(pts: &[DVec3]) -> Aabb {
        pts.iter().fold(Aabb::EMPTY, |b, &p| b.grow(p))
    }
    /// The box extended to hold `p`.
    pub fn grow(self, p: DVec3) -> Aabb {
        Aabb {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }
    /// Smallest box holding both boxes.
    pub fn union(self, o: Aabb) -> Aabb {
        Aabb {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }
    /// Closed boxes overlap (touching counts).
    pub fn overlaps(&self, o: &Aabb) -> bool {
        self.min.cmple(o.max).all() && o.min.cmple(self.max).all()
    }
    /// Squared distance from `p` to the box (0 inside).
    pub fn distance_squared(&self, p: DVec3) -> f64 {
        let d = (self.min - p).max(p - self.max).max(DVec3::ZERO);
        d.length_squared()
    }
    /// Centre of the box.
    pub fn center(&self) -> DVec3 {
        0.5 * (self.min + self.max)
    }
}

/// The tree shape shared by both BVHs.
pub(crate) struct Split {
    /// Per node `[first, count]`: a leaf holds the slots `first..first + count` (count > 0);
    /// an inner node has count 0 and children `first` and `first + 1`. Node 0 is the root;
    /// children are numbered in depth-first, left-first order.
    pub nodes: Vec<[u32; 2]>,
    /// Item of each leaf slot (a permutation of `0..n`).
    pub order: Vec<u32>,
}

/// Median split of the items with the given centroids. Invariant: a node's items are
/// partitioned at `(s + e) / 2` by `(centroid[axis], index)`, `axis` the longest side of
/// the centroid box (x before y before z on ties). Empty input: no nodes.
pub(crate) fn split(cents: &[DVec3]) -> Split {
    let n = cents.len();
    let mut order: Vec<u32> = (0..n as u32).collect();
    let mut nodes = Vec::with_capacity(2 * n / LEAF_SIZE + 2);
    if n == 0 {
        return Split { nodes, order };
    }
    nodes.push([0, 0]);
    // Iterative build: (node index, start, end) ranges of `order`.
    let mut stack = vec![(0usize, 0usize, n)];
    while let Some((ni, s, e)) = stack.pop() {
        if e - s <= LEAF_SIZE {
            nodes[ni] = [s as u32, (e - s) as u32];
            continue;
        }
        let (mut clo, mut chi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
        for &t in &order[s..e] {
            clo = clo.min(cents[t as usize]);
            chi = chi.max(cents[t as usize]);
        }
        let ext = chi - clo;
        let axis = if ext.x >= ext.y && ext.x >= ext.z {
            0
        } else if ext.y >= ext.z {
            1
        } else {
            2
        };
        let mid = (s + e) / 2;
        order[s..e].select_nth_unstable_by(mid - s, |&i, &j| {
            cents[i as usize][axis]
                .total_cmp(&cents[j as usize][axis])
                .then(i.cmp(&j))
        });
        let left = nodes.len();
        nodes.push([0, 0]);
        nodes.push([0, 0]);
        nodes[ni] = [left as u32, 0];
        stack.push((left + 1, mid, e));
        stack.push((left, s, mid));
    }
    Split { nodes, order }
}

/// Conservative segment / box overlap (slab test) of `a + t d`, `t ∈ [0, 1]`.
#[inline]
/// Best-first nearest search, shared by both trees: keep `(i, d2)` if it is nearer than the
/// best so far (ties to the smaller index).
pub(crate) fn keep_nearest<I: Copy + PartialOrd>(best: &mut Option<(I, f64)>, i: I, d2: f64) {
    *best = match *best {
        Some((bi, bd)) if bd < d2 || (bd == d2 && bi < i) => Some((bi, bd)),
        _ => Some((i, d2)),
    };
}

/// Depth-first box-overlap walk shared by both trees (children `first` and `first + 1`,
/// the right one visited first): `node(n)` gives node `n`'s `(bounds, first, count)`, and
/// `leaf(first, count)` is called for every leaf whose bounds overlap `query`.
pub(crate) fn walk_overlapping_leaves(
    num_nodes: usize,
    query: &Aabb,
    node: impl Fn(u32) -> (Aabb, u32, u32),
    mut leaf: impl FnMut(u32, u32),
) {
    if num_nodes == 0 {
        return;
    }
    let mut stack = Vec::with_capacity(64);
    stack.push(0u32);
    while let Some(n) = stack.pop() {
        let (bounds, first, count) = node(n);
        if !bounds.overlaps(query) {
            continue;
        }
        if count > 0 {
            leaf(first, count);
        } else {
            stack.push(first);
            stack.push(first + 1);
        }
    }
}

/// Best-first nearest search: push the two children of a node so that the nearer one is
/// visited first (pushed last).
pub(crate) fn push_nearer_last(
    stack: &mut Vec<(f64, u32)>,
    (dl, l): (f64, u32),
    (dr, r): (f64, u32),
) {
    if dl <= dr {
        stack.push((dr, r));
        stack.push((dl, l));
    } else {
        stack.push((dl, l));
        stack.push((dr, r));
    }
}

pub(crate) fn segment_box(a: DVec3, d: DVec3, lo: DVec3, hi: DVec3) -> bool {
    let mut t0 = 0.0f64;
    let mut t1 = 1.0f64;
    for i in 0..3 {
        let (ai, di) = (a[i], d[i]);
        if di == 0.0 {
            if ai < lo[i] || ai > hi[i] {
                return false;
            }
            continue;
        }
        let inv = 1.0 / di;
        let (mut u, mut v) = ((lo[i] - ai) * inv, (hi[i] - ai) * inv);
        if u > v {
            std::mem::swap(&mut u, &mut v);
        }
        t0 = t0.max(u);
        t1 = t1.min(v);
        if t0 > t1 {
            return false;
        }
    }
    true
}
