//! Uniform grid (ours) over the points for the fixed-radius kernel sums (cache-friendly, no
//! allocation per query): cells of side ≥ the largest support radius, points stored
//! contiguously in cell order with their normal and squared support radius.

use glam::DVec3;

/// One point as the kernel sum needs it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Item {
    pub p: DVec3,
    pub n: DVec3,
    /// Squared support radius.
    pub r2: f64,
    /// `1 / b²`, `b` the data-support band radius (0: no band, every point trusted).
    pub b2inv: f64,
}

#[derive(Clone, Debug)]
pub(crate) struct Grid {
    lo: DVec3,
    inv: f64,
    dims: [usize; 3],
    /// `start[c]..start[c + 1]` are the items of cell `c` (x fastest).
    start: Vec<u32>,
    items: Vec<Item>,
    /// The items' coordinates and squared support radii as columns (same order), for
    /// [`Grid::gather`]'s test on several items at once.
    keys: Keys,
}

/// Columns of the items' `p.x`, `p.y`, `p.z` and `r2`.
#[derive(Clone, Debug, Default)]
struct Keys {
    x: Vec<f64>,
    y: Vec<f64>,
    z: Vec<f64>,
    r2: Vec<f64>,
}

/// Items whose support test [`Grid::gather`] runs at once (two vectors of four).
const LANES: usize = 8;

impl Grid {
    /// `cell` ≥ every support radius. The cell size grows if the grid would have far more
    /// cells than points (sparse, spread-out input).
    pub fn new(
        points: &[DVec3],
        normals: &[DVec3],
        radius: &[f64],
        band: Option<&[f64]>,
        cell: f64,
    ) -> Self {
        let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
        for p in points {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        let mut cell = cell.max(1e-300);
        let max_cells = 4 * points.len() + 4096;
        let dims = loop {
            let d = ((hi - lo) / cell).floor() + DVec3::ONE;
            if d.x * d.y * d.z <= max_cells as f64 {
                break [d.x as usize, d.y as usize, d.z as usize];
            }
            cell *= 1.5;
        };
        let inv = 1.0 / cell;
        let mut grid = Grid {
            lo,
            inv,
            dims,
            start: Vec::new(),
            items: Vec::new(),
            keys: Keys::default(),
        };
        let ncell = dims[0] * dims[1] * dims[2];
        let cid: Vec<usize> = points.iter().map(|p| grid.cell_index(*p)).collect();
        let mut start = vec![0u32; ncell + 1];
        for &c in &cid {
            start[c + 1] += 1;
        }
        for c in 0..ncell {
            start[c + 1] += start[c];
        }
        let mut fill: Vec<u32> = start[..ncell].to_vec();
        let dummy = Item {
            p: DVec3::ZERO,
            n: DVec3::ZERO,
            r2: 0.0,
            b2inv: 0.0,
        };
        let mut items = vec![dummy; points.len()];
        for (i, &c) in cid.iter().enumerate() {
            items[fill[c] as usize] = Item {
                p: points[i],
                n: normals[i],
                r2: radius[i] * radius[i],
                b2inv: band.map_or(0.0, |b| 1.0 / (b[i] * b[i])),
            };
            fill[c] += 1;
        }
        grid.keys = Keys {
            x: items.iter().map(|it| it.p.x).collect(),
            y: items.iter().map(|it| it.p.y).collect(),
            z: items.iter().map(|it| it.p.z).collect(),
            r2: items.iter().map(|it| it.r2).collect(),
        };
        grid.start = start;
        grid.items = items;
        grid
    }

    /// The cell of `v` along `axis`: `⌊(v − lo) / cell⌋` clamped to the grid (0 for NaN).
    /// Truncation is the floor on the positive values it is applied to (`f64::floor` is a
    /// library call on the baseline x86-64 target: about 40 instructions).
    #[inline(always)]
    fn coord(&self, v: f64, axis: usize) -> usize {
        let c = (v - self.lo[axis]) * self.inv;
        if c <= 0.0 {
            0
        } else {
            (c as usize).min(self.dims[axis] - 1)
        }
    }

    fn cell_index(&self, p: DVec3) -> usize {
        let (i, j, k) = (self.coord(p.x, 0), self.coord(p.y, 1), self.coord(p.z, 2));
        (k * self.dims[1] + j) * self.dims[0] + i
    }

    /// Visit every item within `r` of `x` (and possibly a few more: callers test `r2`).
    #[inline]
    pub fn for_each_near<'a>(&'a self, x: DVec3, r: f64, mut f: impl FnMut(&'a Item)) {
        self.for_each_row(x, r, |row| {
            for it in row {
                f(it);
            }
        });
    }

    /// Append to `buf`, in visiting order, every item whose support contains `x` (`|x −
    /// p|² < r2` is not false: the test of `add`, with the same operations in the same
    /// order, so the same items); `r` bounds the support radii. `kept` counts them all; past
    /// the buffer's end they are not stored (the last slot is overwritten).
    ///
    /// The test runs on [`LANES`] items at a time from the columns of [`Keys`] (vector
    /// compares giving a bit mask), and only the items kept are written. Item by item, each
    /// test loaded a 64-byte item and cost about 22 instructions: on the 50k-point bunny
    /// scan a gather scans 239 items and keeps 22 on average, and the gathers were 32% of the
    /// whole command's instructions (valgrind, one thread); with the mask, 25%.
    #[inline]
    pub fn gather<'a>(&'a self, x: DVec3, r: f64, buf: &mut [&'a Item], kept: &mut usize) {
        let last = buf.len() - 1;
        let k = &self.keys;
        self.for_each_range(x, r, |s, e| {
            let mut n = *kept;
            let mut put = |i: usize| {
                buf[n.min(last)] = &self.items[i];
                n += 1;
            };
            let mut i = s;
            while i + LANES <= e {
                let at = |v: &'a [f64]| -> &'a [f64; LANES] {
                    v[i..i + LANES].try_into().expect("LANES entries")
                };
                let mut bits = supported_mask(x, [at(&k.x), at(&k.y), at(&k.z)], at(&k.r2));
                while bits != 0 {
                    put(i + bits.trailing_zeros() as usize);
                    bits &= bits - 1;
                }
                i += LANES;
            }
            for j in i..e {
                if supports(x, DVec3::new(k.x[j], k.y[j], k.z[j]), k.r2[j]) {
                    put(j);
                }
            }
            *kept = n;
        });
    }

    /// The rows of items (contiguous runs of cells along x) of the grid cells that meet the
    /// cube of half-side `r` about `x`.
    #[inline(always)]
    fn for_each_row<'a>(&'a self, x: DVec3, r: f64, mut f: impl FnMut(&'a [Item])) {
        self.for_each_range(x, r, |s, e| f(&self.items[s..e]));
    }

    /// [`Grid::for_each_row`] as index ranges of `items`.
    #[inline(always)]
    fn for_each_range(&self, x: DVec3, r: f64, mut f: impl FnMut(usize, usize)) {
        let a = x - DVec3::splat(r);
        let b = x + DVec3::splat(r);
        let hi = self.lo
            + DVec3::new(
                self.dims[0] as f64,
                self.dims[1] as f64,
                self.dims[2] as f64,
            ) / self.inv;
        if b.cmplt(self.lo).any() || a.cmpgt(hi).any() {
            return;
        }
        let (i0, i1) = (self.coord(a.x, 0), self.coord(b.x, 0));
        let (j0, j1) = (self.coord(a.y, 1), self.coord(b.y, 1));
        let (k0, k1) = (self.coord(a.z, 2), self.coord(b.z, 2));
        for k in k0..=k1 {
            for j in j0..=j1 {
                let row = (k * self.dims[1] + j) * self.dims[0];
                // Cells i0..=i1 of a row are contiguous in `items`.
                let s = self.start[row + i0] as usize;
                let e = self.start[row + i1 + 1] as usize;
                f(s, e);
            }
        }
    }
}

/// Whether the support of the point `p` of squared radius `r2` contains `x`:
/// `!(|x − p|² >= r2)` with `|x − p|²` computed as `(x − p).length_squared()` is (the test
/// of `add`, which keeps a NaN distance).
#[allow(clippy::neg_cmp_op_on_partial_ord)]
#[inline(always)]
fn supports(x: DVec3, p: DVec3, r2: f64) -> bool {
    !((x - p).length_squared() >= r2)
}

/// [`supports`] on [`LANES`] items given as columns (`p` by coordinate): bit `j` set when
/// item `j`'s support contains `x`. Four lanes at a time in `wide`'s vectors (two SSE2
/// registers on the baseline x86-64 target): `(dx·dx + dy·dy) + dz·dz` and the compare, the
/// IEEE operations of [`supports`] in the same order, so the same bits.
#[inline(always)]
fn supported_mask(x: DVec3, p: [&[f64; LANES]; 3], r2: &[f64; LANES]) -> u32 {
    use wide::{CmpGe, f64x4};
    let c = [f64x4::splat(x.x), f64x4::splat(x.y), f64x4::splat(x.z)];
    let mut bits = 0u32;
    for j in [0, 4] {
        let q = |v: &[f64; LANES]| f64x4::new([v[j], v[j + 1], v[j + 2], v[j + 3]]);
        let (dx, dy, dz) = (c[0] - q(p[0]), c[1] - q(p[1]), c[2] - q(p[2]));
        let d2 = dx * dx + dy * dy + dz * dz;
        // `!(d2 >= r2)`: the lanes whose `d2 >= r2` is false (a NaN distance included).
        let far = d2.cmp_ge(q(r2)).move_mask() as u32;
        bits |= (!far & 0xF) << j;
    }
    bits
}

/// The points split by support radius into grids of fitting cell sizes (ours): with a
/// non-uniform density, the few large supports of the sparse regions do not make every query
/// of the dense regions scan large cells. Level 0 holds the radii up to `split`, level 1 the
/// others (if any). One level (`split` ≥ every radius) is exactly the single grid.
#[derive(Clone, Debug)]
pub(crate) struct Levels {
    /// Each level's grid and its largest radius (the query radius).
    levels: Vec<(Grid, f64)>,
}

impl Levels {
    pub fn new(
        points: &[DVec3],
        normals: &[DVec3],
        radius: &[f64],
        band: Option<&[f64]>,
        split: f64,
    ) -> Self {
        let max = radius.iter().copied().fold(0.0, f64::max);
        if max <= split {
            let g = Grid::new(points, normals, radius, band, max);
            return Levels {
                levels: vec![(g, max)],
            };
        }
        let mut levels = Vec::new();
        for big in [false, true] {
            let idx: Vec<usize> = (0..points.len())
                .filter(|&i| (radius[i] > split) == big)
                .collect();
            if idx.is_empty() {
                continue;
            }
            let pick = |v: &[f64]| idx.iter().map(|&i| v[i]).collect::<Vec<f64>>();
            let p: Vec<DVec3> = idx.iter().map(|&i| points[i]).collect();
            let n: Vec<DVec3> = idx.iter().map(|&i| normals[i]).collect();
            let r = pick(radius);
            let b = band.map(pick);
            let m = r.iter().copied().fold(0.0, f64::max);
            levels.push((Grid::new(&p, &n, &r, b.as_deref(), m), m));
        }
        Levels { levels }
    }

    /// Visit every item whose support may contain `x` (callers test `r2`).
    #[inline]
    pub fn for_each_near<'a>(&'a self, x: DVec3, mut f: impl FnMut(&'a Item)) {
        for (g, r) in &self.levels {
            g.for_each_near(x, *r, &mut f);
        }
    }

    /// [`Grid::gather`] over the levels in order: the items whose support contains `x`, in
    /// the order [`Self::for_each_near`] visits them; returns their count (beyond the
    /// buffer's length when it overflowed).
    // `!(d2 >= r2)`, not `d2 < r2`: the test of `add`, which keeps a NaN distance.
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    #[inline]
    pub fn gather<'a>(&'a self, x: DVec3, buf: &mut [&'a Item]) -> usize {
        let mut kept = 0;
        for (g, r) in &self.levels {
            g.gather(x, *r, buf, &mut kept);
        }
        kept
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::roots::SplitMix64;

    /// A placeholder for the buffer's unused entries.
    const DUMMY: Item = Item {
        p: DVec3::ZERO,
        n: DVec3::ZERO,
        r2: 0.0,
        b2inv: 0.0,
    };

    #[test]
    fn visits_every_point_within_the_radius() {
        let mut rng = SplitMix64(3);
        let pts: Vec<DVec3> = (0..2000)
            .map(|_| rng.unit_vector() * (1.0 + 0.3 * rng.next_f64()))
            .collect();
        let nrm = vec![DVec3::Z; pts.len()];
        let rad: Vec<f64> = (0..pts.len())
            .map(|i| 0.05 + 0.1 * (i % 7) as f64 / 7.0)
            .collect();
        let rmax = rad.iter().copied().fold(0.0, f64::max);
        for cell in [rmax, 10.0 * rmax, 1e-6] {
            let g = Grid::new(&pts, &nrm, &rad, None, cell.max(rmax));
            for _ in 0..300 {
                let x = rng.unit_vector() * 2.0 * rng.next_f64() + DVec3::splat(0.1);
                let mut seen = 0;
                g.for_each_near(x, rmax, |it| {
                    seen += usize::from((it.p - x).length() < rmax)
                });
                let want = pts.iter().filter(|p| (**p - x).length() < rmax).count();
                assert_eq!(seen, want, "{x}");
            }
        }
    }

    /// The vector test keeps exactly the items the scalar test keeps, in rows of every
    /// length (full blocks of `LANES` and tails), on supports' boundaries (a point at exactly
    /// its radius is out) and for a NaN query (every visited item in).
    #[test]
    fn the_vector_test_is_the_scalar_test() {
        let mut rng = SplitMix64(9);
        let mut pts: Vec<DVec3> = (0..700)
            .map(|_| rng.unit_vector() * rng.next_f64())
            .collect();
        // Points at exactly their radius from a query on a grid of dyadic values.
        let q = DVec3::new(0.25, 0.5, -0.125);
        pts.extend((0..40).map(|i| q + DVec3::new(0.0625 * f64::from(i % 4), 0.0, 0.0)));
        let nrm = vec![DVec3::Z; pts.len()];
        let rad: Vec<f64> = (0..pts.len())
            .map(|i| {
                if i >= 700 {
                    0.0625 * ((i - 700) % 4) as f64
                } else {
                    0.05 + 0.3 * rng.next_f64()
                }
            })
            .collect();
        let lv = Levels::new(&pts, &nrm, &rad, None, 0.2);
        let mut queries: Vec<DVec3> = (0..400)
            .map(|_| rng.unit_vector() * 1.2 * rng.next_f64())
            .collect();
        queries.push(q);
        queries.push(DVec3::NAN);
        let mut boundary = 0;
        for x in queries {
            let mut want: Vec<*const Item> = Vec::new();
            lv.for_each_near(x, |it| {
                if supports(x, it.p, it.r2) {
                    want.push(it);
                }
                boundary += usize::from(it.r2 > 0.0 && (x - it.p).length_squared() == it.r2);
            });
            let mut buf = vec![&DUMMY; want.len() + 1];
            let kept = lv.gather(x, &mut buf);
            let got: Vec<*const Item> = buf[..kept].iter().map(|&r| r as *const Item).collect();
            assert_eq!(got, want, "{x}");
            if x.is_nan() {
                let mut visited = 0;
                lv.for_each_near(x, |_| visited += 1);
                assert_eq!(kept, visited);
            }
        }
        assert!(boundary >= 20, "{boundary}");
    }

    /// `gather` keeps, in visiting order, exactly the visited items whose support contains
    /// the query, and counts them past a short buffer (the stored prefix still right).
    #[test]
    fn gather_keeps_the_supporting_items_in_order() {
        let mut rng = SplitMix64(5);
        let pts: Vec<DVec3> = (0..3000).map(|_| rng.unit_vector()).collect();
        let nrm = vec![DVec3::Z; pts.len()];
        let rad: Vec<f64> = (0..pts.len())
            .map(|i| 0.05 + 0.2 * (i % 5) as f64 / 5.0)
            .collect();
        // Two levels: the radii above 0.1 in a second grid.
        let lv = Levels::new(&pts, &nrm, &rad, None, 0.1);
        let (mut short, mut total) = (0, 0);
        for _ in 0..300 {
            let x = rng.unit_vector() * (0.8 + 0.4 * rng.next_f64());
            let mut want: Vec<*const Item> = Vec::new();
            lv.for_each_near(x, |it| {
                if (x - it.p).length_squared() < it.r2 {
                    want.push(it);
                }
            });
            for len in [want.len() + 1, 17] {
                let mut buf = vec![&DUMMY; len];
                let kept = lv.gather(x, &mut buf);
                assert_eq!(kept, want.len(), "{x}");
                let stored = kept.min(len - 1);
                let got: Vec<*const Item> =
                    buf[..stored].iter().map(|&r| r as *const Item).collect();
                assert_eq!(got, want[..stored], "{x}");
                short += usize::from(kept >= len);
            }
            total += want.len();
        }
        assert!(short > 10 && total > 2000, "{short} {total}");
    }
}
