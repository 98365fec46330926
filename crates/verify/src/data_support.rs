//! Data support (not in the paper: the paper assumes S known; with point sets and meshes the
//! data is all we know of S): is every part of a mesh backed by the input data, and is every
//! part of the data covered by the mesh?
//!
//! - The *band* of the data: around data point `p_i`, the ball of radius
//!   `b_i = 2 s_i + 3 ν`, with `s_i` the local spacing (mean distance to the `k_spacing`
//!   nearest data points) and `ν` the estimated noise (the median over the data of the RMS
//!   distance of a point's `k_noise` nearest neighbours to their best-fit plane: the normal
//!   spread of a noisy sample, about its standard deviation), raised to [`SupportOptions::min_band`].
//! - A mesh sample is *supported* when its nearest data point `p_i` is within `b_i`. Each
//!   triangle's share is that of its samples (a barycentric grid); a mesh component is
//!   supported when at least [`SupportOptions::min_share`] of its area is.
//! - A data component (a component of the graph joining every data point to its `k_spacing`
//!   nearest neighbours and to the points within twice its spacing; pieces under [`SupportOptions::min_data_component`] points are
//!   ignored) is covered when at least `min_share` of its points lie within their band of the
//!   mesh.
//! - With oriented data normals (a point set's, given or estimated and oriented): a mesh
//!   component must also *face the way the data does*. Its *agreement* is the area-weighted
//!   mean of `n_t · n_i` over its triangles `t` (unit facet normal, outward) and `i` the data
//!   point nearest the triangle's centroid; a component below
//!   [`SupportOptions::min_agreement`] is not supported. Why this catches sheets inside the
//!   band: a closed surface's normals integrate to zero (`∮ n dA = 0`), so a closed bubble
//!   over which the data's normal is about constant (a bubble within the noise of a scan, or
//!   a pocket between two sheets) has agreement near 0, whatever its shape, while a
//!   component that follows the data has agreement near 1.
//! - The unsupported triangles (share below one half) that touch one another form the
//!   *unsupported regions*. Where the mesh bridges a hole in the data they are reported
//!   (area, size, location) and fail nothing; with data normals, a region where the data's
//!   winding number says "outside" (or "inside") extends past data that closes the surface
//!   there, and FAILs the check ([`regions`]).
//!
//! - The mesher drops the unsupported components that no data needs
//!   ([`droppable_components`], the rule of `rdt_mesher::pipeline`'s `unsupported` module);
//!   the check then runs on the mesh written and lists them
//!   ([`DataSupport::dropped_components`]).
//!
//! - The data the mesh misses inside a covered data component (a thin part with no mesh):
//!   the *uncovered regions*, listed; a region the mesh misses by more than its own median
//!   edge is *lost* and FAILs the check ([`uncovered`]).
//!
//! - A closed mesh's handles that the data does not show (a tunnel smaller than the band, or
//!   facing against the data normals): [`handles`], [`DataSupport::unsupported_handles`].
//!
//! Invariants: deterministic (parallel maps collected in order, sequential reductions); the
//! check FAILs iff some mesh component is unsupported, some data component is uncovered,
//! some data region is lost, some handle is unsupported or some unsupported region extends
//! past the data.

use glam::DVec3;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use meshio::TriMesh;
use rayon::prelude::*;
use serde::Serialize;

use crate::distance::triangle_samples;
use crate::short_loops::ShortLoops;
use crate::topology::{Dsu, vertex_components};
use uncovered::centroid_extent;

mod drop_rule;
mod handles;
pub mod regions;
mod samples;
mod uncovered;
pub use drop_rule::{Droppable, MAX_DROP_TRIES, droppable_components};
pub use handles::UnsupportedHandle;
pub use regions::UnsupportedRegion;
pub use samples::mesh_samples;
pub use uncovered::UncoveredRegion;

/// Parameters of the data-support check.
#[derive(Clone, Debug, PartialEq)]
pub struct SupportOptions {
    /// Neighbours for the local spacing (default 8).
    pub k_spacing: usize,
    /// Neighbours for the noise estimate (default 24).
    pub k_noise: usize,
    /// Least supported share of a mesh component's area, and least covered share of a data
    /// component's points (default 0.5).
    pub min_share: f64,
    /// Smallest band radius (default 0; e.g. half the mesh size for exact mesh data, where
    /// the chords of the output are farther from the input than its clean samples' spacing).
    pub min_band: f64,
    /// Data components with fewer points are not required to be covered (default 10).
    pub min_data_component: usize,
    /// Lists keep at most this many entries (default 20).
    pub max_listed: usize,
    /// Least orientation agreement of a mesh component with oriented data normals (default
    /// 0.5; see the module documentation).
    pub min_agreement: f64,
}

impl Default for SupportOptions {
    fn default() -> Self {
        SupportOptions {
            k_spacing: 8,
            k_noise: 24,
            min_share: 0.5,
            min_band: 0.0,
            min_data_component: 10,
            max_listed: 20,
            min_agreement: 0.5,
        }
    }
}

/// One mesh component's support.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct ComponentSupport {
    /// Index of its first triangle (as in [`crate::Component::first_triangle`]).
    pub first_triangle: usize,
    pub triangles: usize,
    pub area: f64,
    /// Share of the area within the band of the data.
    pub supported_share: f64,
    /// Centroid of its vertices (their mean).
    pub centroid: [f64; 3],
    /// Bounding-box diagonal.
    pub extent: f64,
    /// Orientation agreement with the data normals (area-weighted mean of `n_t · n_i`),
    /// when the data has normals.
    pub agreement: Option<f64>,
}

impl ComponentSupport {
    /// Supported: enough area in the band, and (with data normals) facing the data's way.
    pub fn supported(&self, min_share: f64, min_agreement: f64) -> bool {
        self.supported_share >= min_share && self.agreement.is_none_or(|a| a >= min_agreement)
    }
}

/// A data component and how much of it the mesh covers.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct DataComponent {
    pub points: usize,
    /// Share of its points within their band of the mesh.
    pub covered_share: f64,
    pub centroid: [f64; 3],
    pub extent: f64,
}

/// What the data-support check measured.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct DataSupport {
    pub data_points: usize,
    pub median_spacing: f64,
    /// Estimated noise ν (normal spread of the data).
    pub noise: f64,
    pub median_band: f64,
    /// The floor of every point's band ([`SupportOptions::min_band`]).
    pub min_band: f64,
    /// Share of the whole mesh area within the band.
    pub supported_share: f64,
    /// Every mesh component, in the order of [`crate::topology::vertex_components`].
    pub components: Vec<ComponentSupport>,
    pub components_total: usize,
    /// Data components of at least `min_data_component` points, largest first.
    pub data_components: Vec<DataComponent>,
    pub data_components_total: usize,
    /// Regions of the data the mesh does not cover (at least `min_data_component` points
    /// each, lost first, then largest; see [`uncovered`]): the lost ones FAIL the check.
    pub uncovered_regions: Vec<UncoveredRegion>,
    pub uncovered_regions_total: usize,
    /// Uncovered regions that are lost ([`UncoveredRegion::lost`]): each FAILs the check.
    pub lost_regions: usize,
    /// Unsupported regions: those extending past the data first, then largest area first.
    pub unsupported_regions: Vec<UnsupportedRegion>,
    pub unsupported_regions_total: usize,
    /// Unsupported regions whose data winding number says they extend past the data
    /// ([`regions::past_data`]), not bridge a hole in it.
    pub regions_past_data: usize,
    /// Mesh components below `min_share` (or, with data normals, below `min_agreement`),
    /// and data components not covered.
    pub unsupported_components: usize,
    pub uncovered_data_components: usize,
    pub min_share: f64,
    /// The least orientation agreement asked (when the data has normals).
    pub min_agreement: Option<f64>,
    /// Components of the mesher's raw output that the mesher dropped as unsupported before
    /// this check ran (see [`droppable_components`]; empty when none was, or the mesh was
    /// not the mesher's). The check is on the mesh without them; they are listed so that
    /// the change is not silent.
    pub dropped_components: Vec<ComponentSupport>,
    /// Handles of the mesh the data does not show, smallest first (see [`handles`]).
    pub unsupported_handles: Vec<UnsupportedHandle>,
    pub unsupported_handles_total: usize,
}

impl DataSupport {
    /// Every mesh component supported, every data component covered, no region lost, no
    /// unsupported handle and no region past the data.
    pub fn passed(&self) -> bool {
        self.unsupported_components == 0
            && self.uncovered_data_components == 0
            && self.unsupported_handles_total == 0
            && self.regions_past_data == 0
            && self.lost_regions == 0
    }

    /// The check's one-line detail.
    pub fn detail(&self) -> String {
        let fmt_p = |p: [f64; 3]| format!("({:.4}, {:.4}, {:.4})", p[0], p[1], p[2]);
        let mut s = format!(
            "{:.1}% of the area within the band of {} data points (median band {:.3e}; a point's \
             band: 2 x spacing + 3 x noise, at least {:.3e}; median spacing {:.3e}, noise {:.3e})",
            100.0 * self.supported_share,
            self.data_points,
            self.median_band,
            self.min_band,
            self.median_spacing,
            self.noise
        );
        if let Some(c) = self
            .components
            .iter()
            .min_by(|a, b| a.supported_share.total_cmp(&b.supported_share))
        {
            s += &format!(
                "; worst of {} mesh components: {:.1}% supported ({} triangles, {:.3e} across, at {})",
                self.components_total,
                100.0 * c.supported_share,
                c.triangles,
                c.extent,
                fmt_p(c.centroid)
            );
        }
        if let Some(c) = self
            .components
            .iter()
            .filter(|c| c.agreement.is_some())
            .min_by(|a, b| {
                a.agreement
                    .unwrap_or(1.0)
                    .total_cmp(&b.agreement.unwrap_or(1.0))
            })
        {
            s += &format!(
                "; least orientation agreement with the data normals {:.2} ({} triangles, {:.3e} across, at {})",
                c.agreement.unwrap_or(1.0),
                c.triangles,
                c.extent,
                fmt_p(c.centroid)
            );
        }
        if self.unsupported_components > 0 {
            s += &format!(
                "; {} mesh components below {:.0}% support{}",
                self.unsupported_components,
                100.0 * self.min_share,
                match self.min_agreement {
                    Some(a) => format!(" or {a:.2} orientation agreement"),
                    None => String::new(),
                }
            );
        }
        if !self.dropped_components.is_empty() {
            let list: Vec<String> = self
                .dropped_components
                .iter()
                .map(|c| {
                    format!(
                        "{} triangles, area {:.3e}, {:.3e} across, at {}, {:.1}% supported{}",
                        c.triangles,
                        c.area,
                        c.extent,
                        fmt_p(c.centroid),
                        100.0 * c.supported_share,
                        c.agreement
                            .map_or(String::new(), |a| format!(", agreement {a:.2}"))
                    )
                })
                .collect();
            s += &format!(
                "; {} unsupported components dropped from the output before this check ({})",
                self.dropped_components.len(),
                list.join("; ")
            );
        }
        if let Some(h) = self.unsupported_handles.first() {
            s += "; ";
            s += &h.describe(self.unsupported_handles_total);
        }
        s += &format!("; {} data components", self.data_components_total);
        if self.uncovered_data_components > 0 {
            let worst = self
                .data_components
                .iter()
                .min_by(|a, b| a.covered_share.total_cmp(&b.covered_share));
            if let Some(d) = worst {
                s += &format!(
                    ", {} not covered (worst: {} points, {:.1}% covered, at {})",
                    self.uncovered_data_components,
                    d.points,
                    100.0 * d.covered_share,
                    fmt_p(d.centroid)
                );
            }
        } else {
            s += ", all covered";
        }
        if let Some(r) = self.uncovered_regions.first() {
            s += "; ";
            s += &r.describe(self.uncovered_regions_total, self.lost_regions);
        }
        s += &regions::describe(
            &self.unsupported_regions,
            self.unsupported_regions_total,
            self.regions_past_data,
        );
        s
    }
}

/// The data's spacing, noise and band, and a kd-tree over it.
pub struct DataBand {
    points: Vec<DVec3>,
    tree: ImmutableKdTree<f64, 3>,
    /// Band radius per point.
    band: Vec<f64>,
    spacing: Vec<f64>,
    /// kNN lists (`k_spacing` neighbours).
    knn: Vec<Vec<u32>>,
    noise: f64,
}

impl DataBand {
    /// Measure `points` (at least 2, finite). `None` if there are fewer than 2 points.
    pub fn new(points: &[DVec3], opts: &SupportOptions) -> Option<DataBand> {
        let n = points.len();
        if n < 2 || points.iter().any(|p| !p.is_finite()) {
            return None;
        }
        let coords: Vec<[f64; 3]> = points.iter().map(|p| p.to_array()).collect();
        let tree = ImmutableKdTree::<f64, 3>::new_from_slice(&coords).ok()?;
        let ks = opts.k_spacing.clamp(1, n - 1);
        let kn = opts.k_noise.max(3).min(n - 1).max(ks);
        let lists = oracle::pointset::knn_lists(points, &tree, kn);
        let per: Vec<(Vec<u32>, f64, f64)> = points
            .par_iter()
            .zip(lists)
            .map(|(p, nb)| {
                let m = ks.min(nb.len()).max(1);
                let spacing = nb[..m.min(nb.len())]
                    .iter()
                    .map(|&j| (points[j as usize] - *p).length())
                    .sum::<f64>()
                    / m as f64;
                let noise = oracle::pointset::plane_residual(
                    nb.iter().map(|&j| points[j as usize]).chain([*p]),
                );
                (nb[..ks.min(nb.len())].to_vec(), spacing, noise)
            })
            .collect();
        let spacing: Vec<f64> = per.iter().map(|x| x.1).collect();
        let noise = median(per.iter().map(|x| x.2).collect());
        let knn = per.into_iter().map(|x| x.0).collect();
        let band = spacing
            .iter()
            .map(|&s| (2.0 * s + 3.0 * noise).max(opts.min_band))
            .collect();
        Some(DataBand {
            points: points.to_vec(),
            tree,
            band,
            spacing,
            knn,
            noise,
        })
    }

    /// The data point nearest to `x`.
    pub fn nearest(&self, x: DVec3) -> usize {
        self.tree
            .query(&x.to_array())
            .nearest_one::<SquaredEuclidean<f64>>()
            .execute()
            .item as usize
    }

    /// The band radius of the data point nearest to `x`.
    pub fn band_at(&self, x: DVec3) -> f64 {
        self.band[self.nearest(x)]
    }

    /// Is `x` within the band of its nearest data point? Also the distance to it.
    pub fn supports(&self, x: DVec3) -> (bool, f64) {
        let r = self
            .tree
            .query(&x.to_array())
            .nearest_one::<SquaredEuclidean<f64>>()
            .execute();
        let d = r.distance.sqrt();
        (d <= self.band[r.item as usize], d)
    }

    /// The estimated noise ν.
    pub fn noise(&self) -> f64 {
        self.noise
    }

    /// The median band radius.
    pub fn median_band(&self) -> f64 {
        median(self.band.clone())
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    let mid = v.len() / 2;
    *v.select_nth_unstable_by(mid, f64::total_cmp).1
}

/// Per triangle of `mesh`: its area and supported share (barycentric samples, 2
/// subdivisions per edge, plus the centroid); with data normals, also its area times its
/// agreement (`n_t · n_i`, `i` the data point nearest its centroid).
#[allow(clippy::type_complexity)]
fn per_triangle(
    mesh: &TriMesh,
    band: &DataBand,
    normals: Option<&[DVec3]>,
) -> (Vec<(f64, f64)>, Option<Vec<f64>>) {
    let v = &mesh.vertices;
    let per_tri: Vec<(f64, f64)> = mesh
        .triangles
        .par_iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| v[i as usize]);
            let area = 0.5 * (b - a).cross(c - a).length();
            let mut s = Vec::with_capacity(7);
            triangle_samples(a, b, c, 2, &mut s);
            s.push((a + b + c) / 3.0);
            let ok = s.iter().filter(|&&x| band.supports(x).0).count();
            (area, ok as f64 / s.len() as f64)
        })
        .collect();
    let agree: Option<Vec<f64>> = normals.map(|ns| {
        mesh.triangles
            .par_iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| v[i as usize]);
                let cr = 0.5 * (b - a).cross(c - a);
                cr.dot(ns[band.nearest((a + b + c) / 3.0)])
            })
            .collect()
    });
    (per_tri, agree)
}

/// The data-support check of `mesh` (valid, see [`TriMesh::validate`]) against `data`
/// (points: a scan, or samples of an input mesh, see [`mesh_samples`]). `None` if the data
/// has fewer than 2 finite points or the mesh no triangles.
pub fn data_support(mesh: &TriMesh, data: &[DVec3], opts: &SupportOptions) -> Option<DataSupport> {
    data_support_oriented(mesh, data, None, opts)
}

/// [`data_support`] with the data's oriented (outward) unit normals, one per point, if known:
/// each mesh component must then also agree in orientation with the data (see the module
/// documentation). Normals of the wrong count are ignored.
pub fn data_support_oriented(
    mesh: &TriMesh,
    data: &[DVec3],
    normals: Option<&[DVec3]>,
    opts: &SupportOptions,
) -> Option<DataSupport> {
    if mesh.triangles.is_empty() {
        return None;
    }
    let band = DataBand::new(data, opts)?;
    let normals = normals.filter(|n| n.len() == data.len());
    let (components, _, per_tri, agree) = component_measures(mesh, &band, normals);
    let handles = ShortLoops::new(mesh)
        .filter(ShortLoops::has_handles)
        .map_or_else(Vec::new, |l| {
            handles_in_band(mesh, &l, &band, agree.as_deref(), opts)
        });
    let total_area: f64 = per_tri.iter().map(|x| x.0).sum();
    let supported_area: f64 = per_tri.iter().map(|x| x.0 * x.1).sum();
    let unsupported_components = components
        .iter()
        .filter(|c| !c.supported(opts.min_share, opts.min_agreement))
        .count();
    // Data coverage.
    let distances = uncovered::coverage_distances(mesh, &band.points, &band.band, &band.spacing);
    let covered = uncovered::within(&distances, 1.0);
    let mut data_components = data_components(&band, &covered, opts.min_data_component);
    data_components.sort_by_key(|d| std::cmp::Reverse(d.points));
    let uncovered_data_components = data_components
        .iter()
        .filter(|d| d.covered_share < opts.min_share)
        .count();
    let uncovered_regions = uncovered::regions(
        mesh,
        &band.knn,
        &band.points,
        &distances,
        opts.min_data_component,
    );
    // Unsupported regions: triangles with less than half their samples supported, joined
    // through shared vertices.
    let bad: Vec<usize> = (0..mesh.triangles.len())
        .filter(|&t| per_tri[t].1 < 0.5)
        .collect();
    let med_spacing = median(band.spacing.clone());
    // (Built only when some triangle is unsupported.)
    let gwn = (!bad.is_empty())
        .then(|| regions::data_winding(data, normals, &band.spacing, med_spacing))
        .flatten();
    let mut regions = unsupported_regions(mesh, &bad, &per_tri, &band, gwn.as_ref());
    let past = |r: &UnsupportedRegion| {
        r.data_winding
            .is_some_and(|w| regions::past_data(w, r.data_alignment))
    };
    regions.sort_by(|a, b| {
        past(b)
            .cmp(&past(a))
            .then(b.area.total_cmp(&a.area))
            .then(a.triangles.cmp(&b.triangles))
    });
    let regions_past_data = regions.iter().filter(|r| past(r)).count();
    let ml = opts.max_listed;
    Some(DataSupport {
        data_points: data.len(),
        median_spacing: med_spacing,
        noise: band.noise,
        median_band: band.median_band(),
        min_band: opts.min_band,
        supported_share: if total_area > 0.0 {
            supported_area / total_area
        } else {
            1.0
        },
        components_total: components.len(),
        components: components.into_iter().take(ml.max(1)).collect(),
        data_components_total: data_components.len(),
        data_components: data_components.into_iter().take(ml.max(1)).collect(),
        uncovered_regions_total: uncovered_regions.len(),
        lost_regions: uncovered_regions.iter().filter(|r| r.lost()).count(),
        uncovered_regions: uncovered_regions.into_iter().take(ml.max(1)).collect(),
        unsupported_regions_total: regions.len(),
        unsupported_regions: regions.into_iter().take(ml).collect(),
        regions_past_data,
        unsupported_components,
        uncovered_data_components,
        min_share: opts.min_share,
        min_agreement: normals.is_some().then_some(opts.min_agreement),
        dropped_components: Vec::new(),
        unsupported_handles_total: handles.len(),
        unsupported_handles: handles.into_iter().take(ml.max(1)).collect(),
    })
}

/// The data regions `mesh` loses ([`UncoveredRegion::lost`], as [`data_support`] finds them)
/// without the rest of the check, for a caller choosing a size; empty without data or mesh.
pub fn lost_regions(mesh: &TriMesh, data: &[DVec3], opts: &SupportOptions) -> Vec<UncoveredRegion> {
    let Some(band) = DataBand::new(data, opts).filter(|_| !mesh.triangles.is_empty()) else {
        return Vec::new();
    };
    let distances = uncovered::coverage_distances(mesh, &band.points, &band.band, &band.spacing);
    let mut r = uncovered::regions(
        mesh,
        &band.knn,
        &band.points,
        &distances,
        opts.min_data_component,
    );
    r.retain(UncoveredRegion::lost);
    r
}

/// The handles of the closed mesh `mesh` that the data does not show ([`handles`]), all of
/// them, smallest first (what the check would list; the mesher cuts them); empty when the
/// data has fewer than 2 points or the mesh is not closed.
pub fn unsupported_handles(
    mesh: &TriMesh,
    data: &[DVec3],
    normals: Option<&[DVec3]>,
    opts: &SupportOptions,
) -> Vec<UnsupportedHandle> {
    // Genus 0 everywhere (most outputs): nothing to measure, not even the band.
    let Some(loops) = ShortLoops::new(mesh).filter(ShortLoops::has_handles) else {
        return Vec::new();
    };
    let Some(band) = DataBand::new(data, opts) else {
        return Vec::new();
    };
    let normals = normals.filter(|n| n.len() == data.len());
    let (_, agree) = per_triangle(mesh, &band, normals);
    handles_in_band(mesh, &loops, &band, agree.as_deref(), opts)
}

/// The handles of `mesh` (its short loops `loops`) that the data does not show ([`handles`]),
/// measured against `band` and the per-triangle agreement `agree`.
fn handles_in_band(
    mesh: &TriMesh,
    loops: &ShortLoops,
    band: &DataBand,
    agree: Option<&[f64]>,
    opts: &SupportOptions,
) -> Vec<UnsupportedHandle> {
    handles::unsupported_handles(mesh, loops, &|x| band.band_at(x), agree, opts.min_agreement)
}

/// Every component of `mesh` (in the order of [`vertex_components`]) with its support, the
/// component of each triangle, each triangle's (area, supported share) and, with normals,
/// its area-weighted agreement.
#[allow(clippy::type_complexity)]
fn component_measures(
    mesh: &TriMesh,
    band: &DataBand,
    normals: Option<&[DVec3]>,
) -> (
    Vec<ComponentSupport>,
    Vec<usize>,
    Vec<(f64, f64)>,
    Option<Vec<f64>>,
) {
    let v = &mesh.vertices;
    let (per_tri, agree) = per_triangle(mesh, band, normals);
    // Mesh components (vertex-connected).
    let comps = vertex_components(mesh);
    let mut comp_of = vec![usize::MAX; v.len()];
    for (k, c) in comps.iter().enumerate() {
        for &i in c {
            comp_of[i] = k;
        }
    }
    let comp_of_triangle: Vec<usize> = mesh
        .triangles
        .iter()
        .map(|t| comp_of[t[0] as usize])
        .collect();
    let mut acc = vec![(0usize, usize::MAX, 0.0f64, 0.0f64, 0.0f64); comps.len()];
    for (t, &k) in comp_of_triangle.iter().enumerate() {
        let e = &mut acc[k];
        e.0 += 1;
        e.1 = e.1.min(t);
        e.2 += per_tri[t].0;
        e.3 += per_tri[t].0 * per_tri[t].1;
        e.4 += agree.as_ref().map_or(0.0, |a| a[t]);
    }
    let components = comps
        .iter()
        .zip(&acc)
        .map(|(c, &(triangles, first, area, sup, ag))| {
            let (centroid, extent) = centroid_extent(c.iter().map(|&i| (v[i], 1.0)));
            ComponentSupport {
                first_triangle: first,
                triangles,
                area,
                supported_share: if area > 0.0 { sup / area } else { 1.0 },
                centroid,
                extent,
                agreement: agree
                    .is_some()
                    .then_some(if area > 0.0 { ag / area } else { 1.0 }),
            }
        })
        .collect();
    (components, comp_of_triangle, per_tri, agree)
}

/// Which data points the mesh covers: within their band of it (or twice their spacing,
/// whichever is larger).
fn covered_points(mesh: &TriMesh, band: &DataBand) -> Vec<bool> {
    let d = uncovered::coverage_distances(mesh, &band.points, &band.band, &band.spacing);
    uncovered::within(&d, 1.0)
}

/// The points of each component of the data's graph with at least `min_points` points: each
/// point joined to its kNN and to every point within twice its spacing. The kNN alone split
/// non-uniform samples: a dense cluster whose neighbours all lie inside it (measured on
/// `cow.obj` of `pymeshlab`'s wheel: its triangle samples made 24 kNN components of one
/// connected mesh, a horn tip of small triangles among them), while a sparse point next to
/// it reaches it within twice its own spacing.
fn data_groups(band: &DataBand, min_points: usize) -> Vec<Vec<usize>> {
    let n = band.points.len();
    let mut dsu = Dsu::new(n);
    let near: Vec<Vec<u32>> = (0..n)
        .into_par_iter()
        .map(|i| {
            let r = 2.0 * band.spacing[i];
            let q = band.points[i].to_array();
            let found = band.tree.query(&q).within::<SquaredEuclidean<f64>>(r * r);
            found.unsorted().execute().iter().map(|x| x.item).collect()
        })
        .collect();
    for (i, nb) in band
        .knn
        .iter()
        .zip(&near)
        .enumerate()
        .map(|(i, (a, b))| (i, a.iter().chain(b)))
    {
        for &j in nb {
            dsu.union(i as u32, j);
        }
    }
    let mut groups = dsu.groups((0..n).map(|i| (i, i as u32)));
    groups.retain(|g| g.len() >= min_points.max(1));
    groups
}

/// Components of the data's kNN graph with at least `min_points` points.
fn data_components(band: &DataBand, covered: &[bool], min_points: usize) -> Vec<DataComponent> {
    data_groups(band, min_points)
        .into_iter()
        .map(|g| {
            let cov = g.iter().filter(|&&i| covered[i]).count();
            let (centroid, extent) = centroid_extent(g.iter().map(|&i| (band.points[i], 1.0)));
            DataComponent {
                points: g.len(),
                covered_share: cov as f64 / g.len() as f64,
                centroid,
                extent,
            }
        })
        .collect()
}

/// Regions of touching triangles among `bad`.
fn unsupported_regions(
    mesh: &TriMesh,
    bad: &[usize],
    per_tri: &[(f64, f64)],
    band: &DataBand,
    gwn: Option<&geom::bvh::TriangleBvh>,
) -> Vec<UnsupportedRegion> {
    if bad.is_empty() {
        return Vec::new();
    }
    let nv = mesh.vertices.len();
    let mut dsu = Dsu::new(nv);
    for &t in bad {
        let [a, b, c] = mesh.triangles[t];
        dsu.union(a, b);
        dsu.union(a, c);
    }
    let groups = dsu.groups(bad.iter().map(|&t| (t, mesh.triangles[t][0])));
    let v = &mesh.vertices;
    groups
        .into_iter()
        .map(|g| {
            let area: f64 = g.iter().map(|&t| per_tri[t].0).sum();
            let (centroid, extent) = centroid_extent(g.iter().flat_map(|&t| {
                let w = per_tri[t].0 / 3.0;
                mesh.triangles[t].map(|i| (v[i as usize], w))
            }));
            UnsupportedRegion {
                triangles: g.len(),
                area,
                centroid,
                extent,
                distance_to_data: band.supports(DVec3::from_array(centroid)).1,
                data_winding: gwn.map(|w| regions::region_winding(mesh, &g, |t| per_tri[t].0, w)),
                data_alignment: regions::region_alignment(
                    mesh,
                    &g,
                    |t| per_tri[t].0,
                    |x| band.points[band.nearest(x)],
                ),
            }
        })
        .collect()
}

/// Add the `data-support` check (and section) to `report`; SKIP if the check could not run.
pub fn add_check(r: &mut crate::Report, mesh: &TriMesh, data: &[DVec3], opts: &SupportOptions) {
    add_check_oriented(r, mesh, data, None, &[], opts);
}

/// [`add_check`] with the data's oriented normals (see [`data_support_oriented`]) and the
/// components the mesher dropped from its raw output before (see [`droppable_components`]):
/// the check is on `mesh`, and its detail and section list them.
pub fn add_check_oriented(
    r: &mut crate::Report,
    mesh: &TriMesh,
    data: &[DVec3],
    normals: Option<&[DVec3]>,
    dropped: &[ComponentSupport],
    opts: &SupportOptions,
) {
    if r.input_error.is_some() {
        return;
    }
    match data_support_oriented(mesh, data, normals, opts) {
        Some(mut ds) => {
            ds.dropped_components = dropped.to_vec();
            let status = crate::pass_fail(ds.passed());
            r.push("data-support", status, ds.detail());
            r.data_support = Some(ds);
        }
        None => r.push(
            "data-support",
            crate::Status::Skipped,
            format!("{} data points: too few to measure a band", data.len()),
        ),
    }
}
