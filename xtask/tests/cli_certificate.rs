//! The certificate's messages on the command line (issue 15): the verify line never says a
//! bare PASS beside an unmet criterion, the SKIP hint names each command's flag, the
//! certificate says "no guarantee" above epsilon_1, and image Hausdorff figures are measured;
//! components a point set does not support are dropped and said (issue 16).
use std::path::PathBuf;

mod common;
use common::{has, json, lacks, line_starting, root, stdout, xtask, xtask_line};

fn scratch(test: &str) -> PathBuf {
    common::scratch_dir("xtask-cli-certificate", test)
}

/// A fresh scratch directory for `test` and the run of `line` in it.
fn run_in(test: &str, line: &str) -> (PathBuf, std::process::Output) {
    let d = scratch(test);
    let o = xtask_line(&d, line);
    (d, o)
}

#[test]
fn budget_stop_is_never_a_bare_pass() {
    let (d, o) = run_in(
        "budget",
        "mesh implicit:sphere --size 0.02 --max-vertices 3000 -o s.ply --report r.json",
    );
    let s = stdout(&o);
    assert!(!s.lines().any(|l| l.starts_with("verify: PASS (")), "{s}");
    let r = json(&d.join("r.json"));
    let facets = r["stats"]["unmet_facets"].as_array().unwrap();
    assert!(!facets.is_empty() && facets.len() <= 20, "{facets:?}");
    assert_eq!(facets[0]["criterion"], "size");
    assert!(facets[0]["value"].as_f64().unwrap() > 1.0);
    assert!(r["stats"]["unmet_facets_total"].as_u64().unwrap() >= facets.len() as u64);
}

#[test]
fn skip_hint_names_the_flags_of_each_command() {
    let (d, o) = run_in(
        "hint",
        "mesh implicit:x^2+y^2+z^2-1 --bounding-sphere 0,0,0,2 --size 0.3 -o s.ply",
    );
    assert!(o.status.success());
    let v = xtask_line(
        &d,
        "verify s.ply --against implicit:x^2+y^2+z^2-1 --bounding-sphere 0,0,0,2",
    );
    let s = stdout(&v);
    let line = line_starting(&s, "SKIP loose-epsilon");
    has(line, &["verify: --dm poles", "mesh: --epsilon"]);
    lacks(line, &["mesh: --dm"]);
}

#[test]
fn certificate_above_epsilon_1_is_no_guarantee() {
    let d = scratch("range");
    // The sphere at size 0.3: eps = 0.3 with d_M = 1.
    let o = xtask_line(&d, "mesh implicit:sphere --size 0.3 -o s.ply");
    assert!(o.status.success());
    let v = xtask_line(&d, "verify s.ply --against implicit:sphere");
    let s = stdout(&v);
    lacks(&s, &["PASS loose-epsilon", "PASS theorem-4.7"]);
    has(&s, &["INFO loose-epsilon", "no guarantee at eps"]);
}

#[test]
fn image_hausdorff_is_measured_exactly() {
    let d = scratch("image");
    let img = root().join("fixtures/images/nilearn_motor_10426.nii.gz");
    let img = img.to_str().unwrap();
    let m = xtask(
        &d,
        &["mesh", img, "--iso", "3", "--size", "3", "-o", "p.ply"],
    );
    let s = stdout(&m);
    // A criterion is unmet (a control point off the mesh): not a bare PASS.
    has(&s, &["verify: PASS with unmet criteria (control points: "]);
    let v = xtask(&d, &["verify", "p.ply", "--against", img, "--iso", "3"]);
    let s = stdout(&v);
    let line = line_starting(&s, "INFO hausdorff");
    has(
        line,
        &[
            "exact distance to the trilinear level set",
            "points of S on the voxel edges",
        ],
    );
    // Marching cubes at iso 3 (skimage, affine applied) measures 4.613 from its vertices to
    // this mesh and 1.069 from the mesh to its triangles (the trilinear surface is closer;
    // `python/tests/test_images_vs_marching_cubes.py`, case motor@3 at 1 voxel, 2026-12-04;
    // 6.109 before the coverage's stars of issue 14).
    let two_sided: f64 = line
        .split("two-sided ")
        .nth(1)
        .and_then(|x| x.split(' ').next())
        .and_then(|x| x.parse().ok())
        .unwrap();
    assert!((0.9 * 4.613..=1.1 * 4.613).contains(&two_sided), "{line}");
}

/// Issue 16: a simulated scan whose IMLS surface has a bubble. `mesh` drops it, prints it,
/// and the certificate (on the mesh written) says so; `--keep-unsupported` writes it, and
/// `verify --against` the points FAILs that mesh (the other only for its regions past the
/// data).
#[test]
fn unsupported_components_are_dropped_and_said() {
    use verify::scan_sim::{ScanSpec, diagonal, simulate};
    let d = scratch("bubble");
    let m = meshio::read(root().join("fixtures/models/bunny.ply")).unwrap();
    let spec = ScanSpec {
        points: 20_000,
        noise: 0.005,
        normals: false,
        seed: 0,
        ..Default::default()
    };
    let text: String = (simulate(&m, &spec).points.iter())
        .map(|p| format!("{:.17e} {:.17e} {:.17e}\n", p.x, p.y, p.z))
        .collect();
    std::fs::write(d.join("scan.xyz"), text).unwrap();
    // At 0.6% of the diagonal, as `rdt-mesher`'s `tests/unsupported.rs` (at 0.8% the scan has
    // no bubble since its crossings are found to a scan's precision).
    let size = format!("{:.17e}", 0.006 * diagonal(&m));
    let mesh = |extra: &[&str]| {
        let mut a = vec!["mesh", "-q", "scan.xyz", "--size", &size];
        a.extend(extra);
        stdout(&xtask(&d, &a))
    };
    let s = mesh(&["-o", "rule.ply", "--report", "r.json"]);
    has(
        &s,
        &[
            "closed manifold; genus [",
            "dropped 1 component(s) the data does not support (--keep-unsupported keeps them",
            "1 unsupported components dropped from the output before this check (",
            // The raw mesh of the bunny (genus 0) from this noisy scan has genus 3: its three
            // tunnels within the data's band or facing against it are cut (until 2026-12-05
            // the output had genus 3 and verify said PASS).
            "handle(s) the data does not show (--keep-unsupported keeps them",
            "closed manifold; genus [0]",
            // The mesh runs past the ears' data (up to 5.0% of the diagonal from the source
            // at 0.6%, 3.5-4.9% at 0.8% before, measured with trimesh): until 2026-12-05
            // `data-support` said PASS and called those regions bridges over missing data.
            "FAIL data-support: ",
            "unsupported regions extend past the data (where its winding number says outside",
        ],
    );
    let r = json(&d.join("r.json"));
    let dropped = r["verify"]["data_support"]["dropped_components"]
        .as_array()
        .unwrap();
    assert_eq!(dropped.len(), 1, "{r}");
    // The rules' decisions follow the mesher's own (here a cut of its manifold repair).
    let decisions = r["stats"]["topology_decisions"].as_array().unwrap();
    let drops: Vec<_> = (decisions.iter())
        .filter(|x| x["kind"] == "drop_unsupported_component")
        .collect();
    assert_eq!(drops.len(), 1, "{r}");
    let dec = drops[0];
    assert_eq!(dec["triangles"], dropped[0]["triangles"]);
    let s = mesh(&["--keep-unsupported", "-o", "raw.ply"]);
    has(&s, &["2 components", "FAIL data-support: "]);
    lacks(&s, &["dropped"]);
    let v = stdout(&xtask(&d, &["verify", "raw.ply", "--against", "scan.xyz"]));
    has(
        line_starting(&v, "FAIL data-support"),
        &["1 mesh components below 50% support"],
    );
    let v = stdout(&xtask(&d, &["verify", "rule.ply", "--against", "scan.xyz"]));
    has(
        line_starting(&v, "FAIL data-support"),
        &["unsupported regions extend past the data"],
    );
    lacks(&v, &["below 50% support", "handles the data does not show"]);
    // The raw mesh's tunnels, against the 3-column .xyz (normals estimated by `verify`'s own
    // point-set surface): one is found, and the detail says why (since the trust threshold of
    // 2, session 27, the raw mesh's smallest is 0.87 bands wide and found facing against the
    // data; before, 0.18 bands, below the data's band).
    let v = stdout(&xtask(&d, &["verify", "raw.ply", "--against", "scan.xyz"]));
    let line = line_starting(&v, "FAIL data-support");
    has(
        line,
        &["handles the data does not show (smallest: a tunnel at"],
    );
    assert!(
        line.contains("below the data's band") || line.contains("facing against the data"),
        "{line}"
    );
}

/// `--epsilon` on a mesh from `fixtures/` without `--dm-inf` (issue 18): its smooth IMLS
/// approximation is meshed to eps (the exact triangles have d_M = 0 at their edges; before,
/// the rounds ran to the vertex budget), a note says why, and the report carries the rounds.
#[test]
fn epsilon_on_a_mesh_meshes_its_smooth_approximation() {
    let (d, o) = run_in(
        "epsilon-mesh",
        &format!(
            "mesh {} --epsilon 0.5 -o f.ply --report r.json",
            common::fixture("models/fertility.ply")
        ),
    );
    assert!(o.status.success(), "{}", common::stderr(&o));
    has(
        &common::stderr(&o),
        &["--epsilon on a mesh: meshing its smooth IMLS approximation"],
    );
    let s = stdout(&o);
    has(&s, &["stable estimate", "genus [4]", "verify: PASS"]);
    let r = json(&d.join("r.json"));
    let a = &r["adaptive"];
    assert_eq!(a["converged"], true, "{a}");
    let eps = r["verify"]["certificate"]["eps_achieved"].as_f64().unwrap();
    assert!(eps <= 0.5, "{eps}");
    assert!(a["rounds"].as_array().unwrap().len() >= 2);
}
