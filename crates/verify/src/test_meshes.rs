//! Small meshes shared by the unit tests of this crate (test-only).

use glam::DVec3;
use meshio::TriMesh;

/// The octahedron of vertices +-X, +-Y, +-Z, its faces facing out.
pub(crate) fn octahedron() -> TriMesh {
    TriMesh {
        vertices: vec![
            DVec3::X,
            -DVec3::X,
            DVec3::Y,
            -DVec3::Y,
            DVec3::Z,
            -DVec3::Z,
        ],
        triangles: vec![
            [0, 2, 4],
            [2, 1, 4],
            [1, 3, 4],
            [3, 0, 4],
            [2, 0, 5],
            [1, 2, 5],
            [3, 1, 5],
            [0, 3, 5],
        ],
    }
}
