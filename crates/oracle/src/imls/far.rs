//! Far-field sign cache (ours): the sign of the point-set surface where no kernel reaches, from a
//! flood fill instead of one winding number per query.
//!
//! A grid of cells of about half the largest kernel radius covers the bounding sphere's box.
//! A cell is *blocked* when some point's kernel support (the ball of radius `R_i` about
//! `p_i`) meets the cell's box; elsewhere, in the *clear* cells, the kernel weight is exactly
//! 0 and the value is the far field `±max_radius`. The clear cells are split into
//! 6-connected components (typically: the outside, and the inside of each closed surface),
//! and each component is signed once, by the winding number at a few of its cells and at up
//! to [`BORDER_SAMPLES`] of its border cells (next to a blocked cell), spread in
//! breadth-first order; a component whose samples disagree (an open or leaky point set: a
//! hole in the data joins the inside to the outside, and its border cells lie on both
//! sides of the surface) keeps sign 0, "unknown", and its queries are evaluated one by one
//! as before.
//!
//! Invariants: deterministic (a sequential flood fill; signs evaluated independently);
//! [`FarCache::get`] returns ±1 only in a clear cell of a unanimously signed component, or
//! in a blocked cell whose clear neighbours (the 26 around it, all within 1.8 kernel radii,
//! closer than the shell of supports around a well-sampled surface is thick) are all
//! signed alike. Callers ask only for points with (almost) zero kernel weight, i.e. outside
//! that shell, where the neighbours' side is the point's side.

use glam::DVec3;
use rayon::prelude::*;

/// Most cells per axis (`128³` cells: 2 MB of signs).
const MAX_CELLS: usize = 128;
/// Winding-number samples per component, spread over its cells...
const SAMPLES: usize = 5;
/// ...and over its border cells (next to a blocked cell). Without them, a component that a
/// hole in the data joins to the inside was signed by 5 cells all outside (the fandisk
/// missing-patch scan: the inside meshed as a second wall).
const BORDER_SAMPLES: usize = 1024;
/// Stored for a blocked cell.
const BLOCKED: i8 = 2;

#[derive(Clone, Debug, Default)]
pub(crate) struct FarCache {
    lo: DVec3,
    inv: f64,
    n: usize,
    /// Per cell (x fastest): −1 inside, +1 outside, 0 unknown, [`BLOCKED`].
    sign: Vec<i8>,
    /// Clear components found (for tests and statistics).
    pub components: usize,
}

impl FarCache {
    /// Build over the cube `[center − half, center + half]³` for points `p_i` with kernel
    /// radii `r_i` (largest `r_max`); `sign_at(x)` (±1) is the far-field sign at `x`, called
    /// at a few cell centers per component.
    pub fn build(
        center: DVec3,
        half: f64,
        points: &[DVec3],
        radius: &[f64],
        r_max: f64,
        sign_at: impl Fn(DVec3) -> i8 + Sync,
    ) -> FarCache {
        let n = ((2.0 * half / (0.5 * r_max)).ceil()).clamp(4.0, MAX_CELLS as f64) as usize;
        let cell = 2.0 * half / n as f64;
        if !(cell > 0.0 && cell.is_finite()) || points.len() != radius.len() {
            return FarCache::default();
        }
        let lo = center - DVec3::splat(half);
        let inv = 1.0 / cell;
        let blocked = blocked_cells(lo, inv, cell, n, half, points, radius);
        let is_blocked = |c: usize| blocked[c / 64] >> (c % 64) & 1 == 1;
        let (label, samples, comps) = clear_components(n, is_blocked);
        let center_of = |c: usize| {
            let (i, j, k) = (c % n, (c / n) % n, c / (n * n));
            lo + cell * DVec3::new(i as f64 + 0.5, j as f64 + 0.5, k as f64 + 0.5)
        };
        let signs: Vec<i8> = samples
            .par_iter()
            .map(|&(_, c)| sign_at(center_of(c)))
            .collect();
        // A component's sign: its samples' common sign, or 0 if they disagree.
        let mut comp_sign = vec![0i8; comps as usize];
        let mut first = vec![true; comps as usize];
        for (&(comp, _), &s) in samples.iter().zip(&signs) {
            let k = comp as usize;
            if first[k] {
                comp_sign[k] = s;
                first[k] = false;
            } else if comp_sign[k] != s {
                comp_sign[k] = 0;
            }
        }
        let sign = label
            .iter()
            .map(|&l| {
                if l == NONE {
                    BLOCKED
                } else {
                    comp_sign[l as usize]
                }
            })
            .collect();
        FarCache {
            lo,
            inv,
            n,
            sign,
            components: comps as usize,
        }
    }

    /// The far-field sign at `x`, a point with (almost) zero kernel weight (0 if unknown).
    pub fn get(&self, x: DVec3) -> i8 {
        let n = self.n;
        if self.sign.is_empty() {
            return 0;
        }
        let g = (x - self.lo) * self.inv;
        if !(g.min_element() >= 0.0 && g.max_element() < n as f64) {
            return 0;
        }
        let (i, j, k) = (g.x as usize, g.y as usize, g.z as usize);
        let s = self.sign[(k * n + j) * n + i];
        if s != BLOCKED {
            return s;
        }
        // A blocked cell: its clear neighbours, if all signed alike.
        let mut out = 0i8;
        for kk in k.saturating_sub(1)..=(k + 1).min(n - 1) {
            for jj in j.saturating_sub(1)..=(j + 1).min(n - 1) {
                for ii in i.saturating_sub(1)..=(i + 1).min(n - 1) {
                    match self.sign[(kk * n + jj) * n + ii] {
                        BLOCKED => {}
                        0 => return 0,
                        s if out == 0 => out = s,
                        s if s != out => return 0,
                        _ => {}
                    }
                }
            }
        }
        out
    }
}

/// Cells of a clear-cell label array not in any clear component.
const NONE: u32 = u32::MAX;

/// The blocked cells of the `n³` grid with corner `lo` and cell size `cell` (`inv = 1 /
/// cell`), as a bit set (x fastest): every cell whose box meets a support ball (a tiny relative
/// margin covers rounding).
fn blocked_cells(
    lo: DVec3,
    inv: f64,
    cell: f64,
    n: usize,
    half: f64,
    points: &[DVec3],
    radius: &[f64],
) -> Vec<u64> {
    let words = (n * n * n).div_ceil(64);
    points
        .par_iter()
        .zip(radius.par_iter())
        .fold(
            || vec![0u64; words],
            |mut bits, (&p, &r)| {
                let r = r * (1.0 + 1e-9) + 1e-12 * half;
                let range = |axis: usize| {
                    let a = ((p[axis] - r - lo[axis]) * inv).floor().max(0.0);
                    let b = ((p[axis] + r - lo[axis]) * inv).floor().min((n - 1) as f64);
                    (a as usize, b as usize)
                };
                let ((i0, i1), (j0, j1), (k0, k1)) = (range(0), range(1), range(2));
                if i0 > i1 || j0 > j1 || k0 > k1 {
                    return bits;
                }
                // Squared distance from p to the slab of cell index c along `axis`.
                let gap = |axis: usize, c: usize| {
                    let a = lo[axis] + c as f64 * cell;
                    let d = (a - p[axis]).max(p[axis] - (a + cell)).max(0.0);
                    d * d
                };
                for k in k0..=k1 {
                    let dz = gap(2, k);
                    for j in j0..=j1 {
                        let dyz = dz + gap(1, j);
                        if dyz >= r * r {
                            continue;
                        }
                        for i in i0..=i1 {
                            if dyz + gap(0, i) < r * r {
                                let c = (k * n + j) * n + i;
                                bits[c / 64] |= 1 << (c % 64);
                            }
                        }
                    }
                }
                bits
            },
        )
        .reduce(
            || vec![0u64; words],
            |mut a, b| {
                for (x, y) in a.iter_mut().zip(b) {
                    *x |= y;
                }
                a
            },
        )
}

/// The 6-neighbours of cell `c` of the `n³` grid (x fastest) that are in the grid.
fn neighbours6(c: usize, n: usize) -> impl Iterator<Item = usize> {
    crate::grid::neighbours6(c, [n; 3])
}

/// The 6-connected components of the clear cells of the `n³` grid (breadth-first, in index
/// order): the label of each cell ([`NONE`] if blocked), up to [`SAMPLES`] cells of each
/// component and up to [`BORDER_SAMPLES`] of its border cells, spread in breadth-first order
/// (with their component), and the component count.
fn clear_components(
    n: usize,
    is_blocked: impl Fn(usize) -> bool,
) -> (Vec<u32>, Vec<(u32, usize)>, u32) {
    let ncell = n * n * n;
    // 6-connected components of the clear cells (breadth-first, in index order).
    let mut label = vec![NONE; ncell];
    let mut samples: Vec<(u32, usize)> = Vec::new();
    let mut queue: Vec<usize> = Vec::new();
    let mut comps = 0u32;
    for seed in 0..ncell {
        if label[seed] != NONE || is_blocked(seed) {
            continue;
        }
        queue.clear();
        queue.push(seed);
        label[seed] = comps;
        let mut head = 0;
        while head < queue.len() {
            let c = queue[head];
            head += 1;
            for d in neighbours6(c, n) {
                if label[d] == NONE && !is_blocked(d) {
                    label[d] = comps;
                    queue.push(d);
                }
            }
        }
        let m = queue.len();
        let take = SAMPLES.min(m);
        for s in 0..take {
            samples.push((comps, queue[s * m / take + (m / take) / 2]));
        }
        // Its cells next to a blocked cell (the sides of the shell of supports), at most
        // BORDER_SAMPLES of them spread in breadth-first order: a component that reaches
        // both sides of the surface (through a hole in the data) has border cells on both.
        let border: Vec<usize> = queue
            .iter()
            .copied()
            .filter(|&c| neighbours6(c, n).any(&is_blocked))
            .collect();
        let b = border.len();
        let take = BORDER_SAMPLES.min(b);
        for s in 0..take {
            samples.push((comps, border[s * b / take + (b / take) / 2]));
        }
        comps += 1;
    }
    (label, samples, comps)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::roots::SplitMix64;

    /// Points on two concentric spheres (radii 1 and 2) with their kernel balls: three clear
    /// components (inside the small sphere, between them, outside), each signed by the
    /// callback, and every query with zero weight gets its region's sign or 0.
    #[test]
    fn components_are_signed_by_region() {
        let mut rng = SplitMix64(7);
        let mut pts = Vec::new();
        for &rad in &[1.0, 2.0] {
            for _ in 0..(6000.0 * rad * rad) as usize {
                pts.push(rng.unit_vector() * rad);
            }
        }
        let r = vec![0.15; pts.len()];
        let region = |x: DVec3| {
            let l = x.length();
            if l < 1.0 {
                -1
            } else if l < 2.0 {
                1
            } else {
                -1
            }
        };
        let fc = FarCache::build(DVec3::ZERO, 2.5, &pts, &r, 0.15, region);
        assert_eq!(fc.components, 3);
        let (mut known, mut total) = (0, 0);
        for _ in 0..20000 {
            let x = rng.unit_vector() * 2.4 * rng.next_f64().cbrt();
            // Surely zero weight: farther than the radius from both spheres.
            let weight0 = [1.0, 2.0]
                .iter()
                .all(|&rad| (x.length() - rad).abs() >= 0.15);
            let s = fc.get(x);
            if weight0 {
                total += 1;
                if s != 0 {
                    known += 1;
                    assert_eq!(s, region(x), "{x}");
                }
            }
        }
        assert!(known as f64 > 0.9 * total as f64, "{known} of {total}");
        // Outside the grid: unknown.
        assert_eq!(fc.get(DVec3::splat(3.0)), 0);
    }

    /// A sphere of points with a hole: the inside and the outside are one clear component
    /// through the hole, the inside a tiny part of it. Its border cells on the inside sign it
    /// as mixed, so it stays unknown (5 cells spread over the whole component all fall
    /// outside: it was signed "outside", inside included).
    #[test]
    fn a_component_leaking_through_a_hole_stays_unknown() {
        let mut rng = SplitMix64(3);
        let hole = DVec3::new(0.0, 0.0, 0.5);
        let pts: Vec<DVec3> = (0..20_000)
            .map(|_| rng.unit_vector() * 0.5)
            .filter(|p| (*p - hole).length() > 0.3)
            .collect();
        let r = vec![0.04; pts.len()];
        let region = |x: DVec3| if x.length() < 0.5 { -1 } else { 1 };
        let fc = FarCache::build(DVec3::ZERO, 2.5, &pts, &r, 0.04, region);
        assert_eq!(fc.components, 1);
        assert_eq!(fc.get(DVec3::ZERO), 0, "inside");
        assert_eq!(fc.get(DVec3::new(2.0, 0.0, 0.0)), 0, "outside");
        // Closed (no hole): two components, each signed.
        let closed: Vec<DVec3> = (0..20_000).map(|_| rng.unit_vector() * 0.5).collect();
        let r = vec![0.04; closed.len()];
        let fc = FarCache::build(DVec3::ZERO, 2.5, &closed, &r, 0.04, region);
        assert_eq!(fc.components, 2);
        assert_eq!(fc.get(DVec3::ZERO), -1);
        assert_eq!(fc.get(DVec3::new(2.0, 0.0, 0.0)), 1);
    }

    /// A component whose samples disagree stays unknown.
    #[test]
    fn disagreeing_samples_leave_the_sign_unknown() {
        let pts = vec![DVec3::ZERO];
        let fc = FarCache::build(DVec3::ZERO, 1.0, &pts, &[0.1], 0.1, |x| {
            if x.x < 0.0 { -1 } else { 1 }
        });
        assert_eq!(fc.components, 1);
        assert_eq!(fc.get(DVec3::new(0.5, 0.5, 0.5)), 0);
        assert_eq!(fc.get(DVec3::new(-0.5, 0.5, 0.5)), 0);
    }
}
