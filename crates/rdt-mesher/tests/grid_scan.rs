//! Components and handles of an implicit function that the oracle's seed grid does not see:
//! the control point added by the pipeline's grid scan, and `verify`'s `grid-genus` and
//! grid seeds (section 6.4.3's control points; `verify::grid_scan`).

use glam::DVec3;
use oracle::BoundingSphere;
use rdt_mesher::pipeline::{Input, InputOptions, Request, SizeRequest, plan};
use verify::Status;

/// A unit sphere and a sphere of radius 0.05 at distance 4, in a ball of radius 6: the seed
/// grid's step (0.375) is over 3 times the small sphere's diameter.
const BIG_SMALL: &str = "implicit:min(x^2+y^2+z^2-1, (x-4)^2+(y-0.1)^2+(z-0.2)^2-0.0025)";

fn open(spec: &str, center: [f64; 3], radius: f64) -> Input<'static> {
    let opts = InputOptions {
        bounding_sphere: Some(BoundingSphere {
            center: DVec3::from_array(center),
            radius,
        }),
        ..Default::default()
    };
    Input::open(spec, &opts).unwrap()
}

fn sized(s: f64) -> Request {
    Request {
        size: SizeRequest::Size(s),
        ..Default::default()
    }
}

fn check<'r>(r: &'r verify::Report, name: &str) -> &'r verify::Check {
    r.checks
        .iter()
        .find(|c| c.name == name)
        .unwrap_or_else(|| panic!("no {name} check"))
}

/// The small sphere gets a control point and a mesh piece of its own at sizes above and
/// below its diameter; the certificate passes. Before, the mesh was the unit sphere alone.
#[test]
fn a_component_between_seed_grid_nodes_is_meshed() {
    let input = open(BIG_SMALL, [0.0; 3], 6.0);
    for size in [0.1, 0.03] {
        let req = sized(size);
        let p = plan(&input, &req).unwrap();
        assert!(
            p.notes()
                .iter()
                .any(|n| n.contains("found by a grid scan") && n.contains("(4.0")),
            "{:?}",
            p.notes()
        );
        let out = p.execute(&mut |_| {}).unwrap();
        let pieces = verify::topology::vertex_components(&out.mesh);
        assert_eq!(pieces.len(), 2, "size {size}");
        let small = out.mesh.vertices.iter().filter(|v| v.x > 3.0).count();
        assert!(
            small >= 4,
            "size {size}: {small} vertices on the small sphere"
        );
        let r = out.report.as_ref().unwrap();
        assert!(out.verdict.passed(), "size {size}: {}", r.summary());
        assert_eq!(check(r, "grid-genus").status, Status::Pass);
    }
}

/// A catalog surface whose components all hold a seed gets no control point from the scan:
/// its plan is the one without the scan.
#[test]
fn seeded_components_get_no_control_point() {
    let input = Input::open("implicit:barth_octic", &Default::default()).unwrap();
    let req = sized(0.1);
    let p = plan(&input, &req).unwrap();
    assert!(p.mesh_options().control_points.is_none());
    assert!(!p.notes().iter().any(|n| n.contains("grid scan")));
}

/// `verify` against the function: the unit sphere's mesh alone misses the small sphere
/// (found by the grid scan, FAIL at its place), a sphere's mesh has one handle fewer than a
/// torus (FAIL), a torus's one more than a sphere (INFO: not proven wrong), and a sheet thinner
/// than the grid steps gives no genus figure (INFO).
#[test]
fn verify_compares_with_the_grid_scan() {
    let mesh_of = |spec: &str, c: [f64; 3], r: f64, size: f64| {
        let input = open(spec, c, r);
        let req = Request {
            verify: false,
            ..sized(size)
        };
        plan(&input, &req)
            .unwrap()
            .execute(&mut |_| {})
            .unwrap()
            .mesh
    };
    let against = |mesh: &meshio::TriMesh, spec: &str, c: [f64; 3], r: f64| {
        let input = open(spec, c, r);
        let opts = verify::Options {
            grid_scan: Some(verify::grid_scan::DEFAULT_NODES),
            // The distances of a mesh far from S are slow to find: the fewest samples.
            samples_per_edge: 1,
            self_intersections: false,
            ..Default::default()
        };
        verify::check_against(mesh, input.surface(), &opts)
    };
    let torus = "implicit:(sqrt(x^2+y^2)-1)^2+z^2-0.16";
    let sphere = "implicit:x^2+y^2+z^2-1";
    let unit = mesh_of(sphere, [0.0; 3], 6.0, 0.1);
    let r = against(&unit, BIG_SMALL, [0.0; 3], 6.0);
    let c = check(&r, "components-sampled");
    assert_eq!(c.status, Status::Fail, "{}", c.detail);
    assert!(
        c.detail.contains("(3.9") || c.detail.contains("(4.0"),
        "{}",
        c.detail
    );
    // The S -> mesh side of `hausdorff` counts it: the small sphere is about 3 away.
    let s2m = |r: &verify::Report| r.geometry.as_ref().unwrap().surface_to_mesh.max;
    assert!((2.9..3.1).contains(&s2m(&r)), "{}", s2m(&r));
    // Without the scan the seeds and the S -> mesh samples miss it (the old verdict).
    let input = open(BIG_SMALL, [0.0; 3], 6.0);
    let plain = verify::check_against(&unit, input.surface(), &Default::default());
    assert_eq!(check(&plain, "components-sampled").status, Status::Pass);
    assert!(s2m(&plain) < 0.1, "{}", s2m(&plain));
    assert!(plain.checks.iter().all(|c| c.name != "grid-genus"));

    let r = against(&unit, torus, [0.0; 3], 1.5);
    let c = check(&r, "grid-genus");
    assert_eq!(c.status, Status::Fail, "{}", c.detail);
    assert!(c.detail.contains("total genus 0") && c.detail.contains("1 handles"));
    let ring = mesh_of(torus, [0.0; 3], 1.5, 0.05);
    let r = against(&ring, torus, [0.0; 3], 1.5);
    assert_eq!(check(&r, "grid-genus").status, Status::Pass);
    let r = against(&ring, sphere, [0.0; 3], 1.5);
    let c = check(&r, "grid-genus");
    assert_eq!(c.status, Status::Info, "{}", c.detail);
    assert!(c.detail.contains("more handles"), "{}", c.detail);
    // A pretzel whose lobes end in sheets 0.004 thin: the scans (steps 0.039 and 0.020)
    // break them into different numbers of pieces.
    let pretzel = "implicit:(x*(x-1)^2*(x-2)^2*(x-3)+y^2)^2+z^2-0.002";
    let r = against(&unit, pretzel, [1.5, 0.0, 0.0], 2.5);
    let c = check(&r, "grid-genus");
    assert_eq!(c.status, Status::Info, "{}", c.detail);
    assert!(c.detail.contains("disagree"), "{}", c.detail);
}
