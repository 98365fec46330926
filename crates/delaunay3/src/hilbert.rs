//! Hilbert-curve keys of points (ours; the transform of Skilling, "Programming the Hilbert
//! curve", AIP Conf. Proc. 707, 2004): the index along the 3D Hilbert curve of the cell
//! holding each point in a 2^21-per-axis grid over the points' bounding cube. Sorting by key
//! orders a bulk insertion's BRIO rounds (as Marot, Pellerin & Remacle's Delaunay does) in
//! linear-time key computations and one sort, where the median splits of [`crate::sort`]
//! select at every level.

use geom::morton::spread;
use glam::DVec3;

/// Bits per axis: 3 x 21 = 63 key bits.
const BITS: u32 = 21;

/// The largest grid coordinate.
const TOP: f64 = ((1u32 << BITS) - 1) as f64;

/// The grid over a point set's bounding cube: `cell(p)` maps a point to integer coordinates
/// in `0..2^21` per axis, monotone in each coordinate (the same scale on every axis, so the
/// curve is not stretched).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Grid {
    lo: DVec3,
    scale: f64,
}

impl Grid {
    /// The grid of the finite points `pts` (any scale for an empty or one-point set).
    pub(crate) fn new(pts: &[DVec3]) -> Grid {
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for p in pts {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        let extent = (hi - lo).max_element();
        let scale = if extent > 0.0 && extent.is_finite() {
            TOP / extent
        } else {
            0.0
        };
        Grid { lo, scale }
    }

    /// The grid cell of `p` (a point of the set the grid was made for).
    #[inline]
    pub(crate) fn cell(&self, p: DVec3) -> [u32; 3] {
        let c = |x: f64, lo: f64| ((x - lo) * self.scale).clamp(0.0, TOP) as u32;
        [c(p.x, self.lo.x), c(p.y, self.lo.y), c(p.z, self.lo.z)]
    }

    /// The key of `p` (a point of the set the grid was made for).
    #[cfg(test)]
    pub(crate) fn key(&self, p: DVec3) -> u64 {
        index(self.cell(p))
    }

    /// The keys of `pts` (points of the set the grid was made for), in order.
    pub(crate) fn keys(&self, pts: impl ExactSizeIterator<Item = DVec3>) -> Vec<u64> {
        let mut out = Vec::with_capacity(pts.len() + LANES);
        let mut lanes = [[0u32; LANES]; 3];
        let mut n = 0;
        for p in pts {
            let c = self.cell(p);
            for k in 0..3 {
                lanes[k][n] = c[k];
            }
            n += 1;
            if n == LANES {
                out.extend_from_slice(&index_lanes(lanes));
                n = 0;
            }
        }
        if n > 0 {
            out.extend_from_slice(&index_lanes(lanes)[..n]);
        }
        out
    }
}

/// The Hilbert index of the grid point `x` (each coordinate below 2^21): [`index_lanes`] on
/// one lane.
#[cfg(test)]
pub(crate) fn index(x: [u32; 3]) -> u64 {
    let mut lanes = [[0u32; LANES]; 3];
    for k in 0..3 {
        lanes[k][0] = x[k];
    }
    index_lanes(lanes)[0]
}

/// Points per [`index_lanes`] call.
pub(crate) const LANES: usize = 8;

/// The Hilbert indices of [`LANES`] grid points (`x[axis][lane]`, each below 2^21).
/// Skilling's transform to the curve's "transposed" index, without data-dependent branches
/// and lane by lane (so it vectorizes), then the bits interleaved (x's bit first at each
/// level).
// Lane loops index several arrays at one lane: the shape the compiler vectorizes.
#[allow(clippy::needless_range_loop)]
#[inline]
pub(crate) fn index_lanes(mut x: [[u32; LANES]; 3]) -> [u64; LANES] {
    // Undo the excess work, from the top bit down.
    let mut q = 1u32 << (BITS - 1);
    while q > 1 {
        let p = q - 1;
        for i in 0..3 {
            for l in 0..LANES {
                // Bit q of x[i] set: invert the low bits of x[0]; else exchange them with
                // x[i]'s.
                let set = 0u32.wrapping_sub(u32::from(x[i][l] & q != 0));
                let t = (x[0][l] ^ x[i][l]) & p & !set;
                x[0][l] ^= (p & set) | t;
                x[i][l] ^= t;
            }
        }
        q >>= 1;
    }
    let mut out = [0u64; LANES];
    for l in 0..LANES {
        // Gray encode.
        x[1][l] ^= x[0][l];
        x[2][l] ^= x[1][l];
        let mut t = 0;
        let mut q = 1u32 << (BITS - 1);
        while q > 1 {
            t ^= (q - 1) & 0u32.wrapping_sub(u32::from(x[2][l] & q != 0));
            q >>= 1;
        }
        let s = |v: u32| spread(u64::from(v ^ t));
        out[l] = (s(x[0][l]) << 2) | (s(x[1][l]) << 1) | s(x[2][l]);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The curve at a small order, by brute force over the grid: consecutive indices are
    /// 6-neighbors, and every cell has its own index.
    #[test]
    fn consecutive_keys_are_adjacent_cells_and_keys_are_distinct() {
        // The top levels of a 2^21 grid, restricted to cells whose coordinates are multiples
        // of 2^18: an order-3 curve (8^3 cells).
        let s = 1u32 << 18;
        let mut cells: Vec<(u64, [u32; 3])> = Vec::new();
        for x in 0..8 {
            for y in 0..8 {
                for z in 0..8 {
                    let c = [x * s, y * s, z * s];
                    cells.push((index(c), c));
                }
            }
        }
        cells.sort_unstable();
        for w in cells.windows(2) {
            assert_ne!(w[0].0, w[1].0, "two cells with one key");
            let d: u32 = (0..3).map(|k| w[0].1[k].abs_diff(w[1].1[k])).sum();
            assert_eq!(d, s, "{:?} -> {:?} is not one step", w[0].1, w[1].1);
        }
        assert_eq!(cells[0].1, [0, 0, 0], "the curve starts at the origin");
    }

    #[test]
    fn grid_keys_of_the_corners_and_of_a_flat_set() {
        let pts = [DVec3::ZERO, DVec3::new(2.0, 1.0, 0.5)];
        let g = Grid::new(&pts);
        assert_eq!(g.key(DVec3::ZERO), 0);
        // A degenerate set (all points equal) maps every point to the origin's key.
        let g = Grid::new(&[DVec3::ONE; 3]);
        assert_eq!(g.key(DVec3::ONE), 0);
    }
}
