//! The exact polyhedron oracle (section 6.6.4): a triangle mesh, possibly a soup with small
//! holes; see [`super`] for the oracles and invariants.

use crate::roots::{Ends, SplitMix64, bisect};
use crate::{BoundingSphere, Surface};
use geom::bvh::TriangleBvh as Bvh;
use geom::closest::closest_point_segment;
use geom::predicates::{BadPoint, collinear, first_bad_point};
use glam::DVec3;
use meshio::TriMesh;

/// Coordinates must stay below this magnitude for the exact predicates (Shewchuk's range).
const MAX_COORD: f64 = 1e60;

/// Errors building a [`PolyhedronSurface`].
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
#[allow(missing_docs)] // variant fields: named in the variant's docs and message
pub enum PolyhedronError {
    /// The mesh has no vertices.
    /// The mesh has `vertices` vertices but no triangles.
    /// Vertex `index` has a non-finite coordinate.
    /// Vertex `index` has a coordinate beyond the exact predicates' range.
    /// Triangle `face` references a vertex `index` out of range.
    /// Every triangle is degenerate.
    #[error("the mesh is empty (no vertices); give a triangle mesh with at least one face")]
    NoVertices,
    #[error(
        "the mesh has {vertices} vertices but no triangles; a polyhedron needs faces (to mesh a \
         point set, read it as points)"
    )]
    NoTriangles { vertices: usize },
    #[error(
        "vertex {index} has a non-finite coordinate ({x}, {y}, {z}); fix or remove that vertex"
    )]
    NonFinite {
        index: usize,
        x: f64,
        y: f64,
        z: f64,
    },
    #[error(
        "vertex {index} has coordinate {value}, beyond the exact-predicate range (|c| < 1e60); \
         rescale the mesh"
    )]
    OutOfRange { index: usize, value: f64 },
    #[error(
        "triangle {face} references vertex {index}, but the mesh has only {vertices} vertices \
         (valid indices 0..{vertices}); fix the face list"
    )]
    BadIndex {
        face: usize,
        index: u32,
        vertices: usize,
    },
    #[error(
        "all {triangles} triangles are degenerate (zero area: repeated or collinear vertices); \
         the mesh has no surface"
    )]
    AllDegenerate { triangles: usize },
}

/// What [`PolyhedronSurface::new`] found in (and tolerated about) its input.
#[derive(Clone, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct PolyhedronStats {
    /// Input vertices.
    pub vertices: usize,
    /// Input triangles.
    pub triangles: usize,
    /// Vertices with exactly the same coordinates as an earlier vertex (welded for topology).
    pub duplicate_vertices: usize,
    /// Faces with repeated or exactly collinear vertices (ignored).
    pub degenerate_triangles: usize,
    /// Vertices referenced by no face.
    pub unreferenced_vertices: usize,
    /// Connected components of the non-degenerate faces (after welding).
    pub components: usize,
    /// Edges with one incident face (holes).
    pub boundary_edges: usize,
    /// Edges with more than two incident faces.
    pub nonmanifold_edges: usize,
    /// Edges whose two faces traverse them in the same direction (inconsistent orientation).
    pub misoriented_edges: usize,
    /// Vertices around which the faces form more than one fan (sheets meeting at a point).
    pub nonmanifold_vertices: usize,
    /// Faces dropped as duplicates of an earlier face (the same three vertices).
    pub duplicate_faces: usize,
    /// Faces reversed to agree with the orientation of their patch.
    pub flipped_faces: usize,
    /// Pairs of input triangles that intersect other than at shared vertices and edges, when
    /// counted (by the caller: [`PolyhedronSurface::set_self_intersections`]).
    pub self_intersecting_pairs: Option<usize>,
    /// The faces' signed volume is negative (an inside-out export): the surface is read with
    /// every face reversed, so the output's normals point out.
    #[serde(default)]
    pub inside_out: bool,
}

impl PolyhedronStats {
    /// Whether the input is a closed, manifold, consistently oriented mesh without duplicate
    /// faces (and without self-intersections, when they were counted).
    pub fn is_clean(&self) -> bool {
        self.boundary_edges == 0
            && self.nonmanifold_edges == 0
            && self.misoriented_edges == 0
            && self.nonmanifold_vertices == 0
            && self.duplicate_faces == 0
            && self.self_intersecting_pairs.unwrap_or(0) == 0
    }
}

/// A triangle mesh as a surface oracle. See the module documentation.
///
/// ```
/// use glam::DVec3;
/// use meshio::TriMesh;
/// use oracle::Surface;
/// use oracle::polyhedron::PolyhedronSurface;
/// // A tetrahedron, counter-clockwise seen from outside.
/// let mesh = TriMesh {
///     vertices: vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z],
///     triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
/// };
/// let s = PolyhedronSurface::new(&mesh).unwrap();
/// assert!(s.value(DVec3::splat(0.1)) < 0.0); // inside
/// assert!(s.value(DVec3::splat(2.0)) > 0.0); // outside
/// let mut xs = Vec::new();
/// s.crossings(DVec3::new(0.2, 0.2, -1.0), DVec3::new(0.2, 0.2, 1.0), &mut xs);
/// assert_eq!(xs.len(), 2);
/// ```
#[derive(Clone, Debug)]
pub struct PolyhedronSurface {
    pub(super) bvh: Bvh,
    /// Component id of each triangle, in BVH (leaf) order.
    component: Vec<u32>,
    /// Non-degenerate faces as welded vertex indices, in input order, with their input index.
    pub(super) faces: Vec<([u32; 3], u32)>,
    /// Welded vertex positions (indexed by the input vertex index of the representative).
    pub(super) vertices: Vec<DVec3>,
    lo: DVec3,
    hi: DVec3,
    /// +1 if the mesh is oriented outward (positive signed volume), −1 otherwise.
    pub(super) orientation: f64,
    /// Watertight meshes only (else empty): per triangle in leaf order, the angle-weighted
    /// pseudonormals of its features `[face, vertex a, b, c, edge ab, bc, ca]`.
    pseudo: Vec<[DVec3; 7]>,
    stats: PolyhedronStats,
}

impl PolyhedronSurface {
    /// Validate the mesh and build the BVH. Duplicate vertices and degenerate faces are
    /// tolerated and counted in [`PolyhedronSurface::stats`].
    pub fn new(mesh: &TriMesh) -> Result<Self, PolyhedronError> {
        let nv = mesh.vertices.len();
        validate(mesh)?;
        let (canon, duplicate_vertices) = weld(&mesh.vertices);
        let mut faces: Vec<([u32; 3], u32)> = Vec::with_capacity(mesh.triangles.len());
        let mut degenerate = 0;
        let mut referenced = vec![false; nv];
        for (f, t) in mesh.triangles.iter().enumerate() {
            for &i in t {
                referenced[i as usize] = true;
            }
            let c = t.map(|i| canon[i as usize]);
            let [a, b, d] = c.map(|i| mesh.vertices[i as usize]);
            if c[0] == c[1] || c[1] == c[2] || c[0] == c[2] || collinear(a, b, d) {
                degenerate += 1;
                continue;
            }
            faces.push((c, f as u32));
        }
        if faces.is_empty() {
            return Err(PolyhedronError::AllDegenerate {
                triangles: mesh.triangles.len(),
            });
        }
        // Edge statistics of the input (sorted, deterministic), then of the cleaned faces.
        let (_, boundary_edges, nonmanifold_edges, misoriented_edges) = edge_stats(&faces);
        let nonmanifold_vertices = nonmanifold_vertex_count(nv, &faces);
        let cleaned = super::clean::clean(&mut faces, &mesh.vertices);
        let (face_comp, ncomp) = face_components(nv, &faces);
        let (edges, b, n, m) = edge_stats(&faces);
        let watertight = b == 0 && n == 0 && m == 0;
        let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
        let mut volume = 0.0;
        let tris: Vec<[DVec3; 3]> = faces
            .iter()
            .map(|(t, _)| {
                let p = t.map(|i| mesh.vertices[i as usize]);
                for v in p {
                    lo = lo.min(v);
                    hi = hi.max(v);
                }
                volume += p[0].dot(p[1].cross(p[2]));
                p
            })
            .collect();
        let diag = (hi - lo).length();
        let scale = diag.max(lo.abs().max_element()).max(hi.abs().max_element());
        let pad = 1e-9 * scale.max(f64::MIN_POSITIVE);
        let ids: Vec<u32> = (0..faces.len() as u32).collect();
        let bvh = Bvh::build(tris, ids, pad);
        let component = bvh
            .face_ids()
            .iter()
            .map(|&i| face_comp[i as usize])
            .collect();
        let pseudo = if watertight {
            pseudonormals(&mesh.vertices, &faces, &edges, bvh.face_ids())
        } else {
            Vec::new()
        };
        let stats = PolyhedronStats {
            vertices: nv,
            triangles: mesh.triangles.len(),
            duplicate_vertices,
            degenerate_triangles: degenerate,
            unreferenced_vertices: referenced.iter().filter(|&&r| !r).count(),
            components: ncomp as usize,
            boundary_edges,
            nonmanifold_edges,
            misoriented_edges,
            nonmanifold_vertices,
            duplicate_faces: cleaned.duplicate_faces,
            flipped_faces: cleaned.flipped_faces,
            self_intersecting_pairs: None,
            inside_out: volume < 0.0,
        };
        Ok(PolyhedronSurface {
            bvh,
            component,
            faces,
            vertices: mesh.vertices.clone(),
            lo,
            hi,
            orientation: if volume < 0.0 { -1.0 } else { 1.0 },
            stats,
            pseudo,
        })
    }

    /// Whether the (welded, non-degenerate) mesh is closed, manifold and consistently
    /// oriented. Then [`Surface::value`] is the signed distance near the surface (sign from
    /// angle-weighted pseudonormals, Bærentzen & Aanæs 2005) and sign-exact by ray parity
    /// farther; otherwise it is `0.5 − w` (winding number).
    pub fn is_watertight(&self) -> bool {
        !self.pseudo.is_empty()
    }

    /// Sign-exact inside/outside for watertight meshes: within `suggested_size()` of the
    /// surface, the signed distance; farther, `±suggested_size()` with the sign from the
    /// parity of the exact crossings of a segment from `p` out of the bounding box (consistent
    /// with [`Surface::crossings`]). `None` if the mesh is not watertight.
    fn watertight_value(&self, p: DVec3) -> Option<f64> {
        if self.pseudo.is_empty() {
            return None;
        }
        let r = self.suggested_size();
        if let Some((q, k, d2, f)) = self.bvh.closest_within(p, r * r) {
            let s = (p - q).dot(self.pseudo[k as usize][f as usize]) * self.orientation;
            return Some(if s < 0.0 {
                -d2.sqrt()
            } else if s > 0.0 {
                d2.sqrt()
            } else {
                0.0
            });
        }
        if p.cmplt(self.lo).any() || p.cmpgt(self.hi).any() {
            return Some(r);
        }
        // Exit through the nearest face of the bounding box.
        let below = p - self.lo;
        let above = self.hi - p;
        let (mut axis, mut dist, mut dir) = (0, f64::INFINITY, 0.0);
        for i in 0..3 {
            if below[i] < dist {
                (axis, dist, dir) = (i, below[i], -1.0);
            }
            if above[i] < dist {
                (axis, dist, dir) = (i, above[i], 1.0);
            }
        }
        let mut b = p;
        b[axis] += dir * (dist + r);
        let odd = self.bvh.count_hits(p, b) % 2 == 1;
        Some(if odd { -r } else { r })
    }

    /// Signed distance to the triangles (negative inside), for watertight meshes; `None`
    /// otherwise.
    pub fn signed_distance(&self, p: DVec3) -> Option<f64> {
        if self.pseudo.is_empty() {
            return None;
        }
        let (q, k, d2, f) = self.bvh.closest(p);
        let s = (p - q).dot(self.pseudo[k as usize][f as usize]) * self.orientation;
        Some(if s < 0.0 {
            -d2.sqrt()
        } else if s > 0.0 {
            d2.sqrt()
        } else {
            0.0
        })
    }

    /// Counts of what the input contained (duplicates, degenerate faces, components, ...).
    pub fn stats(&self) -> &PolyhedronStats {
        &self.stats
    }

    /// Record the number of self-intersecting pairs of input triangles (counted by the caller,
    /// e.g. with `verify`'s exact test on [`PolyhedronSurface::welded_mesh`]). A closed mesh
    /// that intersects itself is then no longer treated as watertight: ray parity and
    /// pseudonormals would make the overlap of two shells outside (a non-manifold boundary
    /// along the intersection curves), the winding number makes it inside (the solid
    /// {w > 1/2}, the union).
    pub fn set_self_intersections(&mut self, pairs: usize) {
        self.stats.self_intersecting_pairs = Some(pairs);
        if pairs > 0 {
            self.pseudo = Vec::new();
        }
    }

    /// The cleaned, welded, non-degenerate faces as a mesh (on the input's vertex array).
    pub fn welded_mesh(&self) -> TriMesh {
        TriMesh {
            vertices: self.vertices.clone(),
            triangles: self.faces.iter().map(|(t, _)| *t).collect(),
        }
    }

    /// Axis-aligned bounding box `(min, max)` of the non-degenerate triangles.
    pub fn bbox(&self) -> (DVec3, DVec3) {
        (self.lo, self.hi)
    }

    /// Default sizing: 1/50 of the bounding box diagonal.
    pub fn suggested_size(&self) -> f64 {
        (self.hi - self.lo).length() / 50.0
    }

    /// Generalized winding number at `p` (≈ 1 inside, ≈ 0 outside a closed mesh; the mesh's
    /// global orientation is normalized so that the inside is positive).
    pub fn winding_number(&self, p: DVec3) -> f64 {
        self.orientation * self.bvh.winding_number(p)
    }

    /// Parameters `t ∈ [0, 1]` (sorted) of every crossing of `[a, b]` with the triangles.
    pub fn crossing_params(&self, a: DVec3, b: DVec3, out: &mut Vec<f64>) {
        if a == b || !a.is_finite() || !b.is_finite() {
            return;
        }
        let mut hits = Vec::new();
        self.bvh.segment_hits(a, b, &mut hits);
        hits.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
        out.extend(hits.iter().map(|h| h.0));
    }

    /// Closest point on the triangles and the input index of the face it lies on.
    pub fn closest_point(&self, p: DVec3) -> (DVec3, usize) {
        let (q, k, _, _) = self.bvh.closest(p);
        let f = self.faces[self.bvh.face_ids()[k as usize] as usize].1;
        (q, f as usize)
    }

    /// Edges whose two incident faces have normals differing by more than `angle_deg` degrees
    /// (i.e. dihedral angle below 180° − `angle_deg`), in a deterministic order. Boundary and
    /// non-manifold edges are not included (they are counted in [`PolyhedronStats`]).
    pub fn sharp_edges(&self, angle_deg: f64) -> Vec<(DVec3, DVec3)> {
        let cos_t = angle_deg.to_radians().cos();
        let mut edges: Vec<(u32, u32, u32, bool)> = Vec::with_capacity(self.faces.len() * 3);
        for (fi, (t, _)) in self.faces.iter().enumerate() {
            for k in 0..3 {
                let (u, v) = (t[k], t[(k + 1) % 3]);
                edges.push((u.min(v), u.max(v), fi as u32, u < v));
            }
        }
        edges.sort_unstable();
        let normal = |fi: u32| {
            let t = self.faces[fi as usize].0.map(|i| self.vertices[i as usize]);
            (t[1] - t[0]).cross(t[2] - t[0]).normalize_or_zero()
        };
        let mut out = Vec::new();
        for run in edges.chunk_by(|x, y| x.0 == y.0 && x.1 == y.1) {
            if let [e0, e1] = run {
                let n0 = normal(e0.2);
                let mut n1 = normal(e1.2);
                if e0.3 == e1.3 {
                    n1 = -n1; // inconsistent orientation: compare unsigned
                }
                if n0.dot(n1) < cos_t {
                    out.push((self.vertices[e0.0 as usize], self.vertices[e0.1 as usize]));
                }
            }
        }
        out
    }

    /// Gradient direction: the outward unit normal of the nearest feature (its angle-weighted
    /// pseudonormal for watertight meshes, the nearest triangle's normal otherwise).
    fn nearest_normal(&self, p: DVec3) -> DVec3 {
        let (_, k, _, f) = self.bvh.closest(p);
        let n = match self.pseudo.get(k as usize) {
            Some(ps) => ps[f as usize],
            None => {
                let t = self.bvh.tris()[k as usize];
                (t[1] - t[0]).cross(t[2] - t[0])
            }
        };
        self.orientation * n.normalize_or_zero()
    }
}

/// The checks of [`PolyhedronSurface::new`]: vertices and triangles present, finite and
/// moderate coordinates, indices in range.
fn validate(mesh: &TriMesh) -> Result<(), PolyhedronError> {
    let nv = mesh.vertices.len();
    if nv == 0 {
        return Err(PolyhedronError::NoVertices);
    }
    if mesh.triangles.is_empty() {
        return Err(PolyhedronError::NoTriangles { vertices: nv });
    }
    if let Some((index, bad)) = first_bad_point(&mesh.vertices, MAX_COORD) {
        return Err(PolyhedronError::bad_point(index, bad));
    }
    for (f, t) in mesh.triangles.iter().enumerate() {
        if let Some(&bad) = t.iter().find(|&&i| i as usize >= nv) {
            return Err(PolyhedronError::BadIndex {
                face: f,
                index: bad,
                vertices: nv,
            });
        }
    }
    Ok(())
}

impl PolyhedronError {
    /// The error for vertex `index` failing the kernel's input check.
    fn bad_point(index: usize, bad: BadPoint) -> Self {
        match bad {
            BadPoint::NonFinite([x, y, z]) => Self::NonFinite { index, x, y, z },
            BadPoint::TooLarge(value) => Self::OutOfRange { index, value },
        }
    }
}

/// Weld exactly equal vertices: the canonical index of each vertex (the smallest index with
/// the same coordinates) and the number of duplicates.
fn weld(vertices: &[DVec3]) -> (Vec<u32>, usize) {
    // Weld exactly equal vertices: canonical = smallest index with those coordinates.
    let nv = vertices.len();
    let mut order: Vec<u32> = (0..nv as u32).collect();
    let key = |i: u32| vertices[i as usize].to_array();
    order.sort_by(|&i, &j| {
        let (a, b) = (key(i), key(j));
        a[0].total_cmp(&b[0])
            .then(a[1].total_cmp(&b[1]))
            .then(a[2].total_cmp(&b[2]))
            .then(i.cmp(&j))
    });
    let mut canon: Vec<u32> = (0..nv as u32).collect();
    let mut duplicate_vertices = 0;
    for w in 1..nv {
        let (p, c) = (order[w - 1], order[w]);
        if vertices[p as usize] == vertices[c as usize] {
            canon[c as usize] = canon[p as usize];
            duplicate_vertices += 1;
        }
    }
    (canon, duplicate_vertices)
}

/// Components of the faces (union-find on welded vertices): each face's component, numbered
/// in face order, and the count.
fn face_components(nv: usize, faces: &[([u32; 3], u32)]) -> (Vec<u32>, u32) {
    let mut uf: Vec<u32> = (0..nv as u32).collect();
    fn find(uf: &mut [u32], mut x: u32) -> u32 {
        while uf[x as usize] != x {
            uf[x as usize] = uf[uf[x as usize] as usize];
            x = uf[x as usize];
        }
        x
    }
    for (t, _) in faces {
        let r0 = find(&mut uf, t[0]);
        for &v in &t[1..] {
            let r = find(&mut uf, v);
            if r != r0 {
                let (lo, hi) = (r.min(r0), r.max(r0));
                uf[hi as usize] = lo;
            }
        }
    }
    let mut comp_id = vec![u32::MAX; nv];
    let mut ncomp = 0u32;
    let face_comp: Vec<u32> = faces
        .iter()
        .map(|(t, _)| {
            let r = find(&mut uf, t[0]) as usize;
            if comp_id[r] == u32::MAX {
                comp_id[r] = ncomp;
                ncomp += 1;
            }
            comp_id[r]
        })
        .collect();
    (face_comp, ncomp)
}

/// Vertices around which the faces form more than one fan (faces linked through the edges
/// at the vertex that have exactly two faces).
fn nonmanifold_vertex_count(nv: usize, faces: &[([u32; 3], u32)]) -> usize {
    // (vertex, face) incidences and, per vertex, the edges to its neighbours.
    let mut inc: Vec<(u32, u32, u32, u32)> = Vec::with_capacity(3 * faces.len());
    for (fi, (t, _)) in faces.iter().enumerate() {
        for k in 0..3 {
            inc.push((t[k], t[(k + 1) % 3], t[(k + 2) % 3], fi as u32));
        }
    }
    inc.sort_unstable();
    let mut count = 0;
    let mut seen = vec![false; nv];
    for run in inc.chunk_by(|x, y| x.0 == y.0) {
        let v = run[0].0 as usize;
        if seen[v] {
            continue;
        }
        seen[v] = true;
        // Union-find over the faces of the run through shared opposite-side vertices.
        let mut parent: Vec<usize> = (0..run.len()).collect();
        fn root(p: &mut [usize], mut x: usize) -> usize {
            while p[x] != x {
                p[x] = p[p[x]];
                x = p[x];
            }
            x
        }
        let mut ends: Vec<(u32, usize)> = run
            .iter()
            .enumerate()
            .flat_map(|(i, e)| [(e.1, i), (e.2, i)])
            .collect();
        ends.sort_unstable();
        for w in ends.chunk_by(|x, y| x.0 == y.0) {
            if let [a, b] = w {
                let (ra, rb) = (root(&mut parent, a.1), root(&mut parent, b.1));
                parent[ra.max(rb)] = ra.min(rb);
            }
        }
        let fans = (0..run.len())
            .filter(|&i| root(&mut parent, i) == i)
            .count();
        if fans > 1 {
            count += 1;
        }
    }
    count
}

/// One entry per face edge, `(min, max, min→max along the face, face, local edge)`, sorted
/// (deterministic), and the counts of boundary, non-manifold and misoriented edges.
#[allow(clippy::type_complexity)]
fn edge_stats(faces: &[([u32; 3], u32)]) -> (Vec<(u32, u32, bool, u32, u8)>, usize, usize, usize) {
    // (min, max, direction, face, local edge)
    let mut edges: Vec<(u32, u32, bool, u32, u8)> = Vec::with_capacity(faces.len() * 3);
    for (fi, (t, _)) in faces.iter().enumerate() {
        for k in 0..3 {
            let (u, v) = (t[k], t[(k + 1) % 3]);
            edges.push((u.min(v), u.max(v), u < v, fi as u32, k as u8));
        }
    }
    edges.sort_unstable();
    let (mut boundary_edges, mut nonmanifold_edges, mut misoriented_edges) = (0, 0, 0);
    for run in edges.chunk_by(|x, y| x.0 == y.0 && x.1 == y.1) {
        match run.len() {
            1 => boundary_edges += 1,
            2 => {
                if run[0].2 == run[1].2 {
                    misoriented_edges += 1
                }
            }
            _ => nonmanifold_edges += 1,
        }
    }
    (edges, boundary_edges, nonmanifold_edges, misoriented_edges)
}

/// Angle-weighted pseudonormals (Bærentzen & Aanæs 2005) per triangle in leaf order:
/// `[face, vertex a, b, c, edge ab, bc, ca]`. `edges` is the sorted edge list
/// `(min, max, direction, face, local edge)` of a watertight mesh (two faces per edge).
fn pseudonormals(
    vertices: &[DVec3],
    faces: &[([u32; 3], u32)],
    edges: &[(u32, u32, bool, u32, u8)],
    leaf_faces: &[u32],
) -> Vec<[DVec3; 7]> {
    let fnormal: Vec<DVec3> = faces
        .iter()
        .map(|(t, _)| {
            let [a, b, c] = t.map(|i| vertices[i as usize]);
            (b - a).cross(c - a).normalize_or_zero()
        })
        .collect();
    let mut vnormal = vec![DVec3::ZERO; vertices.len()];
    for ((t, _), n) in faces.iter().zip(&fnormal) {
        let p = t.map(|i| vertices[i as usize]);
        for k in 0..3 {
            let (u, v) = (p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
            let angle = u.angle_between(v);
            if angle.is_finite() {
                vnormal[t[k] as usize] += angle * *n;
            }
        }
    }
    let mut enormal = vec![[DVec3::ZERO; 3]; faces.len()];
    for run in edges.chunk_by(|x, y| x.0 == y.0 && x.1 == y.1) {
        let sum: DVec3 = run.iter().map(|e| fnormal[e.3 as usize]).sum();
        for e in run {
            enormal[e.3 as usize][e.4 as usize] = sum;
        }
    }
    leaf_faces
        .iter()
        .map(|&fi| {
            let (t, _) = faces[fi as usize];
            let e = enormal[fi as usize];
            [
                fnormal[fi as usize],
                vnormal[t[0] as usize],
                vnormal[t[1] as usize],
                vnormal[t[2] as usize],
                e[0],
                e[1],
                e[2],
            ]
        })
        .collect()
}

/// Distance from each point to the nearest of the `edges` (infinity if there are none).
pub fn distance_to_sharp_edges(edges: &[(DVec3, DVec3)], points: &[DVec3]) -> Vec<f64> {
    points
        .iter()
        .map(|&p| {
            edges
                .iter()
                .map(|&(a, b)| (closest_point_segment(p, a, b) - p).length())
                .fold(f64::INFINITY, f64::min)
        })
        .collect()
}

/// Largest distance from the sharp `edges` (sampled every `step` along each edge, end points
/// included) to the surface `output` (e.g. a [`PolyhedronSurface`] of the remeshed output):
/// the sharp-edge deviation of a remeshing. 0 if there are no edges.
pub fn sharp_edge_deviation(
    edges: &[(DVec3, DVec3)],
    output: &PolyhedronSurface,
    step: f64,
) -> f64 {
    let mut worst: f64 = 0.0;
    for &(a, b) in edges {
        let n = (((b - a).length() / step.max(f64::MIN_POSITIVE)).ceil() as usize).clamp(1, 10_000);
        for i in 0..=n {
            let p = a.lerp(b, i as f64 / n as f64);
            worst = worst.max((output.closest_point(p).0 - p).length());
        }
    }
    worst
}

impl Surface for PolyhedronSurface {
    fn bounding_sphere(&self) -> BoundingSphere {
        let center = 0.5 * (self.lo + self.hi);
        let half = 0.5 * (self.hi - self.lo).length();
        BoundingSphere {
            center,
            radius: 1.1 * half + 1e-9 * center.abs().max_element().max(1.0),
        }
    }

    /// For watertight meshes ([`PolyhedronSurface::is_watertight`]): the signed distance
    /// within [`PolyhedronSurface::suggested_size`] of the surface, `±suggested_size()` farther
    /// (sign by exact ray parity). Otherwise `0.5 − w(p)` (generalized winding number). NaN
    /// for a non-finite `p`.
    fn value(&self, p: DVec3) -> f64 {
        if !p.is_finite() {
            return f64::NAN;
        }
        match self.watertight_value(p) {
            Some(d) => d,
            None => 0.5 - self.winding_number(p),
        }
    }

    fn crossing(&self, a: DVec3, fa: f64, b: DVec3, fb: f64) -> DVec3 {
        let mut ts = Vec::new();
        self.crossing_params(a, b, &mut ts);
        let at = |t: f64| a + (b - a) * t;
        match ts.len() {
            0 => {}
            1 => return at(ts[0]),
            n => {
                // The first exact crossing where the sign of the value changes.
                let mut prev_neg = fa < 0.0;
                for k in 0..n {
                    let next_neg = if k + 1 < n {
                        self.value(at(0.5 * (ts[k] + ts[k + 1]))) < 0.0
                    } else {
                        fb < 0.0
                    };
                    if next_neg != prev_neg {
                        return at(ts[k]);
                    }
                    prev_neg = next_neg;
                }
            }
        }
        bisect(|p| self.value(p), Ends::new(a, fa, b, fb), self.tolerance())
    }

    /// Watertight meshes: every exact crossing with the triangles. Otherwise the crossings
    /// with the boundary of the solid {w > 1/2} (see `solid.rs`).
    fn crossings(&self, a: DVec3, b: DVec3, out: &mut Vec<DVec3>) {
        if !self.is_watertight() {
            return self.solid_crossings(a, b, out);
        }
        let mut ts = Vec::new();
        self.crossing_params(a, b, &mut ts);
        out.extend(ts.into_iter().map(|t| a + (b - a) * t));
    }

    /// One point per connected component (centroid of its largest triangle), plus up to 8
    /// centroids of random triangles per component (deterministic for a given `seed`). For a
    /// mesh that is not watertight, only triangles on the boundary of the solid {w > 1/2}
    /// count (see `solid.rs`).
    fn seed_points(&self, seed: u64) -> Vec<DVec3> {
        if self.is_watertight() {
            self.seeds_among(seed, &vec![true; self.bvh.len()])
        } else {
            self.solid_seeds(seed)
        }
    }

    fn gradient(&self, p: DVec3) -> DVec3 {
        self.nearest_normal(p)
    }

    fn project(&self, p: DVec3) -> Option<DVec3> {
        Some(self.closest_point(p).0)
    }

    /// The closest point of the input triangles, which hold S: no crossing found along rays is
    /// nearer, so `verify` does not search them (with buried faces: a lower bound; the rays
    /// never corrected it and took 300 s on a self-intersecting cow, see the GUIDE).
    fn exact_projection(&self) -> bool {
        true
    }
}

impl PolyhedronSurface {
    /// [`Surface::seed_points`] among the triangles (leaf order) with `keep` set; components
    /// without one get none.
    pub(super) fn seeds_among(&self, seed: u64, keep: &[bool]) -> Vec<DVec3> {
        let ncomp = self.stats.components;
        let mut best: Vec<(f64, usize)> = vec![(-1.0, 0); ncomp];
        let mut members: Vec<Vec<usize>> = vec![Vec::new(); ncomp];
        for (k, t) in self.bvh.tris().iter().enumerate() {
            if !keep[k] {
                continue;
            }
            let c = self.component[k] as usize;
            let area = (t[1] - t[0]).cross(t[2] - t[0]).length();
            if area > best[c].0 {
                best[c] = (area, k);
            }
            members[c].push(k);
        }
        let centroid = |k: usize| {
            let t = self.bvh.tris()[k];
            (t[0] + t[1] + t[2]) / 3.0
        };
        let mut rng = SplitMix64(seed ^ 0x9017_5EED);
        let mut out = Vec::new();
        for c in 0..ncomp {
            let m = &members[c];
            if m.is_empty() {
                continue;
            }
            out.push(centroid(best[c].1));
            for _ in 0..m.len().min(8) {
                let k = m[(rng.next_u64() % m.len() as u64) as usize];
                out.push(centroid(k));
            }
        }
        out
    }
}
