//! `cargo xtask bench`: timing tables, medians of several runs, with ratios against baselines
//! measured in the same run (our previous stage, or CGAL with --vs-cgal).

use anyhow::{Context, Result, bail};
use glam::DVec3;
use oracle::roots::SplitMix64;
use rdt_mesher::{Criteria, MeshOptions, Sizing};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

#[derive(clap::Args, Debug)]
pub struct BenchArgs {
    /// Which group: delaunay, mesh, image, all.
    #[arg(default_value = "all")]
    pub name: String,
    /// Also run the CGAL baseline programs (bench/cgal; installs libcgal-dev with apt if missing).
    #[arg(long)]
    pub vs_cgal: bool,
    /// Runs per measurement (the median is reported).
    #[arg(long, default_value_t = 3)]
    pub runs: usize,
    /// Only the small sizes (1e5 points, small meshes).
    #[arg(long)]
    pub quick: bool,
    /// Write all rows as JSON here.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

#[derive(serde::Serialize, Clone, Debug)]
pub struct Row {
    pub group: String,
    pub case: String,
    pub tool: String,
    pub median_s: f64,
    pub runs: Vec<f64>,
    pub size: usize,
    pub size_unit: String,
    pub extra: serde_json::Value,
}

pub(crate) fn median(v: &mut [f64]) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    if v.is_empty() {
        f64::NAN
    } else {
        v[v.len() / 2]
    }
}

/// Same generator as bench/cgal (SplitMix64), so both tools triangulate the same points.
pub fn random_points(n: usize, seed: u64, distribution: &str) -> Vec<DVec3> {
    let mut rng = SplitMix64(seed);
    (0..n)
        .map(|_| match distribution {
            "sphere" => loop {
                let x = 2.0 * rng.next_f64() - 1.0;
                let y = 2.0 * rng.next_f64() - 1.0;
                let z = 2.0 * rng.next_f64() - 1.0;
                let s = (x * x + y * y) + z * z;
                if s > 0.0 && s <= 1.0 {
                    let r = s.sqrt();
                    break DVec3::new(x / r, y / r, z / r);
                }
            },
            _ => DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()),
        })
        .collect()
}

fn cgal_dir() -> PathBuf {
    PathBuf::from("target/cgal")
}

fn ensure_cgal() -> Result<()> {
    let script = Path::new("bench/cgal/build.sh");
    if !script.exists() {
        bail!(
            "bench/cgal/build.sh is missing: the CGAL baseline is not available in this checkout"
        );
    }
    eprintln!(
        "building the CGAL baselines (bench/cgal/build.sh; installs libcgal-dev with apt if missing)"
    );
    let st = Command::new("bash")
        .arg(script)
        .arg(cgal_dir())
        .status()
        .context("running bench/cgal/build.sh")?;
    if !st.success() {
        bail!("bench/cgal/build.sh failed ({st})");
    }
    Ok(())
}

fn run_cgal(prog: &str, args: &[String]) -> Result<serde_json::Value> {
    let exe = cgal_dir().join(prog);
    let out = Command::new(&exe)
        .args(args)
        .output()
        .with_context(|| format!("running {}", exe.display()))?;
    if !out.status.success() {
        bail!(
            "{} failed: {}",
            exe.display(),
            String::from_utf8_lossy(&out.stderr)
                .lines()
                .last()
                .unwrap_or("")
        );
    }
    let text = String::from_utf8_lossy(&out.stdout);
    let line = text
        .lines()
        .rev()
        .find(|l| l.trim_start().starts_with('{'))
        .context("no JSON line from CGAL program")?;
    Ok(serde_json::from_str(line)?)
}

/// CGAL's criteria of the mesh and image groups: angle 30, radius = distance = `r`.
pub(crate) fn cgal_criteria_args(r: f64) -> Vec<String> {
    [
        "--angle",
        "30",
        "--radius",
        &r.to_string(),
        "--distance",
        &r.to_string(),
    ]
    .map(String::from)
    .to_vec()
}

/// A CGAL baseline program, run once after each of our runs (alternating, so that both
/// medians sample the same phases of a shared machine: a slow spell of a few seconds falls on
/// both tools, instead of on whichever ran then).
pub(crate) struct CgalBaseline {
    prog: &'static str,
    args: Vec<String>,
    times: Vec<f64>,
    last: serde_json::Value,
}

impl CgalBaseline {
    /// `None` unless `enabled` (`--vs-cgal`).
    pub(crate) fn new(enabled: bool, prog: &'static str, args: Vec<String>) -> Option<Self> {
        enabled.then(|| CgalBaseline {
            prog,
            args,
            times: Vec::new(),
            last: serde_json::Value::Null,
        })
    }

    /// One run of the program; its `seconds` join the times.
    pub(crate) fn run_once(&mut self) -> Result<()> {
        let v = run_cgal(self.prog, &self.args)?;
        self.times
            .push(v["seconds"].as_f64().context("CGAL JSON without seconds")?);
        self.last = v;
        Ok(())
    }

    /// The row of the runs made (size read from the last run's JSON field `size_key`).
    pub(crate) fn row(self, group: &str, case: &str, size_key: &str, unit: &str) -> Row {
        let size = self.last[size_key].as_u64().unwrap_or(0) as usize;
        Row {
            group: group.into(),
            case: case.into(),
            tool: "cgal".into(),
            median_s: median(&mut self.times.clone()),
            runs: self.times,
            size,
            size_unit: unit.into(),
            extra: self.last,
        }
    }
}

fn bench_delaunay(a: &BenchArgs, rows: &mut Vec<Row>) -> Result<()> {
    let mut cases: Vec<(usize, &str)> = vec![(100_000, "cube")];
    if !a.quick {
        cases.push((1_000_000, "cube"));
        cases.push((1_000_000, "sphere"));
    }
    for (n, dist) in cases {
        let pts = random_points(n, 1, dist);
        let mut cgal = CgalBaseline::new(
            a.vs_cgal,
            "cgal_delaunay",
            vec![
                "--random".into(),
                n.to_string(),
                "--seed".into(),
                "1".into(),
                "--distribution".into(),
                dist.into(),
            ],
        );
        let mut times = Vec::new();
        let mut cells = 0;
        let mut bytes = 0;
        for _ in 0..a.runs {
            let t = Instant::now();
            let mut tri = delaunay3::Triangulation::new();
            tri.insert_bulk(&pts).context("insert_bulk")?;
            times.push(t.elapsed().as_secs_f64());
            cells = tri.num_finite_cells();
            bytes = tri.memory_bytes();
            drop(tri);
            if let Some(c) = cgal.as_mut() {
                c.run_once()?;
            }
        }
        let case = format!("{n} {dist}");
        let med = median(&mut times.clone());
        rows.push(Row {
            group: "delaunay".into(),
            case: case.clone(),
            tool: "rdt".into(),
            median_s: med,
            runs: times,
            size: n,
            size_unit: "points".into(),
            extra: serde_json::json!({"finite_cells": cells, "points_per_s": n as f64 / med, "bytes_per_point": bytes as f64 / n as f64}),
        });
        if let Some(c) = cgal {
            rows.push(c.row("delaunay", &case, "n", "points"));
        }
    }
    Ok(())
}

/// CGAL Surface_mesher criteria: angle 30, radius r, distance r.
fn bench_mesh(a: &BenchArgs, rows: &mut Vec<Row>) -> Result<()> {
    let mut cases = vec![("sphere", 0.02), ("torus", 0.0194)];
    if a.quick {
        cases = vec![("sphere", 0.05), ("torus", 0.05)];
    }
    for (name, r) in cases {
        let surf = crate::surface_spec::catalog_surface(name)?;
        let opts = MeshOptions {
            criteria: Criteria {
                size: Some(Sizing::Constant(r)),
                min_angle_deg: 30.0,
                max_distance: Some(r),
            },
            ..Default::default()
        };
        let mut cgal = CgalBaseline::new(
            a.vs_cgal,
            "cgal_surface_mesher",
            [
                vec!["--surface".into(), name.into()],
                cgal_criteria_args(r),
                vec!["--manifold".into()],
            ]
            .concat(),
        );
        let mut times = Vec::new();
        let mut res = None;
        for _ in 0..a.runs {
            let t = Instant::now();
            let out = rdt_mesher::mesh(surf.as_ref(), &opts)?;
            times.push(t.elapsed().as_secs_f64());
            res = Some(out.stats);
            if let Some(c) = cgal.as_mut() {
                c.run_once()?;
            }
        }
        let st = res.unwrap();
        let case = format!("{name} r={r}");
        rows.push(Row {
            group: "mesh".into(),
            case: case.clone(),
            tool: "rdt".into(),
            median_s: median(&mut times.clone()),
            runs: times,
            size: st.vertices,
            size_unit: "vertices".into(),
            extra: serde_json::json!({"facets": st.facets, "time_delaunay_s": st.time_delaunay_s, "time_oracle_s": st.time_oracle_s, "criteria_met": st.criteria_met}),
        });
        if let Some(c) = cgal {
            rows.push(c.row("mesh", &case, "vertices", "vertices"));
        }
    }
    Ok(())
}

pub fn run(a: &BenchArgs) -> Result<()> {
    if a.runs == 0 {
        bail!("--runs must be at least 1");
    }
    if a.vs_cgal {
        ensure_cgal()?;
    }
    let mut rows = Vec::new();
    let all = a.name == "all";
    let mut any = false;
    if all || a.name == "delaunay" {
        bench_delaunay(a, &mut rows)?;
        any = true;
    }
    if all || a.name == "mesh" {
        bench_mesh(a, &mut rows)?;
        any = true;
    }
    if all || a.name == "image" {
        crate::bench_image::bench_image(a, &mut rows)?;
        any = true;
    }
    if !any {
        bail!(
            "unknown bench group '{}': use delaunay, mesh, image or all",
            a.name
        );
    }
    print_table(&rows);
    if let Some(p) = &a.json {
        std::fs::write(p, serde_json::to_string_pretty(&rows)?)?;
    }
    Ok(())
}

fn print_table(rows: &[Row]) {
    outln!(
        "{:<9} {:<26} {:<5} {:>10} {:>10} {:>12} {:>9}",
        "group",
        "case",
        "tool",
        "median s",
        "size",
        "size/s",
        "vs cgal"
    );
    for r in rows {
        let cg = rows
            .iter()
            .find(|c| c.tool == "cgal" && c.group == r.group && c.case == r.case);
        let ratio = match cg {
            Some(c) if r.tool != "cgal" => format!("{:.2}x", c.median_s / r.median_s),
            _ => String::from("-"),
        };
        outln!(
            "{:<9} {:<26} {:<5} {:>10.4} {:>10} {:>12.0} {:>9}",
            r.group,
            r.case,
            r.tool,
            r.median_s,
            format!(
                "{} {}",
                r.size,
                if r.size_unit == "points" { "pts" } else { "v" }
            ),
            r.size as f64 / r.median_s,
            ratio
        );
    }
    outln!(
        "(medians of the runs; 'vs cgal' = CGAL median / our median, the two tools run alternately in this run: >1 means we are faster)"
    );
}
