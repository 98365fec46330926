//! Simulated scans of the bunny fixture (the quick subset of `cargo xtask scans`): one
//! closed genus-0 component within the Hausdorff bound, `data-support` PASS; a scan with a
//! missing patch gives a closed manifold bridging the hole, flagged as unsupported.

use glam::DVec3;
use rdt_mesher::pipeline::{Input, Request, SizeRequest, plan};
use verify::Status;
use verify::scan_sim::{ScanSpec, diagonal, simulate};

fn model(name: &str) -> meshio::TriMesh {
    let dir = env!("CARGO_MANIFEST_DIR");
    meshio::read(format!("{dir}/../../fixtures/models/{name}.ply")).unwrap()
}

fn mesh_scan(spec: &ScanSpec) -> (verify::scan_sim::Scan, rdt_mesher::pipeline::Outcome, f64) {
    mesh_model_scan("bunny", spec, 0.008)
}

/// Mesh a scan of a fixture model at `size` × its diagonal; the two-sided Hausdorff distance
/// to the model, as a fraction of the diagonal.
fn mesh_model_scan(
    name: &str,
    spec: &ScanSpec,
    size: f64,
) -> (verify::scan_sim::Scan, rdt_mesher::pipeline::Outcome, f64) {
    mesh_model_scan_with(name, spec, size, false)
}

/// [`mesh_model_scan`], keeping what the data does not support if `keep_unsupported`.
fn mesh_model_scan_with(
    name: &str,
    spec: &ScanSpec,
    size: f64,
    keep_unsupported: bool,
) -> (verify::scan_sim::Scan, rdt_mesher::pipeline::Outcome, f64) {
    let source = model(name);
    let diag = diagonal(&source);
    let scan = simulate(&source, spec);
    let cloud = oracle::pointset::PointCloud {
        points: scan.points.clone(),
        normals: scan.normals.clone(),
    };
    let input = Input::point_cloud(cloud, "scan", "scan".into()).unwrap();
    let req = Request {
        size: SizeRequest::Size(size * diag),
        keep_unsupported,
        ..Default::default()
    };
    let out = plan(&input, &req).unwrap().execute(&mut |_| {}).unwrap();
    // Two-sided Hausdorff to the source mesh, as a fraction of the diagonal.
    let h = [(&out.mesh, &source), (&source, &out.mesh)]
        .map(|(from, to)| {
            let bvh = verify::intersect::triangle_bvh(to);
            let d = verify::MeshDistance::new(to, &bvh);
            let s = verify::data_support::mesh_samples(from, 50_000);
            verify::distance::surface_to_mesh(&d, &s).max
        })
        .into_iter()
        .fold(0.0, f64::max)
        / diag;
    (scan, out, h)
}

/// A row of `cargo xtask scans`' table: 40,000 points of the model with that noise (fraction
/// of the diagonal), density ratio, normals given or not and seed, meshed at the table's size
/// (0.6% of the diagonal).
fn table_row(
    name: &str,
    noise: f64,
    density_ratio: f64,
    normals: bool,
    seed: u64,
) -> (verify::scan_sim::Scan, rdt_mesher::pipeline::Outcome, f64) {
    let spec = ScanSpec {
        points: 40_000,
        noise,
        density_ratio,
        normals,
        seed,
        ..Default::default()
    };
    mesh_model_scan(name, &spec, 0.006)
}

/// The output is one closed oriented manifold of genus `genus` and `verify` passes.
fn assert_one_closed_component_passing(out: &rdt_mesher::pipeline::Outcome, genus: i64) {
    let r = out.report.as_ref().unwrap();
    let t = r.topology.as_ref().unwrap();
    assert!(t.is_closed_oriented_manifold(), "{}", r.summary());
    assert_eq!(t.genera(), vec![Some(genus)], "{}", r.summary());
    assert!(r.passed(), "{}", r.summary());
}

/// The scan's missing patch is reported as an unsupported region.
fn assert_hole_flagged(scan: &verify::scan_sim::Scan, out: &rdt_mesher::pipeline::Outcome) {
    let r = out.report.as_ref().unwrap();
    let (c, radius) = scan.hole.unwrap();
    let ds = r.data_support.as_ref().unwrap();
    assert!(
        ds.unsupported_regions
            .iter()
            .any(|u| (DVec3::from_array(u.centroid) - c).length() < radius),
        "{}",
        r.summary()
    );
}

#[test]
fn a_clean_scan_meshes_to_one_supported_genus_0_component() {
    let spec = ScanSpec {
        points: 15_000,
        noise: 0.001,
        seed: 3,
        ..Default::default()
    };
    let (_, out, h) = mesh_scan(&spec);
    let r = out.report.as_ref().unwrap();
    let t = r.topology.as_ref().unwrap();
    assert!(t.is_closed_oriented_manifold(), "{}", r.summary());
    assert_eq!(t.genera(), vec![Some(0)], "{}", r.summary());
    assert_eq!(
        r.status("data-support"),
        Some(Status::Pass),
        "{}",
        r.summary()
    );
    // 15k points at 0.8% of the diagonal measured 0.82%: coarser than the table's 40k points
    // at 0.6% (0.45%), where the 0.75% bound applies.
    assert!(h < 0.01, "Hausdorff {h}");
}

/// A 10:1 density scan (the table's row `fertility-n0.1-d10-nrm-s2`): genus 4 within the
/// table's 0.75% of the diagonal. Before the k-th-neighbour radius and the midpoint normals
/// (`PointSetParams::scan`), the sparse half's kernels averaged too few points (total weight
/// below 1 on 18% of the sparse half's surface) and the row measured 0.79%.
#[test]
fn a_ten_to_one_density_scan_keeps_its_genus_within_the_bound() {
    let (_, out, h) = table_row("fertility", 0.001, 10.0, true, 2);
    assert_one_closed_component_passing(&out, 4);
    assert!(h <= 0.0075, "Hausdorff {h}");
}

/// The table's row `bunny-n0.5-d10-nrm-s1` (0.5% noise, 10:1 density, given normals): one
/// genus-0 component within the 1.25% bound. With the IMLS trusted from a kernel weight of 1
/// (`PointSetParams::min_weight`, 2 since 2026-12-05) the mesh ran 1.58% of the diagonal past
/// an ear in the sparse half, where the value kept the sign of the planes from one side
/// until the weight faded; now 1.08%.
#[test]
fn a_sparse_thin_part_ends_where_the_data_does() {
    let (_, out, h) = table_row("bunny", 0.005, 10.0, true, 1);
    assert_one_closed_component_passing(&out, 0);
    assert!(h <= 0.0125, "Hausdorff {h}");
}

/// The table's row `bunny-n0.5-d1-est-s0` (0.5% noise, uniform density, estimated normals):
/// the tree propagation flipped 165 normals at the ears, and the mesh ran 3.9% of the
/// diagonal past one. The orientation vote (`imls/normals.rs`, `repair_by_vote`) flips
/// most of them back: 0.91%, within the 1.25% bound.
#[test]
fn estimated_normals_flipped_at_an_ear_are_repaired_by_their_neighbours() {
    let (_, out, h) = table_row("bunny", 0.005, 1.0, false, 0);
    assert_one_closed_component_passing(&out, 0);
    assert!(h <= 0.0125, "Hausdorff {h}");
}

#[test]
fn a_spurious_handle_is_cut_and_fails_data_support_when_kept() {
    // The scan table's fertility row at 0.5% noise, 10:1 density and estimated normals: the
    // IMLS surface has a tunnel at about (0.73, 30.24, 12.55), a quarter of the data's band
    // across, so the raw output (`--keep-unsupported`) has genus 6 where the model has genus
    // 4. Until the handle rule, verify PASSed such a mesh (a point set has no genus to compare
    // with). (Until the orientation vote of 2026-12-08 this test used the fandisk row at 0.5%
    // noise, uniform density: its tunnel came from flipped normals, which the vote repairs.)
    let spec = ScanSpec {
        points: 40_000,
        noise: 0.005,
        density_ratio: 10.0,
        normals: false,
        seed: 2,
        ..Default::default()
    };
    let (_, raw, _) = mesh_model_scan_with("fertility", &spec, 0.006, true);
    let r = raw.report.as_ref().unwrap();
    assert_eq!(r.topology.as_ref().unwrap().genera()[0], Some(6));
    assert_eq!(
        r.check("data-support").unwrap().status,
        Status::Fail,
        "{}",
        r.summary()
    );
    let ds = r.data_support.as_ref().unwrap();
    let h = &ds.unsupported_handles[0];
    let at = DVec3::from_array(h.at);
    assert!(at.distance(DVec3::new(0.73, 30.24, 12.55)) < 1.0, "{h:?}");
    assert!(h.radius < 0.5 * h.band, "{h:?}");
    // By default the handles are cut: genus 4, verify PASS, the decisions reported, one of
    // them at that tunnel.
    let (_, out, _) = mesh_model_scan("fertility", &spec, 0.006);
    assert_one_closed_component_passing(&out, 4);
    let cut: Vec<_> = out
        .stats
        .topology_decisions
        .iter()
        .filter(|d| {
            matches!(
                d.kind,
                rdt_mesher::DecisionKind::CutUnsupportedHandle { .. }
            )
        })
        .collect();
    assert!(!cut.is_empty());
    assert!(cut.iter().any(|d| d.center.distance(at) < 2.0), "{cut:?}");
}

#[test]
fn a_missing_patch_is_bridged_and_flagged() {
    let spec = ScanSpec {
        points: 15_000,
        noise: 0.002,
        hole: 0.05,
        seed: 1,
        ..Default::default()
    };
    let (scan, out, _) = mesh_scan(&spec);
    assert_one_closed_component_passing(&out, 0);
    assert_hole_flagged(&scan, &out);
}

/// The table's fandisk missing-patch row: the hole joins the model's inside to its outside
/// (one clear component of the far field), which 5 winding-number samples, all outside,
/// signed "outside": the inside was meshed as a second wall (32,056 vertices, 76% of the area
/// supported, `data-support` FAIL, 4.1% from the source). Signed from its border cells too,
/// the component stays unknown and each far query takes its own winding number: one wall
/// (18,994 vertices), within 1.25% of the source.
#[test]
fn a_missing_patch_does_not_turn_the_inside_out() {
    let spec = ScanSpec {
        points: 40_000,
        noise: 0.002,
        hole: 0.05,
        normals: true,
        seed: 1,
        ..Default::default()
    };
    let (scan, out, h) = mesh_model_scan("fandisk", &spec, 0.006);
    assert_one_closed_component_passing(&out, 0);
    let n = out.mesh.vertices.len();
    assert!(n < 24_000, "{n} vertices: a second wall?");
    // The bridge has no data to follow: listed, not held to the table's 0.75%.
    assert!(h < 0.02, "Hausdorff {h}");
    assert_hole_flagged(&scan, &out);
}

/// Sparse point sets (300 points of the fertility and bunny fixtures, `fixtures/points/`,
/// with and without normals) at the default size: the IMLS fit is not a manifold where the
/// data is this sparse, and the manifold patch alone (section 6.6.1) stalled with
/// non-manifold edges left. Point sets now have the topological repair of images and broken
/// meshes: a closed oriented manifold without self-intersections, each decision reported.
/// (Its geometry can still fail `verify`: 300 points do not determine fertility's genus,
/// and the certificate says so.)
/// A mesh running past the data is not PASSed (the table's row `bunny-n0.3-d10-est-s1`: the
/// IMLS surface continues past an ear tip in the sparse half, 4.4% of the diagonal from the
/// source where the bound is 0.75%). Before 2026-12-05 `verify` said PASS and called the
/// region a bridge over missing data; the data's winding number there is 0.05 (outside)
/// and the data lies straight across the mesh (alignment 0.91).
#[test]
fn a_mesh_running_past_the_data_fails_data_support() {
    let (_, out, h) = table_row("bunny", 0.003, 10.0, false, 1);
    let r = out.report.as_ref().unwrap();
    assert!(h > 0.02, "Hausdorff {h}: the row changed, pick another");
    assert_eq!(
        r.status("data-support"),
        Some(Status::Fail),
        "{}",
        r.summary()
    );
    let ds = r.data_support.as_ref().unwrap();
    assert!(ds.regions_past_data >= 1, "{}", r.summary());
    let past = &ds.unsupported_regions[0];
    assert!(past.data_winding.unwrap() < 0.25, "{}", r.summary());
    assert!(
        r.summary().contains("extend past the data"),
        "{}",
        r.summary()
    );
}

#[test]
fn sparse_point_sets_still_mesh_to_closed_manifolds() {
    for name in ["fertility_300_normals.ply", "bunny_300.ply"] {
        let file = format!(
            "{}/../../fixtures/points/{name}",
            env!("CARGO_MANIFEST_DIR")
        );
        let input = Input::open(&file, &Default::default()).unwrap();
        let out = plan(&input, &Request::default())
            .unwrap()
            .execute(&mut |_| {})
            .unwrap();
        let r = out.report.as_ref().unwrap();
        let t = r.topology.as_ref().unwrap();
        assert!(t.is_closed_oriented_manifold(), "{name}: {}", r.summary());
        assert_eq!(r.status("self-intersections"), Some(Status::Pass), "{name}");
        assert!(!out.stats.topology_decisions.is_empty(), "{name}: repaired");
    }
}

/// A point set given with its points repeated (merged scans, repeated rows) is the same
/// point set: the duplicates are merged before the fit, and the mesh is the one of the
/// points given once. (As separate points they were each other's nearest neighbours at
/// distance 0: 2,000 sphere points given three times meshed to genus 25 with the manifold
/// patch stalled.)
#[test]
fn repeated_points_give_the_mesh_of_the_points_given_once() {
    let once = oracle::implicit::fibonacci_sphere(2000);
    let thrice: Vec<DVec3> = once.iter().chain(&once).chain(&once).copied().collect();
    let mesh = |points: Vec<DVec3>| {
        let cloud = oracle::pointset::PointCloud {
            points,
            normals: None,
        };
        let input = Input::point_cloud(cloud, "pts", "pts".into()).unwrap();
        let out = plan(&input, &Request::default())
            .unwrap()
            .execute(&mut |_| {})
            .unwrap();
        (input.notes.clone(), out)
    };
    let (_, a) = mesh(once);
    let (notes, b) = mesh(thrice);
    assert!(
        notes
            .iter()
            .any(|n| n.contains("4000 equal to an earlier point, merged")),
        "{notes:?}"
    );
    assert_eq!(a.mesh.vertices, b.mesh.vertices);
    assert_eq!(a.mesh.triangles, b.mesh.triangles);
    let r = b.report.as_ref().unwrap();
    assert!(r.passed(), "{}", r.summary());
    assert_eq!(r.topology.as_ref().unwrap().genera(), vec![Some(0)]);
}

/// Seeds of S (verify's `components-sampled`, the mesher's control points) lie on the data's
/// surface, not on a pocket of S around a noise outlier: a 200k-point scan at 0.3% noise
/// (`cargo xtask scans --points 200000`'s `bunny-n0.3-d10-est-s1`) had a seed 3.1 mm (1.24%
/// of the diagonal) outside the bunny, on a pocket 0.6 mm thick around an outlier, which
/// FAILed `components-sampled` on a right mesh.
#[test]
fn seeds_of_a_noisy_scan_lie_on_the_data_surface() {
    use oracle::Surface;
    let source = model("bunny");
    let diag = diagonal(&source);
    let spec = ScanSpec {
        points: 200_000,
        noise: 0.003,
        density_ratio: 10.0,
        normals: false,
        hole: 0.0,
        seed: 1,
    };
    let scan = simulate(&source, &spec);
    let s = oracle::pointset::PointSetSurface::new(
        &scan.points,
        None,
        &oracle::pointset::PointSetParams::scan(),
    )
    .unwrap();
    let bvh = verify::intersect::triangle_bvh(&source);
    let d = verify::MeshDistance::new(&source, &bvh);
    // The highest point of a noisy scan is an outlier: every seed value had that seed
    // 1.195% of the diagonal from the bunny, before seeds started from neighbourhood
    // centroids; 0.13-0.23% since.
    for seed in 0..4 {
        let worst = s
            .seed_points(seed)
            .iter()
            .map(|&q| d.nearest(q).unwrap().1)
            .fold(0.0, f64::max);
        assert!(
            worst < 0.005 * diag,
            "seed {seed}: a seed {worst} from the source"
        );
    }
}
