//! Surface oracles for restricted Delaunay meshing (Boissonnat & Oudot, sections 6.4.2 and 6.6).
//!
//! A surface S is the zero set of a value function (negative inside the solid, positive outside).
//! The mesher reaches S only through the [`Surface`] trait (two required methods, the rest
//! provided; see its documentation for the four groups of methods):
//! - the **bipolar oracle** ([`Surface::crossing`]): a segment whose end values have opposite
//!   signs crosses S an odd number of times; return one crossing;
//! - the **intersection oracle** ([`Surface::crossings`]): all points of a segment on S;
//! - P1 ([`Surface::seed_points`]): points on every component; P2
//!   ([`Surface::dm_inf_hint`]): a bound on d_M^inf;
//! - a [`BoundingSphere`] outside which the value is positive.
//!
//! # Backends
//! | module | type | surface | paper |
//! |---|---|---|---|
//! | [`implicit`] (with [`expr`], [`catalog`]) | [`ImplicitSurface`] | zero set of a function or an expression | 6.6.1 |
//! | [`image`] | [`ImageSurface`] | iso-surface of a voxel image (NIfTI, TIFF, PNG, raw) | 6.6.2 |
//! | [`pointset`] | [`PointSetSurface`] | IMLS surface of a point set | 6.6.3 |
//! | [`polyhedron`] | [`PolyhedronSurface`], [`SmoothPolyhedron`] | a triangle mesh, exact or smoothed by IMLS | 6.6.3 (remeshing) |
//!
//! Each backend module is a facade: it re-exports its public items and keeps its files
//! private. The backends do not use each other: what two of them share lives in private
//! modules of this crate (`imls`: the IMLS surface, used by the point-set backend and the
//! smoothed polyhedron) or in [`roots`] (every root finder, in one vocabulary).
//!
//! ```
//! use glam::DVec3;
//! use oracle::{BoundingSphere, ImplicitSurface, Surface};
//! let ball = BoundingSphere { center: DVec3::ZERO, radius: 2.0 };
//! let s = ImplicitSurface::from_expr("x^2 + y^2 + z^2 - 1", ball).unwrap();
//! assert!(s.value(DVec3::ZERO) < 0.0);
//! assert!(!s.seed_points(1).is_empty());
//! ```

#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod catalog;
mod error;
pub mod expr;
mod grid;
pub mod image;
mod imls;
pub mod implicit;
pub mod pointset;
pub mod polyhedron;
pub mod roots;
mod sphere;
mod surface;

pub use error::OracleError;
pub use image::ImageSurface;
pub use implicit::ImplicitSurface;
pub use pointset::PointSetSurface;
pub use polyhedron::{PolyhedronSurface, SmoothPolyhedron};
pub use sphere::BoundingSphere;
pub use surface::Surface;
