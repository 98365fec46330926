//! A node-by-node reference implementation of the voxel scan (ours, tests only): the run-based
//! [`super::compute`] is cross-checked against it.

use super::dsu::Dsu;
use super::pairs::Pairs;
use super::seeds::Topology;
use crate::image::ImageSurface;

#[inline]
fn bit(bits: &[u64], i: usize) -> bool {
    (bits[i >> 6] >> (i & 63)) & 1 == 1
}

/// Node-by-node reference implementation (tests cross-check the run-based one against it).
#[cfg(test)] // the whole file is test-only; this marks the function for the structure scan
pub(crate) fn compute_reference(s: &ImageSurface) -> Topology {
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
            let inside_joined = super::interior::face_saddle(f00, f10, f01, f11) < 0.0;
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
                if i + 1 < nx && j + 1 < ny && k + 1 < nz {
                    // Corner c = dx + 2 dy + 4 dz.
                    let at = |c: u8| {
                        p + (c & 1) as usize + ((c >> 1) & 1) as usize * sy + (c >> 2) as usize * sz
                    };
                    let g: [f64; 8] = std::array::from_fn(|c| s.node_value(at(c as u8)));
                    for j in super::interior::interior_joins(&g) {
                        dsu.union(at(j.a) as u32, at(j.b) as u32);
                    }
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
    let mut edges = 0usize;
    let for_each_crossing = |f: &mut dyn FnMut(usize, isize, usize, [usize; 3])| {
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
                                f(p, ax as isize + 1, q, c);
                            }
                        } else if a {
                            f(p, ax as isize + 1, usize::MAX, c);
                        }
                        // - direction: padding only (grid edges are seen from the other end).
                        if c[ax] == 0 && a {
                            f(p, -(ax as isize) - 1, usize::MAX, c);
                        }
                    }
                }
            }
        }
    };
    let node_runs: Vec<(u32, usize, usize, usize, bool)> = (0..n)
        .map(|p| (p as u32, p / nx, p % nx, p % nx, ins(p)))
        .collect();
    let vanishing = super::vanishing::find(s, [nx, ny, nz], &node_runs, &mut dsu, ext);
    for_each_crossing(&mut |_, _, _, _| edges += 1);
    let stride = edges.div_ceil(4096).max(1);
    let mut pairs = Pairs::default();
    let mut extra_edges = Vec::new();
    let mut count = 0usize;
    for_each_crossing(&mut |p, axd, q, c| {
        let rp = dsu.find(p as u32);
        let rq = if q == usize::MAX {
            dsu.find(ext)
        } else {
            dsu.find(q as u32)
        };
        let key = if ins(p) { (rp, rq) } else { (rq, rp) };
        pairs.add(key, (p, axd, q), c);
        if count.is_multiple_of(stride) && !vanishing.contains(key.1) {
            extra_edges.push((p, axd, q));
        }
        count += 1;
    });
    pairs.finish(
        s,
        dsu.find(ext),
        (inside_components, outside_components),
        edges,
        extra_edges,
        &vanishing,
    )
}
