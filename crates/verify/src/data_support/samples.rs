//! Samples of an input mesh's triangles as the data of the data-support check (not in the
//! paper: a polyhedron's data is its triangles; section 6.6.2's polyhedral oracle meshes them).
//!
//! Invariant: deterministic (triangles in order, a fixed barycentric grid on each).

use glam::DVec3;
use meshio::TriMesh;

use crate::distance::triangle_samples;

/// Deterministic samples of a mesh's triangles as the data of [`super::data_support`]: a barycentric
/// grid on each triangle with `ceil(longest edge / h)` subdivisions (at most 64), `h` such that
/// the whole mesh gets about `target` samples, plus the vertices.
pub fn mesh_samples(mesh: &TriMesh, target: usize) -> Vec<DVec3> {
    let v = &mesh.vertices;
    let area: f64 = mesh
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| v[i as usize]);
            0.5 * (b - a).cross(c - a).length()
        })
        .sum();
    let h = (2.0 * area / target.max(1) as f64).sqrt();
    let mut out: Vec<DVec3> = v.clone();
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| v[i as usize]);
        let e = (b - a).length().max((c - b).length()).max((a - c).length());
        let n = if h > 0.0 {
            (e / h).ceil().clamp(1.0, 64.0) as usize
        } else {
            1
        };
        if n > 1 {
            let mut s = Vec::new();
            triangle_samples(a, b, c, n, &mut s);
            // The corners are already in (the vertices).
            out.extend(s.into_iter().filter(|p| *p != a && *p != b && *p != c));
        }
    }
    out
}
