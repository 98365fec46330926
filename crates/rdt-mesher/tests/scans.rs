//! Simulated scans of the bunny fixture (the quick subset of `cargo xtask scans`): one
//! closed genus-0 component within the Hausdorff bound, `data-support` PASS; a scan with a
//! missing patch gives a closed manifold bridging the hole, flagged as unsupported.

use glam::DVec3;
use rdt_mesher::pipeline::{Input, Request, SizeRequest, plan};
use verify::Status;
use verify::scan_sim::{ScanSpec, diagonal, simulate};

fn bunny() -> meshio::TriMesh {
    let dir = env!("CARGO_MANIFEST_DIR");
    meshio::read(format!("{dir}/../../fixtures/models/bunny.ply")).unwrap()
}

fn mesh_scan(spec: &ScanSpec) -> (verify::scan_sim::Scan, rdt_mesher::pipeline::Outcome, f64) {
    let source = bunny();
    let diag = diagonal(&source);
    let scan = simulate(&source, spec);
    let cloud = oracle::pointset::PointCloud {
        points: scan.points.clone(),
        normals: scan.normals.clone(),
    };
    let input = Input::point_cloud(cloud, "scan", "scan".into()).unwrap();
    let req = Request {
        size: SizeRequest::Size(0.008 * diag),
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
    let r = out.report.as_ref().unwrap();
    let t = r.topology.as_ref().unwrap();
    assert!(t.is_closed_oriented_manifold(), "{}", r.summary());
    assert_eq!(t.genera(), vec![Some(0)], "{}", r.summary());
    assert!(r.passed(), "{}", r.summary());
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
