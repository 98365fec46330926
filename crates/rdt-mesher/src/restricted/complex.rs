//! The complex Del_S(E) of section 6.1 as a set of facets of Del(E), stored without hashing:
//! a slab of restricted facets, reached from the two cells of each facet (`of_facet`) and from
//! queue entries (slab index + version).
//!
//! # Invariants
//! - A slab slot is live iff `slots[i].oriented[0] != FREE`; a live key (the sorted vertex
//!   triple, `sorted3(oriented)`) is in at most one live slot.
//! - When a facet is registered, `of_facet` of both its cells points at its slot. A pointer
//!   may go stale (the slot freed, or reused by another facet): every lookup through
//!   `of_facet` compares the key, so a stale pointer is a miss, never a wrong hit.
//! - Versions are unique per registration (a wrapping `u32`): a queue entry (index, version)
//!   is fresh iff the slot is live with that version.
//! - Bit i of `facet_mask[c]`: facet i of cell c may be registered. Set on both cells of a
//!   facet when it is registered; a set bit without an entry is harmless (a missed lookup),
//!   a registered facet always has its bits set. Bit 7 (`CREATED`) is set only during one
//!   `process_created` round, on the cells that round created, and cleared before it ends.
//! - `vertex_facets[v]` counts the registered facets incident to `v`.

use delaunay3::{CellId, Facet, VertexId};
use glam::DVec3;

/// A restricted facet and its surface Delaunay ball: 64 bytes (the facet's cell and index
/// are two fields, not a padded `Facet`; the key is `sorted3(oriented)`, not stored).
#[derive(Clone, Copy, Debug)]
pub(crate) struct RFacet {
    /// The cell the facet is seen from (a finite cell).
    pub cell: CellId,
    /// The facet's index in `cell`.
    pub index: u8,
    /// Vertex ids oriented counter-clockwise seen from outside (normal toward value > 0).
    pub oriented: [VertexId; 3],
    /// The center of its surface Delaunay ball (a point of S on its dual).
    pub center: DVec3,
    /// The radius of that ball.
    pub radius: f64,
    /// Its badness (`crate::Criteria`): > 1 is bad.
    pub bad: f64,
    /// Unique per registration (see the invariants).
    pub version: u32,
    /// The surface Delaunay ball is not computed yet: the facet was known bad without it
    /// (see `crate::restricted`). Then `center` is NaN, `radius` 0 and `bad` a lower bound of
    /// its badness, > 1. Resolved (`Mesher::resolve_lazy`) when its queue entry is popped.
    pub lazy: bool,
}

impl RFacet {
    /// The facet, seen from its finite cell.
    #[inline]
    pub fn facet(&self) -> Facet {
        Facet {
            cell: self.cell,
            index: self.index,
        }
    }
}

const _: () = assert!(std::mem::size_of::<RFacet>() == 64);

/// `oriented[0]` of a free slot.
const FREE: VertexId = VertexId::INFINITE;
/// No slot.
const NONE: u32 = u32::MAX;
/// Bit 7 of `facet_mask`: the cell was created in the current round (see the invariants).
const CREATED: u8 = 0x80;

/// Del_S(E): the registered facets and their per-cell and per-vertex indexes (see the module
/// docs).
#[derive(Default)]
pub(crate) struct Restricted {
    slots: Vec<RFacet>,
    free: Vec<u32>,
    len: usize,
    /// `of_facet[4 c + i]`: the slot last registered for facet i of cell c, or `NONE`.
    of_facet: Vec<u32>,
    facet_mask: Vec<u8>,
    vertex_facets: Vec<u32>,
    version: u32,
}

impl Restricted {
    /// Heap bytes allocated: (the facets with their balls, the per-cell-facet and per-vertex
    /// indexes).
    pub fn heap_bytes(&self) -> (usize, usize) {
        use std::mem::size_of;
        (
            self.slots.capacity() * size_of::<RFacet>() + self.free.capacity() * 4,
            self.of_facet.capacity() * 4
                + self.facet_mask.capacity()
                + self.vertex_facets.capacity() * 4,
        )
    }

    /// Registered facets.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Remove every facet (versions keep counting: entries queued before stay stale).
    pub fn clear(&mut self) {
        self.slots.clear();
        self.free.clear();
        self.len = 0;
        self.of_facet.clear();
        self.facet_mask.clear();
        self.vertex_facets.clear();
    }

    /// Make room for the vertex ids below `n`.
    pub fn ensure_vertices(&mut self, n: usize) {
        if self.vertex_facets.len() < n {
            self.vertex_facets.resize(n, 0);
        }
    }

    /// Registered facets incident to vertex `v`.
    #[inline]
    pub fn facets_at(&self, v: VertexId) -> u32 {
        self.vertex_facets.get(v.index()).copied().unwrap_or(0)
    }

    /// The facets of cell `c` that may be registered (bit i: facet i).
    #[inline]
    pub fn mask(&self, c: CellId) -> u8 {
        self.facet_mask.get(c.index()).copied().unwrap_or(0) & !CREATED
    }

    /// A round starts: the `created` cells are new (none of their facets is registered) and
    /// are marked created until [`Restricted::end_round`].
    pub fn start_round(&mut self, created: &[CellId]) {
        let need = created.iter().map(|c| c.index() + 1).max().unwrap_or(0);
        if self.facet_mask.len() < need {
            self.facet_mask.resize(need, 0);
        }
        for c in created {
            self.facet_mask[c.index()] = CREATED;
        }
    }

    /// Whether cell `c` was created in the current round.
    #[inline]
    pub fn is_created(&self, c: CellId) -> bool {
        self.facet_mask
            .get(c.index())
            .is_some_and(|&m| m & CREATED != 0)
    }

    /// The round of [`Restricted::start_round`] ends (the same `created` cells).
    pub fn end_round(&mut self, created: &[CellId]) {
        for c in created {
            self.facet_mask[c.index()] &= !CREATED;
        }
    }

    /// Register `rf` (its version is assigned here) under `key` (sorted, not registered,
    /// vertices below `ensure_vertices`), seen from `rf.facet` and its mirror `m`. Returns
    /// the slot and the facet as stored.
    pub fn register(&mut self, key: [VertexId; 3], mut rf: RFacet, m: Facet) -> (u32, RFacet) {
        self.version = self.version.wrapping_add(1);
        rf.version = self.version;
        let f = rf.facet();
        let idx = self.insert(key, rf, m);
        let need = (f.cell.max(m.cell)).index() + 1;
        if self.facet_mask.len() < need {
            self.facet_mask.resize(need, 0);
        }
        self.facet_mask[f.cell.index()] |= 1 << f.index;
        self.facet_mask[m.cell.index()] |= 1 << m.index;
        for v in key {
            self.vertex_facets[v.index()] += 1;
        }
        (idx, rf)
    }

    /// Remove the facet `key`, facet `i` of cell `c`, if registered, and return it.
    pub fn unregister(&mut self, c: CellId, i: u8, key: [VertexId; 3]) -> Option<RFacet> {
        let rf = self.remove(c, i, key)?;
        for v in key {
            self.vertex_facets[v.index()] -= 1;
        }
        Some(rf)
    }

    /// The facets sorted by key, moved out of the slab (no copy); `self` is left empty, its
    /// indexes freed (versions keep counting).
    pub fn take_sorted(&mut self) -> Vec<RFacet> {
        let mut facets = std::mem::take(&mut self.slots);
        facets.retain(|s| s.oriented[0] != FREE);
        facets.sort_by_cached_key(|rf| sorted3(rf.oriented));
        *self = Restricted {
            version: self.version,
            ..Default::default()
        };
        facets
    }

    /// The facet in slot `idx` if it is live with `version`.
    #[inline]
    pub fn get(&self, idx: u32, version: u32) -> Option<&RFacet> {
        let s = self.slots.get(idx as usize)?;
        (s.oriented[0] != FREE && s.version == version).then_some(s)
    }

    /// Mutable access to the facet in slot `idx` if it is live with `version`.
    #[inline]
    pub fn get_mut(&mut self, idx: u32, version: u32) -> Option<&mut RFacet> {
        let s = self.slots.get_mut(idx as usize)?;
        (s.oriented[0] != FREE && s.version == version).then_some(s)
    }

    /// Store `rf` under `key` (which must not be registered), pointed at from the facet
    /// `f` and its mirror `m`. Returns the slot index. (Slab only: see `register`.)
    fn insert(&mut self, key: [VertexId; 3], rf: RFacet, m: Facet) -> u32 {
        debug_assert!(self.find(rf.cell, rf.index, key).is_none());
        debug_assert_eq!(sorted3(rf.oriented), key);
        let slot = rf;
        let idx = match self.free.pop() {
            Some(i) => {
                self.slots[i as usize] = slot;
                i
            }
            None => {
                self.slots.push(slot);
                (self.slots.len() - 1) as u32
            }
        };
        self.len += 1;
        // Grown to the cell it stores, not beyond: the vector's doubling amortizes the
        // resizes and leaves its spare capacity unwritten (no resident memory), where a 1.5x
        // over-resize wrote `NONE` into it.
        let need = 4 * (rf.cell.max(m.cell).index() + 1);
        if self.of_facet.len() < need {
            self.of_facet.resize(need, NONE);
        }
        self.of_facet[4 * rf.cell.index() + rf.index as usize] = idx;
        self.of_facet[4 * m.cell.index() + m.index as usize] = idx;
        idx
    }

    /// The live slot of facet `i` of cell `c` if its key is `key`.
    #[inline]
    fn find(&self, c: CellId, i: u8, key: [VertexId; 3]) -> Option<u32> {
        let idx = *self.of_facet.get(4 * c.index() + i as usize)?;
        let s = self.slots.get(idx as usize)?;
        (sorted3(s.oriented) == key).then_some(idx)
    }

    /// Remove the facet `key`, seen as facet `i` of cell `c`, if stored, and return it.
    /// (Slab only: see `unregister`.)
    fn remove(&mut self, c: CellId, i: u8, key: [VertexId; 3]) -> Option<RFacet> {
        let idx = self.find(c, i, key)?;
        let s = &mut self.slots[idx as usize];
        let rf = *s;
        s.oriented[0] = FREE;
        self.free.push(idx);
        self.len -= 1;
        Some(rf)
    }

    /// Live facets with their keys, in slot order (deterministic, not sorted).
    pub fn iter(&self) -> impl Iterator<Item = (u32, [VertexId; 3], &RFacet)> + '_ {
        self.slots
            .iter()
            .enumerate()
            .filter(|(_, s)| s.oriented[0] != FREE)
            .map(|(i, s)| (i as u32, sorted3(s.oriented), s))
    }
}

/// `v` sorted: the key of a facet.
#[inline]
pub(crate) fn sorted3(mut v: [VertexId; 3]) -> [VertexId; 3] {
    if v[0] > v[1] {
        v.swap(0, 1);
    }
    if v[1] > v[2] {
        v.swap(1, 2);
    }
    if v[0] > v[1] {
        v.swap(0, 1);
    }
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cid(i: u32) -> CellId {
        CellId::from_u32(i)
    }

    fn key(k: [u32; 3]) -> [VertexId; 3] {
        k.map(VertexId::from_u32)
    }

    fn rf(cell: CellId, index: u8, version: u32, k: [u32; 3]) -> RFacet {
        RFacet {
            cell,
            index,
            oriented: key([k[1], k[0], k[2]]),
            center: DVec3::ZERO,
            radius: 1.0,
            bad: 0.5,
            version,
            lazy: false,
        }
    }

    #[test]
    fn stale_pointers_miss_and_versions_tell_fresh_entries() {
        let mut r = Restricted::default();
        let m = Facet {
            cell: cid(7),
            index: 2,
        };
        let a = r.insert(key([1, 2, 3]), rf(cid(3), 0, 10, [1, 2, 3]), m);
        assert_eq!(r.len(), 1);
        assert!(r.get(a, 10).is_some());
        assert!(r.get(a, 9).is_none());
        // Removing through the mirror works; removing twice does not.
        assert_eq!(
            r.remove(cid(7), 2, key([1, 2, 3])).map(|f| f.version),
            Some(10)
        );
        assert!(r.remove(cid(3), 0, key([1, 2, 3])).is_none());
        assert!(r.get(a, 10).is_none());
        // The slot is reused by another facet: the old pointers of cells 3 and 7 (asked with
        // their own facet's key) miss.
        let b = r.insert(
            key([4, 5, 6]),
            rf(cid(9), 1, 11, [4, 5, 6]),
            Facet {
                cell: cid(8),
                index: 0,
            },
        );
        assert_eq!(a, b);
        assert!(r.remove(cid(3), 0, key([1, 2, 3])).is_none());
        assert!(r.remove(cid(7), 2, key([1, 2, 3])).is_none());
        assert_eq!(r.len(), 1);
        assert!(r.remove(cid(8), 0, key([4, 5, 6])).is_some());
        assert_eq!(r.len(), 0);
        assert_eq!(r.iter().count(), 0);
    }
}
