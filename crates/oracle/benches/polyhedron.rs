//! Polyhedron oracle on the bunny (6966 triangles): `value()` (watertight: signed distance /
//! ray parity), `winding_number()` (hierarchical, used for non-watertight meshes),
//! `crossings()` (exact segment-triangle search through the BVH), `project()`, construction.
//! Run: `cargo bench -p oracle --bench polyhedron`.

use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec3;
use meshio::TriMesh;
use oracle::Surface;
use oracle::polyhedron::PolyhedronSurface;
use oracle::roots::SplitMix64;
use std::hint::black_box;

mod common;
use common::cycling;

/// Read a PLY triangle mesh with the project's reader.
fn read_ply(path: &str) -> TriMesh {
    meshio::read(path).expect("fixture mesh")
}

fn bench(c: &mut Criterion) {
    let mesh = read_ply(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../fixtures/models/bunny.ply"
    ));
    let s = PolyhedronSurface::new(&mesh).unwrap();
    let (lo, hi) = s.bbox();
    let mut rng = SplitMix64(1);
    let mut rnd = || lo + (hi - lo) * DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
    // Queries in the bounding box, and queries near the surface (what the mesher asks most).
    let boxed: Vec<DVec3> = (0..1024).map(|_| rnd()).collect();
    let h = s.suggested_size();
    let near: Vec<DVec3> = mesh
        .vertices
        .iter()
        .step_by(3)
        .take(1024)
        .enumerate()
        .map(|(i, v)| *v + DVec3::new((i as f64).sin(), (i as f64 * 1.7).cos(), 0.3) * 0.2 * h)
        .collect();
    // Short segments (mesher-like: ~ sizing length) across the surface, and long chords.
    let short: Vec<(DVec3, DVec3)> = near
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let d = DVec3::new((i as f64 * 0.3).cos(), (i as f64 * 0.5).sin(), 0.5).normalize();
            (*p - d * h, *p + d * h)
        })
        .collect();
    let long: Vec<(DVec3, DVec3)> = (0..256).map(|_| (rnd(), rnd())).collect();
    let mut g = c.benchmark_group("bunny");
    g.bench_function("build", |b| {
        b.iter(|| PolyhedronSurface::new(black_box(&mesh)).unwrap())
    });
    g.bench_function("value_bbox", cycling(&boxed, |p| s.value(p)));
    g.bench_function("value_near_surface", cycling(&near, |p| s.value(p)));
    let winding = |p| s.winding_number(p);
    g.bench_function("winding_number_near_surface", cycling(&near, winding));
    g.bench_function("winding_number_bbox", cycling(&boxed, winding));
    let mut out = Vec::new();
    let mut crossings = |(a, b): (DVec3, DVec3)| {
        out.clear();
        s.crossings(a, b, &mut out);
        out.len()
    };
    g.bench_function("crossings_short", cycling(&short, &mut crossings));
    g.bench_function("crossings_long", cycling(&long, &mut crossings));
    let bipolar = |(a, b): (DVec3, DVec3)| {
        let (fa, fb) = (s.value(a), s.value(b));
        ((fa < 0.0) != (fb < 0.0)).then(|| s.crossing(a, fa, b, fb))
    };
    g.bench_function("crossing_bipolar_short", cycling(&short, bipolar));
    g.bench_function("project_near", cycling(&near, |p| s.project(p)));
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
