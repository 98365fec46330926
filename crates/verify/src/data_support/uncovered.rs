//! Uncovered data regions (section 6.6.3's point sets; not in the paper, which assumes S
//! known): places where the data shows surface and the mesh has none.
//!
//! A data component counts as covered when at least `min_share` of its points lie within
//! their band of the mesh, so a missing part of one connected sample passes that test while
//! it is under half the sample. Measured on real data from a registry package
//! (2026-12-06): the chameleon point set of `pymeshlab`'s wheel (`tests/sample_meshes/
//! chameleon.pts`, 4,594 points with normals) at `--size 1.0` meshes to three components,
//! and most of its tail (195 points from z = -50 to -5.7) has no mesh; the whole sample is
//! one data component, 96% covered, and `data-support` said "all covered".
//!
//! An *uncovered region* is a component of the data's kNN graph restricted to the *missed*
//! points (both ends of an edge missed), with at least `min_points` points (isolated
//! outliers and noise are single points). A point is missed when the mesh is farther from it
//! than [`MISSED`] times its coverage threshold (its band, or twice its spacing): just
//! beyond the threshold lies the approximation error of a coarse mesh (mesh inputs at the
//! default size, about 1,500 vertices: the bunny fixture's ear tips, 117 samples, and 12
//! strips along fandisk's sharp edges lie beyond it), while the chameleon's tail lies far
//! beyond. A region is listed with its point count, size and location. It is reported, not
//! (yet) a FAIL: the false-alarm measurements that a verdict needs (mesh inputs at every
//! size, open scans) have not been made.
//!
//! Invariant: deterministic (union-find over the kNN lists in index order; regions sorted
//! by size, then first point).

use glam::DVec3;
use meshio::TriMesh;
use rayon::prelude::*;
use serde::Serialize;

use crate::distance::MeshDistance;
use crate::topology::Dsu;

/// Missed: farther from the mesh than this many coverage thresholds.
pub const MISSED: f64 = 3.0;

/// A region of the data that the mesh does not cover.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct UncoveredRegion {
    /// Data points in it.
    pub points: usize,
    /// Their centroid.
    pub centroid: [f64; 3],
    /// Their bounding-box diagonal.
    pub extent: f64,
}

impl UncoveredRegion {
    /// `"N data regions the mesh does not cover (largest: P points, E across, at (x, y, z))"`,
    /// for the largest of `total`.
    pub fn describe(&self, total: usize) -> String {
        format!(
            "{total} data regions the mesh does not cover (largest: {} points, {:.3e} across, \
             at ({:.4}, {:.4}, {:.4}))",
            self.points, self.extent, self.centroid[0], self.centroid[1], self.centroid[2]
        )
    }
}

/// Each data point's distance to `mesh` (`∞` when no triangle is found) and its coverage
/// threshold (`band[i]` or twice `spacing[i]`, whichever is larger): covered when the
/// distance is at most the threshold.
pub(super) fn coverage_distances(
    mesh: &TriMesh,
    points: &[DVec3],
    band: &[f64],
    spacing: &[f64],
) -> Vec<(f64, f64)> {
    let bvh = crate::intersect::triangle_bvh(mesh);
    let dist = MeshDistance::new(mesh, &bvh);
    (0..points.len())
        .into_par_iter()
        .map(|i| {
            let t = band[i].max(2.0 * spacing[i]);
            let d = dist.nearest(points[i]).map_or(f64::INFINITY, |(_, d)| d);
            (d, t)
        })
        .collect()
}

/// Per point of `distances` ([`coverage_distances`]): within `k` coverage thresholds of the
/// mesh (`k` = 1: covered; `k` = [`MISSED`]: not missed).
pub(super) fn within(distances: &[(f64, f64)], k: f64) -> Vec<bool> {
    distances.iter().map(|&(d, t)| d <= k * t).collect()
}

/// The point groups of the uncovered regions of at least `min_points` points, largest first
/// (ties: by first point); `knn`: the data's neighbour lists; `distances`: each point's
/// distance to the mesh and coverage threshold ([`coverage_distances`]).
pub(super) fn uncovered_groups(
    knn: &[Vec<u32>],
    distances: &[(f64, f64)],
    min_points: usize,
) -> Vec<Vec<usize>> {
    // Here "covered" means not missed.
    let covered = within(distances, MISSED);
    let n = covered.len();
    let mut dsu = Dsu::new(n);
    for (i, nb) in knn.iter().enumerate() {
        if covered[i] {
            continue;
        }
        for &j in nb {
            if !covered[j as usize] {
                dsu.union(i as u32, j);
            }
        }
    }
    let mut groups = dsu.groups((0..n).filter(|&i| !covered[i]).map(|i| (i, i as u32)));
    groups.retain(|g| g.len() >= min_points.max(2));
    // Stable: groups are in the order of their first point.
    groups.sort_by_key(|g| std::cmp::Reverse(g.len()));
    groups
}
