//! (ours) Seeing the mesh from the command line: `--picture FILE.png` (mesh, verify),
//! `mesh --html [FILE.html]` and `cargo xtask view MESH [--report R.json] -o FILE.html`. The
//! scene is built here from what the run knows (the mesh, the mesher's surface Delaunay balls,
//! the verify report, the unmet criteria); drawing is the `view` crate's.

use anyhow::{Context, Result, bail};
use geom::SurfaceBall;
use rdt_mesher::pipeline::InputKind;
use serde_json::Value;
use std::path::{Path, PathBuf};
use view::{Axis, Measure, PictureOptions, Scene};

/// `--up x|y|z`.
pub fn parse_up(s: &str) -> Result<Axis, String> {
    Axis::parse(s).ok_or_else(|| {
        format!("--up {s}: the surface's up axis is x, y or z, e.g. --up y (Stanford scans)")
    })
}

/// The flags of the pictures, shared by `mesh` and `verify`.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct PictureArgs {
    /// Write a PNG picture of the mesh (front, side and top views, coloured by r/sigma or the
    /// minimum angle, the facets behind a FAIL or an unmet criterion in magenta).
    #[arg(long, value_name = "FILE.png")]
    pub picture: Option<PathBuf>,
    /// Colour of the picture: min_angle, r_sigma, distance or component (default: r_sigma
    /// when known, else min_angle).
    #[arg(long, value_name = "MEASURE", value_parser = ["min_angle", "r_sigma", "distance", "component"])]
    pub picture_color: Option<String>,
    /// The surface's up axis in pictures and the viewer (default: y for mesh and point-set
    /// inputs, as scanned models are stored; z otherwise, as images and the catalog).
    #[arg(long, value_parser = parse_up)]
    pub up: Option<Axis>,
}

/// `cargo xtask view MESH [--report R.json] [--against SURFACE] -o FILE.html`.
#[derive(clap::Args, Debug)]
pub struct ViewArgs {
    /// The mesh (.ply, .off, .obj, .stl).
    pub mesh: PathBuf,
    /// A JSON report of `mesh --report` or `verify --report` about this mesh: its summary,
    /// checks and certificate are shown, its failing facets highlighted.
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// The HTML file to write.
    #[arg(short, long, value_name = "FILE.html")]
    pub output: PathBuf,
    /// Also write a PNG picture.
    #[arg(long, value_name = "FILE.png")]
    pub picture: Option<PathBuf>,
    /// The surface's up axis (default: y against a mesh or point set, z otherwise).
    #[arg(long, value_parser = parse_up)]
    pub up: Option<Axis>,
    /// The surface the mesh approximates (same specs as `mesh`): its surface Delaunay balls
    /// give the distance to the surface, and with the report's sigma r/sigma.
    #[arg(long)]
    pub against: Option<String>,
    /// Bounding sphere `cx,cy,cz,r` for an expression given to --against.
    #[arg(long, allow_hyphen_values = true)]
    pub bounding_sphere: Option<String>,
    #[command(flatten)]
    pub surface: super::input::SurfaceOptions,
}

/// The default up axis for an input kind.
pub fn default_up(kind: Option<InputKind>) -> Axis {
    match kind {
        Some(InputKind::Polyhedron | InputKind::PointSet) => Axis::Y,
        _ => Axis::Z,
    }
}

/// What a run knows about its mesh, to build a scene from.
pub struct Known<'a> {
    pub title: String,
    pub mesh: &'a meshio::TriMesh,
    /// The surface Delaunay ball of each facet (the mesher's or verify's), if known.
    pub balls: Option<&'a [SurfaceBall]>,
    /// The constant size sigma, for r/sigma.
    pub sigma: Option<f64>,
    /// The facet angle bound (degrees), marked on the colour bar.
    pub angle_bound: Option<f64>,
    /// The whole report (`mesh --report`'s object, or a verify report).
    pub report: Option<Value>,
    pub up: Axis,
}

/// The scene: the mesh's own measures and defects, then the balls' r/sigma and distance, then
/// the report's failing facets and unmet criteria.
pub fn scene(k: Known<'_>) -> Result<Scene> {
    let mut s =
        Scene::new(k.mesh, k.title.clone()).map_err(|e| anyhow::anyhow!("{}: {e}", k.title))?;
    s.up = k.up;
    if let Some(m) = s.measures.iter_mut().find(|m| m.key == "min_angle") {
        m.bound = k.angle_bound.filter(|b| *b > 0.0);
    }
    if let Some(balls) = k.balls {
        let n = s.triangles.len();
        let (mut r, mut d) = (vec![f64::NAN; n], vec![f64::NAN; n]);
        for b in balls.iter().filter(|b| b.facet < n) {
            let [p, q, w] = s.triangles[b.facet].map(|i| s.vertices[i as usize]);
            if let Some(sigma) = k.sigma {
                r[b.facet] = b.radius / sigma;
            }
            if let Some((c, _)) = verify::certificate::circumcircle(p, q, w) {
                d[b.facet] = c.distance(b.center);
            }
        }
        if k.sigma.is_some() {
            s.set_measure(Measure {
                key: "r_sigma".into(),
                label: "r/sigma (surface Delaunay ball radius over the size)".into(),
                values: r,
                bound: Some(1.0),
                categorical: false,
            });
        }
        s.set_measure(Measure {
            key: "distance".into(),
            label: "distance to the surface (circumcenter to the ball's center on S)".into(),
            values: d,
            bound: None,
            categorical: false,
        });
    }
    if let Some(rep) = &k.report {
        highlight_report(&mut s, rep);
        s.summary = summary(&s, rep);
        s.report = Some(rep.clone());
    } else {
        s.summary = vec![format!(
            "{} vertices, {} facets",
            s.vertices.len(),
            s.triangles.len()
        )];
    }
    Ok(s)
}

/// The verify part of a report (a `mesh` report holds it under `verify`).
fn verify_part(rep: &Value) -> &Value {
    match rep.get("verify") {
        Some(v) if v.is_object() => v,
        _ => rep,
    }
}

fn indices(v: &Value) -> Vec<usize> {
    v.as_array()
        .map(|a| {
            a.iter()
                .filter_map(|x| x.as_u64().map(|u| u as usize))
                .collect()
        })
        .unwrap_or_default()
}

/// Highlights the facets a report names: self-intersecting pairs, balls exceeding the
/// requested epsilon, degenerate triangles, facets at non-manifold vertices, facets below a
/// failed angle bound, the nearest facets of uncovered component seeds, unmet criteria.
fn highlight_report(s: &mut Scene, rep: &Value) {
    let v = verify_part(rep);
    let pairs: Vec<usize> = v["self_intersections"]["pairs"]
        .as_array()
        .map(|a| a.iter().flat_map(indices).collect())
        .unwrap_or_default();
    s.add_highlight("self-intersections: intersecting facet", pairs);
    s.add_highlight(
        "loose-epsilon: ball radius above eps d_M(c)",
        indices(&v["certificate"]["exceeding"]),
    );
    s.add_highlight(
        "degenerate-triangles: zero area",
        indices(&v["topology"]["degenerate_triangles"]),
    );
    let nmv: std::collections::BTreeSet<usize> = indices(&v["topology"]["non_manifold_vertices"])
        .into_iter()
        .collect();
    if !nmv.is_empty() {
        let f: Vec<usize> = (0..s.triangles.len())
            .filter(|&t| s.triangles[t].iter().any(|&i| nmv.contains(&(i as usize))))
            .collect();
        s.add_highlight("vertex-manifold: facet at a non-manifold vertex", f);
    }
    let failed = |name: &str| {
        v["checks"]
            .as_array()
            .is_some_and(|a| a.iter().any(|c| c["name"] == name && c["status"] == "FAIL"))
    };
    if failed("angles")
        && let Some(b) = s.measure("min_angle").and_then(|m| m.bound)
    {
        let m = s
            .measure("min_angle")
            .map(|m| m.values.clone())
            .unwrap_or_default();
        let f: Vec<usize> = (0..m.len()).filter(|&i| m[i] < b).collect();
        s.add_highlight(format!("angles: below {b} deg"), f);
    }
    let uncovered: Vec<usize> = v["components_sampled"]["seeds"]
        .as_array()
        .map(|a| {
            a.iter()
                .filter(|x| x["covered"] == false)
                .filter_map(|x| x["nearest_triangle"].as_u64().map(|u| u as usize))
                .collect()
        })
        .unwrap_or_default();
    s.add_highlight(
        "components-sampled: facet nearest an uncovered seed",
        uncovered,
    );
    for stats in [&rep["stats"], &rep["second"]] {
        for u in stats["unmet_facets"].as_array().into_iter().flatten() {
            if let Some(f) = u["facet"].as_u64() {
                let c = u["criterion"].as_str().unwrap_or("criterion");
                s.add_highlight(format!("unmet {c} criterion"), [f as usize]);
            }
        }
    }
}

/// The lines beside the view: sizes, the verdict, the mesher's figures.
fn summary(s: &Scene, rep: &Value) -> Vec<String> {
    let v = verify_part(rep);
    let mut lines = vec![format!(
        "{} vertices, {} facets",
        s.vertices.len(),
        s.triangles.len()
    )];
    if let Some(checks) = v["checks"].as_array() {
        let fails: Vec<&str> = checks
            .iter()
            .filter(|c| c["status"] == "FAIL")
            .filter_map(|c| c["name"].as_str())
            .collect();
        lines.push(if fails.is_empty() {
            format!("verify: PASS ({} checks)", checks.len())
        } else {
            format!("verify: FAIL: {}", fails.join(", "))
        });
    }
    let st = if rep["stats"].is_object() {
        &rep["stats"]
    } else {
        &rep["second"]
    };
    if let Some(a) = st["min_angle_deg"].as_f64() {
        lines.push(format!("min angle {a:.2} deg"));
    }
    if let Some(r) = st["max_r_over_sigma"].as_f64() {
        lines.push(format!("max r/sigma {r:.3}"));
    }
    if let Some(sig) = rep["sigma"].as_f64() {
        lines.push(format!("sigma {sig}"));
    }
    if let Some(e) = v["certificate"]["eps_achieved"].as_f64() {
        lines.push(format!("certificate: eps achieved {e:.4}"));
    }
    for u in st["unmet"].as_array().into_iter().flatten() {
        if let Some(k) = u["kind"].as_str() {
            lines.push(format!("unmet: {k}"));
        }
    }
    lines
}

/// Writes the picture of `scene` to `path` (atomically).
pub fn write_picture(path: &Path, scene: &Scene, color: Option<&str>) -> Result<()> {
    let opts = PictureOptions {
        measure: color.map(str::to_string),
        ..Default::default()
    };
    let img = view::picture(scene, &opts).map_err(|e| anyhow::anyhow!("--picture-color: {e}"))?;
    let png = view::encode_png(&img).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    super::output::write_atomically(path, |tmp| {
        std::fs::write(tmp, &png).with_context(|| format!("writing {}", path.display()))
    })
}

/// Writes the HTML viewer of `scene` to `path` (atomically).
pub fn write_html(path: &Path, scene: &Scene) -> Result<()> {
    let page = view::html(scene);
    super::output::write_atomically(path, |tmp| {
        std::fs::write(tmp, &page).with_context(|| format!("writing {}", path.display()))
    })
}

/// `--picture FILE.png` and `--html FILE.html` must end so (a typo would write a PNG named
/// `.ply`).
pub fn check_extension(flag: &str, p: &Path, ext: &str) -> Result<()> {
    let ok = p
        .extension()
        .is_some_and(|e| e.to_string_lossy().eq_ignore_ascii_case(ext));
    if !ok {
        bail!(
            "{flag} {}: the file name must end in .{ext} (e.g. {flag} {})",
            p.display(),
            p.with_extension(ext).display()
        );
    }
    Ok(())
}

/// `cargo xtask view`.
pub fn run(a: &ViewArgs) -> Result<()> {
    check_extension("-o", &a.output, "html")?;
    // Named `--output` here: check_outputs takes `-o` for a mesh path.
    let mut outs = vec![("--output", a.output.as_path())];
    if let Some(p) = &a.picture {
        check_extension("--picture", p, "png")?;
        outs.push(("--picture", p.as_path()));
    }
    super::output::check_outputs(Some(&a.mesh), &outs)?;
    if let Some(r) = &a.report {
        super::output::check_outputs(Some(r), &outs)?;
    }
    let mesh = meshio::read(&a.mesh)?;
    let report = match &a.report {
        Some(r) => {
            let text = std::fs::read_to_string(r)
                .with_context(|| format!("--report {}: cannot read it", r.display()))?;
            let v: Value = serde_json::from_str(&text).map_err(|e| {
                anyhow::anyhow!(
                    "--report {}: not JSON ({e}); give a report written by `mesh --report` or `verify --report`",
                    r.display()
                )
            })?;
            if !v.is_object() {
                bail!(
                    "--report {}: not a report object; give a report written by `mesh --report` or `verify --report`",
                    r.display()
                );
            }
            Some(v)
        }
        None => None,
    };
    if let Some(rep) = &report {
        let n = verify_part(rep)["triangles"].as_u64();
        if n.is_some_and(|n| n as usize != mesh.triangles.len()) {
            bail!(
                "--report {}: it describes a mesh of {} triangles, {} has {}: give the report of this mesh",
                a.report
                    .as_ref()
                    .map(|p| p.display().to_string())
                    .unwrap_or_default(),
                n.unwrap_or(0),
                a.mesh.display(),
                mesh.triangles.len()
            );
        }
    }
    let angle_bound = report.as_ref().and_then(|r| r["angle"].as_f64());
    let (mut kind, mut balls) = (None, None);
    if let Some(spec) = &a.against {
        let opened = super::input::open(spec, a.bounding_sphere.as_deref(), &a.surface)?;
        kind = Some(opened.kind);
        balls = Some(verify::certificate::surface_delaunay_balls(
            &mesh,
            opened.surface(),
        ));
    }
    let sigma = report
        .as_ref()
        .and_then(|r| r["sigma"].as_f64())
        .filter(|s| *s > 0.0 && s.is_finite());
    let s = scene(Known {
        title: a.mesh.display().to_string(),
        mesh: &mesh,
        balls: balls.as_deref(),
        sigma,
        angle_bound,
        report,
        up: a.up.unwrap_or(default_up(kind)),
    })?;
    write_html(&a.output, &s)?;
    if let Some(p) = &a.picture {
        write_picture(p, &s, None)?;
    }
    outln!(
        "{}: {} facets, {} highlighted; wrote {}",
        a.mesh.display(),
        s.triangles.len(),
        s.highlighted().iter().filter(|&&h| h).count(),
        a.output.display()
    );
    Ok(())
}
