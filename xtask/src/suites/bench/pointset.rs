//! Point-set group of `cargo xtask bench` (ours; section 6.6.3's IMLS backend): a simulated
//! scan of the fixture bunny through `mesh`'s pipeline, issue 16's speed case.
//!
//! The scan (`verify::scan_sim`, deterministic): 50,000 points of `fixtures/models/bunny.ply`
//! (the Stanford bunny, as `/work/shared/models/bunny_points.ply`), Gaussian noise of 0.2% of
//! the diagonal per coordinate, the exact normals given. Meshed at `--size` 0.56% of the
//! diagonal (about 20k output vertices, as `bunny_points.ply --size 0.0014`), with `mesh`'s
//! defaults (the support band and the drop rule of issue 16 included), without `verify`.
//!
//! Rows: `rdt` is the whole pipeline from the points in memory (the oracle's construction:
//! kd-tree, spacing, noise, radii, far field; then the mesher and the drop rule), the time a
//! user of `mesh` waits but for reading the file; `rdt-mesh` is the mesher alone (the
//! report's `time_total_s`), the figure issue 16 bounds by 1 s. There is no CGAL row: CGAL
//! meshes point sets through other surfaces (Poisson), not this one, so the ratio to
//! compare is the mesher's vertices per second against the implicit rows of the `mesh`
//! group.

use super::common::{BenchArgs, Row, median};
use anyhow::{Context, Result};
use rdt_mesher::pipeline::{Input, Request, SizeRequest, plan};
use std::path::Path;
use std::time::Instant;
use verify::scan_sim::{ScanSpec, diagonal, simulate};

/// Issue 16's bound on the mesher's time for this case (seconds), printed beside the row.
const TARGET_S: f64 = 1.0;

pub fn bench_pointset(a: &BenchArgs, rows: &mut Vec<Row>) -> Result<()> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fixtures/models/bunny.ply");
    let source = meshio::read(&path).with_context(|| format!("reading {}", path.display()))?;
    let diag = diagonal(&source);
    let points = if a.quick { 20_000 } else { 50_000 };
    let spec = ScanSpec {
        points,
        noise: 0.002,
        density_ratio: 1.0,
        normals: true,
        hole: 0.0,
        seed: 0,
    };
    let scan = simulate(&source, &spec);
    let size = if a.quick { 0.009 } else { 0.0056 } * diag;
    let case = format!("bunny scan {}k", points / 1000);
    let (mut total, mut mesher) = (Vec::new(), Vec::new());
    let mut last = None;
    for _ in 0..a.runs {
        let cloud = oracle::pointset::PointCloud {
            points: scan.points.clone(),
            normals: scan.normals.clone(),
        };
        let t = Instant::now();
        let input = Input::point_cloud(cloud, "bench", case.clone())?;
        let req = Request {
            size: SizeRequest::Size(size),
            verify: false,
            ..Default::default()
        };
        let out = plan(&input, &req)?.execute(&mut |_| {})?;
        total.push(t.elapsed().as_secs_f64());
        mesher.push(out.stats.time_total_s);
        last = Some(out.stats);
    }
    let st = last.context("no run")?;
    let med = median(&mut mesher.clone());
    eprintln!(
        "pointset {case}: {} vertices; mesher median {med:.3} s (issue 16's bound: {TARGET_S} s at 50k points, ~20k vertices: {})",
        st.vertices,
        if points == 50_000 {
            if med <= TARGET_S { "met" } else { "NOT met" }
        } else {
            "not this size (--quick)"
        }
    );
    let extra = serde_json::json!({
        "facets": st.facets,
        "points": points,
        "time_delaunay_s": st.time_delaunay_s,
        "time_oracle_s": st.time_oracle_s,
        "target_mesher_s": TARGET_S,
    });
    rows.push(Row {
        group: "pointset".into(),
        case: case.clone(),
        tool: "rdt".into(),
        median_s: median(&mut total.clone()),
        runs: total,
        size: st.vertices,
        size_unit: "vertices".into(),
        extra: extra.clone(),
    });
    rows.push(Row {
        group: "pointset".into(),
        case,
        tool: "rdt-mesh".into(),
        median_s: med,
        runs: mesher,
        size: st.vertices,
        size_unit: "vertices".into(),
        extra,
    });
    Ok(())
}
