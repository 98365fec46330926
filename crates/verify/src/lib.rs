//! Certificates for triangle meshes: what holds and what does not, for any triangle mesh.
//!
//! - [`check`]: combinatorics (closed, edge- and vertex-manifold, oriented, components, Euler
//!   characteristic and genus, duplicate/unreferenced vertices, degenerate triangles), exact
//!   self-intersections (BVH + `robust` predicates) and quality (angles, radius-edge ratios,
//!   area, enclosed volume).
//! - [`check_against`]: all of the above plus geometry against a surface oracle (mesh -> S and
//!   S -> mesh distances, two-sided Hausdorff estimate, normal deviation) and the paper's
//!   conditions (loose epsilon-sample certificate, vertices on every component, theorem 4.7).
//!
//! The result is a [`Report`] (serde, JSON) with one PASS/FAIL/INFO line per check
//! ([`Report::summary`]). Output is deterministic whatever the thread count.
//!
//! ```
//! use glam::DVec3;
//! use meshio::TriMesh;
//! // A tetrahedron, oriented outward.
//! let mesh = TriMesh {
//!     vertices: vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z],
//!     triangles: vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
//! };
//! let report = verify::check(&mesh, &verify::Options::default());
//! assert!(report.passed(), "{}", report.summary());
//! let topo = report.topology.as_ref().unwrap();
//! assert!(topo.is_closed_oriented_manifold());
//! assert_eq!(topo.genera(), vec![Some(0)]);
//! assert!((report.quality.as_ref().unwrap().volume - 1.0 / 6.0).abs() < 1e-15);
//! println!("{}", report.summary());
//! let json = report.to_json();
//! assert!(json.contains("\"closed\""));
//! ```

#![forbid(unsafe_code)]

use std::fmt;
use std::sync::Arc;

use glam::DVec3;
use meshio::TriMesh;
use oracle::Surface;
use serde::Serialize;

pub mod bvh;
pub mod certificate;
pub mod data_support;
pub mod distance;
pub mod grid_scan;
mod hypothesis;
pub mod intersect;
pub mod level_set;
pub mod medial;
pub mod quality;
pub mod scan_components;
pub mod scan_sim;
pub mod short_loops;
pub mod solid;
mod surface_checks;
#[cfg(test)]
mod test_meshes;
pub mod topology;

/// The exact predicates and intersection tests of the shared kernel ([`geom::predicates`]).
pub use geom::predicates;

pub use certificate::{
    ComponentCoverage, EpsilonCertificate, HausdorffBound, SeedCoverage, SurfaceBall,
};
pub use data_support::{DataSupport, SupportOptions};
pub use distance::{DistanceStats, Geometry, MeshDistance, NormalDeviation};
pub use intersect::SelfIntersections;
pub use medial::{MedialAxisEstimate, MedialError, estimate_dm};
pub use quality::Quality;
pub use topology::{Component, Topology};

/// A d_M function: point of S -> distance to the medial axis.
pub type DmFn = Arc<dyn Fn(DVec3) -> f64 + Send + Sync>;

/// Where the certificate takes d_M from.
#[derive(Clone, Default)]
pub enum DmSource {
    /// The surface's [`Surface::dm_inf_hint`] as a constant (a lower bound of d_M, so the
    /// achieved epsilon is an upper bound); the certificate is skipped without a hint.
    #[default]
    Auto,
    /// d_M = `value` everywhere (uniform sizing: d_M^inf); also used as d_M^sup.
    Constant(f64),
    /// A known d_M function and its supremum over S (e.g. `|x|` near the unit sphere, sup 1).
    Function { dm: DmFn, sup: f64 },
    /// Estimated by Voronoi poles ([`MedialAxisEstimate`]) from [`Options::dm_samples`], else
    /// the dense surface samples ([`Options::surface_samples`], unlabelled), else the mesh
    /// vertices.
    Poles,
}

impl fmt::Debug for DmSource {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DmSource::Auto => write!(f, "Auto"),
            DmSource::Constant(v) => write!(f, "Constant({v})"),
            DmSource::Function { sup, .. } => write!(f, "Function {{ sup: {sup} }}"),
            DmSource::Poles => write!(f, "Poles"),
        }
    }
}

/// What to check and how.
#[derive(Clone, Debug)]
pub struct Options {
    /// Run the exact self-intersection test (default true).
    pub self_intersections: bool,
    /// Angle histogram bin width in degrees (default 10).
    pub angle_bin_deg: f64,
    /// FAIL the angle check below this minimum angle (default: report only).
    pub min_angle_deg: Option<f64>,
    /// Lists in the report (boundary edges, pairs, ...) keep at most this many items.
    pub max_listed: usize,
    /// Mesh -> S samples: a barycentric grid with this many subdivisions per edge,
    /// (n+1)(n+2)/2 points per triangle (default 4: 15 points).
    pub samples_per_edge: usize,
    /// Dense samples of S for the S -> mesh distance (e.g. vertices of a much finer mesh).
    /// Default: projections of the mesh samples onto S (they miss unmeshed components).
    pub surface_samples: Option<Vec<DVec3>>,
    /// What `surface_samples` are, for the report (default: "N given samples"). Labelled
    /// samples serve the S -> mesh distances only: [`DmSource::Poles`] then estimates d_M
    /// from the mesh vertices.
    pub surface_samples_source: Option<String>,
    /// Samples of S for [`DmSource::Poles`] alone, when they must not serve the S -> mesh
    /// distances: the mesher's own sample E (the mesh's vertices, so every S -> mesh
    /// distance from them is about 0, a figure that measures nothing).
    pub dm_samples: Option<Vec<DVec3>>,
    /// FAIL the Hausdorff check above this distance (default: report only).
    pub max_hausdorff: Option<f64>,
    /// Requested epsilon of the loose epsilon-sample certificate.
    pub epsilon: Option<f64>,
    /// `epsilon` was not asked for but derived (the mesher's sigma / d_M^inf): at or above
    /// epsilon_1 (no theorem applies there) a facet over it makes the `loose-epsilon` check
    /// INFO "no guarantee", not FAIL (no guarantee was promised). Default false.
    pub epsilon_derived: bool,
    pub dm: DmSource,
    /// Surface Delaunay balls of the restricted facets (from the mesher). Default: computed
    /// from the mesh ([`certificate::surface_delaunay_balls`]).
    pub surface_balls: Option<Vec<SurfaceBall>>,
    /// Points on every component of S for condition 2 of definition 2.2.
    /// Default: `surface.seed_points(seed)`.
    pub component_seeds: Option<Vec<DVec3>>,
    pub seed: u64,
    /// A seed is covered if the mesh is within this distance. Default: twice the surface
    /// Delaunay ball radius of the facet nearest to the seed (the mesh's own scale there; see
    /// the `components-sampled` check).
    pub seed_tolerance: Option<f64>,
    /// Images: a point of each mesh piece removed by a stated rule (`--min-component`, or
    /// the mesher's repair dropping a sliver: a piece with no interior vertex); when no mesh
    /// vertex lies on their voxel-scan components, those count as dropped, not missed
    /// ([`scan_components::account`]).
    pub dropped_points: Vec<DVec3>,
    /// Images: of those removed pieces, a point of each that the repair removed as a sliver
    /// (not on request); listed here instead of in `dropped_points`, so that the accounting
    /// says which rule removed a component.
    pub sliver_points: Vec<DVec3>,
    /// Point sets and meshes: the triangles of the output's components removed because the
    /// input data does not support them (the mesher's `drop_unsupported_component`
    /// decisions). Such a component is a component of S (the point-set or winding-number
    /// surface) left out on purpose: a seed point of S within its tolerance of these
    /// triangles is on a dropped component, not on a missed one (`components-sampled`).
    pub dropped_triangles: Vec<[DVec3; 3]>,
    /// Told the name of each stage as it starts (`topology`, `self-intersections`,
    /// `quality`, `distances`, `certificate`, `components`): a front end's progress lines.
    /// Default: none.
    pub progress: Option<Progress>,
    /// Implicit functions: scan `f` on grids of this many nodes per axis and twice as fine
    /// ([`grid_scan`]; `grid_scan::DEFAULT_NODES` in `mesh` and `verify`): a point of S on
    /// each scan component joins the `components-sampled` seeds, and the `grid-genus` check
    /// compares the total genus. Ignored for images (their own voxel scan counts). Default
    /// `None`: no scan.
    pub grid_scan: Option<usize>,
}

/// A stage callback of [`Options::progress`].
#[derive(Clone)]
pub struct Progress(pub std::sync::Arc<dyn Fn(&str) + Send + Sync>);

impl std::fmt::Debug for Progress {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Progress(..)")
    }
}

impl Options {
    /// Tell [`Options::progress`] that `stage` starts.
    pub(crate) fn stage(&self, stage: &str) {
        if let Some(p) = &self.progress {
            (p.0)(stage);
        }
    }
}

impl Default for Options {
    fn default() -> Self {
        Options {
            self_intersections: true,
            angle_bin_deg: 10.0,
            min_angle_deg: None,
            max_listed: 20,
            samples_per_edge: 4,
            surface_samples: None,
            surface_samples_source: None,
            dm_samples: None,
            max_hausdorff: None,
            epsilon: None,
            epsilon_derived: false,
            dm: DmSource::Auto,
            surface_balls: None,
            component_seeds: None,
            seed: 0,
            seed_tolerance: None,
            dropped_points: Vec::new(),
            sliver_points: Vec::new(),
            dropped_triangles: Vec::new(),
            progress: None,
            grid_scan: None,
        }
    }
}

impl Options {
    /// The certificate of a two-pass run: `epsilon` checked against the second pass's surface
    /// Delaunay `balls`, with the first pass's vertices `first_pass` as the S -> mesh samples
    /// and d_M from their poles; every other option at its default.
    pub fn two_pass(epsilon: f64, balls: Vec<SurfaceBall>, first_pass: Vec<DVec3>) -> Options {
        Options {
            surface_samples: Some(first_pass),
            epsilon: Some(epsilon),
            dm: DmSource::Poles,
            surface_balls: Some(balls),
            ..Default::default()
        }
    }
}

/// Outcome of one check.
#[derive(Clone, Copy, Debug, Serialize, PartialEq, Eq)]
pub enum Status {
    #[serde(rename = "PASS")]
    Pass,
    #[serde(rename = "FAIL")]
    Fail,
    /// A measurement without a pass criterion.
    #[serde(rename = "INFO")]
    Info,
    /// Not run (reason in the detail).
    #[serde(rename = "SKIP")]
    Skipped,
}

impl fmt::Display for Status {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Status::Pass => "PASS",
            Status::Fail => "FAIL",
            Status::Info => "INFO",
            Status::Skipped => "SKIP",
        })
    }
}

/// One line of the summary.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Check {
    /// Stable name: `input`, `closed`, `edge-manifold`, `vertex-manifold`, `oriented`,
    /// `components`, `duplicate-vertices`, `degenerate-triangles`, `unreferenced-vertices`,
    /// `self-intersections`, `angles`, `radius-edge`, `area-volume`, `hausdorff`, `normals`,
    /// `loose-epsilon`, `components-sampled`, `scan-topology`, `scan-genus`, `theorem-4.7`,
    /// `data-support`, `input-topology`, `grid-genus`
    /// (the mesher's, for a closed input mesh).
    pub name: String,
    pub status: Status,
    pub detail: String,
}

/// Everything measured on a mesh. Sections are `None` when not run.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Report {
    pub vertices: usize,
    pub triangles: usize,
    /// Why the mesh was rejected (indices out of range, non-finite coordinates).
    pub input_error: Option<String>,
    pub topology: Option<Topology>,
    pub self_intersections: Option<SelfIntersections>,
    pub quality: Option<Quality>,
    pub geometry: Option<Geometry>,
    pub certificate: Option<EpsilonCertificate>,
    pub components_sampled: Option<ComponentCoverage>,
    /// Images: the mesh's pieces against the voxel scan's components.
    pub scan_components: Option<scan_components::ScanComponents>,
    pub hausdorff_bound: Option<HausdorffBound>,
    /// d_M was an estimate and the theorems' measured consequences failed: S is thinner
    /// than the estimate somewhere, and the theorem checks say "no guarantee" (or
    /// `loose-epsilon` FAILs when eps was asked for); see the `hypothesis` module.
    pub dm_estimate_contradicted: bool,
    /// Point-set and mesh inputs: the mesh against the input data ([`data_support`]).
    pub data_support: Option<DataSupport>,
    pub checks: Vec<Check>,
}

impl Report {
    /// No check failed.
    pub fn passed(&self) -> bool {
        self.checks.iter().all(|c| c.status != Status::Fail)
    }
    /// The check with this name.
    pub fn check(&self, name: &str) -> Option<&Check> {
        self.checks.iter().find(|c| c.name == name)
    }
    /// Status of the check with this name.
    pub fn status(&self, name: &str) -> Option<Status> {
        self.check(name).map(|c| c.status)
    }
    /// Names of the failed checks.
    pub fn failures(&self) -> Vec<&str> {
        self.checks
            .iter()
            .filter(|c| c.status == Status::Fail)
            .map(|c| c.name.as_str())
            .collect()
    }
    /// One line per check (`PASS closed: ...`) and a verdict line.
    pub fn summary(&self) -> String {
        let w = self.checks.iter().map(|c| c.name.len()).max().unwrap_or(0);
        let mut s = format!(
            "mesh: {} vertices, {} triangles\n",
            self.vertices, self.triangles
        );
        for c in &self.checks {
            s += &format!("{} {:<w$}  {}\n", c.status, c.name, c.detail);
        }
        let f = self.failures();
        if f.is_empty() {
            s += "verdict: PASS\n";
        } else {
            s += &format!("verdict: FAIL ({})\n", f.join(", "));
        }
        s
    }
    /// Pretty JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"))
    }
    /// Write [`Report::to_json`] to a file.
    pub fn write_json(&self, path: impl AsRef<std::path::Path>) -> std::io::Result<()> {
        std::fs::write(path, self.to_json())
    }

    pub(crate) fn push(&mut self, name: &str, status: Status, detail: String) {
        self.checks.push(Check {
            name: name.to_owned(),
            status,
            detail,
        });
    }
}

pub(crate) fn pass_fail(ok: bool) -> Status {
    if ok { Status::Pass } else { Status::Fail }
}

/// A check whose detail counts the offending items (`total`) and lists the first few.
fn push_listed<T: fmt::Debug>(
    r: &mut Report,
    name: &str,
    ok: bool,
    what: &str,
    (items, total): (&[T], usize),
) {
    r.push(
        name,
        pass_fail(ok),
        format!("{total} {what}{}", list(items, total)),
    );
}

fn list<T: fmt::Debug>(v: &[T], total: usize) -> String {
    if total == 0 {
        return String::new();
    }
    let more = if total > v.len() {
        format!(" (+{} more)", total - v.len())
    } else {
        String::new()
    };
    let shown: Vec<String> = v.iter().take(5).map(|x| format!("{x:?}")).collect();
    let more = if v.len() > 5 && more.is_empty() {
        format!(" (+{} more)", total - 5)
    } else {
        more
    };
    format!(": {}{more}", shown.join(" "))
}

/// Check a mesh on its own: combinatorics, self-intersections, quality.
///
/// ```
/// use glam::DVec3;
/// use meshio::TriMesh;
/// // One triangle: an open surface with 3 boundary edges.
/// let mesh = TriMesh { vertices: vec![DVec3::ZERO, DVec3::X, DVec3::Y], triangles: vec![[0, 1, 2]] };
/// let r = verify::check(&mesh, &verify::Options::default());
/// assert_eq!(r.status("closed"), Some(verify::Status::Fail));
/// assert_eq!(r.topology.unwrap().boundary_edges_total, 3);
/// ```
pub fn check(mesh: &TriMesh, opts: &Options) -> Report {
    run(mesh, None, opts)
}

/// Check a mesh against the surface it approximates: everything [`check`] does, plus the
/// distances between mesh and surface, normal deviation and the paper's conditions.
///
/// ```
/// use glam::DVec3;
/// use meshio::TriMesh;
/// use oracle::{BoundingSphere, Surface};
/// struct Plane; // z = 0, as seen from the unit ball around the origin
/// impl Surface for Plane {
///     fn bounding_sphere(&self) -> BoundingSphere { BoundingSphere { center: DVec3::ZERO, radius: 2.0 } }
///     fn value(&self, p: DVec3) -> f64 { p.z }
///     fn project(&self, p: DVec3) -> Option<DVec3> { Some(DVec3::new(p.x, p.y, 0.0)) }
/// }
/// let mesh = TriMesh {
///     vertices: vec![DVec3::new(0.0, 0.0, 0.1), DVec3::new(1.0, 0.0, 0.1), DVec3::new(0.0, 1.0, 0.1)],
///     triangles: vec![[0, 1, 2]],
/// };
/// let opts = verify::Options { component_seeds: Some(vec![DVec3::new(0.2, 0.2, 0.0)]), ..Default::default() };
/// let r = verify::check_against(&mesh, &Plane, &opts);
/// let g = r.geometry.as_ref().unwrap();
/// assert!((g.mesh_to_surface.max - 0.1).abs() < 1e-12);
/// assert!(g.normals.max_deg < 1e-6); // facet normal +z, gradient +z
/// println!("{}", r.summary());
/// ```
pub fn check_against(mesh: &TriMesh, surface: &dyn Surface, opts: &Options) -> Report {
    run(mesh, Some(surface), opts)
}

/// Read a mesh file (any format [`meshio`] reads) and [`check`] it.
pub fn check_file(
    path: impl AsRef<std::path::Path>,
    opts: &Options,
) -> Result<Report, meshio::MeshIoError> {
    Ok(check(&meshio::read(path)?, opts))
}

fn run(mesh: &TriMesh, surface: Option<&dyn Surface>, opts: &Options) -> Report {
    let mut r = Report {
        vertices: mesh.vertices.len(),
        triangles: mesh.triangles.len(),
        input_error: None,
        topology: None,
        self_intersections: None,
        quality: None,
        geometry: None,
        certificate: None,
        components_sampled: None,
        scan_components: None,
        hausdorff_bound: None,
        dm_estimate_contradicted: false,
        data_support: None,
        checks: Vec::new(),
    };
    if !input_checks(&mut r, mesh) {
        return r;
    }
    let ml = opts.max_listed;

    opts.stage("topology");
    topology_checks(&mut r, mesh, ml);

    opts.stage("self-intersections");
    let bvh = intersect::triangle_bvh(mesh);
    self_intersection_checks(&mut r, mesh, &bvh, opts);

    opts.stage("quality");
    quality_checks(&mut r, mesh, opts);
    solid_check(&mut r, mesh, &bvh);

    let Some(surface) = surface else {
        return r;
    };
    surface_checks::against(&mut r, mesh, &bvh, surface, opts);
    r
}

/// Reject malformed input (indices, empty mesh, coordinates outside the exact predicates'
/// range) with a FAIL `input` check; false if rejected.
fn input_checks(r: &mut Report, mesh: &TriMesh) -> bool {
    if let Err(e) = mesh.validate() {
        r.input_error = Some(e.to_string());
        r.push("input", Status::Fail, e.to_string());
        return false;
    }
    if mesh.triangles.is_empty() {
        r.input_error = Some("the mesh has no triangles".into());
        r.push("input", Status::Fail, "the mesh has no triangles".into());
        return false;
    }
    // Shewchuk's predicates are exact only if no intermediate product overflows or
    // underflows (the range Spade also enforces).
    let (hi, lo) = (2f64.powi(200), 2f64.powi(-140));
    if let Some((i, v)) = mesh.vertices.iter().enumerate().find(|(_, v)| {
        v.to_array()
            .iter()
            .any(|c| c.abs() > hi || (*c != 0.0 && c.abs() < lo))
    }) {
        let e = format!(
            "vertex {i} has a coordinate outside the range of exact predicates \
             (|x| in [2^-140, 2^200] or 0): ({}, {}, {}); rescale or translate the mesh",
            v.x, v.y, v.z
        );
        r.input_error = Some(e.clone());
        r.push("input", Status::Fail, e);
        return false;
    }
    r.push(
        "input",
        Status::Pass,
        "indices in range, coordinates finite and in range".into(),
    );
    true
}

/// The names of the checks that together say a mesh is a closed, oriented 2-manifold without
/// self-intersections (each must be [`Status::Pass`]).
pub const CLOSED_MANIFOLD_CHECKS: [&str; 5] = [
    "closed",
    "edge-manifold",
    "vertex-manifold",
    "oriented",
    "self-intersections",
];

/// Combinatorial checks (closed, manifold, oriented, components, degeneracies).
fn topology_checks(r: &mut Report, mesh: &TriMesh, ml: usize) {
    let t = topology::analyze(mesh, ml);
    let (closed, edge_ok, vertex_ok) =
        (t.is_closed(), t.is_edge_manifold(), t.is_vertex_manifold());
    let boundary = (&t.boundary_edges[..], t.boundary_edges_total);
    push_listed(r, "closed", closed, "boundary edges", boundary);
    let non_manifold = (&t.non_manifold_edges[..], t.non_manifold_edges_total);
    let what = "edges with more than 2 facets";
    push_listed(r, "edge-manifold", edge_ok, what, non_manifold);
    let umbrellas = (&t.non_manifold_vertices[..], t.non_manifold_vertices_total);
    let what = "vertices with more than one umbrella";
    push_listed(r, "vertex-manifold", vertex_ok, what, umbrellas);
    let non_orientable = t.components.iter().filter(|c| !c.orientable).count();
    r.push(
        "oriented",
        pass_fail(t.is_consistently_oriented()),
        format!(
            "{} interior edges used twice in the same direction{}{}",
            t.inconsistent_edges_total,
            list(&t.inconsistent_edges, t.inconsistent_edges_total),
            if non_orientable > 0 {
                format!("; {non_orientable} non-orientable components")
            } else {
                String::new()
            }
        ),
    );
    let genera: Vec<String> = t
        .components
        .iter()
        .map(|c| {
            format!(
                "chi={} genus={}",
                c.euler_characteristic,
                c.genus.map_or("-".to_string(), |g| g.to_string())
            )
        })
        .collect();
    let shown: Vec<String> = genera.iter().take(8).cloned().collect();
    r.push(
        "components",
        Status::Info,
        format!(
            "{} components [{}{}]",
            t.components.len(),
            shown.join("; "),
            if genera.len() > 8 { "; ..." } else { "" }
        ),
    );
    let duplicates = (&t.duplicate_vertices[..], t.duplicate_vertices_total);
    let (ok, what) = (duplicates.1 == 0, "vertices equal to an earlier one");
    push_listed(r, "duplicate-vertices", ok, what, duplicates);
    let degenerate = (&t.degenerate_triangles[..], t.degenerate_triangles_total);
    let ok = degenerate.1 == 0;
    let what = "triangles with a repeated index or collinear corners (exact)";
    push_listed(r, "degenerate-triangles", ok, what, degenerate);
    let short = (&t.short_edges[..], t.short_edges_total);
    let what = "edges shorter than 1e-9 of the bounding-box diagonal (numerically coincident \
                vertices: a refinement run away at a point; float32 files merge them)";
    push_listed(r, "short-edges", short.1 == 0, what, short);
    r.push(
        "unreferenced-vertices",
        if t.unreferenced_vertices_total == 0 {
            Status::Pass
        } else {
            Status::Info
        },
        format!(
            "{} vertices used by no triangle",
            t.unreferenced_vertices_total
        ),
    );
    r.topology = Some(t);
}

/// The exact self-intersection check (or SKIP when disabled).
fn self_intersection_checks(
    r: &mut Report,
    mesh: &TriMesh,
    bvh: &bvh::TriangleBvh,
    opts: &Options,
) {
    let ml = opts.max_listed;
    if opts.self_intersections {
        let si = intersect::self_intersections(mesh, bvh, ml);
        r.push(
            "self-intersections",
            pass_fail(si.pairs_total == 0),
            format!(
                "{} intersecting triangle pairs (exact; {} candidate pairs tested){}",
                si.pairs_total,
                si.candidate_pairs,
                list(&si.pairs, si.pairs_total)
            ),
        );
        r.self_intersections = Some(si);
    } else {
        r.push(
            "self-intersections",
            Status::Skipped,
            "disabled by options".into(),
        );
    }
}

/// `solid`: each component of a closed, consistently oriented manifold without
/// self-intersections bounds the solid on the side its facets face away from (see
/// [`solid`]). Before 2026-12-07 an inside-out mesh, or two nested spheres facing the same
/// way, passed `verify` (CGAL's `is_outward_oriented` fails the first).
fn solid_check(r: &mut Report, mesh: &TriMesh, bvh: &bvh::TriangleBvh) {
    let intersecting = r
        .self_intersections
        .as_ref()
        .is_some_and(|si| si.pairs_total > 0);
    let Some(t) = r
        .topology
        .as_ref()
        .filter(|t| t.is_closed_oriented_manifold() && !intersecting)
    else {
        r.push(
            "solid",
            Status::Info,
            "not measured: not a closed, consistently oriented manifold without \
             self-intersections"
                .into(),
        );
        return;
    };
    let (probed, wrong) = solid::wrong_sides(mesh, t, bvh);
    let detail = match wrong.first() {
        None => format!(
            "winding number 1 behind and 0 in front of each of the {probed} component(s) probed: \
             the facets face out of the solid"
        ),
        Some(w) => format!(
            "{} of {probed} component(s) face the wrong way: winding number {:.2} behind and \
             {:.2} in front of triangle {} at ({:.4}, {:.4}, {:.4}) (want 1 and 0: {}); reverse \
             the triangles of the components that face into the solid",
            wrong.len(),
            w.behind,
            w.in_front,
            w.probed_triangle,
            w.at.x,
            w.at.y,
            w.at.z,
            if w.behind.round() == 0.0 && w.in_front.round() == -1.0 {
                "inside out"
            } else {
                "nested in a component that faces the same way"
            }
        ),
    };
    r.push("solid", pass_fail(wrong.is_empty()), detail);
}

/// The triangles whose smallest angle is below `min_deg` (degenerate ones included) and the
/// centroid of the one with the smallest angle.
fn below_angle(mesh: &TriMesh, min_deg: f64) -> (usize, Option<DVec3>) {
    let (mut below, mut worst) = (0, (f64::INFINITY, None));
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| mesh.vertices[i as usize]);
        let smallest = quality::smallest_angle_deg(a, b, c);
        if smallest < min_deg {
            below += 1;
            if smallest < worst.0 {
                worst = (smallest, Some((a + b + c) / 3.0));
            }
        }
    }
    (below, worst.1)
}

/// Angle, radius-edge and area/volume checks.
fn quality_checks(r: &mut Report, mesh: &TriMesh, opts: &Options) {
    let q = quality::analyze(mesh, opts.angle_bin_deg);
    let angle_detail = format!(
        "min {:.3} deg, max {:.3} deg",
        q.min_angle_deg, q.max_angle_deg
    );
    match opts.min_angle_deg {
        Some(m) if q.min_angle_deg < m => {
            let (below, worst) = below_angle(mesh, m);
            let at = worst.map_or(String::new(), |c| {
                format!("; the smallest at ({:.4}, {:.4}, {:.4})", c.x, c.y, c.z)
            });
            r.push(
                "angles",
                Status::Fail,
                format!(
                    "{angle_detail} (required min >= {m}): {below} of {} triangles below{at}",
                    mesh.triangles.len()
                ),
            )
        }
        Some(m) => r.push(
            "angles",
            Status::Pass,
            format!("{angle_detail} (required min >= {m})"),
        ),
        None => r.push("angles", Status::Info, angle_detail),
    }
    r.push(
        "radius-edge",
        Status::Info,
        format!(
            "circumradius/shortest edge: min {:.4}, mean {:.4}, max {:.4}",
            q.radius_edge_min, q.radius_edge_mean, q.radius_edge_max
        ),
    );
    r.push(
        "area-volume",
        Status::Info,
        format!("area {:.6}, signed volume {:.6}", q.total_area, q.volume),
    );
    r.quality = Some(q);
}
