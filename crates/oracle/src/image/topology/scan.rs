//! The run-based voxel scan (P1 for images, section 6.6.2): union-find on runs of equal sign along the grid
//! rows, with the asymptotic decider on ambiguous faces; see [`super`].
//!
//! Invariant: everything is sequential in index order (rows, then words, then bits), so the
//! union-find roots and the pairs do not depend on the thread count.

// Run indices are union-find ids and index several arrays: plain index loops are clearer.
#![allow(clippy::needless_range_loop)]

use super::dsu::Dsu;
use super::pairs::{Edge, Pairs};
use super::seeds::Topology;
use crate::image::ImageSurface;

/// The grid rows (along x) cut into runs of equal sign, from the node signs (64 nodes per
/// word, rows padded to whole words).
struct Runs<'a> {
    bits: &'a [u64],
    nx: usize,
    ny: usize,
    nz: usize,
    /// Words per row.
    w: usize,
    rows: usize,
    /// Start x of each run.
    run_x: Vec<u32>,
    /// Sign of each run (inside).
    run_ins: Vec<bool>,
    /// First run of each row, then the run count.
    row_first: Vec<usize>,
}

/// Valid node positions (x < lim) in word `wi`.
fn mask_below(wi: usize, lim: usize) -> u64 {
    let lo = wi * 64;
    if lim >= lo + 64 {
        !0
    } else if lim <= lo {
        0
    } else {
        (1u64 << (lim - lo)) - 1
    }
}

/// Asymptotic decider on a face with corners p00, p10, p01, p11 (p00 ~ p11 and p10 ~ p01
/// are the diagonals); returns whether the diagonal p00-p11 is joined (`a`: its side).
fn decide(s: &ImageSurface, p00: usize, p10: usize, p01: usize, p11: usize, a: bool) -> bool {
    let (f00, f10, f01, f11) = (
        s.node_value(p00),
        s.node_value(p10),
        s.node_value(p01),
        s.node_value(p11),
    );
    (super::interior::face_saddle(f00, f10, f01, f11) < 0.0) == a
}

impl<'a> Runs<'a> {
    /// Cut the rows of a grid of `[nx, ny, nz]` nodes with signs `bits` into runs.
    fn new([nx, ny, nz]: [usize; 3], bits: &'a [u64]) -> Runs<'a> {
        let w = nx.div_ceil(64);
        let rows = ny * nz;
        let mut runs = Runs {
            bits,
            nx,
            ny,
            nz,
            w,
            rows,
            run_x: Vec::new(),
            run_ins: Vec::new(),
            row_first: Vec::with_capacity(rows + 1),
        };
        for r in 0..rows {
            runs.row_first.push(runs.run_x.len());
            runs.run_x.push(0);
            runs.run_ins.push(runs.get(r, 0));
            for wi in 0..w {
                let mut t = runs.trans(r, wi);
                while t != 0 {
                    let x = wi * 64 + t.trailing_zeros() as usize + 1;
                    runs.run_x.push(x as u32);
                    runs.run_ins.push(runs.get(r, x));
                    t &= t - 1;
                }
            }
        }
        runs.row_first.push(runs.run_x.len());
        runs
    }

    #[inline]
    fn word(&self, r: usize, wi: usize) -> u64 {
        self.bits[r * self.w + wi]
    }

    #[inline]
    fn get(&self, r: usize, x: usize) -> bool {
        (self.bits[r * self.w + (x >> 6)] >> (x & 63)) & 1 == 1
    }

    /// Transition positions (x < nx - 1 where the sign changes between x and x + 1) in word
    /// `wi` of row `r`.
    #[inline]
    fn trans(&self, r: usize, wi: usize) -> u64 {
        let a = self.word(r, wi);
        let next = if wi + 1 < self.w {
            self.word(r, wi + 1) << 63
        } else {
            0
        };
        (a ^ ((a >> 1) | next)) & mask_below(wi, self.nx - 1)
    }

    /// The run of row `r` holding node `x`.
    fn run_of(&self, r: usize, x: usize) -> u32 {
        let (lo, hi) = (self.row_first[r], self.row_first[r + 1]);
        let k = self.run_x[lo..hi].partition_point(|&s| s as usize <= x);
        (lo + k - 1) as u32
    }

    /// The last x of run `t` of row `r`.
    fn run_end(&self, t: usize, r: usize) -> usize {
        if t + 1 < self.row_first[r + 1] {
            self.run_x[t + 1] as usize - 1
        } else {
            self.nx - 1
        }
    }

    #[inline]
    fn node(&self, r: usize, x: usize) -> usize {
        r * self.nx + x
    }

    /// Join the runs of rows `a` and `b` (neighbours along y or z): overlapping runs of equal
    /// sign, and the face diagonals decided by the saddle.
    fn link_rows(&self, s: &ImageSurface, dsu: &mut Dsu, a: usize, b: usize) {
        // 6-neighbours across rows: overlapping runs of equal sign.
        let (mut i, ie) = (self.row_first[a], self.row_first[a + 1]);
        let (mut k, ke) = (self.row_first[b], self.row_first[b + 1]);
        while i < ie && k < ke {
            if self.run_ins[i] == self.run_ins[k] {
                dsu.union(i as u32, k as u32);
            }
            let (ei, ek) = (self.run_end(i, a), self.run_end(k, b));
            if ei <= ek {
                i += 1;
            }
            if ek <= ei {
                k += 1;
            }
        }
        // Face diagonals in the plane of the two rows: both rows change sign between x and
        // x + 1, with opposite signs.
        for wi in 0..self.w {
            let mut c =
                self.trans(a, wi) & self.trans(b, wi) & (self.word(a, wi) ^ self.word(b, wi));
            while c != 0 {
                let x = wi * 64 + c.trailing_zeros() as usize;
                c &= c - 1;
                let (p00, p10, p01, p11) = (
                    self.node(a, x),
                    self.node(a, x + 1),
                    self.node(b, x),
                    self.node(b, x + 1),
                );
                if decide(s, p00, p10, p01, p11, self.get(a, x)) {
                    dsu.union(self.run_of(a, x), self.run_of(b, x + 1));
                } else {
                    dsu.union(self.run_of(a, x + 1), self.run_of(b, x));
                }
            }
        }
    }

    /// Join across the ambiguous yz faces between row `r` = (j, k) and rows (j+1, k),
    /// (j, k+1), (j+1, k+1).
    fn link_yz_faces(&self, s: &ImageSurface, dsu: &mut Dsu, r: usize) {
        let ny = self.ny;
        // yz faces: rows A = (j, k), B = (j+1, k), C = (j, k+1), D = (j+1, k+1).
        let (ra, rb, rc, rd) = (r, r + 1, r + ny, r + ny + 1);
        for wi in 0..self.w {
            let (a, b, c, d) = (
                self.word(ra, wi),
                self.word(rb, wi),
                self.word(rc, wi),
                self.word(rd, wi),
            );
            let mut amb = !(a ^ d) & !(b ^ c) & (a ^ b) & mask_below(wi, self.nx);
            while amb != 0 {
                let x = wi * 64 + amb.trailing_zeros() as usize;
                amb &= amb - 1;
                let (p00, p10, p01, p11) = (
                    self.node(ra, x),
                    self.node(rb, x),
                    self.node(rc, x),
                    self.node(rd, x),
                );
                if decide(s, p00, p10, p01, p11, self.get(ra, x)) {
                    dsu.union(self.run_of(ra, x), self.run_of(rd, x));
                } else {
                    dsu.union(self.run_of(rb, x), self.run_of(rc, x));
                }
            }
        }
    }

    /// Join the corners that the interior of a cell between rows `r` = (j, k), (j+1, k),
    /// (j, k+1) and (j+1, k+1) connects (see [`super::interior`]). Only cells with both
    /// signs among their corners can hold such a join.
    fn link_cells(&self, s: &ImageSurface, dsu: &mut Dsu, r: usize) {
        let rows = [r, r + 1, r + self.ny, r + self.ny + 1];
        for wi in 0..self.w {
            // Bits at x and x + 1 of each row, aligned at x.
            let (mut any, mut all) = (0u64, !0u64);
            for &q in &rows {
                let a = self.word(q, wi);
                let next = if wi + 1 < self.w {
                    self.word(q, wi + 1) << 63
                } else {
                    0
                };
                let b = (a >> 1) | next;
                any |= a | b;
                all &= a & b;
            }
            let mut mixed = any & !all & mask_below(wi, self.nx - 1);
            while mixed != 0 {
                let x = wi * 64 + mixed.trailing_zeros() as usize;
                mixed &= mixed - 1;
                // Corner c = dx + 2 dy + 4 dz: row rows[dy + 2 dz], node x + dx.
                let at = |c: u8| (rows[(c >> 1) as usize], x + (c & 1) as usize);
                let g: [f64; 8] = std::array::from_fn(|c| {
                    let (q, xx) = at(c as u8);
                    s.node_value(self.node(q, xx))
                });
                for j in super::interior::interior_joins(&g) {
                    let ((qa, xa), (qb, xb)) = (at(j.a), at(j.b));
                    dsu.union(self.run_of(qa, xa), self.run_of(qb, xb));
                }
            }
        }
    }

    /// The union-find of the runs (and the exterior `ext`, joined to every outside run on the
    /// grid's border).
    fn link_all(&self, s: &ImageSurface, dsu: &mut Dsu, ext: u32) {
        let (ny, nz) = (self.ny, self.nz);
        for r in 0..self.rows {
            let (j, k) = (r % ny, r / ny);
            let border_row = j == 0 || k == 0 || j + 1 == ny || k + 1 == nz;
            let (lo, hi) = (self.row_first[r], self.row_first[r + 1]);
            for t in lo..hi {
                if !self.run_ins[t] && (border_row || t == lo || t + 1 == hi) {
                    dsu.union(t as u32, ext);
                }
            }
            if j + 1 < ny {
                self.link_rows(s, dsu, r, r + 1);
            }
            if k + 1 < nz {
                self.link_rows(s, dsu, r, r + ny);
            }
            if j + 1 < ny && k + 1 < nz {
                self.link_yz_faces(s, dsu, r);
                self.link_cells(s, dsu, r);
            }
        }
    }

    /// Every sign-changing edge, in a fixed order: per row, x edges, y edges, z edges,
    /// padding; `f(edge, node coordinates, run of p, run of q)` (`ext` for the padding).
    fn for_each_edge(&self, ext: u32, f: &mut dyn FnMut(Edge, [usize; 3], u32, u32)) {
        let (nx, ny, nz) = (self.nx, self.ny, self.nz);
        let (run_x, run_ins, row_first) = (&self.run_x, &self.run_ins, &self.row_first);
        let pad = usize::MAX;
        for r in 0..self.rows {
            let (j, k) = (r % ny, r / ny);
            for t in row_first[r] + 1..row_first[r + 1] {
                let x = run_x[t] as usize - 1;
                f(
                    (self.node(r, x), 1, self.node(r, x + 1)),
                    [x, j, k],
                    t as u32 - 1,
                    t as u32,
                );
            }
            for (dr, ok, axd) in [(1usize, j + 1 < ny, 2isize), (ny, k + 1 < nz, 3)] {
                if !ok {
                    continue;
                }
                for wi in 0..self.w {
                    let mut c = (self.word(r, wi) ^ self.word(r + dr, wi)) & mask_below(wi, nx);
                    while c != 0 {
                        let x = wi * 64 + c.trailing_zeros() as usize;
                        c &= c - 1;
                        let e = (self.node(r, x), axd, self.node(r + dr, x));
                        f(e, [x, j, k], self.run_of(r, x), self.run_of(r + dr, x));
                    }
                }
            }
            let (lo, hi) = (row_first[r], row_first[r + 1]);
            if run_ins[lo] {
                f((self.node(r, 0), -1, pad), [0, j, k], lo as u32, ext);
            }
            if run_ins[hi - 1] {
                f(
                    (self.node(r, nx - 1), 1, pad),
                    [nx - 1, j, k],
                    hi as u32 - 1,
                    ext,
                );
            }
            for (on, axd) in [
                (j == 0, -2isize),
                (j + 1 == ny, 2),
                (k == 0, -3),
                (k + 1 == nz, 3),
            ] {
                if !on {
                    continue;
                }
                for t in lo..hi {
                    if run_ins[t] {
                        for x in run_x[t] as usize..=self.run_end(t, r) {
                            f((self.node(r, x), axd, pad), [x, j, k], t as u32, ext);
                        }
                    }
                }
            }
        }
    }
}

/// Run-based implementation: the grid rows (along x) are cut into runs of equal sign, the
/// union-find works on runs, and sign changes between rows are found 64 nodes at a time.
///
/// `bits` are the node signs from [`ImageSurface::inside_bits_rows`].
pub(crate) fn compute(s: &ImageSurface, bits: &[u64]) -> Topology {
    let runs = Runs::new(s.dims_isize().map(|v| v as usize), bits);
    let nruns = runs.run_x.len();
    let ext = nruns as u32;
    let mut dsu = Dsu((0..=ext).collect());
    runs.link_all(s, &mut dsu, ext);
    let mut inside_components = 0;
    let mut outside_components = 0;
    for t in 0..=nruns {
        if dsu.find(t as u32) == t as u32 {
            if t < nruns && runs.run_ins[t] {
                inside_components += 1;
            } else {
                outside_components += 1;
            }
        }
    }
    let run_list: Vec<(u32, usize, usize, usize, bool)> = (0..runs.rows)
        .flat_map(|r| {
            let runs = &runs;
            (runs.row_first[r]..runs.row_first[r + 1]).map(move |t| {
                let x0 = runs.run_x[t] as usize;
                (t as u32, r, x0, runs.run_end(t, r), runs.run_ins[t])
            })
        })
        .collect();
    let vanishing =
        super::vanishing::find(s, [runs.nx, runs.ny, runs.nz], &run_list, &mut dsu, ext);
    drop(run_list);
    let mut edges = 0usize;
    runs.for_each_edge(ext, &mut |_, _, _, _| edges += 1);
    let stride = edges.div_ceil(4096).max(1);
    let mut pairs = Pairs::default();
    let mut extra_edges = Vec::new();
    let mut count = 0usize;
    runs.for_each_edge(ext, &mut |e, c, tp, tq| {
        let (rp, rq) = (dsu.find(tp), dsu.find(tq));
        let key = if runs.run_ins[tp as usize] {
            (rp, rq)
        } else {
            (rq, rp)
        };
        pairs.add(key, e, c);
        // A vanishing region's crossings are its zero nodes: no seed of S there.
        if count.is_multiple_of(stride) && !vanishing.contains(key.1) {
            extra_edges.push(e);
        }
        count += 1;
    });
    let exterior = dsu.find(ext);
    let labels = super::labels::Labels {
        dims: [runs.nx, runs.ny, runs.nz],
        row_first: runs.row_first.clone(),
        run_x: runs.run_x.clone(),
        run_root: (0..nruns as u32).map(|t| dsu.find(t)).collect(),
        run_ins: runs.run_ins.clone(),
        exterior,
        pairs: pairs.keys(),
    };
    let mut topo = pairs.finish(
        s,
        exterior,
        (inside_components, outside_components),
        edges,
        extra_edges,
        &vanishing,
    );
    topo.labels = Some(std::sync::Arc::new(labels));
    topo
}
