//! The geometry kernel (ours) that every crate of the workspace uses: exact predicates with
//! one [`Sign`], closest points on triangles, one triangle BVH, a seedable RNG, farthest-point
//! selection and the surface Delaunay ball of section 2 (definition 2.2).
//!
//! - [`predicates`]: Shewchuk's exact orient2d / orient3d / insphere through `robust`, and
//!   the exact intersection tests built on them (closed segment-triangle and
//!   triangle-triangle tests for `verify`, the symbolically perturbed segment-triangle
//!   crossing for the polyhedron oracle).
//! - [`closest`]: closest point on a triangle (with the feature it lies on) and on a segment.
//! - [`bvh`]: [`bvh::TriangleBvh`] (nearest triangle, segment crossings, generalized winding
//!   number, box overlaps) and the box [`bvh::Bvh`] (overlaps), both built by one median split.
//! - [`rng`]: [`SplitMix64`], the generator behind every seeded choice in the workspace.
//! - [`farthest`]: greedy farthest-point selection with lowest-index ties.
//! - [`kdtree`]: [`kdtree::PointTree`], exact nearest-point queries over a fixed point set.
//! - [`morton`]: Z-order keys, to run many spatial queries in a cache-friendly order.
//! - [`SurfaceBall`]: a surface Delaunay ball B(c, r) of a restricted facet.
//!
//! Layering: `geom` depends on `glam` and `robust` only (and `serde` behind the `serde`
//! feature). Point clouds with normals ([`meshio::PointCloud`](https://docs.rs/meshio)) live
//! in `meshio` next to `TriMesh`, as the data that file readers return.
//!
//! ```
//! use geom::{Sign, predicates::orient3d};
//! use glam::DVec3;
//! // `d` below the counter-clockwise triangle (seen from +z): positive.
//! let s = orient3d(DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::new(0.2, 0.2, -1.0));
//! assert_eq!(s, Sign::Positive);
//! ```

#![forbid(unsafe_code)]
#![warn(missing_docs)]

mod ball;
pub mod bvh;
pub mod closest;
pub mod farthest;
pub mod kdtree;
pub mod morton;
pub mod predicates;
pub mod rng;

pub use ball::SurfaceBall;
pub use predicates::Sign;
pub use rng::SplitMix64;

/// Shared fixtures of the unit tests.
#[cfg(test)]
pub(crate) mod test_util {
    use glam::DVec3;
    use proptest::prelude::*;

    /// A point with coordinates uniform in `[-r, r)`.
    pub fn pt_within(r: f64) -> impl Strategy<Value = DVec3> {
        prop::array::uniform3(-r..r).prop_map(DVec3::from_array)
    }

    /// The right triangle `(0, x, y)` in the plane z = 0, counter-clockwise seen from +z.
    pub const RIGHT_TRIANGLE: (DVec3, DVec3, DVec3) = (DVec3::ZERO, DVec3::X, DVec3::Y);
}
