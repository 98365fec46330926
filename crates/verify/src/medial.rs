//! Estimating d_M, the distance to the medial axis, from a dense sample of S by Voronoi
//! poles (Amenta & Bern): the poles of the samples approximate the medial axis, so the
//! distance from a point to the nearest pole estimates d_M there.

use delaunay3::{Triangulation, VertexId};
use glam::DVec3;
use thiserror::Error;

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
    tree: geom::kdtree::PointTree,
}

impl MedialAxisEstimate {
    /// Compute the poles of `samples` (with optional outward or inward normals, one per
    /// sample, used to pick the two poles on opposite sides).
    ///
    /// Without normals the first pole of a sample is the farthest vertex of its Voronoi cell
    /// (none if the cell is unbounded: the pole is at infinity) and the second the farthest
    /// vertex on the other side of the sample (negative dot product with the first pole's
    /// direction, or with the averaged hull normal for an unbounded cell): see
    /// [`delaunay3::poles`].
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
        let mut sample_of_vertex = vec![usize::MAX; nv];
        for (i, &v) in vid.iter().enumerate() {
            if sample_of_vertex[v.index()] == usize::MAX {
                sample_of_vertex[v.index()] = i;
            }
        }
        // The reference direction of a vertex: its sample's normal, if given.
        let (cells, centers) = circumcenters(&dt);
        let vertex_poles = poles_in_parallel(&dt, &cells, &centers, |v| {
            let s = sample_of_vertex[v.index()];
            normals.filter(|_| s != usize::MAX).map(|n| n[s])
        });
        let mut poles: Vec<DVec3> = Vec::new();
        for vp in &vertex_poles {
            poles.extend(vp.plus.map(|p| p.point));
            poles.extend(vp.minus.map(|p| p.point));
        }
        if poles.is_empty() {
            return Err(MedialError::NoPoles);
        }
        let tree = geom::kdtree::PointTree::new(&poles);
        Ok(MedialAxisEstimate { poles, tree })
    }

    /// Estimated d_M at `x`: the distance to the nearest pole.
    pub fn dm(&self, x: DVec3) -> f64 {
        self.tree
            .nearest(x)
            .map_or(f64::INFINITY, |(_, d2)| d2.sqrt())
    }
}

/// The finite cells of `dt` in [`Triangulation::finite_cells`] order and their
/// circumcenters, computed in parallel.
pub fn circumcenters(dt: &Triangulation) -> (Vec<delaunay3::CellId>, Vec<DVec3>) {
    use rayon::prelude::*;
    let cells: Vec<delaunay3::CellId> = dt.finite_cells().collect();
    let centers = cells.par_iter().map(|&c| dt.circumcenter(c)).collect();
    (cells, centers)
}

/// [`delaunay3::poles::poles_from_centers`] in parallel: the vertices split in ranges, one
/// task each ([`delaunay3::poles::poles_of_range`]); the same poles, bit for bit, whatever
/// the number of threads.
pub fn poles_in_parallel(
    dt: &Triangulation,
    cells: &[delaunay3::CellId],
    centers: &[DVec3],
    normal: impl Fn(VertexId) -> Option<DVec3> + Sync,
) -> Vec<delaunay3::VertexPoles> {
    use rayon::prelude::*;
    let nv = dt.num_vertices();
    let parts = rayon::current_num_threads().clamp(1, nv.max(1));
    let step = nv.div_ceil(parts).max(1);
    let ranges: Vec<std::ops::Range<usize>> = (0..nv)
        .step_by(step)
        .map(|a| a..(a + step).min(nv))
        .collect();
    ranges
        .into_par_iter()
        .map(|r| delaunay3::poles::poles_of_range(dt, cells, centers, &normal, r))
        .collect::<Vec<_>>()
        .concat()
}

/// d_M estimates at the sample points themselves (see [`MedialAxisEstimate`]).
pub fn estimate_dm(samples: &[DVec3], normals: Option<&[DVec3]>) -> Result<Vec<f64>, MedialError> {
    let m = MedialAxisEstimate::new(samples, normals)?;
    Ok(samples.iter().map(|&p| m.dm(p)).collect())
}
