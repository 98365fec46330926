//! The IMLS value (section 6.6.3, Kolluri's IMLS; ours in the details): kernel sums, their
//! gradient, the blend into the far field and the far-field sign.
//!
//! Invariant: [`PointSetSurface::value_grad`]'s value is bit-identical to
//! [`Surface::value`](crate::Surface::value) (the sums are computed by the same operations,
//! with or without their gradients).

use super::PointSetSurface;
use super::grid::Item;
use crate::Surface;
use glam::DVec3;
use kiddo::SquaredEuclidean;

/// Kernel sums at a point (see [`PointSetSurface::sums_impl`]).
#[derive(Clone, Copy, Default)]
pub(super) struct Sums {
    /// Σ φ n·(x − p).
    pub num: f64,
    /// Σ φ.
    pub den: f64,
    /// Σ φ n.
    pub nsum: DVec3,
    /// ∇ of `num` and `den` (when asked for).
    pub dnum: DVec3,
    pub dden: DVec3,
    /// Σ φ (x − p) (robust passes only).
    pub dsum: DVec3,
    /// Smallest `|x − p_i|² / b_i²` over the points whose support contains `x` (the squared
    /// distance in band radii; `∞` if none, 0 without the support band).
    pub band2: f64,
}

/// Points gathered for the passes of the kernel sums (beyond, each pass visits the grid).
const KEEP: usize = 256;

/// The kernel terms of the gathered points, kept by the plain pass for the reweighted ones.
/// (For the first [`PRE`] points: the others' are computed again, by the same operations.)
struct Pre {
    /// `1 − |x − p|² / R²`.
    u: [f64; PRE],
    u2: [f64; PRE],
    /// `n · (x − p)`.
    nd: [f64; PRE],
}

/// Points whose kernel terms [`Pre`] keeps (a larger array costs its zeroing on every
/// evaluation; 20 to 36 points are within their support on average on the scans).
const PRE: usize = 64;

/// A placeholder for the unused entries of the kept points.
static NO_ITEM: Item = Item {
    p: DVec3::ZERO,
    n: DVec3::ZERO,
    r2: 0.0,
    b2inv: 0.0,
};

/// Beyond this many band radii from every point, the value is the far field alone (blended
/// from 1 band radius).
const BAND_OUT: f64 = 1.5;

/// The weight of the IMLS value at `band2` (squared distance in band radii): 1 within the
/// band, 0 beyond [`BAND_OUT`], smooth in between.
fn band_weight(band2: f64) -> f64 {
    if band2 <= 1.0 {
        return 1.0;
    }
    let t = band2.sqrt();
    if t >= BAND_OUT {
        return 0.0;
    }
    let a = (BAND_OUT - t) / (BAND_OUT - 1.0);
    a * a * (3.0 - 2.0 * a)
}

/// Below the trust weight ([`PointSetParams::min_weight`](super::PointSetParams::min_weight)),
/// the IMLS value signs the far field where the kernel weight is at least this (more than
/// one point's tail; below it, the flood-filled far-field sign is used as where the weight
/// is 0)...
const FRINGE_WEIGHT: f64 = 0.003;

/// ...the contributing normals agree to this ratio (`|Σ φ n| / Σ φ`)...
const COHERENCE: f64 = 0.9;

/// ...and the value is at least this multiple of the median kernel radius away from 0.
const FRINGE_OFFSET: f64 = 0.25;

impl PointSetSurface {
    /// The value where the kernel weight `den` is below
    /// [`PointSetParams::min_weight`](super::PointSetParams::min_weight): a smooth blend of the
    /// IMLS value `num / den` into the far field `far` (they have the same sign away from the
    /// surface).
    fn blend(&self, num: f64, den: f64, far: f64) -> f64 {
        if den <= 0.0 {
            return far;
        }
        let a = den / self.min_weight;
        let a = a * a * (3.0 - 2.0 * a);
        a * (num / den) + (1.0 - a) * far
    }

    /// The IMLS value `Σ φ n·(x − p) / Σ φ` where the total kernel weight is at least the
    /// blending threshold (near the points); `None` elsewhere.
    pub(crate) fn near_value(&self, x: DVec3) -> Option<f64> {
        let s = self.sums_impl::<false>(x);
        (s.den >= self.min_weight && s.band2 <= 1.0).then(|| s.num / s.den)
    }

    /// The value inside the bounding sphere, with the far field (`∓ max_radius`, given the
    /// total kernel weight) from `far`.
    pub(crate) fn value_with_far(&self, x: DVec3, far: impl FnOnce(f64) -> f64) -> f64 {
        let (num, den, _) = self.sums(x);
        if den >= self.min_weight {
            return num / den;
        }
        self.blend(num, den, far(den))
    }

    /// The value inside the bounding sphere from the kernel sums at `x` (what
    /// [`Surface::value`] and [`Self::value_grad`] both return), and whether it is the plain
    /// IMLS quotient (its gradient exact).
    pub(super) fn value_from_sums(&self, x: DVec3, s: &Sums) -> (f64, bool) {
        let w = band_weight(s.band2);
        if w < 1.0 {
            // Out of the data's band: the far field (flood-filled sign, else the winding
            // number), blended with the IMLS value near the band's edge.
            // The winding-number sign at x, when computed here, is reused by the blend below
            // (the same call with the same arguments).
            let (far, uncached) = match self.far_cache.get(x) {
                1 => (self.max_radius, None),
                -1 => (-self.max_radius, None),
                _ => {
                    let v = self.far_value_uncached(x, s.den);
                    (v, Some(v))
                }
            };
            if w == 0.0 {
                return (far, false);
            }
            let near = if s.den >= self.min_weight {
                s.num / s.den
            } else {
                self.blend(
                    s.num,
                    s.den,
                    self.far_value_known(x, s.num, s.den, s.nsum, uncached),
                )
            };
            return (w * near + (1.0 - w) * far, false);
        }
        if s.den >= self.min_weight {
            return (s.num / s.den, true);
        }
        (
            self.blend(s.num, s.den, self.far_value(x, s.num, s.den, s.nsum)),
            false,
        )
    }

    /// Is the value at `x` the plain IMLS quotient (the `true` of `value_from_sums`)?
    pub(super) fn plain_imls_at(&self, x: DVec3) -> bool {
        let s = self.sums_impl::<false>(x);
        band_weight(s.band2) >= 1.0 && s.den >= self.min_weight
    }

    /// Diagnostics: at `x`, the total plain kernel weight `Σ φ_i(x)` (below `min_weight` the
    /// value blends into the far field), the smallest distance to a point in band radii, squared
    /// (`∞` if none; 0 without the band), and the number of points whose support contains `x`.
    pub fn kernel_weight(&self, x: DVec3) -> (f64, f64, usize) {
        let s = self.sums_impl::<false>(x);
        let mut c = 0;
        self.grid.for_each_near(x, |it| {
            c += usize::from((x - it.p).length_squared() < it.r2)
        });
        (s.den, s.band2, c)
    }

    /// The input point nearest to `x` and its squared distance.
    pub(super) fn nearest(&self, x: DVec3) -> (usize, f64) {
        let r = self
            .tree
            .query(&x.to_array())
            .nearest_one::<SquaredEuclidean<f64>>()
            .execute();
        (r.item as usize, r.distance)
    }

    /// IMLS sums at `x`: (Σ φ n·(x−p), Σ φ, Σ φ n).
    pub(super) fn sums(&self, x: DVec3) -> (f64, f64, DVec3) {
        let s = self.sums_impl::<false>(x);
        (s.num, s.den, s.nsum)
    }

    /// The kernel sums at `x`, with their gradients if `GRAD` (otherwise left at zero). The
    /// sums are computed by the same operations either way (bit-identical).
    ///
    /// With [`PointSetParams::robust`](super::PointSetParams::robust) passes (ours, after
    /// Öztireli et al.'s robust IMLS, 2009): the plain sums give `f` and `∇f`; each further
    /// pass weights point `i` by `α_i = exp(−|n_i − ∇f/|∇f||² / σ_n²)`, so points whose normal
    /// disagrees with the surface's at `x` (the other face of a sharp edge, the other side of
    /// a thin part) count less. The returned sums keep the plain weight (`den`, `nsum`,
    /// `band2`: how much data is near) and carry the reweighted value and gradient (`num =
    /// f den`, `dnum = ∇f den`, `dden = 0`). The gradient is the reweighted quotient's with
    /// the `α_i` held fixed (not the exact derivative): the oracles only use it for Newton
    /// steps inside a bracket.
    #[inline]
    pub(super) fn sums_impl<const GRAD: bool>(&self, x: DVec3) -> Sums {
        // The points whose support contains x, gathered once for every pass.
        let mut buf: [&Item; KEEP + 1] = [&NO_ITEM; KEEP + 1];
        let kept = self.grid.gather(x, &mut buf);
        if self.robust == 0 {
            return self.sums_over::<GRAD>(x, None, &buf, kept);
        }
        if kept > KEEP {
            return self.robust_over_grid::<GRAD>(x);
        }
        // The plain pass keeps each point's kernel terms for the reweighted passes.
        let mut pre = Pre {
            u: [0.0; PRE],
            u2: [0.0; PRE],
            nd: [0.0; PRE],
        };
        let s = self.plain_pass(x, &buf[..kept], &mut pre);
        if s.den <= 0.0 {
            return s;
        }
        let mut f = s.num / s.den;
        let mut g = (s.dnum - f * s.dden) / s.den;
        for pass in 0..self.robust {
            let normal = g.normalize_or_zero();
            // The last pass's gradient only when asked for (its value is the same bit for
            // bit: the sums are computed by the same operations either way).
            let r = if GRAD || pass + 1 < self.robust {
                self.reweighted_pass::<true>(x, normal, &buf[..kept], &pre)
            } else {
                self.reweighted_pass::<false>(x, normal, &buf[..kept], &pre)
            };
            // α_i ≥ exp(−4 / σ_n²) > 0, so r.den > 0 where s.den > 0 (unless it underflows).
            if r.den.is_nan() || r.den <= 0.0 {
                break;
            }
            f = self.pass_value(&r, normal);
            g = (r.dnum - f * r.dden) / r.den;
        }
        Sums {
            num: f * s.den,
            dnum: if GRAD { g * s.den } else { DVec3::ZERO },
            dden: DVec3::ZERO,
            ..s
        }
    }

    /// A robust pass's value: `Σ w n_i·(x − p_i) / Σ w`, or with midpoint normals
    /// `Σ w ½(n_i + n)·(x − p_i) / Σ w` (`n` the pass's normal at `x`).
    #[inline]
    fn pass_value(&self, r: &Sums, normal: DVec3) -> f64 {
        if self.midpoint {
            0.5 * (r.num + normal.dot(r.dsum)) / r.den
        } else {
            r.num / r.den
        }
    }

    /// [`Self::sums_impl`] with the robust passes when the gathered points overflowed the
    /// buffer: every pass visits the grid (the same sums, bit for bit).
    #[cold]
    fn robust_over_grid<const GRAD: bool>(&self, x: DVec3) -> Sums {
        let none = [&NO_ITEM; KEEP + 1];
        let s = self.sums_over::<true>(x, None, &none, KEEP + 1);
        if s.den <= 0.0 {
            return s;
        }
        let mut f = s.num / s.den;
        let mut g = (s.dnum - f * s.dden) / s.den;
        for pass in 0..self.robust {
            let nrm = g.normalize_or_zero();
            let normal = Some(nrm);
            let r = if GRAD || pass + 1 < self.robust {
                self.sums_over::<true>(x, normal, &none, KEEP + 1)
            } else {
                self.sums_over::<false>(x, normal, &none, KEEP + 1)
            };
            if r.den.is_nan() || r.den <= 0.0 {
                break;
            }
            f = self.pass_value(&r, nrm);
            g = (r.dnum - f * r.dden) / r.den;
        }
        Sums {
            num: f * s.den,
            dnum: if GRAD { g * s.den } else { DVec3::ZERO },
            dden: DVec3::ZERO,
            ..s
        }
    }

    /// The plain pass (with gradients) over the gathered points `its` (all within their
    /// support): the operations of [`Self::add`] without a normal, keeping each point's `u`,
    /// `u²` and `n·(x − p)` in `pre`.
    #[inline]
    fn plain_pass(&self, x: DVec3, its: &[&Item], pre: &mut Pre) -> Sums {
        let mut s = Sums {
            band2: if self.banded { f64::INFINITY } else { 0.0 },
            ..Default::default()
        };
        for (i, it) in its.iter().enumerate() {
            let d = x - it.p;
            let d2 = d.length_squared();
            if self.banded {
                s.band2 = s.band2.min(d2 * it.b2inv);
            }
            let u = 1.0 - d2 / it.r2;
            let u2 = u * u;
            // `add`'s `alpha * u2 * u2` and `-8 alpha u2 u / R²` with alpha = 1 (exact).
            let w = u2 * u2;
            let nd = it.n.dot(d);
            s.num += w * nd;
            s.den += w;
            s.nsum += w * it.n;
            let gw = d * (-8.0 * u2 * u / it.r2);
            s.dnum += gw * nd + w * it.n;
            s.dden += gw;
            if i < PRE {
                (pre.u[i], pre.u2[i], pre.nd[i]) = (u, u2, nd);
            }
        }
        s
    }

    /// A reweighted pass over the gathered points `its` with the kernel terms `pre` of the
    /// plain pass: the operations of [`Self::add`] with `normal`, computing only what
    /// [`Self::sums_impl`] reads of it (`num`, `den` and, if `GRAD`, `dnum` and `dden`).
    #[inline]
    fn reweighted_pass<const GRAD: bool>(
        &self,
        x: DVec3,
        normal: DVec3,
        its: &[&Item],
        pre: &Pre,
    ) -> Sums {
        let mut s = Sums::default();
        for (i, it) in its.iter().enumerate() {
            let (u, u2, nd) = if i < PRE {
                (pre.u[i], pre.u2[i], pre.nd[i])
            } else {
                let d = x - it.p;
                let u = 1.0 - d.length_squared() / it.r2;
                (u, u * u, it.n.dot(d))
            };
            let alpha = (-(it.n - normal).length_squared() * self.robust_inv_sn2).exp();
            let w = alpha * u2 * u2;
            s.num += w * nd;
            s.den += w;
            if self.midpoint {
                s.dsum += w * (x - it.p);
            }
            if GRAD {
                let d = x - it.p;
                let gw = d * (-8.0 * alpha * u2 * u / it.r2);
                s.dnum += gw * nd + w * it.n;
                s.dden += gw;
            }
        }
        s
    }

    /// A pass of kernel sums at `x` over the `kept` points gathered in `buf` (those whose
    /// support contains `x`, in the grid's order), or over the grid when they overflowed it:
    /// the same points in the same order either way (bit-identical sums). With `normal =
    /// Some(g)`, each point's weight is multiplied by `exp(−|n_i − g|² / σ_n²)` (see
    /// [`Self::sums_impl`]).
    #[inline]
    fn sums_over<const GRAD: bool>(
        &self,
        x: DVec3,
        normal: Option<DVec3>,
        buf: &[&Item; KEEP + 1],
        kept: usize,
    ) -> Sums {
        let mut r = Sums {
            band2: if self.banded { f64::INFINITY } else { 0.0 },
            ..Default::default()
        };
        if kept > KEEP {
            self.grid.for_each_near(x, |it| {
                self.add::<GRAD>(&mut r, x, it, normal);
            });
            return r;
        }
        for it in &buf[..kept] {
            self.add::<GRAD>(&mut r, x, it, normal);
        }
        r
    }

    /// Add point `it` to the sums at `x` if `x` is within its support (and say whether).
    #[inline(always)]
    fn add<const GRAD: bool>(
        &self,
        s: &mut Sums,
        x: DVec3,
        it: &Item,
        normal: Option<DVec3>,
    ) -> bool {
        let d = x - it.p;
        let d2 = d.length_squared();
        if d2 >= it.r2 {
            return false;
        }
        if self.banded {
            s.band2 = s.band2.min(d2 * it.b2inv);
        }
        let u = 1.0 - d2 / it.r2;
        let u2 = u * u;
        let alpha = match normal {
            Some(g) => (-(it.n - g).length_squared() * self.robust_inv_sn2).exp(),
            None => 1.0,
        };
        let w = alpha * u2 * u2;
        let nd = it.n.dot(d);
        s.num += w * nd;
        s.den += w;
        s.nsum += w * it.n;
        if self.midpoint && normal.is_some() {
            s.dsum += w * d;
        }
        if GRAD {
            // ∇φ = 4u³ ∇u, ∇u = −2 (x − p) / R².
            let gw = d * (-8.0 * alpha * u2 * u / it.r2);
            s.dnum += gw * nd + w * it.n;
            s.dden += gw;
        }
        true
    }

    /// The value and its gradient at `x`; the gradient is NaN where the value is not the
    /// plain IMLS quotient (low kernel weight, far field). The value equals
    /// [`Surface::value`] exactly.
    pub(super) fn value_grad(&self, x: DVec3) -> (f64, DVec3) {
        let dc = (x - self.sphere.center).length();
        if !x.is_finite() || dc >= self.sphere.radius {
            return (self.value(x), DVec3::NAN);
        }
        let s = self.sums_impl::<true>(x);
        match self.value_from_sums(x, &s) {
            (f, true) => (f, (s.dnum - f * s.dden) / s.den),
            (f, false) => (f, DVec3::NAN),
        }
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
    pub(super) fn far_value(&self, x: DVec3, num: f64, den: f64, nsum: DVec3) -> f64 {
        self.far_value_known(x, num, den, nsum, None)
    }

    /// [`Self::far_value`], with `uncached` the value of `far_value_uncached(x, den)` when
    /// already known.
    fn far_value_known(
        &self,
        x: DVec3,
        num: f64,
        den: f64,
        nsum: DVec3,
        uncached: Option<f64>,
    ) -> f64 {
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
        uncached.unwrap_or_else(|| self.far_value_uncached(x, den))
    }

    /// The far field signed by the winding number alone (the coarse tree first where no kernel
    /// reaches, kept when clear-cut).
    pub(super) fn far_value_uncached(&self, x: DVec3, den: f64) -> f64 {
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
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::imls::PointSetParams;
    use crate::roots::SplitMix64;

    /// The robust sums over the gathered points (with the plain pass's kernel terms kept)
    /// are bit-identical to the passes over the grid that an overflowing gather falls back
    /// to, with and without gradients.
    #[test]
    fn gathered_sums_equal_the_grid_passes() {
        // Moderate noise (tens of points per support), then strong noise (kernel radii of
        // 6 ν: more points than `Pre` keeps).
        for (noise, n, seed) in [(0.01, 4000, 9), (0.06, 20_000, 10)] {
            let mut rng = SplitMix64(seed);
            let pts: Vec<DVec3> = (0..n)
                .map(|_| {
                    let u = rng.unit_vector();
                    u * (1.0 + 0.1 * (3.0 * u.x).sin()) + rng.unit_vector() * noise * rng.next_f64()
                })
                .collect();
            let s = PointSetSurface::new(&pts, None, &PointSetParams::scan()).unwrap();
            let bits = |v: &Sums| {
                [v.num, v.den, v.band2]
                    .into_iter()
                    .chain(v.nsum.to_array())
                    .chain(v.dnum.to_array())
                    .chain(v.dden.to_array())
                    .map(f64::to_bits)
                    .collect::<Vec<u64>>()
            };
            let (mut near, mut many, mut over) = (0, 0, 0);
            for _ in 0..300 {
                let x = rng.unit_vector() * (0.85 + 0.3 * rng.next_f64());
                let a = s.sums_impl::<true>(x);
                assert_eq!(bits(&a), bits(&s.robust_over_grid::<true>(x)), "{x}");
                let b = s.sums_impl::<false>(x);
                assert_eq!(bits(&b), bits(&s.robust_over_grid::<false>(x)), "{x}");
                near += usize::from(a.den > 0.0);
                let mut buf = [&NO_ITEM; KEEP + 1];
                let kept = s.grid.gather(x, &mut buf);
                many += usize::from(kept > PRE && kept <= KEEP);
                over += usize::from(kept > KEEP);
            }
            assert!(near > 100, "{near}");
            if noise > 0.05 {
                assert!(many > 20, "{many} {over}");
            }
        }
    }
}
