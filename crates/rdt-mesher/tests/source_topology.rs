//! The `input-topology` check: a closed input mesh (fertility, genus 4) meshed at its
//! default size keeps its topology and PASSes; at a size far above the thickness of its
//! handles the output's topology differs, the check FAILs, and its detail says why (parts
//! of the input thinner than sigma).

use rdt_mesher::pipeline::{Input, Request, SizeRequest, plan};
use verify::Status;
use verify::scan_sim::diagonal;

fn fertility() -> meshio::TriMesh {
    let dir = env!("CARGO_MANIFEST_DIR");
    meshio::read(format!("{dir}/../../fixtures/models/fertility.ply")).unwrap()
}

fn run(size: f64) -> verify::Report {
    let m = fertility();
    let input = Input::mesh(&m, "fertility", "fertility".into(), false).unwrap();
    assert_eq!(input.source_topology.as_ref().unwrap().genera, vec![4]);
    let req = Request {
        size: SizeRequest::Size(size * diagonal(&m)),
        ..Default::default()
    };
    let out = plan(&input, &req).unwrap().execute(&mut |_| {}).unwrap();
    out.report.unwrap()
}

#[test]
fn a_closed_mesh_keeps_its_topology_at_its_default_size() {
    let r = run(0.02);
    let c = r.check("input-topology").expect("the check runs");
    assert_eq!(c.status, Status::Pass, "{}", c.detail);
    assert_eq!(r.topology.as_ref().unwrap().genera(), vec![Some(4)]);
}

#[test]
fn a_size_above_the_thin_parts_fails_and_says_why() {
    let r = run(0.2);
    let c = r.check("input-topology").expect("the check runs");
    assert_eq!(c.status, Status::Fail, "{}", c.detail);
    assert!(
        c.detail.contains("input: 1 component of genus [4]") && c.detail.contains("thinner than"),
        "{}",
        c.detail
    );
}

#[test]
fn open_input_meshes_make_no_topology_claim() {
    let mut m = fertility();
    m.triangles.truncate(m.triangles.len() - 10);
    let input = Input::mesh(&m, "open", "open".into(), false).unwrap();
    assert!(input.source_topology.is_none());
}
