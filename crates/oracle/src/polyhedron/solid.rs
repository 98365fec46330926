//! The solid {w > 1/2} of a mesh that is not watertight (not in the paper: section 6.6.4's
//! oracle for open, non-manifold or self-intersecting input), where `w` is the generalized
//! winding number.
//!
//! `w` is harmonic off the triangles and jumps by ±1 across each of them, so the boundary of
//! {w > 1/2} is made of two kinds of pieces: parts of input triangles across which `w` jumps
//! over 1/2, and membranes, smooth level sets {w = 1/2} away from the triangles (over holes,
//! between overlapping sheets). Parts of triangles across which `w` does not jump over 1/2
//! (an interior membrane, the inner sheet of two overlapping shells) are not on it.
//!
//! The oracles here answer for that set, consistently with [`Surface::value`] `= 1/2 − w`:
//! - intersection ([`Surface::crossings`]): along the segment, the exact triangle crossings
//!   at which the sign of `1/2 − w` changes (judged at samples on both sides), and the
//!   membrane crossings found by bisection where the sign changes between two samples of a
//!   triangle-free stretch (at most 16 samples a stretch, at least one per
//!   [`Surface::crossing_step`]);
//! - P1 seeds: centroids of triangles that are on the boundary ([`on_boundary`]);
//! - the bipolar oracle is in `exact.rs` (the exact crossing where the sign changes, else
//!   bisection).

use super::exact::PolyhedronSurface;
use crate::Surface;
use crate::roots::{Ends, bisect};
use glam::DVec3;

/// Most samples in one triangle-free stretch of a segment.
const MAX_STRETCH_SAMPLES: usize = 16;

/// Pieces of an edge in [`PolyhedronSurface::boundary_parts`].
const EDGE_PIECES: usize = 8;

impl PolyhedronSurface {
    /// The parts of `edges` (segments on the input triangles, e.g. its sharp edges) on the
    /// boundary of the solid {w > 1/2}: each edge cut in eight, a piece kept where its
    /// midpoint bounds the solid ([`Self::bounds_solid_at`]). An edge buried in an
    /// overlapping shell is not an edge of the solid's surface.
    pub fn boundary_parts(&self, edges: &[(DVec3, DVec3)]) -> Vec<(DVec3, DVec3)> {
        use rayon::prelude::*;
        edges
            .par_iter()
            .flat_map_iter(|&(a, b)| {
                (0..EDGE_PIECES).filter_map(move |k| {
                    let t = |i: usize| a + (b - a) * (i as f64 / EDGE_PIECES as f64);
                    let (p, q) = (t(k), t(k + 1));
                    self.bounds_solid_at(0.5 * (p + q)).then_some((p, q))
                })
            })
            .collect()
    }

    /// Whether the triangle with leaf-order index `k` separates {w > 1/2} from its complement
    /// at the point `p` of it: `1/2 − w` has opposite signs at `p ± δ n` (`n` its unit
    /// normal, `δ` 1e-6 of the bounding box diagonal).
    pub(super) fn on_boundary(&self, k: usize, p: DVec3) -> bool {
        let t = self.bvh.tris()[k];
        let n = (t[1] - t[0]).cross(t[2] - t[0]).normalize_or_zero();
        self.outward_at(p, n).is_some()
    }

    /// Whether `p`, a point of the input triangles, lies on the boundary of the solid
    /// {w > 1/2} (the test of [`Self::on_boundary`] on the triangle nearest to `p`): false
    /// on an interior membrane or the inner sheet of overlapping shells, which the solid's
    /// surface does not follow.
    pub fn bounds_solid_at(&self, p: DVec3) -> bool {
        let (_, k, _, _) = self.bvh.closest(p);
        self.on_boundary(k as usize, p)
    }

    /// At a point `p` of a triangle with unit normal `n`: `Some(±n)`, the side where
    /// `1/2 − w` is positive (outside the solid), if `1/2 − w` has opposite signs at
    /// `p ± δ n` (`δ` 1e-6 of the bounding box diagonal); `None` if the triangle is not on
    /// the boundary of the solid there.
    pub(super) fn outward_at(&self, p: DVec3, n: DVec3) -> Option<DVec3> {
        let (lo, hi) = self.bbox();
        let d = 1e-6 * (hi - lo).length();
        let (a, b) = (self.value(p + d * n), self.value(p - d * n));
        match (a < 0.0, b < 0.0) {
            (false, true) => Some(n),
            (true, false) => Some(-n),
            _ => None,
        }
    }

    /// The intersection oracle for the solid (see the module documentation), in order from
    /// `a`.
    pub(super) fn solid_crossings(&self, a: DVec3, b: DVec3, out: &mut Vec<DVec3>) {
        if a == b || !a.is_finite() || !b.is_finite() {
            return;
        }
        let mut ts = Vec::new();
        self.crossing_params(a, b, &mut ts);
        let at = |t: f64| a + (b - a) * t;
        let len = (b - a).length();
        let step = self.crossing_step().max(f64::MIN_POSITIVE);
        // Stretches between consecutive hits (and the ends).
        let mut bounds = Vec::with_capacity(ts.len() + 2);
        bounds.push(0.0);
        bounds.extend(ts.iter().copied());
        bounds.push(1.0);
        // (parameter, value) of the previous sample, and whether a hit lies since it.
        let mut prev: Option<(f64, f64)> = None;
        for (i, w) in bounds.windows(2).enumerate() {
            let (lo, hi) = (w[0], w[1]);
            if hi <= lo {
                continue; // a repeated hit parameter: nothing between
            }
            let n = (((hi - lo) * len / step).ceil() as usize).clamp(1, MAX_STRETCH_SAMPLES);
            for j in 0..n {
                let s = lo + (hi - lo) * (j as f64 + 0.5) / n as f64;
                let v = self.value(at(s));
                if let Some((s0, v0)) = prev
                    && (v0 < 0.0) != (v < 0.0)
                {
                    if j == 0 && i > 0 {
                        // The sign changed across the hit at `lo`: the triangle is there.
                        out.push(at(lo));
                    } else {
                        let e = Ends::new(at(s0), v0, at(s), v);
                        out.push(bisect(|p| self.value(p), e, self.tolerance()));
                    }
                }
                prev = Some((s, v));
            }
        }
    }

    /// P1 for the solid: one centroid of the largest boundary triangle per component that
    /// has one, plus up to 8 random boundary triangles' centroids per component.
    pub(super) fn solid_seeds(&self, seed: u64) -> Vec<DVec3> {
        let centroid = |k: usize| {
            let t = self.bvh.tris()[k];
            (t[0] + t[1] + t[2]) / 3.0
        };
        let keep: Vec<bool> = (0..self.bvh.len())
            .map(|k| self.on_boundary(k, centroid(k)))
            .collect();
        let out = self.seeds_among(seed, &keep);
        if out.is_empty() {
            crate::surface::random_line_seeds(self, 64, seed)
        } else {
            out
        }
    }
}
