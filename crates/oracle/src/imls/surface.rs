//! The point-set surface's oracles (section 6.6.3): the bipolar and intersection oracles,
//! Newton projection, P1 seeds and the P2 hint from shrinking balls.

use super::PointSetSurface;
use super::lfs::LfsSample;
use crate::roots::{Ends, SplitMix64};
use crate::{BoundingSphere, Surface};
use glam::DVec3;

/// Precision of a scan's crossing points, as a fraction of the median kernel radius (see
/// [`PointSetSurface`]'s `tolerance`). Each crossing is found by Newton steps inside its
/// bracket. At the default, 1e-7 of the bounding radius (1.5e-8 on the 50k-point bunny scan
/// of `../shared/models`: 3.6e-6 of its median kernel radius, 3.2e-5 of its estimated noise),
/// the last steps confirmed digits the data does not have: 4.63 evaluations a crossing, 3.36
/// at this precision (4.1e-6 there, 1/113 of the noise), 28% fewer in the crossings.
pub const CROSSING_PRECISION: f64 = 1e-3;

/// Neighbours averaged into a seed's starting point (see `neighbourhood_centroid`).
const SEED_NEIGHBOURS: usize = 16;

impl Surface for PointSetSurface {
    fn bounding_sphere(&self) -> BoundingSphere {
        self.sphere
    }

    /// The default (1e-7 of the bounding radius), or with the support band (scans, see
    /// `PointSetParams::support_band`) at least [`CROSSING_PRECISION`] of the median kernel
    /// radius: a scan's surface is not defined below its noise, and the kernel radius is at
    /// least six times the estimated noise. (The Newton projection of seeds keeps the
    /// default: see `project`.)
    fn tolerance(&self) -> f64 {
        let base = 1e-7 * self.sphere.radius;
        if self.banded {
            base.max(CROSSING_PRECISION * self.stats.median_radius)
        } else {
            base
        }
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
        let s = self.sums_impl::<false>(x);
        self.value_from_sums(x, &s).0
    }

    /// Points on the MLS surface: the highest and lowest input points of each component
    /// (horizontal tangent planes, as in the paper's P1) and 32 random input points, each
    /// projected onto the surface from the centroid of its neighbourhood (the point itself
    /// when that fails; see `neighbourhood_centroid`: the extreme points of a noisy scan are
    /// its outliers); those that fail to converge are dropped.
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
            .filter_map(|&i| {
                self.project(self.neighbourhood_centroid(i))
                    .or_else(|| self.project(self.points[i]))
            })
            .collect()
    }

    /// Where the value is the plain IMLS quotient (within the data's band, kernel weight at
    /// least [`PointSetParams::min_weight`](super::PointSetParams::min_weight)): the points
    /// where `Surface::value` takes no far-field term.
    fn data_defined(&self, x: DVec3) -> Option<bool> {
        let inside = x.is_finite() && (x - self.sphere.center).length() < self.sphere.radius;
        Some(inside && self.plain_imls_at(x))
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
    /// capped at the largest kernel radius; stops when a step is below the tolerance. `None`
    /// when it does not converge, or converges where S's value is not the IMLS quotient
    /// (kernel weight below the blending threshold, or out of the data's band).
    fn project(&self, p: DVec3) -> Option<DVec3> {
        if !p.is_finite() {
            return None;
        }
        // The default precision, not the coarser crossing precision of a scan: with the
        // latter the projection of an isolated noisy point of the scan table's
        // `fandisk-n0.5-d1-est-s0` (0.17 outside the model, one data point within 0.1)
        // converged onto a bubble of S around it, where it stalled before; that seed, far
        // from every mesh of the scan (0.176), then failed `components-sampled`.
        let tol = 1e-7 * self.sphere.radius;
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
            let step = if s.den >= self.min_weight && g2 > 0.0 && g2.is_finite() {
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
                // Only a zero of S: where the value is the IMLS quotient (kernel weight at
                // least the blending threshold, and with the support band within the data's
                // band). Below the threshold a small step says only that the quotient is
                // near 0, not S's value (a blend with the far field there).
                let supported = !self.banded || s.band2 <= 1.0;
                return (supported && s.den >= self.min_weight).then_some(x);
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
        let e = Ends::new(a, fa, b, fb);
        crate::roots::newton_bracketed(|x| self.value_grad(x), e, self.tolerance())
    }

    /// Intersection oracle: sign changes of the value sampled at [`Surface::crossing_step`],
    /// each refined by [`Surface::crossing`].
    fn crossings(&self, a: DVec3, b: DVec3, out: &mut Vec<DVec3>) {
        crate::roots::sample_crossings(self, a, b, out);
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

impl PointSetSurface {
    /// Local feature size (distance to the medial axis) estimated near `x`: the smaller
    /// shrinking-ball radius at the nearest point of a subsample (≤ 1024 points) of the input.
    /// Computed once (in parallel) on first use.
    pub fn estimate_local_feature_size(&self, x: DVec3) -> f64 {
        if !x.is_finite() {
            return f64::NAN;
        }
        self.lfs_sample().at(x)
    }

    /// The shrinking-ball sample, computed on first use.
    fn lfs_sample(&self) -> &LfsSample {
        self.lfs.get_or_init(|| {
            // Neighbours within twice the kernel radius are noise-level: ignored.
            let rho = 2.0 * self.stats.median_radius;
            let cap = (self.hi - self.lo).length();
            LfsSample::build(&self.points, &self.tree, rho, cap, |i| {
                // The kernel-averaged normal: less noisy than the PCA normal.
                let n = self.gradient(self.points[i]);
                if n == DVec3::ZERO { self.normals[i] } else { n }
            })
        })
    }

    /// The centroid of point `i` and its [`SEED_NEIGHBOURS`] nearest neighbours within the
    /// median kernel radius: where a seed starts its projection. Why not the point itself:
    /// an extreme or random point of a noisy scan can be an outlier several noise widths off
    /// the surface, and the IMLS value vanishes at an isolated point (its own plane through
    /// it outweighs its neighbours' tails there), so its projection stays on a pocket of S
    /// around it that no data supports (a 200k-point bunny scan at 0.3% noise: a pocket 0.6
    /// mm thick 3 mm outside the bunny, whose seed FAILed `components-sampled` on a right
    /// mesh). The centroid of a neighbourhood lies within the noise of the data's surface.
    fn neighbourhood_centroid(&self, i: usize) -> DVec3 {
        use kiddo::SquaredEuclidean;
        let p = self.points[i];
        let r2 = self.stats.median_radius * self.stats.median_radius;
        let k = std::num::NonZeroUsize::new(SEED_NEIGHBOURS + 1).expect("k + 1 > 0");
        let near = self
            .tree
            .query(&p.to_array())
            .nearest_n::<SquaredEuclidean<f64>>(k)
            .execute();
        let (sum, n) = near
            .iter()
            .filter(|r| r.distance <= r2)
            .fold((DVec3::ZERO, 0usize), |(s, n), r| {
                (s + self.points[r.item as usize], n + 1)
            });
        if n == 0 { p } else { sum / n as f64 }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::imls::PointSetParams;

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
            let fd = crate::roots::central_difference(|q| s.value(q), x, h);
            assert!(
                (fd - g).length() < 1e-4 * g.length().max(1.0),
                "{x}: {g} vs {fd}"
            );
        }
        assert!(near > 50 && far > 50, "{near} near, {far} far");
        // With the robust pass (whose last pass skips its gradient for a value): the same
        // value bit for bit, at points near the surface.
        let r = PointSetSurface::new(&pts, None, &PointSetParams::scan()).unwrap();
        let mut reweighted = 0;
        for _ in 0..400 {
            let x = rng.unit_vector() * (0.9 + 0.2 * rng.next_f64());
            let (f, g) = r.value_grad(x);
            assert_eq!(f.to_bits(), r.value(x).to_bits(), "{x}");
            assert_ne!(f.to_bits(), s.value(x).to_bits(), "{x}");
            reweighted += usize::from(g.is_finite());
        }
        assert!(reweighted > 200, "{reweighted}");
        // The crossing oracle lands on the surface.
        let (a, b) = (DVec3::ZERO, DVec3::new(2.0, 0.1, 0.3));
        let c = s.crossing(a, s.value(a), b, s.value(b));
        assert!(s.value(c).abs() < 1e-6, "{c}");
    }
}
