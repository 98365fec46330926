//! Exact, incremental 3D Delaunay triangulation.
//!
//! API CONTRACT STUB: the signatures below are the contract the mesher is written against;
//! bodies are filled in by the `delaunay3` work (issue 2).
#![allow(unused_variables, dead_code)]

pub use glam::DVec3;

/// Index of a vertex: dense, in order of first insertion of each distinct point.
pub type VertexId = u32;
/// Index of a cell (tetrahedron) slot. Slots are reused through a free list.
pub type CellId = u32;
/// The vertex at infinity; every hull facet forms an infinite cell with it.
pub const INFINITE_VERTEX: VertexId = u32::MAX;

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

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Insertion {
    /// A new vertex was created.
    New(VertexId),
    /// The point equals an existing vertex; nothing changed.
    Duplicate(VertexId),
}

/// What an insertion changed, for callers that maintain data over cells/facets.
#[derive(Clone, Debug, Default)]
pub struct Changes {
    /// Vertex tuples of the cells destroyed (the conflict zone), as they were.
    pub removed: Vec<[VertexId; 4]>,
    /// Cells created by the insertion. Every facet of a created cell is either new or a
    /// boundary facet of the cavity (whose dual changed).
    pub created: Vec<CellId>,
}

#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum Error {
    #[error("point {0:?} has a non-finite or out-of-range coordinate")]
    InvalidPoint([f64; 3]),
}

#[derive(Default, Clone)]
pub struct Triangulation {}

impl Triangulation {
    pub fn new() -> Self {
        unimplemented!()
    }
    pub fn insert(&mut self, p: DVec3) -> Result<Insertion, Error> {
        unimplemented!()
    }
    pub fn insert_with(
        &mut self,
        p: DVec3,
        hint: Option<CellId>,
        changes: Option<&mut Changes>,
    ) -> Result<Insertion, Error> {
        unimplemented!()
    }
    /// 3 once four affinely independent points were inserted, else less.
    pub fn dimension(&self) -> i32 {
        unimplemented!()
    }
    pub fn num_vertices(&self) -> usize {
        unimplemented!()
    }
    pub fn point(&self, v: VertexId) -> DVec3 {
        unimplemented!()
    }
    pub fn cell_vertices(&self, c: CellId) -> [VertexId; 4] {
        unimplemented!()
    }
    pub fn neighbor(&self, c: CellId, i: usize) -> CellId {
        unimplemented!()
    }
    pub fn is_infinite(&self, c: CellId) -> bool {
        unimplemented!()
    }
    pub fn mirror_facet(&self, f: Facet) -> Facet {
        unimplemented!()
    }
    pub fn facet_vertices(&self, f: Facet) -> [VertexId; 3] {
        unimplemented!()
    }
    pub fn circumcenter(&self, c: CellId) -> DVec3 {
        unimplemented!()
    }
    pub fn dual(&self, f: Facet) -> Option<Dual> {
        unimplemented!()
    }
    pub fn finite_cells(&self) -> impl Iterator<Item = CellId> + '_ {
        std::iter::empty()
    }
    pub fn nearest_vertex(&self, p: DVec3, hint: Option<CellId>) -> Option<VertexId> {
        unimplemented!()
    }
}
