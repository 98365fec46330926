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

/// `input` meshed at a constant size, verified.
fn run_at(input: &Input, size: f64) -> rdt_mesher::pipeline::Outcome {
    let req = Request {
        size: SizeRequest::Size(size),
        ..Default::default()
    };
    run(input, &req).unwrap()
}

/// An `n`^3 image of 1-unit voxels at the identity affine, meshed at `iso`.
fn cube_image(n: usize, voxels: oracle::image::Voxels, iso: f64, name: &str) -> Input<'static> {
    let vol = oracle::image::Volume::new([n; 3], voxels, glam::DAffine3::IDENTITY).unwrap();
    let opts = oracle::image::ImageOptions {
        iso: Some(iso),
        ..Default::default()
    };
    Input::image(oracle::image::ImageSurface::new(vol, &opts).unwrap(), name)
}

#[test]
fn every_scan_component_is_accounted_for_and_a_removed_piece_is_missed() {
    let input = t1_crop();
    let out = run_at(&input, 2.0);
    let rep = out.report.as_ref().unwrap();
    let acc = rep.scan_components.as_ref().expect("images are accounted");
    assert_eq!(
        acc.meshed + acc.split + acc.dropped + acc.missed + acc.vanishing,
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

/// `scan-topology` holds the mesh's pieces to the scan's components one to one: PASS on the
/// crop at 2 mm (every component one piece), FAIL when a component has a second piece (the
/// smallest piece copied, moved by a hundredth of a voxel so it stays on its component),
/// naming where the extra piece is; a removed piece is `components-sampled`'s failure, not
/// this one's.
#[test]
fn a_component_in_two_pieces_fails_scan_topology_and_names_the_extra_piece() {
    let input = t1_crop();
    let out = run_at(&input, 2.0);
    let rep = out.report.as_ref().unwrap();
    assert_eq!(
        rep.status("scan-topology"),
        Some(Status::Pass),
        "{}",
        rep.summary()
    );
    let piece = smallest_piece(&out.mesh);
    let shift = glam::DVec3::splat(0.01);
    let mut mesh = out.mesh.clone();
    let base = mesh.vertices.len() as u32;
    let copied: Vec<[u32; 3]> = out
        .mesh
        .triangles
        .iter()
        .filter(|t| piece.contains(&t[0]))
        .map(|t| t.map(|v| base + piece.iter().position(|&p| p == v).unwrap() as u32))
        .collect();
    mesh.vertices
        .extend(piece.iter().map(|&v| out.mesh.vertices[v as usize] + shift));
    mesh.triangles.extend(copied);
    let opts = verify::Options {
        self_intersections: false,
        ..Default::default()
    };
    let r = verify::check_against(&mesh, input.surface(), &opts);
    let acc = r.scan_components.as_ref().unwrap();
    assert_eq!((acc.split, acc.missed), (1, 0), "{}", acc.summary());
    assert_eq!(
        r.status("scan-topology"),
        Some(Status::Fail),
        "{}",
        r.summary()
    );
    let split = acc
        .components
        .iter()
        .find(|c| c.fate == Fate::Split)
        .unwrap();
    let extra = glam::DVec3::from_array(split.other_pieces_at[0]);
    assert!(
        piece
            .iter()
            .any(|&v| (out.mesh.vertices[v as usize] + shift).distance(extra) < 1e-9),
        "the extra piece's vertex {extra} is on the copy"
    );
    assert!(
        r.check("scan-topology")
            .unwrap()
            .detail
            .contains("split into 2 pieces")
    );
    // The piece removed instead: missed, which `components-sampled` FAILs; the pieces left
    // are still one per component.
    let mut mesh = out.mesh.clone();
    mesh.triangles.retain(|t| !piece.contains(&t[0]));
    let r = verify::check_against(&mesh, input.surface(), &opts);
    assert_eq!(r.status("components-sampled"), Some(Status::Fail));
    assert_eq!(
        r.status("scan-topology"),
        Some(Status::Pass),
        "{}",
        r.summary()
    );
}

/// nibabel's `anatomical.nii` (2 mm voxels) at iso 9444.5, `--size 1` (half a voxel): a
/// piece of the largest component, on the image's border and reached by a face saddle 7
/// above the iso value, is refined to a hundredth of a voxel at its tip; every tube from the
/// tip's triangles crossed the piece itself, and it stayed split (`scan-topology` FAIL). The
/// bridges now also try each piece's triangles nearest the other piece (`mutual_anchors`).
#[test]
fn a_piece_refined_to_a_tip_at_the_join_is_bridged_from_its_side() {
    let file = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../fixtures/images/nibabel_anatomical.nii.gz"
    );
    let image = oracle::image::ImageOptions {
        iso: Some(9444.5),
        ..Default::default()
    };
    let opts = InputOptions {
        image,
        ..Default::default()
    };
    let input = Input::open(file, &opts).unwrap();
    let out = run_at(&input, 1.0);
    let rep = out.report.as_ref().unwrap();
    let acc = rep.scan_components.as_ref().unwrap();
    // 284 since the scan's joins through cell interiors (285 before: two surfaces joined by
    // a tunnel through one cell were counted apart; marching cubes of the interpolant
    // sampled at 1/8 voxel finds 284).
    assert_eq!(
        (acc.scan, acc.meshed, acc.split),
        (284, 284, 0),
        "{}",
        acc.summary()
    );
    assert_eq!(
        rep.status("scan-topology"),
        Some(Status::Pass),
        "{}",
        rep.summary()
    );
    for s in [
        "closed",
        "edge-manifold",
        "vertex-manifold",
        "oriented",
        "self-intersections",
    ] {
        assert_eq!(rep.status(s), Some(Status::Pass), "{s}: {}", rep.summary());
    }
}

#[test]
fn voxels_at_the_iso_value_inside_the_solid_are_not_surfaces() {
    // A 12^3 block at 2 in a background of 0, meshed at iso 1: five single voxels and a line
    // of three at 1 (the iso value) inside it are punctures of zero volume, a 2^3 block of
    // zeros is a real cavity (a second surface).
    let n = 20;
    let idx = |i: usize, j: usize, k: usize| i + n * (j + n * k);
    let mut v = vec![0f32; n * n * n];
    for k in 4..16 {
        for j in 4..16 {
            for i in 4..16 {
                v[idx(i, j, k)] = 2.0;
            }
        }
    }
    for [i, j, k] in [[6, 6, 6], [6, 13, 6], [13, 6, 6], [13, 13, 13], [6, 6, 13]] {
        v[idx(i, j, k)] = 1.0;
    }
    for i in 7..10 {
        v[idx(i, 10, 13)] = 1.0;
    }
    for c in 0..8 {
        v[idx(10 + (c & 1), 10 + ((c >> 1) & 1), 9 + (c >> 2))] = 0.0;
    }
    let input = cube_image(n, oracle::image::Voxels::F32(v), 1.0, "block");
    assert_eq!(input.components, Some(2));
    let out = run_at(&input, 1.0);
    let rep = out.report.as_ref().unwrap();
    let acc = rep.scan_components.as_ref().unwrap();
    assert_eq!(
        (acc.scan, acc.meshed, acc.vanishing, acc.missed),
        (8, 2, 6, 0),
        "{}",
        acc.summary()
    );
    assert_eq!(rep.status("components-sampled"), Some(Status::Pass));
    assert!(
        !out.stats
            .unmet
            .iter()
            .any(|u| matches!(u, rdt_mesher::Unmet::ControlPoints { .. })),
        "every control point is on the mesh: {:?}",
        out.stats.unmet
    );
    assert_eq!(verify::topology::vertex_components(&out.mesh).len(), 2);
}

/// The vertices of the mesh piece with the fewest vertices (the lowest-numbered on ties).
fn smallest_piece(mesh: &meshio::TriMesh) -> Vec<u32> {
    let mut pieces = verify::topology::vertex_components(mesh);
    pieces.sort_by_key(|v| (v.len(), v[0]));
    pieces[0].iter().map(|&v| v as u32).collect()
}

/// A cavity around one voxel just below the iso value, flattened between brighter voxels,
/// whose other crossings sit at voxels equal to the iso value (the shape of the cavities
/// the uint8 MNI T1 has at `--iso 171`: 10 of its 451 components were missed at 2 mm): the
/// scan finds it, no seed tetrahedron fits in it, and the reseeding of missed components
/// (`levels/missed.rs`) meshes it, at 1, 2 and 4 voxels.
#[test]
fn a_flat_cavity_at_voxels_equal_to_the_iso_value_is_meshed() {
    let n = 20;
    let idx = |i: usize, j: usize, k: usize| i + n * (j + n * k);
    let mut v = vec![100u8; n * n * n];
    for k in 4..16 {
        for j in 4..16 {
            for i in 4..16 {
                v[idx(i, j, k)] = 200;
            }
        }
    }
    // Component 221 of the T1 at iso 171: 171, 170, 171, 171 along y, 178 and 180 along x,
    // 173 and 172 along z.
    for (j, val) in [(9, 171), (10, 170), (11, 171), (12, 171)] {
        v[idx(10, j, 10)] = val;
    }
    v[idx(9, 10, 10)] = 178;
    v[idx(11, 10, 10)] = 180;
    v[idx(10, 10, 9)] = 173;
    v[idx(10, 10, 11)] = 172;
    let input = cube_image(n, oracle::image::Voxels::U8(v), 171.0, "flat cavity");
    assert_eq!(input.components, Some(2));
    for size in [1.0, 2.0, 4.0] {
        let out = run_at(&input, size);
        let rep = out.report.as_ref().unwrap();
        let acc = rep.scan_components.as_ref().unwrap();
        assert_eq!(
            (acc.scan, acc.meshed, acc.missed),
            (2, 2, 0),
            "size {size}: {}",
            acc.summary()
        );
        assert_eq!(rep.status("components-sampled"), Some(Status::Pass));
        assert_eq!(verify::topology::vertex_components(&out.mesh).len(), 2);
    }
}

/// nibabel's example4d (first volume, int16, oblique 2 mm voxels) at an iso value equal to
/// some of its voxels, `--size 2`: the refinement used to pile 1.4 million vertices within
/// 2e-12 voxel of one crossing (circumcenters of nearly coincident points, which f64 cannot
/// place, inserted as ball centers) until the vertex budget stopped it. A refinement point
/// closer to a sample point than half its ball's radius is no ball center and is not
/// inserted (`schedule/batch.rs`): the run ends on its own, every scan component meshed.
#[test]
fn inexact_ball_centers_are_not_inserted() {
    let file = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../fixtures/images/nibabel_example4d_vol0.nii.gz"
    );
    let image = oracle::image::ImageOptions {
        iso: Some(495.0),
        ..Default::default()
    };
    let input = Input::open(
        file,
        &InputOptions {
            image,
            ..Default::default()
        },
    )
    .unwrap();
    let req = Request {
        size: SizeRequest::Size(2.0),
        max_vertices: Some(400_000),
        ..Default::default()
    };
    let out = run(&input, &req).unwrap();
    assert!(out.stats.stopped_by.is_none(), "{:?}", out.stats.stopped_by);
    assert!(
        out.mesh.vertices.len() < 200_000,
        "{}",
        out.mesh.vertices.len()
    );
    // Since the control points' merge of 2026-12-08 the nearly coincident seeds that started
    // the pile-up are one point, and no unsound centre arises here; the guard is exercised
    // by `seeds_found_twice_at_one_point_do_not_start_a_cluster` (tests/image.rs), with the
    // pair given as an initial sample.
    let rep = out.report.as_ref().unwrap();
    let acc = rep.scan_components.as_ref().unwrap();
    assert_eq!((acc.missed, acc.split), (0, 0), "{}", acc.summary());
    for check in [
        "closed",
        "edge-manifold",
        "vertex-manifold",
        "self-intersections",
    ] {
        assert_eq!(rep.status(check), Some(Status::Pass), "{check}");
    }
}
