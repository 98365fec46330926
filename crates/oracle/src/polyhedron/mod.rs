//! Polyhedron oracle (section 6.6.4): a triangle mesh, possibly a soup with small holes
//! (`exact`), and its smoothed IMLS version for remeshing (`smooth`).
//!
//! - Intersection oracle ([`Surface::crossings`]): every crossing of a segment with the
//!   triangles, through a BVH, decided by exact predicates with a symbolic perturbation of the
//!   segment (a crossing through a shared edge or vertex is counted once; a segment lying in a
//!   triangle's plane does not cross it). Crossing points are computed in f64.
//! - Inside/outside ([`Surface::value`]): for a watertight mesh (closed, manifold, consistently
//!   oriented after welding), the signed distance near the surface, signed by angle-weighted
//!   pseudonormals (Bærentzen & Aanæs 2005) through a BVH nearest query, and farther than
//!   [`PolyhedronSurface::suggested_size`] a constant magnitude signed by the parity of exact
//!   crossings of a ray (the same predicates as the intersection oracle). Otherwise `0.5 − w(p)` where
//!   `w` is the generalized winding number (Jacobson et al. 2013), evaluated hierarchically
//!   (far BVH nodes by a second-order dipole expansion, Barill et al. 2018): negative inside,
//!   positive outside, robust to soups and small holes.
//!   Triangles are expected counter-clockwise seen from outside (then `w ≈ 1` inside); a mesh
//!   with the opposite global orientation is detected (negative signed volume) and flipped.
//! - Bipolar oracle ([`Surface::crossing`]): the exact crossing where the sign changes, with
//!   bisection on the winding number as a fallback (e.g. through a hole).
//! - P1 ([`Surface::seed_points`]): triangle centroids, at least one per connected component.
//!
//! - [`SmoothPolyhedron`]: the oracle used for remeshing (`cargo xtask mesh model.ply`): an
//!   IMLS approximation of the triangles, so that the manifold patch terminates at creases
//!   (see its module documentation); projection stays exact onto the input.
//!
//! Invariants kept by [`PolyhedronSurface`]: every stored triangle is non-degenerate (exactly)
//! and has finite vertices within the exact range of the predicates.

#[cfg(doc)]
use crate::Surface;

mod clean;
mod exact;
mod smooth;
mod solid;

pub use exact::{
    PolyhedronError, PolyhedronStats, PolyhedronSurface, distance_to_sharp_edges,
    sharp_edge_deviation,
};
pub use smooth::{DEFAULT_BANDWIDTH, DEFAULT_SAMPLES, SmoothPolyhedron};
