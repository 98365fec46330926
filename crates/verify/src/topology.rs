//! Combinatorial checks: boundary, edge and vertex manifoldness, orientation, components,
//! Euler characteristic and genus, duplicate/unreferenced vertices, degenerate triangles.

use glam::DVec3;
use meshio::TriMesh;
use rayon::prelude::*;
use serde::Serialize;

use crate::predicates;

/// One connected component (triangles connected through shared vertices).
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Component {
    /// Number of (non-degenerate-by-index) triangles.
    pub triangles: usize,
    pub vertices: usize,
    pub edges: usize,
    /// V - E + F.
    pub euler_characteristic: i64,
    pub boundary_edges: usize,
    /// Number of closed boundary loops (components of the boundary-edge graph).
    pub boundary_loops: usize,
    pub non_manifold_edges: usize,
    pub non_manifold_vertices: usize,
    /// Some facet orientation makes every manifold edge consistent.
    pub orientable: bool,
    /// Genus of an orientable edge- and vertex-manifold component:
    /// (2 - chi - boundary_loops) / 2. `None` otherwise.
    pub genus: Option<i64>,
    /// Index of the first triangle of the component (identifies it).
    pub first_triangle: usize,
}

/// Results of the combinatorial checks. Lists are capped (`*_total` give the full counts).
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Topology {
    pub boundary_edges_total: usize,
    /// Boundary edges (used by exactly one triangle), as sorted vertex pairs.
    pub boundary_edges: Vec<[u32; 2]>,
    pub non_manifold_edges_total: usize,
    /// Edges used by more than two triangles.
    pub non_manifold_edges: Vec<[u32; 2]>,
    pub non_manifold_vertices_total: usize,
    /// Vertices whose incident triangles form more than one umbrella (fan).
    pub non_manifold_vertices: Vec<u32>,
    pub inconsistent_edges_total: usize,
    /// Interior edges whose two triangles use them in the same direction.
    pub inconsistent_edges: Vec<[u32; 2]>,
    pub components: Vec<Component>,
    pub duplicate_vertices_total: usize,
    /// Pairs (first, duplicate) of vertices with exactly equal coordinates.
    pub duplicate_vertices: Vec<[u32; 2]>,
    pub degenerate_triangles_total: usize,
    /// Triangles with a repeated index or three exactly collinear corners.
    pub degenerate_triangles: Vec<usize>,
    pub unreferenced_vertices_total: usize,
    pub unreferenced_vertices: Vec<u32>,
    pub short_edges_total: usize,
    /// Edges (sorted vertex pairs) shorter than [`SHORT_EDGE`] times the bounding-box
    /// diagonal of the referenced vertices: numerically coincident ends.
    pub short_edges: Vec<[u32; 2]>,
}

/// An edge shorter than this fraction of the mesh's extent joins numerically coincident
/// vertices: no sampling of a surface puts vertices that close (a mesh's edges follow its
/// size bound, or the surface's features), float32 files (`.glb`, `.gii`, `.stl`) merge
/// them, and a cluster of such vertices is a refinement that ran away at one point (a label
/// volume's mesh had 1,500 vertices within 2 of its 2,000 units, edges down to 9e-16).
pub const SHORT_EDGE: f64 = 1e-9;

impl Topology {
    /// No boundary edge.
    pub fn is_closed(&self) -> bool {
        self.boundary_edges_total == 0
    }
    /// No edge with more than two triangles.
    pub fn is_edge_manifold(&self) -> bool {
        self.non_manifold_edges_total == 0
    }
    /// Every vertex has a single umbrella.
    pub fn is_vertex_manifold(&self) -> bool {
        self.non_manifold_vertices_total == 0
    }
    /// Every interior edge is used once in each direction.
    pub fn is_consistently_oriented(&self) -> bool {
        self.inconsistent_edges_total == 0
    }
    /// Closed, edge- and vertex-manifold, consistently oriented.
    pub fn is_closed_oriented_manifold(&self) -> bool {
        self.is_closed()
            && self.is_edge_manifold()
            && self.is_vertex_manifold()
            && self.is_consistently_oriented()
    }
    /// Genus of every component (`None` where undefined), in component order.
    pub fn genera(&self) -> Vec<Option<i64>> {
        self.components.iter().map(|c| c.genus).collect()
    }
}

/// Union-find over `0..n` (path halving; the smaller root wins: deterministic).
pub(crate) struct Dsu(Vec<u32>);
impl Dsu {
    pub(crate) fn new(n: usize) -> Self {
        Dsu((0..n as u32).collect())
    }
    /// `items` grouped by the root of their element (`(item, element)` pairs): the groups in
    /// the order of their first item, each in the items' order.
    pub(crate) fn groups(
        &mut self,
        items: impl IntoIterator<Item = (usize, u32)>,
    ) -> Vec<Vec<usize>> {
        let mut index = vec![usize::MAX; self.0.len()];
        let mut groups: Vec<Vec<usize>> = Vec::new();
        for (item, e) in items {
            let r = self.find(e) as usize;
            if index[r] == usize::MAX {
                index[r] = groups.len();
                groups.push(Vec::new());
            }
            groups[index[r]].push(item);
        }
        groups
    }
    pub(crate) fn find(&mut self, mut x: u32) -> u32 {
        while self.0[x as usize] != x {
            let p = self.0[self.0[x as usize] as usize];
            self.0[x as usize] = p;
            x = p;
        }
        x
    }
    pub(crate) fn union(&mut self, a: u32, b: u32) {
        let (a, b) = (self.find(a), self.find(b));
        if a != b {
            let (lo, hi) = if a < b { (a, b) } else { (b, a) };
            self.0[hi as usize] = lo;
        }
    }
}

/// The vertices of each connected piece of `mesh` (vertices joined by its triangles), in
/// increasing order of their lowest vertex; vertices of no triangle are left out.
pub fn vertex_components(mesh: &TriMesh) -> Vec<Vec<usize>> {
    let n = mesh.vertices.len();
    let mut dsu = Dsu::new(n);
    let mut used = vec![false; n];
    for t in &mesh.triangles {
        if t.iter().any(|&v| v as usize >= n) {
            continue;
        }
        dsu.union(t[0], t[1]);
        dsu.union(t[0], t[2]);
        for &v in t {
            used[v as usize] = true;
        }
    }
    dsu.groups((0..n).filter(|&v| used[v]).map(|v| (v, v as u32)))
}

/// Half-edge record: undirected key, triangle, direction.
#[derive(Clone, Copy)]
struct HalfEdge {
    lo: u32,
    hi: u32,
    tri: u32,
    forward: bool,
}

fn cap<T>(n: usize, v: &mut Vec<T>) {
    v.truncate(n);
}

fn exact_key(p: DVec3) -> [u64; 3] {
    let p = p + DVec3::ZERO; // -0.0 == 0.0
    p.to_array().map(f64::to_bits)
}

/// Run every combinatorial check. The mesh must be valid ([`TriMesh::validate`]).
pub fn analyze(mesh: &TriMesh, max_listed: usize) -> Topology {
    let nv = mesh.vertices.len();
    let tris = &mesh.triangles;

    // Degenerate triangles (exact).
    let degenerate = degenerate_flags(mesh);
    let mut degenerate_triangles: Vec<usize> = (0..tris.len()).filter(|&i| degenerate[i]).collect();
    let degenerate_triangles_total = degenerate_triangles.len();
    cap(max_listed, &mut degenerate_triangles);

    // Half-edges of triangles without repeated indices, sorted by undirected edge.
    let he = half_edges(tris);

    let EdgeScan {
        mut boundary_edges,
        mut non_manifold_edges,
        mut inconsistent_edges,
        mut tri_dsu,
        manifold_pairs,
        edge_groups,
    } = scan_edges(&he, tris.len());

    // Umbrellas: per vertex, incident triangles connected through shared edges at the vertex.
    let (start, inc) = incidence(tris, nv);
    let umbrellas = umbrella_counts(tris, nv, &start, &inc);
    let nm_vertex: Vec<u32> = (0..nv as u32)
        .filter(|&v| umbrellas[v as usize] > 1)
        .collect();

    // Components: triangles connected through shared vertices.
    let (mut comps, comp_of_tri, comp_of_vertex) =
        build_components(tris, &start, &inc, &umbrellas, &mut tri_dsu);
    count_edges_and_loops(&mut comps, &he, &edge_groups, &comp_of_tri, &comp_of_vertex);
    mark_non_orientable(&mut comps, tris, &manifold_pairs, &comp_of_tri);
    set_euler_and_genus(&mut comps);

    // Duplicate vertices: sort by exact coordinates.
    let mut duplicate_vertices = duplicate_vertex_pairs(mesh);
    let duplicate_vertices_total = duplicate_vertices.len();

    let mut unreferenced = unreferenced_vertices(mesh);
    let unreferenced_total = unreferenced.len();
    let mut short_edges = short_edge_pairs(mesh);
    let short_edges_total = short_edges.len();
    cap(max_listed, &mut short_edges);

    let (bt, nt, it, nvt) = (
        boundary_edges.len(),
        non_manifold_edges.len(),
        inconsistent_edges.len(),
        nm_vertex.len(),
    );
    let mut nm_vertex = nm_vertex;
    cap(max_listed, &mut boundary_edges);
    cap(max_listed, &mut non_manifold_edges);
    cap(max_listed, &mut inconsistent_edges);
    cap(max_listed, &mut nm_vertex);
    cap(max_listed, &mut duplicate_vertices);
    cap(max_listed, &mut unreferenced);
    Topology {
        boundary_edges_total: bt,
        boundary_edges,
        non_manifold_edges_total: nt,
        non_manifold_edges,
        non_manifold_vertices_total: nvt,
        non_manifold_vertices: nm_vertex,
        inconsistent_edges_total: it,
        inconsistent_edges,
        components: comps,
        duplicate_vertices_total,
        duplicate_vertices,
        degenerate_triangles_total,
        degenerate_triangles,
        unreferenced_vertices_total: unreferenced_total,
        unreferenced_vertices: unreferenced,
        short_edges_total,
        short_edges,
    }
}

/// A repeated index: such triangles take no part in edges, umbrellas or components.
fn repeated(t: &[u32; 3]) -> bool {
    t[0] == t[1] || t[1] == t[2] || t[0] == t[2]
}

/// Per triangle: a repeated index or collinear corners (exact).
fn degenerate_flags(mesh: &TriMesh) -> Vec<bool> {
    let tris = &mesh.triangles;
    tris.par_iter()
        .map(|t| {
            t[0] == t[1]
                || t[1] == t[2]
                || t[0] == t[2]
                || predicates::collinear(
                    mesh.vertices[t[0] as usize],
                    mesh.vertices[t[1] as usize],
                    mesh.vertices[t[2] as usize],
                )
        })
        .collect()
}

/// Half-edges of triangles without repeated indices, sorted by undirected edge.
fn half_edges(tris: &[[u32; 3]]) -> Vec<HalfEdge> {
    let mut he: Vec<HalfEdge> = Vec::with_capacity(3 * tris.len());
    for (ti, t) in tris.iter().enumerate() {
        if repeated(t) {
            continue;
        }
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            he.push(HalfEdge {
                lo: a.min(b),
                hi: a.max(b),
                tri: ti as u32,
                forward: a < b,
            });
        }
    }
    he.par_sort_unstable_by_key(|h| (h.lo, h.hi, h.tri, h.forward));
    he
}

/// What one pass over the sorted half-edges finds.
struct EdgeScan {
    boundary_edges: Vec<[u32; 2]>,
    non_manifold_edges: Vec<[u32; 2]>,
    inconsistent_edges: Vec<[u32; 2]>,
    /// Triangles joined across shared edges.
    tri_dsu: Dsu,
    /// Pairs of triangles across manifold edges, with "same direction" flags.
    manifold_pairs: Vec<(u32, u32, bool)>,
    /// (start, len) into the half-edges, one per undirected edge.
    edge_groups: Vec<(usize, usize)>,
}

/// Classify every undirected edge (boundary, manifold, non-manifold; inconsistent
/// direction) and join the triangles that share it.
fn scan_edges(he: &[HalfEdge], ntris: usize) -> EdgeScan {
    let mut boundary_edges = Vec::new();
    let mut non_manifold_edges = Vec::new();
    let mut inconsistent_edges = Vec::new();
    let mut tri_dsu = Dsu::new(ntris);
    // Pairs of triangles across manifold edges, with "same direction" flags (orientability).
    let mut manifold_pairs: Vec<(u32, u32, bool)> = Vec::new();
    let mut edge_groups: Vec<(usize, usize)> = Vec::new(); // (start, len) into he
    let mut i = 0;
    while i < he.len() {
        let mut j = i + 1;
        while j < he.len() && he[j].lo == he[i].lo && he[j].hi == he[i].hi {
            j += 1;
        }
        let e = [he[i].lo, he[i].hi];
        match j - i {
            1 => boundary_edges.push(e),
            2 => {
                let same = he[i].forward == he[i + 1].forward;
                if same {
                    inconsistent_edges.push(e);
                }
                manifold_pairs.push((he[i].tri, he[i + 1].tri, same));
            }
            _ => non_manifold_edges.push(e),
        }
        for k in i + 1..j {
            tri_dsu.union(he[i].tri, he[k].tri);
        }
        edge_groups.push((i, j - i));
        i = j;
    }
    EdgeScan {
        boundary_edges,
        non_manifold_edges,
        inconsistent_edges,
        tri_dsu,
        manifold_pairs,
        edge_groups,
    }
}

/// Vertex -> incident triangles (without repeated indices), as CSR offsets and entries.
fn incidence(tris: &[[u32; 3]], nv: usize) -> (Vec<u32>, Vec<u32>) {
    let mut start = vec![0u32; nv + 1];
    for t in tris.iter().filter(|t| !repeated(t)) {
        for &v in t {
            start[v as usize + 1] += 1;
        }
    }
    for v in 0..nv {
        start[v + 1] += start[v];
    }
    let mut fill = start.clone();
    let mut inc = vec![0u32; start[nv] as usize];
    for (ti, t) in tris.iter().enumerate() {
        if repeated(t) {
            continue;
        }
        for &v in t {
            inc[fill[v as usize] as usize] = ti as u32;
            fill[v as usize] += 1;
        }
    }
    (start, inc)
}

/// Per vertex, the number of umbrellas (incident triangles connected through shared edges
/// at the vertex).
fn umbrella_counts(tris: &[[u32; 3]], nv: usize, start: &[u32], inc: &[u32]) -> Vec<u32> {
    (0..nv)
        .into_par_iter()
        .map(|v| {
            let list = &inc[start[v] as usize..start[v + 1] as usize];
            if list.len() <= 1 {
                return list.len() as u32;
            }
            let mut pairs: Vec<(u32, u32)> = Vec::with_capacity(2 * list.len());
            for (li, &t) in list.iter().enumerate() {
                for &w in &tris[t as usize] {
                    if w as usize != v {
                        pairs.push((w, li as u32));
                    }
                }
            }
            pairs.sort_unstable();
            let mut dsu = Dsu::new(list.len());
            for k in 1..pairs.len() {
                if pairs[k].0 == pairs[k - 1].0 {
                    dsu.union(pairs[k].1, pairs[k - 1].1);
                }
            }
            (0..list.len() as u32).filter(|&x| dsu.find(x) == x).count() as u32
        })
        .collect()
}

/// Components (triangles connected through shared vertices) with their triangle, vertex and
/// non-manifold vertex counts; also the component of every triangle and vertex.
fn build_components(
    tris: &[[u32; 3]],
    start: &[u32],
    inc: &[u32],
    umbrellas: &[u32],
    tri_dsu: &mut Dsu,
) -> (Vec<Component>, Vec<u32>, Vec<u32>) {
    let nv = start.len() - 1;
    for v in 0..nv {
        let list = &inc[start[v] as usize..start[v + 1] as usize];
        for k in 1..list.len() {
            tri_dsu.union(list[0], list[k]);
        }
    }
    let mut comp_of_root = vec![u32::MAX; tris.len()];
    let mut comp_of_tri = vec![u32::MAX; tris.len()];
    let mut comps: Vec<Component> = Vec::new();
    for (ti, t) in tris.iter().enumerate() {
        if repeated(t) {
            continue;
        }
        let r = tri_dsu.find(ti as u32) as usize;
        if comp_of_root[r] == u32::MAX {
            comp_of_root[r] = comps.len() as u32;
            comps.push(Component {
                triangles: 0,
                vertices: 0,
                edges: 0,
                euler_characteristic: 0,
                boundary_edges: 0,
                boundary_loops: 0,
                non_manifold_edges: 0,
                non_manifold_vertices: 0,
                orientable: true,
                genus: None,
                first_triangle: ti,
            });
        }
        comp_of_tri[ti] = comp_of_root[r];
        comps[comp_of_root[r] as usize].triangles += 1;
    }
    let mut comp_of_vertex = vec![u32::MAX; nv];
    for v in 0..nv {
        let list = &inc[start[v] as usize..start[v + 1] as usize];
        if let Some(&t) = list.first() {
            let c = comp_of_tri[t as usize];
            comp_of_vertex[v] = c;
            comps[c as usize].vertices += 1;
            if umbrellas[v] > 1 {
                comps[c as usize].non_manifold_vertices += 1;
            }
        }
    }
    (comps, comp_of_tri, comp_of_vertex)
}

/// Per component: edges, boundary and non-manifold edges, boundary loops.
fn count_edges_and_loops(
    comps: &mut [Component],
    he: &[HalfEdge],
    edge_groups: &[(usize, usize)],
    comp_of_tri: &[u32],
    comp_of_vertex: &[u32],
) {
    let nv = comp_of_vertex.len();
    let mut boundary_dsu = Dsu::new(nv);
    let mut on_boundary = vec![false; nv];
    for &(s, len) in edge_groups {
        let c = &mut comps[comp_of_tri[he[s].tri as usize] as usize];
        c.edges += 1;
        match len {
            1 => {
                c.boundary_edges += 1;
                boundary_dsu.union(he[s].lo, he[s].hi);
                on_boundary[he[s].lo as usize] = true;
                on_boundary[he[s].hi as usize] = true;
            }
            2 => {}
            _ => c.non_manifold_edges += 1,
        }
    }
    for v in 0..nv {
        if on_boundary[v] && boundary_dsu.find(v as u32) == v as u32 {
            comps[comp_of_vertex[v] as usize].boundary_loops += 1;
        }
    }
}

/// Orientability: propagate a flip bit across manifold edges; a conflict means the
/// component is not orientable.
fn mark_non_orientable(
    comps: &mut [Component],
    tris: &[[u32; 3]],
    manifold_pairs: &[(u32, u32, bool)],
    comp_of_tri: &[u32],
) {
    let mut adj_start = vec![0u32; tris.len() + 1];
    for &(a, b, _) in manifold_pairs {
        adj_start[a as usize + 1] += 1;
        adj_start[b as usize + 1] += 1;
    }
    for t in 0..tris.len() {
        adj_start[t + 1] += adj_start[t];
    }
    let mut adj_fill = adj_start.clone();
    let mut adj = vec![(0u32, false); adj_start[tris.len()] as usize];
    for &(a, b, same) in manifold_pairs {
        adj[adj_fill[a as usize] as usize] = (b, same);
        adj_fill[a as usize] += 1;
        adj[adj_fill[b as usize] as usize] = (a, same);
        adj_fill[b as usize] += 1;
    }
    let mut flip: Vec<i8> = vec![-1; tris.len()];
    let mut stack = Vec::new();
    for seed in 0..tris.len() {
        if flip[seed] >= 0 || repeated(&tris[seed]) {
            continue;
        }
        flip[seed] = 0;
        stack.push(seed as u32);
        while let Some(t) = stack.pop() {
            for &(u, same) in
                &adj[adj_start[t as usize] as usize..adj_start[t as usize + 1] as usize]
            {
                let want = flip[t as usize] ^ (same as i8);
                if flip[u as usize] < 0 {
                    flip[u as usize] = want;
                    stack.push(u);
                } else if flip[u as usize] != want {
                    comps[comp_of_tri[t as usize] as usize].orientable = false;
                }
            }
        }
    }
}

/// Euler characteristic of every component, and genus where it is defined.
fn set_euler_and_genus(comps: &mut [Component]) {
    for c in comps {
        c.euler_characteristic = c.vertices as i64 - c.edges as i64 + c.triangles as i64;
        let chi_plus_b = c.euler_characteristic + c.boundary_loops as i64;
        if c.orientable
            && c.non_manifold_edges == 0
            && c.non_manifold_vertices == 0
            && (2 - chi_plus_b) % 2 == 0
        {
            c.genus = Some((2 - chi_plus_b) / 2);
        }
    }
}

/// Pairs (first, later) of vertices with exactly equal coordinates, sorted.
fn duplicate_vertex_pairs(mesh: &TriMesh) -> Vec<[u32; 2]> {
    let nv = mesh.vertices.len();
    let mut order: Vec<u32> = (0..nv as u32).collect();
    order.par_sort_unstable_by_key(|&v| (exact_key(mesh.vertices[v as usize]), v));
    let mut duplicate_vertices = Vec::new();
    let mut k = 0;
    while k < order.len() {
        let key = exact_key(mesh.vertices[order[k] as usize]);
        let mut j = k + 1;
        while j < order.len() && exact_key(mesh.vertices[order[j] as usize]) == key {
            duplicate_vertices.push([order[k], order[j]]);
            j += 1;
        }
        k = j;
    }
    duplicate_vertices.sort_unstable();
    duplicate_vertices
}

/// The triangles' edges (sorted pairs, each once, sorted) shorter than [`SHORT_EDGE`] times
/// the bounding-box diagonal of the vertices the triangles use; an edge of two equal indices
/// is a degenerate triangle's, counted there.
fn short_edge_pairs(mesh: &TriMesh) -> Vec<[u32; 2]> {
    let (mut lo, mut hi) = (glam::DVec3::INFINITY, glam::DVec3::NEG_INFINITY);
    for t in &mesh.triangles {
        for &v in t {
            let p = mesh.vertices[v as usize];
            lo = lo.min(p);
            hi = hi.max(p);
        }
    }
    let limit = SHORT_EDGE * (hi - lo).length();
    let mut out: Vec<[u32; 2]> = mesh
        .triangles
        .iter()
        .flat_map(|&[a, b, c]| [[a, b], [b, c], [c, a]])
        .filter(|&[a, b]| {
            a != b && mesh.vertices[a as usize].distance(mesh.vertices[b as usize]) < limit
        })
        .map(|[a, b]| [a.min(b), a.max(b)])
        .collect();
    out.sort_unstable();
    out.dedup();
    out
}

/// Vertices used by no triangle.
fn unreferenced_vertices(mesh: &TriMesh) -> Vec<u32> {
    let nv = mesh.vertices.len();
    let tris = &mesh.triangles;
    let mut referenced = vec![false; nv];
    for t in tris {
        for &v in t {
            referenced[v as usize] = true;
        }
    }
    (0..nv as u32)
        .filter(|&v| !referenced[v as usize])
        .collect()
}
