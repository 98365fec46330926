//! Not in the paper: a new size function between the rounds of the adaptive mode
//! (`crate::adaptive`). Every restricted facet's badness is recomputed with the current
//! criteria and the bad ones are queued, so that section 6.1's loop continues from the same
//! Del(E) instead of restarting.
//!
//! Invariant restored: every bad registered facet has a fresh entry in `Mesher::queue`
//! (the invariant of `crate::restricted`), for the criteria as they are now.

use crate::error::MeshError;
use crate::queue::QEntry;
use crate::restricted::RFacet;
use crate::state::Mesher;
use delaunay3::VertexId;

impl Mesher<'_> {
    /// Recompute the badness of every restricted facet (the size function has changed) and
    /// rebuild the queue from it. Lazy facets are resolved first (their bound was computed
    /// with the old criteria). Returns the number of bad facets queued. Called first after
    /// every change of the size function (it drops the values cached at the vertices, and
    /// takes the new ones the caller has: `sizes[i]` at `ids[i]`, NaN or missing when not).
    pub(crate) fn requeue_all(
        &mut self,
        ids: &[VertexId],
        sizes: &[f64],
    ) -> Result<usize, MeshError> {
        // The field changed: sigma at the vertices is stale (before anything reads it);
        // `sizes[i]`, when given, is the new sigma at `ids[i]`.
        self.vertex_sizes.clear();
        self.vertex_sizes.set_all(ids, sizes);
        self.resolve_all_lazy()?;
        self.queue.clear();
        let live: Vec<(u32, RFacet)> = self.restricted.iter().map(|(i, _, rf)| (i, *rf)).collect();
        // sigma at every facet's ball center, in parallel when it pays (a pure function of
        // the center, or a lower bound that decides the same: `vertex_sizes`).
        self.fill_vertex_sizes(live.iter().flat_map(|(_, rf)| rf.oriented));
        let this = &*self;
        let sigmas = self.policy.field(live.len()).map(&live, |(_, rf)| {
            let bound = this.known_badness(rf.oriented);
            (bound, this.sigma_for_test(rf.oriented, bound, rf.center))
        });
        let mut queued = 0;
        for ((idx, rf), (bound, sigma)) in live.into_iter().zip(sigmas) {
            let (radius, bad) = self.ball_badness_with(rf.oriented, bound, rf.center, sigma)?;
            let slot = self
                .restricted
                .get_mut(idx, rf.version)
                .expect("a live facet of `iter`");
            slot.radius = radius;
            slot.bad = bad;
            if bad > 1.0 {
                queued += 1;
                self.queue.push(QEntry {
                    bad,
                    idx,
                    version: rf.version,
                    forced: false,
                    at: self.tri.point(rf.oriented[0]),
                });
            }
        }
        Ok(queued)
    }
}
