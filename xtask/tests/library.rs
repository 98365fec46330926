//! The library's high-level API (`rdt_mesher::pipeline`) and the CLI give the same mesh and the
//! same verdict with the same defaults: `cargo xtask mesh FILE` is `Input::open` + `run`.

use rdt_mesher::pipeline::{Input, InputOptions, Request, SizeRequest, run};
use std::path::{Path, PathBuf};

mod common;
use common::{json, root, xtask};

fn scratch(test: &str) -> PathBuf {
    common::scratch_dir("xtask-library", test)
}

/// Runs `xtask mesh ARGS --strict` in `dir` writing `out.ply` and `r.json`; returns (the
/// verdict passed, the report, the mesh).
fn cli_mesh(dir: &Path, args: &[&str]) -> (bool, serde_json::Value, meshio::TriMesh) {
    let mut a = vec!["mesh"];
    a.extend_from_slice(args);
    a.extend_from_slice(&["-q", "--strict", "-o", "out.ply", "--report", "r.json"]);
    let out = xtask(dir, &a);
    let code = out.status.code();
    assert!(
        code == Some(0) || code == Some(3),
        "exit {code:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report = json(&dir.join("r.json"));
    let mesh = meshio::read(dir.join("out.ply")).expect("the output mesh");
    (code == Some(0), report, mesh)
}

/// The library and `cargo xtask mesh FILE --iso 300 ARGS` on a NIfTI file: the same mesh,
/// counts, size, notes and verdict.
fn nifti_agrees(test: &str, size: Option<f64>) {
    let dir = scratch(test);
    let file = root().join("fixtures/images/phantom_i16_32.nii.gz");
    let file = file.to_str().unwrap();
    let size_arg = size.map(|s| s.to_string());
    let mut args = vec![file, "--iso", "300"];
    if let Some(s) = &size_arg {
        args.extend(["--size", s.as_str()]);
    }
    let (cli_passed, report, from_cli) = cli_mesh(&dir, &args);

    let mut opts = InputOptions::default();
    opts.image.iso = Some(300.0);
    let input = Input::open(file, &opts).unwrap();
    let req = Request {
        size: size.map_or(SizeRequest::Auto, SizeRequest::Size),
        ..Default::default()
    };
    let out = run(&input, &req).unwrap();

    assert_eq!(
        out.stats.vertices as u64,
        report["stats"]["vertices"].as_u64().unwrap()
    );
    assert_eq!(
        out.stats.facets as u64,
        report["stats"]["facets"].as_u64().unwrap()
    );
    assert_eq!(
        out.mesh, from_cli,
        "the same mesh, coordinate for coordinate"
    );
    assert_eq!(out.verdict.passed(), cli_passed, "{:?}", out.verdict);
    assert_eq!(Some(report["sigma"].as_f64().unwrap()), out.sigma);
    let notes: Vec<&str> = report["notes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| n.as_str().unwrap())
        .collect();
    assert_eq!(notes, out.notes, "the same notes");
}

/// The acceptance case at a coarse size (the rest: the defaults).
#[test]
fn nifti_file_library_and_cli_agree() {
    nifti_agrees("nifti", Some(3.0));
}

/// The same with the default size (issue 15: 0.09 d_M^inf forecasts about 380k vertices on
/// the phantom, so the default is half its voxel spacing, about 12k vertices).
#[test]
fn nifti_file_with_default_size_library_and_cli_agree() {
    nifti_agrees("nifti-default", None);
}

/// The default size of an image: 0.09 d_M^inf of its estimate when its forecast is at most
/// 100k vertices; on the phantom it is about 380k, so half the voxel spacing (6, 6.5, 6),
/// with a note saying so and that the theorems' sampling condition is not claimed.
#[test]
fn image_default_size_is_affordable_and_says_why() {
    let file = root().join("fixtures/images/phantom_i16_32.nii.gz");
    let mut opts = InputOptions::default();
    opts.image.iso = Some(300.0);
    let input = Input::open(file.to_str().unwrap(), &opts).unwrap();
    let req = Request::default();
    let p = rdt_mesher::pipeline::plan(&input, &req).unwrap();
    let dm = input.dm_inf().expect("an image estimates d_M^inf");
    let f = rdt_mesher::pipeline::Forecast::at(input.area.unwrap(), 0.09 * dm);
    assert!(f.vertices > rdt_mesher::pipeline::AUTO_MAX_VERTICES, "{f}");
    let half = 0.5 * (6.0f64 * 6.5 * 6.0).cbrt();
    let sigma = p.sigma().unwrap();
    assert!(sigma >= half && sigma < half * 1.01, "{sigma} vs {half}");
    let note = p.notes().last().unwrap();
    for needle in [
        "sigma = 0.09 * d_M^inf",
        "half the voxel spacing",
        "not claimed",
    ] {
        assert!(note.contains(needle), "{needle}: {note}");
    }
}

/// Two-pass mode (`--epsilon`) and a failed verdict (a vertex budget): same counts, same
/// verdict.
#[test]
fn two_pass_and_budget_library_and_cli_agree() {
    let dir = scratch("two-pass");
    let (cli_passed, report, from_cli) = cli_mesh(&dir, &["implicit:sphere", "--epsilon", "0.4"]);
    let input = Input::open("implicit:sphere", &InputOptions::default()).unwrap();
    let req = Request {
        size: SizeRequest::Epsilon {
            epsilon: 0.4,
            dm_inf: None,
        },
        ..Default::default()
    };
    let out = run(&input, &req).unwrap();
    assert_eq!(out.mesh, from_cli);
    assert_eq!(
        out.two_pass.as_ref().unwrap().first.stats.vertices as u64,
        report["first"]["vertices"].as_u64().unwrap()
    );
    assert!(cli_passed && out.verdict.passed(), "{:?}", out.verdict);

    let dir = scratch("budget");
    let (cli_passed, report, _) = cli_mesh(
        &dir,
        &["implicit:sphere", "--size", "0.05", "--max-vertices", "50"],
    );
    let req = Request {
        size: SizeRequest::Size(0.05),
        max_vertices: Some(50),
        ..Default::default()
    };
    let out = run(&input, &req).unwrap();
    assert_eq!(
        out.stats.vertices as u64,
        report["stats"]["vertices"].as_u64().unwrap()
    );
    assert!(!cli_passed && !out.verdict.passed());
}
