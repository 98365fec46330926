//! The Euler characteristic and genus of the trilinear level set from the voxel grid (P1 for
//! images, section 6.6.2: theorem 4.4's homeomorphism preserves the genus, so the scan's
//! genus is what a correct mesh must have).
//!
//! **The sum.** The inside `X = {g < 0}` is cut by the grid into open cells: nodes, open edges,
//! open faces and open cubes. The Euler characteristic with compact support is additive, so
//! `χ(X)` is the sum over the cells of `χ_c(X ∩ cell)`, and each term is local:
//! - a node: 1 if inside;
//! - an open edge (the interpolant is linear on it): -1 if both ends are inside (an open
//!   interval), else 0 (empty or half open);
//! - an open face: `χ(X ∩ closed face) - χ(X ∩ its boundary)`. In the closed face the inside
//!   has no hole (the bilinear interpolant has no interior extremum), so the first term is
//!   its number of pieces: the inside corners joined along sides and, on an ambiguous face,
//!   by the asymptotic decider, as the scan joins them;
//! - an open cube: `χ(X ∩ closed cube) - χ(X ∩ its boundary)`, with
//!   `χ(X ∩ closed cube) = b0(A) - J`, where `A` is the inside part of the cube's boundary
//!   (`b0(A)`: the inside [`face_groups`]) and `J` is the number of tunnels through the
//!   cell's interior, of either sign ([`interior_joins`]).
//!
//! Why `b0(A) - J`: let `Y` be the cube's outside part and `Σ` the level surface in the cube.
//! Mayer-Vietoris on `X ∪ Y` gives `χ(X) + χ(Y) = 1 + χ(Σ)`; Alexander duality in the sphere
//! (the cube's complement glued to `X`) gives `χ(X) - χ(Y) = χ(A) - 1`; so
//! `χ(X) = (χ(A) + χ(Σ)) / 2`. The pieces of `Σ` are disks and, for each tunnel, one annulus
//! (marching cubes 33's cases), so `χ(Σ) = c - 2 J` with `c` the level curves on the cube's
//! boundary; and `c = 2 b0(A) - χ(A)` (a piece of the sphere with `k` boundary curves has
//! `χ = 2 - k`). A test checks the cell formula against a fine sampling of random cells.
//!
//! **Genus.** Each closed surface bounds a compact region, so `χ(∂X) = 2 χ(X)`, and the sum
//! of the genera of the surface's components is `#components - χ(X)` (the components counted
//! with the vanishing ones: zero-volume cavities are cavities of the perturbed level).
//!
//! Ties are the scan's: a node at the iso value is outside, a face saddle at it joins the
//! outside pair, so the figure is that of the same perturbed level as the component counts.
//! Only cells with both signs among their corners contribute (a cell all inside contributes
//! `1 - 3 + 3 - 1 = 0` through the node, edges and faces it owns), so the cost is one read of
//! the signs plus work on the cells the surface crosses.

use super::interior::{Corner, FACES, face_diagonal, face_groups, interior_joins};
use crate::image::ImageSurface;

/// The 12 edges of a cell as corner pairs.
const EDGES: [(usize, usize); 12] = [
    (0, 1),
    (2, 3),
    (4, 5),
    (6, 7),
    (0, 2),
    (1, 3),
    (4, 6),
    (5, 7),
    (0, 4),
    (1, 5),
    (2, 6),
    (3, 7),
];

/// `χ_c` of the inside of the open face `(p00, u, v)` of a cell with corner values `g`.
fn open_face(g: &[f64; 8], (p00, u, v): (Corner, Corner, Corner)) -> i64 {
    let c = [p00, p00 + u, p00 + v, p00 + u + v];
    let ins = c.map(|k| g[k as usize] < 0.0);
    let corners = ins.iter().filter(|&&b| b).count() as i64;
    // The sides in cyclic order 00-10-11-01.
    let sides = [(0, 1), (1, 3), (3, 2), (2, 0)];
    let both = sides.iter().filter(|&&(a, b)| ins[a] && ins[b]).count() as i64;
    let pieces = match face_diagonal(g, (p00, u, v)) {
        _ if corners == 0 => 0,
        // Ambiguous: the inside diagonal is one piece when the saddle joins it.
        Some([a, _]) => 1 + i64::from(g[a as usize] >= 0.0),
        None => 1,
    };
    pieces - (corners - both)
}

/// `χ(X ∩ closed cell)` and `χ(X ∩ the cell's boundary)` for corner values `g`.
fn closed_cell(g: &[f64; 8]) -> (i64, i64) {
    let corners = g.iter().filter(|&&x| x < 0.0).count() as i64;
    let edges = EDGES
        .iter()
        .filter(|&&(a, b)| g[a] < 0.0 && g[b] < 0.0)
        .count() as i64;
    let faces: i64 = FACES.iter().map(|&f| open_face(g, f)).sum();
    let boundary = corners - edges + faces;
    let groups = face_groups(g);
    let inside_groups = (0..8)
        .filter(|&c| g[c] < 0.0 && groups[c] as usize == c)
        .count() as i64;
    let tunnels = interior_joins(g).count() as i64;
    (inside_groups - tunnels, boundary)
}

/// What the cell with corner values `g` adds to `χ(X)` through the cells it owns: its lowest
/// corner, the three edges and three faces there, and its interior.
pub(super) fn owned(g: &[f64; 8]) -> i64 {
    let ins = |c: usize| g[c] < 0.0;
    if (0..8).all(ins) || !(0..8).any(ins) {
        return 0;
    }
    let node = ins(0) as i64;
    let edges = [1, 2, 4].iter().filter(|&&k| ins(0) && ins(k)).count() as i64;
    let faces: i64 = FACES[..3].iter().map(|&f| open_face(g, f)).sum();
    let (closed, boundary) = closed_cell(g);
    node - edges + faces + (closed - boundary)
}

/// `χ` of the inside region of `s`'s level set, summed over the grid's cells (the padding
/// included: the background layer is outside), over [`mixed_cells`]; integer sums, so the
/// result does not depend on the thread count.
pub(crate) fn inside_euler(s: &ImageSurface) -> i64 {
    mixed_cells(s, |_, g, out: &mut Vec<i64>| out.push(owned(g)))
        .into_iter()
        .sum()
}

/// `f(lowest corner, corner values, out)` on every cell of the grid and its padding (lowest
/// corners in `[-1, n - 1]`) with both signs among its corners, the others skipped from the
/// node signs (one pass, 64 nodes a word): what `f` pushes, in cell order (z-slices in
/// parallel, concatenated in order: the same for any thread count).
pub(crate) fn mixed_cells<T: Send>(
    s: &ImageSurface,
    f: impl Fn([i64; 3], &[f64; 8], &mut Vec<T>) + Sync,
) -> Vec<T> {
    use rayon::prelude::*;
    let bits = s.inside_bits_rows();
    let [nx, ny, nz] = s.dims_isize().map(|n| n as i64);
    let w = (nx as usize).div_ceil(64);
    let row = |j: i64, k: i64| -> &[u64] {
        if j < 0 || k < 0 || j >= ny || k >= nz {
            &[]
        } else {
            let r = (j + ny * k) as usize * w;
            &bits[r..r + w]
        }
    };
    let cell = |i: i64, j: i64, k: i64, out: &mut Vec<T>| {
        let g: [f64; 8] = std::array::from_fn(|c| {
            let c = c as i64;
            s.grid_value([i + (c & 1), j + ((c >> 1) & 1), k + (c >> 2)])
        });
        f([i, j, k], &g, out);
    };
    let slices: Vec<Vec<T>> = (-1..nz)
        .into_par_iter()
        .map(|k| {
            let mut out = Vec::new();
            let (mut any, mut all) = (vec![0u64; w], vec![0u64; w]);
            for j in -1..ny {
                // The four node rows of this row of cells: `any` / `all` of their bits.
                let rows = [row(j, k), row(j + 1, k), row(j, k + 1), row(j + 1, k + 1)];
                for wi in 0..w {
                    let word = |r: &[u64]| r.get(wi).copied().unwrap_or(0);
                    any[wi] = rows.iter().fold(0, |a, r| a | word(r));
                    all[wi] = rows.iter().fold(!0, |a, r| a & word(r));
                }
                // The cell below the grid's first node (x = -1): its x = -1 corners are
                // background, so it has both signs when a node at x = 0 is inside.
                if any.first().is_some_and(|&a| a & 1 == 1) {
                    cell(-1, j, k, &mut out);
                }
                for wi in 0..w {
                    // Cell x has corners x and x + 1 (bit x + 1 from the next word; nodes past
                    // the grid are background: 0).
                    let next = |v: &[u64]| v.get(wi + 1).map_or(0, |&n| n << 63);
                    let any_c = any[wi] | (any[wi] >> 1) | next(&any);
                    let all_c = all[wi] & ((all[wi] >> 1) | next(&all));
                    let mut mixed = any_c & !all_c;
                    while mixed != 0 {
                        let b = mixed.trailing_zeros() as i64;
                        mixed &= mixed - 1;
                        cell(wi as i64 * 64 + b, j, k, &mut out);
                    }
                }
            }
            out
        })
        .collect();
    slices.into_iter().flatten().collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::roots::SplitMix64;

    fn tri(g: &[f64; 8], x: f64, y: f64, z: f64) -> f64 {
        (0..8)
            .map(|c| {
                let w = |bit: usize, t: f64| if c & bit != 0 { t } else { 1.0 - t };
                g[c] * w(1, x) * w(2, y) * w(4, z)
            })
            .sum()
    }

    /// The Euler characteristic of the inside samples of `f` on an `n^3` grid, as the cubical
    /// complex of the samples (6-connected: vertices, edges, squares and cubes all inside).
    fn sampled_euler(n: [usize; 3], inside: impl Fn(usize, usize, usize) -> bool) -> i64 {
        let at = |i: usize, j: usize, k: usize| i < n[0] && j < n[1] && k < n[2] && inside(i, j, k);
        let mut chi = 0i64;
        for k in 0..n[2] {
            for j in 0..n[1] {
                for i in 0..n[0] {
                    if !at(i, j, k) {
                        continue;
                    }
                    chi += 1;
                    for (a, b, c) in [(1, 0, 0), (0, 1, 0), (0, 0, 1)] {
                        chi -= at(i + a, j + b, k + c) as i64;
                    }
                    for ((a, b, c), (d, e, f)) in [
                        ((1, 0, 0), (0, 1, 0)),
                        ((1, 0, 0), (0, 0, 1)),
                        ((0, 1, 0), (0, 0, 1)),
                    ] {
                        chi += (at(i + a, j + b, k + c)
                            && at(i + d, j + e, k + f)
                            && at(i + a + d, j + b + e, k + c + f))
                            as i64;
                    }
                    chi -= (1..8).all(|c| at(i + (c & 1), j + ((c >> 1) & 1), k + (c >> 2))) as i64;
                }
            }
        }
        chi
    }

    fn sampled_cell(g: &[f64; 8], n: usize) -> i64 {
        let h = 1.0 / (n - 1) as f64;
        let v: Vec<bool> = (0..n * n * n)
            .map(|p| {
                let (i, j, k) = (p % n, (p / n) % n, p / (n * n));
                tri(g, i as f64 * h, j as f64 * h, k as f64 * h) < 0.0
            })
            .collect();
        sampled_euler([n; 3], |i, j, k| v[i + n * (j + n * k)])
    }

    /// Marching cubes 33's tunnel (case 4.1.2) and its complement: a tube (χ = 1) and a cube
    /// with a tube bored through it (χ = 0); without the tunnel, two blobs and a ball.
    #[test]
    fn a_tunnel_is_a_tube_on_its_side_and_a_hole_on_the_other() {
        let mut deep = [1.0; 8];
        deep[0] = -10.0;
        deep[7] = -10.0;
        let mut shallow = [1.0; 8];
        shallow[0] = -1.0;
        shallow[7] = -1.0;
        assert_eq!(closed_cell(&deep).0, 1);
        assert_eq!(closed_cell(&shallow).0, 2);
        assert_eq!(closed_cell(&deep.map(|x| -x)).0, 0);
        assert_eq!(closed_cell(&shallow.map(|x| -x)).0, 1);
    }

    /// `χ(X ∩ closed cell)` against a fine sampling of random cells biased towards the
    /// ambiguous cases (a feature thinner than the sampling can be missed by it: then a finer
    /// sampling must agree).
    #[test]
    fn the_cell_formula_matches_a_fine_sampling() {
        let mut r = SplitMix64::new(11);
        let (mut tunnels, mut finer) = (0, 0);
        for _ in 0..3000 {
            let pattern = r.next_u64();
            let g: [f64; 8] = std::array::from_fn(|c| {
                let parity = ((c & 1) + ((c >> 1) & 1) + (c >> 2)) & 1;
                let flip = (pattern >> (2 * c)) & 3 == 0;
                let s = if (parity == 1) ^ flip { 1.0 } else { -1.0 };
                s * (0.05 + r.next_f64() * 4.0)
            });
            tunnels += interior_joins(&g).count();
            let exact = closed_cell(&g).0;
            if sampled_cell(&g, 33) != exact {
                finer += 1;
                assert_eq!(sampled_cell(&g, 129), exact, "{g:?}");
            }
        }
        assert!(tunnels > 20, "{tunnels}");
        assert!(finer < 300, "{finer}");
    }

    fn image(dims: [usize; 3], data: Vec<f32>) -> ImageSurface {
        use crate::image::{ImageOptions, Volume, Voxels};
        let vol = Volume::new(dims, Voxels::F32(data), glam::DAffine3::IDENTITY).unwrap();
        let opts = ImageOptions {
            iso: Some(0.0),
            ..Default::default()
        };
        ImageSurface::new(vol, &opts).unwrap()
    }

    fn sampled_image(s: &ImageSurface, per_voxel: usize) -> i64 {
        let [nx, ny, nz] = s.dims_isize().map(|n| n as usize);
        let h = 1.0 / per_voxel as f64;
        let n = [nx, ny, nz].map(|n| (n + 1) * per_voxel + 1);
        sampled_euler(n, |i, j, k| {
            let p = glam::DVec3::new(i as f64, j as f64, k as f64) * h - 1.0;
            crate::Surface::value(s, p) < 0.0
        })
    }

    /// Shapes of known genus sampled as images: a torus (genus 1), a hollow ball (two spheres)
    /// and two disjoint tori.
    #[test]
    fn sampled_shapes_have_their_genus() {
        use glam::DVec3;
        let sample = |dims: [usize; 3], f: &dyn Fn(DVec3) -> f64| {
            let mut data = Vec::new();
            for k in 0..dims[2] {
                for j in 0..dims[1] {
                    for i in 0..dims[0] {
                        data.push(-f(DVec3::new(i as f64, j as f64, k as f64)) as f32);
                    }
                }
            }
            image(dims, data)
        };
        let torus = |p: DVec3, c: DVec3| {
            let q = p - c;
            let r = (q.x * q.x + q.y * q.y).sqrt() - 6.0;
            (r * r + q.z * q.z).sqrt() - 2.5
        };
        let t = sample([20, 20, 10], &|p| torus(p, DVec3::new(9.5, 9.5, 4.5)));
        assert_eq!(
            (t.component_count(), inside_euler(&t), t.scan_genus()),
            (1, 0, Some(1))
        );
        let shell = sample([20, 20, 20], &|p| {
            (p.distance(DVec3::splat(9.5)) - 6.0).abs() - 2.0
        });
        assert_eq!(
            (
                shell.component_count(),
                inside_euler(&shell),
                shell.scan_genus()
            ),
            (2, 2, Some(0))
        );
        let two = sample([40, 20, 10], &|p| {
            torus(p, DVec3::new(9.5, 9.5, 4.5)).min(torus(p, DVec3::new(29.5, 9.5, 4.5)))
        });
        assert_eq!((two.component_count(), two.scan_genus()), (2, Some(2)));
    }

    /// Random images (many saddles and tunnels) against the cubical Euler characteristic of
    /// the interpolant sampled at 1/12 voxel (at 1/36 where a feature is too thin for that).
    #[test]
    fn random_images_match_a_fine_sampling() {
        let mut r = SplitMix64::new(5);
        let (mut genus, mut finer) = (0, 0);
        for _ in 0..12 {
            let dims = [5, 4, 4];
            let data = (0..80)
                .map(|_| {
                    let v = 0.15 + r.next_f64();
                    (if r.next_u64() & 1 == 0 { v } else { -v }) as f32
                })
                .collect();
            let s = image(dims, data);
            let exact = inside_euler(&s);
            if sampled_image(&s, 12) != exact {
                finer += 1;
                assert_eq!(sampled_image(&s, 36), exact);
            }
            genus += s.scan_genus().unwrap();
        }
        assert!(genus > 0 && finer < 4, "{genus} {finer}");
    }

    /// The word-wise selection of the cells with both signs against reading every cell, on
    /// rows longer than a word (the carry between words) and random signs.
    #[test]
    fn the_cells_skipped_are_those_of_one_sign() {
        let mut r = SplitMix64::new(9);
        let dims = [130, 5, 4];
        let data = (0..dims.iter().product::<usize>())
            .map(|_| (r.next_f64() - 0.7) as f32)
            .collect();
        let s = image(dims, data);
        let mut every = 0;
        for k in -1..4 {
            for j in -1..5 {
                for i in -1..130 {
                    let g: [f64; 8] = std::array::from_fn(|c| {
                        let c = c as i64;
                        s.grid_value([i + (c & 1), j + ((c >> 1) & 1), k + (c >> 2)])
                    });
                    every += owned(&g);
                }
            }
        }
        assert_eq!(inside_euler(&s), every);
        assert!(s.scan_genus().unwrap() > 0);
    }
}
