//! Insertion throughput (release, single thread).
//!
//! `cargo bench -p delaunay3 --bench insert` runs 1e5 uniform points in a cube.
//! With `DELAUNAY_BENCH_LARGE=1` it also runs 1e6 uniform points in a cube and 1e6 points on
//! a sphere (few samples; several minutes). Each group prints bytes/point (Vec capacities).
//! Reference on this machine (CGAL 5.5 `Delaunay_triangulation_3`, Epick, spatially sorted
//! range insertion): 0.56 s for 1e5 cube, 6.1 s for 1e6 cube, 12.5 s for 1e6 sphere (issue 2,
//! loaded machine). Same-run comparison (`benches/cgal_baseline.sh`, 2026-11-22, load ~3):
//! 1e5 cube 0.285 s vs CGAL 0.312 s; 1e6 cube 3.15 s vs 3.16 s (peak RSS 298 MB vs 567 MB);
//! 1e6 sphere 3.05 s vs 5.46 s (237 MB vs 445 MB). 280 bytes/point (Vec capacities).

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use delaunay3::{DVec3, Triangulation};
use geom::SplitMix64;
use std::hint::black_box;
use std::time::Duration;

fn cube(n: usize, seed: u64) -> Vec<DVec3> {
    let mut r = SplitMix64(seed);
    (0..n)
        .map(|_| DVec3::new(r.next_f64(), r.next_f64(), r.next_f64()))
        .collect()
}

fn sphere(n: usize, seed: u64) -> Vec<DVec3> {
    let mut r = SplitMix64(seed);
    // Rejection from [-1, 1)^3 (`2u - 1` per coordinate, 1e-6 < |p|^2 <= 1), then p / |p|.
    (0..n).map(|_| r.unit_vector()).collect()
}

fn run(c: &mut Criterion, name: &str, pts: &[DVec3], samples: usize) {
    let mut t = Triangulation::new();
    t.insert_bulk(pts).unwrap();
    eprintln!(
        "{name}: {} points, {} finite cells, {:.1} bytes/point",
        pts.len(),
        t.num_finite_cells(),
        t.memory_bytes() as f64 / pts.len() as f64
    );
    let mut g = c.benchmark_group("insert_bulk");
    g.sample_size(samples)
        .measurement_time(Duration::from_secs(1))
        .warm_up_time(Duration::from_millis(1));
    g.throughput(Throughput::Elements(pts.len() as u64));
    g.bench_with_input(BenchmarkId::new(name, pts.len()), pts, |b, pts| {
        b.iter(|| {
            let mut t = Triangulation::new();
            t.insert_bulk(black_box(pts)).unwrap();
            t.num_finite_cells()
        })
    });
    g.finish();
}

fn bench(c: &mut Criterion) {
    run(c, "cube", &cube(100_000, 1), 10);
    if std::env::var_os("DELAUNAY_BENCH_LARGE").is_some() {
        run(c, "cube", &cube(1_000_000, 1), 10);
        run(c, "sphere", &sphere(1_000_000, 1), 10);
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
