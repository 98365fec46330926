//! The high-level API (ours) that every front end uses (the CLI, bindings): an [`Input`] (a
//! surface opened by spec or given) and a [`Request`] in; the mesh, one surface Delaunay ball
//! per facet, the statistics, the `verify` report and a typed [`Verdict`] out. It owns the
//! policy: the default size (section 6.5's sigma = 0.09 d_M^inf, else R / 20), the two-pass
//! mode of section 6.5, the verification options and the verdict.
//!
//! A NIfTI file meshed as `cargo xtask mesh FILE --iso 300 --size 3` does (the same defaults
//! for everything else, the same mesh, the same verdict; without a size, both take sigma =
//! 0.09 d_M^inf, about 380k vertices on this phantom, too slow for a doc test):
//!
//! ```
//! use rdt_mesher::pipeline::{run, Input, InputOptions, Request, SizeRequest};
//! use oracle::image::ImageOptions;
//! let file = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/images/phantom_i16_32.nii.gz");
//! let image = ImageOptions { iso: Some(300.0), ..Default::default() };
//! let input = Input::open(file, &InputOptions { image, ..Default::default() }).unwrap();
//! let out = run(&input, &Request { size: SizeRequest::Size(3.0), ..Default::default() }).unwrap();
//! meshio::write(std::env::temp_dir().join("phantom.ply"), &out.mesh).unwrap();
//! assert_eq!((out.stats.vertices, out.verdict.passed()), (12297, true)); // as the CLI's
//! ```
//!
//! Steps, for front ends that print between them: [`Input::open`], [`plan`] (validates the
//! request, chooses sigma, says why in [`Plan::notes`]), [`Plan::execute`]. Results do not
//! depend on the number of threads of the rayon pool the run is called from.
#![deny(missing_docs)]

mod error;
mod input;
mod outcome;
mod plan;
mod request;

pub use error::{BoxError, PipelineError};
pub use input::{
    Input, InputKind, InputOptions, ReadAs, SHARP_DEG, image_labels, is_image_spec, stem,
};
pub use outcome::{Failure, Outcome, SharpEdges, Stage, TwoPassOutcome, Verdict, verify_balls};
pub use plan::{Event, Plan, plan};
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
