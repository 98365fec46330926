//! The triangle BVH (ours; median split, see [`super`]) with per-node dipole data for the
//! fast generalized winding number (Barill et al. 2018, "Fast winding numbers for soups and
//! clouds", to second order), nearest-triangle and segment-crossing queries.

use glam::{DMat3, DVec3};

use super::{Aabb, segment_box, split};
use crate::closest::{Feature, closest_point_triangle, closest_point_triangle_feature};
use crate::predicates::segment_crosses_triangle;

/// Solid angle of triangle `abc` seen from `p` (Van Oosterom & Strackee 1983), positive when
/// `p` is behind the triangle (on the side opposite to `(b-a)×(c-a)`).
#[inline]
pub fn solid_angle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let a = a - p;
    let b = b - p;
    let c = c - p;
    let la = a.length();
    let lb = b.length();
    let lc = c.length();
    let num = a.dot(b.cross(c));
    let den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
    2.0 * num.atan2(den)
}

#[derive(Clone, Debug)]
struct Node {
    lo: DVec3,
    hi: DVec3,
    /// Leaf: first triangle; inner: index of the left child (right child = `left + 1`).
    first: u32,
    /// Number of triangles for a leaf, 0 for an inner node.
    count: u32,
    /// Area-weighted centroid (dipole position).
    center: DVec3,
    /// Sum of the triangles' area vectors `½ (b-a)×(c-a)`.
    area_vec: DVec3,
    /// Largest distance from `center` to a vertex of the node's triangles.
    radius: f64,
    /// Total area of the node's triangles (weights of the centers).
    wsum: f64,
    /// First moment `Σ_t a_t ⊗ (g_t − center)` (area vector ⊗ centroid offset), column `j`
    /// holding `Σ a_t (g_t − center)_j`: the second-order term of the far-field expansion.
    moment: DMat3,
}

/// A BVH over triangles stored by value in leaf order, with per-node dipole data for the
/// fast generalized winding number (Barill et al. 2018, to second order).
///
/// Triangles are addressed by their *leaf-order index* (`0..len()`, the order of
/// [`TriangleBvh::tris`]) or by the *face id* given at build time
/// ([`TriangleBvh::face_ids`]). Invariant: node boxes are the tight boxes of their triangles
/// (segment queries inflate them by `pad`); an empty tree has no nodes and answers every
/// query with nothing.
#[derive(Clone, Debug)]
pub struct TriangleBvh {
    nodes: Vec<Node>,
    /// Triangle corners, in leaf order.
    tris: Vec<[DVec3; 3]>,
    /// For each triangle in leaf order: its face id.
    face_ids: Vec<u32>,
    /// Box inflation used by segment traversal (absolute).
    pad: f64,
}

/// Far-field acceptance: a node is approximated by its dipole when the query is farther than
/// `BETA × radius` from its center.
const BETA: f64 = 2.0;

impl TriangleBvh {
    /// Build over `tris` (face id `face_ids[i]` for `tris[i]`); `pad` inflates the node boxes
    /// for segment queries (absolute, to make the slab test conservative).
    pub fn build(tris: Vec<[DVec3; 3]>, face_ids: Vec<u32>, pad: f64) -> Self {
        assert_eq!(tris.len(), face_ids.len(), "one face id per triangle");
        let cents: Vec<DVec3> = tris.iter().map(|t| (t[0] + t[1] + t[2]) / 3.0).collect();
        let s = split(&cents);
        let nodes = s
            .nodes
            .iter()
            .map(|&[first, count]| Node {
                first,
                count,
                ..Node::empty()
            })
            .collect();
        let tris_sorted: Vec<[DVec3; 3]> = s.order.iter().map(|&i| tris[i as usize]).collect();
        let ids_sorted: Vec<u32> = s.order.iter().map(|&i| face_ids[i as usize]).collect();
        let mut bvh = TriangleBvh {
            nodes,
            tris: tris_sorted,
            face_ids: ids_sorted,
            pad,
        };
        if !bvh.nodes.is_empty() {
            bvh.refit(0);
        }
        bvh
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.tris.len()
    }
    /// No triangles.
    pub fn is_empty(&self) -> bool {
        self.tris.is_empty()
    }
    /// Triangle corners in leaf order.
    pub fn tris(&self) -> &[[DVec3; 3]] {
        &self.tris
    }
    /// Face id of each triangle in leaf order.
    pub fn face_ids(&self) -> &[u32] {
        &self.face_ids
    }

    /// Bottom-up fill of boxes and dipoles; returns nothing, recursion depth is O(log n).
    fn refit(&mut self, ni: usize) {
        let node = self.nodes[ni].clone();
        let (lo, hi, center, area_vec, wsum);
        if node.count > 0 {
            let (mut l, mut h) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
            let (mut c, mut av, mut ws) = (DVec3::ZERO, DVec3::ZERO, 0.0);
            for t in &self.tris[node.first as usize..(node.first + node.count) as usize] {
                for v in t {
                    l = l.min(*v);
                    h = h.max(*v);
                }
                let a = 0.5 * (t[1] - t[0]).cross(t[2] - t[0]);
                let w = a.length();
                c += w * (t[0] + t[1] + t[2]) / 3.0;
                ws += w;
                av += a;
            }
            (lo, hi, center, area_vec, wsum) = (l, h, c, av, ws);
        } else {
            let li = node.first as usize;
            self.refit(li);
            self.refit(li + 1);
            let (a, b) = (&self.nodes[li], &self.nodes[li + 1]);
            let (wa, wb) = (a.wsum, b.wsum);
            lo = a.lo.min(b.lo);
            hi = a.hi.max(b.hi);
            center = a.center * wa + b.center * wb;
            wsum = wa + wb;
            area_vec = a.area_vec + b.area_vec;
        }
        let center = if wsum > 0.0 {
            center / wsum
        } else {
            0.5 * (lo + hi)
        };
        // Radius: distance from center to the farthest box corner (a bound on the vertices).
        let far = (center - lo).abs().max((hi - center).abs());
        let outer = |a: DVec3, d: DVec3| DMat3::from_cols(a * d.x, a * d.y, a * d.z);
        let moment = if node.count > 0 {
            let s = node.first as usize;
            self.tris[s..s + node.count as usize]
                .iter()
                .map(|t| {
                    let a = 0.5 * (t[1] - t[0]).cross(t[2] - t[0]);
                    outer(a, (t[0] + t[1] + t[2]) / 3.0 - center)
                })
                .fold(DMat3::ZERO, |m, x| m + x)
        } else {
            let (a, b) = (
                &self.nodes[node.first as usize],
                &self.nodes[node.first as usize + 1],
            );
            a.moment
                + outer(a.area_vec, a.center - center)
                + b.moment
                + outer(b.area_vec, b.center - center)
        };
        // Tighter bound: vertices of a leaf, children's spheres for an inner node.
        let tight = if node.count > 0 {
            let s = node.first as usize;
            self.tris[s..s + node.count as usize]
                .iter()
                .flatten()
                .map(|v| (*v - center).length())
                .fold(0.0, f64::max)
        } else {
            let (a, b) = (
                &self.nodes[node.first as usize],
                &self.nodes[node.first as usize + 1],
            );
            (a.radius + (a.center - center).length()).max(b.radius + (b.center - center).length())
        };
        let n = &mut self.nodes[ni];
        n.moment = moment;
        n.lo = lo;
        n.hi = hi;
        n.center = center;
        n.area_vec = area_vec;
        n.radius = far.length().min(tight);
        n.wsum = wsum;
    }

    /// Generalized winding number at `p` (sum of solid angles / 4π), nodes farther than
    /// `BETA` (2) times their radius by their far-field expansion.
    pub fn winding_number(&self, p: DVec3) -> f64 {
        if self.nodes.is_empty() {
            return 0.0;
        }
        let mut stack = [0u32; 64];
        let mut sp = 1;
        stack[0] = 0;
        let mut omega = 0.0;
        while sp > 0 {
            sp -= 1;
            let node = &self.nodes[stack[sp] as usize];
            let d = node.center - p;
            let d2 = d.length_squared();
            if d2 > (BETA * node.radius) * (BETA * node.radius) {
                // Taylor expansion of dA·(x−p)/|x−p|³ about the node center, to second order:
                // N·r/|r|³ + tr(M)/|r|³ − 3 rᵀMr/|r|⁵, r = center − p.
                let inv3 = 1.0 / (d2 * d2.sqrt());
                let m = &node.moment;
                let tr = m.x_axis.x + m.y_axis.y + m.z_axis.z;
                omega += inv3 * (node.area_vec.dot(d) + tr - 3.0 * d.dot(*m * d) / d2);
                continue;
            }
            if node.count > 0 {
                let s = node.first as usize;
                for t in &self.tris[s..s + node.count as usize] {
                    omega += solid_angle(p, t[0], t[1], t[2]);
                }
            } else if sp + 2 <= stack.len() {
                stack[sp] = node.first;
                stack[sp + 1] = node.first + 1;
                sp += 2;
            } else {
                // Unreachable for balanced trees (depth ≤ log2(n) + 1); exact fallback.
                omega += self.exact_omega(stack[sp] as usize, p);
            }
        }
        omega / (4.0 * std::f64::consts::PI)
    }

    fn exact_omega(&self, ni: usize, p: DVec3) -> f64 {
        let n = &self.nodes[ni];
        if n.count > 0 {
            let s = n.first as usize;
            self.tris[s..s + n.count as usize]
                .iter()
                .map(|t| solid_angle(p, t[0], t[1], t[2]))
                .sum()
        } else {
            self.exact_omega(n.first as usize, p) + self.exact_omega(n.first as usize + 1, p)
        }
    }

    /// Every crossing of the segment `[a, b]` with the triangles (exact, perturbed: see
    /// [`segment_crosses_triangle`]): `(t, leaf-order index)`, in traversal order.
    pub fn segment_hits(&self, a: DVec3, b: DVec3, out: &mut Vec<(f64, u32)>) {
        if self.nodes.is_empty() {
            return;
        }
        let d = b - a;
        // Depth ≤ log2(n / LEAF_SIZE) + 1 for the median-split tree: 64 slots always suffice
        // (the heap fallback is kept for safety).
        let mut fixed = [0u32; 64];
        let mut heap: Vec<u32> = Vec::new();
        let mut sp = 1;
        loop {
            let ni = if let Some(x) = heap.pop() {
                x
            } else if sp > 0 {
                sp -= 1;
                fixed[sp]
            } else {
                break;
            };
            let node = &self.nodes[ni as usize];
            if !segment_box(a, d, node.lo - self.pad, node.hi + self.pad) {
                continue;
            }
            if node.count > 0 {
                let s = node.first as usize;
                for (k, t) in self.tris[s..s + node.count as usize].iter().enumerate() {
                    if let Some(tt) = segment_crosses_triangle(a, b, t[0], t[1], t[2]) {
                        out.push((tt, (s + k) as u32));
                    }
                }
            } else if sp + 2 <= fixed.len() {
                fixed[sp] = node.first;
                fixed[sp + 1] = node.first + 1;
                sp += 2;
            } else {
                heap.push(node.first);
                heap.push(node.first + 1);
            }
        }
    }

    /// Closest point on the triangles to `p`: `(point, leaf-order index, squared distance,
    /// feature)` (as [`closest_point_triangle_feature`]; ties go to the triangle met first in
    /// the near-child-first traversal). Panics on an empty tree.
    pub fn closest(&self, p: DVec3) -> (DVec3, u32, f64, Feature) {
        let mut best = (self.tris[0][0], 0u32, f64::INFINITY, Feature::A);
        self.closest_rec(0, p, &mut best);
        best
    }

    /// Like [`TriangleBvh::closest`], restricted to triangles closer than `sqrt(r2)`.
    pub fn closest_within(&self, p: DVec3, r2: f64) -> Option<(DVec3, u32, f64, Feature)> {
        if self.nodes.is_empty() {
            return None;
        }
        let mut best = (self.tris[0][0], u32::MAX, r2, Feature::A);
        if box_dist2(p, &self.nodes[0]) < r2 {
            self.closest_rec(0, p, &mut best);
        }
        (best.1 != u32::MAX).then_some(best)
    }

    /// Number of crossings of `[a, b]` with the triangles (exact, perturbed predicates).
    pub fn count_hits(&self, a: DVec3, b: DVec3) -> usize {
        if self.nodes.is_empty() {
            return 0;
        }
        let d = b - a;
        let mut stack = [0u32; 64];
        let mut sp = 1;
        let mut n = 0;
        while sp > 0 {
            sp -= 1;
            let node = &self.nodes[stack[sp] as usize];
            if !segment_box(a, d, node.lo - self.pad, node.hi + self.pad) {
                continue;
            }
            if node.count > 0 {
                let s = node.first as usize;
                for t in &self.tris[s..s + node.count as usize] {
                    n += usize::from(segment_crosses_triangle(a, b, t[0], t[1], t[2]).is_some());
                }
            } else if sp + 2 <= stack.len() {
                stack[sp] = node.first;
                stack[sp + 1] = node.first + 1;
                sp += 2;
            } else {
                let mut v = Vec::new();
                self.segment_hits(a, b, &mut v);
                return v.len();
            }
        }
        n
    }

    fn closest_rec(&self, ni: usize, p: DVec3, best: &mut (DVec3, u32, f64, Feature)) {
        let node = &self.nodes[ni];
        if node.count > 0 {
            let s = node.first as usize;
            for (k, t) in self.tris[s..s + node.count as usize].iter().enumerate() {
                let (q, f) = closest_point_triangle_feature(p, t[0], t[1], t[2]);
                let d2 = (q - p).length_squared();
                if d2 < best.2 {
                    *best = (q, (s + k) as u32, d2, f);
                }
            }
            return;
        }
        let l = node.first as usize;
        let dl = box_dist2(p, &self.nodes[l]);
        let dr = box_dist2(p, &self.nodes[l + 1]);
        let (first, df, second, ds) = if dl <= dr {
            (l, dl, l + 1, dr)
        } else {
            (l + 1, dr, l, dl)
        };
        if df < best.2 {
            self.closest_rec(first, p, best);
        }
        if ds < best.2 {
            self.closest_rec(second, p, best);
        }
    }
    /// The triangle nearest to `p` by [`closest_point_triangle`] (degenerate triangles
    /// allowed) as `(face id, squared distance)`: exact branch and bound over the node boxes,
    /// ties to the smallest face id, whatever the tree. `None` for an empty tree.
    pub fn nearest(&self, p: DVec3) -> Option<(u32, f64)> {
        if self.nodes.is_empty() {
            return None;
        }
        let mut best: Option<(u32, f64)> = None;
        let mut stack: Vec<(f64, u32)> = Vec::with_capacity(64);
        stack.push((box_dist2(p, &self.nodes[0]), 0));
        while let Some((d, n)) = stack.pop() {
            if best.is_some_and(|(_, bd)| d > bd) {
                continue;
            }
            let node = &self.nodes[n as usize];
            if node.count > 0 {
                let s = node.first as usize;
                for k in s..s + node.count as usize {
                    let [a, b, c] = self.tris[k];
                    let di = (closest_point_triangle(p, a, b, c) - p).length_squared();
                    let i = self.face_ids[k];
                    super::keep_nearest(&mut best, i, di);
                }
            } else {
                let (l, r) = (node.first, node.first + 1);
                let dl = box_dist2(p, &self.nodes[l as usize]);
                let dr = box_dist2(p, &self.nodes[r as usize]);
                super::push_nearer_last(&mut stack, (dl, l), (dr, r));
            }
        }
        best
    }

    /// Call `f(face id)` for every triangle whose box overlaps `query` (closed boxes), in
    /// traversal order.
    pub fn for_each_overlap(&self, query: &Aabb, mut f: impl FnMut(u32)) {
        let node = |n: u32| {
            let nd = &self.nodes[n as usize];
            let bounds = Aabb {
                min: nd.lo,
                max: nd.hi,
            };
            (bounds, nd.first, nd.count)
        };
        super::walk_overlapping_leaves(self.nodes.len(), query, node, |first, count| {
            let s = first as usize;
            for k in s..s + count as usize {
                if Aabb::from_points(&self.tris[k]).overlaps(query) {
                    f(self.face_ids[k]);
                }
            }
        });
    }
}

impl Node {
    fn empty() -> Self {
        Node {
            lo: DVec3::ZERO,
            hi: DVec3::ZERO,
            first: 0,
            count: 0,
            center: DVec3::ZERO,
            area_vec: DVec3::ZERO,
            radius: 0.0,
            wsum: 0.0,
            moment: DMat3::ZERO,
        }
    }
}

fn box_dist2(p: DVec3, n: &Node) -> f64 {
    let q = p.clamp(n.lo, n.hi);
    (q - p).length_squared()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn far_field_matches_exact_sum() {
        // A wavy open patch of triangles, queried from far and near points.
        let mut tris = Vec::new();
        let f = |x: f64, y: f64| DVec3::new(x, y, 0.3 * (3.0 * x).sin() * (2.0 * y).cos());
        let n = 12;
        for i in 0..n {
            for j in 0..n {
                let (x0, y0, h) = (i as f64 / n as f64, j as f64 / n as f64, 1.0 / n as f64);
                tris.push([f(x0, y0), f(x0 + h, y0), f(x0 + h, y0 + h)]);
                tris.push([f(x0, y0), f(x0 + h, y0 + h), f(x0, y0 + h)]);
            }
        }
        let ids = (0..tris.len() as u32).collect();
        let bvh = TriangleBvh::build(tris.clone(), ids, 0.0);
        for q in [
            DVec3::new(0.5, 0.5, 0.8),
            DVec3::new(3.0, -1.0, 2.0),
            DVec3::new(0.2, 0.9, -0.3),
            DVec3::new(1.5, 0.5, 0.1),
        ] {
            let exact: f64 = tris
                .iter()
                .map(|t| solid_angle(q, t[0], t[1], t[2]))
                .sum::<f64>()
                / (4.0 * std::f64::consts::PI);
            let approx = bvh.winding_number(q);
            assert!(
                (exact - approx).abs() < 5e-3,
                "{q}: exact {exact} approx {approx}"
            );
        }
    }
    fn soup(seed: u64, n: usize) -> Vec<[DVec3; 3]> {
        let mut r = crate::SplitMix64(seed);
        (0..n)
            .map(|_| {
                let c = DVec3::new(r.next_f64(), r.next_f64(), r.next_f64()) * 4.0;
                [0; 3].map(|_| c + 0.3 * DVec3::new(r.next_f64(), r.next_f64(), r.next_f64()))
            })
            .collect()
    }

    proptest::proptest! {
        /// Nearest triangle, closest point, box overlaps and segment crossings agree with
        /// brute force over every triangle.
        #[test]
        fn queries_match_brute_force(
            seed in 0u64..1000,
            n in 1usize..60,
            q in proptest::array::uniform3(-1.0f64..5.0),
            e in proptest::array::uniform3(-1.0f64..5.0),
        ) {
            let tris = soup(seed, n);
            let ids: Vec<u32> = (0..n as u32).map(|i| 1000 + i).collect();
            let bvh = TriangleBvh::build(tris.clone(), ids, 1e-9);
            let q = DVec3::from_array(q);
            let d2 = |t: &[DVec3; 3]| (closest_point_triangle(q, t[0], t[1], t[2]) - q).length_squared();
            let (best_i, best_d) = tris.iter().enumerate().fold((0, f64::INFINITY), |(bi, bd), (i, t)| {
                let d = d2(t);
                if d < bd { (i, d) } else { (bi, bd) }
            });
            proptest::prop_assert_eq!(bvh.nearest(q), Some((1000 + best_i as u32, best_d)));
            let (_, k, d, _) = bvh.closest(q);
            proptest::prop_assert_eq!(d, best_d);
            proptest::prop_assert_eq!(d2(&bvh.tris()[k as usize]), best_d);
            proptest::prop_assert!(bvh.closest_within(q, best_d).is_none());
            let qb = Aabb { min: q, max: q + DVec3::splat(0.5) };
            let mut got = Vec::new();
            bvh.for_each_overlap(&qb, |i| got.push(i));
            got.sort_unstable();
            let want: Vec<u32> = (0..n as u32)
                .filter(|&i| Aabb::from_points(&tris[i as usize]).overlaps(&qb))
                .map(|i| 1000 + i)
                .collect();
            proptest::prop_assert_eq!(got, want);
            let e = DVec3::from_array(e);
            let brute = tris
                .iter()
                .filter(|t| segment_crosses_triangle(q, e, t[0], t[1], t[2]).is_some())
                .count();
            proptest::prop_assert_eq!(bvh.count_hits(q, e), brute);
            let mut hits = Vec::new();
            bvh.segment_hits(q, e, &mut hits);
            proptest::prop_assert_eq!(hits.len(), brute);
        }
    }

    #[test]
    fn empty_tree_answers_nothing() {
        let bvh = TriangleBvh::build(Vec::new(), Vec::new(), 0.0);
        assert!(bvh.is_empty());
        assert_eq!(bvh.nearest(DVec3::ZERO), None);
        assert_eq!(bvh.closest_within(DVec3::ZERO, 1.0), None);
        assert_eq!(bvh.winding_number(DVec3::ZERO), 0.0);
        assert_eq!(bvh.count_hits(DVec3::ZERO, DVec3::X), 0);
    }
}
