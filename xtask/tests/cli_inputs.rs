//! Numeric and list flags of the command line (issues 15 and 17): a negative or out-of-range
//! value is one `error:` line naming the flag with a valid example, not clap's `-- -1` hint.

use std::path::Path;
use std::process::Output;

mod common;
use common::one_error_line;

fn xtask_in(dir: &Path, args: &[&str]) -> Output {
    common::xtask(dir, args)
}

fn xtask(args: &[&str]) -> Output {
    xtask_in(Path::new(env!("CARGO_TARGET_TMPDIR")), args)
}

/// Asserts a usage error (status 2, no panic) whose stderr is ONE `error:` line; returns it.
fn usage_error(out: &Output) -> String {
    let line = one_error_line(out, &[]);
    assert_eq!(out.status.code(), Some(2), "{line}");
    line
}

#[test]
fn numeric_flags_name_the_flag_and_an_example() {
    let cases: [(&[&str], &str); 10] = [
        (
            &["mesh", "x.nii", "--spacing", "-1,1,1"],
            "--spacing -1,1,1: spacing must be three positive finite numbers",
        ),
        (
            &["mesh", "x.nii", "--spacing", "1e308,1e308,1e308"],
            "--spacing 1e308,1e308,1e308: spacing must be",
        ),
        (&["mesh", "x.nii", "--spacing", "1,1"], "--spacing 1,1: "),
        (
            &["mesh", "x.nii", "--spacing", "nan,1,1"],
            "--spacing nan,1,1: ",
        ),
        (
            &["mesh", "x.raw", "--dims", "-4,4,4", "--dtype", "u8"],
            "--dims -4,4,4: dims must be three positive whole numbers, e.g. --dims",
        ),
        (
            &["verify", "m.ply", "--min-angle", "-3"],
            "--min-angle -3: the facet angle bound must be in [0, 60]",
        ),
        (
            &["verify", "m.ply", "--samples-per-edge", "-1"],
            "--samples-per-edge -1: must be a positive whole number",
        ),
        (
            &["verify", "m.ply", "--epsilon", "-0.1"],
            "--epsilon -0.1: ",
        ),
        // A label's surface is its indicator's level set: an --iso beside it was ignored.
        (
            &["mesh", "x.nii", "--label", "2", "--iso", "0.5"],
            "'--label <LABEL>' cannot be used with '--iso <ISO>'",
        ),
        (
            &["mesh", "x.nii", "--labels", "all", "--iso", "0.5"],
            "'--labels <LABELS>' cannot be used with '--iso <ISO>'",
        ),
    ];
    for (args, needle) in cases {
        let e = usage_error(&xtask(args));
        assert!(e.contains(needle), "{args:?}: {needle:?} missing in {e}");
        assert!(!e.contains("-- -"), "{args:?}: clap's hint in {e}");
        assert!(!e.contains("determinant"), "{args:?}: {e}");
    }
    let e = usage_error(&xtask(&["mesh", "x.nii", "--spacing", "-1,1,1"]));
    assert!(e.ends_with("e.g. --spacing 1,1,1"), "{e}");
}

/// issue 17: a .nii with bytes after its voxel data is read as nibabel reads it, with a
/// `note:` naming the file and the count of ignored bytes.
#[test]
fn nifti_trailing_bytes_are_a_note() {
    use oracle::image::{NiftiWriteOptions, synthetic, write_nifti};
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join("xtask-cli-inputs");
    std::fs::create_dir_all(&d).unwrap();
    let aff = glam::DAffine3::from_translation(glam::DVec3::splat(-7.5));
    let ball = synthetic::sample_binary(|p| p.length() - 5.0, [16; 3], aff);
    let p = d.join("ball.nii");
    write_nifti(&p, &ball, &NiftiWriteOptions::new()).unwrap();
    let mut b = std::fs::read(&p).unwrap();
    b.extend_from_slice(b"garbage");
    std::fs::write(&p, &b).unwrap();
    let out = xtask_in(
        &d,
        &[
            "mesh",
            "ball.nii",
            "--size",
            "2",
            "-o",
            "ball.ply",
            "--no-verify",
        ],
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{err}");
    let note = "note: ball.nii: 7 byte(s) after the voxel data (vox_offset 352 + 4096 bytes";
    assert!(err.lines().any(|l| l.starts_with(note)), "{err}");
    assert!(d.join("ball.ply").exists());
}

/// issue 15: `verify --report` bounds its per-component list as `mesh --report` does: the
/// first 20 entries and `components_total`.
#[test]
fn verify_report_lists_are_bounded() {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join("xtask-cli-inputs-verify");
    std::fs::create_dir_all(&d).unwrap();
    let n = 25;
    let mut off = format!("OFF\n{} {} 0\n", 4 * n, 4 * n);
    for i in 0..n {
        for [x, y, z] in [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]] {
            off += &format!("{} {y} {z}\n", x + 3 * i);
        }
    }
    for i in 0..n {
        for [a, b, c] in [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]] {
            off += &format!("3 {} {} {}\n", 4 * i + a, 4 * i + b, 4 * i + c);
        }
    }
    std::fs::write(d.join("tets.off"), off).unwrap();
    let out = xtask_in(&d, &["verify", "tets.off", "--report", "r.json"]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("r.json")).unwrap()).unwrap();
    let topo = &r["topology"];
    assert_eq!(topo["components"].as_array().unwrap().len(), 20, "{topo}");
    assert_eq!(topo["components_total"], 25, "{topo}");
    // Short lists are kept whole (the 13 checks).
    assert!(r["checks"].as_array().unwrap().len() > 10);
    assert!(r.get("checks_total").is_none());
}

/// `--labels all` with one label refused (its forecast over `--max-memory`): that label's
/// error is one line naming it, the other label is meshed and written, and the run ends with
/// a non-zero status naming the label left out (before, the first refusal ended the run and
/// the labels after it were never meshed).
#[test]
fn labels_all_meshes_the_other_labels_when_one_is_refused() {
    let dir =
        Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("labels-go-on-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let n = 40i32;
    let mut b = vec![0u8; (n * n * n) as usize];
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let at = (i + n * (j + n * k)) as usize;
                let d2 = |c: i32| (i - c).pow(2) + (j - 20).pow(2) + (k - 20).pow(2);
                if d2(14) <= 169 {
                    b[at] = 1;
                } else if d2(33) <= 9 {
                    b[at] = 2;
                }
            }
        }
    }
    std::fs::write(dir.join("lab.raw"), &b).unwrap();
    let out = xtask_in(
        &dir,
        &[
            "mesh",
            "lab.raw",
            "--dims",
            "40,40,40",
            "--dtype",
            "u8",
            "--labels",
            "all",
            "--size",
            "0.3",
            "--max-memory",
            "30M",
            "--no-verify",
            "-q",
            "-o",
            "m.ply",
        ],
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert_ne!(out.status.code(), Some(0), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(
        err.contains("error: label 1: --size 0.3: refused before meshing"),
        "{err}"
    );
    assert!(err.contains("1 of 2 label(s) not meshed (1)"), "{err}");
    assert!(!dir.join("m_label1.ply").exists());
    assert!(dir.join("m_label2.ply").exists(), "{err}");
}

/// `--labels all` reads the image once and meshes each label on the crop of its bounding box,
/// as `--label L` does: the same bytes for label 2 both ways, and a note naming the crop.
#[test]
fn labels_all_and_label_write_the_same_mesh() {
    let dir =
        Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("labels-same-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let n = 32i32;
    let mut b = vec![0u8; (n * n * n) as usize];
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let d2 = |c: i32| (i - c).pow(2) + (j - 16).pow(2) + (k - 14).pow(2);
                if d2(9) <= 36 {
                    b[(i + n * (j + n * k)) as usize] = 1;
                } else if d2(24) <= 16 {
                    b[(i + n * (j + n * k)) as usize] = 2;
                }
            }
        }
    }
    std::fs::write(dir.join("lab.raw"), &b).unwrap();
    let common = [
        "lab.raw", "--dims", "32,32,32", "--dtype", "u8", "--size", "0.8",
    ];
    let run = |extra: &[&str]| {
        let mut args = vec!["mesh"];
        args.extend_from_slice(&common);
        args.extend_from_slice(extra);
        let out = xtask_in(&dir, &args);
        let err = String::from_utf8_lossy(&out.stderr).to_string();
        assert_eq!(out.status.code(), Some(0), "{err}");
        err
    };
    let err = run(&["--labels", "all", "-o", "all.ply"]);
    assert!(
        err.contains("label 2: its bounding box and 2 voxels around it (voxels 18..30 x 10..22 x 8..20 of the 32 x 32 x 32 grid)"),
        "{err}"
    );
    run(&["--label", "2", "-o", "one.ply"]);
    let all = std::fs::read(dir.join("all_label2.ply")).unwrap();
    assert_eq!(all, std::fs::read(dir.join("one.ply")).unwrap());
    assert!(dir.join("all_label1.ply").exists());
}
