//! Self-intersections: pairs of triangles that meet other than along their shared vertices
//! and edge, decided with exact predicates, candidates from a BVH over triangle boxes.

use glam::DVec3;
use meshio::TriMesh;
use rayon::prelude::*;
use serde::Serialize;

use geom::bvh::{Aabb, TriangleBvh};
use geom::predicates;

/// Self-intersection results.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct SelfIntersections {
    /// Number of intersecting pairs.
    pub pairs_total: usize,
    /// Intersecting pairs `(i, j)`, `i < j`, in lexicographic order (capped).
    pub pairs: Vec<[usize; 2]>,
    /// Pairs with overlapping boxes that were tested exactly.
    pub candidate_pairs: usize,
    /// Degenerate triangles are skipped (they are reported by the topology checks).
    pub skipped_degenerate: usize,
}

/// Build the kernel's triangle BVH over the mesh (face id = triangle index; degenerate
/// triangles included).
pub fn triangle_bvh(mesh: &TriMesh) -> TriangleBvh {
    let tris = mesh
        .triangles
        .par_iter()
        .map(|t| t.map(|i| mesh.vertices[i as usize]))
        .collect();
    TriangleBvh::build(tris, (0..mesh.triangles.len() as u32).collect(), 0.0)
}

/// Do triangles `i` and `j` (both non-degenerate) intersect improperly?
pub fn pair_intersects(mesh: &TriMesh, i: usize, j: usize) -> bool {
    triangles_intersect(&mesh.vertices, mesh.triangles[i], mesh.triangles[j])
}

/// [`pair_intersects`] for two triangles given by their corners' indices into `vertices`
/// (triangles not, or not yet, in a mesh: a local edit tested before it is made).
pub fn triangles_intersect(vertices: &[DVec3], ti: [u32; 3], tj: [u32; 3]) -> bool {
    let p = |v: u32| vertices[v as usize];
    let shared: Vec<(usize, usize)> = (0..3)
        .flat_map(|a| (0..3).map(move |b| (a, b)))
        .filter(|&(a, b)| ti[a] == tj[b])
        .collect();
    match shared.len() {
        0 => predicates::triangles_intersect(ti.map(p), tj.map(p)),
        1 => {
            let (a, b) = shared[0];
            predicates::shared_vertex_overlap(
                p(ti[a]),
                [p(ti[(a + 1) % 3]), p(ti[(a + 2) % 3])],
                [p(tj[(b + 1) % 3]), p(tj[(b + 2) % 3])],
            )
        }
        2 => {
            let oa = (0..3)
                .find(|&a| shared.iter().all(|s| s.0 != a))
                .unwrap_or(0);
            let ob = (0..3)
                .find(|&b| shared.iter().all(|s| s.1 != b))
                .unwrap_or(0);
            predicates::shared_edge_overlap(
                p(ti[shared[0].0]),
                p(ti[shared[1].0]),
                p(ti[oa]),
                p(tj[ob]),
            )
        }
        _ => true, // the same three vertices: duplicate faces overlap
    }
}

/// Find every pair of non-degenerate triangles that intersect other than along shared
/// vertices/edges. Output is sorted and independent of the thread count.
pub fn self_intersections(
    mesh: &TriMesh,
    bvh: &TriangleBvh,
    max_listed: usize,
) -> SelfIntersections {
    let degenerate: Vec<bool> = mesh
        .triangles
        .par_iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| mesh.vertices[i as usize]);
            predicates::collinear(a, b, c)
        })
        .collect();
    let per_tri: Vec<(usize, Vec<usize>)> = (0..mesh.triangles.len())
        .into_par_iter()
        .map(|i| {
            if degenerate[i] {
                return (0, Vec::new());
            }
            let mut cand = 0;
            let mut hits = Vec::new();
            bvh.for_each_overlap(&Aabb::from_points(&corners(mesh, i)), |j| {
                let j = j as usize;
                if j > i && !degenerate[j] {
                    cand += 1;
                    if pair_intersects(mesh, i, j) {
                        hits.push(j);
                    }
                }
            });
            hits.sort_unstable();
            (cand, hits)
        })
        .collect();
    let candidate_pairs = per_tri.iter().map(|x| x.0).sum();
    let pairs_total = per_tri.iter().map(|x| x.1.len()).sum();
    let pairs = per_tri
        .iter()
        .enumerate()
        .flat_map(|(i, (_, h))| h.iter().map(move |&j| [i, j]))
        .take(max_listed)
        .collect();
    SelfIntersections {
        pairs_total,
        pairs,
        candidate_pairs,
        skipped_degenerate: degenerate.iter().filter(|&&d| d).count(),
    }
}

/// Triangle corner positions.
pub fn corners(mesh: &TriMesh, t: usize) -> [DVec3; 3] {
    mesh.triangles[t].map(|i| mesh.vertices[i as usize])
}
