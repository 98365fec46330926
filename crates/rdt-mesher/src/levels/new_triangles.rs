//! The new triangles of a mesh, for intersection tests against the whole mesh (ours, the
//! images' repair and bridges: a closing or a tube must cross no triangle).

use meshio::TriMesh;

/// The triangles of a mesh from `first_new` on, for intersection tests against the whole
/// mesh: the degenerate ones (collinear corners) and a tree of the boxes of the others (the
/// new triangles are few: the tree queried with every triangle's box gives the same pairs as
/// a tree of the whole mesh queried with the new boxes).
pub(crate) struct NewTriangles {
    /// Degenerate triangles.
    pub degenerate: Vec<usize>,
    /// The other triangles: box `k` of `bvh` is triangle `queried[k]`'s.
    pub queried: Vec<u32>,
    pub bvh: geom::bvh::Bvh,
}

impl NewTriangles {
    pub(crate) fn of(mesh: &TriMesh, first_new: usize) -> Self {
        use geom::bvh::{Aabb, Bvh};
        let (mut degenerate, mut queried) = (Vec::new(), Vec::new());
        for i in first_new..mesh.triangles.len() {
            let c = verify::intersect::corners(mesh, i);
            if geom::predicates::collinear(c[0], c[1], c[2]) {
                degenerate.push(i);
            } else {
                queried.push(i as u32);
            }
        }
        let boxes = queried
            .iter()
            .map(|&i| Aabb::from_points(&verify::intersect::corners(mesh, i as usize)))
            .collect();
        NewTriangles {
            degenerate,
            queried,
            bvh: Bvh::new(boxes),
        }
    }
}
