//! `cargo xtask mesh` without a size, with budgets, and its messages (issue 15): the forecast
//! line, the default size and its note, refusals before meshing, flag validation, readable
//! notes and result lines, the report's fields, `--help`.

use std::path::{Path, PathBuf};
use std::process::Output;

mod common;
use common::{fixture, has, root, stderr, stdout, xtask as run};

fn dir(test: &str) -> PathBuf {
    common::scratch_dir("cli-defaults", test)
}

/// `xtask mesh -q WORDS` (split at spaces).
fn mesh(d: &Path, words: &str) -> Output {
    let mut args = vec!["mesh", "-q"];
    args.extend(words.split_whitespace());
    run(d, &args)
}

/// `xtask mesh -q WORDS` that must succeed; its (stdout, stderr).
fn mesh_ok(d: &Path, words: &str) -> (String, String) {
    let o = mesh(d, words);
    assert!(o.status.success(), "{}", stderr(&o));
    (stdout(&o), stderr(&o))
}

/// The one `error:` line of a failed run (no other line but notes and the forecast), with
/// its exit status.
fn one_error(o: &Output) -> (String, Option<i32>) {
    (
        common::one_error_line(o, &["note:", "forecast:"]),
        o.status.code(),
    )
}

/// No Rust Debug text: no `Name { field: ...` struct dumps, no `Some(..)` / `None` options.
fn no_debug_text(text: &str) {
    let bytes: Vec<char> = text.chars().collect();
    for w in bytes.windows(3) {
        assert!(
            !(w[0].is_ascii_alphanumeric() && w[1] == ' ' && w[2] == '{'),
            "a Debug dump in:\n{text}"
        );
    }
    for bad in ["Some(", "None", "Ok(", "Err("] {
        assert!(!text.contains(bad), "{bad} in:\n{text}");
    }
}

fn report(d: &Path, name: &str) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(d.join(name)).unwrap()).unwrap()
}

/// The default torus: the theorems' size is kept (its forecast, about 11k vertices, is within
/// the default's limit), the forecast line comes before meshing, the mesh is the one of
/// sigma = 0.027 exactly, and the report carries the forecast.
#[test]
fn default_torus_keeps_the_theorem_size_and_prints_a_forecast() {
    let d = dir("torus");
    let (out, err) = mesh_ok(&d, "-o t.ply --report t.json");
    has(
        &err,
        &[
            "note: no --size: using sigma = 0.09 * d_M^inf = 0.02700",
            "forecast: about 11k vertices",
        ],
    );
    has(&out, &["10785 vertices", "genus [1]"]);
    let r = report(&d, "t.json");
    assert_eq!(r["sigma"], 0.09 * 0.3);
    let v = r["forecast"]["vertices"].as_u64().unwrap();
    assert!((9_700..=11_900).contains(&v), "forecast {v} vs 10785");
    assert_eq!(r["forecast"]["area"]["method"], "coarse-mesh");
    let same = mesh(&d, "--size 0.027 -o s.ply");
    assert!(same.status.success());
    assert_eq!(
        std::fs::read(d.join("t.ply")).unwrap(),
        std::fs::read(d.join("s.ply")).unwrap()
    );
}

/// An image whose theorem size forecasts far too many vertices: the default is half the
/// voxel spacing, printed with why, and the theorems' sampling condition is not claimed.
#[test]
fn image_default_is_tied_to_the_voxel_spacing_and_says_so() {
    let d = dir("phantom");
    let file = fixture("images/phantom_i16_32.nii.gz");
    let (out, err) = mesh_ok(&d, &format!("{file} --iso 300 --report r.json -o p.ply"));
    has(
        &err,
        &[
            "no --size: sigma = 0.09 * d_M^inf",
            "using sigma = 3.09 instead (half the voxel spacing",
            "not claimed",
            "forecast: about",
            "voxel edges crossed by the iso level",
        ],
    );
    let r = report(&d, "r.json");
    assert_eq!(r["sigma"], 3.09);
    assert_eq!(r["iso"], 300.0);
    assert_eq!(r["input_kind"], "image");
    assert_eq!(
        r["input_stats"]["image"]["dims"],
        serde_json::json!([32, 32, 32])
    );
    assert_eq!(
        r["input_stats"]["image"]["range"],
        serde_json::json!([-5.0, 605.0])
    );
    let (lo, hi) = (&r["bounding_box"]["min"], &r["bounding_box"]["max"]);
    for k in 0..3 {
        assert!(
            lo[k].as_f64().unwrap() < hi[k].as_f64().unwrap(),
            "{lo} {hi}"
        );
    }
    // The forecast is within 2x of the count (here within 10%).
    let (f, v) = (
        r["forecast"]["vertices"].as_f64().unwrap(),
        r["stats"]["vertices"].as_f64().unwrap(),
    );
    assert!((f / v - 1.0).abs() < 0.1, "forecast {f} vs {v}");
    assert_eq!(r["genus"], serde_json::json!([0, 0]));
    assert_eq!(r["genus_summary"], "[0 x 2]");
    has(&out, &["2 components, genus [0 x 2]"]);
}

/// A requested size over the default vertex budget is refused before meshing: one line with
/// the forecast, the size that fits and the flags that raise the budgets; nothing written.
#[test]
fn a_size_over_budget_is_refused_at_once_with_the_size_that_fits() {
    let d = dir("refused");
    let o = mesh(&d, "implicit:sphere --size 0.001 -o x.ply");
    let (e, code) = one_error(&o);
    assert_eq!(code, Some(1));
    has(
        &e,
        &[
            "--size 0.001: refused before meshing",
            "the forecast is about 8.3M vertices",
            "over the vertex budget of 2.0M",
            "fits",
            "--max-vertices",
            "--max-memory",
        ],
    );
    assert!(!d.join("x.ply").exists());
    // The size it names fits: that run is planned and meshed.
    let fits = e
        .split("; --size ")
        .nth(1)
        .and_then(|t| t.split(' ').next())
        .expect("a fitting size");
    let f: f64 = fits.parse().unwrap();
    assert!(f > 0.001 && f < 0.003, "{fits}");
    // Memory: the same with a tiny memory budget names --max-memory.
    let o = mesh(&d, "implicit:sphere --size 0.01 --max-memory 20M -o x.ply");
    let (e, _) = one_error(&o);
    has(
        &e,
        &[
            "--size 0.01",
            "over the memory budget of 20 MiB",
            "--max-memory",
        ],
    );
    // Two passes: the first pass's size is checked, and the epsilon that fits is named.
    let o = mesh(&d, "implicit:sphere --epsilon 0.001 -o x.ply");
    let (e, _) = one_error(&o);
    has(&e, &["--epsilon 0.001", "first pass", "--epsilon 0.00"]);
}

/// A requested vertex budget below the forecast is a stop, not a refusal: a note says the run
/// will stop there, and the mesh written is valid (closed, readable) with the unmet criteria
/// in the report.
#[test]
fn a_requested_vertex_budget_stops_the_run_with_a_valid_mesh() {
    let d = dir("stop");
    let (out, err) = mesh_ok(
        &d,
        "implicit:sphere --size 0.01 --max-vertices 3000 -o s.ply --report s.json",
    );
    has(&err, &["will stop there with criteria unmet"]);
    has(&out, &["stopped by max_vertices (3000)", "unmet: size"]);
    let r = report(&d, "s.json");
    assert!(!r["stats"]["unmet"].as_array().unwrap().is_empty());
    assert_eq!(r["budgets"]["max_vertices"], 3000);
    let m = meshio::read(d.join("s.ply")).unwrap();
    assert!(m.vertices.len() <= 3000 && !m.triangles.is_empty());
}

/// Bad numeric values are usage errors (status 2) on one line naming the flag and a valid
/// example.
#[test]
fn numeric_flags_are_checked_with_an_example() {
    let d = dir("flags");
    let bad: [(&str, &[&str], &str); 8] = [
        ("--size", &["-inf", "nan", "0"], "e.g. --size 0.05"),
        ("--angle", &["100", "-1"], "e.g. --angle 30"),
        ("--distance", &["-1"], "e.g. --distance 0.01"),
        ("--epsilon", &["2"], "e.g. --epsilon 0.09"),
        ("--dm-inf", &["0"], "e.g. --dm-inf 0.3"),
        ("--certify-epsilon", &["inf"], "e.g. --certify-epsilon 0.09"),
        ("--max-vertices", &["0"], "e.g. --max-vertices 200000"),
        ("--max-memory", &["0", "2X", "-1G"], "e.g. 2G"),
    ];
    for (flag, values, example) in bad {
        for value in values {
            let o = mesh(&d, &format!("implicit:sphere {flag} {value} -o x.ply"));
            let (e, code) = one_error(&o);
            assert_eq!(code, Some(2), "{flag} {value}: {e}");
            has(&e, &[&format!("{flag} {value}"), example]);
        }
    }
    let ok = mesh(&d, "implicit:sphere --size 0.3 --max-memory 1.5G -o x.ply");
    assert!(ok.status.success(), "{}", stderr(&ok));
}

/// A grey-level image without --iso: the error names --iso and gives the value range.
#[test]
fn missing_iso_names_the_flag_and_the_range() {
    let d = dir("iso");
    let o = mesh(
        &d,
        &format!("{} -o x.ply", fixture("images/phantom_i16_32.nii.gz")),
    );
    let (e, _) = one_error(&o);
    has(&e, &["--iso", "[-5, 605]"]);
}

/// A mesh input: the notes say what was found in words (no Debug dump), the result line
/// is readable, and the report's input statistics are structured.
#[test]
fn mesh_input_notes_are_words_and_stats_are_structured() {
    let d = dir("cube");
    let cube = fixture("meshes/cube.off");
    let (out, err) = mesh_ok(&d, &format!("{cube} -o c.ply --report c.json"));
    no_debug_text(&out);
    no_debug_text(&err);
    has(
        &err,
        &["8 vertices, 12 triangles, 1 component, closed, consistently oriented"],
    );
    let r = report(&d, "c.json");
    assert_eq!(r["input_stats"]["polyhedron"]["triangles"], 12);
    assert_eq!(r["input_stats"]["sharp_edges"], 12);
    assert_eq!(r["forecast"]["area"]["method"], "input-triangles");
    assert_eq!(r["iso"], serde_json::Value::Null);
}

/// Many components: the result line summarizes the genus by value and stays one line, and the
/// report keeps the full genus list but cuts per-component objects to 20 with their total.
#[test]
fn many_components_give_a_short_line_and_bounded_report_lists() {
    let d = dir("balls");
    // 27 balls of radius 3 voxels on a 3 x 3 x 3 grid, in a 30^3 u8 raw volume.
    let n = 30usize;
    let mut v = vec![0u8; n * n * n];
    for (i, x) in v.iter_mut().enumerate() {
        let p = [i % n, (i / n) % n, i / (n * n)].map(|c| c as f64);
        let c = p.map(|c| (c / 10.0).floor() * 10.0 + 4.5);
        let r2: f64 = (0..3).map(|k| (p[k] - c[k]).powi(2)).sum();
        *x = u8::from(r2 < 9.0);
    }
    std::fs::write(d.join("balls.raw"), &v).unwrap();
    let (out, _) = mesh_ok(
        &d,
        "balls.raw --dims 30,30,30 --dtype u8 --size 1 -o b.ply --report b.json",
    );
    let line = out.lines().find(|l| l.contains("vertices")).unwrap();
    has(line, &["27 components, genus [0 x 27]"]);
    assert!(line.len() < 220, "{} characters: {line}", line.len());
    let r = report(&d, "b.json");
    assert_eq!(r["genus"].as_array().unwrap().len(), 27);
    let topo = &r["verify"]["topology"];
    assert_eq!(topo["components"].as_array().unwrap().len(), 20);
    assert_eq!(topo["components_total"], 27);
}

/// `mesh --help` speaks plain words first and gives the CGAL and pygalmesh names of every
/// criterion, pointing to the GUIDE's table.
#[test]
fn help_gives_plain_words_and_the_cgal_names() {
    let d = dir("help");
    let o = run(&d, &["mesh", "--help"]);
    assert!(o.status.success());
    let h = stdout(&o);
    has(
        &h,
        &[
            "radius_bound",
            "max_radius_surface_delaunay_ball",
            "facet_angle",
            "min_facet_angle",
            "facet_distance",
            "max_facet_distance",
            "docs/GUIDE.md",
            "--max-memory",
        ],
    );
    let size = &h[h.find("--size <SIZE>").unwrap()..];
    let size = &size[..size.find("--epsilon").unwrap()];
    let plain = size
        .find("Target facet size")
        .expect("plain words for --size");
    assert!(plain < size.find("sigma").unwrap(), "{size}");
}

/// The `cargo xtask` alias shows cargo's progress (the first build takes minutes).
#[test]
fn the_cargo_alias_does_not_hide_the_build() {
    let cfg = std::fs::read_to_string(root().join(".cargo/config.toml")).unwrap();
    let alias = cfg.lines().find(|l| l.starts_with("xtask")).unwrap();
    assert!(
        alias.contains("--package xtask") && !alias.contains("--quiet") && !alias.contains(" -q"),
        "{alias}"
    );
}

/// A thin part the suggested size loses (`fixtures/meshes/ball_with_leg.off`, a unit ball
/// with a leg of radius 0.04): without `--size` the size is halved, with a note naming the
/// part, and the mesh keeps the leg and PASSes; asked for, the suggested size FAILs
/// `data-support` and says to try a smaller `--size`.
#[test]
fn a_lost_part_halves_the_default_size_with_a_note() {
    let d = dir("lost-part");
    let file = fixture("meshes/ball_with_leg.off");
    let (out, err) = mesh_ok(&d, &format!("{file} -o a.ply --report a.json"));
    has(
        &err,
        &[
            "note: no --size: using the input's suggested size 0.08845",
            "note: size 0.08845 lost a part of the data (",
            "median edges from the mesh): meshing again at 0.04423",
        ],
    );
    has(&out, &["closed manifold", "genus [0]", "verify: PASS"]);
    let r = report(&d, "a.json");
    let sigma = r["sigma"].as_f64().unwrap();
    assert!((0.04422..0.04423).contains(&sigma), "{sigma}");
    let o = mesh(&d, &format!("{file} --size 0.08845 -o b.ply"));
    let text = format!("{}{}", stdout(&o), stderr(&o));
    has(
        &text,
        &[
            "FAIL data-support",
            "data regions lost",
            "try a smaller --size",
        ],
    );
    assert!(!text.contains("meshing again"), "{text}");
}
