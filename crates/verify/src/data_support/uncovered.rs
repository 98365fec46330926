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
//! beyond. A region is listed with its point count, size, location and its farthest point's
//! distance to the mesh, also in the mesh's median edges.
//!
//! A region is *lost*, and FAILs the check, when that distance is at least [`LOST_EDGES`]
//! median edges: the miss exceeds both the data's scale (three coverage thresholds) and the
//! mesh's own resolution, so neither noise nor a coarse mesh's chords explain it; a part of
//! the data thinner or smaller than the size has no mesh (the paper's sampling condition
//! fails there), or S has no surface there. Measured (2026-12-06, `mesh` at several sizes):
//! - no region at the default size on the bunny fixture, fandisk, fertility, and
//!   `pymeshlab`'s `bone.ply`, `airplane.obj` and `bunny.obj`, nor at half that size; none
//!   on the 50k-point bunny scan of `../shared/models` at four sizes;
//! - lost parts: `pymeshlab`'s `cow.obj` at its default size (0.043) has no mesh on three
//!   lower legs (4.4 median edges; `data-support` PASSed it, 92% of one data component
//!   covered), and at 0.03 none on the ears and horn tips (1.3-1.9 edges); the chameleon's
//!   tail (4.7-9.1 edges at three sizes); coarse meshes at 2-4 times the default size lose
//!   ear tips, a fin, a wing tip and fertility's thin arms (1.2-2.8 edges: parts below the
//!   size); no region on the 39 rows of the scan table.
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

/// Lost: an uncovered region whose farthest point is at least this many of the mesh's median
/// edges from the mesh (see the module documentation).
pub const LOST_EDGES: f64 = 1.0;

/// A region of the data that the mesh does not cover.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct UncoveredRegion {
    /// Data points in it.
    pub points: usize,
    /// Their centroid.
    pub centroid: [f64; 3],
    /// Their bounding-box diagonal.
    pub extent: f64,
    /// The distance from its farthest point to the mesh.
    pub max_distance: f64,
    /// `max_distance` over the mesh's median edge length: how many of the mesh's own edges
    /// the miss spans.
    pub distance_in_edges: f64,
}

impl UncoveredRegion {
    /// At least [`LOST_EDGES`] median edges from the mesh: FAILs the check.
    pub fn lost(&self) -> bool {
        self.distance_in_edges >= LOST_EDGES
    }

    /// The detail for `total` regions of which `lost` are lost, `self` the first (lost first,
    /// then largest): `"K data regions lost: ... (first: ...)"` or `"N data regions the mesh
    /// does not cover (largest: ...)"`.
    pub fn describe(&self, total: usize, lost: usize) -> String {
        let what = format!(
            "{} points, {:.3e} across, at ({:.4}, {:.4}, {:.4}), up to {:.3e} from the mesh = {:.1} \
             of its median edges",
            self.points,
            self.extent,
            self.centroid[0],
            self.centroid[1],
            self.centroid[2],
            self.max_distance,
            self.distance_in_edges
        );
        if lost == 0 {
            return format!("{total} data regions the mesh does not cover (largest: {what})");
        }
        format!(
            "{lost} data regions lost, the mesh farther from them than {LOST_EDGES} of its median \
             edges (first: {what}; a part thinner or smaller than the size: try a smaller --size){}",
            if total > lost {
                format!("; {} more uncovered within that", total - lost)
            } else {
                String::new()
            }
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

/// The uncovered regions of at least `min_points` points, lost first, then largest:
/// [`uncovered_groups`] measured (`points`: the data; `knn`, `distances`: as there).
pub(super) fn regions(
    mesh: &TriMesh,
    knn: &[Vec<u32>],
    points: &[DVec3],
    distances: &[(f64, f64)],
    min_points: usize,
) -> Vec<UncoveredRegion> {
    let edge = median_edge(mesh);
    let mut regions: Vec<UncoveredRegion> = uncovered_groups(knn, distances, min_points)
        .into_iter()
        .map(|g| {
            let (centroid, extent) = centroid_extent(g.iter().map(|&i| (points[i], 1.0)));
            let max_distance = g.iter().map(|&i| distances[i].0).fold(0.0, f64::max);
            UncoveredRegion {
                points: g.len(),
                centroid,
                extent,
                max_distance,
                distance_in_edges: if edge > 0.0 {
                    max_distance / edge
                } else {
                    f64::INFINITY
                },
            }
        })
        .collect();
    // Stable: lost first, each part still largest first.
    regions.sort_by_key(|r| !r.lost());
    regions
}

/// The median length of the mesh's edges (each triangle's three; an edge of two triangles
/// counts twice, which leaves the median of a closed mesh unchanged); 0 without triangles.
pub(super) fn median_edge(mesh: &TriMesh) -> f64 {
    let v = &mesh.vertices;
    let mut e: Vec<f64> = mesh
        .triangles
        .iter()
        .flat_map(|t| {
            let [a, b, c] = t.map(|i| v[i as usize]);
            [(b - a).length(), (c - b).length(), (a - c).length()]
        })
        .collect();
    if e.is_empty() {
        return 0.0;
    }
    let mid = e.len() / 2;
    *e.select_nth_unstable_by(mid, f64::total_cmp).1
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

/// Centroid (weighted) and bounding-box diagonal of weighted points.
pub(super) fn centroid_extent(pts: impl Iterator<Item = (DVec3, f64)>) -> ([f64; 3], f64) {
    let (mut c, mut w) = (DVec3::ZERO, 0.0);
    let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for (p, a) in pts {
        c += p * a;
        w += a;
        lo = lo.min(p);
        hi = hi.max(p);
    }
    let c = if w > 0.0 { c / w } else { 0.5 * (lo + hi) };
    (c.to_array(), (hi - lo).length())
}
