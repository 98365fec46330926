//! The triangulation data structure (ours; topology only, no geometry): cells as vertex and
//! neighbor quadruples, the free list, the vertex-to-cell map, and the star construction
//! that replaces a cavity.
//!
//! Invariants (kept by [`Tds::replace_with_star`], checked by
//! [`crate::Triangulation::validate`]): a slot is live iff its `v[0] != DEAD`; neighbor `i`
//! of a live cell is across the facet opposite its local vertex `i` and is live, with a
//! unique back pointer; `n_live` / `n_finite` count the live / finite live cells; every live
//! slot not on the free list; `vertex_cell[v]` is a live cell containing `v`.

use crate::hash::{EdgeMap, edge_key};
use crate::ids::{CellId, VertexId};
use crate::star::StarLinks;

/// Marks a dead (free) slot in `v[0]`. Never a vertex of a live cell.
pub(crate) const DEAD: VertexId = VertexId::NONE;

/// Facet `i` of a cell: the three local indices, ordered so that the normal
/// `(b - a) x (c - a)` points away from local vertex `i` (for a positive cell).
pub(crate) const FACET: [[usize; 3]; 4] = [[1, 3, 2], [0, 2, 3], [0, 3, 1], [0, 1, 2]];

/// One cell slot.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Cell {
    /// The vertices (`v[0] == DEAD` for a free slot).
    pub(crate) v: [VertexId; 4],
    /// `n[i]`: the neighbor across the facet opposite `v[i]`.
    pub(crate) n: [CellId; 4],
    /// Visit stamp of the last in-place cavity search (kept next to the cell: one cache
    /// miss). See [`crate::cavity`].
    pub(crate) mark: u32,
}

impl Cell {
    /// Whether the cell has the infinite vertex.
    #[inline]
    pub(crate) fn is_infinite(&self) -> bool {
        self.v.contains(&VertexId::INFINITE)
    }
}

/// A boundary facet of a cavity: its vertices oriented with the normal pointing out of the
/// cavity, the outside cell, and the index of the facet in the outside cell.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Boundary {
    pub(crate) v: [VertexId; 3],
    pub(crate) out: CellId,
    pub(crate) j: u8,
}

/// The index `j` with `cells[n].n[j] == c`, for a neighbor `n` of `c`.
#[inline]
pub(crate) fn mirror_index(cells: &[Cell], n: CellId, c: CellId) -> usize {
    cells[n.index()]
        .n
        .iter()
        .position(|&x| x == c)
        .expect("neighbor symmetry")
}

/// [`mirror_index`] without branches (the conflict search's boundary facets): exactly one
/// neighbor of `n` is `c` (two cells share at most one facet), so the sum is its index.
#[inline(always)]
fn mirror_index_fast(cells: &[Cell], n: CellId, c: CellId) -> usize {
    let m = cells[n.index()].n;
    debug_assert_eq!(
        m.iter().filter(|&&x| x == c).count(),
        1,
        "neighbor symmetry"
    );
    usize::from(m[1] == c) + 2 * usize::from(m[2] == c) + 3 * usize::from(m[3] == c)
}

/// The facet of cavity cell `c` opposite its vertex `i`, whose other side `n` is outside.
#[inline]
pub(crate) fn boundary_facet(cells: &[Cell], c: CellId, i: usize, n: CellId) -> Boundary {
    let cv = cells[c.index()].v;
    let j = mirror_index_fast(cells, n, c) as u8;
    Boundary {
        v: FACET[i].map(|k| cv[k]),
        out: n,
        j,
    }
}

/// Cell storage and adjacency.
#[derive(Clone)]
pub(crate) struct Tds {
    pub(crate) cells: Vec<Cell>,
    pub(crate) free: Vec<CellId>,
    pub(crate) vertex_cell: Vec<CellId>,
    pub(crate) n_finite: usize,
    pub(crate) n_live: usize,
    /// Some live infinite cell (once 3D).
    pub(crate) infinite_cell: CellId,
    /// The last created cell: the default start of a walk.
    pub(crate) last_cell: CellId,
    stamp: u32,
    edges: EdgeMap,
    star: StarLinks,
    links: Vec<[u32; 3]>,
    slots: Vec<CellId>,
}

impl Default for Tds {
    fn default() -> Self {
        Tds {
            cells: Vec::new(),
            free: Vec::new(),
            vertex_cell: Vec::new(),
            n_finite: 0,
            n_live: 0,
            infinite_cell: CellId(0),
            last_cell: CellId(0),
            stamp: 0,
            edges: EdgeMap::default(),
            star: StarLinks::default(),
            links: Vec::new(),
            slots: Vec::new(),
        }
    }
}

impl Tds {
    /// Bytes allocated on the heap: (cells, free list, vertex -> cell, edge map).
    pub(crate) fn heap_bytes(&self) -> [usize; 4] {
        use std::mem::size_of;
        [
            self.cells.capacity() * size_of::<Cell>(),
            self.free.capacity() * size_of::<CellId>(),
            self.vertex_cell.capacity() * size_of::<CellId>(),
            self.edges.memory_bytes()
                + self.star.memory_bytes()
                + self.links.capacity() * 12
                + self.slots.capacity() * 4,
        ]
    }

    #[inline]
    pub(crate) fn cell(&self, c: CellId) -> &Cell {
        &self.cells[c.index()]
    }

    /// Whether `c` is a live cell slot.
    #[inline]
    pub(crate) fn is_cell(&self, c: CellId) -> bool {
        c.index() < self.cells.len() && self.cells[c.index()].v[0] != DEAD
    }

    /// The index `j` with `n[j] == c` in the neighbor `n` of `c`.
    #[inline]
    pub(crate) fn mirror_index(&self, n: CellId, c: CellId) -> usize {
        mirror_index(&self.cells, n, c)
    }

    /// Live cells (finite and infinite), in slot order.
    pub(crate) fn live_cells(&self) -> impl Iterator<Item = CellId> + '_ {
        self.cells
            .iter()
            .enumerate()
            .filter_map(|(i, c)| (c.v[0] != DEAD).then_some(CellId(i as u32)))
    }

    /// A fresh or recycled slot (its content is garbage until written).
    pub(crate) fn alloc_cell(&mut self) -> CellId {
        if let Some(c) = self.free.pop() {
            c
        } else {
            self.cells.push(Cell {
                v: [DEAD; 4],
                n: [CellId::NONE; 4],
                mark: 0,
            });
            CellId((self.cells.len() - 1) as u32)
        }
    }

    /// A new even stamp `s` for an in-place search (`s`: in conflict, `s + 1`: decided not
    /// in conflict); resets all marks on wrap-around.
    pub(crate) fn next_stamp(&mut self) -> u32 {
        if self.stamp >= u32::MAX - 4 {
            self.cells.iter_mut().for_each(|c| c.mark = 0);
            self.stamp = 0;
        }
        self.stamp += 2;
        self.stamp
    }

    /// Replaces the live cells `cavity` by the star of `w` over `boundary` (one cell per
    /// boundary facet, in boundary order, reusing the slots of `cavity` in order first, then
    /// the free list, then fresh slots; unused cavity slots are freed) and returns through
    /// `created` (if any) the new cells. `check` sees each new cell's vertices (debug checks
    /// of the caller; the geometry is not known here). With an empty `cavity`, this builds a
    /// star on a boundary of live cells (the first tetrahedron's outside).
    pub(crate) fn replace_with_star(
        &mut self,
        w: VertexId,
        cavity: &[CellId],
        boundary: &[Boundary],
        created: Option<&mut Vec<CellId>>,
        check: impl Fn([VertexId; 4]),
    ) {
        for &c in cavity {
            self.n_live -= 1;
            if !self.cells[c.index()].is_infinite() {
                self.n_finite -= 1;
            }
        }
        let nb = boundary.len();
        let mut links = std::mem::take(&mut self.links);
        let n_vertices = self.vertex_cell.len();
        if !self
            .star
            .link(boundary.iter().map(|b| b.v), n_vertices, &mut links)
        {
            self.replace_with_star_hashed(w, cavity, boundary, created, check);
            self.links = links;
            return;
        }
        let mut slots = std::mem::take(&mut self.slots);
        slots.clear();
        for k in 0..nb {
            let s = if k < cavity.len() {
                cavity[k]
            } else {
                self.alloc_cell()
            };
            slots.push(s);
        }
        for (k, b) in boundary.iter().enumerate() {
            let slot = slots[k];
            let v = [b.v[0], b.v[1], b.v[2], w];
            let n = links[k].map(|x| slots[(x >> 2) as usize]);
            self.cells[slot.index()] = Cell {
                v,
                n: [n[0], n[1], n[2], b.out],
                mark: 0,
            };
            self.cells[b.out.index()].n[b.j as usize] = slot;
            if v.contains(&VertexId::INFINITE) {
                self.infinite_cell = slot;
            } else {
                self.n_finite += 1;
                check(v);
            }
        }
        self.n_live += nb;
        // Each vertex's cell: the last new cell containing it (as the hashed path does).
        for (x, k) in self.star.vertices() {
            if x != VertexId::INFINITE {
                self.vertex_cell[x.index()] = slots[k as usize];
            }
        }
        if let Some(&last) = slots.last() {
            if w != VertexId::INFINITE {
                self.vertex_cell[w.index()] = last;
            }
            self.last_cell = last;
        }
        if let Some(cr) = created {
            cr.extend_from_slice(&slots);
        }
        for &c in cavity.iter().skip(nb) {
            self.cells[c.index()].v = [DEAD; 4];
            self.free.push(c);
        }
        self.slots = slots;
        self.links = links;
    }

    /// [`Tds::replace_with_star`] for stars of more than [`crate::star::MAX_LOCAL`] boundary
    /// vertices: new cells linked through a hash map of edges (the live counts of the
    /// cavity are already removed).
    fn replace_with_star_hashed(
        &mut self,
        w: VertexId,
        cavity: &[CellId],
        boundary: &[Boundary],
        mut created: Option<&mut Vec<CellId>>,
        check: impl Fn([VertexId; 4]),
    ) {
        let nb = boundary.len();
        self.edges.reset(nb * 3 / 2 + 1);
        for (k, b) in boundary.iter().enumerate() {
            let slot = if k < cavity.len() {
                cavity[k]
            } else {
                self.alloc_cell()
            };
            let v = [b.v[0], b.v[1], b.v[2], w];
            let infinite = v.contains(&VertexId::INFINITE);
            self.cells[slot.index()] = Cell {
                v,
                n: [CellId::NONE, CellId::NONE, CellId::NONE, b.out],
                mark: 0,
            };
            self.cells[b.out.index()].n[b.j as usize] = slot;
            self.n_live += 1;
            if infinite {
                self.infinite_cell = slot;
            } else {
                self.n_finite += 1;
                check(v);
            }
            for (f, key) in [
                edge_key(v[1], v[2]),
                edge_key(v[0], v[2]),
                edge_key(v[0], v[1]),
            ]
            .into_iter()
            .enumerate()
            {
                if let Some((oc, of)) = self.edges.match_or_insert(key, (slot, f as u8)) {
                    self.cells[slot.index()].n[f] = oc;
                    self.cells[oc.index()].n[of as usize] = slot;
                }
            }
            for &x in &v {
                if x != VertexId::INFINITE {
                    self.vertex_cell[x.index()] = slot;
                }
            }
            if let Some(cr) = created.as_deref_mut() {
                cr.push(slot);
            }
            self.last_cell = slot;
        }
        for &c in cavity.iter().skip(nb) {
            self.cells[c.index()].v = [DEAD; 4];
            self.free.push(c);
        }
    }
}
