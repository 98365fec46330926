//! ns per `value()` and per `crossing()` of the image oracle on a 128^3 f32 tanglecube volume.
//! Run: `cargo bench -p oracle --bench image`.

use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec3;
use oracle::Surface;
use oracle::image::{ImageOptions, ImageSurface, synthetic};
use oracle::roots::SplitMix64;
use std::hint::black_box;

mod common;
use common::cycling;

fn surface(n: usize) -> ImageSurface {
    let opts = ImageOptions {
        iso: Some(0.0),
        dark_foreground: true,
        ..Default::default()
    };
    ImageSurface::new(synthetic::tanglecube_volume(n), &opts).unwrap()
}

fn bench(c: &mut Criterion) {
    let s = surface(128);
    let mut rng = SplitMix64(1);
    let pts: Vec<DVec3> = (0..4096)
        .map(|_| (DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) - 0.5) * 5.0)
        .collect();
    c.bench_function("image128/value", cycling(&pts, |p| s.value(p)));
    // Points in a 6-voxel box near the surface (cache-resident): the arithmetic cost.
    let h = 5.2 / 127.0;
    let local: Vec<DVec3> = (0..4096)
        .map(|_| {
            DVec3::new(1.58, 1.58, 1.0)
                + (DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) - 0.5) * 6.0 * h
        })
        .collect();
    c.bench_function("image128/value_local", cycling(&local, |p| s.value(p)));
    // Sign-changing segments about 2 voxels long straddling the surface (like Voronoi edges of
    // a fine mesh), and 1/4 of the box long (coarse mesh).
    let seeds = s.seed_points(0);
    let mut segs = Vec::new();
    for len in [2.0 * h, 1.3] {
        let mut v = Vec::new();
        for (k, p) in seeds.iter().cycle().enumerate() {
            if v.len() == 1024 || k > 100_000 {
                break;
            }
            let d = rng.unit_vector() * len;
            let (a, b) = (*p - d * rng.next_f64(), *p + d);
            let (fa, fb) = (s.value(a), s.value(b));
            if (fa < 0.0) != (fb < 0.0) {
                v.push((a, fa, b, fb));
            }
        }
        segs.push(v);
    }
    for (name, v) in ["crossing_2voxels", "crossing_long"].iter().zip(&segs) {
        let crossing = |(a, fa, b, fb)| s.crossing(a, fa, b, fb);
        c.bench_function(&format!("image128/{name}"), cycling(v, crossing));
        let tol = s.tolerance();
        let bisection = |(a, fa, b, fb)| {
            oracle::roots::bisect(|p| s.value(p), oracle::roots::Ends::new(a, fa, b, fb), tol)
        };
        c.bench_function(&format!("image128/{name}_bisection"), cycling(v, bisection));
    }
    let mut g = c.benchmark_group("image128/setup");
    g.sample_size(10);
    g.bench_function("topology", |b| {
        b.iter(|| {
            let s = surface(128);
            black_box(s.component_count())
        })
    });
    g.bench_function("dm_inf_hint", |b| {
        b.iter(|| {
            let s = surface(128);
            black_box(s.dm_inf_hint())
        })
    });
    g.bench_function("sample_volume", |b| b.iter(|| black_box(surface(128))));
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
