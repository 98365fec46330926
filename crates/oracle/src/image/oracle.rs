//! The voxel-image oracles (section 6.6.2): the bipolar oracle by a block walk and cell-wise
//! root finding on the trilinear polynomial, the intersection oracle, P1 from the voxel scan
//! and P2 from distance transforms.

use super::ImageSurface;
use super::blocks::{self, Blocks};
use super::distance;
use super::surface::{floor3, trilinear};
use super::topology::{self, Topology};
use crate::roots::ParamBracket;
use crate::{BoundingSphere, Surface};
use glam::DVec3;

impl ImageSurface {
    /// Topology of the level set from the voxel grid (computed once, then cached): see
    /// [`Topology`].
    pub fn topology(&self) -> &Topology {
        self.topo.get_or_init(|| {
            // One pass over the voxels for the node signs, shared with the block summary of
            // the crossings (the mesher asks for both).
            let bits = self.inside_bits_rows();
            self.blocks
                .get_or_init(|| Blocks::from_bits(self.dims_isize(), &bits));
            topology::compute(self, &bits)
        })
    }

    /// The voxel-scan component (index into [`Topology::component_seeds`]) of a point `p` of
    /// S (world space): see [`Topology::component_at`].
    pub fn component_of(&self, p: DVec3) -> Option<usize> {
        self.topology().component_at(self.inv.transform_point3(p))
    }

    /// The sum of the genera of the level set's components, from the voxel grid (computed
    /// once, then cached): the number of surface components (the vanishing ones included)
    /// less the Euler characteristic of the inside, which the grid gives exactly (see
    /// `topology::euler`). `None` when the scan found zero-volume components
    /// ([`Topology::vanishing_components`]): the sum would count cavities that are not
    /// surfaces. A mesh with the topology of S has this total genus.
    pub fn scan_genus(&self) -> Option<usize> {
        *self.genus.get_or_init(|| {
            let t = self.topology();
            if t.vanishing_components > 0 {
                return None;
            }
            let surfaces = (t.inside_components + t.outside_components) as i64 - 1;
            let genus = surfaces - topology::inside_euler(self);
            // The genus of each closed surface is >= 0; a negative sum would be a bug.
            debug_assert!(genus >= 0, "{surfaces} surfaces, genus {genus}");
            usize::try_from(genus).ok()
        })
    }

    /// Number of connected components of the surface found by the voxel scan
    /// ([`Topology::surface_components`]). The mesh should have exactly this many.
    pub fn component_count(&self) -> usize {
        self.topology().surface_components
    }
}

impl ImageSurface {
    /// The piece of the segment `va + dv t` (voxel coordinates) where the block walk finds
    /// the first sign change from `t = 0` (sign of `fa`), with exact values at both ends;
    /// `None` if the walk is inconclusive.
    fn locate(&self, va: DVec3, dv: DVec3, fa: f64) -> Option<ParamBracket> {
        let blocks = self
            .blocks
            .get_or_init(|| Blocks::from_bits(self.dims_isize(), &self.inside_bits_rows()));
        let at = |t: f64| self.value_voxel(va + dv * t);
        let run = fa < 0.0;
        let mut found = None;
        // The last exact value computed by the walk (at the end of a mixed piece).
        let mut last = (0.0, fa);
        blocks.walk(va, dv, |u0, u1, flag| {
            if flag != blocks::MIXED {
                // Uniform: the sign cannot change inside; a different sign than the walk's
                // means a sign change at a face (rounding): inconclusive.
                return (flag == blocks::IN) == run;
            }
            let g1 = at(u1);
            if g1.is_nan() || (g1 < 0.0) == run {
                last = (u1, g1);
                return !g1.is_nan();
            }
            // The value at u0 only serves the first false-position step: unknown (NaN, so a
            // bisection step) unless the previous piece computed it.
            let f0 = if last.0 == u0 { last.1 } else { f64::NAN };
            found = Some(ParamBracket {
                t0: u0,
                f0,
                t1: u1,
                f1: g1,
                neg0: run,
            });
            false
        });
        found
    }

    /// Cell-wise root finding in the bracket `br` of the segment `va + dv t` (see
    /// [`Surface::crossing`]), down to the parameter tolerance `ttol`.
    fn solve_cells(&self, va: DVec3, dv: DVec3, mut br: ParamBracket, ttol: f64) -> ParamBracket {
        let at = |t: f64| va + dv * t;
        let mut width_two_ago = f64::INFINITY;
        let mut width_one_ago = br.t1 - br.t0;
        for _ in 0..256 {
            let w = br.t1 - br.t0;
            if w <= ttol {
                break;
            }
            let denom = br.f1 - br.f0;
            let mut t = if w > 0.5 * width_two_ago || !(denom != 0.0 && denom.is_finite()) {
                0.5 * (br.t0 + br.t1)
            } else {
                br.t0 - br.f0 * w / denom
            };
            if !(t > br.t0 && t < br.t1) {
                t = 0.5 * (br.t0 + br.t1);
            }
            let cell = floor3(at(t));
            // Parameter range of the segment inside the cell, within the bracket.
            let (mut u0, mut u1) = (br.t0, br.t1);
            for ax in 0..3 {
                if dv[ax] != 0.0 {
                    let e0 = (cell[ax] - va[ax]) / dv[ax];
                    let e1 = (cell[ax] + 1.0 - va[ax]) / dv[ax];
                    u0 = u0.max(e0.min(e1));
                    u1 = u1.min(e0.max(e1));
                }
            }
            let (u0, u1) = (u0.min(t), u1.max(t));
            let c = self.cell_corners(cell);
            if c.iter().any(|v| v.is_nan()) {
                break;
            }
            let poly = |u: f64| trilinear(&c, at(u) - cell);
            let (g0, g1) = (poly(u0), poly(u1));
            if (g0 < 0.0) != (g1 < 0.0) {
                let sub = ParamBracket {
                    t0: u0,
                    f0: g0,
                    t1: u1,
                    f1: g1,
                    neg0: g0 < 0.0,
                };
                br = sub.solve(poly, ttol);
                break;
            }
            if (g0 < 0.0) == br.neg0 {
                br.t0 = u1;
                br.f0 = g1;
            } else {
                br.t1 = u0;
                br.f1 = g0;
            }
            width_two_ago = width_one_ago;
            width_one_ago = w;
        }
        br
    }
}

impl Surface for ImageSurface {
    fn bounding_sphere(&self) -> BoundingSphere {
        self.sphere
    }

    #[inline]
    fn value(&self, p: DVec3) -> f64 {
        self.value_voxel(self.inv.transform_point3(p))
    }

    /// Block walk (segments longer than a block), then cell-wise root finding. The segment is
    /// walked through the sign summary of `BLOCK³`-cell blocks (see the `blocks` module):
    /// uniform blocks are skipped without touching the voxels, and the image is evaluated
    /// where the segment leaves each mixed block, until the sign differs from the sign at `a`.
    /// That block's piece is the bracket (if the walk is inconclusive, e.g. a root within
    /// rounding of a block face, the bracket is the whole segment). Then each round picks a
    /// candidate (false position, or the midpoint when the bracket did not halve in two rounds
    /// or a value is unknown), fetches the 8 corners of the voxel cell holding it, and
    /// evaluates the cell's trilinear polynomial where the segment enters and leaves the cell:
    /// if the signs differ there, the root is solved on that polynomial (Illinois, no more
    /// fetches) to the tolerance; otherwise the whole cell piece is cut off the bracket. The
    /// bracket `[t0, t1]` keeps opposite signs (by `value < 0`). Returns the midpoint of a
    /// final bracket shorter than the tolerance.
    fn crossing(&self, a: DVec3, fa: f64, b: DVec3, fb: f64) -> DVec3 {
        let tol = self.tolerance();
        let d = b - a;
        let len = d.length();
        if !(len > tol && fa.is_finite() && fb.is_finite()) {
            return crate::roots::bisect(
                |p| self.value(p),
                crate::roots::Ends::new(a, fa, b, fb),
                tol,
            );
        }
        let ttol = tol / len;
        let va = self.inv.transform_point3(a);
        let dv = self.inv.transform_vector3(d);
        // A segment of a block or less is solved directly (the walk would cost more than it
        // saves).
        let br = if dv.length_squared() <= (blocks::BLOCK * blocks::BLOCK) as f64 {
            None
        } else {
            self.locate(va, dv, fa)
        };
        let br = br.unwrap_or_else(|| ParamBracket::new(fa, fb));
        let br = self.solve_cells(va, dv, br, ttol);
        a + d * (0.5 * (br.t0 + br.t1))
    }

    /// Samples the segment every [`Surface::crossing_step`] (a quarter voxel) and refines each
    /// sign change with [`Surface::crossing`] (cell-wise); sorted from `a`.
    fn crossings(&self, a: DVec3, b: DVec3, out: &mut Vec<DVec3>) {
        let len = (b - a).length();
        let n = ((len / self.crossing_step()).ceil() as usize).clamp(1, 1 << 24);
        let mut p0 = a;
        let mut f0 = self.value(a);
        for i in 1..=n {
            let p1 = a + (b - a) * (i as f64 / n as f64);
            let f1 = self.value(p1);
            if (f0 < 0.0) != (f1 < 0.0) {
                out.push(self.crossing(p0, f0, p1, f1));
            }
            p0 = p1;
            f0 = f1;
        }
    }

    /// A quarter of the smallest voxel size: the trilinear interpolant has at most two
    /// crossings per cell along a line, usually one.
    fn crossing_step(&self) -> f64 {
        let s = self.vol.spacing();
        0.25 * s.x.min(s.y).min(s.z)
    }

    /// One point on every surface component found by the voxel scan (see [`Topology`]), seed
    /// tetrahedra around the small ones and crossing points picked deterministically from
    /// `seed`: [`Topology::seed_points_within`] the [`ImageSurface::seed_budget`] (64 points
    /// by default).
    fn seed_points(&self, seed: u64) -> Vec<DVec3> {
        self.topology().seed_points_within(seed, self.seed_budget())
    }

    /// Central differences of the interpolant in voxel space (step 1e-4 voxel), mapped to world
    /// space by the inverse-transpose of the affine.
    fn gradient(&self, p: DVec3) -> DVec3 {
        let v = self.inv.transform_point3(p);
        let h = 1e-4;
        let g = crate::roots::central_difference(|q| self.value_voxel(q), v, h);
        self.inv_t * g
    }

    /// Integer voxels are the true values rounded to a quantum `q` (`|scl_slope|`): each corner
    /// of the interpolating cell is off by up to `q / 2`, each component of the interpolant's
    /// gradient by up to `q / h` (h the smallest voxel size), so its direction by up to
    /// `asin(min(1, sqrt(3) q / (h |grad|)))`. 0 for float voxels.
    fn normal_uncertainty_deg(&self, p: DVec3) -> f64 {
        if !self.vol.dtype().is_integer() {
            return 0.0;
        }
        let q = self.vol.scaling().0.abs();
        let s = self.vol.spacing();
        let h = s.x.min(s.y).min(s.z);
        let g = self.gradient(p).length();
        if !(g > 0.0 && g.is_finite()) {
            return 90.0;
        }
        (3f64.sqrt() * q / (h * g)).min(1.0).asin().to_degrees()
    }

    /// Estimate of d_M^inf from distance transforms of the inside and outside: see
    /// [`ImageSurface::dm_inf_estimate`].
    fn dm_inf_hint(&self) -> Option<f64> {
        *self.dm.get_or_init(|| distance::dm_inf_estimate(self))
    }

    fn as_image(&self) -> Option<&ImageSurface> {
        Some(self)
    }
}

impl ImageSurface {
    /// Same as [`Surface::dm_inf_hint`]: the smallest medial radius found on the ridges of the
    /// Euclidean distance transform (see the `distance` module docs), clamped below by one voxel.
    pub fn dm_inf_estimate(&self) -> Option<f64> {
        self.dm_inf_hint()
    }
}
