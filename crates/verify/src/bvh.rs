//! Bounding-volume hierarchies (ours), from the shared kernel: [`geom::bvh`]. `verify` builds
//! its exact nearest-triangle and self-intersection searches on [`geom::bvh::TriangleBvh`]
//! (see [`crate::intersect::triangle_bvh`]); the box BVH [`Bvh`] indexes points (the Voronoi
//! poles of [`crate::medial`]).

pub use geom::bvh::{Aabb, Bvh, LEAF_SIZE, TriangleBvh};
