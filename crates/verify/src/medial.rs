//! Estimating d_M, the distance to the medial axis, from a dense sample of S by Voronoi
//! poles (Amenta & Bern): the poles of the samples approximate the medial axis, so the
//! distance from a point to the nearest pole estimates d_M there.

use delaunay3::{Triangulation, VertexId};
use glam::DVec3;
use thiserror::Error;

use crate::bvh::{Aabb, Bvh};

#[derive(Debug, Error, Clone, PartialEq)]
/// Why d_M could not be estimated.
pub enum MedialError {
    #[error("d_M estimate: sample {index} is not a valid point ({source}); remove it")]
    BadSample {
        index: usize,
        source: delaunay3::Error,
    },
    #[error(
        "d_M estimate: the {0} samples are coplanar or too few (need 4 affinely independent \
         points); give a dense sample of the surface"
    )]
    Flat(usize),
    #[error(
        "d_M estimate: normals has {normals} entries for {samples} samples; give one per sample"
    )]
    NormalCount { samples: usize, normals: usize },
    #[error("d_M estimate: no Voronoi pole found (the sample is too small)")]
    NoPoles,
}

/// Poles of a sample and a nearest-pole index: `dm(x)` = distance from `x` to the nearest
/// pole, an estimate of d_M(x) for points near S.
pub struct MedialAxisEstimate {
    pub poles: Vec<DVec3>,
    bvh: Bvh,
}

impl MedialAxisEstimate {
    /// Compute the poles of `samples` (with optional outward or inward normals, one per
    /// sample, used to pick the two poles on opposite sides).
    ///
    /// Without normals the first pole of a sample is the farthest vertex of its Voronoi cell
    /// (none if the cell is unbounded: the pole is at infinity) and the second the farthest
    /// vertex on the other side of the sample (negative dot product with the first pole's
    /// direction, or with the averaged hull normal for an unbounded cell).
    pub fn new(samples: &[DVec3], normals: Option<&[DVec3]>) -> Result<Self, MedialError> {
        if let Some(n) = normals
            && n.len() != samples.len()
        {
            return Err(MedialError::NormalCount {
                samples: samples.len(),
                normals: n.len(),
            });
        }
        for (i, &p) in samples.iter().enumerate() {
            delaunay3::validate_point(p)
                .map_err(|source| MedialError::BadSample { index: i, source })?;
        }
        // Spatially sorted insertion (several times faster than input order on large samples).
        let mut dt = Triangulation::new();
        let vid: Vec<VertexId> = dt
            .insert_bulk(samples)
            .map_err(|source| MedialError::BadSample { index: 0, source })?;
        if dt.dimension() < 3 {
            return Err(MedialError::Flat(samples.len()));
        }
        let nv = dt.num_vertices();
        // Per Delaunay vertex: a reference direction (normal or first-pole direction or
        // outward hull direction), the best pole on each side.
        let mut sample_of_vertex = vec![usize::MAX; nv];
        for (i, &v) in vid.iter().enumerate() {
            if sample_of_vertex[v as usize] == usize::MAX {
                sample_of_vertex[v as usize] = i;
            }
        }
        let point = |v: VertexId| dt.point(v);
        let cells: Vec<u32> = dt.finite_cells().collect();
        let mut hull_dir = vec![DVec3::ZERO; nv];
        let mut far = vec![(0.0f64, DVec3::ZERO); nv]; // farthest Voronoi vertex
        for &c in &cells {
            let vs = dt.cell_vertices(c);
            let cc = dt.circumcenter(c);
            for (k, &v) in vs.iter().enumerate() {
                let d = (cc - point(v)).length_squared();
                if cc.is_finite() && d > far[v as usize].0 {
                    far[v as usize] = (d, cc);
                }
                let nb = dt.neighbor(c, k);
                if dt.is_infinite(nb) {
                    // Hull facet opposite v: outward normal points away from v.
                    let f: Vec<DVec3> = vs
                        .iter()
                        .enumerate()
                        .filter(|&(j, _)| j != k)
                        .map(|(_, &w)| point(w))
                        .collect();
                    let mut n = (f[1] - f[0]).cross(f[2] - f[0]);
                    if n.dot(point(v) - f[0]) > 0.0 {
                        n = -n;
                    }
                    let n = n.normalize_or_zero();
                    for (j, &w) in vs.iter().enumerate() {
                        if j != k {
                            hull_dir[w as usize] += n;
                        }
                    }
                }
            }
        }
        // Reference direction per vertex.
        let reference: Vec<(DVec3, bool)> = (0..nv)
            .map(|v| {
                let s = sample_of_vertex[v];
                if let (Some(n), true) = (normals, s != usize::MAX) {
                    (n[s], true)
                } else if hull_dir[v] != DVec3::ZERO {
                    (hull_dir[v], false) // pole at infinity on that side
                } else {
                    (far[v].1 - point(v as VertexId), true)
                }
            })
            .collect();
        let mut plus = vec![(0.0f64, None::<DVec3>); nv];
        let mut minus = vec![(0.0f64, None::<DVec3>); nv];
        for &c in &cells {
            let cc = dt.circumcenter(c);
            if !cc.is_finite() {
                continue;
            }
            for &v in &dt.cell_vertices(c) {
                let p = point(v);
                let d = (cc - p).length_squared();
                let (dir, finite_plus) = reference[v as usize];
                let side = (cc - p).dot(dir);
                let slot = if side > 0.0 {
                    if !finite_plus {
                        continue;
                    }
                    &mut plus[v as usize]
                } else if side < 0.0 {
                    &mut minus[v as usize]
                } else {
                    continue;
                };
                if d > slot.0 {
                    *slot = (d, Some(cc));
                }
            }
        }
        let mut poles: Vec<DVec3> = Vec::new();
        for v in 0..nv {
            poles.extend(plus[v].1);
            poles.extend(minus[v].1);
        }
        if poles.is_empty() {
            return Err(MedialError::NoPoles);
        }
        let bvh = Bvh::new(poles.iter().map(|&p| Aabb { min: p, max: p }).collect());
        Ok(MedialAxisEstimate { poles, bvh })
    }

    /// Estimated d_M at `x`: the distance to the nearest pole.
    pub fn dm(&self, x: DVec3) -> f64 {
        self.bvh
            .nearest(x, |i| (self.poles[i as usize] - x).length_squared())
            .map_or(f64::INFINITY, |(_, d2)| d2.sqrt())
    }
}

/// d_M estimates at the sample points themselves (see [`MedialAxisEstimate`]).
pub fn estimate_dm(samples: &[DVec3], normals: Option<&[DVec3]>) -> Result<Vec<f64>, MedialError> {
    let m = MedialAxisEstimate::new(samples, normals)?;
    Ok(samples.iter().map(|&p| m.dm(p)).collect())
}
