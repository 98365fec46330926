//! The box BVH (ours): items known by their boxes only, over the shared median split of
//! their box centres; overlap queries. (Nearest points: [`crate::kdtree::PointTree`].)

use glam::DVec3;

use super::{Aabb, split};

#[derive(Clone, Copy, Debug)]
struct Node {
    bounds: Aabb,
    /// Leaf: first index into `items`; inner: index of the left child (right = left + 1).
    first: u32,
    /// Leaf: number of items (> 0); inner: 0.
    count: u32,
}

/// A BVH over item boxes; items are identified by their index in the input.
#[derive(Clone, Debug)]
pub struct Bvh {
    nodes: Vec<Node>,
    items: Vec<u32>,
    boxes: Vec<Aabb>,
}

impl Bvh {
    /// Build over `boxes` (item `i` has box `boxes[i]`).
    pub fn new(boxes: Vec<Aabb>) -> Bvh {
        let centers: Vec<DVec3> = boxes.iter().map(Aabb::center).collect();
        let s = split(&centers);
        let mut nodes: Vec<Node> = s
            .nodes
            .iter()
            .map(|&[first, count]| Node {
                bounds: Aabb::EMPTY,
                first,
                count,
            })
            .collect();
        // Children have larger indices than their parent: fill bounds bottom-up.
        for ni in (0..nodes.len()).rev() {
            let Node { first, count, .. } = nodes[ni];
            nodes[ni].bounds = if count > 0 {
                s.order[first as usize..(first + count) as usize]
                    .iter()
                    .fold(Aabb::EMPTY, |b, &i| b.union(boxes[i as usize]))
            } else {
                nodes[first as usize]
                    .bounds
                    .union(nodes[first as usize + 1].bounds)
            };
        }
        Bvh {
            nodes,
            items: s.order,
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
        let node = |n: u32| {
            let nd = &self.nodes[n as usize];
            (nd.bounds, nd.first, nd.count)
        };
        super::walk_overlapping_leaves(self.nodes.len(), query, node, |first, count| {
            for &i in &self.items[first as usize..(first + count) as usize] {
                if self.boxes[i as usize].overlaps(query) {
                    f(i);
                }
            }
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::SplitMix64;

    #[test]
    fn overlap_matches_brute_force() {
        let mut r = SplitMix64(7);
        let mut u = || r.next_f64();
        let pts: Vec<DVec3> = (0..500).map(|_| DVec3::new(u(), u(), u())).collect();
        let boxes: Vec<Aabb> = pts
            .iter()
            .map(|&p| Aabb {
                min: p,
                max: p + DVec3::splat(0.02 * u()),
            })
            .collect();
        let bvh = Bvh::new(boxes.clone());
        assert_eq!(bvh.len(), 500);
        for _ in 0..50 {
            let q = DVec3::new(u(), u(), u()) * 1.2 - 0.1;
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
        }
        assert!(Bvh::new(Vec::new()).is_empty());
    }
}
