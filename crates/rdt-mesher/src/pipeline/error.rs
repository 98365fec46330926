//! Errors of the high-level pipeline (ours): what is wrong with an input or a request, and the
//! fix in library terms (front ends such as the CLI name their own flags instead).

use crate::MeshError;

/// A boxed error of a backend (image, mesh or point-set reader), kept as the `source`.
pub type BoxError = Box<dyn std::error::Error + Send + Sync + 'static>;

/// Why [`open`](super::Input::open), [`plan`](super::plan) or [`run`](super::run) failed.
///
/// Each message says what is wrong and how to fix it with this API; the error's
/// [`source`](std::error::Error::source) chain carries the backend's own message.
///
/// ```
/// use rdt_mesher::pipeline::{Input, InputOptions, PipelineError};
/// let e = Input::open("implicit:sphree", &InputOptions::default()).unwrap_err();
/// assert!(matches!(e, PipelineError::UnknownName { .. }));
/// assert!(e.to_string().contains("sphere"), "{e}"); // lists the catalog names
/// ```
#[derive(Debug, thiserror::Error)]
pub enum PipelineError {
    /// `implicit:NAME` names no catalog surface and no bounding sphere was given for an
    /// expression.
    #[error(
        "implicit:\"{name}\" is not a catalog name ({}); an expression needs a bounding sphere (InputOptions::bounding_sphere)",
        .names.join(", ")
    )]
    UnknownName {
        /// The text after `implicit:`.
        name: String,
        /// The catalog's names.
        names: Vec<&'static str>,
    },
    /// The spec is neither `implicit:...` nor an existing file or folder.
    #[error(
        "input '{spec}' is neither implicit:NAME/EXPR nor an existing file (catalog names: {})",
        .names.join(", ")
    )]
    NoSuchInput {
        /// The spec given.
        spec: String,
        /// The catalog's names.
        names: Vec<&'static str>,
    },
    /// A volume format the image backend does not read (FreeSurfer, MINC, DICOM, ...).
    #[error(
        "{spec}: {what} is not a format this mesher reads; {how}. The images read are \
         .nii, .nii.gz, .hdr/.img, .nrrd, .nhdr, .mha, .mhd, .tif/.tiff, .raw (with --dims and \
         --dtype), OME-Zarr folders and folders of slices"
    )]
    UnsupportedVolume {
        /// The path given.
        spec: String,
        /// The format it is, e.g. "a FreeSurfer MGH/MGZ volume".
        what: &'static str,
        /// How to convert it.
        how: &'static str,
    },
    /// A backend refused the input (`context` says which step, `source` why).
    #[error("{context}")]
    Backend {
        /// The step that failed, e.g. `opening image brain.nii`.
        context: String,
        /// The backend's error.
        #[source]
        source: BoxError,
    },
    /// A reader or the catalog failed; the message is the reader's own.
    #[error(transparent)]
    Read(BoxError),
    /// [`image_labels`](super::image_labels) on an image whose values are not integer labels.
    #[error("{spec} is not a label image")]
    NotALabelImage {
        /// The image path.
        spec: String,
        /// The image backend's reason.
        #[source]
        source: Box<oracle::image::ImageError>,
    },
    /// `SizeRequest::Size(s)` with s not a positive finite number.
    #[error(
        "size bound {0}: the size bound must be a positive number, e.g. SizeRequest::Size(0.05)"
    )]
    InvalidSize(f64),
    /// `SizeRequest::Epsilon` with epsilon outside (0, 1).
    #[error("epsilon {0}: epsilon must be in (0, 1), e.g. 0.09")]
    InvalidEpsilon(f64),
    /// `SizeRequest::Epsilon { dm_inf: Some(d) }` with d not a positive finite number.
    #[error("d_M^inf {0}: must be a positive number")]
    InvalidDmInf(f64),
    /// `SizeRequest::Epsilon { dm_inf: None }` on an input that knows no d_M^inf.
    #[error(
        "SizeRequest::Epsilon needs d_M^inf, which {input} does not provide: give dm_inf \
         (rdt_mesher::sizing::estimate_dm_inf estimates it) or request a size"
    )]
    NoDmInf {
        /// The input's name.
        input: String,
    },
    /// An epsilon that estimates d_M ([`super::SizeRequest::estimates_dm`]) on the exact
    /// triangles of a mesh ([`super::Input::exact_polyhedron`]): refused before meshing.
    #[error(
        "{input}: epsilon without dm_inf on the exact triangles of a mesh: d_M = 0 at every \
         edge that is not flat ({sharp_edges} edges with normals more than 30 deg apart), so \
         no loose eps-sample exists and the rounds would refine until a budget stops them; \
         open the mesh with InputOptions::smooth_polyhedron to mesh its smooth approximation \
         to epsilon, or request a size"
    )]
    EpsilonOnTriangles {
        /// The input's name.
        input: String,
        /// Its edges with normals more than 30 degrees apart.
        sharp_edges: usize,
    },
    /// The forecast of the requested size exceeds a budget: refused before meshing.
    #[error(
        "{input}: the forecast is {forecast}, over {budget}: sigma = {fits} fits (or raise the \
         budget: --max-vertices / --max-memory, Python's max_vertices= / max_memory=)"
    )]
    OverBudget {
        /// The input's name.
        input: String,
        /// The forecast of the requested size (two-pass mode: of the first pass).
        forecast: super::Forecast,
        /// The budget it exceeds.
        budget: super::Budget,
        /// The smallest size (three significant digits) whose forecast fits every budget.
        fits: f64,
        /// Two-pass mode: the d_M^inf of sigma_0 = epsilon d_M^inf (epsilon = fits / dm_inf
        /// fits).
        dm_inf: Option<f64>,
    },
    /// The mesher failed (`two_pass`: in the two-pass mode of section 6.5).
    #[error("meshing {input}{}", if *.two_pass { " (two passes)" } else { "" })]
    Mesh {
        /// The input's name.
        input: String,
        /// The two-pass mode was running.
        two_pass: bool,
        /// The mesher's error.
        #[source]
        source: MeshError,
    },
}

impl PipelineError {
    /// A backend error with the step that failed.
    pub(crate) fn backend(
        context: impl Into<String>,
        source: impl std::error::Error + Send + Sync + 'static,
    ) -> Self {
        PipelineError::Backend {
            context: context.into(),
            source: Box::new(source),
        }
    }

    /// An image reader's error on `spec`: "opening image SPEC: why", or the reader's own
    /// message when it already starts with the path (not named twice on one line).
    pub(crate) fn opening_image(spec: &str, source: oracle::image::ImageError) -> Self {
        if source.to_string().starts_with(spec) {
            PipelineError::read(source)
        } else {
            PipelineError::backend(format!("opening image {spec}"), source)
        }
    }

    /// A reader's error, reported as it is.
    pub(crate) fn read(source: impl std::error::Error + Send + Sync + 'static) -> Self {
        PipelineError::Read(Box::new(source))
    }
}
