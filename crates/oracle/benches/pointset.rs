//! Point-set oracle: construction (kNN, PCA normals, MST orientation) and `value()` /
//! `project()` on 50k noisy samples of a sphere-like blob (no fixture needed).
//! Run: `cargo bench -p oracle --bench pointset`.

use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec3;
use oracle::Surface;
use oracle::pointset::{PointSetParams, PointSetSurface};
use oracle::roots::SplitMix64;
use std::hint::black_box;

mod common;
use common::cycling;

fn bench(c: &mut Criterion) {
    let mut rng = SplitMix64(1);
    // A bumpy closed surface r(u) = 1 + 0.2 sin(3x) sin(2y), 50k points, noise 0.2% of size.
    let pts: Vec<DVec3> = (0..50_000)
        .map(|_| {
            let u = rng.unit_vector();
            let r = 1.0 + 0.2 * (3.0 * u.x).sin() * (2.0 * u.y).sin();
            u * r + (rng.unit_vector() * 0.004 * rng.next_f64())
        })
        .collect();
    let mut g = c.benchmark_group("pointset_50k");
    g.sample_size(10);
    g.bench_function("build_estimated_normals", |b| {
        b.iter(|| PointSetSurface::new(black_box(&pts), None, &PointSetParams::default()).unwrap())
    });
    let s = PointSetSurface::new(&pts, None, &PointSetParams::default()).unwrap();
    g.bench_function("dm_inf_hint_first_call", |b| {
        b.iter(|| {
            let s = PointSetSurface::new(&pts[..20_000], None, &PointSetParams::default()).unwrap();
            s.dm_inf_hint()
        })
    });
    g.finish();
    let mut g = c.benchmark_group("pointset_50k_queries");
    let near: Vec<DVec3> = pts.iter().step_by(50).map(|p| *p * 1.01).collect();
    let boxed: Vec<DVec3> = (0..1000)
        .map(|_| rng.unit_vector() * 1.3 * rng.next_f64())
        .collect();
    g.bench_function("value_near_surface", cycling(&near, |p| s.value(p)));
    g.bench_function("value_bbox", cycling(&boxed, |p| s.value(p)));
    // Crossings of short segments through the surface (as the mesher's dual Voronoi edges).
    let segs: Vec<(DVec3, f64, DVec3, f64)> = near
        .iter()
        .map(|&p| {
            let (a, b) = (p * 0.985, p * 1.015);
            (a, s.value(a), b, s.value(b))
        })
        .filter(|&(_, fa, _, fb)| (fa < 0.0) != (fb < 0.0))
        .collect();
    g.bench_function(
        "crossing_short_segment",
        cycling(&segs, |(a, fa, q, fq)| s.crossing(a, fa, q, fq)),
    );
    g.bench_function("project_near", cycling(&near, |p| s.project(p)));
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
