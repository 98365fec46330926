//! The restricted Delaunay triangulation Del_S(E) of section 6.1 (or, with the bipolar
//! oracle, Del_S^b(E) of section 6.4.2), kept up to date under insertions.
//!
//! - `complex`: the facets of Del(E) whose dual Voronoi edge meets S, with their surface
//!   Delaunay balls.
//! - `test`: the facet test: clip the dual (`crate::voronoi`), ask the oracle, register.
//! - `lazy`: a facet known bad without its ball gets it only when the queue pops it.
//! - `update`: after an insertion, what changed and only that.
//! - `vertex_sizes`: the size test decided from sigma at the vertices when a Lipschitz
//!   bound suffices.
//! - `validate`: the incremental complex against a recomputation (for tests).
//!
//! # Invariants (kept by `update`)
//! - `Mesher::restricted` holds exactly the facets of Del(E) whose (clipped) dual Voronoi
//!   edge meets S according to the oracle, keyed by their sorted vertex triple. After an
//!   insertion, every facet of a destroyed cell is removed, and every facet of a created cell
//!   (new facets and the boundary facets of the cavity, whose duals changed) is re-tested:
//!   nothing else changed.
//! - Every bad registered facet has a fresh entry in `Mesher::queue`.

mod complex;
mod lazy;
mod resize;
mod test;
mod update;
#[cfg(test)]
mod validate;
mod vertex_sizes;

pub(crate) use complex::{RFacet, Restricted, sorted3};
pub(crate) use vertex_sizes::VertexSizes;
