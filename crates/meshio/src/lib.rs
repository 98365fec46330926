//! Triangle meshes and their file formats (PLY ASCII/binary, OFF, OBJ, STL ASCII/binary).

use glam::DVec3;

/// An indexed triangle mesh. Invariant (when produced by the mesher): every index is
/// `< vertices.len()`; triangles are counter-clockwise seen from outside.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriMesh {
    pub vertices: Vec<DVec3>,
    pub triangles: Vec<[u32; 3]>,
}
