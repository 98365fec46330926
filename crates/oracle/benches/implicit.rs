//! ns per evaluation of the catalog surfaces: native closure vs compiled expression (value, and
//! value + exact gradient), the cost of one bipolar-oracle crossing, and construction + seeds.
//!
//! `cargo bench -p oracle --bench implicit`

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use glam::DVec3;
use oracle::expr::Expr;
use oracle::roots::SplitMix64;
use oracle::{Surface, catalog};
use std::hint::black_box;
use std::time::Duration;

const N: usize = 1024;

fn points(name: &str) -> Vec<DVec3> {
    let bs = catalog::entry(name).unwrap().bounding_sphere;
    let mut rng = SplitMix64(42);
    (0..N)
        .map(|_| bs.center + rng.unit_vector() * bs.radius * rng.next_f64().cbrt())
        .collect()
}

fn evals(c: &mut Criterion) {
    let mut g = c.benchmark_group("eval");
    g.throughput(Throughput::Elements(N as u64));
    g.warm_up_time(Duration::from_millis(300));
    g.measurement_time(Duration::from_millis(800));
    for name in catalog::names() {
        let pts = points(name);
        let native = catalog::native_fn(name).unwrap();
        g.bench_with_input(BenchmarkId::new("native", name), &pts, |b, pts| {
            b.iter(|| pts.iter().map(|p| native(black_box(*p))).sum::<f64>())
        });
        // Native-only surfaces (trefoil) have no expression.
        let Some(src) = catalog::entry(name).unwrap().expression else {
            continue;
        };
        let expr = Expr::parse(&src).unwrap();
        g.bench_with_input(BenchmarkId::new("compiled", name), &pts, |b, pts| {
            b.iter(|| pts.iter().map(|p| expr.eval(black_box(*p))).sum::<f64>())
        });
        g.bench_with_input(BenchmarkId::new("compiled_grad", name), &pts, |b, pts| {
            b.iter(|| {
                pts.iter()
                    .map(|p| expr.eval_grad(black_box(*p)).1.x)
                    .sum::<f64>()
            })
        });
    }
    g.finish();
}

fn crossings(c: &mut Criterion) {
    let mut g = c.benchmark_group("crossing");
    g.warm_up_time(Duration::from_millis(300));
    g.measurement_time(Duration::from_millis(800));
    for name in ["sphere", "torus", "chair"] {
        for (kind, s) in [
            ("native", catalog::surface(name).unwrap()),
            ("compiled", catalog::surface_from_expression(name).unwrap()),
        ] {
            // Segments from seed points pushed in and out along the normal.
            let segs: Vec<(DVec3, f64, DVec3, f64)> = s
                .seed_points(1)
                .iter()
                .map(|p| {
                    let n = s.gradient(*p).normalize() * 0.01 * s.bounding_sphere().radius;
                    let (a, b) = (*p - n * 1.3, *p + n * 0.7);
                    (a, s.value(a), b, s.value(b))
                })
                .filter(|(_, fa, _, fb)| (*fa < 0.0) != (*fb < 0.0))
                .collect();
            g.throughput(Throughput::Elements(segs.len() as u64));
            g.bench_function(BenchmarkId::new(kind, name), |b| {
                b.iter(|| {
                    segs.iter()
                        .map(|&(a, fa, b, fb)| s.crossing(a, fa, b, fb).x)
                        .sum::<f64>()
                })
            });
        }
    }
    g.finish();
}

fn construction(c: &mut Criterion) {
    let mut g = c.benchmark_group("build");
    g.sample_size(10);
    g.warm_up_time(Duration::from_millis(300));
    g.measurement_time(Duration::from_secs(1));
    for name in ["torus", "tanglecube", "chair"] {
        g.bench_function(BenchmarkId::new("surface_and_seeds", name), |b| {
            b.iter(|| catalog::surface(name).unwrap().seed_points(1).len())
        });
        g.bench_function(
            BenchmarkId::new("expression_surface_and_seeds", name),
            |b| {
                b.iter(|| {
                    catalog::surface_from_expression(name)
                        .unwrap()
                        .seed_points(1)
                        .len()
                })
            },
        );
    }
    g.finish();
}

criterion_group!(benches, evals, crossings, construction);
criterion_main!(benches);
