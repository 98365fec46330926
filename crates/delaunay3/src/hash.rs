//! Private hash tables (ours): the cell set of a read-only conflict-zone search and the edge
//! map that links the cells of a new star. Both are open-addressing tables cleared in O(1)
//! by bumping a generation counter, so a search or a star allocates nothing once warm.

use crate::ids::{CellId, VertexId};

/// The cells a conflict-zone search has decided (in conflict or not): a small
/// open-addressing table of `generation << 33 | cell << 1 | in_conflict` words, cleared in
/// O(1) by bumping the generation and grown (rehashed) past half full. Invariant: a slot
/// belongs to the current search iff its top 31 bits equal `generation`.
#[derive(Clone, Debug, Default)]
pub(crate) struct SeenCells {
    slots: Vec<u64>,
    len: usize,
    generation: u64,
}

impl SeenCells {
    const MIN_SLOTS: usize = 512;

    pub(crate) fn clear(&mut self) {
        if self.slots.is_empty() {
            self.slots = vec![0; Self::MIN_SLOTS];
        }
        self.len = 0;
        self.generation += 1;
        if self.generation >= 1 << 31 {
            self.slots.iter_mut().for_each(|s| *s = 0);
            self.generation = 1;
        }
    }

    #[inline]
    fn home(&self, c: u32) -> usize {
        ((c as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 32) as usize & (self.slots.len() - 1)
    }

    #[inline]
    pub(crate) fn get(&self, c: CellId) -> Option<bool> {
        let c = c.0;
        let mut h = self.home(c);
        loop {
            let s = self.slots[h];
            if s >> 33 != self.generation {
                return None;
            }
            if (s >> 1) as u32 == c {
                return Some(s & 1 == 1);
            }
            h = (h + 1) & (self.slots.len() - 1);
        }
    }

    /// Records `c` (not present yet).
    #[inline]
    pub(crate) fn insert(&mut self, c: CellId, inside: bool) {
        let c = c.0;
        if 2 * (self.len + 1) > self.slots.len() {
            self.grow();
        }
        let mut h = self.home(c);
        while self.slots[h] >> 33 == self.generation {
            h = (h + 1) & (self.slots.len() - 1);
        }
        self.slots[h] = self.generation << 33 | (c as u64) << 1 | inside as u64;
        self.len += 1;
    }

    #[cold]
    fn grow(&mut self) {
        let live: Vec<u64> = self
            .slots
            .iter()
            .copied()
            .filter(|s| s >> 33 == self.generation)
            .collect();
        self.slots = vec![0; self.slots.len() * 2];
        for s in live {
            let mut h = self.home((s >> 1) as u32);
            while self.slots[h] >> 33 == self.generation {
                h = (h + 1) & (self.slots.len() - 1);
            }
            self.slots[h] = s;
        }
    }
}

/// Small open-addressing map (sorted edge) -> (cell, local facet), cleared by generation.
#[derive(Clone, Default)]
pub(crate) struct EdgeMap {
    keys: Vec<u64>,
    vals: Vec<(CellId, u8)>,
    gen_: Vec<u32>,
    generation: u32,
    mask: usize,
}

impl EdgeMap {
    pub(crate) fn reset(&mut self, expected: usize) {
        let want = (expected * 2).next_power_of_two().max(64);
        if want > self.keys.len() {
            self.keys = vec![0; want];
            self.vals = vec![(CellId(0), 0); want];
            self.gen_ = vec![0; want];
            self.generation = 0;
            self.mask = want - 1;
        }
        self.generation = self.generation.wrapping_add(1);
        if self.generation == 0 {
            self.gen_.iter_mut().for_each(|g| *g = 0);
            self.generation = 1;
        }
    }

    /// Returns the stored entry for `key` (removing nothing) or stores `val` and returns None.
    #[inline]
    pub(crate) fn match_or_insert(&mut self, key: u64, val: (CellId, u8)) -> Option<(CellId, u8)> {
        let mut h = (key.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 40) as usize & self.mask;
        loop {
            if self.gen_[h] != self.generation {
                self.gen_[h] = self.generation;
                self.keys[h] = key;
                self.vals[h] = val;
                return None;
            }
            if self.keys[h] == key {
                return Some(self.vals[h]);
            }
            h = (h + 1) & self.mask;
        }
    }

    /// Bytes held (capacities).
    pub(crate) fn memory_bytes(&self) -> usize {
        self.keys.capacity() * 8 + self.vals.capacity() * 8 + self.gen_.capacity() * 4
    }
}

/// The key of the edge `{a, b}` (order-independent).
#[inline]
pub(crate) fn edge_key(a: VertexId, b: VertexId) -> u64 {
    let (a, b) = if a.0 < b.0 { (a.0, b.0) } else { (b.0, a.0) };
    ((a as u64) << 32) | b as u64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seen_cells_survive_growth_and_clear() {
        let mut s = SeenCells::default();
        s.clear();
        for c in 0..2000u32 {
            s.insert(CellId(c * 7), c % 3 == 0);
        }
        for c in 0..2000u32 {
            assert_eq!(s.get(CellId(c * 7)), Some(c % 3 == 0));
        }
        assert_eq!(s.get(CellId(1)), None);
        s.clear();
        assert_eq!(s.get(CellId(0)), None);
    }

    #[test]
    fn edge_map_matches_each_edge_once_per_generation() {
        let mut m = EdgeMap::default();
        m.reset(10);
        let k = edge_key(VertexId(3), VertexId(9));
        assert_eq!(k, edge_key(VertexId(9), VertexId(3)));
        assert_eq!(m.match_or_insert(k, (CellId(1), 2)), None);
        assert_eq!(m.match_or_insert(k, (CellId(5), 0)), Some((CellId(1), 2)));
        m.reset(10);
        assert_eq!(m.match_or_insert(k, (CellId(5), 0)), None);
    }
}
