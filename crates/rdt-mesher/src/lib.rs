//! Restricted Delaunay refinement: Boissonnat & Oudot, *Provably good sampling and meshing of
//! surfaces*, section 6.
//!
//! The mesher keeps Del(E) (crate `delaunay3`) and, as a subcomplex, Del_S(E): the facets whose
//! dual Voronoi edge meets S, found through an oracle (crate `oracle`). While a surface
//! Delaunay ball B(c, r) is bad ([`Criteria`]), its center c is inserted; only the Voronoi edges
//! that changed are re-tested.
//!
//! ```
//! use rdt_mesher::{mesh, Criteria, MeshOptions};
//! use oracle::{BoundingSphere, Surface};
//! use glam::DVec3;
//!
//! struct Sphere;
//! impl Surface for Sphere {
//!     fn bounding_sphere(&self) -> BoundingSphere {
//!         BoundingSphere { center: DVec3::ZERO, radius: 2.0 }
//!     }
//!     fn value(&self, p: DVec3) -> f64 { p.length_squared() - 1.0 }
//! }
//!
//! let opts = MeshOptions { criteria: Criteria::uniform(0.3), ..Default::default() };
//! let out = mesh(&Sphere, &opts).unwrap();
//! assert!(out.stats.criteria_met);
//! assert_eq!(out.stats.nonmanifold_edges, 0);
//! // Euler characteristic of a sphere: V - E + F = 2 with E = 3F/2.
//! let (v, f) = (out.mesh.vertices.len() as i64, out.mesh.triangles.len() as i64);
//! assert_eq!(v - f / 2, 2);
//! ```

pub mod criteria;
pub mod init;
pub mod refine;
mod restricted;
mod scaffold;
pub mod sizing;
pub mod topology;
mod tuner;

pub use criteria::{Criteria, Sizing};
pub use refine::{
    Initialization, MeshError, MeshOptions, MeshResult, OracleKind, Progress, Stats, SurfaceBall,
    mesh, mesh_with_progress,
};
