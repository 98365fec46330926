//! Point-set surface oracle (section 6.6.3): an implicit MLS surface from oriented points.
//!
//! - Normals: given, or estimated by PCA on the `k` nearest neighbours and oriented
//!   consistently by propagation along a minimum spanning tree of the kNN graph (Hoppe et al.
//!   1992), one tree per graph component, rooted at its highest point whose normal is set to
//!   point up (+z, outward at a topmost point).
//! - Surface: Kolluri's IMLS, `f(x) = Σ φ_i(x) n_i·(x − p_i) / Σ φ_i(x)`, with the compactly
//!   supported weight `φ_i(x) = (1 − |x − p_i|²/R_i²)⁴` and a support radius `R_i` proportional
//!   to the local spacing (mean distance to the nearest neighbours), so it adapts to density and
//!   averages noise over a few rings of neighbours.
//! - Far from the points (total weight below a threshold) the value blends into a constant
//!   (the largest kernel radius), signed by the point-cloud generalized winding number (Barill
//!   et al. 2018: each oriented point a tiny triangle of its share of the area, evaluated
//!   through the polyhedron backend's BVH): negative deep inside, positive outside, robust in
//!   concave regions. On and outside the bounding sphere it is positive by construction.
//! - P1: a few well-spread input points (and the top and bottom of each component, where the
//!   tangent plane is horizontal, as in the paper) projected onto the MLS surface.
//! - P2 ([`Surface::dm_inf_hint`], [`PointSetSurface::estimate_local_feature_size`]): a
//!   kNN-based proxy of the distance to the medial axis, the radius of the inner and outer
//!   *shrinking balls* (Ma, Bae & Choi 2012), which converge to the Voronoi poles' medial balls
//!   of section 6.6.3; neighbours closer than the kernel radius are ignored so that noise does
//!   not shrink the balls. (The Delaunay-based λ-medial axis is not used: `delaunay3` was a stub
//!   when this was written.)

mod far;
mod grid;
mod linalg;
mod xyz;

pub use xyz::{PointCloud, XyzError, read_xyz, read_xyz_from};

use crate::polyhedron::bvh::Bvh;
use crate::roots::SplitMix64;
use crate::{BoundingSphere, Surface};
use far::FarCache;
use glam::DVec3;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;
use std::num::NonZeroUsize;
use std::sync::OnceLock;

/// Fewest points accepted.
pub const MIN_POINTS: usize = 10;

/// Errors building a [`PointSetSurface`].
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum PointSetError {
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
/// sample spacing.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PointSetParams {
    /// Neighbours used for normal estimation (PCA) and the orientation graph.
    pub k_normals: usize,
    /// Neighbours used to measure the local spacing (mean distance).
    pub k_spacing: usize,
    /// Kernel support radius `R_i` in units of the local spacing.
    pub bandwidth: f64,
}

impl Default for PointSetParams {
    fn default() -> Self {
        PointSetParams {
            k_normals: 24,
            k_spacing: 8,
            bandwidth: 3.0,
        }
    }
}

/// What [`PointSetSurface::new`] computed.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PointSetStats {
    pub points: usize,
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
    grid: grid::Grid,
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

/// Local feature size estimated on a subsample.
struct LfsSample {
    points: Vec<DVec3>,
    lfs: Vec<f64>,
    tree: ImmutableKdTree<f64, 3>,
}

impl std::fmt::Debug for PointSetSurface {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PointSetSurface")
            .field("stats", &self.stats)
            .field("bounding_sphere", &self.sphere)
            .finish_non_exhaustive()
    }
}

/// Kernel sums at a point (see [`PointSetSurface::sums_impl`]).
#[derive(Clone, Copy, Default)]
struct Sums {
    /// Σ φ n·(x − p).
    num: f64,
    /// Σ φ.
    den: f64,
    /// Σ φ n.
    nsum: DVec3,
    /// ∇ of `num` and `den` (when asked for).
    dnum: DVec3,
    dden: DVec3,
}

/// Points in the coarse winding-number tree.
const GWN_COARSE: usize = 4096;

/// Total kernel weight below which the IMLS blends into the far field (`∓ max_radius`).
const MIN_WEIGHT: f64 = 1.0;

/// Below [`MIN_WEIGHT`], the IMLS value signs the far field where the kernel weight is at
/// least this (more than one point's tail; below it, the flood-filled far-field sign is
/// used as where the weight is 0)...
const FRINGE_WEIGHT: f64 = 0.003;

/// ...the contributing normals agree to this ratio (`|Σ φ n| / Σ φ`)...
const COHERENCE: f64 = 0.9;

/// ...and the value is at least this multiple of the median kernel radius away from 0.
const FRINGE_OFFSET: f64 = 0.25;

/// The value where the kernel weight `den` is below [`MIN_WEIGHT`]: a smooth blend of the
/// IMLS value `num / den` into the far field `far` (they have the same sign away from the
/// surface).
fn blend(num: f64, den: f64, far: f64) -> f64 {
    if den <= 0.0 {
        return far;
    }
    let a = den / MIN_WEIGHT;
    let a = a * a * (3.0 - 2.0 * a);
    a * (num / den) + (1.0 - a) * far
}

impl PointSetSurface {
    /// Build the surface from points and optional (outward) normals.
    pub fn new(
        points: &[DVec3],
        normals: Option<&[DVec3]>,
        params: &PointSetParams,
    ) -> Result<Self, PointSetError> {
        let n = points.len();
        if n < MIN_POINTS {
            return Err(PointSetError::TooFewPoints(n));
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
        for (i, p) in points.iter().enumerate() {
            if !p.is_finite() {
                return Err(PointSetError::NonFinitePoint {
                    index: i,
                    x: p.x,
                    y: p.y,
                    z: p.z,
                });
            }
            if let Some(c) = p.to_array().into_iter().find(|c| c.abs() > 1e60) {
                return Err(PointSetError::OutOfRange { index: i, value: c });
            }
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
        let coords: Vec<[f64; 3]> = points.iter().map(|p| p.to_array()).collect();
        let tree = ImmutableKdTree::<f64, 3>::new_from_slice(&coords)
            .expect("kd-tree construction from finite points");
        // Neighbours needed: the spacing's, and the normals' (PCA) or, with given normals,
        // only the orientation graph's (components).
        let k_nrm = if normals.is_some() {
            params.k_normals.min(K_GRAPH)
        } else {
            params.k_normals
        };
        let k = k_nrm.max(params.k_spacing).min(n - 1);
        let kq = NonZeroUsize::new(k + 1).expect("k + 1 > 0");
        // kNN lists (without the point itself, robust to duplicates: drop index i).
        let knn: Vec<Vec<u32>> = points
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
            .collect();
        let spacing: Vec<f64> = knn
            .par_iter()
            .enumerate()
            .map(|(i, nb)| {
                let m = params.k_spacing.min(nb.len());
                nb[..m]
                    .iter()
                    .map(|&j| (points[j as usize] - points[i]).length())
                    .sum::<f64>()
                    / m as f64
            })
            .collect();
        let median = |v: &[f64]| {
            let mut s = v.to_vec();
            let mid = s.len() / 2;
            *s.select_nth_unstable_by(mid, f64::total_cmp).1
        };
        let med_spacing = median(&spacing);
        if med_spacing.is_nan() || med_spacing <= 0.0 {
            return Err(PointSetError::Coplanar { ratio: 0.0 });
        }
        // Support radius: bandwidth × spacing, clamped to [0.5, 1.5] × the median (the query
        // radius is the largest support, so this bounds the cost; no empty support at
        // isolated points).
        let radius: Vec<f64> = spacing
            .iter()
            .map(|&s| params.bandwidth * s.clamp(0.5 * med_spacing, 1.5 * med_spacing))
            .collect();
        let max_radius = radius.iter().copied().fold(0.0, f64::max);
        let estimated = normals.is_none();
        let (normals, roots) = match normals {
            Some(ns) => {
                let roots = components_roots(points, &knn, params.k_normals.min(K_GRAPH));
                (ns.iter().map(|v| v.normalize()).collect(), roots)
            }
            None => estimate_normals(points, &knn, params.k_normals),
        };
        // Point-cloud winding number: each point becomes an equilateral triangle of area
        // ≈ 0.9 × spacing² (the share of the surface of a point whose k nearest neighbours are
        // at mean distance `spacing`) in its tangent plane, counter-clockwise about its normal.
        let tiny = |i: usize, scale: f64| {
            let (u, v) = normals[i].any_orthonormal_pair();
            let area = scale * 0.9 * spacing[i].max(0.25 * med_spacing).powi(2);
            let rho = (area / (0.75 * 3f64.sqrt())).sqrt();
            let c = |t: f64| points[i] + rho * (t.cos() * u + t.sin() * v);
            let third = 2.0 * std::f64::consts::FRAC_PI_3;
            [c(0.0), c(third), c(2.0 * third)]
        };
        let gwn = Bvh::build(
            (0..n).map(|i| tiny(i, 1.0)).collect(),
            (0..n as u32).collect(),
            0.0,
        );
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
            let tris = idx.iter().map(|&i| tiny(i, scale)).collect();
            Bvh::build(tris, (0..GWN_COARSE as u32).collect(), 0.0)
        });
        let grid = grid::Grid::new(points, &normals, &radius, max_radius);
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
            estimated_normals: estimated,
            components: roots.len(),
            median_spacing: med_spacing,
            median_radius: median(&radius),
            far_components: 0,
        };
        let mut surface = PointSetSurface {
            points: points.to_vec(),
            normals,
            max_radius,
            grid,
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

    /// [`PointSetSurface::new`] from a [`PointCloud`] (e.g. from [`read_xyz`]).
    pub fn from_cloud(cloud: &PointCloud, params: &PointSetParams) -> Result<Self, PointSetError> {
        Self::new(&cloud.points, cloud.normals.as_deref(), params)
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

    /// The IMLS value `Σ φ n·(x − p) / Σ φ` where the total kernel weight is at least the
    /// blending threshold (near the points); `None` elsewhere.
    pub(crate) fn near_value(&self, x: DVec3) -> Option<f64> {
        let (num, den, _) = self.sums(x);
        (den >= MIN_WEIGHT).then(|| num / den)
    }

    /// The value inside the bounding sphere, with the far field (`∓ max_radius`, given the
    /// total kernel weight) from `far`.
    pub(crate) fn value_with_far(&self, x: DVec3, far: impl FnOnce(f64) -> f64) -> f64 {
        let (num, den, _) = self.sums(x);
        if den >= MIN_WEIGHT {
            return num / den;
        }
        blend(num, den, far(den))
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

    fn nearest(&self, x: DVec3) -> (usize, f64) {
        let r = self
            .tree
            .query(&x.to_array())
            .nearest_one::<SquaredEuclidean<f64>>()
            .execute();
        (r.item as usize, r.distance)
    }

    /// IMLS sums at `x`: (Σ φ n·(x−p), Σ φ, Σ φ n).
    fn sums(&self, x: DVec3) -> (f64, f64, DVec3) {
        let s = self.sums_impl::<false>(x);
        (s.num, s.den, s.nsum)
    }

    /// The kernel sums at `x`, with their gradients if `GRAD` (otherwise left at zero). The
    /// sums are computed by the same operations either way (bit-identical).
    #[inline]
    fn sums_impl<const GRAD: bool>(&self, x: DVec3) -> Sums {
        let mut s = Sums::default();
        self.grid.for_each_near(x, self.max_radius, |it| {
            let d = x - it.p;
            let d2 = d.length_squared();
            if d2 < it.r2 {
                let u = 1.0 - d2 / it.r2;
                let u2 = u * u;
                let w = u2 * u2;
                let nd = it.n.dot(d);
                s.num += w * nd;
                s.den += w;
                s.nsum += w * it.n;
                if GRAD {
                    // ∇φ = 4u³ ∇u, ∇u = −2 (x − p) / R².
                    let gw = d * (-8.0 * u2 * u / it.r2);
                    s.dnum += gw * nd + w * it.n;
                    s.dden += gw;
                }
            }
        });
        s
    }

    /// The value and its gradient at `x`; the gradient is NaN where the value is not the
    /// plain IMLS quotient (low kernel weight, far field). The value equals
    /// [`Surface::value`] exactly.
    fn value_grad(&self, x: DVec3) -> (f64, DVec3) {
        let dc = (x - self.sphere.center).length();
        if !x.is_finite() || dc >= self.sphere.radius {
            return (self.value(x), DVec3::NAN);
        }
        let s = self.sums_impl::<true>(x);
        if s.den >= MIN_WEIGHT {
            let f = s.num / s.den;
            return (f, (s.dnum - f * s.dden) / s.den);
        }
        (
            blend(s.num, s.den, self.far_value(x, s.num, s.den, s.nsum)),
            DVec3::NAN,
        )
    }

    /// Far-field value: `∓ max_radius`, negative inside. `(num, den, nsum)` are the kernel
    /// sums at `x`. Decided, in order, by:
    /// - zero or negligible weight (below [`FRINGE_WEIGHT`]: farther than 0.87 `R_i` from
    ///   every point): the flood-filled sign of the region no kernel reaches, at `x`'s
    ///   cell or its clear neighbours ([`FarCache`]);
    /// - low weight, where the contributing normals agree (`|Σ φ n| ≥ 0.9 Σ φ`) and the
    ///   IMLS value is clearly off the surface (`|f| ≥` [`FRINGE_OFFSET`] × the median
    ///   kernel radius): the sign of the IMLS value, which there agrees with the winding
    ///   number and keeps the blend free of spurious zeros;
    /// - otherwise the point-cloud winding number at `x` (above 1/2: inside).
    fn far_value(&self, x: DVec3, num: f64, den: f64, nsum: DVec3) -> f64 {
        let r = self.max_radius;
        if den < FRINGE_WEIGHT {
            match self.far_cache.get(x) {
                1 => return r,
                -1 => return -r,
                _ => {}
            }
        } else if nsum.length_squared() >= (COHERENCE * den).powi(2) {
            let f = num / den;
            if f.abs() >= FRINGE_OFFSET * self.stats.median_radius {
                return if f < 0.0 { -r } else { r };
            }
        }
        self.far_value_uncached(x, den)
    }

    fn far_value_uncached(&self, x: DVec3, den: f64) -> f64 {
        let coarse = match &self.gwn_coarse {
            Some(c) if den == 0.0 => Some(c.winding_number(x)),
            _ => None,
        };
        let w = match coarse {
            Some(w) if !(0.1..=0.9).contains(&w) => w,
            _ => self.gwn.winding_number(x),
        };
        if w > 0.5 {
            -self.max_radius
        } else {
            self.max_radius
        }
    }

    /// Generalized winding number of the oriented point cloud at `x` (≈ 1 inside, ≈ 0
    /// outside; meaningful at distances above the spacing).
    pub fn winding_number(&self, x: DVec3) -> f64 {
        self.gwn.winding_number(x)
    }

    /// Local feature size (distance to the medial axis) estimated near `x`: the smaller
    /// shrinking-ball radius at the nearest point of a subsample (≤ 1024 points) of the input.
    /// Computed once (in parallel) on first use.
    pub fn estimate_local_feature_size(&self, x: DVec3) -> f64 {
        if !x.is_finite() {
            return f64::NAN;
        }
        let s = self.lfs_sample();
        let r = s
            .tree
            .query(&x.to_array())
            .nearest_one::<SquaredEuclidean<f64>>()
            .execute();
        s.lfs[r.item as usize]
    }

    fn lfs_sample(&self) -> &LfsSample {
        self.lfs.get_or_init(|| {
            let n = self.points.len();
            let step = n.div_ceil(1024).max(1);
            let idx: Vec<usize> = (0..n).step_by(step).collect();
            // Neighbours within twice the kernel radius are noise-level: ignored.
            let rho = 2.0 * self.stats.median_radius;
            let cap = (self.hi - self.lo).length();
            let lfs: Vec<f64> = idx
                .par_iter()
                .map(|&i| {
                    // The kernel-averaged normal: less noisy than the PCA normal.
                    let n = self.gradient(self.points[i]);
                    let n = if n == DVec3::ZERO { self.normals[i] } else { n };
                    let inner = self.shrinking_ball(i, -n, rho, cap);
                    let outer = self.shrinking_ball(i, n, rho, cap);
                    inner.min(outer)
                })
                .collect();
            let points: Vec<DVec3> = idx.iter().map(|&i| self.points[i]).collect();
            let coords: Vec<[f64; 3]> = points.iter().map(|p| p.to_array()).collect();
            let tree = ImmutableKdTree::<f64, 3>::new_from_slice(&coords)
                .expect("kd-tree construction from finite points");
            LfsSample { points, lfs, tree }
        })
    }

    /// Radius of the ball tangent at point `i` with center on the side of the unit vector `n`
    /// that contains no input point farther than `rho` from point `i`, capped at `cap`.
    fn shrinking_ball(&self, i: usize, n: DVec3, rho: f64, cap: f64) -> f64 {
        let p = self.points[i];
        let mut r = cap;
        let kq = NonZeroUsize::new(32.min(self.points.len())).expect("nonzero");
        for _ in 0..40 {
            let c = p + n * r;
            // The nearest point to c that is not a near neighbour of p (usually the nearest).
            let (j, _) = self.nearest(c);
            let q = if (self.points[j] - p).length_squared() > rho * rho {
                Some(self.points[j])
            } else {
                self.tree
                    .query(&c.to_array())
                    .nearest_n::<SquaredEuclidean<f64>>(kq)
                    .execute()
                    .iter()
                    .map(|x| self.points[x.item as usize])
                    .find(|q| (*q - p).length_squared() > rho * rho)
            };
            let Some(q) = q else { break };
            if (q - c).length() >= r * (1.0 - 1e-9) {
                break;
            }
            let pq = q - p;
            let den = 2.0 * n.dot(pq);
            if den.is_nan() || den <= 0.0 {
                break;
            }
            let r_new = pq.length_squared() / den;
            if r_new.is_nan() || r_new >= r {
                break;
            }
            r = r_new;
        }
        r
    }

    /// Deterministic well-spread sample of point indices (for seeds).
    fn spread_indices(&self, count: usize, seed: u64) -> Vec<usize> {
        let mut rng = SplitMix64(seed ^ 0x0B5E_55ED);
        let n = self.points.len();
        (0..count)
            .map(|_| (rng.next_u64() % n as u64) as usize)
            .collect()
    }
}

/// Estimate normals by PCA and orient them by MST propagation; returns the normals and the
/// root (highest point) of each component of the kNN graph.
fn estimate_normals(points: &[DVec3], knn: &[Vec<u32>], k: usize) -> (Vec<DVec3>, Vec<usize>) {
    let mut normals: Vec<DVec3> = knn
        .par_iter()
        .enumerate()
        .map(|(i, nb)| {
            let m = k.min(nb.len());
            let it = std::iter::once(points[i]).chain(nb[..m].iter().map(|&j| points[j as usize]));
            let (cov, _) = linalg::covariance(it);
            let (_, vecs) = linalg::sym_eigen(cov);
            vecs[0]
        })
        .collect();
    let roots = propagate(points, knn, k.min(K_GRAPH), &mut normals);
    (normals, roots)
}

/// Components of the kNN graph (its first `k` neighbours, symmetrized), as the highest point
/// (largest z, then smallest index) of each, in decreasing z order.
fn components_roots(points: &[DVec3], knn: &[Vec<u32>], k: usize) -> Vec<usize> {
    let n = points.len();
    let mut uf: Vec<u32> = (0..n as u32).collect();
    fn find(uf: &mut [u32], mut x: u32) -> u32 {
        while uf[x as usize] != x {
            uf[x as usize] = uf[uf[x as usize] as usize];
            x = uf[x as usize];
        }
        x
    }
    for (i, nb) in knn.iter().enumerate() {
        for &j in &nb[..k.min(nb.len())] {
            let (a, b) = (find(&mut uf, i as u32), find(&mut uf, j));
            if a != b {
                uf[a.max(b) as usize] = a.min(b);
            }
        }
    }
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| points[b].z.total_cmp(&points[a].z).then(a.cmp(&b)));
    let mut seen = vec![false; n];
    let mut roots = Vec::new();
    for i in order {
        let r = find(&mut uf, i as u32) as usize;
        if !seen[r] {
            seen[r] = true;
            roots.push(i);
        }
    }
    roots
}

/// Neighbours per point in the orientation graph (Hoppe et al. use about 8).
const K_GRAPH: usize = 8;

/// Prim's (approximate) minimum spanning tree over the symmetric kNN graph with weights
/// `1 − |n_i·n_j|` (plus a penalty for edges along the normals),
/// flipping each normal to agree with its parent. Components are started from their highest
/// point (largest z, then smallest index), whose normal is oriented to +z.
fn propagate(points: &[DVec3], knn: &[Vec<u32>], k: usize, normals: &mut [DVec3]) -> Vec<usize> {
    let n = points.len();
    // Symmetric adjacency (CSR).
    let mut deg = vec![0u32; n + 1];
    for (i, nb) in knn.iter().enumerate() {
        for &j in &nb[..k.min(nb.len())] {
            deg[i] += 1;
            deg[j as usize] += 1;
        }
    }
    let mut start = vec![0usize; n + 1];
    for i in 0..n {
        start[i + 1] = start[i] + deg[i] as usize;
    }
    let mut fill = start.clone();
    let mut adj = vec![0u32; start[n]];
    for (i, nb) in knn.iter().enumerate() {
        for &j in &nb[..k.min(nb.len())] {
            adj[fill[i]] = j;
            fill[i] += 1;
            adj[fill[j as usize]] = i as u32;
            fill[j as usize] += 1;
        }
    }
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| points[b].z.total_cmp(&points[a].z).then(a.cmp(&b)));
    let mut visited = vec![false; n];
    let mut roots = Vec::new();
    // Prim's algorithm with a bucket queue (weights in [0, 2] quantized to 1/128): an
    // approximate minimum spanning tree, enough for orientation and O(1) per edge. Buckets are
    // stacks, so the order is deterministic.
    const BUCKETS: usize = 257;
    let mut buckets: Vec<Vec<(u32, u32)>> = vec![Vec::new(); BUCKETS];
    for &root in &order {
        if visited[root] {
            continue;
        }
        roots.push(root);
        visited[root] = true;
        if normals[root].z < 0.0 {
            normals[root] = -normals[root];
        }
        let push = |buckets: &mut [Vec<(u32, u32)>],
                    i: usize,
                    normals: &[DVec3],
                    visited: &[bool],
                    cur: &mut usize| {
            for &j in &adj[start[i]..start[i + 1]] {
                if !visited[j as usize] {
                    // Hoppe's 1 − |n_i·n_j|, plus a penalty for edges along the normals: those
                    // jump across thin parts (two sheets with parallel normals), where copying
                    // the orientation is wrong.
                    let (ni, nj) = (normals[i], normals[j as usize]);
                    let d = (points[j as usize] - points[i]).normalize_or_zero();
                    let w = 1.0 - ni.dot(nj).abs() + 0.5 * (ni.dot(d).abs() + nj.dot(d).abs());
                    let b = ((w * 128.0) as usize).min(BUCKETS - 1);
                    buckets[b].push((j, i as u32));
                    *cur = (*cur).min(b);
                }
            }
        };
        let mut cur = BUCKETS;
        push(&mut buckets, root, normals, &visited, &mut cur);
        loop {
            while cur < BUCKETS && buckets[cur].is_empty() {
                cur += 1;
            }
            if cur == BUCKETS {
                break;
            }
            let (j, i) = buckets[cur].pop().expect("non-empty bucket");
            let j = j as usize;
            if visited[j] {
                continue;
            }
            visited[j] = true;
            if normals[i as usize].dot(normals[j]) < 0.0 {
                normals[j] = -normals[j];
            }
            push(&mut buckets, j, normals, &visited, &mut cur);
        }
    }
    roots
}

impl Surface for PointSetSurface {
    fn bounding_sphere(&self) -> BoundingSphere {
        self.sphere
    }

    fn value(&self, x: DVec3) -> f64 {
        if !x.is_finite() {
            return f64::NAN;
        }
        let dc = (x - self.sphere.center).length();
        if dc >= self.sphere.radius {
            // Positive on and outside the bounding sphere (far from every point).
            return dc - self.sphere.radius + self.max_radius;
        }
        let (num, den, nsum) = self.sums(x);
        if den >= MIN_WEIGHT {
            return num / den;
        }
        blend(num, den, self.far_value(x, num, den, nsum))
    }

    /// Points on the MLS surface: the highest and lowest input points of each component
    /// (horizontal tangent planes, as in the paper's P1) and 32 random input points, each
    /// projected onto the surface (those that fail to converge are dropped).
    fn seed_points(&self, seed: u64) -> Vec<DVec3> {
        let mut idx = self.roots.clone();
        // Lowest point of each component: the last of each component in z order is costly to
        // track; use the global lowest point and random points instead.
        let low = (0..self.points.len())
            .min_by(|&a, &b| {
                self.points[a]
                    .z
                    .total_cmp(&self.points[b].z)
                    .then(a.cmp(&b))
            })
            .unwrap_or(0);
        idx.push(low);
        idx.extend(self.spread_indices(32, seed));
        idx.iter()
            .filter_map(|&i| self.project(self.points[i]))
            .collect()
    }

    fn gradient(&self, x: DVec3) -> DVec3 {
        if !x.is_finite() {
            return DVec3::NAN;
        }
        let (_, den, nsum) = self.sums(x);
        if den > 0.0 {
            nsum.normalize_or_zero()
        } else {
            let (j, _) = self.nearest(x);
            let d = (x - self.points[j]).normalize_or_zero();
            if self.normals[j].dot(d) < 0.0 { -d } else { d }
        }
    }

    /// Newton projection: where the kernel weight is at least the blending threshold,
    /// `x ← x − f ∇f / |∇f|²` with the exact gradient of the IMLS quotient (quadratic
    /// convergence); at lower weight, `x ← x − f n̄` along the averaged normal. Steps are
    /// capped at the largest kernel radius; stops when a step is below the tolerance.
    fn project(&self, p: DVec3) -> Option<DVec3> {
        if !p.is_finite() {
            return None;
        }
        let tol = self.tolerance();
        let mut x = p;
        for _ in 0..50 {
            let s = self.sums_impl::<true>(x);
            if s.den.is_nan() || s.den <= 1e-12 {
                // Out of the support: jump to the nearest point first.
                let (j, _) = self.nearest(x);
                x = self.points[j];
                continue;
            }
            let f = s.num / s.den;
            let grad = (s.dnum - f * s.dden) / s.den;
            let g2 = grad.length_squared();
            let step = if s.den >= MIN_WEIGHT && g2 > 0.0 && g2.is_finite() {
                grad * (f / g2)
            } else {
                let g = s.nsum.normalize_or_zero();
                if g == DVec3::ZERO {
                    return None;
                }
                g * f
            };
            // Cap steps at the kernel radius to stay in the region where f is meaningful.
            let len = step.length();
            if !len.is_finite() {
                return None;
            }
            x -= if len > self.max_radius {
                step * (self.max_radius / len)
            } else {
                step
            };
            if len < tol {
                return Some(x);
            }
        }
        None
    }

    /// Bipolar oracle: Newton steps on the IMLS value (close to a signed distance near the
    /// surface, with an exact gradient) kept inside the sign-change bracket, Illinois
    /// (modified regula falsi) steps where the gradient is unavailable or the step leaves the
    /// bracket, and bisection when the bracket shrinks slowly; stops when the bracket, |f|
    /// or the Newton step is below the tolerance.
    fn crossing(&self, a: DVec3, fa: f64, b: DVec3, fb: f64) -> DVec3 {
        crate::roots::newton_bracketed(|x| self.value_grad(x), a, fa, b, fb, self.tolerance())
    }

    /// Intersection oracle: sign changes of the value sampled at [`Surface::crossing_step`],
    /// each refined by [`Surface::crossing`].
    fn crossings(&self, a: DVec3, b: DVec3, out: &mut Vec<DVec3>) {
        crate::roots::sample_crossings(
            |x| self.value(x),
            |p0, f0, p1, f1| self.crossing(p0, f0, p1, f1),
            a,
            b,
            self.crossing_step(),
            out,
        );
    }

    /// Half the median kernel radius: the IMLS surface does not oscillate at smaller scales,
    /// so two crossings closer than this are not expected (and may be missed).
    fn crossing_step(&self) -> f64 {
        0.5 * self.stats.median_radius
    }

    fn dm_inf_hint(&self) -> Option<f64> {
        let s = self.lfs_sample();
        let mut v = s.lfs.clone();
        if v.is_empty() {
            return None;
        }
        // A low percentile (5%) rather than the minimum: robust to a few noisy estimates.
        let k = v.len() / 20;
        let x = *v.select_nth_unstable_by(k, f64::total_cmp).1;
        let _ = &s.points;
        (x > 0.0).then_some(x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::cell::Cell;

    /// `value_grad` returns exactly `value`, and a gradient matching central differences
    /// near the surface (NaN in the blend zone and beyond).
    #[test]
    fn value_grad_matches_value_and_finite_differences() {
        let n = 3000;
        let pts: Vec<DVec3> = (0..n)
            .map(|i| {
                let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
                let t = i as f64 * 2.399963229728653;
                let r = (1.0 - z * z).sqrt();
                DVec3::new(r * t.cos(), r * t.sin(), z) * (1.0 + 0.1 * (3.0 * z).sin())
            })
            .collect();
        let s = PointSetSurface::new(&pts, None, &PointSetParams::default()).unwrap();
        let mut rng = SplitMix64(11);
        let (mut near, mut far) = (0, 0);
        for _ in 0..400 {
            let x = rng.unit_vector() * (0.7 + 0.6 * rng.next_f64());
            let (f, g) = s.value_grad(x);
            assert_eq!(f.to_bits(), s.value(x).to_bits(), "{x}");
            if g.is_nan() {
                far += 1;
                continue;
            }
            near += 1;
            let h = 1e-6;
            let fd = DVec3::new(
                s.value(x + DVec3::X * h) - s.value(x - DVec3::X * h),
                s.value(x + DVec3::Y * h) - s.value(x - DVec3::Y * h),
                s.value(x + DVec3::Z * h) - s.value(x - DVec3::Z * h),
            ) / (2.0 * h);
            assert!(
                (fd - g).length() < 1e-4 * g.length().max(1.0),
                "{x}: {g} vs {fd}"
            );
        }
        assert!(near > 50 && far > 50, "{near} near, {far} far");
        // The crossing oracle lands on the surface.
        let (a, b) = (DVec3::ZERO, DVec3::new(2.0, 0.1, 0.3));
        let c = s.crossing(a, s.value(a), b, s.value(b));
        assert!(s.value(c).abs() < 1e-6, "{c}");
    }
}
