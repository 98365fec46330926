//! The CGAL baselines of `cargo xtask bench --vs-cgal` (ours): building and running the
//! programs of bench/cgal, alternating with our runs.

use super::common::{Row, median};
use anyhow::{Context, Result, bail};
use std::path::{Path, PathBuf};
use std::process::Command;

fn cgal_dir() -> PathBuf {
    PathBuf::from("target/cgal")
}

pub fn ensure_cgal() -> Result<()> {
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

/// The command-line form of `rdt_mesher::pipeline::cgal_criteria(r)` for the CGAL programs:
/// angle 30, radius = distance = `r`.
pub fn cgal_criteria_args(r: f64) -> Vec<String> {
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
pub struct CgalBaseline {
    prog: &'static str,
    args: Vec<String>,
    times: Vec<f64>,
    last: serde_json::Value,
}

impl CgalBaseline {
    /// `None` unless `enabled` (`--vs-cgal`).
    pub fn new(enabled: bool, prog: &'static str, args: Vec<String>) -> Option<Self> {
        enabled.then(|| CgalBaseline {
            prog,
            args,
            times: Vec::new(),
            last: serde_json::Value::Null,
        })
    }

    /// One run of the program; its `seconds` join the times.
    pub fn run_once(&mut self) -> Result<()> {
        let v = run_cgal(self.prog, &self.args)?;
        self.times
            .push(v["seconds"].as_f64().context("CGAL JSON without seconds")?);
        self.last = v;
        Ok(())
    }

    /// The row of the runs made (size read from the last run's JSON field `size_key`).
    pub fn row(self, group: &str, case: &str, size_key: &str, unit: &str) -> Row {
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
