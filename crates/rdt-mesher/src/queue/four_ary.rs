//! The heap under the queue of bad surface Delaunay balls (section 6.1; ours, issue 21): a
//! 4-ary max-heap of 16-byte entries, so that the four children of a node share one or two
//! cache lines and a pop walks log4(n) levels, where `std`'s binary heap of the 24-byte
//! `QEntry` walked log2(n) levels with a line per level.
//!
//! # Invariant
//! `items[i] <= items[(i - 1) / 4]` for every `i > 0`: every node is at most its parent in
//! the total order of [`Packed`], so the root is the maximum. The order is
//! total, so the sequence of pops does not depend on the heap's shape: any correct heap
//! yields the same meshes.

use std::cmp::Ordering;

/// A queue entry in 16 bytes: its priority (larger first; see `super::Queue`), the version,
/// and the slot with the `forced` flag in its top bit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Packed {
    pub prio: u64,
    pub version: u32,
    pub slot_forced: u32,
}

impl Packed {
    /// The order: larger priority first, then the older entry (smaller version).
    #[inline]
    fn key(&self) -> (u64, u32) {
        (self.prio, u32::MAX - self.version)
    }
}

impl Ord for Packed {
    #[inline]
    fn cmp(&self, o: &Self) -> Ordering {
        self.key().cmp(&o.key())
    }
}

impl PartialOrd for Packed {
    #[inline]
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}

/// The 4-ary max-heap.
#[derive(Default)]
pub(crate) struct FourAryHeap {
    items: Vec<Packed>,
}

impl FourAryHeap {
    pub fn len(&self) -> usize {
        self.items.len()
    }

    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }

    pub fn capacity(&self) -> usize {
        self.items.capacity()
    }

    pub fn clear(&mut self) {
        self.items.clear();
    }

    pub fn push(&mut self, e: Packed) {
        self.items.push(e);
        self.sift_up(self.items.len() - 1);
    }

    /// The maximum.
    pub fn peek(&self) -> Option<&Packed> {
        self.items.first()
    }

    /// The maximum, removed.
    pub fn pop(&mut self) -> Option<Packed> {
        let last = self.items.pop()?;
        if self.items.is_empty() {
            return Some(last);
        }
        let top = std::mem::replace(&mut self.items[0], last);
        self.sift_down(0);
        Some(top)
    }

    /// Keeps the entries for which `keep` holds, then restores the heap (bottom-up, O(n)).
    pub fn retain(&mut self, keep: impl FnMut(&Packed) -> bool) {
        self.items.retain(keep);
        self.heapify();
    }

    /// The entries, in heap order.
    pub fn into_vec(self) -> Vec<Packed> {
        self.items
    }

    /// A heap of `items` (any order; bottom-up, O(n)).
    pub fn from_vec(items: Vec<Packed>) -> FourAryHeap {
        let mut h = FourAryHeap { items };
        h.heapify();
        h
    }

    fn heapify(&mut self) {
        for i in (0..self.items.len().div_ceil(4)).rev() {
            self.sift_down(i);
        }
    }

    /// Moves the entry at `i` up to its place (a hole moves up, the entry is written once).
    fn sift_up(&mut self, mut i: usize) {
        let e = self.items[i];
        while i > 0 {
            let parent = (i - 1) / 4;
            if self.items[parent] >= e {
                break;
            }
            self.items[i] = self.items[parent];
            i = parent;
        }
        self.items[i] = e;
    }

    /// Moves the entry at `i` down to its place.
    fn sift_down(&mut self, mut i: usize) {
        let n = self.items.len();
        let e = self.items[i];
        loop {
            let first = 4 * i + 1;
            if first >= n {
                break;
            }
            let last = (first + 4).min(n);
            let mut best = first;
            for c in first + 1..last {
                if self.items[c] > self.items[best] {
                    best = c;
                }
            }
            if self.items[best] <= e {
                break;
            }
            self.items[i] = self.items[best];
            i = best;
        }
        self.items[i] = e;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn entry(bad: u8, version: u32) -> Packed {
        Packed {
            prio: (1.0 + f64::from(bad)).to_bits(),
            version,
            slot_forced: version.wrapping_mul(7),
        }
    }

    proptest! {
        /// Pops come out in the order of a full sort, with pushes, pops and a retain mixed.
        #[test]
        fn pops_follow_the_total_order(
            ops in proptest::collection::vec((0u8..6, any::<bool>()), 0..400),
            drop_mod in 2u32..5,
        ) {
            let mut h = FourAryHeap::default();
            let mut model: Vec<Packed> = Vec::new();
            for (k, &(bad, pop)) in ops.iter().enumerate() {
                if pop {
                    model.sort();
                    prop_assert_eq!(h.pop(), model.pop());
                } else {
                    let e = entry(bad, k as u32);
                    h.push(e);
                    model.push(e);
                }
                if k == ops.len() / 2 {
                    h.retain(|e| e.version % drop_mod != 0);
                    model.retain(|e| e.version % drop_mod != 0);
                }
            }
            model.sort();
            while let Some(e) = h.pop() {
                prop_assert_eq!(Some(e), model.pop());
            }
            prop_assert!(model.is_empty());
        }
    }

    #[test]
    fn older_entry_first_among_equal_badness() {
        let mut h = FourAryHeap::default();
        for v in [5, 3, 9, 1] {
            h.push(entry(2, v));
        }
        h.push(entry(4, 100));
        let order: Vec<u32> = std::iter::from_fn(|| h.pop()).map(|e| e.version).collect();
        assert_eq!(order, vec![100, 1, 3, 5, 9]);
    }
}
