//! P2 for images (section 6.6.2): an estimate of d_M^inf (the smallest distance from S to its medial axis).
//!
//! Method. `min_{x ∈ S} d(x, M) = min_{m ∈ M} d(m, S)`, the smallest medial-ball radius, so we
//! look for medial points in the distance map:
//! 1. *boundary nodes*: the nearer end (by the linear crossing on the edge) of every
//!    sign-changing grid edge, and border nodes inside with a crossing towards the padding;
//!    they lie within half a voxel of S;
//! 2. an exact separable Euclidean distance transform (Felzenszwalb & Huttenlocher) to the
//!    boundary nodes, with the world length of each voxel axis: `D(x)` = distance to S within
//!    about half a voxel (inside and outside alike);
//! 3. a node (off the grid border) is on a *ridge* when no 26-neighbour `y` increases `D` at a
//!    rate `(D(y) - D(x)) / |y - x|` of [`RIDGE_RATE`] (0.5) or more. Away from M, `D` grows at
//!    rate ~1 along the normal (lattice artefacts near voxel staircases go down to 1/√3, hence
//!    0.5); at a medial point whose nearest surface points are more than 120° apart (seen from
//!    the point) it grows at rate < 0.5 in every direction;
//! 4. the thickness estimate is the smallest `D` on a ridge node;
//! 5. for greyscale images (not binary, not a label), the smallest radius of curvature at the
//!    seed points (see [`curvature_radius`]) also bounds it, since the medial axis reaches the
//!    centres of curvature: the estimate is the smaller of the two, clamped below by the
//!    smallest voxel size;
//! 6. a two-valued image with contacts (voxels touching only along an edge,
//!    see [`ImageSurface::contacts`]): at most [`CONTACT_DM_VOXELS`](super::CONTACT_DM_VOXELS)
//!    of the smallest voxel size, d_M at the necks the level leaves there.
//!
//! Accuracy (tests, voxel size 1): ball R = 12 (signed distance or binary) gives 10.9 and 10.4,
//! i.e. R minus about one voxel; a torus of tube radius 3 gives 1.7 (the estimate loses about
//! a voxel, so it is coarse for features of a few voxels, and errs on the small, safe side).
//! The ridge test misses the medial sheet's rim (centres of curvature, where the feet angle
//! tends to 0): for greyscale images the curvature bound covers it (sampled ellipsoid with
//! semi-axes 9, 6, 5: true d_M^inf = 25/9 ≈ 2.78, tested within [2, 3.2]); for binary and
//! label images it does not, and the estimate can be too large there by up to the ratio of the
//! local thickness to the curvature radius. Use it as a coarse scale, not a certified bound.
//! Cost: O(N) time, 4 bytes per voxel (plus the topology scan for the seeds).

use super::ImageSurface;
use rayon::prelude::*;

/// Ridge threshold on the growth rate of the distance map (see the module docs).
pub const RIDGE_RATE: f32 = 0.5;

/// 1D squared distance transform of `f` (in place) with sample spacing `h`.
fn edt_1d(f: &mut [f32], h: f32, v: &mut Vec<usize>, z: &mut Vec<f32>, out: &mut Vec<f32>) {
    let n = f.len();
    v.clear();
    z.clear();
    out.clear();
    out.resize(n, f32::INFINITY);
    for q in 0..n {
        if !f[q].is_finite() {
            continue;
        }
        let xq = q as f32 * h;
        loop {
            match v.last() {
                None => {
                    v.push(q);
                    z.push(f32::NEG_INFINITY);
                    break;
                }
                Some(&p) => {
                    let xp = p as f32 * h;
                    let s = ((f[q] + xq * xq) - (f[p] + xp * xp)) / (2.0 * (xq - xp));
                    if s <= *z.last().unwrap() {
                        v.pop();
                        z.pop();
                    } else {
                        v.push(q);
                        z.push(s);
                        break;
                    }
                }
            }
        }
    }
    if v.is_empty() {
        return;
    }
    let mut k = 0;
    for (q, o) in out.iter_mut().enumerate() {
        let xq = q as f32 * h;
        while k + 1 < v.len() && z[k + 1] < xq {
            k += 1;
        }
        let xp = v[k] as f32 * h;
        *o = (xq - xp) * (xq - xp) + f[v[k]];
    }
    f.copy_from_slice(out);
}

/// Distance map `D` (world units) of every grid node to the level set. `None` if no crossing.
pub(crate) fn distance_map(s: &ImageSurface) -> Option<Vec<f32>> {
    let [nx, ny, nz] = s.dims_isize().map(|v| v as usize);
    let n = nx * ny * nz;
    let sp = s.volume().spacing();
    let h = [sp.x as f32, sp.y as f32, sp.z as f32];
    let bits = s.inside_bits();
    let ins = |i: usize| (bits[i >> 6] >> (i & 63)) & 1 == 1;
    let bg = s.background_value();
    let (sy, sz) = (nx, nx * ny);
    let st = [1usize, sy, sz];
    let dims = [nx, ny, nz];
    // 1. boundary nodes: the nearer end of every sign-changing edge (and border nodes with a
    //    crossing towards the padding) get 0, all others +inf.
    let mut d = vec![f32::INFINITY; n];
    d.par_chunks_mut(nx).enumerate().for_each(|(r, row)| {
        let (j, k) = (r % ny, r / ny);
        for (i, out) in row.iter_mut().enumerate() {
            let p = i + j * sy + k * sz;
            let a = ins(p);
            let c = [i, j, k];
            let mut fp = f64::NAN; // fetched on the first sign change only
            let mut boundary = false;
            for ax in 0..3 {
                for dir in [-1isize, 1] {
                    let ci = c[ax] as isize + dir;
                    if ci < 0 || ci >= dims[ax] as isize {
                        boundary |= a && bg > 0.0;
                        continue;
                    }
                    let q = (p as isize + dir * st[ax] as isize) as usize;
                    if ins(q) == a {
                        continue;
                    }
                    if fp.is_nan() {
                        fp = s.node_value(p);
                    }
                    let fq = s.node_value(q);
                    let t = if fp != fq { fp / (fp - fq) } else { 0.5 };
                    boundary |= t <= 0.5;
                }
            }
            if boundary {
                *out = 0.0;
            }
        }
    });
    if !d.iter().any(|x| x.is_finite()) {
        return None;
    }
    // 2. separable EDT: x rows, then y columns per z-slab, then z columns.
    d.par_chunks_mut(nx).for_each_init(
        || (Vec::new(), Vec::new(), Vec::new()),
        |(v, z, o), row| edt_1d(row, h[0], v, z, o),
    );
    d.par_chunks_mut(nx * ny).for_each_init(
        || (Vec::new(), Vec::new(), Vec::new(), Vec::new()),
        |(v, z, o, col), slab| {
            for i in 0..nx {
                col.clear();
                col.extend((0..ny).map(|j| slab[i + j * nx]));
                edt_1d(col, h[1], v, z, o);
                for j in 0..ny {
                    slab[i + j * nx] = col[j];
                }
            }
        },
    );
    if nz > 1 {
        // z pass, a block of 8 y-rows at a time: columns transformed in parallel into a small
        // buffer (8 * nx * nz), then copied back, so no full-size second buffer is needed.
        const B: usize = 8;
        let mut buf = vec![0f32; B * nx * nz];
        for j0 in (0..ny).step_by(B) {
            let nb = B.min(ny - j0);
            let dd = &d;
            buf[..nb * nx * nz]
                .par_chunks_mut(nz)
                .enumerate()
                .for_each_init(
                    || (Vec::new(), Vec::new(), Vec::new()),
                    |(v, z, o), (c, col)| {
                        let (jj, i) = (c / nx, c % nx);
                        let base = i + (j0 + jj) * sy;
                        for (k, x) in col.iter_mut().enumerate() {
                            *x = dd[base + k * sz];
                        }
                        edt_1d(col, h[2], v, z, o);
                    },
                );
            for jj in 0..nb {
                for i in 0..nx {
                    let col = &buf[(jj * nx + i) * nz..(jj * nx + i + 1) * nz];
                    let base = i + (j0 + jj) * sy;
                    for (k, &x) in col.iter().enumerate() {
                        d[base + k * sz] = x;
                    }
                }
            }
        }
    }
    d.par_iter_mut().for_each(|x| *x = x.sqrt());
    Some(d)
}

/// The estimate described in the module docs; `None` if the image has no crossing or no ridge.
pub(crate) fn dm_inf_estimate(s: &ImageSurface) -> Option<f64> {
    let [nx, ny, nz] = s.dims_isize().map(|v| v as usize);
    let d = distance_map(s)?;
    let sp = s.volume().spacing();
    let mut offs: Vec<(isize, f32)> = Vec::new();
    for dk in -1isize..=1 {
        for dj in -1isize..=1 {
            for di in -1isize..=1 {
                if (di, dj, dk) == (0, 0, 0) {
                    continue;
                }
                let len = ((di as f64 * sp.x).powi(2)
                    + (dj as f64 * sp.y).powi(2)
                    + (dk as f64 * sp.z).powi(2))
                .sqrt();
                offs.push((di + dj * nx as isize + dk * (nx * ny) as isize, len as f32));
            }
        }
    }
    // Axis neighbours first: off the medial axis one of them has rate >= 1/sqrt(3) > 0.5, so
    // most nodes are rejected after a few reads.
    offs.sort_by_key(|&(o, _)| {
        let a = o.unsigned_abs();
        (a != 1 && a != nx && a != nx * ny, o)
    });
    // Greyscale images: also bound by the smallest curvature radius at the seeds (binary and
    // label images are staircases at the voxel scale, where this would only see the voxels).
    let curv = if s.stats().binary.is_none() && !s.is_label() {
        curvature_radius(s)
    } else {
        None
    };
    // The estimate is min(thickness, curv): ridge nodes with D >= curv cannot lower it, so the
    // ridge test starts from that bound and skips them (same result, far fewer tests).
    let start = curv.map_or(f32::INFINITY, |c| c as f32);
    let best = (1..nz.saturating_sub(1))
        .into_par_iter()
        .map(|k| {
            let mut best = start;
            for j in 1..ny.saturating_sub(1) {
                for i in 1..nx.saturating_sub(1) {
                    let p = (i + nx * (j + ny * k)) as isize;
                    let dp = d[p as usize];
                    if !(dp < best) {
                        continue;
                    }
                    let ridge = offs
                        .iter()
                        .all(|&(o, len)| d[(p + o) as usize] - dp < RIDGE_RATE * len);
                    if ridge {
                        best = dp;
                    }
                }
            }
            best
        })
        .reduce(|| start, f32::min);
    let h = sp.x.min(sp.y).min(sp.z);
    let thickness = (best < start).then_some(best as f64);
    let est = match (thickness, curv) {
        (Some(t), Some(c)) => Some(t.min(c)),
        (t, c) => t.or(c),
    };
    // A two-valued image whose midpoint pinches the level set: the level is moved off it and
    // leaves a neck at each contact, with d_M about a sixth of a voxel (see `pinch`), finer
    // than the ridges and the clamp see.
    let contact = match s.contacts() {
        Some((n, _)) if n > 0 => super::CONTACT_DM_VOXELS * h,
        _ => f64::INFINITY,
    };
    est.map(|e| e.max(h).min(contact))
}

/// Smallest radius of curvature over the seed points (component seeds and the strided extra
/// crossings, up to ~4k points spread over the surface). Normals are the normalised gradient by
/// central differences of step `h`; the shape operator is their derivative along two tangent
/// directions, by central differences of the same step.
///
/// The step is `1.5` voxels, larger where the voxels are integers and the gradient is shallow:
/// each value then carries a rounding error of up to half a quantum `q` (`|scl_slope|`), the
/// normal an error of about `q / (2 h |grad f|)` and the curvature that over `h` again. The
/// step is widened until the normal's error is below 0.5 % (`h >= 100 q / |grad f|`), at most to
/// 8 voxels: without it, a smooth 16-bit ramp of 10 units per voxel reads as a curvature radius
/// of about a third of the true one (quantization noise, maximised over thousands of seeds).
pub(crate) fn curvature_radius(s: &ImageSurface) -> Option<f64> {
    use crate::Surface;
    use glam::DVec3;
    let sp = s.volume().spacing();
    let voxel = sp.x.min(sp.y).min(sp.z);
    let h0 = 1.5 * voxel;
    let q = if s.volume().dtype().is_integer() {
        s.volume().scaling().0.abs()
    } else {
        0.0
    };
    let gradient = |p: DVec3, h: f64| crate::roots::central_difference(|q| s.value(q), p, h);
    let normal = |p: DVec3, h: f64| -> Option<DVec3> {
        let g = gradient(p, h);
        let l = g.length();
        (l > 0.0 && l.is_finite()).then(|| g / l)
    };
    let t = s.topology();
    let kmax = t
        .component_seeds
        .par_iter()
        .chain(t.extra_seeds.par_iter())
        .filter_map(|&p| {
            let g = gradient(p, h0).length();
            if !(g > 0.0 && g.is_finite()) {
                return None;
            }
            let h = (100.0 * q / g).clamp(h0, 8.0 * voxel);
            let n = normal(p, h)?;
            let t1 = n.any_orthonormal_vector();
            let t2 = n.cross(t1);
            let dn = |t: DVec3| Some((normal(p + t * h, h)? - normal(p - t * h, h)?) / (2.0 * h));
            let (d1, d2) = (dn(t1)?, dn(t2)?);
            // Symmetric 2x2 shape operator in the (t1, t2) basis; largest |eigenvalue|.
            let (a, b, c) = (d1.dot(t1), 0.5 * (d1.dot(t2) + d2.dot(t1)), d2.dot(t2));
            let m = 0.5 * (a + c);
            let r = (0.25 * (a - c) * (a - c) + b * b).sqrt();
            Some((m.abs() + r).max(0.0))
        })
        .reduce(|| 0.0f64, f64::max);
    (kmax > 0.0).then(|| 1.0 / kmax)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn edt_1d_matches_brute_force() {
        let mut rng = crate::roots::SplitMix64(9);
        for len in [1usize, 2, 7, 40] {
            for _ in 0..50 {
                let f: Vec<f32> = (0..len)
                    .map(|_| {
                        if rng.next_f64() < 0.3 {
                            (rng.next_f64() * 4.0) as f32
                        } else {
                            f32::INFINITY
                        }
                    })
                    .collect();
                let h = 0.7f32;
                let brute: Vec<f32> = (0..len)
                    .map(|q| {
                        (0..len)
                            .map(|p| ((q as f32 - p as f32) * h).powi(2) + f[p])
                            .fold(f32::INFINITY, f32::min)
                    })
                    .collect();
                let mut g = f.clone();
                edt_1d(&mut g, h, &mut Vec::new(), &mut Vec::new(), &mut Vec::new());
                for (a, b) in g.iter().zip(&brute) {
                    assert!(
                        a == b || (a - b).abs() < 1e-4 * (1.0 + b),
                        "{g:?} vs {brute:?}"
                    );
                }
            }
        }
    }
}
#[cfg(test)]
mod curvature_tests {
    use crate::image::{ImageOptions, ImageSurface, synthetic};
    use glam::DVec3;

    /// The tanglecube's smallest radius of curvature, from its analytic Hessian at 200k random
    /// points projected onto the surface.
    fn analytic_min_radius() -> f64 {
        let f = synthetic::tanglecube;
        let g = |p: DVec3| 4.0 * p * p * p - 10.0 * p;
        let mut rng = crate::roots::SplitMix64(5);
        let mut kmax: f64 = 0.0;
        for _ in 0..200_000 {
            let mut p = (DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) - 0.5) * 5.2;
            for _ in 0..40 {
                let gg = g(p);
                p -= gg * (f(p) / gg.length_squared());
            }
            if f(p).abs() > 1e-9 {
                continue;
            }
            let gg = g(p);
            let gl = gg.length();
            let n = gg / gl;
            let hdiag = 12.0 * p * p - DVec3::splat(10.0);
            let t1 = n.any_orthonormal_vector();
            let t2 = n.cross(t1);
            let h = |u: DVec3, v: DVec3| (u * hdiag * v).element_sum() / gl;
            let (a, b, c) = (h(t1, t1), h(t1, t2), h(t2, t2));
            let r = (0.25 * (a - c) * (a - c) + b * b).sqrt();
            kmax = kmax.max(0.5 * (a + c).abs() + r);
        }
        1.0 / kmax
    }

    #[test]
    fn curvature_radius_of_the_tanglecube() {
        let exact = analytic_min_radius();
        assert!((exact - 0.206).abs() < 0.003, "{exact}");
        let dark = ImageOptions {
            iso: Some(0.0),
            dark_foreground: true,
            ..Default::default()
        };
        let s = ImageSurface::new(synthetic::tanglecube_volume(64), &dark).unwrap();
        let r = super::curvature_radius(&s).unwrap();
        // 64^3 (voxel 0.083): measured 0.240; 128^3: 0.215.
        assert!(r > exact * 0.9 && r < exact * 1.25, "{r} vs {exact}");
    }
}
