//! `cargo xtask test` (ours): the project's whole test suite in one command, what CI runs:
//! the Rust tests, the quick regression suite, the Python package's tests (wheel built and
//! installed in a fresh virtual environment) and the black-box mutation smoke pass.
//!
//! Every step runs even when an earlier one fails; the summary names each step's verdict and
//! time, and the command fails when any step did.

use anyhow::{Result, bail};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

#[derive(clap::Args)]
pub struct TestArgs {
    /// Skip the Python package's tests (they need python3 with pip and venv, and PyPI).
    #[arg(long)]
    pub no_python: bool,
    /// Skip the mutation smoke pass of the CLI's readers.
    #[arg(long)]
    pub no_mutate: bool,
}

/// The workspace root (this crate's parent directory).
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("xtask lives in the workspace")
        .to_path_buf()
}

struct Step {
    name: &'static str,
    cmd: Command,
}

fn cargo() -> Command {
    Command::new(std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into()))
}

pub fn run(a: &TestArgs) -> Result<()> {
    let root = root();
    let mut steps = Vec::new();
    let mut c = cargo();
    // The release profile's optimisations without its LTO (see `[profile.test-release]`).
    c.args(["test", "--workspace", "--profile", "test-release"]);
    steps.push(Step {
        name: "cargo test --workspace --profile test-release",
        cmd: c,
    });
    let mut c = Command::new(std::env::current_exe()?);
    c.args(["regress", "--quick"]);
    steps.push(Step {
        name: "cargo xtask regress --quick",
        cmd: c,
    });
    let py = root.join("python/build_and_test.sh");
    if !a.no_python && py.exists() {
        let mut c = Command::new("bash");
        c.arg(&py);
        steps.push(Step {
            name: "python/build_and_test.sh (wheel, fresh venv, pytest)",
            cmd: c,
        });
    }
    if !a.no_mutate {
        let mut c = Command::new("python3");
        c.args(["scripts/mutate.py", "--per-format", "30"]);
        steps.push(Step {
            name: "python3 scripts/mutate.py --per-format 30",
            cmd: c,
        });
    }
    let mut results = Vec::new();
    for mut s in steps {
        eprintln!("==> {}", s.name);
        let t = Instant::now();
        let ok = match s.cmd.current_dir(&root).status() {
            Ok(st) => st.success(),
            Err(e) => {
                eprintln!("error: {}: could not start: {e}", s.name);
                false
            }
        };
        results.push((s.name, ok, t.elapsed().as_secs_f64()));
    }
    eprintln!("summary:");
    for (name, ok, secs) in &results {
        eprintln!(
            "  {} {name} ({secs:.0} s)",
            if *ok { "PASS" } else { "FAIL" }
        );
    }
    let failed: Vec<_> = results.iter().filter(|r| !r.1).map(|r| r.0).collect();
    if !failed.is_empty() {
        bail!(
            "{} of {} steps failed: {}",
            failed.len(),
            results.len(),
            failed.join("; ")
        );
    }
    Ok(())
}
