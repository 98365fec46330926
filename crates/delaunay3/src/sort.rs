//! Deterministic spatial sorting: BRIO (Amenta, Choi & Rote) rounds sorted along the
//! Hilbert curve by grid keys ([`crate::hilbert`]) for bulk insertions, and the Hilbert
//! median sort (Delage & Devillers, as in CGAL's `Hilbert_sort_median_3`) for the few points
//! held before a triangulation is 3D.

use glam::DVec3;

use crate::hilbert;

/// A small deterministic PRNG (64-bit LCG with output mixing). Works from any state.
#[derive(Clone, Debug, Default)]
pub(crate) struct Rng(pub u64);

impl Rng {
    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let mut z = self.0;
        z = (z ^ (z >> 31)).wrapping_mul(0xbf58476d1ce4e5b9);
        z ^ (z >> 29)
    }
    /// Uniform in `0..n` (n > 0), by multiply-shift.
    #[inline]
    pub fn below(&mut self, n: usize) -> usize {
        (((self.next_u64() >> 32) * n as u64) >> 32) as usize
    }
}

/// A point with its index, sorted in place of the index: the comparisons of a median split
/// read contiguous memory instead of gathering `pts[i]` at random.
///
/// The permutation is the same as sorting the bare `u32` indices with the same comparator:
/// `select_nth_unstable_by` decides every move from comparison outcomes only (its partition
/// scheme is chosen by element size, the same for every size up to 96 bytes), so equal
/// outcomes give equal moves, ties included. `sort_matches_index_sort` checks it.
#[derive(Clone, Copy, Debug)]
struct Rec {
    p: [f64; 3],
    i: u32,
}

/// Splits `recs` at its median along `axis` (ascending if `up`), returns the median position.
fn split(recs: &mut [Rec], axis: usize, up: bool) -> usize {
    let mid = recs.len() / 2;
    if recs.is_empty() {
        return 0;
    }
    recs.select_nth_unstable_by(mid, |a, b| {
        let o = a.p[axis]
            .partial_cmp(&b.p[axis])
            .unwrap_or(std::cmp::Ordering::Equal);
        if up { o } else { o.reverse() }
    });
    mid
}

/// Hilbert median sort of `recs`. `x` is the current first axis and `up[k]` the direction
/// of local axis `k` (x, y, z = x, x+1, x+2 mod 3).
fn hilbert(recs: &mut [Rec], x: usize, up: [bool; 3]) {
    if recs.len() <= 1 {
        return;
    }
    let (y, z) = ((x + 1) % 3, (x + 2) % 3);
    let [ux, uy, uz] = up;
    let n = recs.len();
    let m4 = split(recs, x, ux);
    let m2 = split(&mut recs[..m4], y, uy);
    let m1 = split(&mut recs[..m2], z, uz);
    let m3 = m2 + split(&mut recs[m2..m4], z, !uz);
    let m6 = m4 + split(&mut recs[m4..n], y, !uy);
    let m5 = m4 + split(&mut recs[m4..m6], z, uz);
    let m7 = m6 + split(&mut recs[m6..n], z, !uz);
    hilbert(&mut recs[..m1], z, [uz, ux, uy]);
    hilbert(&mut recs[m1..m2], y, [uy, uz, ux]);
    hilbert(&mut recs[m2..m3], y, [uy, uz, ux]);
    hilbert(&mut recs[m3..m4], x, [ux, !uy, !uz]);
    hilbert(&mut recs[m4..m5], x, [ux, !uy, !uz]);
    hilbert(&mut recs[m5..m6], y, [!uy, uz, !ux]);
    hilbert(&mut recs[m6..m7], y, [!uy, uz, !ux]);
    hilbert(&mut recs[m7..n], z, [!uz, !ux, uy]);
}

/// The records of `idx` (indices into `pts`), in the order of `idx`.
fn records(pts: &[DVec3], idx: &[u32]) -> Vec<Rec> {
    idx.iter()
        .map(|&i| Rec {
            p: pts[i as usize].to_array(),
            i,
        })
        .collect()
}

/// Hilbert-sorts `idx` in place (no randomization).
pub(crate) fn hilbert_sort(pts: &[DVec3], idx: &mut [u32]) {
    let mut recs = records(pts, idx);
    hilbert(&mut recs, 0, [true, true, true]);
    for (i, r) in idx.iter_mut().zip(&recs) {
        *i = r.i;
    }
}

/// BRIO order of `0..pts.len()`: a seeded shuffle, then rounds of geometrically growing size
/// (ratio 1/4, first round at most 1024 points), each round sorted by Hilbert key (ties in
/// shuffled order). Deterministic. Returns each index with its point (read in this order:
/// contiguous, not gathered).
pub(crate) fn brio_order(pts: &[DVec3], seed: u64) -> Vec<(DVec3, u32)> {
    let mut idx: Vec<u32> = (0..pts.len() as u32).collect();
    let mut rng = Rng(seed);
    for i in (1..idx.len()).rev() {
        let j = rng.below(i + 1);
        idx.swap(i, j);
    }
    let grid = hilbert::Grid::new(pts);
    // (key, shuffled position): distinct, so an unstable sort is deterministic.
    let keys = grid.keys(idx.iter().map(|&i| pts[i as usize]));
    let mut keyed: Vec<(u64, u32)> = keys.into_iter().zip(0..).collect();
    let mut end = keyed.len();
    while end > 0 {
        let start = if end > 1024 { end / 4 } else { 0 };
        keyed[start..end].sort_unstable();
        end = start;
    }
    keyed
        .iter()
        .map(|&(_, k)| {
            let i = idx[k as usize];
            (pts[i as usize], i)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn brio_is_a_permutation_and_local() {
        let mut rng = Rng(7);
        let pts: Vec<DVec3> = (0..5000)
            .map(|_| {
                DVec3::new(
                    rng.below(1000) as f64,
                    rng.below(1000) as f64,
                    rng.below(1000) as f64,
                )
            })
            .collect();
        let ord: Vec<u32> = brio_order(&pts, 1).iter().map(|r| r.1).collect();
        let mut s = ord.clone();
        s.sort_unstable();
        assert_eq!(s, (0..5000).collect::<Vec<u32>>());
        assert!(
            brio_order(&pts, 1)
                .iter()
                .map(|r| r.1)
                .eq(ord.iter().copied())
        );
        // The last round (3750 points) is Hilbert-ordered: consecutive points are close.
        let tail = &ord[1250..];
        let mean: f64 = tail
            .windows(2)
            .map(|w| pts[w[0] as usize].distance(pts[w[1] as usize]))
            .sum::<f64>()
            / (tail.len() - 1) as f64;
        assert!(mean < 150.0, "mean step {mean}");
    }

    /// The index-based Hilbert median sort that [`Rec`] replaced (the reference order).
    fn index_hilbert(pts: &[DVec3], idx: &mut [u32], x: usize, up: [bool; 3]) {
        if idx.len() <= 1 {
            return;
        }
        let split = |idx: &mut [u32], axis: usize, up: bool| {
            let mid = idx.len() / 2;
            if idx.is_empty() {
                return 0;
            }
            idx.select_nth_unstable_by(mid, |&a, &b| {
                let (ca, cb) = (pts[a as usize][axis], pts[b as usize][axis]);
                let o = ca.partial_cmp(&cb).unwrap_or(std::cmp::Ordering::Equal);
                if up { o } else { o.reverse() }
            });
            mid
        };
        let (y, z) = ((x + 1) % 3, (x + 2) % 3);
        let [ux, uy, uz] = up;
        let n = idx.len();
        let m4 = split(idx, x, ux);
        let m2 = split(&mut idx[..m4], y, uy);
        let m1 = split(&mut idx[..m2], z, uz);
        let m3 = m2 + split(&mut idx[m2..m4], z, !uz);
        let m6 = m4 + split(&mut idx[m4..n], y, !uy);
        let m5 = m4 + split(&mut idx[m4..m6], z, uz);
        let m7 = m6 + split(&mut idx[m6..n], z, !uz);
        index_hilbert(pts, &mut idx[..m1], z, [uz, ux, uy]);
        index_hilbert(pts, &mut idx[m1..m2], y, [uy, uz, ux]);
        index_hilbert(pts, &mut idx[m2..m3], y, [uy, uz, ux]);
        index_hilbert(pts, &mut idx[m3..m4], x, [ux, !uy, !uz]);
        index_hilbert(pts, &mut idx[m4..m5], x, [ux, !uy, !uz]);
        index_hilbert(pts, &mut idx[m5..m6], y, [!uy, uz, !ux]);
        index_hilbert(pts, &mut idx[m6..m7], y, [!uy, uz, !ux]);
        index_hilbert(pts, &mut idx[m7..n], z, [!uz, !ux, uy]);
    }

    #[test]
    fn sort_matches_index_sort() {
        // Ties on every axis (few distinct values), duplicates, and distinct values.
        let mut rng = Rng(3);
        for (n, levels) in [(50_000, 1u64 << 40), (30_000, 5), (20_000, 2), (3000, 1)] {
            let pts: Vec<DVec3> = (0..n)
                .map(|_| {
                    let mut c = || (rng.next_u64() % levels) as f64 * 0.5;
                    DVec3::new(c(), c(), c())
                })
                .collect();
            let mut idx: Vec<u32> = (0..n as u32).rev().collect();
            let mut want = idx.clone();
            index_hilbert(&pts, &mut want, 0, [true, true, true]);
            hilbert_sort(&pts, &mut idx);
            assert_eq!(idx, want, "{n} points, {levels} levels");
        }
    }
}
