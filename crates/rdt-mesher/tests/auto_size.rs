//! The default size of a mesh input, checked against the data (`pipeline::auto_size`):
//! `fixtures/meshes/ball_with_leg.off`, a unit ball with a thin leg (radius 0.04, 1.5 long;
//! the two closed pieces overlap, meshed as the solid of their winding number), at its
//! suggested size (bbox diagonal / 50 = 0.088) loses most of the leg and `data-support`
//! FAILs; without `--size` the size is halved once and the output is one closed piece with
//! the leg, every `verify` check PASS.

use meshio::TriMesh;
use rdt_mesher::pipeline::{Input, Request, SizeRequest, plan};
use verify::Status;

fn ball_with_leg() -> TriMesh {
    let dir = env!("CARGO_MANIFEST_DIR");
    meshio::read(format!("{dir}/../../fixtures/meshes/ball_with_leg.off")).unwrap()
}

fn run(size: SizeRequest) -> rdt_mesher::pipeline::Outcome {
    let m = ball_with_leg();
    let input = Input::mesh(&m, "ball-with-leg", "ball-with-leg".into(), false).unwrap();
    let req = Request {
        size,
        ..Default::default()
    };
    plan(&input, &req).unwrap().execute(&mut |_| {}).unwrap()
}

#[test]
fn a_lost_leg_halves_the_default_size_and_a_requested_size_fails() {
    let m = ball_with_leg();
    let suggested = Input::mesh(&m, "b", "b".into(), false)
        .unwrap()
        .default_size
        .unwrap();
    // As asked: the leg is lost, and the check says so.
    let asked = run(SizeRequest::Size(suggested));
    let r = asked.report.as_ref().unwrap();
    let c = r.check("data-support").unwrap();
    assert_eq!(c.status, Status::Fail, "{}", c.detail);
    assert!(c.detail.contains("data regions lost"), "{}", c.detail);
    assert!(asked.size_halvings.is_empty());
    // Without a size: halved until nothing is lost.
    let auto = run(SizeRequest::Auto);
    assert_eq!(auto.size_halvings.len(), 1, "{:?}", auto.size_halvings);
    assert!(
        auto.size_halvings[0].contains("lost a part of the data"),
        "{:?}",
        auto.size_halvings
    );
    assert_eq!(auto.sigma, Some(0.5 * suggested));
    let r = auto.report.as_ref().unwrap();
    // Every check (the verdict also holds the size criterion, which the repair's closing of
    // the leg's concave junction can leave unmet: r/sigma 1.35 on a 9-digit copy of this mesh).
    assert!(r.passed(), "{:?}", r.failures());
    assert_eq!(r.status("data-support"), Some(Status::Pass));
    assert_eq!(r.topology.as_ref().unwrap().genera(), vec![Some(0)]);
    // The leg's tip is meshed.
    let tip = auto
        .mesh
        .vertices
        .iter()
        .map(|v| v.x)
        .fold(f64::MIN, f64::max);
    assert!(tip > 2.3, "{tip}");
}

/// A mesh stopped by a budget is not halved: its missing parts are the budget's. Here the
/// run is interrupted (`Request::cancel`, what the CLI's Ctrl-C sets) at the first progress
/// event, after a few hundred insertions, deterministically. Before, the size was halved
/// anyway and the halved run, cancelled at once, was the output: an empty mesh (measured).
#[test]
fn an_interrupted_mesh_is_not_halved_and_is_kept() {
    let m = ball_with_leg();
    let input = Input::mesh(&m, "ball-with-leg", "ball-with-leg".into(), false).unwrap();
    let cancel = rdt_mesher::Cancel::default();
    let req = Request {
        cancel: Some(cancel.clone()),
        ..Default::default()
    };
    let suggested = input.default_size.unwrap();
    let out = plan(&input, &req)
        .unwrap()
        .execute(&mut |e| {
            if matches!(e, rdt_mesher::pipeline::Event::Meshing(_)) {
                cancel.cancel();
            }
        })
        .unwrap();
    assert_eq!(
        out.stats.stopped_by,
        Some(rdt_mesher::StopReason::Cancelled)
    );
    assert_eq!(out.sigma, Some(suggested));
    assert!(out.mesh.vertices.len() > 100, "{}", out.mesh.vertices.len());
    assert_eq!(out.size_halvings.len(), 1, "{:?}", out.size_halvings);
    assert!(
        out.size_halvings[0].contains("not halved"),
        "{:?}",
        out.size_halvings
    );
}
