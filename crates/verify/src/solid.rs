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
//! the 0.25 allowed. Each component is probed at its largest triangle.

use geom::bvh::TriangleBvh;
use glam::DVec3;
use meshio::TriMesh;

use crate::topology::Topology;

/// A component whose facets do not bound the solid the right way round.
#[derive(Clone, Debug, PartialEq)]
pub struct WrongSide {
    /// The component's first triangle (see [`crate::topology::Component::first_triangle`]).
    pub first_triangle: usize,
    /// The triangle probed: the component's largest (a tiny triangle, such as one of a
    /// cluster of nearly coincident vertices, is no place to read a winding number).
    pub probed_triangle: usize,
    /// Where it was probed (that triangle's centroid).
    pub at: DVec3,
    /// The winding number just behind the triangle (1 for a right mesh).
    pub behind: f64,
    /// The winding number just in front of it (0 for a right mesh).
    pub in_front: f64,
}

/// Twice the area vector of triangle `t`.
fn normal(mesh: &TriMesh, t: usize) -> DVec3 {
    let [a, b, c] = mesh.triangles[t].map(|i| mesh.vertices[i as usize]);
    (b - a).cross(c - a)
}

/// The largest triangle of each component of `t` (by its first triangle's vertex piece).
fn largest_triangles(mesh: &TriMesh, t: &Topology) -> Vec<usize> {
    let mut piece = vec![usize::MAX; mesh.vertices.len()];
    for (i, vs) in crate::topology::vertex_components(mesh).iter().enumerate() {
        for &v in vs {
            piece[v] = i;
        }
    }
    let of = |tri: usize| piece[mesh.triangles[tri][0] as usize];
    let mut best: std::collections::HashMap<usize, (f64, usize)> = Default::default();
    for tri in 0..mesh.triangles.len() {
        let a = normal(mesh, tri).length();
        let e = best.entry(of(tri)).or_insert((-1.0, tri));
        if a > e.0 {
            *e = (a, tri);
        }
    }
    t.components
        .iter()
        .map(|c| {
            best.get(&of(c.first_triangle))
                .map_or(c.first_triangle, |b| b.1)
        })
        .collect()
}

/// The components of `t` that bound the solid the wrong way round, probed at their largest
/// triangle; and how many components were probed (a component without a triangle of
/// positive area is not).
pub fn wrong_sides(mesh: &TriMesh, t: &Topology, bvh: &TriangleBvh) -> (usize, Vec<WrongSide>) {
    let mut probed = 0;
    let mut wrong = Vec::new();
    for (c, tri) in t.components.iter().zip(largest_triangles(mesh, t)) {
        let [a, b, cc] = mesh.triangles[tri].map(|i| mesh.vertices[i as usize]);
        let n = normal(mesh, tri);
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
                probed_triangle: tri,
                at: g,
                behind,
                in_front,
            });
        }
    }
    (probed, wrong)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An octahedron facing inward whose first triangle is a sliver of area 1e-14 (one face
    /// split at a point 1e-14 from a corner): it is reported inside out, probed at one of its
    /// large faces, not at the sliver.
    #[test]
    fn a_component_is_probed_at_its_largest_triangle() {
        // Outward faces, then every one reversed.
        let TriMesh {
            vertices: mut v,
            triangles: mut faces,
        } = crate::test_meshes::octahedron();
        let [a, b, c] = faces.remove(0);
        let p = v[a as usize] + 1e-14 * (v[b as usize] + v[c as usize] - 2.0 * v[a as usize]);
        v.push(p);
        let p = 6;
        faces.splice(0..0, [[a, b, p], [b, c, p], [c, a, p]]);
        for f in &mut faces {
            f.swap(1, 2);
        }
        let mesh = TriMesh {
            vertices: v,
            triangles: faces,
        };
        let t = crate::topology::analyze(&mesh, 10);
        assert!(t.is_closed_oriented_manifold());
        let bvh = crate::intersect::triangle_bvh(&mesh);
        let (probed, wrong) = wrong_sides(&mesh, &t, &bvh);
        assert_eq!((probed, wrong.len()), (1, 1));
        let w = &wrong[0];
        assert_eq!(w.first_triangle, 0);
        assert!(![0, 2].contains(&w.probed_triangle), "{w:?}");
        assert!(
            w.behind.abs() < 0.01 && (w.in_front + 1.0).abs() < 0.01,
            "{w:?}"
        );
    }
}
