//! `cargo xtask mesh`: mesh a surface, write the mesh, print a summary, write a JSON report.
//! The policy (default size, two passes, verification, verdict) is `rdt_mesher::pipeline`'s.

use super::output::{epsilon, parse_angle, positive};
use crate::cli::input::{self, SurfaceOptions, cli_error};
use crate::cli::mesh_report;
use anyhow::{Context, Result, bail};
use clap::builder::{PossibleValuesParser, TypedValueParser};
use indicatif::{ProgressBar, ProgressStyle};
use rdt_mesher::pipeline::{self, Event, Failure, Outcome, Request, SizeRequest, Verdict};
use rdt_mesher::{Initialization, OracleKind};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// A clap parser of a library enum spelled by its `name()`s (the library's one spelling).
fn names<T: std::str::FromStr + Clone + Send + Sync + 'static>(
    names: [&'static str; 2],
) -> impl TypedValueParser<Value = T> {
    PossibleValuesParser::new(names).map(|s| {
        s.parse::<T>()
            .unwrap_or_else(|_| unreachable!("a possible value parses"))
    })
}

/// Shown after the flags of `mesh --help`.
const AFTER_HELP: &str = "The three size and shape criteria are CGAL's and pygalmesh's: --size is \
CGAL's radius_bound (Mesh_3: facet_size), pygalmesh's max_radius_surface_delaunay_ball; --angle \
is angular_bound / facet_angle, pygalmesh's min_facet_angle; --distance is distance_bound / \
facet_distance, pygalmesh's max_facet_distance. The full table: docs/GUIDE.md, \"CGAL / pygalmesh \
parameter names\". Without --size, the size and the forecast printed before meshing are \
explained in docs/GUIDE.md, \"Default size, forecast and budgets\".";

#[derive(clap::Args, Debug, Clone)]
#[command(allow_negative_numbers = true, after_help = AFTER_HELP)]
pub struct MeshArgs {
    /// Surface to mesh: `implicit:NAME` (catalog), `implicit:"EXPR"` (with --bounding-sphere),
    /// an image (.nii, .nii.gz, .nrrd, .nhdr, .mha, .mhd, .zarr, a folder of slices, .raw), a
    /// mesh (.ply .off .obj .stl .glb .vtk .vtp .gii) or a
    /// point set (.xyz, .ply without faces). Default: implicit:torus.
    pub input: Option<String>,
    /// Target facet size: the largest radius of a facet's surface Delaunay ball (about the
    /// edge length), in the surface's units; smaller is finer, vertices grow as 1 / size^2.
    /// CGAL: radius_bound (facet_size); pygalmesh: max_radius_surface_delaunay_ball; the
    /// paper's sigma. Default: chosen from a forecast (docs/GUIDE.md).
    #[arg(long, allow_hyphen_values = true, conflicts_with = "epsilon", value_parser = positive("--size", "the size bound", "0.05"))]
    pub size: Option<f64>,
    /// Adaptive size in (0, 1): finer where the surface is curved or close to itself, in two
    /// passes (a uniform pass at epsilon times the smallest feature size, then sizes of 0.9
    /// epsilon times the local feature size; the paper's section 6.5, d_M^inf and d_M). On a
    /// mesh without --dm-inf: its smooth approximation, as --smooth-polyhedron (the triangles
    /// have no eps-sample).
    #[arg(long, allow_hyphen_values = true, value_parser = epsilon("--epsilon"))]
    pub epsilon: Option<f64>,
    /// The smallest feature size (the paper's d_M^inf: the least distance from the surface to
    /// its medial axis), for --epsilon (default: the catalog's or the backend's value).
    #[arg(long, allow_hyphen_values = true, value_parser = positive("--dm-inf", "d_M^inf", "0.3"))]
    pub dm_inf: Option<f64>,
    /// With --epsilon: adaptive rounds on one triangulation, d_M estimated from each round's
    /// sample, no uniform pass and no d_M^inf (the default when the input knows no d_M^inf).
    #[arg(long, requires = "epsilon", conflicts_with = "dm_inf")]
    pub adaptive: bool,
    /// Initial sample: control points (6.4.3) or persistent facets (6.2).
    #[arg(long, default_value = "control-points", value_parser = names::<Initialization>(Initialization::ALL.map(Initialization::name)))]
    pub initialization: Initialization,
    /// Smallest facet angle in degrees, in [0, 35) (0 = off; 30, the default, has a
    /// termination proof). CGAL: angular_bound (facet_angle); pygalmesh: min_facet_angle.
    #[arg(long, allow_hyphen_values = true, default_value_t = 30.0, value_parser = parse_angle)]
    pub angle: f64,
    /// Largest distance from a facet's circumcenter to the surface (to its surface Delaunay
    /// ball's center), in the surface's units. CGAL: distance_bound (facet_distance);
    /// pygalmesh: max_facet_distance.
    #[arg(long, allow_hyphen_values = true, value_parser = positive("--distance", "the distance bound", "0.01"))]
    pub distance: Option<f64>,
    /// Oracle: bipolar (sign change + one point) or intersection (all points).
    #[arg(long, default_value = "bipolar", value_parser = names::<OracleKind>(OracleKind::ALL.map(OracleKind::name)))]
    pub oracle: OracleKind,
    /// Do not enforce a manifold output (section 6.6.1's patch is on by default).
    #[arg(long)]
    pub no_manifold: bool,
    /// Do not insert scaffold points inside the solid (an acceleration that leaves the
    /// output's guarantees unchanged; see docs/GUIDE.md).
    #[arg(long)]
    pub no_scaffold: bool,
    /// Seed for every random choice.
    #[arg(long, default_value_t = 0, allow_hyphen_values = true)]
    pub seed: u64,
    /// Vertex budget: stop at this many sample points (the mesh so far is written, unmet
    /// criteria reported). Default 2,000,000, and then a --size or --epsilon forecasting more
    /// is refused before meshing.
    #[arg(long, allow_hyphen_values = true, value_parser = super::output::parse_max_vertices)]
    pub max_vertices: Option<usize>,
    /// Memory budget, e.g. 2G or 500M (binary units; default 4G): a --size or --epsilon
    /// whose forecast needs more is refused before meshing, and the run stops at the vertex
    /// count it affords.
    #[arg(long, allow_hyphen_values = true, value_parser = super::output::parse_memory)]
    pub max_memory: Option<u64>,
    /// Stop after this many seconds (the mesh so far is written, unmet criteria reported).
    #[arg(long, value_parser = super::output::parse_seconds)]
    pub time_limit: Option<f64>,
    /// Output mesh (.ply, .off, .obj, .stl, .glb, .vtk, .vtp, .gii; .vtk and .vtp carry the
    /// per-facet min angle and r/sigma as cell data). Default: out/NAME.ply.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Write a JSON report here.
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Bounding sphere `cx,cy,cz,r` for an expression.
    #[arg(long, allow_hyphen_values = true)]
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
    /// Drop closed components of the output enclosing less than this volume (the surface's
    /// units cubed, e.g. mm^3), each listed in the report's topology_decisions.
    #[arg(long, value_name = "VOLUME", allow_hyphen_values = true, value_parser = parse_volume)]
    pub min_component: Option<f64>,
    /// Point sets and meshes: keep the output's components that the input data does not
    /// support (the raw mesh of the IMLS surface). By default such a component is dropped
    /// when no data is lost (docs/GUIDE.md, "Point sets and scans"), printed and listed in
    /// the report's topology_decisions and verify.data_support.dropped_components.
    #[arg(long)]
    pub keep_unsupported: bool,
    /// Requested epsilon for the certificate, in (0, 1) (default: sigma / d_M^inf when known).
    #[arg(long, allow_hyphen_values = true, value_parser = epsilon("--certify-epsilon"))]
    pub certify_epsilon: Option<f64>,
    /// No progress bar.
    #[arg(long, short)]
    pub quiet: bool,
    #[command(flatten)]
    pub surface: SurfaceOptions,
    #[command(flatten)]
    pub pictures: super::view::PictureArgs,
    /// Write the HTML viewer of the mesh (one self-contained page; default name: the mesh's
    /// with .html).
    #[arg(long, value_name = "FILE.html", num_args = 0..=1, default_missing_value = "")]
    pub html: Option<String>,
    /// Image: `all` meshes every label present except 0, one file per label
    /// (`NAME_label<L>.ply`, or -o's stem with `_label<L>`).
    #[arg(long, conflicts_with_all = ["label", "iso"])]
    pub labels: Option<String>,
}

/// `--min-component`: a positive, finite volume.
fn parse_volume(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!(
            "--min-component {s}: give a positive, finite volume in the surface's units cubed, e.g. --min-component 8"
        )),
    }
}

/// `--labels all`: one run (and one output file) per label of the image.
fn run_labels(a: &MeshArgs, which: &str) -> Result<Verdict> {
    let spec = a.input.clone().unwrap_or_default();
    if which != "all" {
        bail!("--labels {which}: only `--labels all` is supported; use --label L for one label");
    }
    // Read once: each label is meshed on the crop of its bounding box.
    let image = input::label_image(&spec, &a.surface)?;
    let labels = image.labels();
    if labels.is_empty() {
        bail!("--labels all: {spec} has no label other than the background 0: nothing to mesh");
    }
    let list: Vec<String> = labels.iter().take(20).map(|l| l.to_string()).collect();
    let n = labels.len();
    eprintln!(
        "note: {n} label(s) to mesh: {}{}",
        list.join(", "),
        if n > 20 { ", ..." } else { "" }
    );
    let mut failures = Vec::new();
    // A label that cannot be meshed (a budget, an oracle error) is reported and the others
    // are meshed: one line each, and the run's exit status says so at the end.
    let mut errors: Vec<String> = Vec::new();
    for (i, l) in labels.into_iter().enumerate() {
        if n > 1 {
            eprintln!("label {l} ({} of {n})", i + 1);
        }
        let mut b = a.clone();
        b.labels = None;
        b.surface.label = Some(l);
        let out = a.output.clone().unwrap_or_else(|| {
            PathBuf::from(format!("out/{}.ply", pipeline::stem(Path::new(&spec))))
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
        b.pictures.picture = a
            .pictures
            .picture
            .as_ref()
            .map(|r| r.with_extension(format!("label{l}.png")));
        b.html = a.html.as_ref().map(|h| match h.as_str() {
            "" => String::new(),
            h => Path::new(h)
                .with_extension(format!("label{l}.html"))
                .display()
                .to_string(),
        });
        match run_with(&b, Some(&image)) {
            Ok(Verdict::Fail(f)) => failures.extend(f),
            Ok(_) => {}
            Err(e) => {
                eprintln!("error: label {l}: {e:#}");
                errors.push(l.to_string());
            }
        }
    }
    if !errors.is_empty() {
        bail!(
            "--labels all: {} of {n} label(s) not meshed ({}{}); each error is above, the other \
             labels' meshes are written",
            errors.len(),
            errors
                .iter()
                .take(20)
                .cloned()
                .collect::<Vec<_>>()
                .join(", "),
            if errors.len() > 20 { ", ..." } else { "" }
        );
    }
    Ok(if failures.is_empty() {
        Verdict::Pass
    } else {
        Verdict::Fail(failures)
    })
}

/// The library's request from the flags.
fn request(a: &MeshArgs) -> Result<Request> {
    Ok(Request {
        size: match (a.size, a.epsilon) {
            (Some(s), _) => SizeRequest::Size(s),
            (None, Some(e)) if a.adaptive => SizeRequest::Adaptive { epsilon: e },
            (None, Some(e)) => SizeRequest::Epsilon {
                epsilon: e,
                dm_inf: a.dm_inf,
            },
            (None, None) => SizeRequest::Auto,
        },
        min_angle_deg: a.angle,
        max_distance: a.distance,
        oracle: a.oracle,
        manifold: !a.no_manifold,
        scaffold: !a.no_scaffold,
        initialization: a.initialization,
        seed: a.seed,
        max_vertices: a.max_vertices,
        max_memory: a.max_memory,
        time_limit: a.time_limit.map(Duration::from_secs_f64),
        initial_points: match &a.initial_points {
            Some(p) => crate::cli::points::read_xyz(p)?,
            None => Vec::new(),
        },
        verify: !a.no_verify,
        certify_epsilon: a.certify_epsilon,
        min_component: a.min_component,
        keep_unsupported: a.keep_unsupported,
        cancel: None,
    })
}

/// Mesh, write, print; the verdict decides `--strict`'s exit status (see `main`).
pub fn run(a: &MeshArgs) -> Result<Verdict> {
    if let Some(which) = &a.labels {
        return run_labels(a, which);
    }
    run_with(a, None)
}

/// [`run`] of one input: `a`'s, or label `a.surface.label` of `labels`, read already.
fn run_with(a: &MeshArgs, labels: Option<&pipeline::LabelImage>) -> Result<Verdict> {
    let spec = a
        .input
        .clone()
        .unwrap_or_else(|| "implicit:torus".to_string());
    let req = request(a)?;
    // A mesh under an --epsilon that estimates d_M: its smooth approximation (the plan
    // refuses the exact triangles, which have d_M = 0 at their edges; a note says so).
    let surface = SurfaceOptions {
        smooth_polyhedron: a.surface.smooth_polyhedron || req.size.estimates_dm(),
        ..a.surface.clone()
    };
    let bs = a.bounding_sphere.as_deref();
    let opened = match labels {
        Some(li) => input::label_input(li, &spec, bs, &surface)?,
        None => input::open(&spec, bs, &surface)?,
    };
    let out_path = a
        .output
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("out/{}.ply", opened.name)));
    let html_path = a.html.as_ref().map(|h| {
        if h.is_empty() {
            out_path.with_extension("html")
        } else {
            PathBuf::from(h)
        }
    });
    let mut outputs = vec![("-o", out_path.as_path())];
    if let Some(r) = &a.report {
        outputs.push(("--report", r.as_path()));
    }
    if let Some(p) = &a.pictures.picture {
        super::view::check_extension("--picture", p, "png")?;
        outputs.push(("--picture", p.as_path()));
    }
    if let Some(h) = &html_path {
        super::view::check_extension("--html", h, "html")?;
        outputs.push(("--html", h.as_path()));
    }
    super::output::check_outputs(Some(Path::new(&spec)), &outputs)?;
    let plan = pipeline::plan(&opened, &req).map_err(|e| cli_error(e, &spec))?;
    for n in plan.notes() {
        eprintln!("note: {n}");
    }
    let forecast = plan.forecast().copied();
    let budgets = *plan.budgets();
    if let Some(f) = &forecast {
        eprintln!("forecast: {f}");
    }
    let bar = if a.quiet || plan.two_pass().is_some() {
        ProgressBar::hidden()
    } else {
        let b = ProgressBar::new_spinner();
        b.set_style(ProgressStyle::with_template("{spinner} {elapsed} {msg}").unwrap());
        b.enable_steady_tick(Duration::from_millis(200));
        b
    };
    let out = plan
        .execute(&mut |e| match e {
            Event::Meshing(p) => bar.set_message(format!(
                "{} points, {} restricted facets, queue {}",
                p.sample_points, p.restricted_facets, p.queue
            )),
            Event::Verifying => bar.set_message("verifying"),
            Event::Round(r) => {
                bar.suspend(|| eprintln!("{}", super::mesh_adaptive::round_line(&r)))
            }
        })
        .map_err(|e| cli_error(e, &spec))?;
    bar.finish_and_clear();
    for n in &out.size_halvings {
        eprintln!("note: {n}");
    }
    if out.mesh.triangles.is_empty() {
        bail!(
            "{spec}: the mesh is empty ({} sample points, no facet on the surface); nothing written. \
             An open or flat input mesh bounds no solid: close it, or mesh its vertices with \
             --as points; for other inputs check --iso / --label or try a smaller --size",
            out.stats.sample_points
        );
    }
    if out.two_pass.is_some() {
        print_two_pass(&spec, &out);
    }
    if out.adaptive.is_some() {
        outln!("{}", super::mesh_adaptive::summary(&spec, &out));
    }
    write_mesh(&out_path, &out)?;
    if out.two_pass.is_some() {
        print_two_pass_verdict(&out, &out_path);
    } else {
        print_single(&spec, &out, &out_path);
        // (After a halving the forecast is the suggested size's, not the size's.)
        let forecast = forecast.filter(|_| out.size_halvings.is_empty());
        if let Some(n) = forecast.and_then(|f| f.overshoot(out.mesh.vertices.len())) {
            eprintln!("note: {n}");
        }
    }
    if let Some(r) = &a.report {
        let report = mesh_report::mesh_report(
            &spec,
            &out_path,
            &opened,
            forecast.as_ref(),
            &budgets,
            &req,
            &out,
        );
        write_json(r, &report)?;
    }
    write_views(a, &spec, opened.kind, &out, html_path.as_deref())?;
    Ok(out.verdict)
}

/// `--picture` and `--html`: the mesh with the mesher's balls (r/sigma, distance), its
/// verification and unmet criteria.
fn write_views(
    a: &MeshArgs,
    spec: &str,
    kind: pipeline::InputKind,
    out: &Outcome,
    html: Option<&Path>,
) -> Result<()> {
    if a.pictures.picture.is_none() && html.is_none() {
        return Ok(());
    }
    let report = if out.two_pass.is_some() {
        serde_json::json!({"second": out.stats, "verify": out.report, "angle": a.angle})
    } else {
        serde_json::json!({"sigma": out.sigma, "stats": out.stats, "verify": out.report, "angle": a.angle})
    };
    // The mesher's balls are in facet order.
    let balls: Vec<geom::SurfaceBall> = (out.balls.iter().enumerate())
        .map(|(facet, b)| geom::SurfaceBall {
            facet,
            center: b.center,
            radius: b.radius,
        })
        .collect();
    let scene = super::view::scene(super::view::Known {
        title: spec.to_string(),
        mesh: &out.mesh,
        balls: Some(&balls),
        sigma: out.sigma,
        angle_bound: Some(a.angle),
        report: Some(report),
        up: a.pictures.up.unwrap_or(super::view::default_up(Some(kind))),
    })?;
    if let Some(p) = &a.pictures.picture {
        super::view::write_picture(p, &scene, a.pictures.picture_color.as_deref())?;
        outln!("wrote {}", p.display());
    }
    if let Some(h) = html {
        super::view::write_html(h, &scene)?;
        outln!("wrote {}", h.display());
    }
    Ok(())
}

fn write_mesh(out_path: &Path, out: &Outcome) -> Result<()> {
    let cells = facet_quality(out);
    super::output::write_atomically(out_path, |tmp| {
        meshio::write_with_cell_data(tmp, &out.mesh, &cells)
            .with_context(|| format!("writing {}", out_path.display()))
    })
}

/// Per-facet quality for the formats that store cell data (`.vtk`, `.vtp`): the smallest
/// angle in degrees, and the surface Delaunay ball's radius over sigma when the run had one
/// constant sigma.
fn facet_quality(out: &Outcome) -> Vec<meshio::CellData> {
    let m = &out.mesh;
    let angle = m
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| m.vertices[i as usize]);
            verify::quality::triangle_shape(a, b, c).map_or(0.0, |(ang, _, _)| {
                ang.iter()
                    .fold(f64::INFINITY, |x, &y| x.min(y))
                    .to_degrees()
            })
        })
        .collect();
    let mut cells = vec![meshio::CellData {
        name: "min_angle_deg".into(),
        values: angle,
    }];
    if let Some(sigma) = out.sigma.filter(|_| out.balls.len() == m.triangles.len()) {
        cells.push(meshio::CellData {
            name: "r_over_sigma".into(),
            values: out.balls.iter().map(|b| b.radius / sigma).collect(),
        });
    }
    cells
}

/// Write a JSON report atomically (also `verify --report`).
pub(super) fn write_json(r: &Path, report: &serde_json::Value) -> Result<()> {
    let text = serde_json::to_string_pretty(report)?;
    super::output::write_atomically(r, |tmp| {
        std::fs::write(tmp, &text).with_context(|| format!("cannot write report {}", r.display()))
    })
}

/// The lines of a constant-size run.
fn print_single(spec: &str, out: &Outcome, out_path: &Path) {
    if let Some(s) = &out.sharp_edges {
        outln!("{s}");
    }
    let st = &out.stats;
    let topo = out.report.as_ref().and_then(|c| c.topology.as_ref());
    let manifold = topo.map(|t| {
        t.boundary_edges_total == 0
            && t.non_manifold_edges_total == 0
            && t.non_manifold_vertices_total == 0
            && t.inconsistent_edges_total == 0
    });
    let genus = topo.map_or("genus not measured (--no-verify)".into(), |t| {
        let g = mesh_report::genus_summary(&t.genera());
        match t.components.len() {
            1 => format!("genus {g}"),
            n => format!("{n} components, genus {g}"),
        }
    });
    outln!(
        "{spec}: {} vertices, {} facets in {:.3} s (Delaunay {:.3} s, oracle {:.3} s); min angle {:.2} deg; max r/sigma {:.3}; {}; {genus}; wrote {}",
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
        out_path.display()
    );
    if let Some(acc) = out.report.as_ref().and_then(|r| r.scan_components.as_ref())
        && (acc.split
            + acc.joined
            + acc.missed
            + acc.dropped
            + acc.vanishing
            + acc.unassigned_pieces
            > 0)
    {
        outln!(
            "components: {}{} (each listed with a point on it in the report's verify.scan_components)",
            acc.summary(),
            if acc.missed + acc.split > 0 {
                "; parts thinner than the size bound are split or missed: try a smaller --size"
            } else {
                ""
            }
        );
    }
    print_dropped(out);
    print_cut_handles(out);
    if let Some(line) = out.verify_line() {
        outln!("{line}");
    }
    print_data_failures(out);
    if let Some(s) = &st.stopped_by {
        outln!("stopped by {s}; unmet: {}", unmet(st));
    } else if !st.unmet.is_empty() {
        outln!("unmet: {}", unmet(st));
    }
}

/// The components dropped as unsupported by the input data (`pipeline`'s rule; kept with
/// `--keep-unsupported`), one line each.
fn print_dropped(out: &Outcome) {
    let dropped: Vec<_> = out
        .stats
        .topology_decisions
        .iter()
        .filter_map(|d| match &d.kind {
            rdt_mesher::DecisionKind::DropUnsupportedComponent(c) => Some(c),
            _ => None,
        })
        .collect();
    if dropped.is_empty() {
        return;
    }
    outln!(
        "dropped {} component(s) the data does not support (--keep-unsupported keeps them; listed in the report's topology_decisions):",
        dropped.len()
    );
    for c in dropped {
        let [x, y, z] = c.centroid;
        outln!(
            "  {} triangles, area {:.3e}, {:.3e} across, at ({x:.4}, {y:.4}, {z:.4}): {:.1}% of the area within the data's band{}",
            c.triangles,
            c.area,
            c.extent,
            100.0 * c.supported_share,
            c.agreement
                .map_or(String::new(), |a| format!(", orientation agreement {a:.2}"))
        );
    }
}

/// The handles cut as not shown by the input data (`pipeline`'s rule; kept with
/// `--keep-unsupported`), one line each.
fn print_cut_handles(out: &Outcome) {
    let cut: Vec<_> = out
        .stats
        .topology_decisions
        .iter()
        .filter_map(|d| match &d.kind {
            rdt_mesher::DecisionKind::CutUnsupportedHandle { loops, handle } => {
                Some((d, *loops, handle))
            }
            _ => None,
        })
        .collect();
    if cut.is_empty() {
        return;
    }
    outln!(
        "cut {} handle(s) the data does not show (--keep-unsupported keeps them; listed in the report's topology_decisions):",
        cut.len()
    );
    for (d, loops, h) in cut {
        let [x, y, z] = d.center.to_array();
        outln!(
            "  at ({x:.4}, {y:.4}, {z:.4}), {:.3e} across: a tunnel within a geodesic ball of {}; {} triangles removed, {loops} loops closed with {}",
            d.size,
            h.why(),
            d.facets_removed,
            d.facets_added
        );
    }
}

/// The details of a failed `input-topology`, `data-support` or `angles` check (why the
/// output's topology is not the input's; which component the data does not support; how
/// many triangles are below the angle bound and where), and of a `data-support` check that
/// says components were dropped before it.
fn print_data_failures(out: &Outcome) {
    let Some(r) = &out.report else { return };
    let dropped = r
        .data_support
        .as_ref()
        .is_some_and(|d| !d.dropped_components.is_empty());
    for name in ["input-topology", "data-support", "angles"] {
        if let Some(c) = r.check(name)
            && (c.status == verify::Status::Fail || (name == "data-support" && dropped))
        {
            outln!("  {} {name}: {}", c.status, c.detail);
        }
    }
}

/// The unmet criteria of a pass, as the CLI prints them.
fn unmet(st: &rdt_mesher::Stats) -> String {
    st.unmet
        .iter()
        .map(|u| u.to_string())
        .collect::<Vec<_>>()
        .join("; ")
}

/// The summary of a two-pass run (`--epsilon`), before the mesh is written.
fn print_two_pass(spec: &str, out: &Outcome) {
    let tp = out.two_pass.as_ref().expect("a two-pass outcome");
    let (s1, s2) = (&tp.first.stats, &out.stats);
    let (e, dm) = (tp.epsilon, tp.dm_inf);
    if tp.second_skipped {
        outln!(
            "{spec}: first pass (sigma_0 = {e} * {dm} = {:.5}): {} vertices, {} facets in {:.3} s; \
             {}",
            tp.sigma0,
            s1.vertices,
            s1.facets,
            s1.time_total_s,
            pipeline::SECOND_SKIPPED
        );
        return;
    }
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
        tp.medial_points
    );
    if !tp.first_pass_uniform() {
        outln!(
            "note: the first pass's d_M estimate has minimum {:.4} < d_M^inf = {dm}: the first \
             pass is not a uniform {e}-sample (pass a smaller --dm-inf); the second pass \
             follows the estimate",
            tp.dm_inf_estimate
        );
    }
}

/// The verification and budget lines of a two-pass run, after the mesh is written.
fn print_two_pass_verdict(out: &Outcome, out_path: &Path) {
    if let Some(c) = &out.report {
        if let Some(l) = c.check("loose-epsilon") {
            outln!(
                "loose-epsilon (d_M by Voronoi poles of the first pass): {}",
                l.detail
            );
        }
        if c.passed() {
            // `PASS with unmet criteria (...)` when a pass left one unmet.
            let line = out.verify_line().unwrap_or_default();
            outln!("{line}; wrote {}", out_path.display());
        } else {
            outln!("verify: FAIL: {}", c.failures().join(", "));
        }
    }
    print_dropped(out);
    print_cut_handles(out);
    print_data_failures(out);
    if let Verdict::Fail(failures) = &out.verdict {
        // A skipped second pass is the first (its line says so).
        let skipped = out.two_pass.as_ref().is_some_and(|t| t.second_skipped);
        for f in failures {
            if let Failure::Stopped(stage) = f {
                if skipped && *stage == pipeline::Stage::Second {
                    continue;
                }
                let st = out.stats_of(*stage);
                let name = if *stage == pipeline::Stage::First {
                    "first"
                } else {
                    "second"
                };
                if let Some(s) = &st.stopped_by {
                    outln!("{name} pass stopped by {s}; unmet: {}", unmet(st));
                }
            }
        }
    }
}
