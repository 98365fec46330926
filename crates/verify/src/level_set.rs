//! Exact distances to an image's level set (ours; the trilinear surface of section 6.6.2).
//!
//! An image's value is trilinear in every voxel cell, hence a convex combination of the cell's
//! 8 corner values: a cell (or any axis-aligned sub-box, whose corner values are again those of
//! the same trilinear polynomial) whose corners are all strictly of one sign holds no point of
//! S. Along an edge of a box the polynomial is linear, so a sign change there gives an exact
//! point of S. [`LevelSet::nearest`] is a branch and bound on these two facts: boxes are
//! visited by increasing distance from the query (a min-max pyramid of the node signs skips
//! uniform regions), mixed boxes are split in 8 and give points of S on their edges, until
//! the nearest point found is within the tolerance of the lower bound. The answer is a
//! measurement with a stated gap, not a projection that may stall or land on a far sheet.
//!
//! [`LevelSet::edge_crossings`] gives the points of S on the voxel edges (the vertices of
//! marching cubes at the same level): since a trilinear function is harmonic, every piece of
//! S in a cell reaches an edge of the cell (no interior extremum), so every point of S is
//! within a cell diagonal of one of them ([`LevelSet::covering_radius`]).

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use glam::{DAffine3, DVec3};
use oracle::Surface;
use oracle::image::{ImageSurface, trilinear};
use rayon::prelude::*;

/// Pyramid levels from this one up store the node signs of their blocks (2^level cells a side).
const STORED_FROM: u32 = 1;
/// Newton steps of [`LevelSet::seed`].
const SEED_STEPS: usize = 2;
/// Heap pops after which [`LevelSet::nearest`] stops with the bounds it has.
const MAX_POPS: usize = 1 << 16;
/// Relative part of the tolerance of [`LevelSet::nearest`] (of the distance).
const REL_TOL: f64 = 1e-2;
/// Absolute part of the tolerance (of the smallest voxel size).
const ABS_TOL: f64 = 5e-2;
/// The same parts for [`Precision::Coarse`].
const COARSE_REL_TOL: f64 = 1e-1;
const COARSE_ABS_TOL: f64 = 2.5e-1;

/// How close [`LevelSet::nearest_with`] brings its bounds together.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Precision {
    /// Within max(1% of the distance, 5% of the smallest voxel size): [`LevelSet::tolerance`].
    Fine,
    /// Within max(10% of the distance, 25% of the smallest voxel size): enough for means and
    /// to tell which samples may hold the maximum, at a fraction of the work.
    Coarse,
}

/// Sign flags of a set of node values: some positive, some negative, some zero.
const POS: u8 = 1;
const NEG: u8 = 2;
const ZERO: u8 = 4;

fn flags(v: f64) -> u8 {
    if v > 0.0 {
        POS
    } else if v < 0.0 {
        NEG
    } else {
        ZERO
    }
}

/// The flags allow a zero (not all strictly of one sign).
fn mixed(f: u8) -> bool {
    f != POS && f != NEG
}

/// The zero set of an image's trilinear interpolant, with a pyramid of the node signs.
pub struct LevelSet<'a> {
    img: &'a ImageSurface,
    w2v: DAffine3,
    v2w: DAffine3,
    /// The voxel axes map to world axes (a diagonal linear part): world boxes are exact.
    axis_aligned: bool,
    /// A lower bound of the smallest singular value of the voxel-to-world map.
    sigma_min: f64,
    /// Cells (origins) where S can be: `-1..=n-1` per axis (the value is background beyond).
    n: [i64; 3],
    /// Smallest world length of a voxel edge.
    h: f64,
    /// `levels[l - STORED_FROM]`: flags of the blocks of level l (2^l cells a side, origins
    /// shifted by one cell so that indices start at 0), x fastest.
    levels: Vec<(Vec<u8>, [usize; 3])>,
    top: u32,
    /// [`LevelSet::covering_radius`], kept.
    cover: f64,
}

/// What [`LevelSet::nearest`] found: the distance to S lies in `[lower, upper]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Nearest {
    /// The nearest point of S found (`None`: no point of S, e.g. an empty level set).
    pub point: Option<DVec3>,
    /// Distance to `point` (infinite without one).
    pub upper: f64,
    /// A certified lower bound of the distance to S.
    pub lower: f64,
}

impl<'a> LevelSet<'a> {
    /// Scan the image's nodes once (in parallel) for the sign pyramid.
    pub fn new(img: &'a ImageSurface) -> LevelSet<'a> {
        let w2v = img.world_to_voxel();
        let v2w = w2v.inverse();
        let m = v2w.matrix3;
        let axis_aligned = m.x_axis.y == 0.0
            && m.x_axis.z == 0.0
            && m.y_axis.x == 0.0
            && m.y_axis.z == 0.0
            && m.z_axis.x == 0.0
            && m.z_axis.y == 0.0;
        let inv = w2v.matrix3;
        let frob = (inv.x_axis.length_squared()
            + inv.y_axis.length_squared()
            + inv.z_axis.length_squared())
        .sqrt();
        let d = img.volume().dims();
        let n = [d[0] as i64, d[1] as i64, d[2] as i64];
        let h = m
            .x_axis
            .length()
            .min(m.y_axis.length())
            .min(m.z_axis.length());
        let mut ls = LevelSet {
            img,
            w2v,
            v2w,
            axis_aligned,
            sigma_min: 1.0 / frob,
            n,
            h,
            levels: Vec::new(),
            top: 0,
            cover: 0.0,
        };
        ls.cover = ls.covering_radius();
        ls.build_pyramid();
        ls
    }

    /// Signed value of node `(i, j, k)` (background outside the grid).
    fn node(&self, i: i64, j: i64, k: i64) -> f64 {
        self.img.grid_value([i, j, k])
    }

    fn build_pyramid(&mut self) {
        // Cells -1..=n-1: n + 1 a side; blocks of level STORED_FROM.
        let b = 1i64 << STORED_FROM;
        let cells = self.n.map(|x| x + 1);
        let nb = cells.map(|c| ((c + b - 1) / b) as usize);
        let layer = nb[0] * nb[1];
        let base: Vec<u8> = (0..nb[2])
            .into_par_iter()
            .flat_map_iter(|bz| {
                let mut f = vec![0u8; layer];
                // Nodes of the blocks of this layer: shifted node index s = node + 1, block
                // bz holds the nodes s in [bz b, bz b + b].
                let z0 = bz as i64 * b;
                for sz in z0..=(z0 + b).min(cells[2]) {
                    for sy in 0..=cells[1] {
                        for sx in 0..=cells[0] {
                            let fl = flags(self.node(sx - 1, sy - 1, sz - 1));
                            let bxs = block_span(sx, b, nb[0]);
                            let bys = block_span(sy, b, nb[1]);
                            for by in bys.clone() {
                                for bx in bxs.clone() {
                                    f[bx + nb[0] * by] |= fl;
                                }
                            }
                        }
                    }
                }
                f
            })
            .collect();
        self.levels.push((base, nb));
        let mut l = STORED_FROM;
        while self
            .levels
            .last()
            .is_some_and(|(_, d)| d.iter().any(|&x| x > 1))
        {
            let (prev, pd) = self.levels.last().expect("a level");
            let nd = pd.map(|x| x.div_ceil(2));
            let mut f = vec![0u8; nd[0] * nd[1] * nd[2]];
            for z in 0..pd[2] {
                for y in 0..pd[1] {
                    for x in 0..pd[0] {
                        f[x / 2 + nd[0] * (y / 2 + nd[1] * (z / 2))] |=
                            prev[x + pd[0] * (y + pd[1] * z)];
                    }
                }
            }
            self.levels.push((f, nd));
            l += 1;
        }
        self.top = l;
    }

    /// World length of a cell's longest diagonal: every point of S is within it of an edge
    /// crossing.
    pub fn covering_radius(&self) -> f64 {
        let m = self.v2w.matrix3;
        [
            DVec3::new(1.0, 1.0, 1.0),
            DVec3::new(-1.0, 1.0, 1.0),
            DVec3::new(1.0, -1.0, 1.0),
            DVec3::new(1.0, 1.0, -1.0),
        ]
        .iter()
        .map(|d| (m * *d).length())
        .fold(0.0, f64::max)
    }

    /// The gap [`LevelSet::nearest`] aims at for a distance `d`: 1% of `d` or 5% of the
    /// smallest voxel size, whichever is larger.
    pub fn tolerance(&self, d: f64) -> f64 {
        self.tolerance_at(Precision::Fine, d)
    }

    /// The gap aimed at for a distance `d` at precision `prec`.
    pub fn tolerance_at(&self, prec: Precision, d: f64) -> f64 {
        let (rel, abs) = match prec {
            Precision::Fine => (REL_TOL, ABS_TOL),
            Precision::Coarse => (COARSE_REL_TOL, COARSE_ABS_TOL),
        };
        if d.is_finite() {
            (rel * d).max(abs * self.h)
        } else {
            abs * self.h
        }
    }

    /// Lower bound of the world distance from `p` (voxel `u`) to the voxel box `[lo, hi]`.
    fn lower(&self, p: DVec3, u: DVec3, lo: DVec3, hi: DVec3) -> f64 {
        if self.axis_aligned {
            let (a, b) = (self.v2w.transform_point3(lo), self.v2w.transform_point3(hi));
            let (wl, wh) = (a.min(b), a.max(b));
            return (p.clamp(wl, wh) - p).length();
        }
        let vox = (u.clamp(lo, hi) - u).length() * self.sigma_min;
        let c = self.v2w.transform_point3(0.5 * (lo + hi));
        let m = self.v2w.matrix3;
        let e = hi - lo;
        let r = [
            DVec3::new(e.x, e.y, e.z),
            DVec3::new(-e.x, e.y, e.z),
            DVec3::new(e.x, -e.y, e.z),
            DVec3::new(e.x, e.y, -e.z),
        ]
        .iter()
        .map(|d| 0.5 * (m * *d).length())
        .fold(0.0, f64::max);
        vox.max((p - c).length() - r)
    }

    /// Voxel box of block `(l, b)` (cells, unshifted), clipped to the cells that exist.
    fn block_box(&self, l: u32, b: [usize; 3]) -> (DVec3, DVec3) {
        let s = 1i64 << l;
        let lo = b.map(|x| x as i64 * s - 1);
        let hi = [0, 1, 2].map(|a| (lo[a] + s).min(self.n[a]));
        (
            DVec3::new(lo[0] as f64, lo[1] as f64, lo[2] as f64),
            DVec3::new(hi[0] as f64, hi[1] as f64, hi[2] as f64),
        )
    }

    fn block_flags(&self, l: u32, b: [usize; 3]) -> Option<u8> {
        if l < STORED_FROM {
            return None;
        }
        let (f, d) = &self.levels[(l - STORED_FROM) as usize];
        (b[0] < d[0] && b[1] < d[1] && b[2] < d[2]).then(|| f[b[0] + d[0] * (b[1] + d[1] * b[2])])
    }

    /// The nearest point of S to `p`, to within [`LevelSet::tolerance`] (or the bounds
    /// reached after a fixed amount of work: `upper - lower` says how far from it).
    pub fn nearest(&self, p: DVec3) -> Nearest {
        self.nearest_with(p, Precision::Fine)
    }

    /// [`LevelSet::nearest`] to within [`LevelSet::tolerance_at`] `prec`.
    pub fn nearest_with(&self, p: DVec3, prec: Precision) -> Nearest {
        let tol = |d: f64| self.tolerance_at(prec, d);
        let u = self.w2v.transform_point3(p);
        let mut st = Search {
            best: Nearest {
                point: None,
                upper: f64::INFINITY,
                lower: 0.0,
            },
            floor: f64::INFINITY,
            pruned: f64::INFINITY,
            heap: BinaryHeap::new(),
            items: Vec::new(),
        };
        if !p.is_finite() {
            return st.best;
        }
        if let Some(q) = self.seed(p) {
            st.best.point = Some(q);
            st.best.upper = (q - p).length();
        }
        let (lo, hi) = self.block_box(self.top, [0; 3]);
        st.push(self.lower(p, u, lo, hi), Item::Block(self.top, [0; 3]));
        let mut pops = 0;
        while let Some(Reverse((lb, idx))) = st.heap.pop() {
            let lb = f64::from_bits(lb);
            if lb >= st.best.upper - tol(st.best.upper) || pops >= MAX_POPS {
                st.best.lower = lb.min(st.floor).min(st.pruned).min(st.best.upper);
                return st.best;
            }
            pops += 1;
            let item = st.items[idx];
            match item {
                Item::Block(l, b) => {
                    if self.block_flags(l, b).is_some_and(|f| !mixed(f)) {
                        continue;
                    }
                    if l == 0 {
                        let (o, _) = self.block_box(0, b);
                        let c = self.cell_corners(o);
                        self.visit_box(p, u, SubBox { o, s: 1.0, c }, &mut st, &tol);
                        continue;
                    }
                    for k in 0..8 {
                        let cb = [0, 1, 2].map(|a| 2 * b[a] + ((k >> a) & 1));
                        let (lo, hi) = self.block_box(l - 1, cb);
                        if lo.cmplt(hi).all() {
                            st.push(self.lower(p, u, lo, hi), Item::Block(l - 1, cb));
                        }
                    }
                }
                Item::Box(bx) => {
                    for child in bx.children() {
                        self.visit_box(p, u, child, &mut st, &tol);
                    }
                }
            }
        }
        // Every box was examined or dropped as smaller than the tolerance.
        st.best.lower = st.floor.min(st.pruned).min(st.best.upper);
        st.best
    }

    /// A point of S near `p`, to start [`LevelSet::nearest`] with a small upper bound: a few
    /// Newton steps on the interpolant, then the image's crossing oracle on the segment from
    /// `p` to one and a half times the step, when the sign changes there (`None` otherwise).
    /// Only the bound's value depends on it, never the lower bound: the search still proves
    /// that nothing of S is nearer than its tolerance allows.
    fn seed(&self, p: DVec3) -> Option<DVec3> {
        let f0 = self.img.value(p);
        if f0 == 0.0 {
            return Some(p);
        }
        let reach = 2.0 * self.cover;
        let mut q = p;
        for _ in 0..SEED_STEPS {
            let (f, g) = (self.img.value(q), self.img.gradient(q));
            let gg = g.length_squared();
            if !(gg > 0.0 && f.is_finite()) {
                return None;
            }
            q -= g * (f / gg);
            let moved = (q - p).length();
            if moved.is_nan() || moved > reach {
                return None;
            }
        }
        let far = p + (q - p) * 1.5;
        let ff = self.img.value(far);
        if ff == 0.0 {
            return Some(far);
        }
        ((ff < 0.0) != (f0 < 0.0)).then(|| self.img.crossing(p, f0, far, ff))
    }

    fn cell_corners(&self, o: DVec3) -> [f64; 8] {
        let (i, j, k) = (o.x as i64, o.y as i64, o.z as i64);
        std::array::from_fn(|c| {
            self.node(
                i + (c & 1) as i64,
                j + ((c >> 1) & 1) as i64,
                k + ((c >> 2) & 1) as i64,
            )
        })
    }

    /// A box (a cell or part of one): nothing if it holds no zero; else its edge crossings
    /// update the best point and, when it is larger than the tolerance, it goes back to the
    /// heap to be split (a smaller one only lowers the floor of the lower bound).
    fn visit_box(&self, p: DVec3, u: DVec3, bx: SubBox, st: &mut Search, tol: &dyn Fn(f64) -> f64) {
        let SubBox { o, s, c } = bx;
        let f = c.iter().fold(0u8, |f, &v| f | flags(v));
        if !mixed(f) {
            return;
        }
        let corner = |k: usize| {
            o + DVec3::new(
                (k & 1) as f64 * s,
                ((k >> 1) & 1) as f64 * s,
                ((k >> 2) & 1) as f64 * s,
            )
        };
        let best = &mut st.best;
        let mut consider = |v: DVec3| {
            let q = self.v2w.transform_point3(v);
            let d = (q - p).length();
            if d < best.upper {
                best.upper = d;
                best.point = Some(q);
            }
        };
        for a in 0..8 {
            if c[a] == 0.0 {
                consider(corner(a));
            }
            for bit in [1usize, 2, 4] {
                let b = a | bit;
                if a & bit == 0 && (c[a] > 0.0 && c[b] < 0.0 || c[a] < 0.0 && c[b] > 0.0) {
                    let t = c[a] / (c[a] - c[b]);
                    consider(corner(a).lerp(corner(b), t));
                }
            }
        }
        let lb = self.lower(p, u, o, o + DVec3::splat(s));
        if lb >= st.best.upper - tol(st.best.upper) {
            st.pruned = st.pruned.min(lb);
            return;
        }
        if self.cover * s > tol(lb) {
            st.push(lb, Item::Box(bx));
        } else {
            st.floor = st.floor.min(lb);
        }
    }

    /// The points of S on the voxel edges (each edge once; a tied node when it is on the
    /// boundary of the regularized solid, [`Self::node_on_boundary`]), in a fixed
    /// order: the vertices of marching cubes at the same level.
    pub fn edge_crossings(&self) -> Vec<DVec3> {
        let b = 1i64 << STORED_FROM;
        let (f, d) = &self.levels[0];
        let d = *d;
        let per_layer: Vec<Vec<DVec3>> = (0..d[2])
            .into_par_iter()
            .map(|bz| {
                let mut out = Vec::new();
                for by in 0..d[1] {
                    for bx in 0..d[0] {
                        if !mixed(f[bx + d[0] * (by + d[1] * bz)]) {
                            continue;
                        }
                        self.block_crossings([bx, by, bz].map(|x| x as i64 * b - 1), b, &mut out);
                    }
                }
                out
            })
            .collect();
        per_layer.concat()
    }

    /// Whether node `(i, j, k)`, whose value is 0 (a tie with the iso value), is a point of the
    /// boundary of the regularized solid: the inside reaches it (an edge neighbour is inside,
    /// `< 0`: the interpolant is negative along that edge) and so does an outside with volume
    /// (an edge neighbour is `> 0`, or one of the 8 cells around the node has no inside
    /// corner: under the scan's convention, which puts a tie outside, that cell is outside).
    /// Marching cubes puts a vertex at every tied node with an inside edge neighbour (its
    /// crossing at `t = 0`); the nodes left out are the punctures of the inside (a point, a
    /// line or a face of ties with no outside cell around it: `oracle`'s vanishing regions),
    /// where the regularized solid has no surface, and the ties with no inside neighbour.
    fn node_on_boundary(&self, i: i64, j: i64, k: i64) -> bool {
        const STEPS: [(i64, i64, i64); 6] = [
            (1, 0, 0),
            (-1, 0, 0),
            (0, 1, 0),
            (0, -1, 0),
            (0, 0, 1),
            (0, 0, -1),
        ];
        let nb = STEPS.map(|(a, b, c)| self.node(i + a, j + b, k + c));
        if !nb.iter().any(|&w| w < 0.0) {
            return false;
        }
        if nb.iter().any(|&w| w > 0.0) {
            return true;
        }
        // Every edge neighbour is inside or a tie: look for a cell around the node with no
        // inside corner.
        (0..8).any(|c: i64| {
            let o = [i - (c & 1), j - ((c >> 1) & 1), k - ((c >> 2) & 1)];
            (0..8).all(|d: i64| {
                self.node(o[0] + (d & 1), o[1] + ((d >> 1) & 1), o[2] + ((d >> 2) & 1)) >= 0.0
            })
        })
    }

    /// Crossings on the edges leaving the nodes `o + [0, b)^3` in the +x, +y, +z directions.
    fn block_crossings(&self, o: [i64; 3], b: i64, out: &mut Vec<DVec3>) {
        for k in o[2]..(o[2] + b).min(self.n[2] + 1) {
            for j in o[1]..(o[1] + b).min(self.n[1] + 1) {
                for i in o[0]..(o[0] + b).min(self.n[0] + 1) {
                    let v = self.node(i, j, k);
                    let at = DVec3::new(i as f64, j as f64, k as f64);
                    if v == 0.0 {
                        if self.node_on_boundary(i, j, k) {
                            out.push(self.v2w.transform_point3(at));
                        }
                        continue;
                    }
                    for (di, dj, dk) in [(1, 0, 0), (0, 1, 0), (0, 0, 1)] {
                        let w = self.node(i + di, j + dj, k + dk);
                        if v > 0.0 && w < 0.0 || v < 0.0 && w > 0.0 {
                            let t = v / (v - w);
                            let e = DVec3::new(di as f64, dj as f64, dk as f64);
                            out.push(self.v2w.transform_point3(at + e * t));
                        }
                    }
                }
            }
        }
    }
}

/// Blocks (of `b` cells, shifted indices) that hold shifted node `s`: one, or two on a
/// block boundary.
fn block_span(s: i64, b: i64, nb: usize) -> std::ops::Range<usize> {
    let hi = (s / b) as usize;
    let lo = if s % b == 0 && s > 0 { hi - 1 } else { hi };
    lo..(hi + 1).min(nb)
}

/// The state of one [`LevelSet::nearest`] search.
struct Search {
    best: Nearest,
    /// Smallest lower bound of the boxes dropped as smaller than the tolerance.
    floor: f64,
    /// Smallest lower bound of the boxes dropped as no nearer than the best point minus the
    /// tolerance (with `floor` and the heap's least bound, what makes `lower` certified).
    pruned: f64,
    /// Min-heap of (lower bound bits, index in `items`): bounds are non-negative, so their
    /// bits order as the numbers; ties go to the earlier item (deterministic).
    heap: BinaryHeap<Reverse<(u64, usize)>>,
    items: Vec<Item>,
}

impl Search {
    fn push(&mut self, lb: f64, it: Item) {
        self.heap
            .push(Reverse((lb.max(0.0).to_bits(), self.items.len())));
        self.items.push(it);
    }
}

#[derive(Clone, Copy)]
enum Item {
    /// A pyramid block (level, index).
    Block(u32, [usize; 3]),
    /// A part of a cell.
    Box(SubBox),
}

/// An axis-aligned box inside a cell: origin, side (voxels), corner values (x fastest).
#[derive(Clone, Copy)]
struct SubBox {
    o: DVec3,
    s: f64,
    c: [f64; 8],
}

impl SubBox {
    /// The 8 half-size boxes, with their corner values from the same trilinear polynomial.
    fn children(&self) -> impl Iterator<Item = SubBox> + '_ {
        let g = |x: f64, y: f64, z: f64| trilinear(&self.c, DVec3::new(x, y, z));
        let h = 0.5 * self.s;
        (0..8).map(move |k| {
            let (a, b, c) = (
                (k & 1) as f64 * 0.5,
                ((k >> 1) & 1) as f64 * 0.5,
                ((k >> 2) & 1) as f64 * 0.5,
            );
            let vals = std::array::from_fn(|m| {
                g(
                    a + (m & 1) as f64 * 0.5,
                    b + ((m >> 1) & 1) as f64 * 0.5,
                    c + ((m >> 2) & 1) as f64 * 0.5,
                )
            });
            SubBox {
                o: self.o + DVec3::new(a, b, c) * self.s,
                s: h,
                c: vals,
            }
        })
    }
}
