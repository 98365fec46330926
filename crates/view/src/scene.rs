//! (ours) What is drawn: the mesh, its per-facet measures (minimum angle, r/sigma, distance to
//! the surface, component) and the facets to highlight (those behind a FAIL or an unmet
//! criterion). The topology defects (boundary, non-manifold and misoriented edges, repeated
//! indices) are found here from the triangles alone, so any mesh shows its holes.

use crate::camera::Axis;
use glam::DVec3;
use meshio::TriMesh;
use std::fmt;

/// A scene that cannot be built from its mesh (the mesh is not a valid triangle list).
#[derive(Debug, Clone, PartialEq)]
pub struct SceneError(pub String);

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for SceneError {}

/// One value per facet, drawn through a colour map.
#[derive(Debug, Clone, PartialEq)]
pub struct Measure {
    /// Short name, used in URLs and on the command line: `min_angle`, `r_sigma`, `distance`,
    /// `component`.
    pub key: String,
    /// What the colour bar says, e.g. `minimum angle (deg)`.
    pub label: String,
    /// `values[i]` belongs to triangle `i`; NaN where it is not known (drawn grey).
    pub values: Vec<f64>,
    /// The criterion's bound, marked on the colour bar (e.g. 30 deg, r/sigma 1).
    pub bound: Option<f64>,
    /// Whole numbers naming classes (components): drawn with distinct colours, no bar.
    pub categorical: bool,
}

impl Measure {
    /// The smallest and largest finite value (None when none is finite).
    pub fn range(&self) -> Option<(f64, f64)> {
        let mut r: Option<(f64, f64)> = None;
        for &v in self.values.iter().filter(|v| v.is_finite()) {
            r = Some(r.map_or((v, v), |(a, b)| (a.min(v), b.max(v))));
        }
        r
    }
}

/// A set of facets to show in the highlight colour, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct Highlight {
    /// E.g. `closed: facet at a boundary edge`.
    pub reason: String,
    /// Triangle indices, sorted, without repeats.
    pub facets: Vec<usize>,
}

/// A mesh with what to draw on it.
#[derive(Debug, Clone)]
pub struct Scene {
    pub vertices: Vec<DVec3>,
    pub triangles: Vec<[u32; 3]>,
    /// Title of the picture and the page (e.g. the input spec).
    pub title: String,
    /// Lines shown beside the view (the verdict, sizes, the certificate).
    pub summary: Vec<String>,
    /// The JSON report, shown in the HTML page when given.
    pub report: Option<serde_json::Value>,
    pub measures: Vec<Measure>,
    pub highlights: Vec<Highlight>,
    /// The surface's up axis (pictures are drawn with it pointing up).
    pub up: Axis,
}

impl Scene {
    /// A scene of `mesh` with the measures every mesh has (minimum angle, component) and its
    /// topology defects highlighted. Errors on an index out of range or a non-finite
    /// coordinate.
    pub fn new(mesh: &TriMesh, title: impl Into<String>) -> Result<Scene, SceneError> {
        let n = mesh.vertices.len();
        if let Some((i, _)) = mesh
            .vertices
            .iter()
            .enumerate()
            .find(|(_, p)| !p.is_finite())
        {
            return Err(SceneError(format!(
                "vertex {i} has a non-finite coordinate: the mesh cannot be drawn"
            )));
        }
        for (t, tri) in mesh.triangles.iter().enumerate() {
            if let Some(&v) = tri.iter().find(|&&v| v as usize >= n) {
                return Err(SceneError(format!(
                    "triangle {t} names vertex {v} but the mesh has {n} vertices"
                )));
            }
        }
        let mut scene = Scene {
            vertices: mesh.vertices.clone(),
            triangles: mesh.triangles.clone(),
            title: title.into(),
            summary: Vec::new(),
            report: None,
            measures: Vec::new(),
            highlights: Vec::new(),
            up: Axis::Z,
        };
        let angles = scene.triangles.iter().map(|t| scene.min_angle(t)).collect();
        scene.measures.push(Measure {
            key: "min_angle".into(),
            label: "minimum angle (deg)".into(),
            values: angles,
            bound: None,
            categorical: false,
        });
        let comp = components(&scene.triangles, n);
        scene.measures.push(Measure {
            key: "component".into(),
            label: "component".into(),
            values: comp,
            bound: None,
            categorical: true,
        });
        for (reason, facets) in topology_defects(&scene.triangles) {
            scene.add_highlight(reason, facets);
        }
        Ok(scene)
    }

    /// The smallest angle of a triangle in degrees (0 for a degenerate one).
    fn min_angle(&self, t: &[u32; 3]) -> f64 {
        let p = t.map(|i| self.vertices[i as usize]);
        let mut best = 180.0_f64;
        for k in 0..3 {
            let (a, b, c) = (p[k], p[(k + 1) % 3], p[(k + 2) % 3]);
            let (u, v) = (b - a, c - a);
            let d = u.length() * v.length();
            if d == 0.0 {
                return 0.0;
            }
            let cos = (u.dot(v) / d).clamp(-1.0, 1.0);
            best = best.min(cos.acos().to_degrees());
        }
        best
    }

    /// Adds (or replaces, by key) a measure; values beyond the triangle count are dropped and
    /// missing ones are NaN.
    pub fn set_measure(&mut self, mut m: Measure) {
        m.values.resize(self.triangles.len(), f64::NAN);
        match self.measures.iter_mut().find(|x| x.key == m.key) {
            Some(x) => *x = m,
            None => self.measures.push(m),
        }
    }

    /// The measure named `key`.
    pub fn measure(&self, key: &str) -> Option<&Measure> {
        self.measures.iter().find(|m| m.key == key)
    }

    /// Highlights `facets` for `reason` (indices out of range are ignored; an empty set adds
    /// nothing; a reason given twice merges).
    pub fn add_highlight(
        &mut self,
        reason: impl Into<String>,
        facets: impl IntoIterator<Item = usize>,
    ) {
        let reason = reason.into();
        let mut f: Vec<usize> = facets
            .into_iter()
            .filter(|&i| i < self.triangles.len())
            .collect();
        if let Some(h) = self.highlights.iter_mut().find(|h| h.reason == reason) {
            f.extend(h.facets.iter().copied());
            f.sort_unstable();
            f.dedup();
            h.facets = f;
            return;
        }
        f.sort_unstable();
        f.dedup();
        if !f.is_empty() {
            self.highlights.push(Highlight { reason, facets: f });
        }
    }

    /// `true` for every facet of some highlight.
    pub fn highlighted(&self) -> Vec<bool> {
        let mut h = vec![false; self.triangles.len()];
        for f in self.highlights.iter().flat_map(|h| &h.facets) {
            h[*f] = true;
        }
        h
    }

    /// The measure a picture shows by default: r/sigma when known, else the minimum angle.
    pub fn default_measure(&self) -> &str {
        match self.measure("r_sigma") {
            Some(m) if m.range().is_some() => "r_sigma",
            _ => "min_angle",
        }
    }
}

/// Per-facet component index (vertex-connected; numbered in the order of their first facet).
fn components(tris: &[[u32; 3]], n: usize) -> Vec<f64> {
    let mut parent: Vec<usize> = (0..n).collect();
    fn find(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
    for t in tris {
        let a = find(&mut parent, t[0] as usize);
        for &v in &t[1..] {
            let b = find(&mut parent, v as usize);
            if a != b {
                let (lo, hi) = (a.min(b), a.max(b));
                parent[hi] = lo;
            }
        }
    }
    let mut number = vec![usize::MAX; n];
    let mut next = 0usize;
    tris.iter()
        .map(|t| {
            let r = find(&mut parent, t[0] as usize);
            if number[r] == usize::MAX {
                number[r] = next;
                next += 1;
            }
            number[r] as f64
        })
        .collect()
}

/// The facets at boundary, non-manifold and misoriented edges, and those with a repeated
/// index, each with the verify check it fails.
fn topology_defects(tris: &[[u32; 3]]) -> Vec<(&'static str, Vec<usize>)> {
    // (lo, hi, facet, forward): sorted, so each edge's uses are adjacent.
    let mut uses: Vec<(u32, u32, usize, bool)> = Vec::with_capacity(3 * tris.len());
    let mut degenerate = Vec::new();
    for (f, t) in tris.iter().enumerate() {
        if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
            degenerate.push(f);
            continue;
        }
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            uses.push((a.min(b), a.max(b), f, a < b));
        }
    }
    uses.sort_unstable();
    let (mut boundary, mut nonmanifold, mut misoriented) = (Vec::new(), Vec::new(), Vec::new());
    for group in uses.chunk_by(|x, y| (x.0, x.1) == (y.0, y.1)) {
        let facets = group.iter().map(|u| u.2);
        match group.len() {
            1 => boundary.extend(facets),
            2 if group[0].3 == group[1].3 => misoriented.extend(facets),
            2 => {}
            _ => nonmanifold.extend(facets),
        }
    }
    vec![
        ("closed: facet at a boundary edge", boundary),
        ("edge-manifold: facet at an edge of 3+ facets", nonmanifold),
        ("oriented: facet at a misoriented edge", misoriented),
        ("degenerate-triangles: repeated index", degenerate),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tetra() -> TriMesh {
        TriMesh {
            vertices: vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z],
            triangles: vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
        }
    }

    #[test]
    fn closed_tetrahedron_has_no_highlight_and_one_component() {
        let s = Scene::new(&tetra(), "t").unwrap();
        assert!(s.highlights.is_empty(), "{:?}", s.highlights);
        assert_eq!(s.measure("component").unwrap().values, vec![0.0; 4]);
        let a = s.measure("min_angle").unwrap().range().unwrap();
        assert!(
            (a.0 - 45.0).abs() < 1e-9 && (a.1 - 60.0).abs() < 1e-9,
            "{a:?}"
        );
    }

    #[test]
    fn a_removed_facet_highlights_its_three_neighbours() {
        let mut m = tetra();
        m.triangles.pop();
        let s = Scene::new(&m, "t").unwrap();
        assert_eq!(s.highlights.len(), 1);
        assert_eq!(s.highlights[0].facets, vec![0, 1, 2]);
    }

    #[test]
    fn a_flipped_facet_and_a_bad_index_are_found() {
        let mut m = tetra();
        m.triangles[3] = [0, 2, 3];
        let s = Scene::new(&m, "t").unwrap();
        assert!(
            s.highlights
                .iter()
                .any(|h| h.reason.starts_with("oriented"))
        );
        m.triangles[0] = [0, 2, 9];
        let e = Scene::new(&m, "t").unwrap_err();
        assert!(e.0.contains("vertex 9"), "{e}");
    }
}
