//! Checking the invariants of `crate::restricted` and `crate::voronoi` (ours, for tests, as
//! spade's `sanity_check`): the incremental Del_S(E) against a recomputation from scratch.

use super::sorted3;
use crate::state::Mesher;
use delaunay3::{Facet, VertexId};

impl Mesher<'_> {
    /// Check, without changing anything: Del(E) is valid (combinatorics, orientation, local
    /// Delaunay property); every live cell's cached Voronoi vertex and value equal a
    /// recomputation; the registered facets are exactly those a full scan of Del(E) finds
    /// restricted, each with its mask bits, and the per-vertex counts match. Call it between
    /// steps (no batch pending). The error lists what differs.
    pub(crate) fn validate(&self) -> Result<(), String> {
        let mut problems = Vec::new();
        if let Err(e) = self.tri.is_valid() {
            problems.push(format!("Del(E) is invalid: {e:?}"));
        }
        let mut stale_cells = 0;
        for c in self.tri.live_cells() {
            let want = self.cell_info(c);
            let have = self.voronoi.get(c);
            let f = if want.f.is_nan() {
                self.s.value(want.cc)
            } else {
                want.f
            };
            if have.cc.to_array().map(f64::to_bits) != want.cc.to_array().map(f64::to_bits)
                || have.f.to_bits() != f.to_bits()
            {
                stale_cells += 1;
            }
        }
        if stale_cells > 0 {
            problems.push(format!("{stale_cells} cells with a stale Voronoi vertex"));
        }
        // The facets a full scan finds restricted (the cache is exact, checked above).
        let mut want: Vec<[VertexId; 3]> = Vec::new();
        let mut buf = Vec::new();
        for c in self.tri.finite_cells() {
            for i in 0..4u8 {
                let f = Facet { cell: c, index: i };
                let m = self.tri.mirror_facet(f);
                if !(self.tri.is_infinite(m.cell) || c < m.cell) {
                    continue;
                }
                if let Some(pf) = self.prepare_facet(f, m)
                    && self.resolve_facet(&pf, &mut buf).is_some()
                {
                    want.push(sorted3(pf.verts));
                }
            }
        }
        want.sort_unstable();
        let mut have: Vec<[VertexId; 3]> = self.restricted.iter().map(|(_, k, _)| k).collect();
        have.sort_unstable();
        let missing = want
            .iter()
            .filter(|k| have.binary_search(k).is_err())
            .count();
        let extra = have
            .iter()
            .filter(|k| want.binary_search(k).is_err())
            .count();
        if missing + extra > 0 {
            problems.push(format!(
                "Del_S(E) differs from a full scan: {missing} facets missing, {extra} extra"
            ));
        }
        let mut count = vec![0u32; self.tri.num_vertices()];
        let mut unmasked = 0;
        for (_, k, rf) in self.restricted.iter() {
            for v in k {
                count[v.index()] += 1;
            }
            let m = self.tri.mirror_facet(rf.facet());
            let bit = |f: Facet| self.restricted.mask(f.cell) & (1 << f.index) != 0;
            unmasked += usize::from(!(bit(rf.facet()) && bit(m)));
        }
        if unmasked > 0 {
            problems.push(format!(
                "{unmasked} registered facets without their mask bits"
            ));
        }
        let wrong = (0..count.len())
            .filter(|&v| self.restricted.facets_at(VertexId::from_index(v)) != count[v])
            .count();
        if wrong > 0 {
            problems.push(format!("{wrong} vertices with a wrong facet count"));
        }
        if problems.is_empty() {
            Ok(())
        } else {
            Err(problems.join("; "))
        }
    }
}
