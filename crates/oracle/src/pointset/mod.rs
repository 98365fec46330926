//! Point-set surface oracle (section 6.6.3): the IMLS surface of a point set with or without
//! normals, read from `.xyz` files or given in memory.
//!
//! The surface itself (kernel, normals, far field, d_M estimate) lives in the shared `imls`
//! module, which the smoothed polyhedron uses too; this module is the backend's entry point:
//! [`PointSetSurface`], its parameters and errors, and the `.xyz` reader.

// Moves to `meshio` on helper K1's branch; allowed until it merges.
#[allow(missing_docs)]
mod xyz;

pub use crate::imls::linalg::plane_residual;
pub use crate::imls::{
    CROSSING_PRECISION, MIN_POINTS, PointSetError, PointSetParams, PointSetStats, PointSetSurface,
    knn_lists, winding_disks,
};
pub use xyz::{PointCloud, XyzError, read_xyz, read_xyz_from};

impl PointSetSurface {
    /// [`PointSetSurface::new`] from a [`PointCloud`] (e.g. from [`read_xyz`]).
    pub fn from_cloud(cloud: &PointCloud, params: &PointSetParams) -> Result<Self, PointSetError> {
        Self::new(&cloud.points, cloud.normals.as_deref(), params)
    }
}
