//! A bounding volume hierarchy over triangles (median split on the longest axis of the
//! centroid box), with per-node dipole data for the fast generalized winding number
//! (Barill et al. 2018, first order).

use super::predicates::{closest_point_triangle_feature, segment_triangle, solid_angle};
use glam::{DMat3, DVec3};

/// Triangles per leaf (at most).
const LEAF_SIZE: usize = 4;

#[derive(Clone, Debug)]
pub(crate) struct Node {
    pub lo: DVec3,
    pub hi: DVec3,
    /// Leaf: first triangle; inner: index of the left child (right child = `left + 1`).
    pub first: u32,
    /// Number of triangles for a leaf, 0 for an inner node.
    pub count: u32,
    /// Area-weighted centroid (dipole position).
    pub center: DVec3,
    /// Sum of the triangles' area vectors `½ (b-a)×(c-a)`.
    pub area_vec: DVec3,
    /// Largest distance from `center` to a vertex of the node's triangles.
    pub radius: f64,
    /// Total area of the node's triangles (weights of the centers).
    pub wsum: f64,
    /// First moment `Σ_t a_t ⊗ (g_t − center)` (area vector ⊗ centroid offset), column `j`
    /// holding `Σ a_t (g_t − center)_j`: the second-order term of the far-field expansion.
    pub moment: DMat3,
}

/// BVH over triangles stored by value in BVH order.
#[derive(Clone, Debug)]
pub(crate) struct Bvh {
    pub nodes: Vec<Node>,
    /// Triangle corners, in leaf order.
    pub tris: Vec<[DVec3; 3]>,
    /// For each triangle in leaf order: its index in the input face list.
    pub face_ids: Vec<u32>,
    /// Box inflation used by segment traversal (absolute).
    pub pad: f64,
}

/// Far-field acceptance: a node is approximated by its dipole when the query is farther than
/// `BETA × radius` from its center.
const BETA: f64 = 2.0;

impl Bvh {
    pub fn build(tris: Vec<[DVec3; 3]>, face_ids: Vec<u32>, pad: f64) -> Self {
        let n = tris.len();
        let cents: Vec<DVec3> = tris.iter().map(|t| (t[0] + t[1] + t[2]) / 3.0).collect();
        let mut order: Vec<u32> = (0..n as u32).collect();
        let mut nodes = Vec::with_capacity(2 * n / LEAF_SIZE + 2);
        nodes.push(Node::empty());
        // Iterative build: (node index, start, end) ranges of `order`.
        let mut stack = vec![(0usize, 0usize, n)];
        while let Some((ni, s, e)) = stack.pop() {
            if e - s <= LEAF_SIZE {
                nodes[ni].first = s as u32;
                nodes[ni].count = (e - s) as u32;
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
            nodes.push(Node::empty());
            nodes.push(Node::empty());
            nodes[ni].first = left as u32;
            nodes[ni].count = 0;
            stack.push((left + 1, mid, e));
            stack.push((left, s, mid));
        }
        let tris_sorted: Vec<[DVec3; 3]> = order.iter().map(|&i| tris[i as usize]).collect();
        let ids_sorted: Vec<u32> = order.iter().map(|&i| face_ids[i as usize]).collect();
        let mut bvh = Bvh {
            nodes,
            tris: tris_sorted,
            face_ids: ids_sorted,
            pad,
        };
        bvh.refit(0);
        bvh
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

    /// Generalized winding number at `p` (sum of solid angles / 4π), far nodes by their dipole.
    pub fn winding_number(&self, p: DVec3) -> f64 {
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

    /// Every crossing of the segment `[a, b]` with the triangles: `(t, leaf-order index)`.
    pub fn segment_hits(&self, a: DVec3, b: DVec3, out: &mut Vec<(f64, u32)>) {
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
                    if let Some(tt) = segment_triangle(a, b, t[0], t[1], t[2]) {
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
    /// feature)` (feature as in `closest_point_triangle_feature`).
    pub fn closest(&self, p: DVec3) -> (DVec3, u32, f64, u8) {
        let mut best = (self.tris[0][0], 0u32, f64::INFINITY, 1u8);
        self.closest_rec(0, p, &mut best);
        best
    }

    /// Like [`Bvh::closest`], restricted to triangles closer than `sqrt(r2)`.
    pub fn closest_within(&self, p: DVec3, r2: f64) -> Option<(DVec3, u32, f64, u8)> {
        let mut best = (self.tris[0][0], u32::MAX, r2, 1u8);
        if box_dist2(p, &self.nodes[0]) < r2 {
            self.closest_rec(0, p, &mut best);
        }
        (best.1 != u32::MAX).then_some(best)
    }

    /// Number of crossings of `[a, b]` with the triangles (exact, perturbed predicates).
    pub fn count_hits(&self, a: DVec3, b: DVec3) -> usize {
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
                    n += usize::from(segment_triangle(a, b, t[0], t[1], t[2]).is_some());
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

    fn closest_rec(&self, ni: usize, p: DVec3, best: &mut (DVec3, u32, f64, u8)) {
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

/// Conservative segment / box overlap (slab test).
#[inline]
fn segment_box(a: DVec3, d: DVec3, lo: DVec3, hi: DVec3) -> bool {
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
        let bvh = Bvh::build(tris.clone(), ids, 0.0);
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
}
