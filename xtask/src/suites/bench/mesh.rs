//! Mesh group of `cargo xtask bench` (ours): catalog surfaces through the mesher, beside
//! CGAL's Surface_mesher with `--vs-cgal`.

use super::cgal::{CgalBaseline, cgal_criteria_args};
use super::common::{BenchArgs, Row, cgal_mesh_options, median};
use anyhow::Result;
use std::time::Instant;

/// The catalog sphere and torus with CGAL Surface_mesher's criteria (angle 30, radius r,
/// distance r).
pub fn bench_mesh(a: &BenchArgs, rows: &mut Vec<Row>) -> Result<()> {
    let mut cases = vec![("sphere", 0.02), ("torus", 0.0194)];
    if a.quick {
        cases = vec![("sphere", 0.05), ("torus", 0.05)];
    }
    for (name, r) in cases {
        let surf = oracle::catalog::surface(name)?;
        let opts = cgal_mesh_options(r);
        let mut cgal = CgalBaseline::new(
            a.vs_cgal,
            "cgal_surface_mesher",
            [
                vec!["--surface".into(), name.into()],
                cgal_criteria_args(r),
                vec!["--manifold".into()],
            ]
            .concat(),
        );
        let mut times = Vec::new();
        let mut res = None;
        for _ in 0..a.runs {
            let t = Instant::now();
            let out = rdt_mesher::mesh(&surf, &opts)?;
            times.push(t.elapsed().as_secs_f64());
            res = Some(out.stats);
            if let Some(c) = cgal.as_mut() {
                c.run_once()?;
            }
        }
        let st = res.unwrap();
        let case = format!("{name} r={r}");
        rows.push(Row {
            group: "mesh".into(),
            case: case.clone(),
            tool: "rdt".into(),
            median_s: median(&mut times.clone()),
            runs: times,
            size: st.vertices,
            size_unit: "vertices".into(),
            extra: serde_json::json!({"facets": st.facets, "time_delaunay_s": st.time_delaunay_s, "time_oracle_s": st.time_oracle_s, "criteria_met": st.criteria_met}),
        });
        if let Some(c) = cgal {
            rows.push(c.row("mesh", &case, "vertices", "vertices"));
        }
    }
    Ok(())
}
