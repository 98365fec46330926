//! A smoothed polyhedron oracle for remeshing (ours, after section 6.6.4): the IMLS surface
//! ([`PointSetSurface`], the shared `imls` module) of a dense, deterministic, area-uniform
//! sample of the triangles with their exact face normals.
//!
//! When: restricted Delaunay refinement is proved for smooth surfaces; on a polyhedron every
//! edge is a crease. The exact polyhedron oracle is the default of `cargo xtask mesh` and
//! terminates as a closed manifold on the test models (the manifold patch has termination
//! rules), but its guarantees do not apply at creases. This smoothed oracle is an
//! alternative (`--smooth-polyhedron`): the IMLS surface equals the input's plane on the flat
//! part of each triangle and blends the planes over the kernel radius (a few sample spacings)
//! at creases, so the surface is smooth and the output stays within about the kernel radius
//! of sharp edges (reported as the sharp-edge deviation), and much closer elsewhere.
//! (Historical note: before the overflow-free clipping of far circumcenters, the exact oracle
//! produced holes that the manifold patch tried to repair without end.)
//!
//! [`Surface::project`] is the exact closest point on the *input* triangles, so that
//! verification (`verify::check_against`) measures the distance to the input itself.

use super::exact::PolyhedronSurface;
use crate::imls::{MIN_POINTS, PointSetError, PointSetParams, PointSetSurface};
use crate::roots::{Ends, SplitMix64};
use crate::{BoundingSphere, Surface};
use glam::DVec3;

/// Default number of samples of [`SmoothPolyhedron::new`].
pub const DEFAULT_SAMPLES: usize = 100_000;

/// Default kernel radius of [`SmoothPolyhedron::new`], in sample spacings (the samples are
/// noise-free, so less averaging than for scanned points is needed).
pub const DEFAULT_BANDWIDTH: f64 = 3.0;

/// A polyhedron seen through a smooth IMLS approximation. See the module documentation.
///
/// ```
/// use glam::DVec3;
/// use meshio::TriMesh;
/// use oracle::Surface;
/// use oracle::polyhedron::{PolyhedronSurface, SmoothPolyhedron};
/// let mesh = TriMesh {
///     vertices: vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z],
///     triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
/// };
/// let s = SmoothPolyhedron::new(PolyhedronSurface::new(&mesh).unwrap(), 5000).unwrap();
/// assert!(s.value(DVec3::splat(0.1)) < 0.0 && s.value(DVec3::splat(2.0)) > 0.0);
/// // Projection is onto the input triangles.
/// let p = s.project(DVec3::new(0.2, 0.2, -1.0)).unwrap();
/// assert!(p.z.abs() < 1e-12);
/// ```
pub struct SmoothPolyhedron {
    exact: PolyhedronSurface,
    imls: PointSetSurface,
}

impl std::fmt::Debug for SmoothPolyhedron {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SmoothPolyhedron")
            .field("exact", &self.exact.stats())
            .field("imls", &self.imls)
            .finish()
    }
}

impl SmoothPolyhedron {
    /// Sample about `samples` points (at least one per non-degenerate triangle's share of the
    /// area, by error diffusion, deterministic) with the outward face normals, and fit the IMLS
    /// surface on them.
    pub fn new(exact: PolyhedronSurface, samples: usize) -> Result<Self, PointSetError> {
        let params = PointSetParams {
            bandwidth: DEFAULT_BANDWIDTH,
            ..PointSetParams::default()
        };
        Self::with_params(exact, samples, &params)
    }

    /// As [`SmoothPolyhedron::new`] with explicit IMLS parameters.
    pub fn with_params(
        exact: PolyhedronSurface,
        samples: usize,
        params: &PointSetParams,
    ) -> Result<Self, PointSetError> {
        let (mut pts, mut nrm) = exact.area_samples(samples.max(MIN_POINTS));
        if !exact.is_watertight() {
            // Only the samples on the boundary of the solid {w > 1/2}, each with the normal
            // pointing out of it (see `solid.rs`): an interior membrane, the inner sheets of
            // overlapping shells and the orientation of flipped faces then leave no trace.
            use rayon::prelude::*;
            let out: Vec<Option<DVec3>> = pts
                .par_iter()
                .zip(&nrm)
                .map(|(&p, &n)| exact.outward_at(p, n))
                .collect();
            let kept: (Vec<DVec3>, Vec<DVec3>) = pts
                .iter()
                .zip(&out)
                .filter_map(|(&p, o)| o.map(|n| (p, n)))
                .unzip();
            if kept.0.len() >= MIN_POINTS {
                (pts, nrm) = kept;
            }
        }
        let imls = PointSetSurface::new(&pts, Some(&nrm), params)?;
        Ok(SmoothPolyhedron { exact, imls })
    }

    /// The input polyhedron (exact oracle).
    pub fn exact(&self) -> &PolyhedronSurface {
        &self.exact
    }

    /// The IMLS surface actually meshed.
    pub fn imls(&self) -> &PointSetSurface {
        &self.imls
    }
}

impl PolyhedronSurface {
    /// About `n` points uniform with respect to area on the non-degenerate triangles (error
    /// diffusion over the triangles in input order, uniform points inside each from a fixed
    /// seed), with the outward unit face normal of each.
    pub fn area_samples(&self, n: usize) -> (Vec<DVec3>, Vec<DVec3>) {
        let tris: Vec<[DVec3; 3]> = self
            .faces
            .iter()
            .map(|(t, _)| t.map(|i| self.vertices[i as usize]))
            .collect();
        let areas: Vec<f64> = tris
            .iter()
            .map(|t| 0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length())
            .collect();
        let total: f64 = areas.iter().sum();
        let mut rng = SplitMix64(0x5A3F_1E5D_0000_0001);
        let (mut pts, mut nrm) = (Vec::with_capacity(n + 16), Vec::with_capacity(n + 16));
        let mut carry = 0.0;
        for (t, &a) in tris.iter().zip(&areas) {
            carry += a / total * n as f64;
            let k = carry.floor();
            carry -= k;
            let normal = self.orientation * (t[1] - t[0]).cross(t[2] - t[0]).normalize_or_zero();
            if normal == DVec3::ZERO {
                continue;
            }
            for _ in 0..k as usize {
                let (mut u, mut v) = (rng.next_f64(), rng.next_f64());
                if u + v > 1.0 {
                    (u, v) = (1.0 - u, 1.0 - v);
                }
                pts.push(t[0] + (t[1] - t[0]) * u + (t[2] - t[0]) * v);
                nrm.push(normal);
            }
        }
        (pts, nrm)
    }
}

impl Surface for SmoothPolyhedron {
    fn bounding_sphere(&self) -> BoundingSphere {
        self.imls.bounding_sphere()
    }
    /// The IMLS value within the largest kernel radius `R` of the input triangles. Farther,
    /// the exact polyhedron's value (signed distance, or its sign by ray parity, for
    /// watertight inputs; `1/2 − w` otherwise, so that the solid is {w > 1/2} away from the
    /// samples, over holes for instance), which has the same sign there and is cheaper than
    /// the IMLS far field.
    fn value(&self, p: DVec3) -> f64 {
        if p.is_finite() {
            if let Some(v) = self
                .imls
                .bounding_sphere()
                .contains(p)
                .then(|| self.imls.near_value(p))
                .flatten()
            {
                return v;
            }
            let r = self.imls.max_radius();
            if self.exact.bvh.closest_within(p, r * r).is_none() {
                let d = self.exact.value(p);
                if self.imls.bounding_sphere().contains(p) {
                    if d < 0.0 {
                        return d.min(-r);
                    } else if d > 0.0 {
                        return d.max(r);
                    }
                }
            } else if self.imls.bounding_sphere().contains(p) {
                // Blending zone: the far field signed by the exact polyhedron (its value
                // is the signed distance here), not by the costly winding number.
                let d = self.exact.value(p);
                return self
                    .imls
                    .value_with_far(p, |_| if d < 0.0 { -r } else { r });
            }
        }
        self.imls.value(p)
    }
    fn tolerance(&self) -> f64 {
        self.imls.tolerance()
    }
    /// Illinois (safeguarded regula falsi) on [`SmoothPolyhedron`]'s value.
    fn crossing(&self, a: DVec3, fa: f64, b: DVec3, fb: f64) -> DVec3 {
        crate::roots::illinois(|x| self.value(x), Ends::new(a, fa, b, fb), self.tolerance())
    }
    /// Sign changes of the value sampled at [`Surface::crossing_step`], each refined by
    /// [`Surface::crossing`].
    fn crossings(&self, a: DVec3, b: DVec3, out: &mut Vec<DVec3>) {
        crate::roots::sample_crossings(self, a, b, out);
    }
    fn crossing_step(&self) -> f64 {
        self.imls.crossing_step()
    }
    /// The input's seeds (one per component at least), projected onto the IMLS surface.
    fn seed_points(&self, seed: u64) -> Vec<DVec3> {
        let mut out: Vec<DVec3> = self
            .exact
            .seed_points(seed)
            .into_iter()
            .filter_map(|p| self.imls.project(p))
            .collect();
        if out.is_empty() {
            out = self.imls.seed_points(seed);
        }
        out
    }
    fn gradient(&self, p: DVec3) -> DVec3 {
        self.imls.gradient(p)
    }
    /// Exact closest point on the input triangles.
    fn project(&self, p: DVec3) -> Option<DVec3> {
        self.exact.project(p)
    }
    /// `verify` measures a smoothed mesh against the input triangles: [`Surface::project`]
    /// is their exact closest point.
    fn exact_projection(&self) -> bool {
        true
    }
}
