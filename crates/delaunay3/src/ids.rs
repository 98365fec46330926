//! Handles (ours): the newtype ids of vertices, cells and facets, and their validity rules.
//!
//! Both ids are `u32` indices (`#[repr(transparent)]`, so a `[VertexId; 4]` has the layout of
//! a `[u32; 4]` and the newtypes cost nothing at run time).
//!
//! # Invalidation rules
//! - A [`VertexId`] is permanent: vertices are never removed, finite ids are dense
//!   (`0..num_vertices()`) and assigned in order of first insertion of each distinct point
//!   ([`crate::Triangulation::insert_bulk`] inserts in its spatially sorted order and returns
//!   the id of each input point). An insertion never renumbers existing vertices, so arrays
//!   indexed by [`VertexId::index`] stay valid; they only need to grow.
//! - A [`CellId`] names a *slot*. An insertion destroys the cells of its conflict zone and
//!   creates new ones, reusing the destroyed slots first (in the order of
//!   [`crate::Changes::removed_cells`]), then a free list, then fresh slots. So after an
//!   insertion a destroyed cell's id may name a *different* live cell, or no cell at all:
//!   callers keeping per-cell data update it from [`crate::Changes`]. Ids of cells not in the
//!   conflict zone stay valid with the same vertices (their neighbors may change).
//!   [`crate::Triangulation::is_cell`] tells whether a slot is live.
//! - A [`Facet`] is valid as long as its cell is.

/// A vertex: [`VertexId::INFINITE`] or a finite vertex, an index into
/// [`crate::Triangulation::points`] (see the module docs for its lifetime).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[repr(transparent)]
pub struct VertexId(pub(crate) u32);

/// A cell (tetrahedron) slot (see the module docs: slots are reused).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[repr(transparent)]
pub struct CellId(pub(crate) u32);

/// The index and raw-`u32` conversions that both ids share.
macro_rules! u32_id {
    ($id:ident, $index_doc:literal) => {
        impl $id {
            #[doc = $index_doc]
            #[inline]
            pub const fn index(self) -> usize {
                self.0 as usize
            }

            /// The raw `u32` (for compact storage or output formats).
            #[inline]
            pub const fn to_u32(self) -> u32 {
                self.0
            }

            #[doc = concat!("The id of raw value `x` (the inverse of [`", stringify!($id), "::to_u32`]).")]
            #[inline]
            pub const fn from_u32(x: u32) -> $id {
                $id(x)
            }
        }
    };
}

u32_id!(
    VertexId,
    "The index of this vertex in per-vertex arrays (meaningless for [`VertexId::INFINITE`] \
     and [`VertexId::NONE`])."
);
u32_id!(CellId, "The slot index of this cell, for per-cell arrays.");

impl VertexId {
    /// The vertex at infinity; every hull facet forms an infinite cell with it. It is the
    /// largest id (sorted vertex tuples put it last).
    pub const INFINITE: VertexId = VertexId(u32::MAX);
    /// Never a vertex of the triangulation (neither finite nor infinite): a documented
    /// placeholder for callers, e.g. "the vertex about to be inserted" in
    /// [`crate::Cavity::new_cells`], or a free slot in a table of vertex tuples. Sorts just
    /// below [`VertexId::INFINITE`], above every finite id.
    pub const NONE: VertexId = VertexId(u32::MAX - 1);

    /// The id of the finite vertex with index `i` (no check that it exists).
    ///
    /// Panics if `i` is not below [`VertexId::NONE`]'s index (at most `2^32 - 2` vertices).
    #[inline]
    pub const fn from_index(i: usize) -> VertexId {
        assert!(i < (u32::MAX - 1) as usize, "vertex index out of range");
        VertexId(i as u32)
    }

    /// Whether this is the infinite vertex.
    #[inline]
    pub const fn is_infinite(self) -> bool {
        self.0 == u32::MAX
    }
}

impl CellId {
    /// "No cell" (e.g. the neighbor of a cell under construction).
    pub const NONE: CellId = CellId(u32::MAX);

    /// The cell in slot `i` (no check that it is live).
    ///
    /// Panics if `i` is not below [`CellId::NONE`]'s index.
    #[inline]
    pub const fn from_index(i: usize) -> CellId {
        assert!(i < u32::MAX as usize, "cell index out of range");
        CellId(i as u32)
    }
}

impl std::fmt::Display for VertexId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            VertexId::INFINITE => f.write_str("inf"),
            VertexId::NONE => f.write_str("none"),
            v => write!(f, "{}", v.0),
        }
    }
}

impl std::fmt::Display for CellId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            CellId::NONE => f.write_str("none"),
            c => write!(f, "{}", c.0),
        }
    }
}

/// Facet of `cell` opposite to its local vertex `index` (0..4).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Facet {
    /// The cell seen from.
    pub cell: CellId,
    /// Local index (0..4) of the cell's vertex opposite the facet.
    pub index: u8,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_are_u32_sized_and_order_like_u32() {
        assert_eq!(std::mem::size_of::<[VertexId; 4]>(), 16);
        assert_eq!(std::mem::size_of::<CellId>(), 4);
        let v = VertexId::from_index(7);
        assert_eq!(v.index(), 7);
        assert!(v < VertexId::NONE && VertexId::NONE < VertexId::INFINITE);
        assert!(VertexId::INFINITE.is_infinite() && !v.is_infinite());
        assert_eq!(CellId::from_index(3).index(), 3);
        assert_eq!(VertexId::from_u32(5).to_u32(), 5);
        assert_eq!(
            format!("{} {}", VertexId::INFINITE, CellId::from_index(2)),
            "inf 2"
        );
    }
}
