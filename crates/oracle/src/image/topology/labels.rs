//! Region labels of the voxel scan (ours, P1 of section 6.6.2): on which surface component of
//! [`Topology`](super::Topology) a point of S lies, from the regions of its cell's corners.

use glam::DVec3;

/// The union-find roots of the scan's runs, and the (inside, outside) region pairs in the
/// order of [`Topology::component_seeds`](super::Topology::component_seeds).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Labels {
    pub dims: [usize; 3],
    /// First run of each row (rows along x, row index j + ny k), then the run count.
    pub row_first: Vec<usize>,
    /// Start x of each run.
    pub run_x: Vec<u32>,
    /// Region (union-find root) of each run.
    pub run_root: Vec<u32>,
    /// Whether each run is inside.
    pub run_ins: Vec<bool>,
    /// The unbounded outside region (the padding).
    pub exterior: u32,
    /// The component pairs (inside region, outside region), sorted.
    pub pairs: Vec<(u32, u32)>,
}

impl Labels {
    /// Region and side of node (i, j, k); the padding outside the grid is the exterior.
    pub(crate) fn region(&self, [i, j, k]: [i64; 3]) -> (u32, bool) {
        let [nx, ny, nz] = self.dims.map(|d| d as i64);
        if i < 0 || j < 0 || k < 0 || i >= nx || j >= ny || k >= nz {
            return (self.exterior, false);
        }
        let r = (j + ny * k) as usize;
        let (lo, hi) = (self.row_first[r], self.row_first[r + 1]);
        let t = lo + self.run_x[lo..hi].partition_point(|&s| s as i64 <= i) - 1;
        (self.run_root[t], self.run_ins[t])
    }

    /// The component (index into the topology's pairs) of the point at voxel coordinates `v`,
    /// a point of S: the pair of the nearest inside and outside corners of its cell that
    /// touch (the next nearest when they do not). A point on a face, an edge or a node of the
    /// grid (a crossing at a node whose value equals the iso value) is in several cells: when
    /// the cell of `v.floor()` has no touching pair, the others are tried, in a fixed order.
    /// `None` if no pair of corners touches.
    pub fn component_at(&self, v: DVec3) -> Option<usize> {
        if !v.is_finite() {
            return None;
        }
        let c = v.floor();
        self.component_in_cell(v, c).or_else(|| {
            // The other cells holding v: one step down on each axis where v is on a face.
            let on = [0, 1, 2].map(|a| v[a] == c[a]);
            (1..8usize)
                .filter(|m| (0..3).all(|a| m & (1 << a) == 0 || on[a]))
                .find_map(|m| {
                    let d =
                        DVec3::new((m & 1) as f64, ((m >> 1) & 1) as f64, ((m >> 2) & 1) as f64);
                    self.component_in_cell(v, c - d)
                })
        })
    }

    /// [`Labels::component_at`] from the corners of the cell with origin `c`.
    fn component_in_cell(&self, v: DVec3, c: DVec3) -> Option<usize> {
        // The corners by side, on the stack (8 in all).
        let mut ins = [(0.0f64, 0u32); 8];
        let mut outs = [(0.0f64, 0u32); 8];
        let (mut ni, mut no) = (0, 0);
        for k in 0..8 {
            let o = DVec3::new((k & 1) as f64, ((k >> 1) & 1) as f64, (k >> 2) as f64);
            let p = c + o;
            let (root, inside) = self.region([p.x as i64, p.y as i64, p.z as i64]);
            let d = p.distance_squared(v);
            if inside {
                ins[ni] = (d, root);
                ni += 1;
            } else {
                outs[no] = (d, root);
                no += 1;
            }
        }
        let (ins, outs) = (&mut ins[..ni], &mut outs[..no]);
        ins.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        outs.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        for &(_, a) in ins.iter() {
            for &(_, b) in outs.iter() {
                if let Ok(i) = self.pairs.binary_search(&(a, b)) {
                    return Some(i);
                }
            }
        }
        None
    }
}
