//! Updating Del_S(E) after insertions (section 6.1: "only the Voronoi edges that changed are
//! re-tested"); see the invariants of `crate::restricted`.

use super::sorted3;
use super::test::inside;
use crate::error::MeshError;
use crate::schedule::Calls;
use crate::state::Mesher;
use crate::voronoi::{CellInfo, cell_info_of};
use delaunay3::{CellId, Changes, Facet, Insertion, VertexId};
use glam::DVec3;
use std::time::Instant;

impl Mesher<'_> {
    /// Compute every cell's circumcenter and value, and test every facet of Del(E) once.
    pub(crate) fn full_scan(&mut self) -> Result<(), MeshError> {
        for c in self.tri.live_cells().collect::<Vec<_>>() {
            let info = self.cell_info(c); // infinite cells get f = +inf
            self.voronoi.set(c, info);
        }
        let cells: Vec<CellId> = self.tri.finite_cells().collect();
        self.eval_cells(&cells)?;
        let mut pairs = Vec::new();
        for &c in &cells {
            for i in 0..4u8 {
                let f = Facet { cell: c, index: i };
                let m = self.tri.mirror_facet(f);
                if self.tri.is_infinite(m.cell) || c < m.cell {
                    pairs.push((f, m));
                }
            }
        }
        for chunk in pairs.chunks(4096) {
            self.test_facets(chunk)?;
        }
        Ok(())
    }

    /// Circumcenter of live cell `c`, with f = NaN ("value not evaluated yet", see
    /// `eval_cells`) inside the bounding ball and +inf outside it or for an infinite cell.
    pub(crate) fn cell_info(&self, c: CellId) -> CellInfo {
        cell_info_of(&self.tri, &self.ball, self.tri.cell_vertices(c), DVec3::NAN)
    }

    /// Evaluate the surface at the circumcenters of `cells` left pending (timed as oracle
    /// time).
    pub(crate) fn eval_cells(&mut self, cells: &[CellId]) -> Result<(), MeshError> {
        let t = Instant::now();
        let n = cells.len();
        let exec = self.policy.oracle(n, Calls::Values);
        self.values += self.voronoi.eval(self.s, cells, exec)?;
        let dt = t.elapsed();
        self.t_oracle += dt;
        self.policy.observe(Calls::Values, dt, n);
        Ok(())
    }

    /// Insert `p` and update Del_S(E). Returns false if `p` was already a vertex.
    pub(crate) fn insert(&mut self, p: DVec3, hint: Option<CellId>) -> Result<bool, MeshError> {
        let t = Instant::now();
        let mut changes = Changes::default();
        let res = self.tri_mut().insert_with(p, hint, Some(&mut changes));
        self.t_delaunay += t.elapsed();
        if let Insertion::Duplicate(_) = res? {
            return Ok(false);
        }
        self.remove_destroyed(&changes);
        self.process_created(&changes.created, &[])?;
        Ok(true)
    }

    /// Remove the restricted facets of the cells an insertion destroyed (registered facets
    /// have their bits in the complex's mask; this includes the cavity's boundary facets,
    /// whose duals changed).
    pub(crate) fn remove_destroyed(&mut self, changes: &Changes) {
        self.ensure_vertex_slots();
        for (cell, &id) in changes.removed.iter().zip(&changes.removed_cells) {
            let mask = self.restricted.mask(id);
            if mask == 0 {
                continue;
            }
            for i in 0..4 {
                if mask & (1 << i) == 0 {
                    continue;
                }
                let mut f = [VertexId::INFINITE; 3];
                let mut k = 0;
                for (j, &v) in cell.iter().enumerate() {
                    if j != i {
                        f[k] = v;
                        k += 1;
                    }
                }
                if !f.contains(&VertexId::INFINITE)
                    && let Some(rf) = self.restricted.unregister(id, i as u8, sorted3(f))
                {
                    // Its queue entry, if any, is stale now.
                    self.queue.facet_removed(&rf);
                }
            }
        }
    }

    /// Compute the circumcenters and values of `created` cells (given as `infos` when they
    /// were computed during the conflict-zone search, else empty) and test every facet of
    /// them (new facets and the boundary facets of the cavities, whose duals changed).
    pub(crate) fn process_created(
        &mut self,
        created: &[CellId],
        infos: &[CellInfo],
    ) -> Result<(), MeshError> {
        if infos.len() == created.len() {
            for (&c, &info) in created.iter().zip(infos) {
                debug_assert_eq!(
                    (info.cc.to_array(), info.f.is_nan()),
                    {
                        let i = self.cell_info(c);
                        (i.cc.to_array(), i.f.is_nan())
                    },
                    "planned cell info differs"
                );
                self.voronoi.set(c, info);
            }
        } else {
            let this = &*self;
            let infos = self
                .policy
                .cells(created.len())
                .map(created, |&c| this.cell_info(c));
            for (&c, info) in created.iter().zip(infos) {
                self.voronoi.set(c, info);
            }
        }
        self.eval_cells(created)?;
        self.restricted.start_round(created);
        let this = &*self;
        let pairs = self
            .policy
            .cells(created.len())
            .flat_map_chunks(created, 64, |chunk, out| this.facets_to_test(chunk, out));
        self.restricted.end_round(created);
        self.test_facets(&pairs)
    }

    /// The facets of `cells` (created in this round) to test, each with its mirror facet,
    /// once each: a facet between two created cells is taken from the smaller id.
    fn facets_to_test(&self, cells: &[CellId], out: &mut Vec<(Facet, Facet)>) {
        let bipolar = self.opts.oracle == crate::OracleKind::Bipolar;
        for &c in cells {
            let fc = self.voronoi.get(c).f;
            for i in 0..4u8 {
                let n = self.tri.neighbor(c, i as usize);
                if n < c && self.restricted.is_created(n) {
                    continue; // tested from n's side
                }
                // Invariant (kept by `full_scan` and `process_created`): every live cell has
                // its Voronoi entry, with f = +inf for infinite cells. So the bipolar sign
                // rejection of `prepare_facet` can run here before the mirror facet is built.
                if bipolar && inside(fc) == inside(self.voronoi.get(n).f) {
                    continue;
                }
                let f = Facet { cell: c, index: i };
                out.push((f, self.tri.mirror_facet(f)));
            }
        }
    }
}
