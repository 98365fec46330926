//! Component accounting against the voxel scan (issue 14): every component the scan finds is
//! meshed, split, dropped on request, or listed as missed, never left out silently; the
//! `components-sampled` check FAILs a missed component and only that.

use rdt_mesher::pipeline::{Input, InputOptions, Request, SizeRequest, run};
use verify::Status;
use verify::scan_components::Fate;

fn t1_crop() -> Input<'static> {
    let file = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../fixtures/images/mni_t1_crop56.nii.gz"
    );
    let image = oracle::image::ImageOptions {
        iso: Some(171.2),
        ..Default::default()
    };
    Input::open(
        file,
        &InputOptions {
            image,
            ..Default::default()
        },
    )
    .unwrap()
}

#[test]
fn every_scan_component_is_accounted_for_and_a_removed_piece_is_missed() {
    let input = t1_crop();
    let req = Request {
        size: SizeRequest::Size(2.0),
        ..Default::default()
    };
    let out = run(&input, &req).unwrap();
    let rep = out.report.as_ref().unwrap();
    let acc = rep.scan_components.as_ref().expect("images are accounted");
    assert_eq!(
        acc.meshed + acc.split + acc.dropped + acc.missed,
        acc.scan,
        "{}",
        acc.summary()
    );
    assert_eq!(acc.missed, 0, "{}", acc.summary());
    assert_eq!(rep.status("components-sampled"), Some(Status::Pass));
    // Remove the smallest mesh piece: its component is now missed, and listed with its seed.
    let mut mesh = out.mesh.clone();
    let piece = smallest_piece(&mesh);
    mesh.triangles.retain(|t| !piece.contains(&t[0]));
    let opts = verify::Options {
        component_seeds: input.control_points.clone(),
        ..Default::default()
    };
    let r = verify::check_against(&mesh, input.surface(), &opts);
    let acc2 = r.scan_components.as_ref().unwrap();
    assert_eq!(
        r.status("components-sampled"),
        Some(Status::Fail),
        "{}",
        r.summary()
    );
    assert!(acc2.missed >= 1, "{}", acc2.summary());
    assert_eq!(acc2.components[0].fate, Fate::Missed);
    // The same piece named as dropped on request: not a failure.
    let dropped = vec![out.mesh.vertices[piece[0] as usize]];
    let opts = verify::Options {
        dropped_points: dropped,
        ..opts
    };
    let r = verify::check_against(&mesh, input.surface(), &opts);
    let acc3 = r.scan_components.as_ref().unwrap();
    assert_eq!(
        (acc3.missed, acc3.dropped),
        (acc2.missed - 1, 1),
        "{}",
        acc3.summary()
    );
}

/// The vertices of the mesh piece with the fewest vertices (the lowest-numbered on ties).
fn smallest_piece(mesh: &meshio::TriMesh) -> Vec<u32> {
    let mut pieces = verify::topology::vertex_components(mesh);
    pieces.sort_by_key(|v| (v.len(), v[0]));
    pieces[0].iter().map(|&v| v as u32).collect()
}
