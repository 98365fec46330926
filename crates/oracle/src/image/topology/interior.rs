//! Joins through a voxel cell's interior (P1 for images, section 6.6.2): corners of equal sign
//! that the trilinear interpolant connects inside the cell, not along its edges and faces.
//!
//! The scan joins 6-neighbours and the diagonals of ambiguous faces (asymptotic decider). A
//! region can also pass through a cell's interior, between two corners that no face joins:
//! the tunnel of marching cubes 33 (its cases 4.1.2, 6.1.2, 7.4.2, 10.1.2, 12.1.2, 13.5.2).
//! Without these joins the counts are too high: on nibabel's `anatomical.nii` at iso 9444.5
//! the scan found 285 surface components where the level set has 284 (marching cubes of the
//! interpolant sampled every 1/4, 1/16 and 1/32 voxel joins the two), and the mesher split
//! the surface there to match.
//!
//! **The test.** Slice the cell by planes `z = t`. On each slice the interpolant is bilinear,
//! and every component of a slice's inside (or outside) region holds a corner of the slice
//! (a point of one of the four z-parallel edges): the function is linear along the slice's
//! sides. So the cell's inside region is connected exactly as the inside parts of its four
//! z-edges are joined by slices. Two z-edges sharing a side face are joined on that face
//! (the scan's face joins already hold them). Two diagonal z-edges `e, e'` (with `o, o'` the
//! other two) are joined through the slice `t` when `e(t), e'(t)` have one sign, `o(t), o'(t)`
//! the other, and the slice's bilinear saddle lies on the side of `e`: with
//! `N(t) = e(t) e'(t) - o(t) o'(t)` (the saddle value is `N / (e + e' - o - o')`, whose
//! denominator has the sign of `e`), exactly when `N(t) > 0`. The slices where the signs hold
//! form an open interval `J` of `(0, 1)` (each condition is linear in `t`) and `N` is a
//! quadratic: the join exists iff `J` is not empty and `N > 0` somewhere on its closure
//! (at an end of `J` with `N > 0`, `N` stays positive a little inside). The slices `t = 0, 1`
//! are the cell's bottom and top faces, left to the face joins.
//!
//! Signs are those of the scan: inside is `g < 0`. The intervals use strict signs (`g < 0`,
//! `g > 0`): a value exactly 0 on an edge (a tie) joins nothing here.

/// A cell's corner `x + 2 y + 4 z` (`x, y, z` in {0, 1}).
pub(super) type Corner = u8;

/// The six faces of a cell as `(p00, u, v)`: corners `p00, p00 + u, p00 + v, p00 + u + v`
/// (the first three are the faces at corner 0).
pub(super) const FACES: [(Corner, Corner, Corner); 6] = [
    (0, 1, 2),
    (0, 1, 4),
    (0, 2, 4),
    (4, 1, 2),
    (2, 1, 4),
    (1, 2, 4),
];

/// The open interval of `t` in (0, 1) where `a + (b - a) t` is `< 0` (`neg`) or `> 0`.
fn sign_interval(a: f64, b: f64, neg: bool) -> (f64, f64) {
    let (a, b) = if neg { (a, b) } else { (-a, -b) };
    match (a < 0.0, b < 0.0) {
        (true, true) => (0.0, 1.0),
        (true, false) => (0.0, a / (a - b)),
        (false, true) => (a / (a - b), 1.0),
        (false, false) => (1.0, 0.0),
    }
}

/// The value of the bilinear interpolant of a face at its saddle (corners f00, f11 on one
/// diagonal, f10, f01 on the other; 0 for a degenerate face): the asymptotic decider joins the
/// inside diagonal when it is `< 0`, else the outside one. The scan, its reference and
/// [`face_groups`] decide every face with it.
pub(super) fn face_saddle(f00: f64, f10: f64, f01: f64, f11: f64) -> f64 {
    let den = f00 + f11 - f10 - f01;
    if den != 0.0 {
        (f00 * f11 - f10 * f01) / den
    } else {
        0.0
    }
}

/// On an ambiguous face `(p00, u, v)` of a cell with corner values `g` (one sign on each
/// diagonal, the two differ), the diagonal its saddle joins (the asymptotic decider:
/// the inside pair when [`face_saddle`] is `< 0`, else the outside pair); `None` on any
/// other face. The scan's face joins, [`face_groups`], the Euler sum and the saddle joins
/// all decide a face with it.
pub(super) fn face_diagonal(
    g: &[f64; 8],
    (p00, u, v): (Corner, Corner, Corner),
) -> Option<[Corner; 2]> {
    let (p10, p01, p11) = (p00 + u, p00 + v, p00 + u + v);
    let ins = |c: Corner| g[c as usize] < 0.0;
    let (a, b) = (ins(p00), ins(p10));
    if a != ins(p11) || b != ins(p01) || a == b {
        return None;
    }
    let [f00, f10, f01, f11] = [p00, p10, p01, p11].map(|c| g[c as usize]);
    Some(if (face_saddle(f00, f10, f01, f11) < 0.0) == a {
        [p00, p11]
    } else {
        [p10, p01]
    })
}

/// The groups of a cell's corners joined along its edges and faces as the scan joins them:
/// corners of one sign (inside: `g < 0`, as the scan's bits) that are 6-neighbours, and the
/// diagonal of an ambiguous face that the asymptotic decider picks (the saddle value `< 0`
/// joins the inside pair, else the outside pair). `groups[c]`: the smallest corner of `c`'s
/// group.
pub(super) fn face_groups(g: &[f64; 8]) -> [Corner; 8] {
    let mut parent: [Corner; 8] = std::array::from_fn(|c| c as Corner);
    fn find(p: &[Corner; 8], mut x: Corner) -> Corner {
        while p[x as usize] != x {
            x = p[x as usize];
        }
        x
    }
    let union = |p: &mut [Corner; 8], a: Corner, b: Corner| {
        let (ra, rb) = (find(p, a), find(p, b));
        p[ra.max(rb) as usize] = ra.min(rb);
    };
    let ins = |c: Corner| g[c as usize] < 0.0;
    for a in 0..8 {
        for k in [1, 2, 4] {
            if a & k == 0 && ins(a) == ins(a | k) {
                union(&mut parent, a, a | k);
            }
        }
    }
    for face in FACES {
        if let Some([a, b]) = face_diagonal(g, face) {
            union(&mut parent, a, b);
        }
    }
    std::array::from_fn(|c| find(&parent, c as Corner))
}

/// A join through a cell's interior: a corner of each of two diagonal z-edges, of the
/// join's sign (`g < 0` for an inside join, `g > 0` for an outside one), in different
/// [`face_groups`], and a point of the region between them (cell coordinates in [0, 1]^3:
/// the saddle of the slice where `N` is largest).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct InteriorJoin {
    pub a: Corner,
    pub b: Corner,
    pub via: [f64; 3],
}

/// The joins of the cell with corner values `g` (at corners `x + 2 y + 4 z`) through its
/// interior that its edges and faces do not make (see the module docs): at most one per
/// diagonal of z-edges and sign.
pub(super) fn interior_joins(g: &[f64; 8]) -> impl Iterator<Item = InteriorJoin> {
    let lin = |e: u8| (g[e as usize], g[e as usize + 4]);
    // The face groups only where a join is found (rare): this runs on every cell with both
    // signs among its corners.
    let mut groups: Option<[Corner; 8]> = None;
    let mut out = [None; 4];
    for (d, (e, f, o, p)) in [(0u8, 3u8, 1u8, 2u8), (1, 2, 0, 3)].into_iter().enumerate() {
        for (s, neg) in [true, false].into_iter().enumerate() {
            let mut lo = 0.0f64;
            let mut hi = 1.0f64;
            for (edge, want_neg) in [(e, neg), (f, neg), (o, !neg), (p, !neg)] {
                let (a, b) = lin(edge);
                let (l, h) = sign_interval(a, b, want_neg);
                lo = lo.max(l);
                hi = hi.min(h);
            }
            if lo >= hi {
                continue;
            }
            // N(t) = e(t) f(t) - o(t) p(t), with x(t) = x0 + dx t.
            let ((e0, e1), (f0, f1), (o0, o1), (p0, p1)) = (lin(e), lin(f), lin(o), lin(p));
            let (de, df, dob, dp) = (e1 - e0, f1 - f0, o1 - o0, p1 - p0);
            let n2 = de * df - dob * dp;
            let n1 = e0 * df + f0 * de - o0 * dp - p0 * dob;
            let n0 = e0 * f0 - o0 * p0;
            let n = |t: f64| n0 + t * (n1 + t * n2);
            let mut best = if n(hi) > n(lo) {
                (n(hi), hi)
            } else {
                (n(lo), lo)
            };
            if n2 < 0.0 {
                let tv = -n1 / (2.0 * n2);
                if tv > lo && tv < hi && n(tv) > best.0 {
                    best = (n(tv), tv);
                }
            }
            if best.0 <= 0.0 {
                continue;
            }
            let corner = |edge: u8| {
                let bottom = g[edge as usize];
                if (bottom < 0.0) == neg && bottom != 0.0 {
                    edge
                } else {
                    edge + 4
                }
            };
            let (a, b) = (corner(e), corner(f));
            let groups = groups.get_or_insert_with(|| face_groups(g));
            if groups[a as usize] == groups[b as usize] {
                continue;
            }
            // The slice's saddle (corners 0, 1, 2, 3 of the slice at (0,0), (1,0), (0,1),
            // (1,1)): on the region's side since N > 0.
            let t = best.1;
            let at = |c: u8| {
                let (x0, x1) = lin(c);
                x0 + (x1 - x0) * t
            };
            let (g00, g10, g01, g11) = (at(0), at(1), at(2), at(3));
            let den = g00 + g11 - g10 - g01;
            let via = if den != 0.0 {
                [
                    ((g00 - g01) / den).clamp(0.0, 1.0),
                    ((g00 - g10) / den).clamp(0.0, 1.0),
                    t,
                ]
            } else {
                [0.5, 0.5, t]
            };
            out[2 * d + s] = Some(InteriorJoin { a, b, via });
        }
    }
    out.into_iter().flatten()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::roots::SplitMix64;

    /// The trilinear interpolant of the corner values at (x, y, z) in the unit cube.
    fn tri(g: &[f64; 8], x: f64, y: f64, z: f64) -> f64 {
        let mut v = 0.0;
        for (c, gc) in g.iter().enumerate() {
            let (cx, cy, cz) = ((c & 1) as f64, ((c >> 1) & 1) as f64, ((c >> 2) & 1) as f64);
            v += gc
                * (if cx > 0.0 { x } else { 1.0 - x })
                * (if cy > 0.0 { y } else { 1.0 - y })
                * (if cz > 0.0 { z } else { 1.0 - z });
        }
        v
    }

    /// Components of the samples of one sign on an n^3 grid of the cube (6-connected), as a
    /// label per corner (None if the corner has the other sign).
    fn sampled_corner_labels(g: &[f64; 8], n: usize, neg: bool) -> [Option<usize>; 8] {
        let idx = |i: usize, j: usize, k: usize| i + n * (j + n * k);
        let h = 1.0 / (n - 1) as f64;
        let inside: Vec<bool> = (0..n * n * n)
            .map(|p| {
                let (i, j, k) = (p % n, (p / n) % n, p / (n * n));
                let v = tri(g, i as f64 * h, j as f64 * h, k as f64 * h);
                if neg { v < 0.0 } else { v > 0.0 }
            })
            .collect();
        let mut label = vec![usize::MAX; n * n * n];
        let mut next = 0;
        for start in 0..n * n * n {
            if !inside[start] || label[start] != usize::MAX {
                continue;
            }
            let mut stack = vec![start];
            label[start] = next;
            while let Some(p) = stack.pop() {
                let (i, j, k) = (p % n, (p / n) % n, p / (n * n));
                let mut visit = |q: usize| {
                    if inside[q] && label[q] == usize::MAX {
                        label[q] = next;
                        stack.push(q);
                    }
                };
                if i > 0 {
                    visit(idx(i - 1, j, k));
                }
                if i + 1 < n {
                    visit(idx(i + 1, j, k));
                }
                if j > 0 {
                    visit(idx(i, j - 1, k));
                }
                if j + 1 < n {
                    visit(idx(i, j + 1, k));
                }
                if k > 0 {
                    visit(idx(i, j, k - 1));
                }
                if k + 1 < n {
                    visit(idx(i, j, k + 1));
                }
            }
            next += 1;
        }
        std::array::from_fn(|c| {
            let (i, j, k) = (
                (c & 1) * (n - 1),
                ((c >> 1) & 1) * (n - 1),
                (c >> 2) * (n - 1),
            );
            let l = label[idx(i, j, k)];
            (l != usize::MAX).then_some(l)
        })
    }

    /// Corner components of one sign from the faces (as the scan joins them) and the
    /// interior joins.
    fn joined_corner_labels(g: &[f64; 8], neg: bool) -> [Option<usize>; 8] {
        let mut groups = face_groups(g).map(usize::from);
        for j in interior_joins(g) {
            let (ga, gb) = (groups[j.a as usize], groups[j.b as usize]);
            let (lo, hi) = (ga.min(gb), ga.max(gb));
            groups
                .iter_mut()
                .filter(|x| **x == hi)
                .for_each(|x| *x = lo);
        }
        let of = |c: usize| if neg { g[c] < 0.0 } else { g[c] > 0.0 };
        std::array::from_fn(|c| of(c).then_some(groups[c]))
    }

    /// Same partition of the corners (labels up to renaming).
    fn same_partition(a: &[Option<usize>; 8], b: &[Option<usize>; 8]) -> bool {
        (0..8).all(|i| {
            (0..8).all(|j| match (a[i], a[j], b[i], b[j]) {
                (Some(x), Some(y), Some(u), Some(v)) => (x == y) == (u == v),
                (None, _, None, _) | (_, None, _, None) => true,
                _ => false,
            })
        })
    }

    /// The marching cubes 33 tunnel (case 4.1.2): two opposite corners inside, joined only
    /// through the interior; and its separated variant (4.1.1).
    #[test]
    fn opposite_corners_join_through_a_tunnel_only_when_it_exists() {
        let mut g = [1.0; 8];
        g[0] = -1.0;
        g[7] = -1.0;
        // Far below the iso value at both corners: the tunnel exists.
        let deep = {
            let mut h = g;
            h[0] = -10.0;
            h[7] = -10.0;
            h
        };
        let joins: Vec<_> = interior_joins(&deep).map(|j| (j.a, j.b)).collect();
        assert_eq!(joins, vec![(0, 7)]);
        let via = interior_joins(&deep).next().unwrap().via;
        assert!(tri(&deep, via[0], via[1], via[2]) < 0.0, "{via:?}");
        assert_eq!(interior_joins(&g).count(), 0);
        assert!(tri(&deep, 0.5, 0.5, 0.5) < 0.0 && tri(&g, 0.5, 0.5, 0.5) > 0.0);
    }

    /// Against a 33^3 flood fill of random cells biased towards the ambiguous cases: the same
    /// corner components wherever the sampled answer is clear-cut (a tunnel thinner than the
    /// sampling can be missed by the flood fill, never invented by it).
    #[test]
    fn corner_components_match_a_fine_flood_fill() {
        let mut r = SplitMix64::new(3);
        let (mut checked, mut tunnels) = (0, 0);
        for _ in 0..4000 {
            let mut g = [0.0; 8];
            // Checkerboard-ish signs with random magnitudes: many ambiguous cells.
            let pattern = r.next_u64();
            for (c, v) in g.iter_mut().enumerate() {
                let parity = ((c & 1) + ((c >> 1) & 1) + (c >> 2)) & 1;
                let flip = (pattern >> c) & 3 == 0;
                let s = if (parity == 1) ^ flip { 1.0 } else { -1.0 };
                *v = s * (0.05 + r.next_f64() * 4.0);
            }
            tunnels += interior_joins(&g).count();
            for neg in [true, false] {
                let fine = sampled_corner_labels(&g, 33, neg);
                let exact = joined_corner_labels(&g, neg);
                if same_partition(&fine, &exact) {
                    checked += 1;
                    continue;
                }
                // Disagreement only where the flood fill misses a thin join: the exact
                // partition is coarser, and a finer fill agrees.
                let finer = sampled_corner_labels(&g, 129, neg);
                assert!(same_partition(&finer, &exact), "{g:?} neg {neg}");
                checked += 1;
            }
        }
        assert_eq!(checked, 8000);
        assert!(tunnels > 20, "{tunnels}");
    }
}
