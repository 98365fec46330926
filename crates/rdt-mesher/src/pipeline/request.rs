//! What to mesh for (ours): the size request (section 6.5's choices of sigma), the criteria of
//! section 6.1, the oracle of section 6.4.2, the budgets (vertices, memory, time), the seed;
//! and the one spelling of the oracle and initialization names.

use crate::{Criteria, Initialization, OracleKind, Sizing};
use glam::DVec3;
use std::time::Duration;

/// How the size bound sigma is chosen.
///
/// ```
/// use rdt_mesher::pipeline::SizeRequest;
/// let s = SizeRequest::Epsilon { epsilon: 0.2, dm_inf: None }; // d_M^inf from the input
/// assert_ne!(s, SizeRequest::Auto);
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum SizeRequest {
    /// The input's suggested size (meshes, point sets), else sigma = 0.09 d_M^inf when the
    /// input knows d_M^inf, else the bounding radius / 20.
    #[default]
    Auto,
    /// A constant sigma, in the surface's units.
    Size(f64),
    /// Two-pass sizing (section 6.5): a uniform pass at sigma_0 = epsilon * d_M^inf, then an
    /// adaptive pass at sigma = 0.9 epsilon d_M (lambda-medial axis estimate). `dm_inf`:
    /// `None` takes the input's (catalog value, backend estimate).
    Epsilon {
        /// Target epsilon, in (0, 1).
        epsilon: f64,
        /// d_M^inf, if not the input's. With neither, the adaptive mode runs
        /// ([`SizeRequest::Adaptive`]).
        dm_inf: Option<f64>,
    },
    /// Adaptive eps-sampling without a uniform pass ([`crate::adaptive`]): rounds of
    /// refinement on one Del(E), sigma = max(floor, 0.9 epsilon d_M) with d_M estimated from
    /// the current sample, until stable. Needs no d_M^inf.
    Adaptive {
        /// Target epsilon, in (0, 1).
        epsilon: f64,
    },
}

impl SizeRequest {
    /// Whether this size estimates d_M from the surface on an input that gives no d_M^inf
    /// (a mesh): [`SizeRequest::Adaptive`], or [`SizeRequest::Epsilon`] without `dm_inf`.
    /// The exact triangles of a mesh have d_M = 0 at every edge that is not flat, so front
    /// ends open a mesh with `InputOptions::smooth_polyhedron` for such a size (and
    /// [`super::plan`] refuses it on the exact triangles).
    ///
    /// ```
    /// use rdt_mesher::pipeline::SizeRequest;
    /// assert!(SizeRequest::Epsilon { epsilon: 0.3, dm_inf: None }.estimates_dm());
    /// assert!(!SizeRequest::Epsilon { epsilon: 0.3, dm_inf: Some(0.1) }.estimates_dm());
    /// assert!(!SizeRequest::Size(0.1).estimates_dm());
    /// ```
    pub fn estimates_dm(&self) -> bool {
        matches!(
            self,
            SizeRequest::Adaptive { .. } | SizeRequest::Epsilon { dm_inf: None, .. }
        )
    }
}

/// A meshing request: everything but the surface. `Request::default()` is what
/// `cargo xtask mesh` does without options.
///
/// ```
/// use rdt_mesher::pipeline::{Request, SizeRequest};
/// use rdt_mesher::OracleKind;
/// let r = Request { size: SizeRequest::Size(0.1), oracle: OracleKind::Intersection,
///                   ..Default::default() };
/// assert_eq!(r.min_angle_deg, 30.0);
/// assert!(r.verify && r.manifold && r.scaffold);
/// ```
#[derive(Clone, Debug)]
pub struct Request {
    /// How sigma is chosen.
    pub size: SizeRequest,
    /// Facet angle bound in degrees (0 = off); 30 has a termination proof.
    pub min_angle_deg: f64,
    /// Distance bound between a facet's circumcenter and its ball center (CGAL's).
    pub max_distance: Option<f64>,
    /// Bipolar (sign change + one point) or intersection (all points) oracle.
    pub oracle: OracleKind,
    /// Enforce a closed manifold output (section 6.6.1's patch).
    pub manifold: bool,
    /// Scaffold points inside the solid (an acceleration; same guarantees).
    pub scaffold: bool,
    /// Initial sample: control points (6.4.3) or persistent facets (6.2).
    pub initialization: Initialization,
    /// Seed for every random choice (the result does not depend on the thread count).
    pub seed: u64,
    /// Stop at this many sample points (the mesh so far is returned, unmet criteria reported).
    /// `None`: [`DEFAULT_MAX_VERTICES`](super::DEFAULT_MAX_VERTICES), and a size whose
    /// [`Forecast`](super::Forecast) exceeds it is refused before meshing (a requested budget
    /// is not: the run stops there).
    pub max_vertices: Option<usize>,
    /// Memory budget in bytes (`None`: [`DEFAULT_MAX_MEMORY`](super::DEFAULT_MAX_MEMORY)): a
    /// size whose forecast exceeds it is refused before meshing, and the mesher stops at the
    /// vertices it affords.
    pub max_memory: Option<u64>,
    /// Stop after this long (likewise).
    pub time_limit: Option<Duration>,
    /// A sample E_0 inserted before refinement (section 6.4.1).
    pub initial_points: Vec<DVec3>,
    /// Verify the output (topology, self-intersections, quality, Hausdorff against the
    /// surface, loose-epsilon certificate) and return the `verify` report.
    pub verify: bool,
    /// Requested epsilon of the certificate (default: sigma / d_M^inf when known; the
    /// requested epsilon in two-pass mode).
    pub certify_epsilon: Option<f64>,
    /// Drop closed components enclosing less than this volume (units cubed), each reported.
    pub min_component: Option<f64>,
    /// Point sets and meshes: keep the output's components that the input data does not
    /// support (by default they are dropped when no data is lost, each reported; the rule
    /// of `pipeline::unsupported`, docs/GUIDE.md "Point sets and scans").
    pub keep_unsupported: bool,
    /// Stop meshing (like a budget) once cancelled; unused, it changes nothing.
    pub cancel: Option<crate::Cancel>,
}

impl Default for Request {
    fn default() -> Self {
        Request {
            size: SizeRequest::Auto,
            min_angle_deg: 30.0,
            max_distance: None,
            oracle: OracleKind::Bipolar,
            manifold: true,
            scaffold: true,
            initialization: Initialization::ControlPoints,
            seed: 0,
            max_vertices: None,
            max_memory: None,
            time_limit: None,
            initial_points: Vec::new(),
            verify: true,
            certify_epsilon: None,
            min_component: None,
            keep_unsupported: false,
            cancel: None,
        }
    }
}

/// The criteria of CGAL's `Surface_mesh_default_criteria_3(30, r, r)` (angle 30 degrees,
/// radius bound = distance bound = r), the setting of every comparison with CGAL.
///
/// ```
/// let c = rdt_mesher::pipeline::cgal_criteria(0.05);
/// assert_eq!((c.min_angle_deg, c.max_distance), (30.0, Some(0.05)));
/// ```
pub fn cgal_criteria(r: f64) -> Criteria {
    Criteria {
        size: Some(Sizing::Constant(r)),
        min_angle_deg: 30.0,
        max_distance: Some(r),
    }
}

impl OracleKind {
    /// Both oracles, bipolar first.
    ///
    /// ```
    /// use rdt_mesher::OracleKind;
    /// assert_eq!(OracleKind::ALL.map(OracleKind::name), ["bipolar", "intersection"]);
    /// ```
    pub const ALL: [OracleKind; 2] = [OracleKind::Bipolar, OracleKind::Intersection];

    /// The one name of the oracle (CLI value, report field, golden files).
    ///
    /// ```
    /// assert_eq!(rdt_mesher::OracleKind::Intersection.name(), "intersection");
    /// ```
    pub fn name(self) -> &'static str {
        match self {
            OracleKind::Bipolar => "bipolar",
            OracleKind::Intersection => "intersection",
        }
    }
}

impl std::str::FromStr for OracleKind {
    type Err = String;
    /// The inverse of [`OracleKind::name`].
    ///
    /// ```
    /// use rdt_mesher::OracleKind;
    /// assert_eq!("bipolar".parse::<OracleKind>(), Ok(OracleKind::Bipolar));
    /// assert!("other".parse::<OracleKind>().is_err());
    /// ```
    fn from_str(s: &str) -> Result<Self, String> {
        OracleKind::ALL
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| format!("unknown oracle '{s}': use bipolar or intersection"))
    }
}

impl Initialization {
    /// Both strategies, the default first.
    ///
    /// ```
    /// use rdt_mesher::Initialization;
    /// assert_eq!(Initialization::ALL[0], Initialization::default());
    /// ```
    pub const ALL: [Initialization; 2] = [
        Initialization::ControlPoints,
        Initialization::PersistentFacets,
    ];

    /// The one name of the strategy (CLI value, report field).
    ///
    /// ```
    /// assert_eq!(rdt_mesher::Initialization::PersistentFacets.name(), "persistent-facets");
    /// ```
    pub fn name(self) -> &'static str {
        match self {
            Initialization::ControlPoints => "control-points",
            Initialization::PersistentFacets => "persistent-facets",
        }
    }
}

impl std::str::FromStr for Initialization {
    type Err = String;
    /// The inverse of [`Initialization::name`].
    ///
    /// ```
    /// use rdt_mesher::Initialization;
    /// assert_eq!("control-points".parse(), Ok(Initialization::ControlPoints));
    /// ```
    fn from_str(s: &str) -> Result<Self, String> {
        Initialization::ALL
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| {
                format!("unknown initialization '{s}': use control-points or persistent-facets")
            })
    }
}
