//! `cargo xtask verify mesh.ply [--against SURFACE] [--epsilon E] [--dm auto|poles|D] [--report r.json]`.

use crate::cli::input::{self, SurfaceOptions};
use anyhow::{Context, Result};
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct VerifyArgs {
    /// The mesh to check (.ply, .off, .obj, .stl, .glb, .vtk, .vtp, .gii).
    pub mesh: PathBuf,
    /// Check against this surface (same specs as `mesh`: implicit:NAME, an image, a mesh...).
    #[arg(long)]
    pub against: Option<String>,
    /// Bounding sphere `cx,cy,cz,r` for an implicit expression.
    #[arg(long, allow_hyphen_values = true)]
    pub bounding_sphere: Option<String>,
    /// Requested epsilon of the loose epsilon-sample certificate.
    #[arg(long, allow_hyphen_values = true, value_parser = super::output::epsilon("--epsilon"))]
    pub epsilon: Option<f64>,
    /// Where the certificate takes d_M from (with --against): `auto` (the surface's d_M^inf,
    /// when its backend knows one), `poles` (estimated from the Voronoi poles of the mesh's
    /// vertices), or a positive number (a constant d_M).
    #[arg(long, default_value = "auto", allow_hyphen_values = true)]
    pub dm: String,
    /// FAIL if the two-sided Hausdorff estimate exceeds this distance.
    #[arg(long, allow_hyphen_values = true, value_parser = super::output::positive("--max-hausdorff", "the Hausdorff bound", "0.01"))]
    pub max_hausdorff: Option<f64>,
    /// FAIL if a facet angle is below this bound (degrees).
    #[arg(long, allow_hyphen_values = true, value_parser = parse_min_angle)]
    pub min_angle: Option<f64>,
    /// Mesh samples per triangle edge for the distance estimates.
    #[arg(long, default_value_t = 4, allow_hyphen_values = true, value_parser = parse_samples)]
    pub samples_per_edge: usize,
    /// Write the JSON report here.
    #[arg(long)]
    pub report: Option<PathBuf>,
    #[command(flatten)]
    pub surface: SurfaceOptions,
    #[command(flatten)]
    pub pictures: super::view::PictureArgs,
}

/// `--dm`: `auto`, `poles` or a positive finite number.
/// `--min-angle DEG`: in [0, 60] (no triangle has all angles above 60 degrees).
fn parse_min_angle(s: &str) -> Result<f64, String> {
    let v: f64 = s.trim().parse().unwrap_or(f64::NAN);
    if !(0.0..=60.0).contains(&v) {
        return Err(format!(
            "--min-angle {s}: the facet angle bound must be in [0, 60] degrees, e.g. --min-angle 30"
        ));
    }
    Ok(v)
}

/// `--samples-per-edge N`: a positive whole number.
fn parse_samples(s: &str) -> Result<usize, String> {
    match s.trim().parse::<usize>() {
        Ok(n) if n > 0 => Ok(n),
        _ => Err(format!(
            "--samples-per-edge {s}: must be a positive whole number, e.g. --samples-per-edge 4"
        )),
    }
}

fn parse_dm(v: &str) -> Result<verify::DmSource> {
    match v {
        "auto" => Ok(verify::DmSource::Auto),
        "poles" => Ok(verify::DmSource::Poles),
        _ => match v.parse::<f64>() {
            Ok(d) if d > 0.0 && d.is_finite() => Ok(verify::DmSource::Constant(d)),
            _ => anyhow::bail!(
                "--dm '{v}': use auto, poles, or a positive number (a constant d_M, in the mesh's units)"
            ),
        },
    }
}

pub fn run(a: &VerifyArgs) -> Result<()> {
    let dm = parse_dm(&a.dm)?;
    if a.against.is_none() && !matches!(dm, verify::DmSource::Auto) {
        anyhow::bail!(
            "--dm {} needs --against SURFACE (the certificate is about a surface)",
            a.dm
        );
    }
    if let Some(p) = &a.pictures.picture {
        super::view::check_extension("--picture", p, "png")?;
        let mut outs = vec![("--picture", p.as_path())];
        if let Some(r) = &a.report {
            outs.push(("--report", r.as_path()));
        }
        super::output::check_outputs(Some(&a.mesh), &outs)?;
    }
    // A spinner on a terminal (hidden otherwise) naming the stage: a large mesh against a
    // surface takes minutes.
    let bar =
        indicatif::ProgressBar::new_spinner().with_finish(indicatif::ProgressFinish::AndClear);
    bar.set_style(indicatif::ProgressStyle::with_template("{spinner} {elapsed} {msg}").unwrap());
    bar.enable_steady_tick(std::time::Duration::from_millis(200));
    bar.set_message(format!("reading {}", a.mesh.display()));
    let mesh = meshio::read(&a.mesh)?;
    let stage = bar.clone();
    let progress = verify::Progress(std::sync::Arc::new(move |s: &str| {
        stage.set_message(format!("verify: {s}"))
    }));
    let opts = verify::Options {
        progress: Some(progress),
        epsilon: a.epsilon,
        max_hausdorff: a.max_hausdorff,
        min_angle_deg: a.min_angle,
        samples_per_edge: a.samples_per_edge,
        dm,
        ..Default::default()
    };
    let mut kind = None;
    let mut balls = None;
    let report = match &a.against {
        Some(spec) => {
            bar.set_message(format!("opening {spec}"));
            let opened = input::open(spec, a.bounding_sphere.as_deref(), &a.surface)?;
            kind = Some(opened.kind);
            if a.pictures.picture.is_some() {
                balls = Some(verify::certificate::surface_delaunay_balls(
                    &mesh,
                    opened.surface(),
                ));
            }
            let (samples, source) = reference_samples(spec, &opened, &a.surface).unzip();
            let opts = verify::Options {
                surface_samples: samples,
                surface_samples_source: source,
                grid_scan: (opened.kind == rdt_mesher::pipeline::InputKind::Implicit)
                    .then_some(verify::grid_scan::DEFAULT_NODES),
                ..opts
            };
            let mut r = verify::check_against(&mesh, opened.surface(), &opts);
            // Point sets and meshes: the data-support check (the mesh's mean edge as sigma).
            bar.set_message("verify: data-support");
            rdt_mesher::pipeline::data_support(&mut r, &opened, &mesh, mean_edge(&mesh), &[]);
            r
        }
        None => verify::check(&mesh, &opts),
    };
    bar.finish_and_clear();
    out!("{}", report.summary());
    if let Some(p) = &a.report {
        // Per-component and per-item lists bounded as in `mesh --report`.
        let mut v: serde_json::Value = serde_json::from_str(&report.to_json())?;
        super::mesh_report::bound_lists(&mut v, super::mesh_report::LIST_LIMIT);
        super::mesh::write_json(p, &v).with_context(|| format!("writing {}", p.display()))?;
    }
    if let Some(p) = &a.pictures.picture {
        let scene = super::view::scene(super::view::Known {
            title: a.mesh.display().to_string(),
            mesh: &mesh,
            balls: balls.as_deref(),
            sigma: None,
            angle_bound: a.min_angle,
            report: Some(serde_json::from_str(&report.to_json())?),
            up: a.pictures.up.unwrap_or(super::view::default_up(kind)),
        })?;
        super::view::write_picture(p, &scene, a.pictures.picture_color.as_deref())?;
        outln!("wrote {}", p.display());
    }
    if !report.passed() {
        anyhow::bail!(
            "{}: FAIL ({})",
            a.mesh.display(),
            report.failures().join(", ")
        );
    }
    Ok(())
}

/// The mean edge length of `mesh` (0 for an empty mesh).
fn mean_edge(mesh: &meshio::TriMesh) -> f64 {
    let v = &mesh.vertices;
    let sum: f64 = mesh
        .triangles
        .iter()
        .filter(|t| t.iter().all(|&i| (i as usize) < v.len()))
        .map(|t| {
            let [a, b, c] = t.map(|i| v[i as usize]);
            (b - a).length() + (c - b).length() + (a - c).length()
        })
        .sum();
    sum / (3 * mesh.triangles.len()).max(1) as f64
}

/// Dense samples of S for the S -> mesh side, when the input gives them: the triangles of an
/// exact mesh input (S itself, 15 points per triangle), the points of a point set (noisy
/// samples of S: the figure includes their noise). `None` otherwise (images sample their
/// level set on the voxel edges themselves).
fn reference_samples(
    spec: &str,
    opened: &rdt_mesher::pipeline::Input<'_>,
    o: &SurfaceOptions,
) -> Option<(Vec<glam::DVec3>, String)> {
    use rdt_mesher::pipeline::InputKind;
    match opened.kind {
        // The samples `mesh` measures from: those of the triangles bounding the solid (an
        // interior membrane or the buried faces of overlapping shells are not S).
        InputKind::Polyhedron if !o.smooth_polyhedron => opened
            .support_data
            .clone()
            .map(|pts| (pts, rdt_mesher::pipeline::POLYHEDRON_SAMPLES.into())),
        InputKind::PointSet => {
            let pts = if spec.to_ascii_lowercase().ends_with(".xyz") {
                oracle::pointset::read_xyz(spec).ok()?.points
            } else {
                meshio::read_point_cloud(spec)
                    .map(|c| c.points)
                    .or_else(|_| meshio::read(spec).map(|m| m.vertices))
                    .ok()?
            };
            Some((
                pts,
                "input points (noisy samples of S: the figure includes their noise, not only \
                 the mesh's error)"
                    .into(),
            ))
        }
        _ => None,
    }
}
