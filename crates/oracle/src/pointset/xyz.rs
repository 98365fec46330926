//! `.xyz` point files and the point-cloud type (ours): defined once in `meshio`
//! ([`meshio::xyz`], [`meshio::PointCloud`]) and re-exported here under their old paths.

pub use meshio::PointCloud;
pub use meshio::xyz::{XyzError, read_xyz, read_xyz_from};
