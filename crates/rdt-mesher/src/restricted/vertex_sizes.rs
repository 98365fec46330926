//! Section 6.1's size test r <= sigma(c) decided from sigma at the facet's vertices (ours: an
//! acceleration; every decision is the one the exact test makes).
//!
//! For a [`crate::Sizing::Lipschitz`] field with constant L, and a facet with vertices v_i
//! on its surface Delaunay ball B(c, r) (so |c - v_i| = r up to rounding),
//!
//! sigma(c) >= lb = max_i (sigma(v_i) - L |c - v_i|).
//!
//! and likewise sigma(c) <= ub = min_i (sigma(v_i) + L |c - v_i|). When lb > 0 and the
//! facet's badness with lb in place of sigma(c) is <= 1, its exact badness (r / sigma(c) <=
//! r / lb, the other criteria unchanged) is <= 1 too: the facet is good, and sigma(c) is not
//! evaluated; a good facet stores that upper bound of its badness (only `bad > 1` is read for
//! good facets). When its badness with ub is > 1 it is bad whatever sigma(c) is, and it is
//! queued with an estimate of its badness (see [`Mesher::sigma_for_test`]). Only the facets
//! in between get the exact sigma(c). Every facet is classified as the exact test would
//! classify it; the order in which bad facets are refined, and so the mesh, can differ
//! slightly.
//!
//! sigma(v) is evaluated once per vertex and per field: [`VertexSizes`] is indexed by vertex
//! id and cleared when the field changes (`requeue_all`) or the ids do (`drop_scaffold`).
//! On a field whose nearest-point query is costly (the adaptive mode's distance to Voronoi
//! poles) this replaces most evaluations at ball centers by one per vertex.

use crate::state::Mesher;
use delaunay3::VertexId;
use glam::DVec3;

/// Relative allowance for rounding in the bound (sigma is computed in f64: a bound within
/// 1e-9 of the exact value decides nothing; the exact test is run instead).
const ROUNDING: f64 = 1e-9;

/// sigma at the vertices of Del(E) under the current field (NaN: not evaluated yet).
#[derive(Default)]
pub(crate) struct VertexSizes {
    values: Vec<f64>,
}

impl VertexSizes {
    /// Heap bytes allocated.
    pub fn heap_bytes(&self) -> usize {
        self.values.capacity() * 8
    }

    /// Forget every value (the field or the vertex ids changed).
    pub fn clear(&mut self) {
        self.values.clear();
    }

    fn get(&self, v: VertexId) -> f64 {
        self.values.get(v.index()).copied().unwrap_or(f64::NAN)
    }

    /// Take `sizes[i]` as sigma at `ids[i]` (values computed by the caller under the current
    /// field; NaN or missing: unknown).
    pub fn set_all(&mut self, ids: &[VertexId], sizes: &[f64]) {
        for (&v, &s) in ids.iter().zip(sizes) {
            if self.values.len() <= v.index() {
                self.values.resize(v.index() + 1, f64::NAN);
            }
            self.values[v.index()] = s;
        }
    }
}

impl Mesher<'_> {
    /// Evaluate sigma at those of `verts` without a value (in parallel when it pays; a pure
    /// function of the point, so the values do not depend on it). No-op unless the size is
    /// a [`crate::Sizing::Lipschitz`] field.
    pub(crate) fn fill_vertex_sizes(&mut self, verts: impl Iterator<Item = VertexId>) {
        let Some(size) = &self.opts.criteria.size else {
            return;
        };
        if size.lipschitz().is_none() {
            return;
        }
        let n = self.tri.num_vertices();
        let values = &mut self.vertex_sizes.values;
        if values.len() < n {
            values.resize(n, f64::NAN);
        }
        let mut missing: Vec<VertexId> = verts
            .filter(|v| !v.is_infinite() && values[v.index()].is_nan())
            .collect();
        if missing.is_empty() {
            return;
        }
        // In Z-order (then by id, for the duplicates): a field's nearest-point queries then
        // hit the cache (same values).
        let (center, half) = (self.ball.center, self.ball.radius);
        let tri = &self.tri;
        missing.sort_by_cached_key(|&v| (geom::morton::morton_key(tri.point(v), center, half), v));
        missing.dedup();
        let got = self
            .policy
            .field(missing.len())
            .map(&missing, |&v| size.at(tri.point(v)));
        for (v, s) in missing.into_iter().zip(got) {
            values[v.index()] = s;
        }
    }

    /// sigma at `ids` under the current field (evaluated where missing), or nothing when the
    /// size is not a Lipschitz field.
    pub(crate) fn vertex_sizes_at(&mut self, ids: &[VertexId]) -> Vec<f64> {
        let lipschitz = self.opts.criteria.size.as_ref().and_then(|s| s.lipschitz());
        if lipschitz.is_none() {
            return Vec::new();
        }
        self.fill_vertex_sizes(ids.iter().copied());
        ids.iter().map(|&v| self.vertex_sizes.get(v)).collect()
    }

    /// Bounds lb <= sigma(c) <= ub from the values at `verts` (filled by
    /// [`Mesher::fill_vertex_sizes`]), or `None` when there are none (no Lipschitz field, a
    /// vertex without a value, or lb <= 0).
    pub(crate) fn sigma_bounds(&self, verts: [VertexId; 3], c: DVec3) -> Option<(f64, f64)> {
        self.sigma_estimate(verts, c).map(|(lb, ub, _)| (lb, ub))
    }

    /// [`Mesher::sigma_bounds`] and an estimate in [lb, ub]: the mean of the values at the
    /// vertices (sigma(c) to first order, c being equidistant from them).
    fn sigma_estimate(&self, verts: [VertexId; 3], c: DVec3) -> Option<(f64, f64, f64)> {
        let l = self.opts.criteria.size.as_ref()?.lipschitz()?;
        let (mut lb, mut ub, mut sum) = (f64::NEG_INFINITY, f64::INFINITY, 0.0);
        for v in verts {
            let s = self.vertex_sizes.get(v);
            if s.is_nan() {
                return None;
            }
            let d = l * c.distance(self.tri.point(v));
            lb = lb.max(s - d);
            ub = ub.min(s + d);
            sum += s;
        }
        let (lb, ub) = (lb * (1.0 - ROUNDING), ub * (1.0 + ROUNDING));
        (lb > 0.0 && ub.is_finite()).then_some((lb, ub, (sum / 3.0).clamp(lb, ub)))
    }

    /// sigma for the size test of the ball B(c, .) of the facet `verts` whose other criteria
    /// give `bound` (`Mesher::known_badness`), `None` without a size criterion:
    ///
    /// - the lower bound lb when the facet's badness with it is <= 1 (good whatever sigma(c)
    ///   is in [lb, ub]);
    /// - when the facet's badness with the upper bound ub is > 1 (bad whatever sigma(c) is),
    ///   the mean of sigma at the vertices, clamped to [lb, ub]: its queue priority is then
    ///   within a factor ub / lb of the exact one, and the facet stays bad;
    /// - else the exact sigma(c).
    ///
    /// Every facet is classified good or bad as the exact test would; only the order in which
    /// bad facets are refined can differ.
    pub(crate) fn sigma_for_test(
        &self,
        verts: [VertexId; 3],
        bound: (f64, DVec3),
        c: DVec3,
    ) -> Option<f64> {
        if let Some((lb, ub, mid)) = self.sigma_estimate(verts, c) {
            let r = verts
                .iter()
                .map(|&v| self.tri.point(v).distance(c))
                .fold(0.0, f64::max);
            let criteria = &self.opts.criteria;
            if criteria.badness_from_bound(bound, c, r, Some(lb)) <= 1.0 {
                return Some(lb);
            }
            if criteria.badness_from_bound(bound, c, r, Some(ub)) > 1.0 {
                return Some(mid);
            }
        }
        self.opts.criteria.sigma_at(c)
    }
}
