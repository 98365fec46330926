//! Closed manifolds on real images (issue 14): a crop of the MNI T1 template (fixture) meshed
//! as the image pipeline does (seed tetrahedra, the voxel size as the resolution), where the
//! manifold patch of section 6.6.1 alone leaves non-manifold elements; the topological repair
//! must leave a closed, oriented 2-manifold without self-intersections, report each decision,
//! and `min_component` must drop the small components on request.

use oracle::image::{ImageOptions, ImageSurface, LoadOptions};
use rdt_mesher::{Criteria, DecisionKind, MeshOptions, MeshResult, mesh};

fn crop(iso: f64) -> ImageSurface {
    let p = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../fixtures/images/mni_t1_crop56.nii.gz"
    );
    let opts = ImageOptions {
        iso: Some(iso),
        ..Default::default()
    };
    ImageSurface::open(p, &LoadOptions::default(), &opts)
        .expect("the fixture opens")
        .with_seed_budget(None)
}

fn run(s: &ImageSurface, sigma: f64, resolution: Option<f64>, min: Option<f64>) -> MeshResult {
    let o = MeshOptions {
        criteria: Criteria::uniform(sigma),
        resolution,
        min_component: min,
        max_control_points: s.seed_budget(),
        ..Default::default()
    };
    mesh(s, &o).expect("meshing succeeds")
}

fn assert_closed_manifold(r: &MeshResult) {
    let rep = verify::check(&r.mesh, &verify::Options::default());
    for name in verify::CLOSED_MANIFOLD_CHECKS {
        assert_eq!(
            rep.status(name),
            Some(verify::Status::Pass),
            "{name}: {:?}",
            rep.check(name)
        );
    }
    assert_eq!(
        (r.stats.nonmanifold_edges, r.stats.nonmanifold_vertices),
        (0, 0)
    );
}

#[test]
fn the_t1_crop_is_a_closed_manifold_after_repair_and_not_before() {
    let s = crop(171.2);
    // Without the resolution (the paper's patch alone), the patch stalls.
    let plain = run(&s, 2.0, None, None);
    assert!(plain.stats.nonmanifold_edges + plain.stats.nonmanifold_vertices > 0);
    assert!(plain.stats.topology_decisions.is_empty());
    let r = run(&s, 2.0, Some(1.0), None);
    assert_closed_manifold(&r);
    let d = &r.stats.topology_decisions;
    assert!(!d.is_empty());
    for x in d {
        assert!(
            x.size.is_finite() && x.size > 0.0 && x.center.is_finite(),
            "{x:?}"
        );
        assert!(x.facets_removed + x.facets_added > 0);
    }
    assert!(
        r.stats
            .unmet
            .iter()
            .any(|u| matches!(u, rdt_mesher::Unmet::Repaired { .. }))
    );
    assert_eq!(r.balls.len(), r.mesh.triangles.len());
}

#[test]
fn min_component_drops_specks_and_reports_them() {
    let s = crop(190.5);
    let all = run(&s, 2.0, Some(1.0), None);
    let some = run(&s, 2.0, Some(1.0), Some(8.0));
    assert_closed_manifold(&some);
    let dropped: Vec<f64> = some
        .stats
        .topology_decisions
        .iter()
        .filter_map(|d| match d.kind {
            DecisionKind::DropSmallComponent { volume, .. } => Some(volume),
            _ => None,
        })
        .collect();
    assert!(!dropped.is_empty());
    assert!(dropped.iter().all(|&v| (0.0..8.0).contains(&v)));
    assert!(some.mesh.triangles.len() < all.mesh.triangles.len());
}
