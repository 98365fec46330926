//! The IMLS surface of a point set (section 6.6.3), shared by the point-set backend
//! ([`crate::pointset`]) and the smoothed polyhedron ([`crate::polyhedron::SmoothPolyhedron`],
//! which samples its triangles): an implicit MLS surface from oriented points.
//!
//! Files: this one builds the surface (validation, kNN, spacing, kernel radii, normals, the
//! winding-number trees, the far-field cache); `kernel` evaluates the value and its
//! gradient; `normals` estimates and orients normals; `far` flood-fills the far-field signs;
//! `lfs` estimates d_M (shrinking balls); `surface` implements the oracles
//! ([`Surface`](crate::Surface)).
//!
//! - Normals: given, or estimated by PCA on the `k` nearest neighbours and oriented
//!   consistently by propagation along a minimum spanning tree of the kNN graph (Hoppe et al.
//!   1992), one tree per graph component, rooted at its highest point whose normal is set to
//!   point up (+z, outward at a topmost point).
//! - Surface: Kolluri's IMLS, `f(x) = Σ φ_i(x) n_i·(x − p_i) / Σ φ_i(x)`, with the compactly
//!   supported weight `φ_i(x) = (1 − |x − p_i|²/R_i²)⁴` and a support radius `R_i` proportional
//!   to the local spacing (mean distance to the nearest neighbours), so it adapts to density and
//!   averages noise over a few rings of neighbours.
//! - Far from the points (total weight below `min_weight`) the value blends into a constant
//!   (the largest kernel radius), signed by the point-cloud generalized winding number (Barill
//!   et al. 2018: each oriented point a tiny triangle of its share of the area, evaluated
//!   through a triangle BVH): negative deep inside, positive outside, robust in
//!   concave regions. On and outside the bounding sphere it is positive by construction.
//! - P1: a few well-spread input points (and the top and bottom of each component, where the
//!   tangent plane is horizontal, as in the paper) projected onto the MLS surface.
//! - P2 ([`Surface::dm_inf_hint`](crate::Surface::dm_inf_hint),
//!   [`PointSetSurface::estimate_local_feature_size`]): a
//!   kNN-based proxy of the distance to the medial axis, the radius of the inner and outer
//!   *shrinking balls* (Ma, Bae & Choi 2012), which converge to the Voronoi poles' medial balls
//!   of section 6.6.3; neighbours closer than the kernel radius are ignored so that noise does
//!   not shrink the balls. (The Delaunay-based λ-medial axis is not used: `delaunay3` was a stub
//!   when this was written.)

mod far;
mod grid;
mod kernel;
mod lfs;
pub(crate) mod linalg;
mod normals;
mod surface;

pub use surface::CROSSING_PRECISION;

use crate::BoundingSphere;
use crate::roots::SplitMix64;
use far::FarCache;
use geom::bvh::TriangleBvh as Bvh;
use geom::predicates::BadPoint;
use glam::DVec3;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use lfs::LfsSample;
use normals::{K_GRAPH, components_roots, estimate_normals};
use rayon::prelude::*;
use std::num::NonZeroUsize;
use std::sync::OnceLock;

/// Fewest points accepted.
pub const MIN_POINTS: usize = 10;

/// Errors building a [`PointSetSurface`].
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
#[allow(missing_docs)] // variant fields: named in the variant's docs and message
pub enum PointSetError {
    /// Fewer points than [`MIN_POINTS`].
    /// Point `index` has a non-finite coordinate.
    /// Point `index` has a coordinate beyond 1e60.
    /// The normals are not one per point.
    /// Normal `index` is not a finite non-zero vector.
    /// The points are (nearly) coplanar or collinear.
    /// A parameter of [`PointSetParams`] is out of range.
    #[error(
        "the point set has {0} points; at least {MIN_POINTS} are needed to fit a surface (give \
         a denser sample)"
    )]
    TooFewPoints(usize),
    #[error("point {index} has a non-finite coordinate ({x}, {y}, {z}); fix or remove it")]
    NonFinitePoint {
        index: usize,
        x: f64,
        y: f64,
        z: f64,
    },
    #[error("point {index} has coordinate {value}, too large (|c| < 1e60); rescale the input")]
    OutOfRange { index: usize, value: f64 },
    #[error(
        "{normals} normals for {points} points; give one normal per point or none (normals are \
         then estimated)"
    )]
    NormalCount { points: usize, normals: usize },
    #[error(
        "normal {index} is ({x}, {y}, {z}), not a finite non-zero vector; fix it or drop the \
         normals so they are estimated"
    )]
    BadNormal {
        index: usize,
        x: f64,
        y: f64,
        z: f64,
    },
    #[error(
        "all points are coplanar (or collinear): the smallest spread of the set is {ratio:.3e} \
         of the largest; a point set must sample a closed surface, not a plane"
    )]
    Coplanar { ratio: f64 },
    #[error("invalid parameter {name} = {value}: {hint}")]
    BadParameter {
        name: &'static str,
        value: f64,
        hint: &'static str,
    },
}

/// Tuning of [`PointSetSurface`]. The defaults suit uniform samples with noise up to about the
/// sample spacing; [`PointSetParams::scan`] suits scans (non-uniform density, noise, holes).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct PointSetParams {
    /// Neighbours used for normal estimation (PCA) and the orientation graph.
    pub k_normals: usize,
    /// Neighbours used to measure the local spacing (mean distance).
    pub k_spacing: usize,
    /// Kernel support radius `R_i` in units of the local spacing.
    pub bandwidth: f64,
    /// The local spacing used for `R_i` is clamped to at most this multiple of the median
    /// spacing (default 1.5; larger values use a second grid for the large supports).
    pub max_spacing_ratio: f64,
    /// Trust the IMLS value only within the data's band: `b_i = 2 s_i + 3 ν` about each point
    /// (`s_i` its spacing, `ν` the estimated noise); beyond 1.5 `b_i` from every point, the
    /// value is the far field (its sign from the flood-filled regions or the winding number),
    /// blended in between. Removes zero-sets the data does not support.
    pub support_band: bool,
    /// Kernel support radius at least this multiple of the estimated noise ν (0: off), so
    /// that the kernel averages the noise over enough points wherever the spacing is small
    /// against the noise. Needs the noise estimate (computed when this or `support_band` is
    /// on).
    pub noise_bandwidth: f64,
    /// Estimated normals and the noise estimate use at least the neighbours within about
    /// this multiple of ν (more than `k_normals` when the noise is large against the
    /// spacing; at most [`MAX_K_NOISE`]); 0: off.
    pub noise_neighbourhood: f64,
    /// Robust reweighting passes (ours, after Öztireli et al. 2009, robust IMLS): 0 is plain
    /// IMLS; each pass down-weights the points whose normals disagree with the surface's
    /// gradient, so sharp edges and thin parts are less smoothed.
    pub robust: usize,
    /// The normal-agreement scale σ_n of the robust passes (on unit normals).
    pub robust_sigma_n: f64,
    /// Kernel support radius at least [`Self::radius_knn_factor`] times the distance to the
    /// `radius_knn`-th nearest neighbour (0: off), not clamped by the median spacing: every
    /// query near the data then averages about that many points, whatever the local density
    /// (the sparse side of a non-uniform scan).
    pub radius_knn: usize,
    /// See [`Self::radius_knn`].
    pub radius_knn_factor: f64,
    /// The robust passes' value uses, for each point, the mean of its normal and the
    /// surface's normal at `x` (the previous pass's gradient direction): `Σ w ½(n_i + n)·(x −
    /// p_i) / Σ w`. On a sphere this is exactly 0 at every point of the sphere, where the
    /// plain `n_i·(x − p_i) = −|x − p_i|²/(2ρ)` offsets the zero-set by about `R²/(12ρ)`
    /// (radius `ρ`, kernel radius `R`); so a larger kernel costs less bias on curved parts.
    /// Needs `robust` ≥ 1.
    pub midpoint_normals: bool,
    /// The total kernel weight `Σ φ_i(x)` below which the IMLS value blends into the far
    /// field (each point weighs at most 1, at its own position): where fewer points' worth of
    /// data reaches `x`, the value is an extrapolation of planes from one side. Default 1;
    /// [`Self::scan`] 2 (issue 16: past a thin part's rim or a sharp corner the IMLS value
    /// keeps its sign until the weight fades, and the mesh followed it there).
    pub min_weight: f64,
}

/// Largest neighbour count of [`PointSetParams::noise_neighbourhood`].
pub const MAX_K_NOISE: usize = 96;

impl Default for PointSetParams {
    fn default() -> Self {
        PointSetParams {
            k_normals: 24,
            k_spacing: 8,
            bandwidth: 3.0,
            max_spacing_ratio: 1.5,
            support_band: false,
            noise_bandwidth: 0.0,
            noise_neighbourhood: 0.0,
            robust: 0,
            robust_sigma_n: 0.5,
            radius_knn: 0,
            radius_knn_factor: 1.0,
            midpoint_normals: false,
            min_weight: 1.0,
        }
    }
}

impl PointSetParams {
    /// The settings for scans (what `mesh` uses on point sets): the support band on; kernel
    /// radii at least 6 ν and normals from the neighbours within about 8 ν (noise-adaptive);
    /// one robust pass with σ_n = 0.8. Measured on the scan table (`cargo xtask scans`,
    /// issue 16): the robust pass took fandisk at 0.1% noise from 0.84% to 0.52% of the
    /// diagonal (two passes or σ_n 0.5 / 0.35 were worse: noisy normals then break the
    /// surface), the noise-adaptive radius took fertility at 0.5% noise from 1.26% to
    /// 0.70%. A wider `max_spacing_ratio` (2.5, 3.5) or `bandwidth` 2.5 measured worse.
    /// Radii at least 1.5 × the 16th-neighbour distance and midpoint normals (the sparse
    /// half of a 10:1 scan): fertility at 0.1% and 0.3% noise, 10:1, given normals, 0.79% and
    /// 1.15% -> 0.40% and 0.58% (GUIDE, "Point sets and scans"). The IMLS trusted from a
    /// kernel weight of 2 (`min_weight`; 1 before): 19 -> 20 of the table's 39 rows, the
    /// failing rows' distances down (fandisk 0.5%, 10:1, given normals 5.47% -> 2.84%), no
    /// passing row past 0.89 of its bound (GUIDE, "The trust threshold").
    pub fn scan() -> Self {
        PointSetParams {
            support_band: true,
            noise_bandwidth: 6.0,
            noise_neighbourhood: 8.0,
            robust: 1,
            robust_sigma_n: 0.8,
            radius_knn: 16,
            radius_knn_factor: 1.5,
            midpoint_normals: true,
            min_weight: 2.0,
            ..Default::default()
        }
    }
}

/// What [`PointSetSurface::new`] computed.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PointSetStats {
    /// Points used: the input's, exact duplicates merged.
    pub points: usize,
    /// Input points equal to an earlier one (merged; the first keeps its normal).
    pub duplicates: usize,
    /// Whether the normals were estimated (no input normals).
    pub estimated_normals: bool,
    /// Components of the kNN graph (one orientation tree each).
    pub components: usize,
    /// Median local spacing (mean distance to the `k_spacing` nearest neighbours).
    pub median_spacing: f64,
    /// Median kernel support radius.
    pub median_radius: f64,
    /// Connected regions that no kernel reaches (outside, inside...), each signed once.
    pub far_components: usize,
    /// Estimated noise ν (median RMS distance of a point's neighbours to their plane; 0
    /// without the support band).
    pub noise: f64,
    /// Median support band radius `2 s_i + 3 ν` (0 without the support band).
    pub median_band: f64,
}

/// A surface defined by a point set (an IMLS surface). See the module documentation.
///
/// ```
/// use glam::DVec3;
/// use oracle::Surface;
/// use oracle::pointset::{PointSetParams, PointSetSurface};
/// // 2000 points on the unit sphere (Fibonacci lattice), without normals.
/// let n = 2000;
/// let pts: Vec<DVec3> = (0..n)
///     .map(|i| {
///         let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
///         let t = i as f64 * 2.399963229728653;
///         let r = (1.0 - z * z).sqrt();
///         DVec3::new(r * t.cos(), r * t.sin(), z)
///     })
///     .collect();
/// let s = PointSetSurface::new(&pts, None, &PointSetParams::default()).unwrap();
/// assert!(s.value(DVec3::ZERO) < 0.0 && s.value(DVec3::splat(1.0)) > 0.0);
/// let p = s.project(DVec3::new(0.0, 0.9, 0.0)).unwrap();
/// assert!((p.length() - 1.0).abs() < 0.03);
/// ```
pub struct PointSetSurface {
    points: Vec<DVec3>,
    normals: Vec<DVec3>,
    /// Largest `radius` (query radius).
    max_radius: f64,
    /// Points, normals and radii bucketed for the kernel sums.
    grid: grid::Levels,
    /// The support band is on ([`PointSetParams::support_band`]).
    banded: bool,
    /// [`PointSetParams::robust`] and `1 / σ_n²` ([`PointSetParams::robust_sigma_n`]).
    robust: usize,
    robust_inv_sn2: f64,
    /// [`PointSetParams::midpoint_normals`].
    midpoint: bool,
    /// [`PointSetParams::min_weight`].
    min_weight: f64,
    tree: ImmutableKdTree<f64, 3>,
    lo: DVec3,
    hi: DVec3,
    sphere: BoundingSphere,
    stats: PointSetStats,
    /// Root point of each kNN component (highest point).
    roots: Vec<usize>,
    /// Each point as a tiny oriented triangle (area ≈ its share of the surface), for the
    /// point-cloud generalized winding number (Barill et al. 2018) that signs the far field.
    gwn: Bvh,
    /// Subsampled copy of `gwn` (large inputs only).
    gwn_coarse: Option<Bvh>,
    lfs: OnceLock<LfsSample>,
    /// Far-field signs where no kernel reaches (flood-filled components of a grid).
    far_cache: FarCache,
}

impl std::fmt::Debug for PointSetSurface {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PointSetSurface")
            .field("stats", &self.stats)
            .field("bounding_sphere", &self.sphere)
            .finish_non_exhaustive()
    }
}

/// Points in the coarse winding-number tree.
const GWN_COARSE: usize = 4096;

impl PointSetSurface {
    /// Build the surface from points and optional (outward) normals.
    pub fn new(
        points: &[DVec3],
        normals: Option<&[DVec3]>,
        params: &PointSetParams,
    ) -> Result<Self, PointSetError> {
        validate(points, normals, params)?;
        // Exact duplicates (merged scans, repeated rows) are one point: as separate points
        // they are each other's nearest neighbours at distance 0, which shrinks the spacing,
        // the kernel radius and the PCA neighbourhoods (2,000 sphere points given three times
        // meshed to genus 25). The first of each keeps its normal.
        let (kept, duplicates) = distinct_points(points);
        let (points, normals): (Vec<DVec3>, Option<Vec<DVec3>>) = (
            kept.iter().map(|&i| points[i]).collect(),
            normals.map(|ns| kept.iter().map(|&i| ns[i]).collect()),
        );
        if points.len() < MIN_POINTS {
            return Err(PointSetError::TooFewPoints(points.len()));
        }
        let (points, normals) = (&points[..], normals.as_deref());
        let n = points.len();
        let coords: Vec<[f64; 3]> = points.iter().map(|p| p.to_array()).collect();
        let tree = ImmutableKdTree::<f64, 3>::new_from_slice(&coords)
            .expect("kd-tree construction from finite points");
        let Near {
            knn,
            spacing,
            med_spacing,
            noise,
            k_normals,
        } = neighbourhoods(points, normals.is_some(), &tree, params)?;
        let radius = kernel_radii(points, &knn, &spacing, med_spacing, noise, params);
        let max_radius = radius.iter().copied().fold(0.0, f64::max);
        let estimated = normals.is_none();
        let (normals, roots) = match normals {
            Some(ns) => {
                let roots = components_roots(points, &knn, params.k_normals.min(K_GRAPH));
                (ns.iter().map(|v| v.normalize()).collect(), roots)
            }
            None => estimate_normals(points, &knn, k_normals),
        };
        let (gwn, gwn_coarse) = winding_trees(points, &normals, &spacing, med_spacing);
        let band: Option<Vec<f64>> = params
            .support_band
            .then(|| spacing.iter().map(|&s| 2.0 * s + 3.0 * noise).collect());
        // Default clamp: one grid, as before; wider clamps: a second grid for the large radii.
        let split = (params.bandwidth * (1.5 * med_spacing)).max(params.noise_bandwidth * noise);
        let grid = grid::Levels::new(points, &normals, &radius, band.as_deref(), split);
        let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
        for p in points {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        let center = 0.5 * (lo + hi);
        let sphere = BoundingSphere {
            center,
            radius: 0.55 * (hi - lo).length() + 2.0 * max_radius,
        };
        let stats = PointSetStats {
            points: n,
            duplicates,
            estimated_normals: estimated,
            components: roots.len(),
            median_spacing: med_spacing,
            median_radius: median(&radius),
            far_components: 0,
            noise,
            median_band: band.as_deref().map_or(0.0, median),
        };
        let mut surface = PointSetSurface {
            points: points.to_vec(),
            normals,
            max_radius,
            grid,
            banded: params.support_band,
            robust: params.robust,
            robust_inv_sn2: 1.0 / (params.robust_sigma_n * params.robust_sigma_n),
            midpoint: params.midpoint_normals,
            min_weight: params.min_weight,
            tree,
            lo,
            hi,
            sphere,
            stats,
            roots,
            gwn,
            gwn_coarse,
            lfs: OnceLock::new(),
            far_cache: FarCache::default(),
        };
        surface.far_cache = FarCache::build(
            surface.sphere.center,
            surface.sphere.radius,
            points,
            &radius,
            max_radius,
            |c| {
                if surface.far_value_uncached(c, 0.0) < 0.0 {
                    -1
                } else {
                    1
                }
            },
        );
        surface.stats.far_components = surface.far_cache.components;
        Ok(surface)
    }

    /// What the construction found (spacing, components, whether normals were estimated).
    pub fn stats(&self) -> &PointSetStats {
        &self.stats
    }

    /// The input points.
    pub fn points(&self) -> &[DVec3] {
        &self.points
    }

    /// Unit normals (input or estimated and oriented), one per point.
    pub fn normals(&self) -> &[DVec3] {
        &self.normals
    }

    /// Axis-aligned bounding box of the points.
    pub fn bbox(&self) -> (DVec3, DVec3) {
        (self.lo, self.hi)
    }

    /// Largest kernel support radius: farther than this from every point, the value is the
    /// far field (signed by the winding number).
    pub fn max_radius(&self) -> f64 {
        self.max_radius
    }

    /// Default sizing: 1/50 of the bounding box diagonal.
    pub fn suggested_size(&self) -> f64 {
        (self.hi - self.lo).length() / 50.0
    }
}

/// What [`neighbourhoods`] measured.
struct Near {
    knn: Vec<Vec<u32>>,
    spacing: Vec<f64>,
    med_spacing: f64,
    noise: f64,
    /// Neighbours for the estimated normals.
    k_normals: usize,
}

/// The kNN lists, the local spacing and its median, the estimated noise ν (when the
/// parameters need it; 0 otherwise) and the neighbour count of the normals: `k_normals`, or
/// more when the noise is large against the spacing
/// ([`PointSetParams::noise_neighbourhood`]; the lists are then that long and ν is measured
/// again on them).
fn neighbourhoods(
    points: &[DVec3],
    given_normals: bool,
    tree: &ImmutableKdTree<f64, 3>,
    params: &PointSetParams,
) -> Result<Near, PointSetError> {
    let n = points.len();
    // Neighbours needed: the spacing's, and the normals' (PCA) or, with given normals,
    // only the orientation graph's (components).
    let wants_noise =
        params.support_band || params.noise_bandwidth > 0.0 || params.noise_neighbourhood > 0.0;
    let k_nrm = if given_normals && !wants_noise {
        params.k_normals.min(K_GRAPH)
    } else {
        params.k_normals
    };
    let k = k_nrm
        .max(params.k_spacing)
        .max(params.radius_knn)
        .min(n - 1);
    let mut knn = knn_lists(points, tree, k);
    let spacing = mean_spacing(points, &knn, params.k_spacing);
    let med_spacing = median(&spacing);
    if med_spacing.is_nan() || med_spacing <= 0.0 {
        return Err(PointSetError::Coplanar { ratio: 0.0 });
    }
    let mut noise = if wants_noise {
        plane_noise(points, &knn)
    } else {
        0.0
    };
    // Large noise against the spacing: wider neighbourhoods for the normals and the noise
    // (the kNN radius is about 0.5 sqrt(k) times the mean 8-NN distance on a surface).
    let k_wide = if params.noise_neighbourhood > 0.0 {
        let r = params.noise_neighbourhood * noise / (0.5 * med_spacing);
        ((r * r).ceil() as usize)
            .clamp(k, MAX_K_NOISE.max(k))
            .min(n - 1)
    } else {
        k
    };
    let k_normals = if k_wide > k {
        knn = knn_lists(points, tree, k_wide);
        noise = plane_noise(points, &knn);
        k_wide
    } else {
        params.k_normals
    };
    Ok(Near {
        knn,
        spacing,
        med_spacing,
        noise,
        k_normals,
    })
}

/// The kernel support radii: `bandwidth` × the spacing clamped to [0.5,
/// `max_spacing_ratio`] × the median (the query radius is the largest support, so this bounds
/// the cost; no empty support at isolated points), at least `noise_bandwidth` × ν and
/// `radius_knn_factor` × the distance to the `radius_knn`-th neighbour (not clamped: the
/// sparse side of a non-uniform scan; the large radii go to a second grid).
fn kernel_radii(
    points: &[DVec3],
    knn: &[Vec<u32>],
    spacing: &[f64],
    med_spacing: f64,
    noise: f64,
    params: &PointSetParams,
) -> Vec<f64> {
    spacing
        .iter()
        .enumerate()
        .map(|(i, &s)| {
            let knn_r = match knn[i].get(params.radius_knn.min(knn[i].len()).wrapping_sub(1)) {
                Some(&j) if params.radius_knn > 0 => {
                    params.radius_knn_factor * (points[j as usize] - points[i]).length()
                }
                _ => 0.0,
            };
            (params.bandwidth * s.clamp(0.5 * med_spacing, params.max_spacing_ratio * med_spacing))
                .max(params.noise_bandwidth * noise)
                .max(knn_r)
        })
        .collect()
}

/// The checks of [`PointSetSurface::new`]: enough finite points of moderate size, valid
/// parameters, one finite non-zero normal per point (if given), not all coplanar.
fn validate(
    points: &[DVec3],
    normals: Option<&[DVec3]>,
    params: &PointSetParams,
) -> Result<(), PointSetError> {
    let n = points.len();
    if n < MIN_POINTS {
        return Err(PointSetError::TooFewPoints(n));
    }
    if !(params.max_spacing_ratio.is_finite() && params.max_spacing_ratio >= 0.5) {
        return Err(PointSetError::BadParameter {
            name: "max_spacing_ratio",
            value: params.max_spacing_ratio,
            hint: "at least 0.5, e.g. 1.5 (uniform samples) or 3.5 (scans)",
        });
    }
    if params.robust > 0 && !(params.robust_sigma_n.is_finite() && params.robust_sigma_n > 0.0) {
        return Err(PointSetError::BadParameter {
            name: "robust_sigma_n",
            value: params.robust_sigma_n,
            hint: "a positive scale of the normals' disagreement, e.g. 0.8",
        });
    }
    if params.radius_knn > 256 {
        return Err(PointSetError::BadParameter {
            name: "radius_knn",
            value: params.radius_knn as f64,
            hint: "a neighbour count up to 256 (0: off), e.g. 16",
        });
    }
    if !(params.radius_knn_factor.is_finite() && params.radius_knn_factor > 0.0) {
        return Err(PointSetError::BadParameter {
            name: "radius_knn_factor",
            value: params.radius_knn_factor,
            hint: "a positive multiple of the k-th neighbour distance, e.g. 1.5",
        });
    }
    if !(params.min_weight.is_finite() && params.min_weight > 0.0) {
        return Err(PointSetError::BadParameter {
            name: "min_weight",
            value: params.min_weight,
            hint: "a positive total kernel weight (about that many points' worth), e.g. 1 or 2",
        });
    }
    if !(params.bandwidth.is_finite() && params.bandwidth > 0.0) {
        return Err(PointSetError::BadParameter {
            name: "bandwidth",
            value: params.bandwidth,
            hint: "a positive multiple of the spacing, e.g. 3",
        });
    }
    for (name, k) in [
        ("k_normals", params.k_normals),
        ("k_spacing", params.k_spacing),
    ] {
        if !(3..=256).contains(&k) {
            return Err(PointSetError::BadParameter {
                name,
                value: k as f64,
                hint: "a neighbour count between 3 and 256, e.g. 12",
            });
        }
    }
    if let Some((index, bad)) = geom::predicates::first_bad_point(points, 1e60) {
        return Err(match bad {
            BadPoint::NonFinite([x, y, z]) => PointSetError::NonFinitePoint { index, x, y, z },
            BadPoint::TooLarge(value) => PointSetError::OutOfRange { index, value },
        });
    }
    if let Some(ns) = normals {
        if ns.len() != n {
            return Err(PointSetError::NormalCount {
                points: n,
                normals: ns.len(),
            });
        }
        if let Some((i, v)) = ns
            .iter()
            .enumerate()
            .find(|(_, v)| !v.is_finite() || v.length_squared() == 0.0)
        {
            return Err(PointSetError::BadNormal {
                index: i,
                x: v.x,
                y: v.y,
                z: v.z,
            });
        }
    }
    let (cov, _) = linalg::covariance(points.iter().copied());
    let (vals, _) = linalg::sym_eigen(cov);
    let ratio = vals[0].max(0.0) / vals[2].max(f64::MIN_POSITIVE);
    if ratio < 1e-10 {
        return Err(PointSetError::Coplanar { ratio });
    }
    Ok(())
}

/// The indices of the first occurrence of each distinct point (bitwise equal coordinates,
/// `-0.0` as `0.0`), in input order, and the number of the others.
fn distinct_points(points: &[DVec3]) -> (Vec<usize>, usize) {
    let key = |p: &DVec3| p.to_array().map(|c| (c + 0.0).to_bits());
    let mut seen = std::collections::HashSet::with_capacity(points.len());
    let kept: Vec<usize> = (0..points.len())
        .filter(|&i| seen.insert(key(&points[i])))
        .collect();
    let duplicates = points.len() - kept.len();
    (kept, duplicates)
}

/// The `k` nearest neighbours of each point (without the point itself, robust to duplicates:
/// index `i` is dropped), nearest first; in parallel, the same lists on any thread count.
pub fn knn_lists(points: &[DVec3], tree: &ImmutableKdTree<f64, 3>, k: usize) -> Vec<Vec<u32>> {
    let kq = NonZeroUsize::new(k + 1).expect("k + 1 > 0");
    // kNN lists (without the point itself, robust to duplicates: drop index i).
    points
        .par_iter()
        .enumerate()
        .map(|(i, p)| {
            let res = tree
                .query(&p.to_array())
                .nearest_n::<SquaredEuclidean<f64>>(kq)
                .execute();
            let mut v: Vec<u32> = res
                .iter()
                .map(|r| r.item)
                .filter(|&j| j as usize != i)
                .collect();
            v.truncate(k);
            v
        })
        .collect()
}

/// One point's disk of the point-cloud winding number: an equilateral triangle of area
/// ≈ 0.9 × spacing² (the share of the surface of a point whose k nearest neighbours are at
/// mean distance `spacing`, at least a quarter of the median) times `scale`, in the tangent
/// plane at `p`, counter-clockwise about the unit normal `n`.
fn winding_disk(p: DVec3, n: DVec3, spacing: f64, med_spacing: f64, scale: f64) -> [DVec3; 3] {
    let (u, v) = n.any_orthonormal_pair();
    let area = scale * 0.9 * spacing.max(0.25 * med_spacing).powi(2);
    let rho = (area / (0.75 * 3f64.sqrt())).sqrt();
    let c = |t: f64| p + rho * (t.cos() * u + t.sin() * v);
    let third = 2.0 * std::f64::consts::FRAC_PI_3;
    [c(0.0), c(third), c(2.0 * third)]
}

/// The generalized winding number of an oriented point cloud (after Barill et al. 2018), as
/// the point-set surface's far field uses it: each point a small disk in its tangent plane
/// ([`winding_disk`]); `TriangleBvh::winding_number` of the result is ≈ 1 inside the sampled
/// solid and ≈ 0 outside, meaningful at distances above the spacing. `normals`: outward unit
/// normals; `spacing`: each point's mean distance to its nearest neighbours (the `k_spacing`
/// mean of [`PointSetParams`]), `med_spacing` their median.
pub fn winding_disks(
    points: &[DVec3],
    normals: &[DVec3],
    spacing: &[f64],
    med_spacing: f64,
) -> Bvh {
    let n = points.len();
    Bvh::build(
        (0..n)
            .map(|i| winding_disk(points[i], normals[i], spacing[i], med_spacing, 1.0))
            .collect(),
        (0..n as u32).collect(),
        0.0,
    )
}

/// The point-cloud winding-number trees: [`winding_disks`], and, for large inputs, a coarse
/// copy from a random subsample (areas scaled up).
fn winding_trees(
    points: &[DVec3],
    normals: &[DVec3],
    spacing: &[f64],
    med_spacing: f64,
) -> (Bvh, Option<Bvh>) {
    let n = points.len();
    let gwn = winding_disks(points, normals, spacing, med_spacing);
    // A coarse copy from a random subsample (areas scaled up), tried first out of the
    // kernel support; its answer is kept when clear-cut (w < 0.1 or w > 0.9).
    let gwn_coarse = (n > 2 * GWN_COARSE).then(|| {
        let mut idx: Vec<usize> = (0..n).collect();
        let mut rng = SplitMix64(0x00C0_A25E);
        for k in 0..GWN_COARSE {
            let j = k + (rng.next_u64() % (n - k) as u64) as usize;
            idx.swap(k, j);
        }
        idx.truncate(GWN_COARSE);
        idx.sort_unstable();
        let scale = n as f64 / GWN_COARSE as f64;
        let tris = idx
            .iter()
            .map(|&i| winding_disk(points[i], normals[i], spacing[i], med_spacing, scale))
            .collect();
        Bvh::build(tris, (0..GWN_COARSE as u32).collect(), 0.0)
    });
    (gwn, gwn_coarse)
}

/// The local spacing of each point: the mean distance to its first `k_spacing` neighbours.
fn mean_spacing(points: &[DVec3], knn: &[Vec<u32>], k_spacing: usize) -> Vec<f64> {
    knn.par_iter()
        .enumerate()
        .map(|(i, nb)| {
            let m = k_spacing.min(nb.len());
            nb[..m]
                .iter()
                .map(|&j| (points[j as usize] - points[i]).length())
                .sum::<f64>()
                / m as f64
        })
        .collect()
}

/// The estimated noise: the median over the points of the RMS distance of the point and its
/// neighbours to their least-squares plane (the root of the smallest covariance eigenvalue
/// over the count).
fn plane_noise(points: &[DVec3], knn: &[Vec<u32>]) -> f64 {
    let r: Vec<f64> = knn
        .par_iter()
        .enumerate()
        .map(|(i, nb)| {
            let pts = nb.iter().map(|&j| points[j as usize]).chain([points[i]]);
            let (cov, _) = linalg::covariance(pts);
            let (vals, _) = linalg::sym_eigen(cov);
            (vals[0].max(0.0) / (nb.len() + 1) as f64).sqrt()
        })
        .collect();
    median(&r)
}

/// The median (the upper one for an even count) of `v`.
fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    let mid = s.len() / 2;
    *s.select_nth_unstable_by(mid, f64::total_cmp).1
}
