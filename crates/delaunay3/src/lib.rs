//! Exact, incremental 3D Delaunay triangulation.
//!
//! Points (`f64`) are inserted one at a time (Bowyer–Watson: the cavity of cells whose
//! circumsphere contains the point is replaced by the star of the new vertex) or in bulk
//! ([`Triangulation::insert_bulk`], which spatially sorts first: BRIO rounds in Hilbert-curve
//! order).
//! All decisions use exact predicates (`robust` orient3d / insphere, wrapped in
//! [`predicates`]); ties are broken by the Devillers–Teillaud symbolic perturbation with the
//! lexicographic `(x, y, z)` order of the points, so the triangulation of a point set is
//! unique and well defined for *any* input (cospherical, coplanar, grid points), independent
//! of the insertion order.
//!
//! # Structure
//! - An infinite vertex [`VertexId::INFINITE`] closes the space: each convex-hull facet forms an
//!   *infinite cell* with it. Every cell has exactly four neighbors.
//! - Cells are stored compactly as `[VertexId; 4]` vertices plus `[CellId; 4]` neighbors
//!   (both `u32` newtypes); neighbor `i` is across the facet opposite local vertex `i`. Freed
//!   slots are reused (free list): see [`ids`] for when a [`CellId`] stops being valid.
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
//! # Invariants (checked by [`Triangulation::validate`])
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
//! Points are spatially sorted once (BRIO rounds sorted by Hilbert keys on a 2^21 grid,
//! computed eight points at a time; the median splits on contiguous (point, index) records
//! order the few points held before the triangulation is 3D). Point location is a randomized
//! visibility walk from the last created cell (or a hint); the cavity search uses a per-cell
//! visit stamp, prefetches the neighbors of the cells it finds in conflict, and reuses its
//! buffers, so an insertion does not allocate. In-sphere tests go through a semi-static filter inline in the search (an
//! error bound from the largest coordinate differences, proved in `semi_static`), then
//! Shewchuk's static filter, an exact `i128` stage for grid-like inputs, a double-double
//! stage (decides nearly-cospherical inputs such as rounded sphere samples), then `robust`'s
//! exact arithmetic. The new cells of a star are linked through a table indexed by local ids
//! of the cavity's boundary vertices (`star`), not by hashing edges. About 250-290 bytes per
//! point. `crates/delaunay3/benches/cgal_baseline.sh` compares with CGAL on the same points;
//! `cargo bench -p delaunay3 --bench insert` is the criterion bench.
//!
//! # Modules (in reading order)
//! [`ids`] (handles and their lifetimes), `tds` (cell storage, topology only), `triangulation`
//! (the struct and read-only queries), `locate` (the walk), `cavity` (the conflict zone: one
//! search for every insertion path), `star` (the new cells' adjacency), `insert` and `bulk`
//! (insertion), [`construct`] (circumcenters), [`predicates`] (exact, perturbed; its first
//! in-sphere filter in `semi_static`), [`poles`] (Voronoi poles), `validate`.
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
//! assert!(matches!(r, Insertion::New(v) if v.index() == 4));
//! assert_eq!(changes.removed.len(), 1); // only the tetrahedron contains it in its sphere
//! assert_eq!(changes.created.len(), 4);
//! assert_eq!(t.num_finite_cells(), 4);
//! // insert_bulk returns the vertex of each input point (ids follow its sorted order).
//! assert_eq!(t.insert(DVec3::new(1.0, 0.0, 0.0)).unwrap(), Insertion::Duplicate(ids[1]));
//! assert!(t.validate().is_ok());
//! assert!(t.insert(DVec3::new(f64::NAN, 0.0, 0.0)).is_err());
//! ```

// Two `unsafe` blocks, each with its proof comment: calling a `target_feature` function
// after detecting the feature (`predicates`), and the cache prefetch hint of the conflict
// search (`cavity`); everything else is safe.
#![deny(unsafe_code)]
#![warn(missing_docs)]

mod bulk;
mod cavity;
pub mod construct;
mod dd_arith;
mod hash;
mod hilbert;
pub mod ids;
mod insert;
mod locate;
pub mod poles;
pub mod predicates;
mod semi_static;
mod sort;
mod star;
mod tds;
mod triangulation;
mod validate;

pub use cavity::Cavity;
pub use construct::circumcenter;
pub use glam::DVec3;
pub use ids::{CellId, Facet, VertexId};
pub use insert::{Changes, Insertion};
pub use locate::Location;
pub use poles::{Pole, VertexPoles};
pub use triangulation::{Dual, Error, Triangulation, validate_point};
pub use validate::ValidationError;
