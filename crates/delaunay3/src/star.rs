//! The adjacency of a new star (ours): which new cells share a facet, found through a small
//! table indexed by local ids of the cavity's boundary vertices instead of hashing edges.
//!
//! The boundary of a cavity is a closed surface whose facets are oriented consistently (out
//! of the cavity), so every boundary edge appears exactly twice, as `a -> b` in one facet
//! and `b -> a` in the other. The new cell on facet `k = [v0, v1, v2]` is `[v0, v1, v2, w]`;
//! its facet `f` (opposite `v_f`, `f < 3`) holds the boundary edge `v_{f+1} -> v_{f+2}`
//! (indices mod 3) and is shared with the new cell of the facet holding `v_{f+2} -> v_{f+1}`.
//! With `s` boundary vertices numbered `0..s`, a first pass writes `k * 4 + f` at
//! `half[a * s + b]` for every directed edge, a second reads the twin at `half[b * s + a]`:
//! every twin was written in the first pass (the surface is closed), so nothing needs
//! clearing, and no branch depends on the data. Stars with more than [`MAX_LOCAL`] boundary
//! vertices (degenerate inputs) return `None`; the caller then hashes edges.
//!
//! Invariant: `local[x + 1]` (the infinite vertex, `u32::MAX`, wraps to index 0) is
//! `base + (local id of x)` for the boundary vertices of the current star and below `base`
//! for every other vertex, including those of an earlier star that overflowed (its ids reach
//! `MAX_LOCAL + 2`: consecutive bases are [`STRIDE`] apart).

use crate::ids::VertexId;

/// Largest number of boundary vertices handled by the table (`half` has `s * s` entries).
pub(crate) const MAX_LOCAL: usize = 128;

/// Local ids a star may write: the overflow is seen after a whole facet, so an overflowing
/// star writes ids up to `MAX_LOCAL + 2`. Consecutive stars' ranges are this far apart.
const STRIDE: u32 = MAX_LOCAL as u32 + 3;

/// Scratch space of [`StarLinks::link`], reused across insertions.
#[derive(Clone, Default)]
pub(crate) struct StarLinks {
    local: Vec<u32>,
    base: u32,
    /// Local id -> vertex (the first [`StarLinks::len`] entries).
    verts: Vec<VertexId>,
    /// Local id -> the last new cell (boundary index) containing the vertex.
    last: Vec<u32>,
    len: usize,
    /// Boundary facet -> its three local ids.
    tri: Vec<[u32; 3]>,
    half: Vec<u32>,
}

impl StarLinks {
    /// Bytes held (capacities).
    pub(crate) fn memory_bytes(&self) -> usize {
        (self.local.capacity() + self.last.capacity() + self.half.capacity()) * 4
            + self.verts.capacity() * 4
            + self.tri.capacity() * 12
    }

    /// Numbers the vertices of `facets` (first appearance order) and records, for each,
    /// the last facet containing it. `n_vertices`: the number of finite vertices. `false`
    /// if there are more than [`MAX_LOCAL`] of them. Branch-free per vertex: `verts` and
    /// `last` are written at the next free id whether or not the vertex is new.
    fn number(&mut self, facets: impl Iterator<Item = [VertexId; 3]>, n_vertices: usize) -> bool {
        if self.local.len() < n_vertices + 1 {
            self.local.resize(n_vertices + 1, 0);
        }
        if self.base > u32::MAX - 2 * STRIDE {
            self.local.iter_mut().for_each(|l| *l = 0);
            self.base = 0;
        }
        // Every id written by the last star, overflowing or not, is below `STRIDE`, so its
        // slots are now below `base`: fresh for this star.
        self.base += STRIDE;
        let base = self.base;
        if self.verts.len() < MAX_LOCAL + 3 {
            self.verts.resize(MAX_LOCAL + 3, VertexId::NONE);
            self.last.resize(MAX_LOCAL + 3, 0);
        }
        self.tri.clear();
        let mut len = 0usize;
        for (k, f) in facets.enumerate() {
            let mut t = [0u32; 3];
            for i in 0..3 {
                let x = f[i];
                let slot = &mut self.local[x.0.wrapping_add(1) as usize];
                let fresh = *slot < base;
                let l = if fresh { len as u32 } else { *slot - base };
                *slot = base + l;
                self.verts[len] = x;
                len += fresh as usize;
                self.last[l as usize] = k as u32;
                t[i] = l;
            }
            self.tri.push(t);
            if len > MAX_LOCAL {
                return false;
            }
        }
        self.len = len;
        true
    }

    /// The neighbors among the new cells: for boundary facet `k`, `out[k][f]` is
    /// `k' * 4 + f'` with new cell `k'` across its facet `f` (`f, f' < 3`). `false` (and
    /// `out` untouched) for stars of more than [`MAX_LOCAL`] boundary vertices.
    pub(crate) fn link(
        &mut self,
        facets: impl Iterator<Item = [VertexId; 3]>,
        n_vertices: usize,
        out: &mut Vec<[u32; 3]>,
    ) -> bool {
        if !self.number(facets, n_vertices) {
            return false;
        }
        let s = self.len;
        if self.half.len() < s * s {
            self.half.resize(s * s, 0);
        }
        let half = &mut self.half[..s * s];
        for (k, t) in self.tri.iter().enumerate() {
            let [a, b, c] = t.map(|x| x as usize);
            let k4 = (k * 4) as u32;
            // Facet f holds the directed edge t[f + 1] -> t[f + 2].
            half[b * s + c] = k4;
            half[c * s + a] = k4 + 1;
            half[a * s + b] = k4 + 2;
        }
        out.clear();
        for t in &self.tri {
            let [a, b, c] = t.map(|x| x as usize);
            out.push([half[c * s + b], half[a * s + c], half[b * s + a]]);
        }
        true
    }

    /// The boundary vertices of the last star linked by [`StarLinks::link`], each with the
    /// last new cell (boundary index) containing it.
    pub(crate) fn vertices(&self) -> impl Iterator<Item = (VertexId, u32)> + '_ {
        self.verts[..self.len]
            .iter()
            .copied()
            .zip(self.last[..self.len].iter().copied())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn links_the_faces_of_a_tetrahedron_boundary() {
        // The boundary of tetrahedron 0123 oriented outward: each edge twice, opposite ways.
        let v = |i: u32| VertexId(i * 10);
        let facets = [[1, 3, 2], [0, 2, 3], [0, 3, 1], [0, 1, 2]].map(|f| f.map(v));
        let mut s = StarLinks::default();
        let mut out = Vec::new();
        assert!(s.link(facets.iter().copied(), 40, &mut out));
        for (k, n) in out.iter().enumerate() {
            for (f, &nf) in n.iter().enumerate() {
                let (k2, f2) = ((nf / 4) as usize, (nf % 4) as usize);
                assert_ne!(k2, k);
                assert_eq!(out[k2][f2], (k * 4 + f) as u32, "symmetric");
                // The shared facet's two boundary vertices are the same.
                let e = |k: usize, f: usize| {
                    let mut e = [facets[k][(f + 1) % 3], facets[k][(f + 2) % 3]];
                    e.sort();
                    e
                };
                assert_eq!(e(k, f), e(k2, f2));
            }
        }
        // A second star reuses the scratch; the infinite vertex has a slot too.
        let facets2 = [[1, 3, 2], [0, 2, 3], [0, 3, 1], [0, 1, 2]]
            .map(|f| f.map(|i| if i == 0 { VertexId::INFINITE } else { v(i) }));
        assert!(s.link(facets2.iter().copied(), 40, &mut out));
        let last: Vec<u32> = s.vertices().map(|x| x.1).collect();
        assert_eq!(last, vec![3, 2, 3, 3]);
    }

    /// A star that overflows [`MAX_LOCAL`] in a facet of three new vertices writes local ids
    /// up to `MAX_LOCAL + 2`; the next star must still see those vertices as fresh. (With a
    /// stride of `MAX_LOCAL + 1` between stars they read as the next star's ids 0 and 1, and
    /// its cells were linked wrong: a corrupt triangulation, found on the noisy phantom at
    /// iso 4.5, `--size 18`.)
    #[test]
    fn a_star_after_an_overflowing_one_is_linked_right() {
        let v = |i: u32| VertexId(i);
        let mut s = StarLinks::default();
        let mut out = Vec::new();
        // 42 facets of three new vertices (126), one with two (128), one with three more:
        // ids 128, 129 and 130 are written before the overflow is seen.
        let mut big: Vec<[VertexId; 3]> = (0..42)
            .map(|k| [v(3 * k), v(3 * k + 1), v(3 * k + 2)])
            .collect();
        big.push([v(126), v(127), v(0)]);
        big.push([v(128), v(129), v(130)]);
        assert!(!s.link(big.iter().copied(), 200, &mut out));
        // A tetrahedron's boundary on vertices 129, 130 (ids 129 and 130 above) and two others.
        let facets = [[1, 3, 2], [0, 2, 3], [0, 3, 1], [0, 1, 2]]
            .map(|f| f.map(|i| v([129, 130, 150, 151][i])));
        assert!(s.link(facets.iter().copied(), 200, &mut out));
        for (k, n) in out.iter().enumerate() {
            for (f, &nf) in n.iter().enumerate() {
                let (k2, f2) = ((nf / 4) as usize, (nf % 4) as usize);
                assert_ne!(k2, k, "facet {k} linked to itself");
                assert_eq!(out[k2][f2], (k * 4 + f) as u32, "symmetric");
            }
        }
        let verts: Vec<VertexId> = s.vertices().map(|x| x.0).collect();
        assert_eq!(verts, [130, 151, 150, 129].map(v));
    }
}
