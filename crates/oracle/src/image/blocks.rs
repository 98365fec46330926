//! Sign summary of the voxel grid by blocks of `BLOCK³` cells (ours), for the bipolar crossing.
//!
//! A cell whose 8 corners have the same sign (`value < 0` or not) has that sign everywhere:
//! the trilinear interpolant is a convex combination of the corners. A block of cells is
//! *uniform* when all its corner nodes (grid nodes, or the background outside the grid) have
//! one sign, else *mixed*. [`ImageSurface::crossing`](crate::Surface::crossing) walks a segment
//! block by block (a 3D DDA, one byte per block: the summary of a 256³ volume is 270 KB and
//! stays in cache) and only evaluates the image where the segment leaves a mixed block, so a
//! Voronoi edge tens of voxels long costs a few evaluations near the surface instead of
//! scattered cell fetches along its length.
//!
//! Blocks tile the cells `-1 ..= n - 1` of each axis (the cells that meet the grid; beyond
//! them the image is the background): block `b` holds cells `b·BLOCK - 1 .. (b + 1)·BLOCK - 1`,
//! i.e. voxel coordinates `v` with `floor((v + 1) / BLOCK) = b`.

use glam::DVec3;
use rayon::prelude::*;

/// Block edge, in cells.
pub(crate) const BLOCK: usize = 8;

/// Block is outside everywhere (`value >= 0`).
pub(crate) const OUT: u8 = 0;
/// Block is inside everywhere (`value < 0`).
pub(crate) const IN: u8 = 1;
/// Block may hold a sign change.
pub(crate) const MIXED: u8 = 2;

/// One byte per block ([`OUT`], [`IN`] or [`MIXED`]), x fastest.
#[derive(Debug)]
pub(crate) struct Blocks {
    pub(crate) nb: [usize; 3],
    pub(crate) flags: Vec<u8>,
}

impl Blocks {
    /// Classify every block of a grid of `dims` nodes from the node signs `bits`
    /// ([`ImageSurface::inside_bits_rows`](super::ImageSurface::inside_bits_rows)), in parallel.
    pub(crate) fn from_bits(dims: [isize; 3], bits: &[u64]) -> Blocks {
        let [nx, ny, nz] = dims.map(|v| v as usize);
        let nb = [
            (nx + 1).div_ceil(BLOCK),
            (ny + 1).div_ceil(BLOCK),
            (nz + 1).div_ceil(BLOCK),
        ];
        let w = nx.div_ceil(64);
        // Node range of block b along an axis of n nodes: (first, last) clipped to the grid,
        // and whether the block reaches past the grid (background nodes, outside).
        let range = |b: usize, n: usize| -> (usize, usize, bool) {
            let lo = (b * BLOCK) as isize - 1;
            let hi = (b * BLOCK + BLOCK) as isize - 1;
            let pad = lo < 0 || hi >= n as isize;
            (lo.max(0) as usize, (hi.min(n as isize - 1)) as usize, pad)
        };
        // Number of inside nodes among x0..=x1 (at most BLOCK + 1 < 64 of them) of row r.
        let ones = |r: usize, x0: usize, x1: usize| -> u32 {
            let len = x1 - x0 + 1;
            let (wi, sh) = (x0 >> 6, x0 & 63);
            let mut v = bits[r * w + wi] >> sh;
            if sh + len > 64 {
                v |= bits[r * w + wi + 1] << (64 - sh);
            }
            (v & ((1u64 << len) - 1)).count_ones()
        };
        let mut flags = vec![OUT; nb[0] * nb[1] * nb[2]];
        flags
            .par_chunks_mut(nb[0] * nb[1])
            .enumerate()
            .for_each(|(bz, slab)| {
                let (z0, z1, pz) = range(bz, nz);
                for by in 0..nb[1] {
                    let (y0, y1, py) = range(by, ny);
                    for bx in 0..nb[0] {
                        let (x0, x1, px) = range(bx, nx);
                        let len = (x1 - x0 + 1) as u32;
                        let (mut any_in, mut any_out) = (false, px || py || pz);
                        for z in z0..=z1 {
                            for y in y0..=y1 {
                                let c = ones(y + ny * z, x0, x1);
                                any_in |= c > 0;
                                any_out |= c < len;
                            }
                        }
                        slab[bx + nb[0] * by] = match (any_in, any_out) {
                            (true, true) => MIXED,
                            (true, false) => IN,
                            _ => OUT,
                        };
                    }
                }
            });
        Blocks { nb, flags }
    }

    /// Walk the segment `va + dv t`, `t` in `[0, 1]` (voxel coordinates), block by block from
    /// `t = 0`: calls `f(u0, u1, flag)` for consecutive pieces covering `[0, 1]` in order
    /// (the parts beyond the blocks are [`OUT`]), until `f` returns `false`. Piece ends are
    /// computed in floating point: a point near a block face may be classified with the
    /// neighbouring block, so callers must not trust a flag within rounding of a piece end.
    pub(crate) fn walk(&self, va: DVec3, dv: DVec3, mut f: impl FnMut(f64, f64, u8) -> bool) {
        let nb = self.nb;
        // Clip to the blocks' box, v + 1 in [0, nb·BLOCK] (slab method).
        let (mut tc0, mut tc1) = (0.0f64, 1.0f64);
        for ax in 0..3 {
            let lo = -1.0;
            let hi = (nb[ax] * BLOCK) as f64 - 1.0;
            if dv[ax] == 0.0 {
                if !(va[ax] >= lo && va[ax] <= hi) {
                    tc0 = 1.0;
                    tc1 = 0.0;
                }
            } else {
                let e0 = (lo - va[ax]) / dv[ax];
                let e1 = (hi - va[ax]) / dv[ax];
                tc0 = tc0.max(e0.min(e1));
                tc1 = tc1.min(e0.max(e1));
            }
        }
        if !(tc0 < tc1) {
            f(0.0, 1.0, OUT);
            return;
        }
        if tc0 > 0.0 && !f(0.0, tc0, OUT) {
            return;
        }
        // Start block: the one holding the entry point (behind a face when moving backwards),
        // clamped into the grid of blocks.
        let p = va + dv * tc0;
        let mut b = [0isize; 3];
        let mut step = [0isize; 3];
        let mut t_max = [f64::INFINITY; 3];
        let mut t_delta = [f64::INFINITY; 3];
        for ax in 0..3 {
            let w = (p[ax] + 1.0) / BLOCK as f64;
            let mut bi = w.floor() as isize;
            // On a face, moving backwards: the block behind it.
            if dv[ax] < 0.0 && w == w.floor() {
                bi -= 1;
            }
            b[ax] = bi.clamp(0, nb[ax] as isize - 1);
            if dv[ax] > 0.0 {
                step[ax] = 1;
                let next = ((b[ax] + 1) * BLOCK as isize) as f64 - 1.0;
                t_max[ax] = (next - va[ax]) / dv[ax];
                t_delta[ax] = BLOCK as f64 / dv[ax];
            } else if dv[ax] < 0.0 {
                step[ax] = -1;
                let next = (b[ax] * BLOCK as isize) as f64 - 1.0;
                t_max[ax] = (next - va[ax]) / dv[ax];
                t_delta[ax] = -(BLOCK as f64) / dv[ax];
            }
        }
        let mut u0 = tc0;
        loop {
            let ax = if t_max[0] <= t_max[1] && t_max[0] <= t_max[2] {
                0
            } else if t_max[1] <= t_max[2] {
                1
            } else {
                2
            };
            let u1 = t_max[ax].min(tc1);
            if u1 > u0 {
                let i = b[0] as usize + nb[0] * (b[1] as usize + nb[1] * b[2] as usize);
                if !f(u0, u1, self.flags[i]) {
                    return;
                }
                u0 = u1;
            }
            if u1 >= tc1 {
                break;
            }
            b[ax] += step[ax];
            if b[ax] < 0 || b[ax] >= nb[ax] as isize {
                break;
            }
            t_max[ax] += t_delta[ax];
        }
        if u0 < 1.0 {
            f(u0, 1.0, OUT);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::image::{ImageSurface, Volume, Voxels};
    use crate::roots::SplitMix64;
    use glam::DAffine3;

    /// The walk's pieces cover [0, 1] in order, each piece's flag is its block's (OUT beyond
    /// the blocks), and a uniform flag is the sign of the image inside the piece.
    #[test]
    fn walk_covers_the_segment_with_the_right_flags() {
        let mut rng = SplitMix64(11);
        let n = [45usize, 38, 27];
        let data: Vec<f32> = (0..n[0] * n[1] * n[2])
            .map(|i| {
                let p = DVec3::new(
                    (i % n[0]) as f64,
                    ((i / n[0]) % n[1]) as f64,
                    (i / (n[0] * n[1])) as f64,
                );
                // A big ball (uniform inside blocks) with a wavy surface (mixed blocks).
                let d = (p - DVec3::new(22.0, 18.0, 13.0)).length();
                (16.0 - d + 1.5 * (p.x * 0.4).sin() * (p.y * 0.3).cos()) as f32
            })
            .collect();
        let vol = Volume::new(n, Voxels::F32(data), DAffine3::IDENTITY).unwrap();
        let s = ImageSurface::at_iso(vol, 1.5).unwrap();
        let blocks = Blocks::from_bits(s.dims_isize(), &s.inside_bits_rows());
        assert!(blocks.flags.contains(&IN) && blocks.flags.contains(&OUT));
        assert!(blocks.flags.contains(&MIXED));
        let hi = DVec3::new(n[0] as f64, n[1] as f64, n[2] as f64);
        for case in 0..2000 {
            let r = |rng: &mut SplitMix64| {
                DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * (hi + 12.0) - 6.0
            };
            let va = r(&mut rng);
            let mut dv = r(&mut rng) - va;
            // Axis-parallel and degenerate directions too.
            if case % 7 == 0 {
                dv.y = 0.0;
            }
            if case % 11 == 0 {
                dv.x = 0.0;
                dv.z = 0.0;
            }
            if case % 13 == 0 {
                dv = -dv;
            }
            let mut end = 0.0;
            blocks.walk(va, dv, |u0, u1, flag| {
                assert_eq!(u0, end, "pieces must be contiguous");
                assert!(u1 > u0 && u1 <= 1.0);
                end = u1;
                for k in 1..8 {
                    let t = u0 + (u1 - u0) * k as f64 / 8.0;
                    // Away from the piece ends (rounding): the point's block.
                    if (t - u0).min(u1 - t) * dv.length() < 1e-6 {
                        continue;
                    }
                    let v = va + dv * t;
                    let w = (v + 1.0) / BLOCK as f64;
                    let b = [w.x.floor(), w.y.floor(), w.z.floor()];
                    let inside = (0..3).all(|a| b[a] >= 0.0 && (b[a] as usize) < blocks.nb[a]);
                    let expect = if inside {
                        let (x, y, z) = (b[0] as usize, b[1] as usize, b[2] as usize);
                        blocks.flags[x + blocks.nb[0] * (y + blocks.nb[1] * z)]
                    } else {
                        OUT
                    };
                    assert_eq!(flag, expect, "case {case} at {v}");
                    if flag != MIXED {
                        assert_eq!(s.value_voxel(v) < 0.0, flag == IN, "case {case} at {v}");
                    }
                }
                true
            });
            assert_eq!(end, 1.0, "case {case}: the walk stopped early");
        }
    }
}
