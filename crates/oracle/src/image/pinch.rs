//! The level of a two-valued image (section 6.6.2's smoothness assumption): where the midpoint
//! pinches the trilinear level set, and the level used instead.
//!
//! On a binary image (and a label's indicator) the values are 0 and 1 after scaling. A grid
//! face whose four nodes alternate (1, 0 / 0, 1: two voxels touching only along an edge; two
//! touching only at a corner make no such face, and the body saddle of their cell is at 1/4)
//! is bilinear with its saddle at the face centre, of value exactly 1/2. So the
//! level set at the midpoint 1/2 passes through that saddle: two sheets cross there, and S is
//! not a surface (d_M = 0). No sampling is an eps-sample of it: the refinement stalls at the
//! point (the manifold patch makes topological decisions, with needle triangles) and on a
//! checkerboard it ran to 2 million vertices for a 16^3 image.
//!
//! The critical values of the trilinear interpolant of 0/1 corners are 1/4, 4/9, 1/2, 5/9 and
//! 3/4 (every configuration of a cell, enumerated: face saddles 1/2, body saddles 1/4, 4/9,
//! 1/2, 5/9, 3/4). When the midpoint is pinched, the surface takes [`BINARY_LEVEL`] = 19/36
//! of the way from the background to the foreground value, the middle of (1/2, 5/9): a regular
//! value, at 1/36 from the nearest critical ones, with the topology of the levels just past
//! the midpoint: the voxels of each contact stay apart (the foreground is 6-connected), as the
//! voxel scan decides a saddle exactly at the level. Each contact leaves a gap 1/3 of a voxel
//! wide on the face's diagonal, and there d_M is about 1/6 of a voxel (the face's hyperbola
//! `uv = 1/72`, centred, has curvature radius 1/6 at its vertices, 1/6 from the centre); a
//! flat boundary moves by 1/36 of a voxel. Images without a contact keep the midpoint.

use super::surface::Mode;
use super::{ImageOptions, ImageSurface};

/// Where a pinched two-valued image puts its level: this fraction of the way from the
/// background value to the foreground value (see the module docs).
pub const BINARY_LEVEL: f64 = 19.0 / 36.0;

/// d_M at a contact, in voxels, with the level at [`BINARY_LEVEL`] (module docs).
pub const CONTACT_DM_VOXELS: f64 = 1.0 / 6.0;

/// The grid faces whose four nodes alternate (inside, outside / outside, inside), from the
/// node signs `bits` (1 = inside; rows along x of 64 nodes per word, row `j + ny k`, rows
/// padded to whole words) of a grid of `[nx, ny, nz]` nodes. Faces with a node outside the grid
/// never alternate (the background is outside).
pub(crate) fn alternating_faces(bits: &[u64], [nx, ny, nz]: [usize; 3]) -> usize {
    let w = nx.div_ceil(64);
    let row = |j: usize, k: usize| &bits[(j + ny * k) * w..(j + ny * k + 1) * w];
    // Node x + 1 of each bit position (the next word's first node shifted in).
    let next = |r: &[u64], wi: usize| (r[wi] >> 1) | r.get(wi + 1).map_or(0, |n| n << 63);
    let below = |lim: usize, wi: usize| {
        let lo = wi * 64;
        if lim >= lo + 64 {
            !0u64
        } else if lim <= lo {
            0
        } else {
            (1u64 << (lim - lo)) - 1
        }
    };
    // Faces of nodes (x, a), (x + 1, a), (x, b), (x + 1, b) of two rows a, b.
    let xfaces = |a: &[u64], b: &[u64]| -> u32 {
        (0..w)
            .map(|wi| {
                let (a0, a1, b0, b1) = (a[wi], next(a, wi), b[wi], next(b, wi));
                (!(a0 ^ b1) & !(a1 ^ b0) & (a0 ^ a1) & below(nx - 1, wi)).count_ones()
            })
            .sum()
    };
    let mut count = 0usize;
    for k in 0..nz {
        for j in 0..ny {
            let p = row(j, k);
            if j + 1 < ny {
                count += xfaces(p, row(j + 1, k)) as usize;
            }
            if k + 1 < nz {
                count += xfaces(p, row(j, k + 1)) as usize;
            }
            if j + 1 < ny && k + 1 < nz {
                let (q, r, s) = (row(j + 1, k), row(j, k + 1), row(j + 1, k + 1));
                count += (0..w)
                    .map(|wi| {
                        (!(p[wi] ^ s[wi]) & !(q[wi] ^ r[wi]) & (p[wi] ^ q[wi]) & below(nx, wi))
                            .count_ones() as usize
                    })
                    .sum::<usize>();
            }
        }
    }
    count
}

impl ImageSurface {
    /// On a two-valued image at its midpoint: count the faces where the level set is pinched
    /// and, when there are some and the level is the default, move it to
    /// [`BINARY_LEVEL`] (see `pinch`'s docs). Before any cache is filled.
    pub(super) fn leave_the_pinched_midpoint(&mut self, opts: &ImageOptions) {
        let midpoint = match (self.mode, self.stats.binary) {
            (Mode::Label { .. }, _) => true,
            (Mode::Intensity { .. }, Some((lo, hi))) => self.iso == 0.5 * (lo + hi),
            _ => false,
        };
        if !midpoint {
            return;
        }
        let n = self.n.map(|v| v as usize);
        let count = alternating_faces(&self.inside_bits_rows(), n);
        let moved = count > 0 && (opts.label.is_some() || opts.iso.is_none());
        self.contacts = Some((count, moved));
        if !moved {
            return;
        }
        let t = BINARY_LEVEL;
        let apart = self.off_midpoint_levels().map(|l| l.0);
        let slope = self.vol.scaling().0;
        match &mut self.mode {
            Mode::Label { level, .. } => {
                *level = t;
                self.iso = t;
            }
            Mode::Intensity { a, b } => {
                let iso = apart.expect("a binary image");
                let inter = self.vol.scaling().1;
                *b = (*a / slope) * (inter - iso);
                self.iso = iso;
            }
        }
    }

    /// Two-valued images (binary, or a label's indicator) at their midpoint: the number of
    /// grid faces whose nodes alternate (voxels touching only along an edge),
    /// where the level set at the midpoint is pinched (not a surface), and whether the level
    /// was moved to [`BINARY_LEVEL`] for them (the default level) or not
    /// (an iso given at the midpoint). `None` for other images and levels.
    ///
    /// ```
    /// use oracle::image::{ImageOptions, ImageSurface, Volume, Voxels, BINARY_LEVEL};
    /// use glam::DAffine3;
    /// // Two bright voxels touching along an edge.
    /// let mut v = vec![0u8; 4 * 4 * 4];
    /// v[1 + 4 * (1 + 4 * 1)] = 200;
    /// v[2 + 4 * (2 + 4 * 1)] = 200;
    /// let vol = Volume::new([4; 3], Voxels::U8(v), DAffine3::IDENTITY).unwrap();
    /// let s = ImageSurface::new(vol.clone(), &ImageOptions::default()).unwrap();
    /// assert_eq!(s.contacts(), Some((1, true)));
    /// assert_eq!(s.iso(), 200.0 * BINARY_LEVEL);
    /// assert_eq!(s.component_count(), 2);
    /// let s = ImageSurface::at_iso(vol, 100.0).unwrap();
    /// assert_eq!((s.contacts(), s.iso()), (Some((1, false)), 100.0));
    /// ```
    pub fn contacts(&self) -> Option<(usize, bool)> {
        self.contacts
    }

    /// The levels of a binary image off its midpoint: [`BINARY_LEVEL`]
    /// of the way from the background value to the foreground value (the pinched voxels
    /// apart), and its mirror image about the midpoint (joined). `None` for other images.
    fn off_midpoint_levels(&self) -> Option<(f64, f64)> {
        let (Mode::Intensity { a, .. }, Some((lo, hi))) = (self.mode, self.stats.binary) else {
            return None;
        };
        // a = -slope for a bright foreground (inside where the intensity is above the iso).
        let bright = a / self.vol.scaling().0 < 0.0;
        let (bg, fg) = if bright { (lo, hi) } else { (hi, lo) };
        let apart = bg + BINARY_LEVEL * (fg - bg);
        Some((apart, lo + hi - apart))
    }

    /// A note for the user when [`ImageSurface::contacts`] found pinches: the level used and
    /// how to choose the other side, or, for an iso given at the midpoint, that it is not a
    /// surface there and which levels are.
    pub fn level_note(&self) -> Option<String> {
        let (count, moved) = self.contacts.filter(|c| c.0 > 0)?;
        let what = format!(
            "{count} grid face(s) where voxels touch only along an edge pinch the \
             level set at the midpoint of the two values (two sheets cross at each: not a surface)"
        );
        let fmt = |x: f64| {
            let (lo, hi) = self.stats.binary.unwrap_or((0.0, 1.0));
            let digits = (4.0 - (hi - lo).abs().log10().floor()).clamp(0.0, 12.0) as usize;
            format!("{x:.digits$}")
        };
        let levels = self.off_midpoint_levels();
        Some(if moved {
            let how = levels.map_or(String::new(), |(_, join)| {
                format!("; --iso {} joins them", fmt(join))
            });
            format!(
                "image: {what}; using the level {} instead (19/36 of the way to the foreground: \
                 those voxels stay apart, as the voxel scan counts them{how})",
                fmt(self.iso)
            )
        } else {
            let (apart, join) = levels.unwrap_or((self.iso, self.iso));
            format!(
                "image: --iso {}: {what}; there the sampling conditions fail and the refinement \
                 stalls (no guarantee); leave --iso out for the level {} (those voxels apart), \
                 or pass --iso {} to join them",
                self.iso,
                fmt(apart),
                fmt(join)
            )
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Bit rows of a node predicate, in the layout of [`alternating_faces`].
    fn bits(n: [usize; 3], inside: impl Fn(usize, usize, usize) -> bool) -> Vec<u64> {
        let w = n[0].div_ceil(64);
        let mut b = vec![0u64; w * n[1] * n[2]];
        for k in 0..n[2] {
            for j in 0..n[1] {
                for i in 0..n[0] {
                    if inside(i, j, k) {
                        b[(j + n[1] * k) * w + i / 64] |= 1 << (i % 64);
                    }
                }
            }
        }
        b
    }

    /// The faces counted one by one.
    fn brute(n: [usize; 3], inside: &impl Fn(usize, usize, usize) -> bool) -> usize {
        let mut c = 0;
        let at =
            |p: [usize; 3]| p[0] < n[0] && p[1] < n[1] && p[2] < n[2] && inside(p[0], p[1], p[2]);
        for k in 0..n[2] {
            for j in 0..n[1] {
                for i in 0..n[0] {
                    let o = [i, j, k];
                    for (a, b) in [(0, 1), (0, 2), (1, 2)] {
                        let (mut u, mut v, mut uv) = (o, o, o);
                        u[a] += 1;
                        v[b] += 1;
                        uv[a] += 1;
                        uv[b] += 1;
                        if uv[a] >= n[a] || uv[b] >= n[b] {
                            continue;
                        }
                        let (p00, p10, p01, p11) = (at(o), at(u), at(v), at(uv));
                        c += (p00 == p11 && p10 == p01 && p00 != p10) as usize;
                    }
                }
            }
        }
        c
    }

    /// Against the one-by-one count, on sparse random grids spanning several words a row.
    #[test]
    fn the_word_count_matches_the_faces_one_by_one() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        for (n, density) in [
            ([5, 4, 3], 50),
            ([70, 3, 4], 30),
            ([130, 5, 2], 10),
            ([64, 2, 2], 50),
        ] {
            let mut set = std::collections::HashSet::new();
            for k in 0..n[2] {
                for j in 0..n[1] {
                    for i in 0..n[0] {
                        state = state
                            .wrapping_mul(6364136223846793005)
                            .wrapping_add(1442695040888963407);
                        if (state >> 33) % 100 < density {
                            set.insert((i, j, k));
                        }
                    }
                }
            }
            let f = |i, j, k| set.contains(&(i, j, k));
            let got = alternating_faces(&bits(n, f), n);
            assert_eq!(got, brute(n, &f), "{n:?}");
            assert!(got > 0, "{n:?}: the test needs contacts");
        }
    }

    /// A 3^3 checkerboard: every one of its 3 * 3 * 2 * 2 faces alternates; one voxel has none.
    #[test]
    fn a_checkerboard_alternates_everywhere_and_a_lone_voxel_nowhere() {
        let n = [3, 3, 3];
        assert_eq!(
            alternating_faces(&bits(n, |i, j, k| (i + j + k) % 2 == 1), n),
            36
        );
        assert_eq!(
            alternating_faces(&bits(n, |i, j, k| (i, j, k) == (1, 1, 1)), n),
            0
        );
    }

    /// The module docs' list of critical values, found again: Newton's method on the gradient
    /// of every 0/1 cell from 64 starts (body critical points) and the bilinear saddle of every
    /// 0/1 face; [`BINARY_LEVEL`] is at least 1/36 from each.
    #[test]
    fn the_level_is_a_regular_value_of_every_binary_cell() {
        let b = |c: usize, t: f64| if c == 1 { t } else { 1.0 - t };
        let d = |c: usize| if c == 1 { 1.0 } else { -1.0 };
        let mut found: Vec<f64> = Vec::new();
        let mut add = |v: f64| {
            if !found.iter().any(|&f| (f - v).abs() < 1e-9) {
                found.push(v);
            }
        };
        // Every cell but the two constant ones (gradient 0 everywhere, no level set).
        for conf in 1u32..255 {
            let corner = |i: usize, j: usize, k: usize| ((conf >> (i + 2 * j + 4 * k)) & 1) as f64;
            let eval = |p: [f64; 3]| {
                let (mut f, mut g, mut h) = (0.0, [0.0; 3], [[0.0; 3]; 3]);
                for c in 0..8 {
                    let (i, j, k) = (c & 1, (c >> 1) & 1, (c >> 2) & 1);
                    let v = corner(i, j, k);
                    let (bx, by, bz) = (b(i, p[0]), b(j, p[1]), b(k, p[2]));
                    f += v * bx * by * bz;
                    g[0] += v * d(i) * by * bz;
                    g[1] += v * bx * d(j) * bz;
                    g[2] += v * bx * by * d(k);
                    h[0][1] += v * d(i) * d(j) * bz;
                    h[0][2] += v * d(i) * by * d(k);
                    h[1][2] += v * bx * d(j) * d(k);
                }
                (h[1][0], h[2][0], h[2][1]) = (h[0][1], h[0][2], h[1][2]);
                (f, g, h)
            };
            for s in 0..64 {
                let mut p = [s % 4, (s / 4) % 4, s / 16].map(|i| 0.125 + 0.25 * i as f64);
                for _ in 0..50 {
                    let (_, g, h) = eval(p);
                    let m = glam::DMat3::from_cols_array_2d(&h);
                    if m.determinant().abs() < 1e-12 {
                        break;
                    }
                    let step = m.inverse() * glam::DVec3::from_array(g);
                    p = (glam::DVec3::from_array(p) - step).to_array();
                }
                let (f, g, _) = eval(p);
                let inside = p.iter().all(|&t| t > 1e-9 && t < 1.0 - 1e-9);
                if inside && g.iter().all(|&x| x.abs() < 1e-12) {
                    add(f);
                }
            }
        }
        for conf in 0u32..16 {
            let v = [0, 1, 2, 3].map(|i| ((conf >> i) & 1) as f64);
            let den = v[0] + v[3] - v[1] - v[2];
            if den != 0.0 {
                let (u, w) = ((v[0] - v[2]) / den, (v[0] - v[1]) / den);
                if u > 0.0 && u < 1.0 && w > 0.0 && w < 1.0 {
                    add((v[0] * v[3] - v[1] * v[2]) / den);
                }
            }
        }
        found.sort_by(f64::total_cmp);
        let listed = [0.25, 4.0 / 9.0, 0.5, 5.0 / 9.0, 0.75];
        assert_eq!(found.len(), listed.len(), "{found:?}");
        for (f, l) in found.iter().zip(listed) {
            assert!((f - l).abs() < 1e-9, "{found:?}");
            assert!((BINARY_LEVEL - f).abs() >= 1.0 / 36.0 - 1e-12, "{f}");
        }
    }
}
