//! Reliability cases of the command line (issue 17) found by hand or by `scripts/mutate.py`,
//! each as a literal input: degenerate `delaunay` inputs are errors, not empty "valid"
//! triangulations; a mesh output without a mesh extension is refused before any work.

use std::path::PathBuf;
use std::process::Output;

mod common;
use common::xtask;

/// A fresh, empty scratch directory for one test (under cargo's per-target tmp dir).
fn scratch(test: &str) -> PathBuf {
    common::scratch_dir("xtask-cli-reliability", test)
}

/// Asserts exit status 1, no panic, and ONE `error:` line on stderr (apart from notes);
/// returns it.
fn one_error(out: &Output) -> String {
    assert_eq!(
        out.status.code(),
        Some(1),
        "stderr:\n{}",
        common::stderr(out)
    );
    common::one_error_line(out, &["note:"])
}

/// issue 17: `delaunay` on an empty file or 0, 1, 3, collinear, coplanar or duplicate points
/// said `"valid": true` with 0 cells. Each is now an error that says why, and writes nothing.
#[test]
fn delaunay_degenerate_inputs_are_errors() {
    let d = scratch("delaunay-degenerate");
    let cases = [
        ("", "there are no points"),
        ("# only a comment\n\n", "there are no points"),
        ("1 2 3\n", "there is only 1 point"),
        (
            "1 2 3\n1 2 3\n1 2 3\n1 2 3\n1 2 3\n",
            "all 5 points are the same point",
        ),
        ("0 0 0\n1 0 0\n0 0 0\n1 0 0\n", "only 2 distinct positions"),
        ("0 0 0\n1 0 0\n0 1 0\n", "only 3 distinct positions"),
        (
            "0 0 0\n1 1 1\n2 2 2\n3 3 3\n-7 -7 -7\n",
            "(5 distinct) all lie on one line",
        ),
        (
            "0 0 0\n1 0 0\n0 1 0\n1 1 0\n5 -3 0\n0 0 0\n",
            "the 6 points (5 distinct) all lie on one plane",
        ),
        // Coplanar but not axis-aligned: the plane x + y + z = 1.
        (
            "1 0 0\n0 1 0\n0 0 1\n-1 1 1\n3 -1 -1\n",
            "all lie on one plane",
        ),
    ];
    for (content, needle) in cases {
        std::fs::write(d.join("p.xyz"), content).unwrap();
        let out = xtask(&d, &["delaunay", "--input", "p.xyz", "--output", "t.txt"]);
        let e = one_error(&out);
        for n in [
            "p.xyz",
            needle,
            "at least 4 points not on one plane",
            "t.txt not written",
        ] {
            assert!(e.contains(n), "{content:?}: {n:?} missing in {e}");
        }
        assert!(out.stdout.is_empty(), "no JSON summary for {content:?}");
        assert!(
            !d.join("t.txt").exists(),
            "{content:?}: an output was written"
        );
    }
    // The smallest non-degenerate input still works: one tetrahedron.
    std::fs::write(d.join("p.xyz"), "0 0 0\n1 0 0\n0 1 0\n0 0 1\n0 0 0\n").unwrap();
    let out = xtask(&d, &["delaunay", "--input", "p.xyz", "--output", "t.txt"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        (v["finite_cells"].as_u64(), v["valid"].as_bool()),
        (Some(1), Some(true))
    );
    let tets = std::fs::read_to_string(d.join("t.txt")).unwrap();
    assert_eq!(tets.lines().count(), 1, "{tets}");
}

#[test]
fn delaunay_random_below_four_points_is_an_error() {
    let d = scratch("delaunay-random-few");
    for n in ["1", "2", "3"] {
        let out = xtask(&d, &["delaunay", "--random", n]);
        let e = one_error(&out);
        assert!(
            e.contains(&format!("--random {n}")) && e.contains("--random 4"),
            "{e}"
        );
    }
    // Grid points: 3 of a 2x2x2 grid are coplanar, 4 may be too; 8 never are.
    let out = xtask(&d, &["delaunay", "--random", "8", "--distribution", "grid"]);
    assert!(out.status.success());
}

/// The output must not be the input (`--output` equal to `--input` overwrote the points).
#[test]
fn delaunay_output_may_not_be_the_input() {
    let d = scratch("delaunay-same");
    let pts = "0 0 0\n1 0 0\n0 1 0\n0 0 1\n";
    std::fs::write(d.join("p.xyz"), pts).unwrap();
    let e = one_error(&xtask(
        &d,
        &["delaunay", "--input", "p.xyz", "--output", "./p.xyz"],
    ));
    assert!(e.contains("that is the input file"), "{e}");
    assert_eq!(std::fs::read_to_string(d.join("p.xyz")).unwrap(), pts);
}

/// `-o` with an unknown or no extension was only refused after meshing, with the name of
/// the temporary file (`/tmp/.x.21871.tmp: unknown mesh file extension "tmp"`).
#[test]
fn mesh_output_without_a_mesh_extension_is_refused_up_front() {
    let d = scratch("mesh-out-ext");
    for (out, needle) in [
        ("x", "no file extension"),
        ("x.abc", "unknown mesh file extension \"abc\""),
    ] {
        let args = ["mesh", "implicit:sphere", "--size", "0.5", "-q", "-o", out];
        let e = one_error(&xtask(&d, &args));
        assert!(e.contains(&format!("-o {out}: {needle}")), "{e}");
        assert!(e.contains(".ply") && !e.contains("tmp"), "{e}");
        assert_eq!(std::fs::read_dir(&d).unwrap().count(), 0, "nothing written");
    }
}
