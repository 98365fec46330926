//! A bounding-volume hierarchy over axis-aligned boxes: median split on the longest axis of
//! the centroid bounds, leaves of at most [`LEAF_SIZE`] items. Deterministic: the same boxes
//! always give the same tree.

use glam::DVec3;

/// Maximum number of items in a leaf.
pub const LEAF_SIZE: usize = 4;

/// An axis-aligned box (closed).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: DVec3,
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

#[derive(Clone, Copy, Debug)]
struct Node {
    bounds: Aabb,
    /// Leaf: first index into `items`; inner: index of the left child (right = left + 1).
    first: u32,
    /// Leaf: number of items (> 0); inner: 0.
    count: u32,
}

/// A BVH over item boxes; items are identified by their index in the input slice.
#[derive(Clone, Debug)]
pub struct Bvh {
    nodes: Vec<Node>,
    items: Vec<u32>,
    boxes: Vec<Aabb>,
}

impl Bvh {
    /// Build over `boxes` (item `i` has box `boxes[i]`).
    pub fn new(boxes: Vec<Aabb>) -> Bvh {
        let mut items: Vec<u32> = (0..boxes.len() as u32).collect();
        let centers: Vec<DVec3> = boxes.iter().map(Aabb::center).collect();
        let mut nodes = Vec::with_capacity(2 * boxes.len() / LEAF_SIZE + 1);
        if !boxes.is_empty() {
            nodes.push(Node {
                bounds: Aabb::EMPTY,
                first: 0,
                count: 0,
            });
            build(&mut nodes, 0, &mut items, 0, &boxes, &centers);
        }
        Bvh {
            nodes,
            items,
            boxes,
        }
    }

    /// Number of items.
    pub fn len(&self) -> usize {
        self.boxes.len()
    }
    /// No items.
    pub fn is_empty(&self) -> bool {
        self.boxes.is_empty()
    }
    /// Box of item `i`.
    pub fn item_box(&self, i: u32) -> Aabb {
        self.boxes[i as usize]
    }

    /// Call `f(i)` for every item whose box overlaps `query` (closed boxes).
    pub fn for_each_overlap(&self, query: &Aabb, mut f: impl FnMut(u32)) {
        if self.nodes.is_empty() {
            return;
        }
        let mut stack = Vec::with_capacity(64);
        stack.push(0u32);
        while let Some(n) = stack.pop() {
            let node = &self.nodes[n as usize];
            if !node.bounds.overlaps(query) {
                continue;
            }
            if node.count > 0 {
                for &i in &self.items[node.first as usize..(node.first + node.count) as usize] {
                    if self.boxes[i as usize].overlaps(query) {
                        f(i);
                    }
                }
            } else {
                stack.push(node.first);
                stack.push(node.first + 1);
            }
        }
    }

    /// The item minimising `dist2(i)` (a squared distance from `p` that is at least the
    /// squared distance from `p` to the item's box), with that value. Exact branch and bound:
    /// ties go to the smaller item index. `None` for an empty tree.
    pub fn nearest(&self, p: DVec3, dist2: impl Fn(u32) -> f64) -> Option<(u32, f64)> {
        if self.nodes.is_empty() {
            return None;
        }
        let mut best: Option<(u32, f64)> = None;
        let mut stack: Vec<(f64, u32)> = Vec::with_capacity(64);
        stack.push((self.nodes[0].bounds.distance_squared(p), 0));
        while let Some((d, n)) = stack.pop() {
            if let Some((_, bd)) = best
                && d > bd
            {
                continue;
            }
            let node = &self.nodes[n as usize];
            if node.count > 0 {
                for &i in &self.items[node.first as usize..(node.first + node.count) as usize] {
                    if let Some((_, bd)) = best
                        && self.boxes[i as usize].distance_squared(p) > bd
                    {
                        continue;
                    }
                    let di = dist2(i);
                    best = match best {
                        Some((bi, bd)) if bd < di || (bd == di && bi < i) => Some((bi, bd)),
                        _ => Some((i, di)),
                    };
                }
            } else {
                let (l, r) = (node.first, node.first + 1);
                let dl = self.nodes[l as usize].bounds.distance_squared(p);
                let dr = self.nodes[r as usize].bounds.distance_squared(p);
                // Visit the nearer child first (pushed last).
                if dl <= dr {
                    stack.push((dr, r));
                    stack.push((dl, l));
                } else {
                    stack.push((dl, l));
                    stack.push((dr, r));
                }
            }
        }
        best
    }
}

fn build(
    nodes: &mut Vec<Node>,
    node: usize,
    items: &mut [u32],
    offset: usize,
    boxes: &[Aabb],
    centers: &[DVec3],
) {
    let bounds = items
        .iter()
        .fold(Aabb::EMPTY, |b, &i| b.union(boxes[i as usize]));
    if items.len() <= LEAF_SIZE {
        nodes[node] = Node {
            bounds,
            first: offset as u32,
            count: items.len() as u32,
        };
        return;
    }
    let cb = items
        .iter()
        .fold(Aabb::EMPTY, |b, &i| b.grow(centers[i as usize]));
    let ext = cb.max - cb.min;
    let axis = if ext.x >= ext.y && ext.x >= ext.z {
        0
    } else if ext.y >= ext.z {
        1
    } else {
        2
    };
    let mid = items.len() / 2;
    items.select_nth_unstable_by(mid, |&a, &b| {
        centers[a as usize][axis]
            .total_cmp(&centers[b as usize][axis])
            .then(a.cmp(&b))
    });
    let left = nodes.len();
    nodes.push(Node {
        bounds: Aabb::EMPTY,
        first: 0,
        count: 0,
    });
    nodes.push(Node {
        bounds: Aabb::EMPTY,
        first: 0,
        count: 0,
    });
    nodes[node] = Node {
        bounds,
        first: left as u32,
        count: 0,
    };
    let (lo, hi) = items.split_at_mut(mid);
    build(nodes, left, lo, offset, boxes, centers);
    build(nodes, left + 1, hi, offset + mid, boxes, centers);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lcg(s: &mut u64) -> f64 {
        *s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (*s >> 11) as f64 / (1u64 << 53) as f64
    }

    #[test]
    fn overlap_and_nearest_match_brute_force() {
        let mut s = 7;
        let pts: Vec<DVec3> = (0..500)
            .map(|_| DVec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)))
            .collect();
        let boxes: Vec<Aabb> = pts
            .iter()
            .map(|&p| Aabb {
                min: p,
                max: p + DVec3::splat(0.02 * lcg(&mut s)),
            })
            .collect();
        let bvh = Bvh::new(boxes.clone());
        for _ in 0..50 {
            let q = DVec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) * 1.2 - 0.1;
            let qb = Aabb {
                min: q,
                max: q + DVec3::splat(0.1),
            };
            let mut got = Vec::new();
            bvh.for_each_overlap(&qb, |i| got.push(i));
            got.sort();
            let want: Vec<u32> = (0..500u32)
                .filter(|&i| boxes[i as usize].overlaps(&qb))
                .collect();
            assert_eq!(got, want);
            let (i, d) = bvh
                .nearest(q, |i| boxes[i as usize].distance_squared(q))
                .unwrap();
            let bd = boxes
                .iter()
                .map(|b| b.distance_squared(q))
                .fold(f64::INFINITY, f64::min);
            assert_eq!(d, bd);
            assert_eq!(boxes[i as usize].distance_squared(q), bd);
        }
    }
}
