//! The high-level API (ours) that every front end uses (the CLI, bindings): an [`Input`] (a
//! surface opened by spec or given) and a [`Request`] in; the mesh, one surface Delaunay ball
//! per facet, the statistics, the `verify` report and a typed [`Verdict`] out. It owns the
//! policy: the forecast and the budgets, the default size (section 6.5's sigma = 0.09
//! d_M^inf when its forecast is affordable, else a size forecasting tens of thousands of
//! vertices), the two-pass mode of section 6.5, the verification options and the verdict.
//!
//! A NIfTI file meshed as `cargo xtask mesh FILE --iso 300` does (the same defaults, the
//! same mesh, the same verdict; on this phantom sigma = 0.09 d_M^inf forecasts about 380k
//! vertices, so the default is half its voxel spacing, 3.1):
//!
//! ```
//! use rdt_mesher::pipeline::{run, Input, InputOptions, Request};
//! use oracle::image::ImageOptions;
//! let file = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/images/phantom_i16_32.nii.gz");
//! let image = ImageOptions { iso: Some(300.0), ..Default::default() };
//! let input = Input::open(file, &InputOptions { image, ..Default::default() }).unwrap();
//! let out = run(&input, &Request::default()).unwrap();
//! meshio::write(std::env::temp_dir().join("phantom.ply"), &out.mesh).unwrap();
//! assert_eq!((out.stats.vertices, out.verdict.passed()), (11631, true)); // as the CLI's
//! ```
//!
//! Steps, for front ends that print between them: [`Input::open`], [`plan`] (validates the
//! request, chooses sigma, says why in [`Plan::notes`], forecasts the cost in
//! [`Plan::forecast`] and refuses a size over budget), [`Plan::execute`]. Results do not
//! depend on the number of threads of the rayon pool the run is called from.
#![deny(missing_docs)]

mod angle_sources;
mod auto_size;
mod budget;
mod component_seeds;
mod error;
mod forecast;
mod handles;
mod input;
mod labels;
mod outcome;
mod plan;
pub mod report;
mod request;
pub mod source_topology;
mod unsupported;

pub use budget::{
    AUTO_MAX_VERTICES, AUTO_TARGET_VERTICES, Budget, Budgets, DEFAULT_MAX_MEMORY,
    DEFAULT_MAX_VERTICES,
};
pub use error::{BoxError, PipelineError};
pub use forecast::{
    AreaEstimate, AreaSource, BASE_BYTES, BYTES_PER_VERTEX, Forecast, PROBE_MAX_VERTICES,
    VERTICES_PER_AREA, bytes, count, memory_for, parse_bytes, probe_area, round_up_3,
    triangle_area, vertices_for_memory, voxel_crossing_area,
};
pub use input::{
    ImageStats, Input, InputKind, InputOptions, InputStats, PointStats, ReadAs, SHARP_DEG,
    is_image_spec, stem,
};
pub use labels::{LabelImage, image_labels};
pub use outcome::{
    AdaptiveOutcome, Failure, Outcome, SharpEdges, Stage, TwoPassOutcome, Verdict, verify_balls,
};
pub use plan::{
    Event, POLYHEDRON_SAMPLES, Plan, SECOND_SKIPPED, SMOOTH_FOR_EPSILON, data_support, plan,
};
pub use request::{Request, SizeRequest, cgal_criteria};

/// Mesh `input` as `request` asks: [`plan`] then [`Plan::execute`].
///
/// ```
/// use rdt_mesher::pipeline::{run, Input, Request, SizeRequest};
/// // Any surface: here a catalog one, borrowed.
/// let torus = oracle::catalog::surface("torus").unwrap();
/// let req = Request { size: SizeRequest::Size(0.15), ..Default::default() };
/// let out = run(&Input::borrowed(&torus), &req).unwrap();
/// assert!(out.verdict.passed());
/// let genus = out.report.unwrap().topology.unwrap().genera();
/// assert_eq!(genus, vec![Some(1)]);
/// ```
pub fn run(input: &Input<'_>, request: &Request) -> Result<Outcome, PipelineError> {
    run_with_progress(input, request, &mut |_| {})
}

/// [`run`], calling `progress` while meshing and before verifying.
///
/// ```
/// use rdt_mesher::pipeline::{run_with_progress, Event, Input, Request, SizeRequest};
/// let input = Input::open("implicit:sphere", &Default::default()).unwrap();
/// let req = Request { size: SizeRequest::Size(0.3), verify: false, ..Default::default() };
/// let mut events = 0;
/// let out = run_with_progress(&input, &req, &mut |_e: Event| events += 1).unwrap();
/// assert!(out.report.is_none());
/// ```
pub fn run_with_progress(
    input: &Input<'_>,
    request: &Request,
    progress: &mut (dyn FnMut(Event) + Send),
) -> Result<Outcome, PipelineError> {
    plan(input, request)?.execute(progress)
}
