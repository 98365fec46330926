//! Shared by the xtask integration tests: scratch directories, the repository root, running
//! the built binary and reading its JSON reports.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The verify checks of a closed, embedded, oriented manifold mesh.
pub const MANIFOLD_CHECKS: [&str; 5] = [
    "closed",
    "edge-manifold",
    "vertex-manifold",
    "oriented",
    "self-intersections",
];

/// A fresh, empty scratch directory `group/test` (under cargo's per-target tmp dir).
pub fn scratch_dir(group: &str, test: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(group)
        .join(test);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The repository root (the tests read committed fixtures only).
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .unwrap()
        .to_path_buf()
}

/// Runs `xtask ARGS` in `dir` (so a default `out/` path would land in the scratch directory).
pub fn xtask(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_xtask"))
        .args(args)
        .current_dir(dir)
        .env("RUST_BACKTRACE", "1")
        .output()
        .expect("cannot run the xtask binary")
}

/// Runs `xtask` with the space-separated words of `line` (no quoting: arguments that hold
/// spaces go through [`xtask`]).
pub fn xtask_line(dir: &Path, line: &str) -> Output {
    xtask(dir, &line.split_whitespace().collect::<Vec<_>>())
}

/// The JSON file at `path` (a `--report`), with a clear panic if it is missing or not JSON.
pub fn json(path: &Path) -> serde_json::Value {
    let s = std::fs::read_to_string(path)
        .unwrap_or_else(|e| panic!("cannot read report {}: {e}", path.display()));
    serde_json::from_str(&s)
        .unwrap_or_else(|e| panic!("report {} is not JSON: {e}", path.display()))
}

/// The path of the committed fixture `fixtures/P`, as a command-line argument.
pub fn fixture(p: &str) -> String {
    root()
        .join("fixtures")
        .join(p)
        .to_str()
        .unwrap()
        .to_string()
}

/// A run's stdout as text.
pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// A run's stderr as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Asserts a failed run without a panic whose stderr holds ONE `error:` line apart from the
/// lines that start with one of `ignore` (e.g. `note:`); returns that line.
pub fn one_error_line(o: &Output, ignore: &[&str]) -> String {
    let err = stderr(o);
    assert!(!o.status.success(), "expected a failure: {}", stdout(o));
    assert!(!err.contains("panicked"), "{err}");
    let lines: Vec<&str> = err
        .lines()
        .filter(|l| !l.trim().is_empty() && !ignore.iter().any(|p| l.starts_with(p)))
        .collect();
    assert_eq!(lines.len(), 1, "expected ONE error line:\n{err}");
    assert!(lines[0].starts_with("error: "), "{err}");
    lines[0].to_string()
}

/// Asserts that `text` contains every one of `needles`.
pub fn has(text: &str, needles: &[&str]) {
    for n in needles {
        assert!(text.contains(n), "missing {n:?} in:\n{text}");
    }
}

/// Asserts that `text` contains none of `needles`.
pub fn lacks(text: &str, needles: &[&str]) {
    for n in needles {
        assert!(!text.contains(n), "unexpected {n:?} in:\n{text}");
    }
}

/// The first line of `text` that starts with `prefix`, with a clear panic if none does.
pub fn line_starting<'a>(text: &'a str, prefix: &str) -> &'a str {
    text.lines()
        .find(|l| l.starts_with(prefix))
        .unwrap_or_else(|| panic!("no line starting with {prefix:?} in:\n{text}"))
}
