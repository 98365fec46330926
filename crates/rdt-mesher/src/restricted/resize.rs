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

impl Mesher<'_> {
    /// Recompute the badness of every restricted facet (the size function has changed) and
    /// rebuild the queue from it. Lazy facets are resolved first (their bound was computed
    /// with the old criteria). Returns the number of bad facets queued.
    pub(crate) fn requeue_all(&mut self) -> Result<usize, MeshError> {
        self.resolve_all_lazy()?;
        self.queue.clear();
        let live: Vec<(u32, RFacet)> = self.restricted.iter().map(|(i, _, rf)| (i, *rf)).collect();
        let mut queued = 0;
        for (idx, rf) in live {
            let bound = self.known_badness(rf.oriented);
            let (radius, bad) = self.ball_badness(rf.oriented, bound, rf.center)?;
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
                });
            }
        }
        Ok(queued)
    }
}
