//! Unsupported regions (section 6.6.3's point-set surface beyond its data; not in the paper,
//! which assumes S known): touching triangles beyond the data's band, and whether such a
//! region bridges missing data or extends past data that shows a closed surface there.
//!
//! Two measures of an unsupported region (beyond the data's band), each an area-weighted
//! median over its triangles:
//! - the data's generalized winding number `w` (Barill et al. 2018; the point cloud as small
//!   oriented disks, [`oracle::pointset::winding_disks`], the construction the point-set
//!   oracle's far field uses): about 1 inside the sampled solid, 0 outside, and 1/2 on a flat
//!   surface spanning a hole of the data (the missing patch's share jumps by one half on
//!   each side of it); on a curved surface over a hole, lower on its convex side
//!   (`(1 − sin(α/2)) / 2` at the middle of a spherical cap of angular radius α);
//! - the *alignment* ([`region_alignment`]): near 1 when the nearest data lies straight
//!   across the mesh, near 0 when it lies to its side, as a hole's rim does.
//!
//! A region with `w` below [`PAST_DATA_OUTSIDE`] (above [`PAST_DATA_INSIDE`]) and alignment
//! at least [`PAST_DATA_ALIGNMENT`] lies beside data that closes the surface there, on the
//! side the data calls outside (inside): the mesh continues past a rim or a tip (the IMLS
//! extrapolation of a thin part, the fringe of a sharp corner), a part that the data
//! contradicts, not a bridge. Measured (2026-12-05): on the scan table (`cargo xtask
//! scans`), the excursions of the six 10:1 rows that carry one have `w` 0.01-0.12 and
//! alignment 0.71-0.96; the mesher's bridges over the three missing patches `w` 0.50-0.69
//! (alignment 0.16-0.70); the bunny's own surface over an 8% hole of a scan (test
//! `a_region_past_the_data_fails_and_a_bridge_over_a_hole_does_not`) `w` 0.17, alignment
//! 0.23: low `w` alone would call that bridge an excursion (GUIDE, "Point sets and scans").
//!
//! Invariants: `w` is measured only with oriented data normals (else `None`, no verdict);
//! deterministic (a sequential area-weighted median over the region's triangle centroids).

use geom::bvh::TriangleBvh;
use glam::DVec3;
use meshio::TriMesh;
use serde::Serialize;

/// Touching unsupported triangles: where the mesh bridges missing data, or (see
/// [`past_data`]) runs past data that closes the surface there.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct UnsupportedRegion {
    pub triangles: usize,
    pub area: f64,
    pub centroid: [f64; 3],
    /// Bounding-box diagonal (the hole's size).
    pub extent: f64,
    /// Distance from the centroid to the nearest data point.
    pub distance_to_data: f64,
    /// The area-weighted median of the data's winding number over the region (with data
    /// normals; see the module documentation): about 1/2 on a bridge over missing data,
    /// near 0 or 1 where the mesh extends past data that closes the surface there.
    pub data_winding: Option<f64>,
    /// Where the data lies from the region ([`region_alignment`]): about 1 straight across
    /// the mesh, about 0 to its side.
    pub data_alignment: f64,
}

/// Below this median winding number of the data, an unsupported region lies outside the
/// sampled solid (see the module documentation).
pub const PAST_DATA_OUTSIDE: f64 = 0.25;
/// Above this, inside it.
pub const PAST_DATA_INSIDE: f64 = 0.85;

/// The data's winding disks when its normals are known (`spacing`: the band's per-point
/// spacing, `med_spacing` its median).
pub(super) fn data_winding(
    data: &[DVec3],
    normals: Option<&[DVec3]>,
    spacing: &[f64],
    med_spacing: f64,
) -> Option<TriangleBvh> {
    let n = normals.filter(|n| n.len() == data.len())?;
    Some(oracle::pointset::winding_disks(
        data,
        n,
        spacing,
        med_spacing,
    ))
}

/// The area-weighted median of the data's winding number at the centroids of the region's
/// triangles `tris` (`area(t)`: triangle `t`'s area).
pub(super) fn region_winding(
    mesh: &TriMesh,
    tris: &[usize],
    area: impl Fn(usize) -> f64,
    gwn: &TriangleBvh,
) -> f64 {
    region_median(mesh, tris, area, |[a, b, c]| {
        gwn.winding_number((a + b + c) / 3.0)
    })
}

/// The area-weighted median over the region's triangles of `|n_t · u|`, `n_t` the unit
/// facet normal and `u` the unit direction from the centroid to its nearest data point
/// (`nearest`): near 1 when the data lies straight across the mesh (a layer beside data
/// that closes the surface), near 0 when it lies to the side (the rim around a hole).
pub(super) fn region_alignment(
    mesh: &TriMesh,
    tris: &[usize],
    area: impl Fn(usize) -> f64,
    nearest: impl Fn(DVec3) -> DVec3,
) -> f64 {
    region_median(mesh, tris, area, |[a, b, c]| {
        let x = (a + b + c) / 3.0;
        let n = (b - a).cross(c - a).normalize_or_zero();
        n.dot((nearest(x) - x).normalize_or_zero()).abs()
    })
}

/// The area-weighted median of `measure` over the region's triangles `tris`.
fn region_median(
    mesh: &TriMesh,
    tris: &[usize],
    area: impl Fn(usize) -> f64,
    measure: impl Fn([DVec3; 3]) -> f64,
) -> f64 {
    let v = &mesh.vertices;
    let ws = tris
        .iter()
        .map(|&t| (measure(mesh.triangles[t].map(|i| v[i as usize])), area(t)))
        .collect();
    weighted_median(ws)
}

/// The weighted median of `(value, weight)` pairs (0.5 when empty).
fn weighted_median(mut ws: Vec<(f64, f64)>) -> f64 {
    ws.sort_by(|x, y| x.0.total_cmp(&y.0));
    let half = 0.5 * ws.iter().map(|x| x.1).sum::<f64>();
    let mut acc = 0.0;
    for &(w, a) in &ws {
        acc += a;
        if acc >= half {
            return w;
        }
    }
    ws.last().map_or(0.5, |x| x.0)
}

/// The least [`region_alignment`] of a region past the data.
pub const PAST_DATA_ALIGNMENT: f64 = 0.5;

/// Whether a region with median data winding number `w` and alignment `alignment` extends
/// past the data: the data says outside (or inside) there, and lies across the mesh rather
/// than to its side.
pub fn past_data(w: f64, alignment: f64) -> bool {
    !(PAST_DATA_OUTSIDE..=PAST_DATA_INSIDE).contains(&w) && alignment >= PAST_DATA_ALIGNMENT
}

/// The regions' part of the check's line: the regions past the data (which FAIL it), then
/// the bridges over missing data (`regions` ordered as `DataSupport` keeps them).
pub(super) fn describe(regions: &[UnsupportedRegion], total: usize, past: usize) -> String {
    let fmt_p = |p: [f64; 3]| format!("({:.4}, {:.4}, {:.4})", p[0], p[1], p[2]);
    let one = |r: &UnsupportedRegion| {
        format!(
            "{} triangles, area {:.3e}, {:.3e} across, at {}, {:.3e} from the data{}",
            r.triangles,
            r.area,
            r.extent,
            fmt_p(r.centroid),
            r.distance_to_data,
            r.data_winding
                .map_or(String::new(), |w| format!(", data winding number {w:.2}"))
        ) + &format!(", alignment {:.2}", r.data_alignment)
    };
    let mut s = String::new();
    if let Some(r) = regions.first().filter(|_| past > 0) {
        let side = match r.data_winding {
            Some(w) if w > PAST_DATA_INSIDE => "inside",
            _ => "outside",
        };
        s += &format!(
            "; {past} unsupported regions extend past the data (where its winding number says {side} the sampled solid, not a bridge over missing data; first: {})",
            one(r)
        );
    }
    if let Some(r) = regions.get(past).filter(|_| total > past) {
        s += &format!(
            "; {} unsupported regions bridged (no data; largest: {})",
            total - past,
            one(r)
        );
    }
    s
}
