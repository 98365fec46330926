//! The manifold patch of section 6.6.1: while Del_S(E) has a non-manifold (or boundary) edge
//! or vertex, the facets there are refined as if bad ("forced" queue entries), down to a
//! floor, and until the count of bad elements stops decreasing (sharp edges and singular
//! points would otherwise be refined forever).

use crate::error::MeshError;
use crate::queue::QEntry;
use crate::restricted::RFacet;
use crate::state::Mesher;
use crate::stats::StopReason;
use delaunay3::VertexId;
use glam::DVec3;

/// Manifold passes without a decrease of the non-manifold count before the patch gives up.
const MANIFOLD_STALL_PASSES: u32 = 6;

impl Mesher<'_> {
    /// Queue (forced) every restricted facet at a non-manifold edge or vertex, or at a
    /// boundary edge. Returns how many facets were queued.
    pub(crate) fn push_nonmanifold(&mut self) -> Result<usize, MeshError> {
        self.resolve_all_lazy()?;
        self.stats.manifold_passes += 1;
        let (bad_edges, bad_vertices) = self.nonmanifold_elements();
        if bad_edges.is_empty() && bad_vertices.is_empty() {
            // Del_S(E) changes only with the vertices: `finish` reuses this.
            self.manifold.last = Some((self.tri.num_vertices(), (bad_edges, bad_vertices)));
            return Ok(0);
        }
        let mut keys: Vec<(u32, RFacet)> = Vec::new();
        for (idx, k, rf) in self.restricted.iter() {
            let e = [[k[0], k[1]], [k[1], k[2]], [k[0], k[2]]];
            if e.iter().any(|e| bad_edges.binary_search(e).is_ok())
                || k.iter().any(|v| bad_vertices.binary_search(v).is_ok())
            {
                keys.push((idx, *rf));
            }
        }
        // Termination: stop when the count of bad elements has not decreased for
        // `MANIFOLD_STALL_PASSES` passes, and never force facets smaller than the floor.
        let bad = bad_edges.len() + bad_vertices.len();
        if bad < self.manifold.best {
            self.manifold.best = bad;
            self.manifold.stall = 0;
        } else {
            self.manifold.stall += 1;
            if self.manifold.stall >= MANIFOLD_STALL_PASSES {
                self.stats.stopped_by = Some(StopReason::ManifoldStalled {
                    passes: MANIFOLD_STALL_PASSES,
                    left: bad,
                });
                return Ok(0);
            }
        }
        keys.retain(|(_, rf)| rf.radius >= self.manifold_floor(rf.center));
        Ok(self.push_forced(keys))
    }

    /// Queue `facets` as forced entries (refined whatever their badness, larger first);
    /// returns how many. The queue's order is total (badness, then version): push order does
    /// not matter.
    pub(crate) fn push_forced(&mut self, facets: Vec<(u32, RFacet)>) -> usize {
        let n = facets.len();
        for (idx, rf) in facets {
            self.queue.push(QEntry {
                bad: 1.0 + rf.radius,
                idx,
                version: rf.version,
                forced: true,
                at: self.tri.point(rf.oriented[0]),
            });
        }
        n
    }

    /// Facets smaller than this are not refined by the manifold patch: a tenth of sigma(c)
    /// with a size criterion, else 1e-3 of the bounding radius (and always 100 x the oracle's
    /// tolerance).
    pub(crate) fn manifold_floor(&self, c: DVec3) -> f64 {
        let base = match self.opts.criteria.sigma_at(c) {
            Some(s) => 0.1 * s,
            None => 1e-3 * self.ball.radius,
        };
        // A sampled surface: down to an eighth of its resolution (a bounded refinement of
        // sub-voxel features before the topological repair decides).
        let base = match self.opts.resolution {
            Some(h) => base.min(h / 8.0),
            None => base,
        };
        base.max(100.0 * self.s.tolerance())
    }

    /// Edges (sorted pairs) with other than two restricted facets, and vertices whose link is
    /// not a single cycle. Both lists sorted.
    pub(crate) fn nonmanifold_elements(&self) -> (Vec<[VertexId; 2]>, Vec<VertexId>) {
        // The order of the triangles does not matter to the result.
        let tris: Vec<[u32; 3]> = self
            .restricted
            .iter()
            .map(|(_, k, _)| k.map(VertexId::to_u32))
            .collect();
        let (e, v) =
            crate::topology::nonmanifold_elements_with(&tris, self.policy.tuner.parallel());
        (
            e.into_iter().map(|e| e.map(VertexId::from_u32)).collect(),
            v.into_iter().map(VertexId::from_u32).collect(),
        )
    }
}
