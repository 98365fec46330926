//! Combinatorial manifold checks on a set of triangles (used by the manifold patch).

/// A vertex of the triangle soup: a mesh index, or a raw Delaunay id
/// ([`delaunay3::VertexId::to_u32`]).
type VertexId = u32;

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
    nonmanifold_elements_with(tris, true)
}

/// [`nonmanifold_elements`], its vertex pass on rayon's threads only when `parallel` (the
/// mesher follows its tuner). The result is the same either way.
pub(crate) fn nonmanifold_elements_with(
    tris: &[[VertexId; 3]],
    parallel: bool,
) -> (Vec<[VertexId; 2]>, Vec<VertexId>) {
    // The link of every vertex, bucketed by vertex (counting sort): the triangle (a, b, c)
    // puts the link edge (b, c) in a's bucket, and so on. The edge (a, x) has as many
    // triangles as x has link edges in a's bucket, so one pass over the links finds both the
    // bad edges and the bad vertices. The result does not depend on the triangles' order.
    let n = tris
        .iter()
        .flatten()
        .map(|&v| v as usize + 1)
        .max()
        .unwrap_or(0);
    // The links are built for one range of vertices at a time, at most 2^20 link edges
    // each: a bounded buffer, where the links of every vertex at once were 8 bytes a link
    // edge (48 MB at 10^6 vertices, the peak of the run's end).
    nonmanifold_in_ranges(tris, n, parallel, 1 << 20)
}

/// [`nonmanifold_elements_with`] on vertices `0..n`, building the links of a range of
/// vertices with at most `link_edges` link edges at a time (a range has at least one
/// vertex), one pass over the triangles a range. The ranges do not change the result.
fn nonmanifold_in_ranges(
    tris: &[[VertexId; 3]],
    n: usize,
    parallel: bool,
    link_edges: u32,
) -> (Vec<[VertexId; 2]>, Vec<VertexId>) {
    let start = bucket_starts(tris, n);
    let mut bad_edges = Vec::new();
    let mut bad_vertices = Vec::new();
    let mut link: Vec<[VertexId; 2]> = Vec::new();
    let mut lo = 0;
    while lo < n {
        let mut hi = lo + 1;
        while hi < n && start[hi + 1] - start[lo] <= link_edges {
            hi += 1;
        }
        let base = start[lo];
        link.clear();
        link.resize((start[hi] - base) as usize, [0, 0]);
        let mut fill: Vec<u32> = start[lo..hi].iter().map(|&s| s - base).collect();
        for t in tris {
            for i in 0..3 {
                let a = t[i] as usize;
                if (lo..hi).contains(&a) {
                    let k = &mut fill[a - lo];
                    link[*k as usize] = [t[(i + 1) % 3], t[(i + 2) % 3]];
                    *k += 1;
                }
            }
        }
        let (e, v) = check_links(&start, base, &link, lo..hi, parallel);
        bad_edges.extend(e);
        bad_vertices.extend(v);
        lo = hi;
    }
    // Bad edges with both endpoints seen from the smaller one come out sorted.
    (bad_edges, bad_vertices)
}

/// `start[v]..start[v + 1]`: where vertex v's link edges go in a counting sort of the link
/// edges of `tris` by vertex (vertices `0..n`).
pub(crate) fn bucket_starts(tris: &[[VertexId; 3]], n: usize) -> Vec<u32> {
    let mut start = vec![0u32; n + 1];
    for t in tris {
        for &v in t {
            start[v as usize + 1] += 1;
        }
    }
    for v in 0..n {
        start[v + 1] += start[v];
    }
    start
}

/// The bad edges and vertices among `range`, whose link edges are `link` (vertex v's at
/// `start[v] - base..start[v + 1] - base`), on rayon's threads when `parallel`.
fn check_links(
    start: &[u32],
    base: u32,
    link: &[[VertexId; 2]],
    range: std::ops::Range<usize>,
    parallel: bool,
) -> (Vec<[VertexId; 2]>, Vec<VertexId>) {
    let check = |range: std::ops::Range<usize>| {
        let mut bad_edges = Vec::new();
        let mut bad_vertices = Vec::new();
        let mut ends: Vec<(VertexId, u32)> = Vec::new();
        for v in range {
            let l = &link[(start[v] - base) as usize..(start[v + 1] - base) as usize];
            if l.is_empty() {
                continue;
            }
            let (single, edges_ok) = link_of(l, &mut ends);
            if !edges_ok {
                // Edges (v, x) with x > v whose count (x's degree in the link) is not 2.
                let mut k = 0;
                while k < ends.len() {
                    let x = ends[k].0;
                    let mut m = k;
                    while m < ends.len() && ends[m].0 == x {
                        m += 1;
                    }
                    if m - k != 2 && x as usize > v {
                        bad_edges.push([v as VertexId, x]);
                    }
                    k = m;
                }
            }
            if !single {
                bad_vertices.push(v as VertexId);
            }
        }
        (bad_edges, bad_vertices)
    };
    use rayon::prelude::*;
    const CHUNK: usize = 4096;
    let (lo, hi) = (range.start, range.end);
    let chunk = |k: usize| check(lo + k * CHUNK..(lo + (k + 1) * CHUNK).min(hi));
    let parts: Vec<_> = if parallel {
        (0..(hi - lo).div_ceil(CHUNK))
            .into_par_iter()
            .map(chunk)
            .collect()
    } else {
        (0..(hi - lo).div_ceil(CHUNK)).map(chunk).collect()
    };
    let mut bad_edges = Vec::new();
    let mut bad_vertices = Vec::new();
    for (e, v) in parts {
        bad_edges.extend(e);
        bad_vertices.extend(v);
    }
    (bad_edges, bad_vertices)
}

/// The link edges of vertices `0..n` (every index of `tris` below `n`), bucketed by vertex in
/// triangle order: the triangle (a, b, c) puts (b, c) in a's bucket, (c, a) in b's, (a, b) in
/// c's. Bucket v is `link[start[v]..start[v + 1]]`.
pub(crate) fn link_buckets(tris: &[[VertexId; 3]], n: usize) -> (Vec<u32>, Vec<[VertexId; 2]>) {
    let start = bucket_starts(tris, n);
    let mut fill = start.clone();
    let mut link = vec![[0 as VertexId; 2]; tris.len() * 3];
    for t in tris {
        for i in 0..3 {
            let (a, b, c) = (t[i], t[(i + 1) % 3], t[(i + 2) % 3]);
            let k = &mut fill[a as usize];
            link[*k as usize] = [b, c];
            *k += 1;
        }
    }
    (start, link)
}

/// The link edges `link` of one vertex: whether they form exactly one cycle, and whether
/// every link vertex has degree exactly 2 (every edge at the vertex has two triangles).
/// Leaves `ends` = the (link vertex, link edge) pairs sorted.
fn link_of(link: &[[VertexId; 2]], ends: &mut Vec<(VertexId, u32)>) -> (bool, bool) {
    let n = link.len();
    ends.clear();
    for (k, &[a, b]) in link.iter().enumerate() {
        ends.push((a, k as u32));
        ends.push((b, k as u32));
    }
    ends.sort_unstable();
    // Every link vertex must have degree exactly 2.
    let mut degrees_ok = ends.len().is_multiple_of(2);
    if degrees_ok {
        for pair in ends.chunks(2) {
            if pair[0].0 != pair[1].0 {
                degrees_ok = false;
                break;
            }
        }
    }
    if degrees_ok && ends.windows(3).any(|w| w[0].0 == w[2].0) {
        degrees_ok = false;
    }
    if !degrees_ok || n < 3 {
        return (false, degrees_ok);
    }
    // Walk the cycle from edge 0 and count its edges.
    let other = |x: VertexId, k: usize| -> usize {
        let i = ends.partition_point(|e| e.0 < x);
        if ends[i].1 as usize == k {
            ends[i + 1].1 as usize
        } else {
            ends[i].1 as usize
        }
    };
    let [start_a, mut at] = link[0];
    let mut k = 0usize;
    let mut len = 1;
    while at != start_a {
        k = other(at, k);
        let [a, b] = link[k];
        at = if a == at { b } else { a };
        len += 1;
        if len > n {
            return (false, true);
        }
    }
    (len == n, true)
}

/// Union-find over vertex ids, joined by triangles. Invariant: a set's root is its smallest
/// vertex (a union keeps the smaller root), so roots do not depend on the order of the joins.
pub(crate) struct VertexUnion(Vec<u32>);

impl VertexUnion {
    /// `n` singleton sets.
    pub(crate) fn new(n: usize) -> VertexUnion {
        VertexUnion((0..n as u32).collect())
    }

    /// The root of `x`'s set (with path halving).
    pub(crate) fn find(&mut self, mut x: u32) -> u32 {
        let p = &mut self.0;
        while p[x as usize] != x {
            p[x as usize] = p[p[x as usize] as usize];
            x = p[x as usize];
        }
        x
    }

    /// Join the three corners of `t`.
    pub(crate) fn join_triangle(&mut self, t: [u32; 3]) {
        for k in 1..3 {
            let (a, b) = (self.find(t[0]), self.find(t[k]));
            if a != b {
                self.0[a.max(b) as usize] = a.min(b);
            }
        }
    }
}

/// Up to `per_component` well-spread vertices (farthest-point order) of every connected
/// component of a triangle mesh, in a deterministic order.
pub fn component_representatives(mesh: &meshio::TriMesh, per_component: usize) -> Vec<glam::DVec3> {
    let n = mesh.vertices.len();
    let mut parent = VertexUnion::new(n);
    for &t in &mesh.triangles {
        parent.join_triangle(t);
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
            let r = parent.find(v);
            comps.entry(r).or_default().push(v);
        }
    }
    let mut out = Vec::new();
    for (_, vs) in comps {
        let pts: Vec<glam::DVec3> = vs.iter().map(|&v| mesh.vertices[v as usize]).collect();
        // Farthest-point order from the first vertex (ties to the lowest index).
        let picks = geom::farthest::farthest_points(&[], &pts, per_component.max(1), None);
        out.extend(picks.into_iter().map(|i| pts[i]));
    }
    out
}

/// The vertex directions of [`OCTAHEDRON`]: +x, -x, +y, -y (the equator), +z, -z (the poles).
#[cfg(test)]
pub(crate) const OCTAHEDRON_VERTICES: [glam::DVec3; 6] = [
    glam::DVec3::X,
    glam::DVec3::NEG_X,
    glam::DVec3::Y,
    glam::DVec3::NEG_Y,
    glam::DVec3::Z,
    glam::DVec3::NEG_Z,
];

/// The triangles of an outward-oriented octahedron: vertices 0 to 3 around the equator, 4 and 5
/// the poles (a test fixture).
#[cfg(test)]
pub(crate) const OCTAHEDRON: [[VertexId; 3]; 8] = [
    [0, 2, 4],
    [2, 1, 4],
    [1, 3, 4],
    [3, 0, 4],
    [2, 0, 5],
    [1, 2, 5],
    [3, 1, 5],
    [0, 3, 5],
];

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

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
        assert_eq!(nonmanifold_elements(&OCTAHEDRON), (vec![], vec![]));
    }

    /// The definition, written plainly: sort all edges, and each vertex's link edges.
    fn reference(tris: &[[VertexId; 3]]) -> (Vec<[VertexId; 2]>, Vec<VertexId>) {
        let mut edges: Vec<[VertexId; 2]> = Vec::new();
        let mut link: std::collections::BTreeMap<VertexId, Vec<[VertexId; 2]>> = Default::default();
        for t in tris {
            for i in 0..3 {
                let (a, b, c) = (t[i], t[(i + 1) % 3], t[(i + 2) % 3]);
                edges.push([a.min(b), a.max(b)]);
                link.entry(a).or_default().push([b, c]);
            }
        }
        edges.sort_unstable();
        let mut bad_edges: Vec<[VertexId; 2]> = Vec::new();
        for e in &edges {
            let n = edges.iter().filter(|x| *x == e).count();
            if n != 2 && bad_edges.last() != Some(e) {
                bad_edges.push(*e);
            }
        }
        let mut bad_vertices = Vec::new();
        for (v, l) in link {
            // One cycle: every link vertex of degree 2, and the edges connected.
            let mut deg: std::collections::BTreeMap<VertexId, usize> = Default::default();
            for [a, b] in &l {
                *deg.entry(*a).or_default() += 1;
                *deg.entry(*b).or_default() += 1;
            }
            let mut ok = l.len() >= 3 && deg.values().all(|&d| d == 2);
            if ok {
                let mut seen = vec![false; l.len()];
                let mut stack = vec![0];
                seen[0] = true;
                while let Some(k) = stack.pop() {
                    for (m, e) in l.iter().enumerate() {
                        if !seen[m] && e.iter().any(|x| l[k].contains(x)) {
                            seen[m] = true;
                            stack.push(m);
                        }
                    }
                }
                ok = seen.iter().all(|&s| s);
            }
            if !ok {
                bad_vertices.push(v);
            }
        }
        (bad_edges, bad_vertices)
    }

    proptest::proptest! {
        /// Random triangle soups on few vertices (many non-manifold edges and vertices) and
        /// closed surfaces with a few triangles dropped or doubled, in any order.
        #[test]
        fn matches_the_definition(
            soup in proptest::collection::vec(
                (0u32..9, 0u32..9, 0u32..9).prop_filter("distinct", |(a, b, c)| a != b && b != c && a != c),
                0..30,
            ),
            drop in proptest::collection::vec(0usize..8, 0..3),
            twice in proptest::collection::vec(0usize..8, 0..2),
            shift in 0u32..5,
        ) {
            let t: Vec<[VertexId; 3]> = soup.iter().map(|&(a, b, c)| [a, b, c]).collect();
            proptest::prop_assert_eq!(nonmanifold_elements(&t), reference(&t));
            let n = t.iter().flatten().map(|&v| v as usize + 1).max().unwrap_or(0);
            for limit in [1, 5] {
                proptest::prop_assert_eq!(
                    nonmanifold_in_ranges(&t, n, false, limit),
                    reference(&t)
                );
            }
            // An octahedron with vertex ids shifted, some triangles dropped or doubled.
            let oct = [
                [0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4],
                [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5],
            ];
            let mut t: Vec<[VertexId; 3]> = oct
                .iter()
                .enumerate()
                .filter(|(i, _)| !drop.contains(i))
                .map(|(_, x)| x.map(|v: u32| v * 3 + shift))
                .collect();
            for &k in &twice {
                t.push(oct[k].map(|v: u32| v * 3 + shift));
            }
            t.reverse();
            proptest::prop_assert_eq!(nonmanifold_elements(&t), reference(&t));
        }
    }

    #[test]
    fn three_facets_on_an_edge() {
        let t = [[0, 1, 2], [0, 1, 3], [0, 1, 4]];
        let (e, _) = nonmanifold_elements(&t);
        assert!(e.contains(&[0, 1]));
    }
}
