//! P1 for images: components of the trilinear level set from the voxel grid, and seed points.
//!
//! Grid nodes (voxel centres) are *inside* when their value is `< 0`. The grid is padded by
//! one layer of background nodes (outside), all joined into one *exterior* node.
//!
//! **Connectivity.** Two nodes of the same sign are joined when they are 6-neighbours (the grid
//! edge between them is linear, so it never leaves their side), or when they are the diagonal
//! of an ambiguous face and the bilinear saddle of that face is on their side (the asymptotic
//! decider: the inside pair is joined if the saddle value is `< 0`, the outside pair otherwise).
//! These are exact connections of the trilinear interpolant's inside and outside regions, so
//! every component of the node sets lies in one true region. The only connection not detected
//! is an interior tunnel through a cell (a body-diagonal pair joined through the cell's
//! interior), so the counts are exact except in that rare case, where they are too high.
//!
//! **Surface components.** The regions of R³ \ S form a tree (each closed surface separates
//! space in two), so #surface components = #inside regions + #outside regions - 1.
//!
//! **Seeds.** Every surface component crosses a grid edge (the trilinear interpolant is
//! harmonic, so a component inside one cell would break the maximum principle; a component
//! meeting only face interiors would give a closed curve inside a face, same argument). For
//! every pair (inside component, outside component) joined by a sign-changing edge we keep the
//! first such edge in scan order; its crossing (exact: the interpolant is linear along an
//! edge) lies on the unique surface component separating the two regions, so every surface
//! component gets a seed. Up to 4096 other crossings are kept at a regular stride for extra
//! seeds. The scan of node signs runs in parallel (rayon); union-find and the collection are
//! sequential in index order, so the result does not depend on the thread count.

use super::ImageSurface;
use crate::roots::SplitMix64;
use glam::DVec3;
use std::collections::BTreeMap;

/// Components of the level set found on the voxel grid, and on-surface seed points.
#[derive(Clone, Debug, PartialEq)]
pub struct Topology {
    /// Connected components of the inside (value < 0) region.
    pub inside_components: usize,
    /// Connected components of the outside region, including the unbounded one.
    pub outside_components: usize,
    /// Connected components of the surface: `inside + outside - 1`.
    pub surface_components: usize,
    /// Number of grid edges (including edges to the padding) with a sign change.
    pub crossing_edges: usize,
    /// One world-space point on each pair (inside component, outside component) that touch:
    /// at least one per surface component.
    pub component_seeds: Vec<DVec3>,
    /// Further crossing points (world space), at a regular stride over the grid.
    pub extra_seeds: Vec<DVec3>,
}

impl Topology {
    /// All component seeds plus up to 64 extra seeds chosen from `seed` (deterministic).
    pub fn seed_points(&self, seed: u64) -> Vec<DVec3> {
        let mut out = self.component_seeds.clone();
        let n = self.extra_seeds.len();
        if n <= 64 {
            out.extend_from_slice(&self.extra_seeds);
        } else {
            let mut rng = SplitMix64(seed ^ 0x001A_A6E5_EED5);
            let start = (rng.next_u64() % n as u64) as usize;
            let step = n / 64;
            out.extend((0..64).map(|i| self.extra_seeds[(start + i * step) % n]));
        }
        out
    }
}

struct Dsu(Vec<u32>);
impl Dsu {
    #[inline]
    fn find(&mut self, mut x: u32) -> u32 {
        while self.0[x as usize] != x {
            let p = self.0[x as usize];
            self.0[x as usize] = self.0[p as usize];
            x = p;
        }
        x
    }
    #[inline]
    fn union(&mut self, a: u32, b: u32) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            let (lo, hi) = if ra < rb { (ra, rb) } else { (rb, ra) };
            self.0[hi as usize] = lo;
        }
    }
}

#[inline]
fn bit(bits: &[u64], i: usize) -> bool {
    (bits[i >> 6] >> (i & 63)) & 1 == 1
}

pub(crate) fn compute(s: &ImageSurface) -> Topology {
    let [nx, ny, nz] = s.dims_isize().map(|v| v as usize);
    let n = nx * ny * nz;
    let bits = s.inside_bits();
    let ins = |i: usize| bit(&bits, i);
    let ext = n as u32; // the exterior (padding) node
    let mut dsu = Dsu((0..=n as u32).collect());
    let (sy, sz) = (nx, nx * ny);
    // Asymptotic decider on the face with corners p00, p10 = p00 + u, p01 = p00 + v, p11.
    let face = |dsu: &mut Dsu, p00: usize, u: usize, v: usize| {
        let (a, b, c, d) = (ins(p00), ins(p00 + u), ins(p00 + v), ins(p00 + u + v));
        if a == d && b == c && a != b {
            let (f00, f10, f01, f11) = (
                s.node_value(p00),
                s.node_value(p00 + u),
                s.node_value(p00 + v),
                s.node_value(p00 + u + v),
            );
            let den = f00 + f11 - f10 - f01;
            let saddle = if den != 0.0 {
                (f00 * f11 - f10 * f01) / den
            } else {
                0.0
            };
            let inside_joined = saddle < 0.0;
            if inside_joined == a {
                dsu.union(p00 as u32, (p00 + u + v) as u32);
            } else {
                dsu.union((p00 + u) as u32, (p00 + v) as u32);
            }
        }
    };
    for k in 0..nz {
        for j in 0..ny {
            let row = j * sy + k * sz;
            for i in 0..nx {
                let p = row + i;
                let a = ins(p);
                let border =
                    i == 0 || j == 0 || k == 0 || i + 1 == nx || j + 1 == ny || k + 1 == nz;
                if border && !a {
                    dsu.union(p as u32, ext);
                }
                if i + 1 < nx && ins(p + 1) == a {
                    dsu.union(p as u32, (p + 1) as u32);
                }
                if j + 1 < ny && ins(p + sy) == a {
                    dsu.union(p as u32, (p + sy) as u32);
                }
                if k + 1 < nz && ins(p + sz) == a {
                    dsu.union(p as u32, (p + sz) as u32);
                }
                if i + 1 < nx && j + 1 < ny {
                    face(&mut dsu, p, 1, sy);
                }
                if i + 1 < nx && k + 1 < nz {
                    face(&mut dsu, p, 1, sz);
                }
                if j + 1 < ny && k + 1 < nz {
                    face(&mut dsu, p, sy, sz);
                }
            }
        }
    }
    // Count components: roots among inside nodes / outside nodes (+ exterior).
    let mut inside_components = 0;
    let mut outside_components = 0;
    for p in 0..=n {
        if dsu.find(p as u32) == p as u32 {
            if p < n && ins(p) {
                inside_components += 1;
            } else {
                outside_components += 1;
            }
        }
    }
    // Crossing edges: count, then collect pair seeds and strided extras.
    let bg = s.background_value();
    let aff = s.volume().affine();
    let mut edges = 0usize;
    let for_each_crossing = |f: &mut dyn FnMut(usize, isize, usize)| {
        // (node p inside, axis, neighbour q or usize::MAX for padding, direction sign)
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    let p = i + j * sy + k * sz;
                    let a = ins(p);
                    let c = [i, j, k];
                    let dims = [nx, ny, nz];
                    let st = [1, sy, sz];
                    for ax in 0..3 {
                        // + direction: grid edge or padding.
                        if c[ax] + 1 < dims[ax] {
                            let q = p + st[ax];
                            if ins(q) != a {
                                f(p, ax as isize + 1, q);
                            }
                        } else if a {
                            f(p, ax as isize + 1, usize::MAX);
                        }
                        // - direction: padding only (grid edges are seen from the other end).
                        if c[ax] == 0 && a {
                            f(p, -(ax as isize) - 1, usize::MAX);
                        }
                    }
                }
            }
        }
    };
    for_each_crossing(&mut |_, _, _| edges += 1);
    let stride = edges.div_ceil(4096).max(1);
    let mut pairs: BTreeMap<(u32, u32), (usize, isize, usize)> = BTreeMap::new();
    let mut extra_edges = Vec::new();
    let mut count = 0usize;
    for_each_crossing(&mut |p, axd, q| {
        let rp = dsu.find(p as u32);
        let rq = if q == usize::MAX {
            dsu.find(ext)
        } else {
            dsu.find(q as u32)
        };
        let key = if ins(p) { (rp, rq) } else { (rq, rp) };
        pairs.entry(key).or_insert((p, axd, q));
        if count.is_multiple_of(stride) {
            extra_edges.push((p, axd, q));
        }
        count += 1;
    });
    let point = |(p, axd, q): (usize, isize, usize)| -> DVec3 {
        let fp = s.node_value(p);
        let fq = if q == usize::MAX { bg } else { s.node_value(q) };
        let t = if fp != fq {
            (fp / (fp - fq)).clamp(0.0, 1.0)
        } else {
            0.5
        };
        let ax = axd.unsigned_abs() - 1;
        let mut dir = DVec3::ZERO;
        dir[ax] = axd.signum() as f64;
        let c = DVec3::new(
            (p % nx) as f64,
            ((p / nx) % ny) as f64,
            (p / (nx * ny)) as f64,
        );
        aff.transform_point3(c + dir * t)
    };
    let component_seeds = pairs.into_values().map(point).collect();
    let extra_seeds = extra_edges.into_iter().map(point).collect();
    Topology {
        inside_components,
        outside_components,
        surface_components: (inside_components + outside_components).saturating_sub(1),
        crossing_edges: edges,
        component_seeds,
        extra_seeds,
    }
}
