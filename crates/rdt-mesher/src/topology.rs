//! Combinatorial manifold checks on a set of triangles (used by the manifold patch).

use delaunay3::VertexId;

/// Edges (sorted vertex pairs) with other than two incident triangles, and vertices whose link
/// is not a single cycle (more than one umbrella, or a boundary). Both lists are sorted.
///
/// ```
/// use rdt_mesher::topology::nonmanifold_elements;
/// // A closed tetrahedron is a 2-manifold.
/// let tet = [[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]];
/// assert_eq!(nonmanifold_elements(&tet), (vec![], vec![]));
/// // Remove one facet: its three edges and three vertices are on the boundary.
/// let (e, v) = nonmanifold_elements(&tet[..3]);
/// assert_eq!((e.len(), v.len()), (3, 3));
/// ```
pub fn nonmanifold_elements(tris: &[[VertexId; 3]]) -> (Vec<[VertexId; 2]>, Vec<VertexId>) {
    let mut edges: Vec<[VertexId; 2]> = Vec::with_capacity(tris.len() * 3);
    let mut link: Vec<(VertexId, VertexId, VertexId)> = Vec::with_capacity(tris.len() * 3);
    for t in tris {
        for i in 0..3 {
            let (a, b, c) = (t[i], t[(i + 1) % 3], t[(i + 2) % 3]);
            edges.push(if a < b { [a, b] } else { [b, a] });
            link.push((a, b.min(c), b.max(c)));
        }
    }
    edges.sort_unstable();
    let mut bad_edges = Vec::new();
    let mut i = 0;
    while i < edges.len() {
        let mut j = i + 1;
        while j < edges.len() && edges[j] == edges[i] {
            j += 1;
        }
        if j - i != 2 {
            bad_edges.push(edges[i]);
        }
        i = j;
    }
    link.sort_unstable();
    let mut bad_vertices = Vec::new();
    let mut i = 0;
    let mut ends: Vec<(VertexId, usize)> = Vec::new();
    while i < link.len() {
        let v = link[i].0;
        let mut j = i;
        while j < link.len() && link[j].0 == v {
            j += 1;
        }
        if !is_single_cycle(&link[i..j], &mut ends) {
            bad_vertices.push(v);
        }
        i = j;
    }
    (bad_edges, bad_vertices)
}

/// Whether the link edges (v, a, b) of one vertex form exactly one cycle.
fn is_single_cycle(
    link: &[(VertexId, VertexId, VertexId)],
    ends: &mut Vec<(VertexId, usize)>,
) -> bool {
    let n = link.len();
    if n < 3 {
        return false;
    }
    ends.clear();
    for (k, &(_, a, b)) in link.iter().enumerate() {
        ends.push((a, k));
        ends.push((b, k));
    }
    ends.sort_unstable();
    // Every link vertex must have degree exactly 2.
    for pair in ends.chunks(2) {
        if pair.len() != 2 || pair[0].0 != pair[1].0 {
            return false;
        }
    }
    if ends.windows(3).any(|w| w[0].0 == w[2].0) {
        return false;
    }
    // Walk the cycle from edge 0 and count its edges.
    let other = |x: VertexId, k: usize| -> usize {
        let i = ends.partition_point(|e| e.0 < x);
        if ends[i].1 == k {
            ends[i + 1].1
        } else {
            ends[i].1
        }
    };
    let (_, start_a, _) = link[0];
    let mut k = 0usize;
    let mut at = link[0].2;
    let mut len = 1;
    while at != start_a {
        k = other(at, k);
        let (_, a, b) = link[k];
        at = if a == at { b } else { a };
        len += 1;
        if len > n {
            return false;
        }
    }
    len == n
}

/// Up to `per_component` well-spread vertices (farthest-point order) of every connected
/// component of a triangle mesh, in a deterministic order.
pub fn component_representatives(mesh: &meshio::TriMesh, per_component: usize) -> Vec<glam::DVec3> {
    let n = mesh.vertices.len();
    let mut parent: Vec<u32> = (0..n as u32).collect();
    fn find(p: &mut [u32], mut x: u32) -> u32 {
        while p[x as usize] != x {
            p[x as usize] = p[p[x as usize] as usize];
            x = p[x as usize];
        }
        x
    }
    for t in &mesh.triangles {
        for i in 0..3 {
            let (a, b) = (find(&mut parent, t[i]), find(&mut parent, t[(i + 1) % 3]));
            if a != b {
                parent[a.max(b) as usize] = a.min(b);
            }
        }
    }
    let mut used = vec![false; n];
    for t in &mesh.triangles {
        for &v in t {
            used[v as usize] = true;
        }
    }
    let mut comps: std::collections::BTreeMap<u32, Vec<u32>> = Default::default();
    for v in 0..n as u32 {
        if used[v as usize] {
            let r = find(&mut parent, v);
            comps.entry(r).or_default().push(v);
        }
    }
    let mut out = Vec::new();
    for (_, vs) in comps {
        let pts: Vec<glam::DVec3> = vs.iter().map(|&v| mesh.vertices[v as usize]).collect();
        let mut dist: Vec<f64> = pts.iter().map(|p| p.distance_squared(pts[0])).collect();
        out.push(pts[0]);
        for _ in 1..per_component.min(pts.len()) {
            let (i, _) = dist
                .iter()
                .enumerate()
                .max_by(|a, b| a.1.total_cmp(b.1).then(b.0.cmp(&a.0)))
                .unwrap();
            let p = pts[i];
            out.push(p);
            for (d, q) in dist.iter_mut().zip(&pts) {
                *d = d.min(q.distance_squared(p));
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_tets_sharing_a_vertex_is_nonmanifold_vertex() {
        let mut t = vec![[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]];
        t.extend([[0, 4, 5], [0, 4, 6], [0, 5, 6], [4, 5, 6]]);
        let (e, v) = nonmanifold_elements(&t);
        assert!(e.is_empty());
        assert_eq!(v, vec![0]);
    }

    #[test]
    fn octahedron_is_manifold() {
        let t = [
            [0, 2, 4],
            [2, 1, 4],
            [1, 3, 4],
            [3, 0, 4],
            [2, 0, 5],
            [1, 2, 5],
            [3, 1, 5],
            [0, 3, 5],
        ];
        assert_eq!(nonmanifold_elements(&t), (vec![], vec![]));
    }

    #[test]
    fn three_facets_on_an_edge() {
        let t = [[0, 1, 2], [0, 1, 3], [0, 1, 4]];
        let (e, _) = nonmanifold_elements(&t);
        assert!(e.contains(&[0, 1]));
    }
}
