//! What the bench groups share (ours): the flags, the table's rows, the median.

use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct BenchArgs {
    /// Which group: delaunay, mesh, image, pointset, all; or scale (issue 21's sizes, not in all).
    #[arg(default_value = "all")]
    pub name: String,
    /// Also run the CGAL baseline programs (bench/cgal; installs libcgal-dev with apt if missing).
    #[arg(long)]
    pub vs_cgal: bool,
    /// Runs per measurement (the median is reported).
    #[arg(long, default_value_t = 3)]
    pub runs: usize,
    /// Only the small sizes (1e5 points, small meshes).
    #[arg(long)]
    pub quick: bool,
    /// Write all rows as JSON here.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

#[derive(serde::Serialize, Clone, Debug)]
pub struct Row {
    pub group: String,
    pub case: String,
    pub tool: String,
    pub median_s: f64,
    pub runs: Vec<f64>,
    pub size: usize,
    pub size_unit: String,
    pub extra: serde_json::Value,
}

/// The mesher's default options with CGAL Surface_mesher's criteria at `r`
/// (`rdt_mesher::pipeline::cgal_criteria`: angle 30, radius = distance = `r`).
pub fn cgal_mesh_options(r: f64) -> rdt_mesher::MeshOptions {
    rdt_mesher::MeshOptions {
        criteria: rdt_mesher::pipeline::cgal_criteria(r),
        ..Default::default()
    }
}

pub fn median(v: &mut [f64]) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    if v.is_empty() {
        f64::NAN
    } else {
        v[v.len() / 2]
    }
}
