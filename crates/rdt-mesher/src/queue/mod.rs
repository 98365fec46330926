//! The queue of bad surface Delaunay balls of section 6.1, worst first.
//!
//! # Invariant
//! An entry (slot, version) is fresh iff that slot of `crate::restricted::Restricted` is live
//! with that version; stale entries (their facet left Del_S(E)) are skipped when popped, and
//! purged in bulk once they are about half of the queue.

mod four_ary;

use crate::restricted::{RFacet, Restricted};
use four_ary::{FourAryHeap, Packed};

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
}

/// The top bit of [`Packed::slot_forced`]: the `forced` flag.
const FORCED: u32 = 1 << 31;

impl QEntry {
    /// The heap's 16-byte form. Its order is the queue's: larger badness first; `bad` > 0, so
    /// its bits order like its value; versions are unique, so the order is total and
    /// deterministic (older entries first among equals).
    fn pack(self) -> Packed {
        assert!(
            self.idx < FORCED,
            "restricted facet slot {} above 2^31",
            self.idx
        );
        debug_assert!(self.bad > 0.0);
        Packed {
            bad_bits: self.bad.to_bits(),
            version: self.version,
            slot_forced: self.idx | if self.forced { FORCED } else { 0 },
        }
    }

    fn unpack(p: Packed) -> QEntry {
        QEntry {
            bad: f64::from_bits(p.bad_bits),
            idx: p.slot_forced & !FORCED,
            version: p.version,
            forced: p.slot_forced & FORCED != 0,
        }
    }
}

/// The priority queue, with an estimate of its stale entries.
#[derive(Default)]
pub(crate) struct Queue {
    heap: FourAryHeap,
    /// About how many entries of `heap` are stale (forced entries are not counted: rare).
    stale: usize,
}

impl Queue {
    /// Heap bytes allocated.
    pub fn heap_bytes(&self) -> usize {
        self.heap.capacity() * std::mem::size_of::<Packed>()
    }

    /// Entries, fresh or stale.
    pub fn len(&self) -> usize {
        self.heap.len()
    }

    /// No entry left.
    pub fn is_empty(&self) -> bool {
        self.heap.is_empty()
    }

    /// Queue `e`. The order is total (badness, then version): push order does not matter.
    pub fn push(&mut self, e: QEntry) {
        self.heap.push(e.pack());
    }

    /// Drop every entry.
    pub fn clear(&mut self) {
        self.heap.clear();
        self.stale = 0;
    }

    /// A facet with a queue entry (if it was bad) left Del_S(E).
    pub fn facet_removed(&mut self, rf: &RFacet) {
        self.stale += usize::from(rf.bad > 1.0);
    }

    /// The worst fresh entry and its facet, skipping stale ones.
    pub fn pop_fresh(&mut self, r: &Restricted) -> Option<(QEntry, RFacet)> {
        loop {
            let e = QEntry::unpack(self.heap.pop()?);
            match r.get(e.idx, e.version) {
                Some(rf) => return Some((e, *rf)),
                None => self.stale = self.stale.saturating_sub(1),
            }
        }
    }

    /// Drop the stale entries once they are about half of the queue: most popped entries are
    /// stale then, and each pop costs a walk down the heap. The pop order is unchanged (a
    /// total order on fresh entries).
    pub fn purge_stale(&mut self, r: &Restricted) {
        if self.stale > PURGE_MIN && 2 * self.stale > self.heap.len() {
            self.heap
                .retain(|p| r.get(p.slot_forced & !FORCED, p.version).is_some());
            self.stale = 0;
        }
    }
}
