//! The data-support check's handle rule (`verify::data_support`'s `handles`): a thin handle
//! that the data shows passes; the same handle FAILs when its tunnel is below the data's band
//! or when it faces against the data's normals.

mod common;
use common::*;

use glam::DVec3;
use verify::SupportOptions;
use verify::data_support::data_support_oriented;
use verify::scan_sim::{ScanSpec, simulate};

/// A thin torus (tube radius 0.1: its meridian, the shortest loop through the tunnel, is
/// 0.63 long) and a fine scan of it with its exact normals (noise 0.02% of the diagonal).
fn thin_torus_and_scan() -> (meshio::TriMesh, Vec<DVec3>, Vec<DVec3>) {
    let m = torus(1.0, 0.1, 192, 24);
    let spec = ScanSpec {
        points: 40_000,
        noise: 0.0002,
        seed: 3,
        ..Default::default()
    };
    let s = simulate(&m, &spec);
    let n = s.normals.clone().expect("exact normals asked");
    (m, s.points, n)
}

#[test]
fn a_thin_handle_the_data_shows_passes() {
    let (m, p, n) = thin_torus_and_scan();
    let ds = data_support_oriented(&m, &p, Some(&n), &SupportOptions::default()).unwrap();
    assert!(ds.passed(), "{}", ds.detail());
    assert!(ds.unsupported_handles.is_empty());
    // The band is far below the tube: nothing to search.
    assert!(ds.median_band < 0.05, "{}", ds.median_band);
}

#[test]
fn a_handle_below_the_band_fails() {
    // The same mesh and data with the band raised to 1 (as for coarse mesh data): the
    // tunnel's ball (radius about 0.3) is within half a band.
    let (m, p, n) = thin_torus_and_scan();
    let opts = SupportOptions {
        min_band: 1.0,
        ..Default::default()
    };
    let ds = data_support_oriented(&m, &p, Some(&n), &opts).unwrap();
    assert!(!ds.passed());
    let h = &ds.unsupported_handles[0];
    assert_eq!(h.reason, "below_band");
    assert!(h.radius > 0.25 && h.radius < 0.45, "{h:?}");
    assert!(
        ds.detail().contains("handles the data does not show"),
        "{}",
        ds.detail()
    );
}

#[test]
fn a_handle_facing_against_the_data_fails() {
    // The band raised to 0.4 (the tunnel at about 0.8 band: not below it), and the data's
    // normals turned along the tube (as on a tube between two sheets, whose walls face
    // sideways): the handle's agreement is about 0.
    let (m, p, _) = thin_torus_and_scan();
    let along: Vec<DVec3> = p
        .iter()
        .map(|q| DVec3::new(-q.y, q.x, 0.0).normalize())
        .collect();
    let opts = SupportOptions {
        min_band: 0.4,
        ..Default::default()
    };
    let ds = data_support_oriented(&m, &p, Some(&along), &opts).unwrap();
    assert!(
        ds.unsupported_handles
            .iter()
            .any(|h| h.reason == "faces_against_data" && h.agreement.is_some_and(|a| a.abs() < 0.2)),
        "{:?}",
        ds.unsupported_handles
    );
    // With the true normals the same handle passes.
    let (_, _, n) = thin_torus_and_scan();
    let ds = data_support_oriented(&m, &p, Some(&n), &opts).unwrap();
    assert!(
        ds.unsupported_handles.is_empty(),
        "{:?}",
        ds.unsupported_handles
    );
}
