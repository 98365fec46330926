//! Regions of zero volume (ours, P1 of section 6.6.2 on images with ties): outside regions of
//! the voxel scan whose every node has the iso value exactly.
//!
//! The scan's sign convention (inside iff value < 0) puts a node whose value equals the iso
//! value on the outside, like a symbolic perturbation of the iso value. A region made only
//! of such nodes, with no whole cell of them, encloses no volume: around it every cell's
//! corners are 0 or inside, so the trilinear interpolant is <= 0 there and `{value > 0}` is
//! empty; the region is a puncture (a point, an edge or a face of zeros) of the inside, and
//! the level set there is that zero set, not a surface. Under any perturbation of the iso
//! value toward the outside it is a blob whose volume goes to zero with the perturbation.
//! The accounting reports such components as *vanishing* instead of expecting a mesh of
//! them, and the seeding skips them (the mesher meshes the regularized solid, the interior
//! of the closure of the inside, which has no puncture). A region with a whole cell of
//! zeros encloses that cell (under the perturbation) and is a component like any other.
//!
//! Invariant: the result depends only on the node values and the union-find roots, so not
//! on the thread count.

use super::dsu::Dsu;
use crate::image::ImageSurface;

/// Per run root: whether it is the root of a vanishing outside region (indexed by run id;
/// the exterior `ext` is never vanishing).
pub(super) struct Vanishing(pub Vec<bool>);

impl Vanishing {
    /// Whether region (root) `r` vanishes.
    #[inline]
    pub fn contains(&self, r: u32) -> bool {
        self.0.get(r as usize).copied().unwrap_or(false)
    }

    /// Number of vanishing regions.
    pub fn count(&self) -> usize {
        self.0.iter().filter(|&&v| v).count()
    }
}

/// The vanishing regions among the outside runs: `runs` yields `(run, row, first x, last x,
/// inside)` for every run, `dims` the grid size, `ext` the exterior's id.
pub(super) fn find(
    s: &ImageSurface,
    dims: [usize; 3],
    runs: &[(u32, usize, usize, usize, bool)],
    dsu: &mut Dsu,
    ext: u32,
) -> Vanishing {
    let [nx, ny, nz] = dims;
    let exterior = dsu.find(ext);
    // 0: no run seen, 1: every node seen is 0, 2: some node is not 0 (or the exterior).
    let mut state = vec![0u8; ext as usize + 1];
    state[exterior as usize] = 2;
    for &(t, r, x0, x1, inside) in runs {
        if inside {
            continue;
        }
        let root = dsu.find(t) as usize;
        if state[root] == 2 {
            continue;
        }
        let zero = (x0..=x1).all(|x| s.node_value(r * nx + x) == 0.0);
        state[root] = if zero { 1 } else { 2 };
    }
    // A whole cell of zeros in a candidate region: it encloses volume.
    let zero_at = |i: isize, j: isize, k: isize| -> bool {
        i >= 0
            && j >= 0
            && k >= 0
            && (i as usize) < nx
            && (j as usize) < ny
            && (k as usize) < nz
            && s.node_value(i as usize + nx * (j as usize + ny * k as usize)) == 0.0
    };
    for &(t, r, x0, x1, inside) in runs {
        if inside {
            continue;
        }
        let root = dsu.find(t) as usize;
        if state[root] != 1 {
            continue;
        }
        let (j, k) = ((r % ny) as isize, (r / ny) as isize);
        let full_cell = (x0..=x1).any(|x| {
            let i = x as isize;
            (0..8).any(|c| {
                let (di, dj, dk) = (
                    if c & 1 == 0 { -1 } else { 0 },
                    if c & 2 == 0 { -1 } else { 0 },
                    if c & 4 == 0 { -1 } else { 0 },
                );
                (0..8).all(|q| {
                    zero_at(
                        i + di + (q & 1) as isize,
                        j + dj + ((q >> 1) & 1) as isize,
                        k + dk + ((q >> 2) & 1) as isize,
                    )
                })
            })
        });
        if full_cell {
            state[root] = 2;
        }
    }
    Vanishing(state.into_iter().map(|s| s == 1).collect())
}
