//! `cargo xtask bench`: timing tables, medians of several runs, with ratios against baselines
//! measured in the same run (our previous stage, or CGAL with --vs-cgal).

mod cgal;
mod common;
mod delaunay;
mod image;
mod mesh;
mod pointset;
mod scale;

use anyhow::{Result, bail};
pub use common::BenchArgs;
use common::Row;

pub fn run(a: &BenchArgs) -> Result<()> {
    if a.runs == 0 {
        bail!("--runs must be at least 1");
    }
    if a.vs_cgal {
        cgal::ensure_cgal()?;
    }
    let mut rows = Vec::new();
    let all = a.name == "all";
    let mut any = false;
    if all || a.name == "delaunay" {
        delaunay::bench_delaunay(a, &mut rows)?;
        any = true;
    }
    if all || a.name == "mesh" {
        mesh::bench_mesh(a, &mut rows)?;
        any = true;
    }
    if all || a.name == "image" {
        image::bench_image(a, &mut rows)?;
        any = true;
    }
    if all || a.name == "pointset" {
        pointset::bench_pointset(a, &mut rows)?;
        any = true;
    }
    if a.name == "scale" {
        scale::bench_scale(a, &mut rows)?;
        any = true;
    }
    if !any {
        bail!(
            "unknown bench group '{}': use delaunay, mesh, image, pointset, scale or all (scale is not in all)",
            a.name
        );
    }
    print_table(&rows);
    if let Some(p) = &a.json {
        std::fs::write(p, serde_json::to_string_pretty(&rows)?)?;
    }
    Ok(())
}

fn print_table(rows: &[Row]) {
    outln!(
        "{:<9} {:<26} {:<5} {:>10} {:>10} {:>12} {:>9}",
        "group",
        "case",
        "tool",
        "median s",
        "size",
        "size/s",
        "vs cgal"
    );
    for r in rows {
        let cg = rows
            .iter()
            .find(|c| c.tool == "cgal" && c.group == r.group && c.case == r.case);
        let ratio = match cg {
            Some(c) if r.tool != "cgal" => format!("{:.2}x", c.median_s / r.median_s),
            _ => String::from("-"),
        };
        outln!(
            "{:<9} {:<26} {:<5} {:>10.4} {:>10} {:>12.0} {:>9}",
            r.group,
            r.case,
            r.tool,
            r.median_s,
            format!(
                "{} {}",
                r.size,
                if r.size_unit == "points" { "pts" } else { "v" }
            ),
            r.size as f64 / r.median_s,
            ratio
        );
    }
    outln!(
        "(medians of the runs; 'vs cgal' = CGAL median / our median, the two tools run alternately in this run: >1 means we are faster)"
    );
}
