//! `cargo xtask regress [--quick] [--update-golden] [--json out.json]`: the regression suite.
//!
//! Every catalog surface (plus `heart` with a constant sigma in manifold mode and two disjoint
//! spheres) at two sizes (~2k and ~50k vertices; `--quick`: ~2k only) with both oracles. Each
//! case is meshed (angle 30, constant sigma, seed 0), verified with `verify::check_against`, and
//! checked against the guarantees of the paper:
//!
//! - closed, oriented 2-manifold; genus per component equal to the catalog's;
//! - every facet angle >= 30 degrees; every surface Delaunay ball radius <= sigma
//!   (recomputed here from the mesher's balls, not taken from its stats);
//! - Hausdorff distance: <= sigma always (every facet lies in its surface Delaunay ball, whose
//!   center is on S and radius <= sigma), and theorem 4.7's 4.5 eps^2 d_M^sup when d_M is known
//!   and eps < 0.096 (`verify`'s `theorem-4.7` check);
//! - loose epsilon-sample certificate (eps = sigma / d_M^inf) where d_M is known;
//! - every control point is a vertex and every seed point of S is near the mesh;
//! - both oracles give the same topology;
//! - vertex / facet counts within `--tolerance` (5%) of the golden JSON file
//!   `fixtures/golden/CASE-ORACLE.json`, which `--update-golden` rewrites.
//!
//! It prints one table and a summary line, and exits non-zero on any failure.

use anyhow::{Context, Result, bail};
use glam::DVec3;
use indicatif::{ProgressBar, ProgressStyle};
use oracle::{BoundingSphere, Surface, implicit::ImplicitSurface};
use rdt_mesher::{Criteria, MeshOptions, MeshResult, OracleKind};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::time::Duration;

#[derive(clap::Args, Debug)]
pub struct RegressArgs {
    /// Only the ~2k-vertex size (CI; well under two minutes).
    #[arg(long)]
    pub quick: bool,
    /// Rewrite the golden files of the cases run instead of comparing with them.
    #[arg(long)]
    pub update_golden: bool,
    /// Write every row (and the verify failures) as JSON here.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Relative tolerance on vertex and facet counts against the golden files.
    #[arg(long, default_value_t = 0.05)]
    pub tolerance: f64,
    /// Only the cases whose name contains this string (e.g. `torus`, `-2k`).
    #[arg(long)]
    pub filter: Option<String>,
    /// Folder of the golden files (default: fixtures/golden of the workspace).
    #[arg(long)]
    pub golden_dir: Option<PathBuf>,
    /// No progress bar.
    #[arg(long, short)]
    pub quiet: bool,
    /// Also write each case's mesh as binary PLY here (`CASE-ORACLE.ply`), e.g. to compare
    /// meshes byte for byte across a refactor.
    #[arg(long)]
    pub out_dir: Option<PathBuf>,
}

/// One surface of the suite and its two sizes (sigma for ~2k and ~50k vertices, chosen
/// empirically with `cargo xtask mesh implicit:NAME --size S --no-verify`).
struct SurfaceCase {
    name: &'static str,
    sizes: [(&'static str, f64); 2],
}

impl SurfaceCase {
    const fn new(name: &'static str, sizes: [(&'static str, f64); 2]) -> SurfaceCase {
        SurfaceCase { name, sizes }
    }
}

/// (name, [(label, ~2k sigma), (label, ~50k sigma)]).
const SURFACES: &[SurfaceCase] = &[
    SurfaceCase::new("sphere", [("2k", 0.065), ("50k", 0.013)]),
    SurfaceCase::new("ellipsoid", [("2k", 0.042), ("50k", 0.0084)]),
    SurfaceCase::new("torus", [("2k", 0.063), ("50k", 0.0126)]),
    SurfaceCase::new("double_torus", [("2k", 0.043), ("50k", 0.0087)]),
    SurfaceCase::new("tanglecube", [("2k", 0.18), ("50k", 0.036)]),
    SurfaceCase::new("chair", [("2k", 0.29), ("50k", 0.058)]),
    SurfaceCase::new("blobs", [("2k", 0.039), ("50k", 0.0078)]),
    SurfaceCase::new("heart", [("2k", 0.062), ("12k", 0.025)]),
    SurfaceCase::new("two_spheres", [("2k", 0.092), ("50k", 0.0184)]),
];

/// Two disjoint unit spheres centered at (+-1.5, 0, 0): d_M^inf = 0.5 (the bisector plane).
pub fn two_spheres() -> Result<ImplicitSurface> {
    let (c1, c2) = (DVec3::new(-1.5, 0.0, 0.0), DVec3::new(1.5, 0.0, 0.0));
    let bs = BoundingSphere::at_origin(3.0);
    ImplicitSurface::builder(move |p| (p - c1).length().min((p - c2).length()) - 1.0, bs)
        .dm_inf_hint(0.5)
        .build()
        .context("building the two-spheres surface")
}

fn open(name: &str) -> Result<(Box<dyn Surface>, Vec<i64>, bool)> {
    if name == "two_spheres" {
        return Ok((Box::new(two_spheres()?), vec![0, 0], true));
    }
    let e = oracle::catalog::entry(name).with_context(|| format!("no catalog entry {name}"))?;
    let s = oracle::catalog::surface(name)?;
    let genus = vec![e.genus.unwrap_or(0) as i64; e.components.unwrap_or(1) as usize];
    Ok((Box::new(s), genus, e.smooth))
}

/// Golden counts of one case.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Golden {
    pub case: String,
    pub oracle: String,
    pub sigma: f64,
    pub angle: f64,
    pub seed: u64,
    pub vertices: usize,
    pub facets: usize,
    pub genus: Vec<i64>,
}

/// One row of the table.
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    pub case: String,
    pub oracle: String,
    pub sigma: f64,
    pub vertices: usize,
    pub facets: usize,
    pub time_s: f64,
    pub min_angle_deg: f64,
    pub max_r_over_sigma: f64,
    pub hausdorff: Option<f64>,
    pub hausdorff_bound: f64,
    pub eps_achieved: Option<f64>,
    pub genus: Vec<i64>,
    pub genus_ok: bool,
    pub manifold_ok: bool,
    pub verify_ok: bool,
    pub verify_failures: Vec<String>,
    pub golden: String,
    pub golden_ok: bool,
    /// Every reason this row fails (empty: the row passes).
    pub failures: Vec<String>,
}

struct Job {
    surface: &'static SurfaceCase,
    size: &'static str,
    sigma: f64,
    oracle: OracleKind,
}

fn golden_dir(a: &RegressArgs) -> PathBuf {
    a.golden_dir.clone().unwrap_or_else(|| {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("..")
            .join("fixtures")
            .join("golden")
    })
}

/// The guarantees of the paper that a case breaks (the genus is checked by the caller), and
/// the verify checks that must have passed (a SKIP would hide a guarantee).
fn guarantee_failures(
    res: &MeshResult,
    rep: &verify::Report,
    max_r: f64,
    dm_known: bool,
) -> Vec<String> {
    let st = &res.stats;
    let mut failures = Vec::new();
    if !rep
        .topology
        .as_ref()
        .is_some_and(|t| t.is_closed_oriented_manifold())
    {
        failures.push("not a closed oriented manifold".to_string());
    }
    if res.mesh.triangles.is_empty() || st.min_angle_deg < 30.0 {
        failures.push(format!("min angle {:.3} < 30", st.min_angle_deg));
    }
    if max_r > 1.0 + 1e-9 {
        failures.push(format!("max r/sigma {max_r:.4} > 1"));
    }
    if st.control_points_missing > 0 {
        failures.push(format!(
            "{} control points are not vertices",
            st.control_points_missing
        ));
    }
    if let Some(s) = &st.stopped_by {
        failures.push(format!("stopped by {s}"));
    }
    if !st.unmet.is_empty() {
        let unmet: Vec<String> = st.unmet.iter().map(|u| u.to_string()).collect();
        failures.push(format!("unmet: {}", unmet.join("; ")));
    }
    let required = super::regress_images::MANIFOLD_CHECKS.into_iter().chain([
        "angles",
        "hausdorff",
        "components-sampled",
        "grid-genus",
    ]);
    // The certificate must hold (an INFO "no guarantee" above epsilon_1 is its PASS there).
    if dm_known && !rep.certificate.as_ref().is_some_and(|c| c.passed()) {
        failures.push("the loose epsilon-sample certificate does not hold".to_string());
    }
    for name in required {
        if rep.status(name) != Some(verify::Status::Pass) {
            failures.push(format!("verify check {name} did not pass"));
        }
    }
    failures
}

fn run_case(j: &Job, a: &RegressArgs, gdir: &Path) -> Result<Row> {
    let case = format!("{}-{}", j.surface.name, j.size);
    let oname = j.oracle.name();
    let (surface, genus_expected, _smooth) = open(j.surface.name)?;
    let surface = surface.as_ref();
    let opts = MeshOptions {
        criteria: Criteria::uniform(j.sigma),
        oracle: j.oracle,
        manifold: true,
        seed: 0,
        ..Default::default()
    };
    let res = rdt_mesher::mesh(surface, &opts).with_context(|| format!("meshing {case}"))?;
    if let Some(dir) = &a.out_dir {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        let p = dir.join(format!("{case}-{oname}.ply"));
        meshio::write(&p, &res.mesh).with_context(|| format!("writing {}", p.display()))?;
    }
    let st = &res.stats;
    let max_r = res
        .balls
        .iter()
        .map(|b| b.radius / j.sigma)
        .fold(0.0, f64::max);
    let dm = surface.dm_inf_hint();
    let balls = rdt_mesher::pipeline::verify_balls(&res.balls);
    let vopts = verify::Options {
        samples_per_edge: 2,
        surface_balls: Some(balls),
        epsilon: dm.map(|d| j.sigma / d),
        min_angle_deg: Some(30.0 - 1e-9),
        max_hausdorff: Some(j.sigma),
        seed: 0,
        // Catalog surfaces: the grid scan's components, genus and points of S as in `mesh`.
        grid_scan: Some(verify::grid_scan::DEFAULT_NODES),
        ..Default::default()
    };
    let rep = verify::check_against(&res.mesh, surface, &vopts);
    let topo = rep.topology.as_ref();
    let manifold_ok = topo.is_some_and(|t| t.is_closed_oriented_manifold());
    let mut genus: Vec<i64> = topo
        .map(|t| t.genera().iter().map(|g| g.unwrap_or(-1)).collect())
        .unwrap_or_default();
    genus.sort_unstable();
    let genus_ok = genus == genus_expected;
    let mut failures = guarantee_failures(&res, &rep, max_r, dm.is_some());
    if !genus_ok {
        failures.insert(
            usize::from(!manifold_ok),
            format!("genus {genus:?}, expected {genus_expected:?}"),
        );
    }
    let verify_failures: Vec<String> = rep.failures().iter().map(|f| f.to_string()).collect();
    let verify_ok = verify_failures.is_empty();
    if !verify_ok {
        failures.push(format!("verify FAIL: {}", verify_failures.join(", ")));
    }
    let hausdorff = rep.geometry.as_ref().map(|g| g.hausdorff);
    let th47 = rep
        .hausdorff_bound
        .as_ref()
        .filter(|h| h.applicable)
        .map(|h| h.bound);
    let hausdorff_bound = th47.map_or(j.sigma, |b| b.min(j.sigma));

    // Golden file.
    let gpath = gdir.join(format!("{case}-{oname}.json"));
    let current = Golden {
        case: case.clone(),
        oracle: oname.to_string(),
        sigma: j.sigma,
        angle: 30.0,
        seed: 0,
        vertices: st.vertices,
        facets: st.facets,
        genus: genus.clone(),
    };
    let (golden, golden_ok) = golden_status(&current, &gpath, a)?;
    if !golden_ok {
        failures.push(format!("golden: {golden}"));
    }
    Ok(Row {
        case,
        oracle: oname.to_string(),
        sigma: j.sigma,
        vertices: st.vertices,
        facets: st.facets,
        time_s: st.time_total_s,
        min_angle_deg: st.min_angle_deg,
        max_r_over_sigma: max_r,
        hausdorff,
        hausdorff_bound,
        eps_achieved: rep.certificate.as_ref().map(|c| c.eps_achieved),
        genus,
        genus_ok,
        manifold_ok,
        verify_ok,
        verify_failures,
        golden,
        golden_ok,
        failures,
    })
}

/// Rewrite (`--update-golden`) or compare with the golden file `gpath`: (description, ok).
fn golden_status(current: &Golden, gpath: &Path, a: &RegressArgs) -> Result<(String, bool)> {
    Ok(if a.update_golden {
        let text = serde_json::to_string_pretty(current)? + "\n";
        std::fs::write(gpath, text).with_context(|| format!("writing {}", gpath.display()))?;
        ("written".to_string(), true)
    } else {
        match std::fs::read_to_string(gpath) {
            Err(_) => (
                format!(
                    "missing {} (run `cargo xtask regress --update-golden`)",
                    gpath.display()
                ),
                false,
            ),
            Ok(text) => match serde_json::from_str::<Golden>(&text) {
                Err(e) => (
                    format!("{}: not a golden file: {e}", gpath.display()),
                    false,
                ),
                Ok(g) => compare_golden(&g, current, a.tolerance),
            },
        }
    })
}

/// Compare counts with the golden file: (description, ok).
pub fn compare_golden(g: &Golden, cur: &Golden, tol: f64) -> (String, bool) {
    if g.sigma != cur.sigma || g.angle != cur.angle || g.seed != cur.seed {
        return (
            format!(
                "golden made with sigma {} angle {} seed {}, case now sigma {} angle {} seed {}: \
                 run --update-golden",
                g.sigma, g.angle, g.seed, cur.sigma, cur.angle, cur.seed
            ),
            false,
        );
    }
    let rel = |a: usize, b: usize| (a as f64 - b as f64).abs() / (b.max(1) as f64);
    let (dv, df) = (rel(cur.vertices, g.vertices), rel(cur.facets, g.facets));
    let ok = dv <= tol && df <= tol && g.genus == cur.genus;
    let desc = format!(
        "V {:+.1}% F {:+.1}% vs {}/{}{}",
        100.0 * (cur.vertices as f64 / g.vertices.max(1) as f64 - 1.0),
        100.0 * (cur.facets as f64 / g.facets.max(1) as f64 - 1.0),
        g.vertices,
        g.facets,
        if g.genus == cur.genus {
            String::new()
        } else {
            format!(", genus {:?} vs golden {:?}", cur.genus, g.genus)
        }
    );
    (desc, ok)
}

fn yes(b: bool) -> &'static str {
    if b { "yes" } else { "NO" }
}

/// The cases to run: every surface at its sizes (`--quick`: the first) with both oracles,
/// filtered by name.
fn jobs(a: &RegressArgs) -> Vec<Job> {
    let mut jobs = Vec::new();
    for s in SURFACES {
        for (i, &(size, sigma)) in s.sizes.iter().enumerate() {
            if a.quick && i > 0 {
                continue;
            }
            for oracle in OracleKind::ALL {
                let name = format!("{}-{size}", s.name);
                if a.filter
                    .as_ref()
                    .is_some_and(|f| !name.contains(f.as_str()))
                {
                    continue;
                }
                jobs.push(Job {
                    surface: s,
                    size,
                    sigma,
                    oracle,
                });
            }
        }
    }
    jobs
}

/// One line per row.
fn print_table(rows: &[Row]) {
    outln!(
        "{:<17} {:<12} {:>8} {:>7} {:>7} {:>7} {:>7} {:>9} {:>9} {:>8} {:>7} {:>5} {:>8} {:>7}  golden",
        "case",
        "oracle",
        "sigma",
        "verts",
        "facets",
        "time s",
        "min ang",
        "max r/sig",
        "Hausdorff",
        "H bound",
        "eps",
        "genus",
        "manifold",
        "verify"
    );
    for r in rows {
        let verify = if r.verify_ok { "PASS" } else { "FAIL" };
        outln!(
            "{:<17} {:<12} {:>8} {:>7} {:>7} {:>7.2} {:>7.2} {:>9.4} {:>9} {:>8.2e} {:>7} {:>5} {:>8} {:>7}  {}{}",
            r.case,
            r.oracle,
            r.sigma,
            r.vertices,
            r.facets,
            r.time_s,
            r.min_angle_deg,
            r.max_r_over_sigma,
            r.hausdorff.map_or("-".into(), |h| format!("{h:.2e}")),
            r.hausdorff_bound,
            r.eps_achieved.map_or("-".into(), |e| format!("{e:.4}")),
            yes(r.genus_ok),
            yes(r.manifold_ok),
            verify,
            if r.golden_ok { "ok " } else { "NO " },
            r.golden
        );
    }
}

pub fn run(a: &RegressArgs) -> Result<()> {
    let mut gdir = golden_dir(a);
    if a.update_golden {
        std::fs::create_dir_all(&gdir)
            .with_context(|| format!("cannot create {}", gdir.display()))?;
    }
    if let Ok(c) = gdir.canonicalize() {
        gdir = c;
    }
    if !(a.tolerance >= 0.0 && a.tolerance.is_finite()) {
        bail!(
            "--tolerance {}: must be a non-negative number, e.g. 0.05",
            a.tolerance
        );
    }
    let jobs = jobs(a);
    let bar = if a.quiet {
        ProgressBar::hidden()
    } else {
        let b = ProgressBar::new(jobs.len() as u64);
        b.set_style(
            ProgressStyle::with_template("{bar:30} {pos}/{len} cases {elapsed} {msg}")
                .expect("valid template"),
        );
        b.enable_steady_tick(Duration::from_millis(200));
        b
    };
    let t0 = std::time::Instant::now();
    let mut rows = Vec::new();
    for j in &jobs {
        bar.set_message(format!("{}-{} {}", j.surface.name, j.size, j.oracle.name()));
        let row = run_case(j, a, &gdir)?;
        bar.inc(1);
        rows.push(row);
    }
    bar.finish_and_clear();

    // Same topology with both oracles.
    let mut cross = Vec::new();
    for (i, r) in rows.iter().enumerate() {
        if let Some(o) = rows[i + 1..].iter().find(|o| o.case == r.case)
            && o.genus != r.genus
        {
            cross.push(format!(
                "{}: genus {:?} (bipolar) vs {:?} (intersection)",
                r.case, r.genus, o.genus
            ));
        }
    }

    print_table(&rows);
    let failed: Vec<&Row> = rows.iter().filter(|r| !r.failures.is_empty()).collect();
    for r in &failed {
        outln!("FAIL {} {}: {}", r.case, r.oracle, r.failures.join("; "));
    }
    for c in &cross {
        outln!("FAIL oracles disagree: {c}");
    }
    // The image cases (issue 14): closed manifolds on real and hard volumes.
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let images = super::regress_images::run(&root, a.quick, a.filter.as_deref())?;
    super::regress_images::print_lines(&images, "FAIL", |r| &r.failures);
    let image_fails = images.iter().filter(|r| !r.failures.is_empty()).count();
    if jobs.is_empty() && images.is_empty() {
        bail!(
            "no case matches --filter {} (catalog cases are named like torus-2k, image cases \
             like mni-crop@171.2)",
            a.filter.as_deref().unwrap_or("(none)")
        );
    }
    if let Some(p) = &a.json {
        let j =
            serde_json::json!({ "rows": rows, "oracle_disagreements": cross, "images": images });
        std::fs::write(p, serde_json::to_string_pretty(&j)?)
            .with_context(|| format!("cannot write {}", p.display()))?;
    }
    let nfail = failed.len() + cross.len() + image_fails;
    outln!(
        "regress{}: {} cases, {} passed, {} failed; {} image cases, {} failed{} in {:.1} s{}",
        if a.quick { " --quick" } else { "" },
        rows.len(),
        rows.len() - failed.len(),
        failed.len(),
        images.len(),
        image_fails,
        if cross.is_empty() {
            String::new()
        } else {
            format!(", {} oracle disagreements", cross.len())
        },
        t0.elapsed().as_secs_f64(),
        if a.update_golden {
            format!("; golden files written to {}", gdir.display())
        } else {
            String::new()
        }
    );
    if nfail > 0 {
        bail!("regression suite: {nfail} failures");
    }
    Ok(())
}
