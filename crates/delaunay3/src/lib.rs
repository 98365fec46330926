//! Exact, incremental 3D Delaunay triangulation.
//!
//! Points (`f64`) are inserted one at a time (Bowyer–Watson: the cavity of cells whose
//! circumsphere contains the point is replaced by the star of the new vertex) or in bulk
//! ([`Triangulation::insert_bulk`], which spatially sorts first: BRIO + Hilbert median order).
//! All decisions use exact predicates (`robust` orient3d / insphere, wrapped in
//! [`predicates`]); ties are broken by the Devillers–Teillaud symbolic perturbation with the
//! lexicographic `(x, y, z)` order of the points, so the triangulation of a point set is
//! unique and well defined for *any* input (cospherical, coplanar, grid points), independent
//! of the insertion order.
//!
//! # Structure
//! - An infinite vertex [`INFINITE_VERTEX`] closes the space: each convex-hull facet forms an
//!   *infinite cell* with it. Every cell has exactly four neighbors.
//! - Cells are stored compactly as `[u32; 4]` vertices plus `[u32; 4]` neighbors; neighbor
//!   `i` is across the facet opposite local vertex `i`. Freed slots are reused (free list);
//!   [`CellId`]s of destroyed cells become invalid.
//!
//! # Orientation convention
//! A finite cell `[v0, v1, v2, v3]` is *positive*: `predicates::orient3d(p0, p1, p2, p3)` is
//! [`predicates::Sign::Positive`], i.e. `p3` lies on the side of plane `p0 p1 p2` opposite to
//! the normal `(p1 - p0) x (p2 - p0)`. [`Triangulation::facet_vertices`] returns the facet
//! opposite vertex `i` ordered so that `(b - a) x (c - a)` points *out of* the cell (away from
//! vertex `i`, toward the mirror cell). An infinite cell is oriented as if its infinite vertex
//! were a point far outside the hull: its hull facet, as returned by `facet_vertices` at the
//! index of the infinite vertex, has its normal pointing *into* the hull.
//!
//! # Invariants (checked by [`Triangulation::is_valid`])
//! - Neighbor symmetry: `neighbor(neighbor(c, i), j) == c` for the mirror index `j`, and the
//!   two cells share exactly the three facet vertices.
//! - Every finite cell is positive; every infinite cell's hull facet sees the rest of the
//!   triangulation on its inner side; the hull is locally convex.
//! - Every vertex has a cell ([`Triangulation::vertex_cell`]).
//! - Every facet is locally Delaunay under the perturbation: the vertex of a neighbor opposite
//!   a shared facet is not in conflict with the cell.
//!
//! Until four affinely independent points have been inserted ([`Triangulation::dimension`]
//! `< 3`) points are held without cells; the triangulation is then built from all of them.
//!
//! # Performance
//! Point location is a randomized visibility walk from the last created cell (or a hint);
//! the cavity search uses a per-cell visit stamp and reused buffers, so an insertion does not
//! allocate. In-sphere tests go through a static f64 filter, a double-double stage (decides
//! nearly-cospherical inputs such as rounded sphere samples), an exact `i128` stage for
//! grid-like inputs, then `robust`'s exact arithmetic. About 250-280 bytes per point.
//! `crates/delaunay3/benches/cgal_baseline.sh` compares with CGAL on the same points;
//! `cargo bench -p delaunay3 --bench insert` is the criterion bench.
//!
//! # Example
//! ```
//! use delaunay3::{DVec3, Triangulation, Insertion, Changes};
//! let mut t = Triangulation::new();
//! let ids = t
//!     .insert_bulk(&[
//!         DVec3::new(0.0, 0.0, 0.0),
//!         DVec3::new(1.0, 0.0, 0.0),
//!         DVec3::new(0.0, 1.0, 0.0),
//!         DVec3::new(0.0, 0.0, 1.0),
//!     ])
//!     .unwrap();
//! assert_eq!(ids.len(), 4);
//! assert_eq!(t.num_finite_cells(), 1);
//! let mut changes = Changes::default();
//! let r = t.insert_with(DVec3::splat(0.2), None, Some(&mut changes)).unwrap();
//! assert!(matches!(r, Insertion::New(4)));
//! assert_eq!(changes.removed.len(), 1); // only the tetrahedron contains it in its sphere
//! assert_eq!(changes.created.len(), 4);
//! assert_eq!(t.num_finite_cells(), 4);
//! // insert_bulk returns the vertex of each input point (ids follow its sorted order).
//! assert_eq!(t.insert(DVec3::new(1.0, 0.0, 0.0)).unwrap(), Insertion::Duplicate(ids[1]));
//! assert!(t.is_valid().is_ok());
//! assert!(t.insert(DVec3::new(f64::NAN, 0.0, 0.0)).is_err());
//! ```

mod dd_arith;
pub mod predicates;
mod sort;

use std::collections::HashMap;

pub use glam::DVec3;
use predicates::{Sign, incircle_facet_perturbed, insphere_perturbed, orient3d};
use sort::Rng;

/// Index of a vertex: dense, in order of first insertion of each distinct point.
pub type VertexId = u32;
/// Index of a cell (tetrahedron) slot. Slots are reused through a free list.
pub type CellId = u32;
/// The vertex at infinity; every hull facet forms an infinite cell with it.
pub const INFINITE_VERTEX: VertexId = u32::MAX;
/// "No cell" marker (e.g. [`Triangulation::vertex_cell`] before the triangulation is 3D).
pub const NO_CELL: CellId = u32::MAX;
const DEAD: u32 = u32::MAX - 1;

/// Facet `i` of a cell: the three local indices, ordered so that the normal
/// `(b - a) x (c - a)` points away from local vertex `i` (for a positive cell).
const FACET: [[usize; 3]; 4] = [[1, 3, 2], [0, 2, 3], [0, 3, 1], [0, 1, 2]];

/// Facet of `cell` opposite to its local vertex `index` (0..4).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Facet {
    pub cell: CellId,
    pub index: u8,
}

/// The Voronoi dual of a Delaunay facet.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Dual {
    /// Between the circumcenters of the two finite cells sharing the facet.
    Segment(DVec3, DVec3),
    /// Hull facet: from the circumcenter of its finite cell, away from the hull.
    Ray { origin: DVec3, direction: DVec3 },
}

/// What [`Triangulation::insert`] did with a point.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Insertion {
    /// A new vertex was created.
    New(VertexId),
    /// The point equals an existing vertex; nothing changed.
    Duplicate(VertexId),
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

/// Why a point could not be inserted (the triangulation is left unchanged).
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum Error {
    #[error(
        "point {0:?} has a non-finite or out-of-range coordinate: every coordinate must be \
         finite, at most 2^200 in magnitude, and either 0 or at least 2^-140 in magnitude \
         (the range where the exact predicates cannot overflow); remove or rescale the point"
    )]
    InvalidPoint([f64; 3]),
}

/// Where a point lies, as found by [`Triangulation::locate`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Location {
    /// The point is this vertex.
    Vertex(VertexId),
    /// The point is in this finite cell (closed: possibly on its boundary, never a vertex).
    Cell(CellId),
    /// The point is outside the convex hull, strictly beyond the hull facet of this infinite
    /// cell.
    Outside(CellId),
    /// The triangulation is not 3D yet.
    NoCells,
}

/// A violated invariant, as reported by [`Triangulation::is_valid`].
#[derive(Debug, thiserror::Error, Clone, PartialEq, Eq)]
pub enum ValidationError {
    #[error("cell {cell}: neighbor {index} is {neighbor}, which is not a live cell")]
    BadNeighbor {
        cell: CellId,
        index: u8,
        neighbor: CellId,
    },
    #[error(
        "cell {cell}: neighbor {index} ({neighbor}) does not point back or shares a wrong facet"
    )]
    Asymmetric {
        cell: CellId,
        index: u8,
        neighbor: CellId,
    },
    #[error("cell {cell} {vertices:?} has a repeated, out-of-range or doubly infinite vertex")]
    BadVertices {
        cell: CellId,
        vertices: [VertexId; 4],
    },
    #[error("finite cell {cell} {vertices:?} is not positively oriented")]
    BadOrientation {
        cell: CellId,
        vertices: [VertexId; 4],
    },
    #[error(
        "hull facet of infinite cell {cell} does not face the hull interior or is not convex (facet {index})"
    )]
    BadHull { cell: CellId, index: u8 },
    #[error("vertex {vertex} has no incident cell (vertex_cell = {cell})")]
    VertexWithoutCell { vertex: VertexId, cell: CellId },
    #[error("facet {index} of cell {cell} is not locally Delaunay")]
    NotDelaunay { cell: CellId, index: u8 },
    #[error("cell counts disagree: {0}")]
    Counts(String),
}

#[derive(Clone, Copy, Debug)]
struct Cell {
    v: [u32; 4],
    n: [u32; 4],
    /// Visit stamp of the last cavity search (kept next to the cell: one cache miss).
    mark: u32,
}

/// A boundary facet of a cavity: its vertices oriented with the normal pointing out of the
/// cavity, the outside cell, and the index of the facet in the outside cell.
#[derive(Clone, Copy, Debug)]
struct Boundary {
    v: [u32; 3],
    out: CellId,
    j: u8,
}

/// The conflict zone of a point, found by [`Triangulation::find_cavity`] (read-only) and
/// applied by [`Triangulation::insert_cavity`]. Reusable: searches clear it.
#[derive(Clone, Debug, Default)]
pub struct Cavity {
    p: DVec3,
    cells: Vec<CellId>,
    boundary: Vec<Boundary>,
    duplicate: Option<VertexId>,
    seen: SeenCells,
}

impl Cavity {
    /// The point searched for.
    pub fn point(&self) -> DVec3 {
        self.p
    }

    /// The existing vertex equal to the point, if any (then the zone is empty).
    pub fn duplicate(&self) -> Option<VertexId> {
        self.duplicate
    }

    /// The cells in conflict with the point (destroyed by its insertion).
    pub fn cells(&self) -> &[CellId] {
        &self.cells
    }

    /// The cells in conflict and their neighbors across the zone's boundary. A zone stays
    /// valid after other zones were inserted as long as none of its touched cells was
    /// destroyed by them, i.e. its touched cells avoid their [`Cavity::cells`] (sharing an
    /// outside neighbor is fine: see [`Triangulation::insert_cavity`]).
    pub fn touched_cells(&self) -> impl Iterator<Item = CellId> + '_ {
        self.cells
            .iter()
            .copied()
            .chain(self.boundary.iter().map(|b| b.out))
    }

    /// The vertices of the cells that [`Triangulation::insert_cavity`] will create, in the
    /// order of [`Changes::created`] and with the same vertex order as
    /// [`Triangulation::cell_vertices`]; `new` stands for the inserted point's vertex id,
    /// unknown before the insertion. Lets a caller compute per-cell data (circumcenters)
    /// during the parallel search, while the boundary's points are in cache.
    ///
    /// ```
    /// use delaunay3::{Cavity, Changes, Triangulation};
    /// use glam::DVec3;
    /// let mut t = Triangulation::new();
    /// for p in [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z, DVec3::ONE] {
    ///     t.insert(p).unwrap();
    /// }
    /// let mut cav = Cavity::default();
    /// t.find_cavity(DVec3::splat(0.3), None, 1, &mut cav).unwrap();
    /// let planned: Vec<[u32; 4]> = cav.new_cells(u32::MAX).collect();
    /// let mut ch = Changes::default();
    /// let delaunay3::Insertion::New(v) = t.insert_cavity(&cav, Some(&mut ch)) else {
    ///     unreachable!()
    /// };
    /// let made: Vec<[u32; 4]> = ch.created.iter().map(|&c| t.cell_vertices(c)).collect();
    /// let planned: Vec<[u32; 4]> = planned
    ///     .iter()
    ///     .map(|q| q.map(|x| if x == u32::MAX { v } else { x }))
    ///     .collect();
    /// assert_eq!(made, planned);
    /// ```
    pub fn new_cells(&self, new: VertexId) -> impl ExactSizeIterator<Item = [VertexId; 4]> + '_ {
        // `build_star` makes one cell per boundary facet, in boundary order.
        self.boundary
            .iter()
            .map(move |b| [b.v[0], b.v[1], b.v[2], new])
    }
}

/// The cells a conflict-zone search has decided (in conflict or not): a small
/// open-addressing table of `generation << 33 | cell << 1 | in_conflict` words, cleared in
/// O(1) by bumping the generation and grown (rehashed) past half full. Invariant: a slot
/// belongs to the current search iff its top 31 bits equal `generation`.
#[derive(Clone, Debug, Default)]
struct SeenCells {
    slots: Vec<u64>,
    len: usize,
    generation: u64,
}

impl SeenCells {
    const MIN_SLOTS: usize = 512;

    fn clear(&mut self) {
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
    fn home(&self, c: CellId) -> usize {
        ((c as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 32) as usize & (self.slots.len() - 1)
    }

    #[inline]
    fn get(&self, c: CellId) -> Option<bool> {
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
    fn insert(&mut self, c: CellId, inside: bool) {
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

enum Walk {
    Vertex(VertexId),
    Inside(CellId),
    Outside(CellId),
}

/// Small open-addressing map (sorted edge) -> (cell, local facet), cleared by generation.
#[derive(Clone, Default)]
struct EdgeMap {
    keys: Vec<u64>,
    vals: Vec<(u32, u8)>,
    gen_: Vec<u32>,
    generation: u32,
    mask: usize,
}

impl EdgeMap {
    fn reset(&mut self, expected: usize) {
        let want = (expected * 2).next_power_of_two().max(64);
        if want > self.keys.len() {
            self.keys = vec![0; want];
            self.vals = vec![(0, 0); want];
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
    fn match_or_insert(&mut self, key: u64, val: (u32, u8)) -> Option<(u32, u8)> {
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
}

#[inline]
fn edge_key(a: u32, b: u32) -> u64 {
    let (a, b) = if a < b { (a, b) } else { (b, a) };
    ((a as u64) << 32) | b as u64
}

/// Checks that `p` can be inserted: finite coordinates, each 0 or of magnitude within
/// `[2^-140, 2^200]` (the range where the exact predicates cannot overflow or underflow).
pub fn validate_point(p: DVec3) -> Result<(), Error> {
    check_point(p)
}

fn check_point(p: DVec3) -> Result<(), Error> {
    const MAX: f64 = 1.606_938_044_258_990_3e60; // 2^200
    const MIN: f64 = 7.174_648_137_343_063e-43; // 2^-140
    for x in p.to_array() {
        let a = x.abs();
        if !x.is_finite() || a > MAX || (a != 0.0 && a < MIN) {
            return Err(Error::InvalidPoint(p.to_array()));
        }
    }
    Ok(())
}

/// An exact, incremental 3D Delaunay triangulation (see the crate docs).
#[derive(Default, Clone)]
pub struct Triangulation {
    points: Vec<DVec3>,
    vertex_cell: Vec<CellId>,
    cells: Vec<Cell>,
    free: Vec<CellId>,
    n_finite: usize,
    n_live: usize,
    infinite_cell: CellId,
    last_cell: CellId,
    built: bool,
    stamp: u32,
    rng: Rng,
    // Before the triangulation is 3D: the held points and an affinely independent subset.
    held_map: HashMap<[u64; 3], VertexId>,
    basis: Vec<VertexId>,
    // Reusable per-insertion buffers.
    cavity: Vec<CellId>,
    stack: Vec<CellId>,
    boundary: Vec<Boundary>,
    edges: EdgeMap,
}

impl Triangulation {
    /// An empty triangulation.
    pub fn new() -> Self {
        Self::default()
    }

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
            ch.removed.clear();
            ch.removed_cells.clear();
            ch.created.clear();
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

    /// Inserts all points (validated first: on error nothing is inserted) in a spatially
    /// sorted order (seeded BRIO + Hilbert, deterministic) and returns the vertex of each
    /// input point, in input order. Vertex ids follow the insertion (sorted) order.
    pub fn insert_bulk(&mut self, pts: &[DVec3]) -> Result<Vec<VertexId>, Error> {
        for &p in pts {
            check_point(p)?;
        }
        // Random points have ~6.7 tetrahedra per vertex; surface samples fewer. Untouched
        // reserved pages cost no resident memory.
        self.points.reserve(pts.len());
        self.vertex_cell.reserve(pts.len());
        self.cells.reserve(pts.len() * 7);
        let order = sort::brio_order(pts, 0x5eed_0000_0000_0000 ^ pts.len() as u64);
        let mut ids = vec![0; pts.len()];
        for &i in &order {
            let p = pts[i as usize];
            let r = if self.built {
                let start = self.start_cell(None);
                self.insert_3d(p, None, start, None)
            } else {
                self.insert_held(p)
            };
            ids[i as usize] = match r {
                Insertion::New(v) | Insertion::Duplicate(v) => v,
            };
        }
        Ok(ids)
    }

    /// 3 once four affinely independent points were inserted, else less (-1 when empty).
    pub fn dimension(&self) -> i32 {
        if self.built {
            3
        } else {
            self.basis.len() as i32 - 1
        }
    }

    /// Number of finite vertices (distinct points inserted).
    pub fn num_vertices(&self) -> usize {
        self.points.len()
    }

    /// The finite points, indexed by [`VertexId`].
    pub fn points(&self) -> &[DVec3] {
        &self.points
    }

    /// Panics if `v` is not a finite vertex.
    pub fn point(&self, v: VertexId) -> DVec3 {
        self.points[v as usize]
    }

    /// The four vertices of cell `c`, positively oriented for a finite cell (one of them is
    /// [`INFINITE_VERTEX`] for an infinite cell).
    pub fn cell_vertices(&self, c: CellId) -> [VertexId; 4] {
        self.cells[c as usize].v
    }

    /// The cell across the facet of `c` opposite its `i`-th vertex.
    pub fn neighbor(&self, c: CellId, i: usize) -> CellId {
        self.cells[c as usize].n[i]
    }

    /// Local index (0..4) of vertex `v` in cell `c`, if present.
    pub fn vertex_index(&self, c: CellId, v: VertexId) -> Option<usize> {
        self.cells[c as usize].v.iter().position(|&w| w == v)
    }

    /// Whether cell `c` has the infinite vertex (it lies outside the convex hull).
    pub fn is_infinite(&self, c: CellId) -> bool {
        self.cells[c as usize].v.contains(&INFINITE_VERTEX)
    }

    /// Whether `c` is a live cell slot.
    pub fn is_cell(&self, c: CellId) -> bool {
        (c as usize) < self.cells.len() && self.cells[c as usize].v[0] != DEAD
    }

    /// The same facet seen from the neighbor cell.
    pub fn mirror_facet(&self, f: Facet) -> Facet {
        let n = self.cells[f.cell as usize].n[f.index as usize];
        let j = self.cells[n as usize]
            .n
            .iter()
            .position(|&c| c == f.cell)
            .expect("neighbor symmetry");
        Facet {
            cell: n,
            index: j as u8,
        }
    }

    /// The three vertices of facet `f`, ordered so that the normal `(b - a) x (c - a)` points
    /// OUT of `f.cell` (away from its vertex `f.index`, toward the mirror cell). For the hull
    /// facet of an infinite cell that normal points into the hull.
    pub fn facet_vertices(&self, f: Facet) -> [VertexId; 3] {
        let v = self.cells[f.cell as usize].v;
        FACET[f.index as usize].map(|k| v[k])
    }

    /// Circumcenter of the finite cell `c`, computed relative to one vertex, with a
    /// double-double fallback for nearly flat cells. Panics if `c` is infinite.
    pub fn circumcenter(&self, c: CellId) -> DVec3 {
        let v = self.cells[c as usize].v;
        assert!(
            !v.contains(&INFINITE_VERTEX) && v[0] != DEAD,
            "circumcenter of infinite or dead cell {c}"
        );
        let p = v.map(|i| self.points[i as usize]);
        circumcenter(p[0], p[1], p[2], p[3])
    }

    /// The Voronoi dual of facet `f`: `None` if the facet contains the infinite vertex;
    /// `Segment(cc(f.cell), cc(mirror))` if both cells are finite (possibly of zero length);
    /// otherwise a ray from the circumcenter of the finite cell along the outward normal of
    /// the hull facet (not normalized).
    pub fn dual(&self, f: Facet) -> Option<Dual> {
        let cv = self.cells[f.cell as usize].v;
        let inf = cv.iter().position(|&w| w == INFINITE_VERTEX);
        match inf {
            Some(k) if k != f.index as usize => None,
            Some(_) => {
                let m = self.mirror_facet(f);
                Some(self.ray(m))
            }
            None => {
                let m = self.mirror_facet(f);
                if self.is_infinite(m.cell) {
                    Some(self.ray(f))
                } else {
                    Some(Dual::Segment(
                        self.circumcenter(f.cell),
                        self.circumcenter(m.cell),
                    ))
                }
            }
        }
    }

    /// Ray dual of the hull facet `f` seen from its finite cell.
    fn ray(&self, f: Facet) -> Dual {
        let [a, b, c] = self.facet_vertices(f).map(|v| self.points[v as usize]);
        Dual::Ray {
            origin: self.circumcenter(f.cell),
            direction: (b - a).cross(c - a),
        }
    }

    /// Live finite cells, in slot order.
    pub fn finite_cells(&self) -> impl Iterator<Item = CellId> + '_ {
        self.cells.iter().enumerate().filter_map(|(i, c)| {
            (c.v[0] != DEAD && !c.v.contains(&INFINITE_VERTEX)).then_some(i as CellId)
        })
    }

    /// Every facet not containing the infinite vertex (those with a Voronoi dual), once each,
    /// seen from the cell with the smaller id. Hull facets are included (their dual is a ray).
    pub fn finite_facets(&self) -> impl Iterator<Item = Facet> + '_ {
        self.live_cells().flat_map(move |c| {
            let cell = self.cells[c as usize];
            (0..4u8).filter_map(move |i| {
                let inf = cell.v.iter().position(|&w| w == INFINITE_VERTEX);
                let finite = inf.is_none_or(|k| k == i as usize);
                (finite && c < cell.n[i as usize]).then_some(Facet { cell: c, index: i })
            })
        })
    }

    /// Live cells (finite and infinite), in slot order.
    pub fn live_cells(&self) -> impl Iterator<Item = CellId> + '_ {
        self.cells
            .iter()
            .enumerate()
            .filter_map(|(i, c)| (c.v[0] != DEAD).then_some(i as CellId))
    }

    /// Number of live cells without the infinite vertex (tetrahedra of the hull).
    pub fn num_finite_cells(&self) -> usize {
        self.n_finite
    }

    /// Live cells, finite and infinite.
    pub fn num_cells(&self) -> usize {
        self.n_live
    }

    /// A cell incident to `v` ([`INFINITE_VERTEX`] allowed), or `None` before the
    /// triangulation is 3D.
    pub fn vertex_cell(&self, v: VertexId) -> Option<CellId> {
        if !self.built {
            return None;
        }
        if v == INFINITE_VERTEX {
            return Some(self.infinite_cell);
        }
        let c = *self.vertex_cell.get(v as usize)?;
        (c != NO_CELL).then_some(c)
    }

    /// All cells incident to `v` (finite vertex or [`INFINITE_VERTEX`]), in a deterministic
    /// order (breadth-first from [`Triangulation::vertex_cell`]).
    pub fn incident_cells(&self, v: VertexId) -> Vec<CellId> {
        let mut out = Vec::new();
        let Some(c0) = self.vertex_cell(v) else {
            return out;
        };
        // Stars have tens to hundreds of cells: a fast hash (cell ids are not adversarial).
        let mut seen = rustc_hash::FxHashSet::default();
        out.push(c0);
        seen.insert(c0);
        let mut k = 0;
        while k < out.len() {
            let c = out[k];
            k += 1;
            let cell = self.cells[c as usize];
            for i in 0..4 {
                if cell.v[i] == v {
                    continue;
                }
                let n = cell.n[i];
                if seen.insert(n) {
                    out.push(n);
                }
            }
        }
        out
    }

    /// Facets incident to the finite vertex `v`, each reported once (from the side with the
    /// smaller `(cell, index)`).
    pub fn incident_facets(&self, v: VertexId) -> Vec<Facet> {
        let mut out = Vec::new();
        for c in self.incident_cells(v) {
            let cell = self.cells[c as usize];
            for i in 0..4 {
                if cell.v[i] == v {
                    continue;
                }
                let f = Facet {
                    cell: c,
                    index: i as u8,
                };
                if f < self.mirror_facet(f) {
                    out.push(f);
                }
            }
        }
        out
    }

    /// Locates `p` by a visibility walk from `hint` (or the last created cell). Does not
    /// modify the triangulation. Errors on invalid coordinates.
    pub fn locate(&self, p: DVec3, hint: Option<CellId>) -> Result<Location, Error> {
        check_point(p)?;
        if !self.built {
            return Ok(Location::NoCells);
        }
        let mut rng = Rng(p.x.to_bits() ^ p.y.to_bits().rotate_left(21) ^ p.z.to_bits());
        Ok(match self.walk(p, self.start_cell(hint), &mut rng) {
            Walk::Vertex(v) => Location::Vertex(v),
            Walk::Inside(c) => Location::Cell(c),
            Walk::Outside(c) => Location::Outside(c),
        })
    }

    /// The conflict zone of `p` without modifying anything: the cells whose (perturbed)
    /// circumsphere contains `p` and the boundary facets of that cavity (seen from the cells
    /// inside it). Both are empty if `p` is an existing vertex or the triangulation is not
    /// 3D yet. The cells are exactly those an insertion of `p` would destroy.
    pub fn conflict_zone(
        &self,
        p: DVec3,
        hint: Option<CellId>,
    ) -> Result<(Vec<CellId>, Vec<Facet>), Error> {
        let c0 = match self.locate(p, hint)? {
            Location::Cell(c) | Location::Outside(c) => c,
            Location::Vertex(_) | Location::NoCells => return Ok((vec![], vec![])),
        };
        let mut inside = std::collections::HashSet::new();
        let mut outside = std::collections::HashSet::new();
        let mut cells = vec![c0];
        let mut facets = Vec::new();
        inside.insert(c0);
        let mut k = 0;
        while k < cells.len() {
            let c = cells[k];
            k += 1;
            for i in 0..4 {
                let n = self.cells[c as usize].n[i];
                if inside.contains(&n) {
                    continue;
                }
                if !outside.contains(&n) {
                    if self.in_conflict(n, p) {
                        inside.insert(n);
                        cells.push(n);
                        continue;
                    }
                    outside.insert(n);
                }
                facets.push(Facet {
                    cell: c,
                    index: i as u8,
                });
            }
        }
        Ok((cells, facets))
    }

    /// Nearest vertex to `p` (Euclidean, f64 distances; ties go to the first found), by
    /// locating `p` and walking greedily on Delaunay edges. `None` when empty or on bad input.
    pub fn nearest_vertex(&self, p: DVec3, hint: Option<CellId>) -> Option<VertexId> {
        if self.points.is_empty() || check_point(p).is_err() {
            return None;
        }
        if !self.built {
            return (0..self.points.len() as u32).min_by(|&a, &b| {
                let (da, db) = (
                    self.points[a as usize].distance_squared(p),
                    self.points[b as usize].distance_squared(p),
                );
                da.partial_cmp(&db).unwrap()
            });
        }
        let c = match self.locate(p, hint).ok()? {
            Location::Vertex(v) => return Some(v),
            Location::Cell(c) | Location::Outside(c) => c,
            Location::NoCells => return None,
        };
        let mut best = INFINITE_VERTEX;
        let mut bd = f64::INFINITY;
        for &v in &self.cells[c as usize].v {
            if v != INFINITE_VERTEX {
                let d = self.points[v as usize].distance_squared(p);
                if d < bd {
                    bd = d;
                    best = v;
                }
            }
        }
        loop {
            let mut improved = false;
            for c in self.incident_cells(best) {
                for &w in &self.cells[c as usize].v {
                    if w != INFINITE_VERTEX {
                        let d = self.points[w as usize].distance_squared(p);
                        if d < bd {
                            bd = d;
                            best = w;
                            improved = true;
                        }
                    }
                }
            }
            if !improved {
                return Some(best);
            }
        }
    }

    /// Bytes held by the triangulation's vectors (capacities), excluding the small hash map
    /// used before the triangulation is 3D.
    pub fn memory_bytes(&self) -> usize {
        use std::mem::size_of;
        self.points.capacity() * size_of::<DVec3>()
            + self.vertex_cell.capacity() * 4
            + self.cells.capacity() * size_of::<Cell>()
            + self.free.capacity() * 4
            + self.cavity.capacity() * 4
            + self.stack.capacity() * 4
            + self.boundary.capacity() * size_of::<Boundary>()
            + self.edges.keys.capacity() * 8
            + self.edges.vals.capacity() * 8
            + self.edges.gen_.capacity() * 4
    }

    // ------------------------------------------------------------------ internals

    fn start_cell(&self, hint: Option<CellId>) -> CellId {
        match hint {
            Some(c) if self.is_cell(c) => c,
            _ => {
                if self.is_cell(self.last_cell) {
                    self.last_cell
                } else {
                    self.infinite_cell
                }
            }
        }
    }

    #[inline]
    fn pt(&self, v: VertexId) -> DVec3 {
        // SAFETY-free: plain indexing; v is finite here.
        self.points[v as usize]
    }

    /// Whether `p` (not a vertex of `c`) is in conflict with live cell `c` (perturbed).
    fn in_conflict(&self, c: CellId, p: DVec3) -> bool {
        let cell = &self.cells[c as usize];
        let v = cell.v;
        if let Some(k) = v.iter().position(|&w| w == INFINITE_VERTEX) {
            let [a, b, d] = FACET[k].map(|i| self.pt(v[i]));
            match orient3d(a, b, d, p) {
                Sign::Positive => true,
                Sign::Negative => false,
                Sign::Zero => {
                    let m = cell.n[k];
                    let mc = &self.cells[m as usize];
                    let j =
                        mc.n.iter()
                            .position(|&x| x == c)
                            .expect("neighbor symmetry");
                    let mp = mc.v.map(|w| self.pt(w));
                    incircle_facet_perturbed(&mp, j, p)
                }
            }
        } else {
            let pts = &self.points;
            let (a, b, d, e) = (
                pts[v[0] as usize],
                pts[v[1] as usize],
                pts[v[2] as usize],
                pts[v[3] as usize],
            );
            match predicates::insphere(a, b, d, e, p) {
                Sign::Positive => true,
                Sign::Negative => false,
                Sign::Zero => insphere_perturbed(&[a, b, d, e], p),
            }
        }
    }

    /// Visibility walk from `start` (randomized facet order).
    fn walk(&self, p: DVec3, start: CellId, rng: &mut Rng) -> Walk {
        let mut c = start;
        let mut prev = NO_CELL;
        {
            let v = self.cells[c as usize].v;
            if let Some(k) = v.iter().position(|&w| w == INFINITE_VERTEX) {
                let [a, b, d] = FACET[k].map(|i| self.pt(v[i]));
                if orient3d(a, b, d, p) == Sign::Positive {
                    return Walk::Outside(c);
                }
                prev = c;
                c = self.cells[c as usize].n[k];
            }
        }
        'walk: loop {
            let cell = self.cells[c as usize];
            let r = (rng.next_u64() >> 62) as usize;
            for t in 0..4 {
                let i = (r + t) & 3;
                let n = cell.n[i];
                if n == prev {
                    continue;
                }
                let [a, b, d] = FACET[i];
                let pts = &self.points;
                if orient3d(
                    pts[cell.v[a] as usize],
                    pts[cell.v[b] as usize],
                    pts[cell.v[d] as usize],
                    p,
                ) == Sign::Negative
                {
                    prev = c;
                    c = n;
                    if self.cells[n as usize].v.contains(&INFINITE_VERTEX) {
                        return Walk::Outside(n);
                    }
                    continue 'walk;
                }
            }
            if let Some(&w) = cell.v.iter().find(|&&w| self.points[w as usize] == p) {
                return Walk::Vertex(w);
            }
            return Walk::Inside(c);
        }
    }

    fn alloc_cell(&mut self) -> CellId {
        if let Some(c) = self.free.pop() {
            c
        } else {
            self.cells.push(Cell {
                v: [DEAD; 4],
                n: [NO_CELL; 4],
                mark: 0,
            });
            (self.cells.len() - 1) as CellId
        }
    }

    fn next_stamp(&mut self) -> u32 {
        if self.stamp >= u32::MAX - 4 {
            self.cells.iter_mut().for_each(|c| c.mark = 0);
            self.stamp = 0;
        }
        self.stamp += 2;
        self.stamp
    }

    /// Builds the star of `w` over `self.boundary` (reusing the slots in `self.cavity` first,
    /// freeing the unused ones) and returns through `created` (if any) the new cells.
    fn build_star(&mut self, w: VertexId, mut created: Option<&mut Vec<CellId>>) {
        let nb = self.boundary.len();
        self.edges.reset(nb * 3 / 2 + 1);
        for k in 0..nb {
            let b = self.boundary[k];
            let slot = if k < self.cavity.len() {
                self.cavity[k]
            } else {
                self.alloc_cell()
            };
            let v = [b.v[0], b.v[1], b.v[2], w];
            let infinite = v.contains(&INFINITE_VERTEX);
            self.cells[slot as usize] = Cell {
                v,
                n: [NO_CELL, NO_CELL, NO_CELL, b.out],
                mark: 0,
            };
            self.cells[b.out as usize].n[b.j as usize] = slot;
            self.n_live += 1;
            if infinite {
                self.infinite_cell = slot;
            } else {
                self.n_finite += 1;
                debug_assert_eq!(
                    orient3d(self.pt(v[0]), self.pt(v[1]), self.pt(v[2]), self.pt(v[3])),
                    Sign::Positive,
                    "new cell {v:?} is not positive"
                );
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
                    self.cells[slot as usize].n[f] = oc;
                    self.cells[oc as usize].n[of as usize] = slot;
                }
            }
            for &x in &v {
                if x != INFINITE_VERTEX {
                    self.vertex_cell[x as usize] = slot;
                }
            }
            if let Some(cr) = created.as_deref_mut() {
                cr.push(slot);
            }
            self.last_cell = slot;
        }
        for k in nb..self.cavity.len() {
            let c = self.cavity[k];
            self.cells[c as usize].v = [DEAD; 4];
            self.free.push(c);
        }
    }

    /// Inserts `p` into a 3D triangulation, with vertex id `id` if pre-assigned.
    #[allow(clippy::needless_range_loop)]
    fn insert_3d(
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
        let stamp = self.next_stamp();
        let (inm, outm) = (stamp, stamp + 1);
        let mut cavity = std::mem::take(&mut self.cavity);
        let mut stack = std::mem::take(&mut self.stack);
        let mut boundary = std::mem::take(&mut self.boundary);
        cavity.clear();
        stack.clear();
        boundary.clear();
        self.cells[c0 as usize].mark = inm;
        cavity.push(c0);
        stack.push(c0);
        while let Some(c) = stack.pop() {
            for i in 0..4 {
                let n = self.cells[c as usize].n[i];
                let m = self.cells[n as usize].mark;
                if m == inm {
                    continue;
                }
                if m != outm {
                    if self.in_conflict(n, p) {
                        self.cells[n as usize].mark = inm;
                        cavity.push(n);
                        stack.push(n);
                        continue;
                    }
                    self.cells[n as usize].mark = outm;
                }
                boundary.push(self.boundary_facet(c, i, n));
            }
        }
        self.cavity = cavity;
        self.stack = stack;
        self.boundary = boundary;
        self.replace_cavity(p, id, changes)
    }

    /// The facet of cavity cell `c` opposite its vertex `i`, whose other side `n` is outside.
    fn boundary_facet(&self, c: CellId, i: usize, n: CellId) -> Boundary {
        let cv = self.cells[c as usize].v;
        let j = self.cells[n as usize]
            .n
            .iter()
            .position(|&x| x == c)
            .expect("neighbor symmetry") as u8;
        Boundary {
            v: FACET[i].map(|k| cv[k]),
            out: n,
            j,
        }
    }

    /// Replaces the cells of `self.cavity` (bounded by `self.boundary`) by the star of a new
    /// vertex at `p`.
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
                self.vertex_cell.push(NO_CELL);
                (self.points.len() - 1) as VertexId
            }
        };
        let mut created = None;
        if let Some(ch) = changes {
            for &c in &self.cavity {
                ch.removed.push(self.cells[c as usize].v);
                ch.removed_cells.push(c);
            }
            created = Some(&mut ch.created);
        }
        for k in 0..self.cavity.len() {
            let c = self.cavity[k];
            self.n_live -= 1;
            if !self.cells[c as usize].v.contains(&INFINITE_VERTEX) {
                self.n_finite -= 1;
            }
        }
        self.build_star(v, created);
        Insertion::New(v)
    }

    /// Finds, without changing the triangulation, the conflict zone of `p`: the cells whose
    /// circumsphere contains it (perturbed), from a point location started at `hint` with a
    /// walk randomized by `seed`. Several searches may run at once on a shared triangulation;
    /// [`Triangulation::insert_cavity`] applies one. The triangulation must be 3D.
    ///
    /// Errors: [`Error::InvalidPoint`] for non-finite or out-of-range coordinates.
    pub fn find_cavity(
        &self,
        p: DVec3,
        hint: Option<CellId>,
        seed: u64,
        out: &mut Cavity,
    ) -> Result<(), Error> {
        check_point(p)?;
        assert!(self.built, "find_cavity needs a 3D triangulation");
        out.p = p;
        out.cells.clear();
        out.boundary.clear();
        out.duplicate = None;
        out.seen.clear();
        let mut rng = Rng(seed);
        let c0 = match self.walk(p, self.start_cell(hint), &mut rng) {
            Walk::Vertex(v) => {
                out.duplicate = Some(v);
                return Ok(());
            }
            Walk::Inside(c) | Walk::Outside(c) => c,
        };
        out.seen.insert(c0, true);
        out.cells.push(c0);
        let mut k = 0;
        while k < out.cells.len() {
            let c = out.cells[k];
            k += 1;
            for i in 0..4 {
                let n = self.cells[c as usize].n[i];
                let inside = match out.seen.get(n) {
                    Some(b) => b,
                    None => {
                        let b = self.in_conflict(n, p);
                        out.seen.insert(n, b);
                        if b {
                            out.cells.push(n);
                        }
                        b
                    }
                };
                if !inside {
                    out.boundary.push(self.boundary_facet(c, i, n));
                }
            }
        }
        Ok(())
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
            ch.removed.clear();
            ch.removed_cells.clear();
            ch.created.clear();
        }
        if let Some(v) = cav.duplicate {
            return Insertion::Duplicate(v);
        }
        debug_assert!(cav.cells.iter().all(|&c| self.is_cell(c)));
        let mut cavity = std::mem::take(&mut self.cavity);
        let mut boundary = std::mem::take(&mut self.boundary);
        cavity.clear();
        cavity.extend_from_slice(&cav.cells);
        boundary.clear();
        boundary.extend_from_slice(&cav.boundary);
        self.cavity = cavity;
        self.boundary = boundary;
        self.replace_cavity(cav.p, None, changes)
    }

    /// Insertion while fewer than four affinely independent points are known.
    fn insert_held(&mut self, p: DVec3) -> Insertion {
        let key = (p + DVec3::ZERO).to_array().map(f64::to_bits); // -0.0 -> 0.0
        if let Some(&v) = self.held_map.get(&key) {
            return Insertion::Duplicate(v);
        }
        let v = self.points.len() as VertexId;
        self.points.push(p);
        self.vertex_cell.push(NO_CELL);
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
        let c0 = self.alloc_cell();
        self.cells[c0 as usize] = Cell {
            v: b,
            n: [NO_CELL; 4],
            mark: 0,
        };
        self.n_live = 1;
        self.n_finite = 1;
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
        self.build_star(INFINITE_VERTEX, None);
        for &x in &b {
            self.vertex_cell[x as usize] = c0;
        }
        self.last_cell = c0;
        let in_basis = |v: VertexId| b.contains(&v);
        let mut rest: Vec<u32> = (0..self.points.len() as u32)
            .filter(|&v| !in_basis(v))
            .collect();
        sort::hilbert_sort(&self.points, &mut rest);
        for v in rest {
            let start = self.start_cell(None);
            self.insert_3d(self.pt(v), Some(v), start, None);
        }
        self.held_map = HashMap::new();
        self.basis.clear();
    }

    /// Checks every invariant listed in the crate docs; returns the first violation.
    #[allow(clippy::needless_range_loop)]
    pub fn is_valid(&self) -> Result<(), ValidationError> {
        if !self.built {
            if self.n_live != 0 {
                return Err(ValidationError::Counts("cells before 3D".into()));
            }
            return Ok(());
        }
        let nv = self.points.len() as u32;
        let (mut live, mut finite) = (0, 0);
        for (ci, cell) in self.cells.iter().enumerate() {
            let c = ci as CellId;
            if cell.v[0] == DEAD {
                continue;
            }
            live += 1;
            let v = cell.v;
            let n_inf = v.iter().filter(|&&w| w == INFINITE_VERTEX).count();
            let distinct = (0..4).all(|i| (i + 1..4).all(|j| v[i] != v[j]));
            if n_inf > 1 || !distinct || v.iter().any(|&w| w != INFINITE_VERTEX && w >= nv) {
                return Err(ValidationError::BadVertices {
                    cell: c,
                    vertices: v,
                });
            }
            if n_inf == 0 {
                finite += 1;
                let q = v.map(|w| self.pt(w));
                if orient3d(q[0], q[1], q[2], q[3]) != Sign::Positive {
                    return Err(ValidationError::BadOrientation {
                        cell: c,
                        vertices: v,
                    });
                }
            }
            for i in 0..4 {
                let n = cell.n[i];
                if !self.is_cell(n) {
                    return Err(ValidationError::BadNeighbor {
                        cell: c,
                        index: i as u8,
                        neighbor: n,
                    });
                }
                let nc = &self.cells[n as usize];
                let back: Vec<usize> = (0..4).filter(|&j| nc.n[j] == c).collect();
                let asym = ValidationError::Asymmetric {
                    cell: c,
                    index: i as u8,
                    neighbor: n,
                };
                if back.len() != 1 {
                    return Err(asym);
                }
                let j = back[0];
                // Shared facet: the vertices other than i in c are those other than j in n.
                let mut fa: Vec<u32> = (0..4).filter(|&k| k != i).map(|k| v[k]).collect();
                let mut fb: Vec<u32> = (0..4).filter(|&k| k != j).map(|k| nc.v[k]).collect();
                fa.sort_unstable();
                fb.sort_unstable();
                if fa != fb || nc.v[j] == v[i] {
                    return Err(asym);
                }
                let w = nc.v[j];
                if n_inf == 1 && v[i] == INFINITE_VERTEX {
                    // Hull facet: the finite cell behind it must be on the inner side.
                    let [a, b, d] = FACET[i].map(|k| self.pt(v[k]));
                    if orient3d(a, b, d, self.pt(w)) != Sign::Negative {
                        return Err(ValidationError::BadHull {
                            cell: c,
                            index: i as u8,
                        });
                    }
                }
                if w != INFINITE_VERTEX && self.in_conflict(c, self.pt(w)) {
                    if n_inf == 1 && nc.v.contains(&INFINITE_VERTEX) {
                        return Err(ValidationError::BadHull {
                            cell: c,
                            index: i as u8,
                        });
                    }
                    return Err(ValidationError::NotDelaunay {
                        cell: c,
                        index: i as u8,
                    });
                }
            }
        }
        if live != self.n_live
            || finite != self.n_finite
            || live + self.free.len() != self.cells.len()
        {
            return Err(ValidationError::Counts(format!(
                "live {live} (counter {}), finite {finite} (counter {}), free {}, slots {}",
                self.n_live,
                self.n_finite,
                self.free.len(),
                self.cells.len()
            )));
        }
        for v in 0..nv {
            let c = self.vertex_cell[v as usize];
            if !self.is_cell(c) || !self.cells[c as usize].v.contains(&v) {
                return Err(ValidationError::VertexWithoutCell { vertex: v, cell: c });
            }
        }
        if !self.is_cell(self.infinite_cell) || !self.is_infinite(self.infinite_cell) {
            return Err(ValidationError::Counts(
                "infinite_cell is not an infinite cell".into(),
            ));
        }
        Ok(())
    }
}

// ---------------------------------------------------------------------- circumcenter

/// Circumcenter of a non-flat tetrahedron, relative to `p0`; falls back to double-double
/// arithmetic when the determinant is small relative to the edge lengths.
pub fn circumcenter(p0: DVec3, p1: DVec3, p2: DVec3, p3: DVec3) -> DVec3 {
    let a = p1 - p0;
    let b = p2 - p0;
    let c = p3 - p0;
    let bc = b.cross(c);
    let ca = c.cross(a);
    let ab = a.cross(b);
    let det = a.dot(bc);
    let scale = a.length() * b.length() * c.length();
    if det.abs() > 1e-4 * scale {
        let num = bc * a.length_squared() + ca * b.length_squared() + ab * c.length_squared();
        return p0 + num / (2.0 * det);
    }
    dd::circumcenter(p0, p1, p2, p3).unwrap_or_else(|| {
        let num = bc * a.length_squared() + ca * b.length_squared() + ab * c.length_squared();
        p0 + num / (2.0 * det)
    })
}

mod dd {
    use crate::dd_arith::{D, two_sum};
    use glam::DVec3;

    type V = [D; 3];
    fn cross(a: V, b: V) -> V {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    }
    fn dot(a: V, b: V) -> D {
        a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
    }
    fn diff(p: DVec3, q: DVec3) -> V {
        let d = |x: f64, y: f64| two_sum(x, -y);
        [d(p.x, q.x), d(p.y, q.y), d(p.z, q.z)]
    }

    pub fn circumcenter(p0: DVec3, p1: DVec3, p2: DVec3, p3: DVec3) -> Option<DVec3> {
        let (a, b, c) = (diff(p1, p0), diff(p2, p0), diff(p3, p0));
        let (bc, ca, ab) = (cross(b, c), cross(c, a), cross(a, b));
        let det = dot(a, bc);
        let den = det + det;
        if den.0 == 0.0 || !den.0.is_finite() {
            return None;
        }
        let (la, lb, lc) = (dot(a, a), dot(b, b), dot(c, c));
        let mut out = [0.0; 3];
        for k in 0..3 {
            let num = bc[k] * la + ca[k] * lb + ab[k] * lc;
            let q = num.0 / den.0;
            let r = num - D(q, 0.0) * den;
            out[k] = q + r.0 / den.0;
        }
        Some(p0 + DVec3::from_array(out))
    }
}
