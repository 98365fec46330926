//! Options of a meshing run (paper, sections 6.2 to 6.6: oracle, initialization, budgets).

use crate::criteria::Criteria;
use crate::error::MeshError;
use glam::DVec3;
use std::time::Duration;

/// Which oracle answers "does this Voronoi edge meet S" (section 6.4.2).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum OracleKind {
    /// Sign change + one crossing point: the bipolar Delaunay triangulation Del_S^b(E).
    Bipolar,
    /// All crossing points of the segment: the restricted Delaunay triangulation Del_S(E).
    Intersection,
}

/// How the initial sample is built (paper, sections 6.2 and 6.4.3).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Initialization {
    /// Section 6.4.3: the control points E'_i are the initial sample; the main loop shoots
    /// random rays until every control point is a vertex of Del_S(E). No persistent facets.
    #[default]
    ControlPoints,
    /// Section 6.2: three points of S on a small sphere around every control point form a
    /// persistent facet (with the bipolar oracle, section 6.4.2's extra insertions).
    PersistentFacets,
}

/// Options of one meshing run.
#[derive(Clone, Debug)]
pub struct MeshOptions {
    /// When a surface Delaunay ball is bad.
    pub criteria: Criteria,
    /// Bipolar (default) or intersection oracle.
    pub oracle: OracleKind,
    /// Keep refining until Del_S(E) is a closed 2-manifold (section 6.6.1's patch). Default on.
    pub manifold: bool,
    /// Seed for every random choice (seed points, rays of section 6.4.3).
    pub seed: u64,
    /// Stop (with the mesh so far, criteria reported unmet) at this many vertices of E.
    pub max_vertices: Option<usize>,
    /// Stop (likewise) after this much time.
    pub time_limit: Option<Duration>,
    /// A given sample E_0 inserted before refinement (section 6.4.1, skinny-facet removal).
    pub initial_points: Vec<DVec3>,
    /// Control points E'_i (section 6.4.3). `None`: the oracle's `seed_points`.
    pub control_points: Option<Vec<DVec3>>,
    /// At most this many control points are kept (farthest-point selection).
    pub max_control_points: usize,
    /// Initialization strategy.
    pub initialization: Initialization,
    /// Insert scaffold points far from S before refining (see `crate::levels`): several
    /// times faster on surfaces with tunnels or thin parts, same guarantees, never in the
    /// output. Default on.
    pub scaffold: bool,
    /// The input's resolvable scale (images: the smallest voxel size), `None` for surfaces
    /// given as functions. When set, the manifold patch may refine below a tenth of sigma
    /// down to an eighth of it, and what it leaves non-manifold is repaired by stated
    /// topological rules (`crate::levels::repair`), each decision reported.
    pub resolution: Option<f64>,
    /// Drop closed components of the output enclosing less than this volume (the surface's
    /// units cubed), each reported.
    pub min_component: Option<f64>,
    /// Stop (like a budget, `StopReason::Cancelled`) once this is cancelled: a front end's
    /// interrupt (Ctrl-C in Python). Unused, it changes nothing.
    pub cancel: Option<Cancel>,
    /// Vertices from which the queue of bad balls takes entries of about the same badness
    /// in a spatial (Z-order) order instead of strictly worst first: consecutive insertions
    /// then touch nearby memory (1.4x less CPU time at 10^6 vertices). Any order keeps the
    /// guarantees; the meshes of runs below it are unchanged. Default 2^17; `usize::MAX`
    /// keeps the worst-first order throughout.
    pub spatial_order_from: usize,
}

/// A cancellation flag shared between a run and its caller (cloning shares it).
///
/// ```
/// let c = rdt_mesher::Cancel::default();
/// let seen = c.clone();
/// assert!(!seen.is_cancelled());
/// c.cancel();
/// assert!(seen.is_cancelled());
/// ```
#[derive(Clone, Debug, Default)]
pub struct Cancel(std::sync::Arc<std::sync::atomic::AtomicBool>);

impl Cancel {
    /// Ask the run to stop at its next budget check.
    pub fn cancel(&self) {
        self.0.store(true, std::sync::atomic::Ordering::Relaxed);
    }
    /// Whether [`Cancel::cancel`] was called.
    pub fn is_cancelled(&self) -> bool {
        self.0.load(std::sync::atomic::Ordering::Relaxed)
    }
}

impl Default for MeshOptions {
    fn default() -> Self {
        MeshOptions {
            criteria: Criteria::default(),
            oracle: OracleKind::Bipolar,
            manifold: true,
            seed: 0,
            max_vertices: None,
            time_limit: None,
            initial_points: Vec::new(),
            control_points: None,
            max_control_points: 64,
            initialization: Initialization::ControlPoints,
            scaffold: true,
            resolution: None,
            min_component: None,
            cancel: None,
            spatial_order_from: 1 << 17,
        }
    }
}

impl MeshOptions {
    /// Check the options before a run: the criteria are valid ([`Criteria::validate`]) and
    /// something stops the refinement (a criterion, or the manifold patch).
    ///
    /// ```
    /// use rdt_mesher::{Criteria, MeshError, MeshOptions};
    /// let none = Criteria { size: None, min_angle_deg: 0.0, max_distance: None };
    /// let opts = MeshOptions { criteria: none, manifold: false, ..Default::default() };
    /// assert!(matches!(opts.validate(), Err(MeshError::NoCriterion)));
    /// ```
    pub fn validate(&self) -> Result<(), MeshError> {
        let c = &self.criteria;
        c.validate()?;
        if c.size.is_none() && c.min_angle_deg == 0.0 && c.max_distance.is_none() && !self.manifold
        {
            return Err(MeshError::NoCriterion);
        }
        Ok(())
    }
}
