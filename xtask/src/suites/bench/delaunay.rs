//! Delaunay group of `cargo xtask bench` (ours): `insert_bulk` on random points, beside
//! CGAL's `Delaunay_triangulation_3` with `--vs-cgal`.

use super::cgal::CgalBaseline;
use super::common::{BenchArgs, Row, median};
use anyhow::{Context, Result};
use geom::SplitMix64;
use glam::DVec3;
use std::time::Instant;

/// Same generator as bench/cgal (SplitMix64), so both tools triangulate the same points.
pub fn random_points(n: usize, seed: u64, distribution: &str) -> Vec<DVec3> {
    let mut rng = SplitMix64(seed);
    (0..n)
        .map(|_| match distribution {
            "sphere" => loop {
                let x = 2.0 * rng.next_f64() - 1.0;
                let y = 2.0 * rng.next_f64() - 1.0;
                let z = 2.0 * rng.next_f64() - 1.0;
                let s = (x * x + y * y) + z * z;
                if s > 0.0 && s <= 1.0 {
                    let r = s.sqrt();
                    break DVec3::new(x / r, y / r, z / r);
                }
            },
            _ => DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()),
        })
        .collect()
}

pub fn bench_delaunay(a: &BenchArgs, rows: &mut Vec<Row>) -> Result<()> {
    let mut cases: Vec<(usize, &str)> = vec![(100_000, "cube")];
    if !a.quick {
        cases.push((1_000_000, "cube"));
        cases.push((1_000_000, "sphere"));
    }
    for (n, dist) in cases {
        let pts = random_points(n, 1, dist);
        let mut cgal = CgalBaseline::new(
            a.vs_cgal,
            "cgal_delaunay",
            vec![
                "--random".into(),
                n.to_string(),
                "--seed".into(),
                "1".into(),
                "--distribution".into(),
                dist.into(),
            ],
        );
        let mut times = Vec::new();
        let mut cells = 0;
        let mut bytes = 0;
        for _ in 0..a.runs {
            let t = Instant::now();
            let mut tri = delaunay3::Triangulation::new();
            tri.insert_bulk(&pts).context("insert_bulk")?;
            times.push(t.elapsed().as_secs_f64());
            cells = tri.num_finite_cells();
            bytes = tri.memory_bytes();
            drop(tri);
            if let Some(c) = cgal.as_mut() {
                c.run_once()?;
            }
        }
        let case = format!("{n} {dist}");
        let med = median(&mut times.clone());
        rows.push(Row {
            group: "delaunay".into(),
            case: case.clone(),
            tool: "rdt".into(),
            median_s: med,
            runs: times,
            size: n,
            size_unit: "points".into(),
            extra: serde_json::json!({"finite_cells": cells, "points_per_s": n as f64 / med, "bytes_per_point": bytes as f64 / n as f64}),
        });
        if let Some(c) = cgal {
            rows.push(c.row("delaunay", &case, "n", "points"));
        }
    }
    Ok(())
}
