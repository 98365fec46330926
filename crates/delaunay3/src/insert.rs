//! Insertion (Bowyer-Watson; the paper's "insert c into E and update Del(E)", section 6.1):
//! the cavity of cells in conflict with the point is replaced by the star of the new vertex.
//! Also the start: points are held until four are affinely independent, then the first
//! tetrahedron is built and the held points are inserted.

use glam::DVec3;

use crate::cavity::{Cavity, Stamps, search};
use crate::ids::{CellId, VertexId};
use crate::locate::Walk;
use crate::predicates::{self, Sign, orient3d};
use crate::sort;
use crate::tds::{Boundary, Cell, FACET};
use crate::triangulation::{Error, Triangulation, check_point};

/// What [`Triangulation::insert`] did with a point.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Insertion {
    /// A new vertex was created.
    New(VertexId),
    /// The point equals an existing vertex; nothing changed.
    Duplicate(VertexId),
}

impl Insertion {
    /// The vertex of the point (new or existing).
    pub fn vertex(self) -> VertexId {
        match self {
            Insertion::New(v) | Insertion::Duplicate(v) => v,
        }
    }
}

/// What an insertion changed, for callers that maintain data over cells/facets.
/// [`Triangulation::insert_with`] clears both vectors before filling them.
#[derive(Clone, Debug, Default)]
pub struct Changes {
    /// Vertex tuples of the cells destroyed (the conflict zone), as they were.
    pub removed: Vec<[VertexId; 4]>,
    /// The ids the destroyed cells had (parallel to `removed`). Their slots may already be
    /// reused by `created` cells: read your per-cell data for them before updating it.
    pub removed_cells: Vec<CellId>,
    /// Cells created by the insertion. Every facet of a created cell is either new or a
    /// boundary facet of the cavity (whose dual changed).
    pub created: Vec<CellId>,
}

impl Changes {
    fn clear(&mut self) {
        self.removed.clear();
        self.removed_cells.clear();
        self.created.clear();
    }
}

impl Triangulation {
    /// Inserts `p` (hint: the last cell). See [`Triangulation::insert_with`].
    pub fn insert(&mut self, p: DVec3) -> Result<Insertion, Error> {
        self.insert_with(p, None, None)
    }

    /// Inserts `p`, starting the point location at `hint` (a live cell; otherwise the last
    /// created cell is used). If `changes` is given it is cleared and filled with the cells
    /// destroyed and created. A duplicate of an existing vertex changes nothing. When this
    /// insertion makes the triangulation 3D, `changes.created` holds every cell.
    ///
    /// Errors: [`Error::InvalidPoint`] for non-finite or out-of-range coordinates.
    pub fn insert_with(
        &mut self,
        p: DVec3,
        hint: Option<CellId>,
        changes: Option<&mut Changes>,
    ) -> Result<Insertion, Error> {
        check_point(p)?;
        let mut changes = changes;
        if let Some(ch) = changes.as_deref_mut() {
            ch.clear();
        }
        if !self.built {
            let r = self.insert_held(p);
            if self.built
                && let Some(ch) = changes
            {
                ch.created.extend(self.live_cells());
            }
            return Ok(r);
        }
        let start = self.start_cell(hint);
        Ok(self.insert_3d(p, None, start, changes))
    }

    /// Inserts the point of a conflict zone found by [`Triangulation::find_cavity`] on this
    /// triangulation. Correct only if no cell of the zone, and no cell just outside it, was
    /// destroyed since the search: the caller applies zones of one batch in order and skips
    /// a zone whose [`Cavity::touched_cells`] meet the [`Cavity::cells`] of a zone applied
    /// before it.
    ///
    /// Why that suffices: a cell created by an earlier zone A joins A's point to a facet
    /// between a destroyed cell D and an outside cell O, and its circumball lies in the union
    /// of the balls of D and O. Neither D (a cell of A, not touched by this zone B, so not in
    /// conflict with B's point: conflict zones are connected) nor O (O is not in B's zone,
    /// else D, its neighbor, would be in B's zone or on its boundary) is in conflict with B's
    /// point, so no new cell is; and B's own cells and outside neighbors are still alive,
    /// with the facets between them unchanged (A only rewires O's facet toward D).
    /// `changes` as for [`Triangulation::insert_with`].
    pub fn insert_cavity(&mut self, cav: &Cavity, changes: Option<&mut Changes>) -> Insertion {
        let mut changes = changes;
        if let Some(ch) = changes.as_deref_mut() {
            ch.clear();
        }
        if let Some(v) = cav.duplicate {
            return Insertion::Duplicate(v);
        }
        debug_assert!(cav.cells.iter().all(|&c| self.is_cell(c)));
        self.cavity.clear();
        self.cavity.extend_from_slice(&cav.cells);
        self.boundary.clear();
        self.boundary.extend_from_slice(&cav.boundary);
        self.replace_cavity(cav.p, None, changes)
    }

    /// Inserts `p` into a 3D triangulation, with vertex id `id` if pre-assigned: the walk
    /// from `start`, then the in-place depth-first cavity search with cell stamps.
    pub(crate) fn insert_3d(
        &mut self,
        p: DVec3,
        id: Option<VertexId>,
        start: CellId,
        changes: Option<&mut Changes>,
    ) -> Insertion {
        let mut rng = std::mem::take(&mut self.rng);
        let found = self.walk(p, start, &mut rng);
        self.rng = rng;
        let c0 = match found {
            Walk::Vertex(v) => {
                debug_assert!(id.is_none(), "held point found as a duplicate");
                return Insertion::Duplicate(v);
            }
            Walk::Inside(c) | Walk::Outside(c) => c,
        };
        let inside = self.tds.next_stamp();
        self.cavity.clear();
        self.stack.clear();
        self.boundary.clear();
        let mut d = Stamps {
            cells: &mut self.tds.cells,
            inside,
        };
        search::<_, true>(
            &mut d,
            &self.points,
            p,
            c0,
            &mut self.cavity,
            &mut self.stack,
            &mut self.boundary,
        );
        self.replace_cavity(p, id, changes)
    }

    /// Replaces the cells of `self.cavity` (bounded by `self.boundary`) by the star of a new
    /// vertex at `p` (with id `id` if pre-assigned).
    fn replace_cavity(
        &mut self,
        p: DVec3,
        id: Option<VertexId>,
        changes: Option<&mut Changes>,
    ) -> Insertion {
        let v = match id {
            Some(v) => v,
            None => {
                self.points.push(p);
                self.tds.vertex_cell.push(CellId::NONE);
                VertexId((self.points.len() - 1) as u32)
            }
        };
        let mut created = None;
        if let Some(ch) = changes {
            for &c in &self.cavity {
                ch.removed.push(self.tds.cell(c).v);
                ch.removed_cells.push(c);
            }
            created = Some(&mut ch.created);
        }
        let points = &self.points;
        self.tds
            .replace_with_star(v, &self.cavity, &self.boundary, created, |q| {
                debug_assert_eq!(
                    orient3d(
                        points[q[0].index()],
                        points[q[1].index()],
                        points[q[2].index()],
                        points[q[3].index()]
                    ),
                    Sign::Positive,
                    "new cell {q:?} is not positive"
                );
            });
        Insertion::New(v)
    }

    /// Insertion while fewer than four affinely independent points are known.
    pub(crate) fn insert_held(&mut self, p: DVec3) -> Insertion {
        let key = (p + DVec3::ZERO).to_array().map(f64::to_bits); // -0.0 -> 0.0
        if let Some(&v) = self.held_map.get(&key) {
            return Insertion::Duplicate(v);
        }
        let v = VertexId(self.points.len() as u32);
        self.points.push(p);
        self.tds.vertex_cell.push(CellId::NONE);
        self.held_map.insert(key, v);
        let b = &self.basis;
        let independent = match b.len() {
            0 | 1 => true,
            2 => !predicates::collinear(self.pt(b[0]), self.pt(b[1]), p),
            _ => orient3d(self.pt(b[0]), self.pt(b[1]), self.pt(b[2]), p) != Sign::Zero,
        };
        if independent {
            self.basis.push(v);
        }
        if self.basis.len() == 4 {
            self.build_3d();
        }
        Insertion::New(v)
    }

    /// Builds the first tetrahedron from the basis, then inserts every other held point.
    fn build_3d(&mut self) {
        let mut b = [self.basis[0], self.basis[1], self.basis[2], self.basis[3]];
        if orient3d(self.pt(b[0]), self.pt(b[1]), self.pt(b[2]), self.pt(b[3])) == Sign::Negative {
            b.swap(0, 1);
        }
        self.built = true;
        let c0 = self.tds.alloc_cell();
        self.tds.cells[c0.index()] = Cell {
            v: b,
            n: [CellId::NONE; 4],
            mark: 0,
        };
        self.tds.n_live = 1;
        self.tds.n_finite = 1;
        // The outside of c0 is a cavity around the infinite vertex.
        self.cavity.clear();
        self.boundary.clear();
        for (i, f) in FACET.iter().enumerate() {
            let [x, y, z] = f.map(|k| b[k]);
            self.boundary.push(Boundary {
                v: [x, z, y],
                out: c0,
                j: i as u8,
            });
        }
        self.tds
            .replace_with_star(VertexId::INFINITE, &[], &self.boundary, None, |_| {});
        for &x in &b {
            self.tds.vertex_cell[x.index()] = c0;
        }
        self.tds.last_cell = c0;
        let mut rest: Vec<u32> = (0..self.points.len() as u32)
            .filter(|&v| !b.contains(&VertexId(v)))
            .collect();
        sort::hilbert_sort(&self.points, &mut rest);
        for v in rest {
            let start = self.start_cell(None);
            self.insert_3d(self.pt(VertexId(v)), Some(VertexId(v)), start, None);
        }
        self.held_map = Default::default();
        self.basis.clear();
    }
}
