//! Whether a closed, consistently oriented mesh bounds a solid the right way round (ours: a
//! check of the output's orientation; the surface of sections 2 and 4 bounds a solid, and a
//! mesh of it must say which side is inside): the generalized winding number of the whole
//! mesh is 1 just inside each component (behind its facets) and 0 just in front of them. An
//! inside-out mesh (0 behind, -1 in front), or two nested components facing the same way (2
//! inside the inner one), fail; a hollow shell whose cavity faces inward passes.
//!
//! Invariant: only meaningful on a closed, consistently oriented manifold without
//! self-intersections (the caller checks); the winding number is then an integer off the mesh,
//! so a probe a thousandth of a facet's size off its centroid reads it to within far less than
//! the 0.25 allowed.

use geom::bvh::TriangleBvh;
use glam::DVec3;
use meshio::TriMesh;

use crate::topology::Topology;

/// A component whose facets do not bound the solid the right way round.
#[derive(Clone, Debug, PartialEq)]
pub struct WrongSide {
    /// The component's first triangle (see [`crate::topology::Component::first_triangle`]).
    pub first_triangle: usize,
    /// Where it was probed (the triangle's centroid).
    pub at: DVec3,
    /// The winding number just behind the triangle (1 for a right mesh).
    pub behind: f64,
    /// The winding number just in front of it (0 for a right mesh).
    pub in_front: f64,
}

/// The components of `t` that bound the solid the wrong way round, probed at their first
/// triangle; and how many components were probed (a component whose first triangle has no
/// area is not).
pub fn wrong_sides(mesh: &TriMesh, t: &Topology, bvh: &TriangleBvh) -> (usize, Vec<WrongSide>) {
    let mut probed = 0;
    let mut wrong = Vec::new();
    for c in &t.components {
        let [a, b, cc] = mesh.triangles[c.first_triangle].map(|i| mesh.vertices[i as usize]);
        let n = (b - a).cross(cc - a);
        let len = n.length();
        if !(len > 0.0 && len.is_finite()) {
            continue;
        }
        probed += 1;
        let g = (a + b + cc) / 3.0;
        let delta = 1e-3 * len.sqrt();
        let u = n / len;
        let behind = bvh.winding_number(g - delta * u);
        let in_front = bvh.winding_number(g + delta * u);
        if (behind - 1.0).abs() > 0.25 || in_front.abs() > 0.25 {
            wrong.push(WrongSide {
                first_triangle: c.first_triangle,
                at: g,
                behind,
                in_front,
            });
        }
    }
    (probed, wrong)
}
