//! Lazy surface Delaunay balls (ours, an acceleration of section 6.1's loop): a facet whose
//! badness is known to exceed 1 without its ball (its angle, or its circumradius over a
//! constant sigma: `crate::Criteria::badness_lower_bound`) is bad whatever the crossing; with
//! the bipolar oracle it is registered without one, and the oracle is asked only when its
//! queue entry is popped (or before a pass that reads every ball). The refinement order
//! changes (the queue sees the bound, not the badness), the guarantees do not.

use super::test::PendingFacet;
use crate::error::MeshError;
use crate::restricted::RFacet;
use crate::state::Mesher;
use delaunay3::VertexId;
use glam::DVec3;
use oracle::OracleError;
use std::time::Instant;

/// Badness of a restricted facet with a scaffold vertex (refined before anything else).
const SCAFFOLD_BAD: f64 = 1e300;

impl Mesher<'_> {
    /// A lower bound of the badness of any surface Delaunay ball of the facet `verts` (a
    /// facet at a scaffold point is always bad, else [`crate::Criteria::badness_lower_bound`]),
    /// and its circumcenter.
    pub(super) fn known_badness(&self, verts: [VertexId; 3]) -> (f64, DVec3) {
        let (mut lb, cc) = self
            .opts
            .criteria
            .facet_bound(verts.map(|v| self.tri.point(v)), self.two_sin);
        if self.scaffold.count() > 0 && verts.iter().any(|&v| self.scaffold.contains(v)) {
            lb = SCAFFOLD_BAD;
        }
        (lb, cc)
    }

    /// The radius and badness of the surface Delaunay ball of `verts` centered at `center`,
    /// from the facet's `known_badness`.
    pub(super) fn ball_badness(
        &self,
        verts: [VertexId; 3],
        bound: (f64, DVec3),
        center: DVec3,
    ) -> Result<(f64, f64), MeshError> {
        let sigma = self.opts.criteria.sigma_checked(center)?;
        self.ball_badness_with(verts, bound, center, sigma)
    }

    /// [`Mesher::ball_badness`] with sigma(center) given (a field's value is checked here).
    pub(super) fn ball_badness_with(
        &self,
        verts: [VertexId; 3],
        bound: (f64, DVec3),
        center: DVec3,
        sigma: Option<f64>,
    ) -> Result<(f64, f64), MeshError> {
        if let Some(s) = sigma
            && !(s > 0.0 && s.is_finite())
        {
            return Err(MeshError::InvalidSizeField {
                value: s,
                at: center,
            });
        }
        let pts = verts.map(|v| self.tri.point(v));
        let radius = pts.iter().map(|v| v.distance(center)).fold(0.0, f64::max);
        let criteria = &self.opts.criteria;
        // The bound includes SCAFFOLD_BAD for a facet at a scaffold point: never kept (see
        // `crate::levels`).
        let bad = criteria.badness_from_bound(bound, center, radius, sigma);
        Ok((radius, bad))
    }

    /// Compute the surface Delaunay ball of the lazy facet in slot `idx` (`RFacet::lazy`)
    /// and store it. Its cells are live (a fresh entry's facet is registered, and a
    /// destroyed cell's facets are removed), so its dual is the one it was registered with.
    /// Returns the resolved facet.
    pub(crate) fn resolve_lazy(&mut self, idx: u32, rf: RFacet) -> Result<RFacet, MeshError> {
        debug_assert!(rf.lazy);
        let f = rf.facet();
        let m = self.tri.mirror_facet(f);
        let verts = self.tri.facet_vertices(f);
        let (p, fp, q, fq) = self
            .clipped_dual(f, m, verts)
            .expect("a registered facet has a clipped dual");
        let (lb, cc) = self.known_badness(verts);
        let pf = PendingFacet {
            f,
            m,
            verts,
            p,
            fp,
            q,
            fq,
            lb,
            cc,
            lazy: false,
        };
        self.crossing_calls += 1;
        let t = Instant::now();
        let hit = self.resolve_facet(&pf, &mut Vec::new());
        self.t_oracle += t.elapsed();
        let (center, _) = hit.expect("the bipolar oracle always finds a crossing");
        if !center.is_finite() {
            return Err(OracleError::NaN(center.x, center.y, center.z).into());
        }
        // Bad whatever sigma(center) is: the size test's bounds (`vertex_sizes`) spare a
        // costly field's evaluation where they suffice.
        self.fill_vertex_sizes(verts.into_iter());
        let sigma = self.sigma_for_test(verts, (lb, cc), center);
        let (radius, bad) = self.ball_badness_with(verts, (lb, cc), center, sigma)?;
        let slot = self
            .restricted
            .get_mut(idx, rf.version)
            .expect("resolve_lazy takes a live facet");
        slot.center = center;
        slot.radius = radius;
        // Bad anyway (the bound was > 1), up to rounding: then it stays a bad facet.
        slot.bad = bad.max(rf.bad);
        slot.lazy = false;
        Ok(*slot)
    }

    /// Resolve every lazy facet left (after a budget stop, or before a pass that reads the
    /// balls of all facets).
    pub(crate) fn resolve_all_lazy(&mut self) -> Result<(), MeshError> {
        let lazy: Vec<(u32, RFacet)> = self
            .restricted
            .iter()
            .filter(|(_, _, rf)| rf.lazy)
            .map(|(i, _, rf)| (i, *rf))
            .collect();
        for (idx, rf) in lazy {
            self.resolve_lazy(idx, rf)?;
        }
        Ok(())
    }
}
