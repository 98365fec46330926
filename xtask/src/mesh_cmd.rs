//! `cargo xtask mesh`: mesh a surface, write the mesh, print a summary, write a JSON report.

use crate::surface_spec::{self, SurfaceOptions};
use anyhow::{Context, Result, bail};
use clap::ValueEnum;
use glam::DVec3;
use indicatif::{ProgressBar, ProgressStyle};
use rdt_mesher::{Criteria, MeshOptions, OracleKind, Sizing};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum OracleArg {
    Bipolar,
    Intersection,
}

#[derive(clap::Args, Debug, Clone)]
#[command(allow_negative_numbers = true)]
pub struct MeshArgs {
    /// Surface to mesh: `implicit:NAME` (catalog), `implicit:"EXPR"` (with --bounding-sphere),
    /// an image (.nii, .nii.gz, a folder of slices, .raw), a mesh (.ply .off .obj .stl) or a
    /// point set (.xyz, .ply without faces). Default: implicit:torus.
    pub input: Option<String>,
    /// Size bound sigma (constant), in the surface's units.
    #[arg(long, conflicts_with = "epsilon")]
    pub size: Option<f64>,
    /// Target epsilon: two-pass sizing (section 6.5): a uniform pass at sigma_0 = epsilon *
    /// d_M^inf, then an adaptive pass at sigma = 0.9 epsilon d_M (lambda-medial axis estimate).
    #[arg(long)]
    pub epsilon: Option<f64>,
    /// d_M^inf for --epsilon (default: the catalog's or the backend's value).
    #[arg(long)]
    pub dm_inf: Option<f64>,
    /// Initial sample: control points (6.4.3) or persistent facets (6.2).
    #[arg(long, value_enum, default_value = "control-points")]
    pub initialization: InitArg,
    /// Facet angle bound in degrees (0 = off).
    #[arg(long, default_value_t = 30.0)]
    pub angle: f64,
    /// Distance bound between a facet's circumcenter and its ball center (CGAL's distance_bound).
    #[arg(long)]
    pub distance: Option<f64>,
    /// Oracle: bipolar (sign change + one point) or intersection (all points).
    #[arg(long, value_enum, default_value = "bipolar")]
    pub oracle: OracleArg,
    /// Do not enforce a manifold output (section 6.6.1's patch is on by default).
    #[arg(long)]
    pub no_manifold: bool,
    /// Do not insert scaffold points inside the solid (an acceleration that leaves the
    /// output's guarantees unchanged; see docs/GUIDE.md).
    #[arg(long)]
    pub no_scaffold: bool,
    /// Seed for every random choice.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Stop at this many sample points (the mesh so far is written, unmet criteria reported).
    #[arg(long)]
    pub max_vertices: Option<usize>,
    /// Stop after this many seconds (likewise).
    #[arg(long)]
    pub time_limit: Option<f64>,
    /// Output mesh (.ply, .off, .obj, .stl). Default: out/NAME.ply.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Write a JSON report here.
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Bounding sphere `cx,cy,cz,r` for an expression.
    #[arg(long)]
    pub bounding_sphere: Option<String>,
    /// Start from this sample E_0 (`x y z` per line), section 6.4.1.
    #[arg(long)]
    pub initial_points: Option<PathBuf>,
    /// Skip the verification of the output (default: topology, self-intersections,
    /// quality, Hausdorff against the surface, loose-epsilon certificate).
    #[arg(long)]
    pub no_verify: bool,
    /// Exit with status 3 (after writing the mesh and the report) when the verification
    /// fails or a criterion is unmet: for scripts and regression suites.
    #[arg(long)]
    pub strict: bool,
    /// Requested epsilon for the certificate (default: sigma / d_M^inf when known).
    #[arg(long)]
    pub certify_epsilon: Option<f64>,
    /// No progress bar.
    #[arg(long, short)]
    pub quiet: bool,
    #[command(flatten)]
    pub surface: SurfaceOptions,
    /// Image: `all` meshes every label present except 0, one file per label
    /// (`NAME_label<L>.ply`, or -o's stem with `_label<L>`).
    #[arg(long, conflicts_with = "label")]
    pub labels: Option<String>,
}

/// `--labels all`: one run (and one output file) per label of the image.
fn run_labels(a: &MeshArgs, which: &str) -> Result<()> {
    let spec = a.input.clone().unwrap_or_default();
    if which != "all" {
        bail!("--labels {which}: only `--labels all` is supported; use --label L for one label");
    }
    let labels = surface_spec::image_labels(&spec, &a.surface)?;
    if labels.is_empty() {
        bail!("--labels all: {spec} has no label other than the background 0: nothing to mesh");
    }
    eprintln!("note: {} label(s) to mesh: {labels:?}", labels.len());
    for l in labels {
        let mut b = a.clone();
        b.labels = None;
        b.surface.label = Some(l);
        let out = a.output.clone().unwrap_or_else(|| {
            PathBuf::from(format!(
                "out/{}.ply",
                surface_spec::stem(std::path::Path::new(&spec))
            ))
        });
        let ext = out
            .extension()
            .map_or("ply".into(), |e| e.to_string_lossy().to_string());
        let stem = out
            .file_stem()
            .map_or("mesh".into(), |e| e.to_string_lossy().to_string());
        b.output = Some(out.with_file_name(format!("{stem}_label{l}.{ext}")));
        b.report = a
            .report
            .as_ref()
            .map(|r| r.with_extension(format!("label{l}.json")));
        run(&b).with_context(|| format!("label {l}"))?;
    }
    Ok(())
}

pub fn parse_vec3(s: &str, what: &str) -> Result<Vec<f64>> {
    s.split(',')
        .map(|t| {
            t.trim().parse::<f64>().with_context(|| {
                format!("{what}: '{t}' is not a number (expected comma-separated numbers)")
            })
        })
        .collect()
}

/// Set when a run prints a failed verdict (verification FAIL, unmet criteria, a budget hit):
/// with `--strict` the command then exits with status 3 (see `main`).
pub static VERDICT_FAILED: AtomicBool = AtomicBool::new(false);

/// The mesher's surface Delaunay balls in `verify`'s form (one per output triangle).
pub fn verify_balls(balls: &[rdt_mesher::SurfaceBall]) -> Vec<verify::SurfaceBall> {
    verify::SurfaceBall::per_facet(balls.iter().map(|b| (b.center, b.radius)))
}

pub fn read_xyz(path: &PathBuf) -> Result<Vec<DVec3>> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let mut pts = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let l = line.trim();
        if l.is_empty() || l.starts_with('#') {
            continue;
        }
        let v: Vec<f64> = l
            .split_whitespace()
            .take(3)
            .map(|t| t.parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|_| {
                anyhow::anyhow!(
                    "{}:{}: expected `x y z`, found '{l}'",
                    path.display(),
                    i + 1
                )
            })?;
        if v.len() < 3 || v.iter().any(|x| !x.is_finite()) {
            bail!(
                "{}:{}: expected three finite numbers `x y z`, found '{l}'",
                path.display(),
                i + 1
            );
        }
        pts.push(DVec3::new(v[0], v[1], v[2]));
    }
    Ok(pts)
}

pub fn run(a: &MeshArgs) -> Result<()> {
    if let Some(which) = &a.labels {
        return run_labels(a, which);
    }
    let spec = a
        .input
        .clone()
        .unwrap_or_else(|| "implicit:torus".to_string());
    let opened = surface_spec::open(&spec, a.bounding_sphere.as_deref(), &a.surface)?;
    let surface = opened.surface.as_ref();
    if let (None, Some(e)) = (a.size, a.epsilon) {
        return run_two_pass(a, &spec, &opened, e);
    }
    let mut notes = opened.notes.clone();
    let sigma = match (a.size, a.epsilon) {
        (Some(s), _) => {
            if !(s > 0.0 && s.is_finite()) {
                bail!("--size {s}: the size bound must be a positive number, e.g. --size 0.05");
            }
            s
        }
        (None, Some(e)) => {
            if !(e > 0.0 && e.is_finite()) {
                bail!("--epsilon {e}: epsilon must be a positive number, e.g. --epsilon 0.09");
            }
            let dm = opened
                .dm_inf()
                .context("--epsilon needs an estimate of d_M^inf, which this input does not provide; pass --size instead")?;
            notes.push(format!("sigma = {e} * d_M^inf ({dm:.4}) = {:.5}", e * dm));
            e * dm
        }
        (None, None) => match (opened.dm_inf(), opened.default_size) {
            (_, Some(d)) => {
                notes.push(format!(
                    "no --size: using the input's suggested size {d:.5}"
                ));
                d
            }
            (Some(dm), None) => {
                notes.push(format!(
                    "no --size: using sigma = 0.09 * d_M^inf = {:.5}",
                    0.09 * dm
                ));
                0.09 * dm
            }
            (None, None) => {
                let r = surface.bounding_sphere().radius / 20.0;
                notes.push(format!(
                    "no --size: using sigma = bounding radius / 20 = {r:.5}"
                ));
                r
            }
        },
    };
    let initial_points = match &a.initial_points {
        Some(p) => read_xyz(p)?,
        None => Vec::new(),
    };
    let opts = MeshOptions {
        criteria: Criteria {
            size: Some(Sizing::Constant(sigma)),
            min_angle_deg: a.angle,
            max_distance: a.distance,
        },
        oracle: match a.oracle {
            OracleArg::Bipolar => OracleKind::Bipolar,
            OracleArg::Intersection => OracleKind::Intersection,
        },
        manifold: !a.no_manifold,
        scaffold: !a.no_scaffold,
        seed: a.seed,
        max_vertices: a.max_vertices,
        time_limit: a.time_limit.map(Duration::from_secs_f64),
        initial_points,
        control_points: opened.control_points.clone(),
        initialization: a.initialization.into(),
        ..opened.mesh_defaults()
    };
    for n in &notes {
        eprintln!("note: {n}");
    }
    let bar = if a.quiet {
        ProgressBar::hidden()
    } else {
        let b = ProgressBar::new_spinner();
        b.set_style(ProgressStyle::with_template("{spinner} {elapsed} {msg}").unwrap());
        b.enable_steady_tick(Duration::from_millis(200));
        b
    };
    let result = rdt_mesher::mesh_with_progress(surface, &opts, &mut |p| {
        bar.set_message(format!(
            "{} points, {} restricted facets, queue {}",
            p.sample_points, p.restricted_facets, p.queue
        ))
    })
    .with_context(|| format!("meshing {spec}"))?;
    bar.finish_and_clear();
    let out_path = a
        .output
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("out/{}.ply", opened.name)));
    if let Some(dir) = out_path.parent()
        && !dir.as_os_str().is_empty()
    {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    }
    meshio::write(&out_path, &result.mesh)
        .with_context(|| format!("writing {}", out_path.display()))?;
    let st = &result.stats;
    if !opened.sharp_edges.is_empty() {
        // Sharp-edge deviation: the largest distance from the input's sharp edges to the output.
        let dev = oracle::polyhedron::PolyhedronSurface::new(&result.mesh).map(|out| {
            oracle::polyhedron::sharp_edge_deviation(&opened.sharp_edges, &out, sigma / 4.0)
        });
        let (lo, hi) = opened.sharp_edges.iter().fold(
            (DVec3::INFINITY, DVec3::NEG_INFINITY),
            |(lo, hi), &(a, b)| (lo.min(a).min(b), hi.max(a).max(b)),
        );
        let diag = result
            .mesh
            .vertices
            .iter()
            .fold((lo, hi), |(lo, hi), &v| (lo.min(v), hi.max(v)));
        let diag = (diag.1 - diag.0).length();
        let n = match dev {
            Ok(d) => format!(
                "sharp edges: {} input edges (normals > {} deg apart), largest distance to the output {d:.3e} ({:.3}% of the output's bbox diagonal)",
                opened.sharp_edges.len(),
                surface_spec::SHARP_DEG,
                100.0 * d / diag
            ),
            Err(e) => format!("sharp edges: deviation not measured ({e})"),
        };
        outln!("{n}");
        notes.push(n);
    }
    let check = if a.no_verify {
        None
    } else {
        bar.set_message("verifying");
        let balls = verify_balls(&result.balls);
        let vopts = verify::Options {
            samples_per_edge: 2,
            surface_balls: Some(balls),
            epsilon: a.certify_epsilon.or(opened.dm_inf().map(|d| sigma / d)),
            min_angle_deg: (a.angle > 0.0).then_some(a.angle - 1e-9),
            component_seeds: opened.control_points.clone(),
            seed: a.seed,
            ..Default::default()
        };
        Some(verify::check_against(&result.mesh, surface, &vopts))
    };
    let topo = check.as_ref().and_then(|c| c.topology.as_ref());
    let manifold = topo.map(|t| {
        t.boundary_edges_total == 0
            && t.non_manifold_edges_total == 0
            && t.non_manifold_vertices_total == 0
            && t.inconsistent_edges_total == 0
    });
    let genus: Vec<String> = topo
        .map(|t| {
            t.components
                .iter()
                .map(|c| c.genus.map_or("?".into(), |g| g.to_string()))
                .collect()
        })
        .unwrap_or_default();
    outln!(
        "{spec}: {} vertices, {} facets in {:.3} s (Delaunay {:.3} s, oracle {:.3} s); min angle {:.2} deg; max r/sigma {:.3}; {}; genus [{}]; wrote {}",
        st.vertices,
        st.facets,
        st.time_total_s,
        st.time_delaunay_s,
        st.time_oracle_s,
        st.min_angle_deg,
        st.max_r_over_sigma.unwrap_or(f64::NAN),
        match manifold {
            Some(true) => "closed manifold",
            Some(false) => "NOT a closed manifold",
            None => "not verified",
        },
        genus.join(", "),
        out_path.display()
    );
    if let (Some(scan), Some(t)) = (opened.components, topo)
        && t.components.len() < scan as usize
    {
        outln!(
            "warning: the mesh has {} of the {scan} surface components found by the voxel scan; components smaller than the size bound may be missed (try a smaller --size)",
            t.components.len()
        );
    }
    if let Some(c) = &check {
        if !c.passed() {
            outln!("verify: FAIL: {}", c.failures().join(", "));
            VERDICT_FAILED.store(true, Ordering::Relaxed);
        } else {
            outln!("verify: PASS ({} checks)", c.checks.len());
        }
    }
    if let Some(s) = &st.stopped_by {
        outln!("stopped by {s}; unmet: {}", st.unmet_summary());
    } else if !st.unmet.is_empty() {
        outln!("unmet: {}", st.unmet_summary());
    }
    if !st.unmet.is_empty() || st.stopped_by.is_some() {
        VERDICT_FAILED.store(true, Ordering::Relaxed);
    }
    if let Some(r) = &a.report {
        let report = serde_json::json!({
            "input": spec,
            "output": out_path,
            "sigma": sigma,
            "angle": a.angle,
            "distance": a.distance,
            "oracle": format!("{:?}", a.oracle).to_lowercase(),
            "manifold": !a.no_manifold,
            "scaffold": !a.no_scaffold,
            "initialization": a.initialization.name(),
            "seed": a.seed,
            "notes": notes,
            "stats": st,
            "verify": check,
        });
        std::fs::write(r, serde_json::to_string_pretty(&report)?)
            .with_context(|| format!("cannot write report {}", r.display()))?;
    }
    Ok(())
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum InitArg {
    ControlPoints,
    PersistentFacets,
}

impl InitArg {
    /// The option's value, as given on the command line.
    fn name(self) -> &'static str {
        match self {
            InitArg::ControlPoints => "control-points",
            InitArg::PersistentFacets => "persistent-facets",
        }
    }
}

impl From<InitArg> for rdt_mesher::Initialization {
    fn from(a: InitArg) -> Self {
        match a {
            InitArg::ControlPoints => rdt_mesher::Initialization::ControlPoints,
            InitArg::PersistentFacets => rdt_mesher::Initialization::PersistentFacets,
        }
    }
}

/// `--epsilon E` (without --size): the two-pass mode of section 6.5.
fn run_two_pass(a: &MeshArgs, spec: &str, opened: &surface_spec::Opened, e: f64) -> Result<()> {
    if !(e > 0.0 && e < 1.0) {
        bail!("--epsilon {e}: epsilon must be in (0, 1), e.g. --epsilon 0.09");
    }
    let dm = match (a.dm_inf, opened.dm_inf()) {
        (Some(d), _) if d > 0.0 && d.is_finite() => d,
        (Some(d), _) => bail!("--dm-inf {d}: must be a positive number"),
        (None, Some(d)) => d,
        (None, None) => bail!(
            "--epsilon needs d_M^inf, which {spec} does not provide: pass --dm-inf VALUE \
             (`cargo xtask paper-table` prints estimates) or use --size"
        ),
    };
    let surface = opened.surface.as_ref();
    for n in &opened.notes {
        eprintln!("note: {n}");
    }
    let base = MeshOptions {
        criteria: Criteria {
            size: None,
            min_angle_deg: a.angle,
            max_distance: a.distance,
        },
        oracle: match a.oracle {
            OracleArg::Bipolar => OracleKind::Bipolar,
            OracleArg::Intersection => OracleKind::Intersection,
        },
        manifold: !a.no_manifold,
        scaffold: !a.no_scaffold,
        seed: a.seed,
        max_vertices: a.max_vertices,
        time_limit: a.time_limit.map(Duration::from_secs_f64),
        initial_points: match &a.initial_points {
            Some(p) => read_xyz(p)?,
            None => Vec::new(),
        },
        control_points: opened.control_points.clone(),
        initialization: a.initialization.into(),
        ..opened.mesh_defaults()
    };
    let tp = rdt_mesher::sizing::two_pass(surface, e, dm, &base, &mut |_| {})
        .with_context(|| format!("meshing {spec} (two passes)"))?;
    let (s1, s2) = (&tp.first.stats, &tp.second.stats);
    outln!(
        "{spec}: first pass (sigma_0 = {e} * {dm} = {:.5}): {} vertices in {:.3} s; second pass \
         (sigma = max({:.5}, {:.4} d_M)): {} vertices, {} facets in {:.3} s (Delaunay {:.3} s, \
         oracle {:.3} s); ratio {:.2}; {} medial vertices",
        tp.sigma0,
        s1.vertices,
        s1.time_total_s,
        tp.floor,
        tp.eps_prime,
        s2.vertices,
        s2.facets,
        s2.time_total_s,
        s2.time_delaunay_s,
        s2.time_oracle_s,
        s1.vertices as f64 / s2.vertices.max(1) as f64,
        tp.medial.len()
    );
    if tp.dm_inf_estimate < 0.9 * dm {
        outln!(
            "note: the first pass's d_M estimate has minimum {:.4} < d_M^inf = {dm}: the first \
             pass is not a uniform {e}-sample (pass a smaller --dm-inf); the second pass \
             follows the estimate",
            tp.dm_inf_estimate
        );
    }
    let out_path = a
        .output
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("out/{}.ply", opened.name)));
    if let Some(dir) = out_path.parent()
        && !dir.as_os_str().is_empty()
    {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    }
    meshio::write(&out_path, &tp.second.mesh)
        .with_context(|| format!("writing {}", out_path.display()))?;
    let check = (!a.no_verify).then(|| {
        let balls = verify_balls(&tp.second.balls);
        let vopts = verify::Options {
            samples_per_edge: 2,
            surface_balls: Some(balls),
            epsilon: Some(a.certify_epsilon.unwrap_or(e)),
            dm: verify::DmSource::Poles,
            surface_samples: Some(tp.first.mesh.vertices.clone()),
            min_angle_deg: (a.angle > 0.0).then_some(a.angle - 1e-9),
            component_seeds: opened.control_points.clone(),
            seed: a.seed,
            ..Default::default()
        };
        verify::check_against(&tp.second.mesh, surface, &vopts)
    });
    if let Some(c) = &check {
        if let Some(l) = c.check("loose-epsilon") {
            outln!(
                "loose-epsilon (d_M by Voronoi poles of the first pass): {}",
                l.detail
            );
        }
        if c.passed() {
            outln!(
                "verify: PASS ({} checks); wrote {}",
                c.checks.len(),
                out_path.display()
            );
        } else {
            outln!("verify: FAIL: {}", c.failures().join(", "));
            VERDICT_FAILED.store(true, Ordering::Relaxed);
        }
    }
    for (name, st) in [("first", s1), ("second", s2)] {
        if let Some(s) = &st.stopped_by {
            outln!("{name} pass stopped by {s}; unmet: {}", st.unmet_summary());
            VERDICT_FAILED.store(true, Ordering::Relaxed);
        }
    }
    if let Some(r) = &a.report {
        let report = serde_json::json!({
            "input": spec, "output": out_path, "epsilon": e, "dm_inf": dm,
            "initialization": a.initialization.name(),
            "sigma0": tp.sigma0, "eps_prime": tp.eps_prime,
            "first": s1, "second": s2, "verify": check,
        });
        std::fs::write(r, serde_json::to_string_pretty(&report)?)
            .with_context(|| format!("cannot write report {}", r.display()))?;
    }
    Ok(())
}
