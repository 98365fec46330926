//! The queue of bad surface Delaunay balls of section 6.1, worst first.
//!
//! # Invariant
//! An entry (slot, version) is fresh iff that slot of `crate::restricted::Restricted` is live
//! with that version; stale entries (their facet left Del_S(E)) are skipped when popped, and
//! purged in bulk once they are about half of the queue.

mod four_ary;

use crate::restricted::{RFacet, Restricted};
use delaunay3::VertexId;
use four_ary::{FourAryHeap, Packed};
use geom::morton::morton_key;
use glam::DVec3;

/// Queue length below which `Queue::purge_stale` leaves stale entries alone.
const PURGE_MIN: usize = 4096;

/// A bad facet to refine.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct QEntry {
    /// Its badness (> 0): larger first.
    pub bad: f64,
    /// Slot in `Restricted` (below 2^31).
    pub idx: u32,
    /// The facet's version when queued.
    pub version: u32,
    /// Queued by the manifold patch (section 6.6.1), not by a criterion.
    pub forced: bool,
    /// Where the facet is (a vertex of it): the spatial order's key (see [`Queue`]).
    pub at: DVec3,
}

/// The top bit of [`Packed::slot_forced`]: the `forced` flag.
const FORCED: u32 = 1 << 31;

impl QEntry {
    /// The heap's 16-byte form, ordered by `prio` (see [`Queue`]), then the older entry.
    fn pack(self, prio: u64) -> Packed {
        assert!(
            self.idx < FORCED,
            "restricted facet slot {} above 2^31",
            self.idx
        );
        debug_assert!(self.bad > 0.0);
        Packed {
            prio,
            version: self.version,
            slot_forced: self.idx | if self.forced { FORCED } else { 0 },
        }
    }
}

/// An entry taken from the queue: its slot, version and flag, and its place in the order
/// (kept, so that [`Queue::requeue`] puts it back where it was).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Popped(Packed);

impl Popped {
    /// Slot in `Restricted`.
    pub fn idx(&self) -> u32 {
        self.0.slot_forced & !FORCED
    }

    /// The facet's version when queued.
    pub fn version(&self) -> u32 {
        self.0.version
    }

    /// Queued by the manifold patch.
    pub fn forced(&self) -> bool {
        self.0.slot_forced & FORCED != 0
    }
}

/// The Z-order frame of the spatial order: a cube (center, half side).
#[derive(Clone, Copy, Debug)]
struct Frame {
    center: DVec3,
    half: f64,
}

/// The priority of `bad` at `at`: in the badness order, `bad`'s bits (a positive f64's bits
/// order like its value); in the spatial order, its eighth of an octave (sign, exponent and
/// 3 mantissa bits: 14 bits) above 48 bits of Z-order key, ascending along the curve.
fn prio(bad: f64, at: DVec3, frame: Option<Frame>) -> u64 {
    match frame {
        None => bad.to_bits(),
        Some(f) => {
            const LOW48: u64 = (1 << 48) - 1;
            let z = morton_key(at, f.center, f.half) >> 15;
            ((bad.to_bits() >> 49) << 48) | (!z & LOW48)
        }
    }
}

/// The priority queue, with an estimate of its stale entries.
///
/// Two orders, both total (the priority, then the older entry first), so a run's pops do not
/// depend on the heap's shape or the push order:
/// - the badness order (worst first), the paper's section 6.1 order, until the run has
///   `MeshOptions::spatial_order_from` vertices (2^17 by default);
/// - then the spatial order: entries within an eighth of an octave of badness of each other
///   are taken along a Z-order curve over S's bounding cube. Consecutive insertions then touch
///   nearby cells, points and facets, where the worst-first order jumped across the surface
///   at every insertion (cache misses: a 10^6-vertex torus took 1.4x the CPU time; 1.6% fewer
///   vertices). Any order of refinement of bad balls keeps the paper's guarantees (section
///   6.1 needs only that every bad ball is eventually refined). Runs below the threshold are
///   unchanged.
///
/// Entries a batch takes and leaves for later without a search (too close to one it took,
/// see `crate::schedule::batch`) wait in `deferred`, a run in decreasing order, instead of
/// going back into the heap: pops take the larger of the heap's top and the run's front, so
/// the sequence of pops is the same as if they had been pushed back (the order is total),
/// without a sift down and up per deferral (5.2 million of them for the 886k-vertex torus,
/// issue 21).
#[derive(Default)]
pub(crate) struct Queue {
    heap: FourAryHeap,
    /// Deferred entries, largest first; every one at most each entry popped before it was
    /// deferred (see [`Queue::defer`]).
    deferred: std::collections::VecDeque<Packed>,
    /// About how many entries of `heap` are stale (forced entries are not counted: rare).
    stale: usize,
    /// The spatial order's frame, once it is on.
    frame: Option<Frame>,
}

impl Queue {
    /// Heap bytes allocated.
    pub fn heap_bytes(&self) -> usize {
        (self.heap.capacity() + self.deferred.capacity()) * std::mem::size_of::<Packed>()
    }

    /// Entries, fresh or stale.
    pub fn len(&self) -> usize {
        self.heap.len() + self.deferred.len()
    }

    /// No entry left.
    pub fn is_empty(&self) -> bool {
        self.heap.is_empty() && self.deferred.is_empty()
    }

    /// Put back the entries `taken` by [`Queue::pop_fresh`] since the last call, in the order
    /// they were taken, leaving each at its place in the order (as [`Queue::requeue`] would).
    /// They must be the last entries taken: then each is at least every entry still queued,
    /// so the run stays in decreasing order.
    pub fn defer(&mut self, taken: &[Popped]) {
        for p in taken.iter().rev() {
            debug_assert!(self.deferred.front().is_none_or(|f| p.0 >= *f));
            self.deferred.push_front(p.0);
        }
    }

    /// The largest entry of the heap and the deferred run, removed.
    fn pop_any(&mut self) -> Option<Packed> {
        match (self.heap.peek(), self.deferred.front()) {
            (Some(h), Some(d)) if d > h => self.deferred.pop_front(),
            (None, Some(_)) => self.deferred.pop_front(),
            _ => self.heap.pop(),
        }
    }

    /// Queue `e`. The order is total: push order does not matter.
    pub fn push(&mut self, e: QEntry) {
        self.heap.push(e.pack(prio(e.bad, e.at, self.frame)));
    }

    /// Put back an entry taken by [`Queue::pop_fresh`], at its place in the order.
    pub fn requeue(&mut self, p: Popped) {
        self.heap.push(p.0);
    }

    /// Whether the spatial order is on.
    pub fn is_spatial(&self) -> bool {
        self.frame.is_some()
    }

    /// Turn the spatial order on, over the cube (center, half side): stale entries are
    /// dropped, the others re-keyed from their facet (`point` gives a vertex's position).
    pub fn go_spatial(
        &mut self,
        (center, half): (DVec3, f64),
        r: &Restricted,
        point: impl Fn(VertexId) -> DVec3,
    ) {
        let frame = Frame { center, half };
        let old = std::mem::take(&mut self.heap);
        let mut items = old.into_vec();
        items.extend(self.deferred.drain(..));
        items.retain_mut(|p| {
            let Some(rf) = r.get(p.slot_forced & !FORCED, p.version) else {
                return false;
            };
            // Badness order: the priority is the badness's bits.
            let bad = f64::from_bits(p.prio);
            p.prio = prio(bad, point(rf.oriented[0]), Some(frame));
            true
        });
        self.heap = FourAryHeap::from_vec(items);
        self.stale = 0;
        self.frame = Some(frame);
    }

    /// Drop every entry.
    pub fn clear(&mut self) {
        self.heap.clear();
        self.deferred.clear();
        self.stale = 0;
    }

    /// A facet with a queue entry (if it was bad) left Del_S(E).
    pub fn facet_removed(&mut self, rf: &RFacet) {
        self.stale += usize::from(rf.bad > 1.0);
    }

    /// The worst fresh entry and its facet, skipping stale ones.
    pub fn pop_fresh(&mut self, r: &Restricted) -> Option<(Popped, RFacet)> {
        loop {
            let e = Popped(self.pop_any()?);
            match r.get(e.idx(), e.version()) {
                Some(rf) => return Some((e, *rf)),
                None => self.stale = self.stale.saturating_sub(1),
            }
        }
    }

    /// Drop the stale entries once they are about half of the queue: most popped entries are
    /// stale then, and each pop costs a walk down the heap. The pop order is unchanged (a
    /// total order on fresh entries).
    pub fn purge_stale(&mut self, r: &Restricted) {
        if self.stale > PURGE_MIN && 2 * self.stale > self.len() {
            let fresh = |p: &Packed| r.get(p.slot_forced & !FORCED, p.version).is_some();
            self.heap.retain(fresh);
            self.deferred.retain(fresh);
            self.stale = 0;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Deferring entries gives the pops of pushing them back (`requeue`), with new entries
    /// pushed in between.
    #[test]
    fn deferred_entries_pop_as_if_pushed_back() {
        let mut rng = geom::SplitMix64(7);
        let mut entry = |v: u32| Packed {
            prio: rng.next_u64() % 64,
            version: v,
            slot_forced: v,
        };
        let (mut a, mut b) = (Queue::default(), Queue::default());
        let mut version = 0;
        for _ in 0..200 {
            let e = entry(version);
            version += 1;
            a.heap.push(e);
            b.heap.push(e);
        }
        let mut rng = geom::SplitMix64(8);
        let (mut popped_a, mut popped_b) = (Vec::new(), Vec::new());
        while !b.is_empty() {
            // Take a few, defer (a) or push back (b) some of them, then push new entries.
            let take = 1 + (rng.next_u64() % 6) as usize;
            let mut deferred = Vec::new();
            for _ in 0..take {
                let (Some(x), Some(y)) = (a.pop_any(), b.heap.pop()) else {
                    break;
                };
                assert_eq!(x, y);
                if rng.next_u64().is_multiple_of(3) || version > 2000 {
                    popped_a.push(x);
                    popped_b.push(y);
                } else {
                    deferred.push(Popped(x));
                }
            }
            a.defer(&deferred);
            for p in &deferred {
                b.requeue(*p);
            }
            if version < 2000 {
                for _ in 0..(rng.next_u64() % 3) {
                    let e = Packed {
                        prio: rng.next_u64() % 64,
                        version,
                        slot_forced: version,
                    };
                    version += 1;
                    a.heap.push(e);
                    b.heap.push(e);
                }
            }
            assert_eq!(a.len(), b.len());
        }
        assert!(a.is_empty());
        assert_eq!(popped_a, popped_b);
        assert!(popped_a.len() > 1000, "{}", popped_a.len());
    }

    #[test]
    fn spatial_priority_is_badness_bucket_then_z_order() {
        let at = |x: f64| DVec3::new(x, -0.9, -0.9);
        // The badness order is the badness's bits.
        assert_eq!(prio(2.5, at(0.0), None), 2.5f64.to_bits());
        let f = Some(Frame {
            center: DVec3::ZERO,
            half: 1.0,
        });
        // 2.0 and 2.2 share an eighth of an octave ([2, 2.25)); 2.3 does not.
        assert!(prio(2.0, at(0.5), f) > prio(2.2, at(0.6), f));
        assert!(prio(2.2, at(-0.5), f) > prio(2.0, at(0.5), f));
        for x in [-0.9, 0.0, 0.9] {
            assert!(prio(2.3, at(x), f) > prio(2.2, at(-0.9), f));
        }
    }
}
