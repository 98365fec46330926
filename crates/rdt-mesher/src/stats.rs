//! What a run returns (ours): the mesh of Del_S(E) with its surface Delaunay balls
//! (section 6.1), figures, and typed outcomes (the budget that stopped it, the criteria unmet).

use glam::DVec3;
use meshio::TriMesh;
use std::fmt;

/// A surface Delaunay ball B(c, r) circumscribing a restricted facet.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct SurfaceBall {
    /// Its center c, a point of S.
    pub center: DVec3,
    /// Its radius r.
    pub radius: f64,
}

/// Why a run stopped before every criterion held.
///
/// `Display` gives the text the CLI prints after "stopped by".
///
/// ```
/// use rdt_mesher::StopReason;
/// assert_eq!(StopReason::MaxVertices { limit: 500 }.to_string(), "max_vertices (500)");
/// ```
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum StopReason {
    /// [`crate::MeshOptions::max_vertices`] was reached.
    MaxVertices {
        /// The budget.
        limit: usize,
    },
    /// [`crate::MeshOptions::time_limit`] was reached.
    TimeLimit {
        /// The budget, in seconds.
        seconds: f64,
    },
    /// [`crate::MeshOptions::cancel`] was cancelled (an interrupt).
    Cancelled,
    /// The manifold patch (section 6.6.1) made no progress for `passes` passes.
    ManifoldStalled {
        /// Passes without a decrease of the count of non-manifold elements.
        passes: u32,
        /// Non-manifold elements (edges and vertices) left.
        left: usize,
    },
}

impl StopReason {
    /// Whether a budget stopped the run (`max_vertices`, `time_limit`, a cancel), not the
    /// manifold patch: its missing parts are the budget's.
    pub fn is_budget(&self) -> bool {
        matches!(
            self,
            StopReason::MaxVertices { .. } | StopReason::TimeLimit { .. } | StopReason::Cancelled
        )
    }

    /// The reason as the caller's budget says it: a run that got only the time left of a
    /// `limit` spread over several runs reports `limit`, not its share.
    ///
    /// ```
    /// use rdt_mesher::StopReason;
    /// use std::time::Duration;
    /// let r = StopReason::TimeLimit { seconds: 0.25 };
    /// let given = r.with_time_limit(Some(Duration::from_secs(2)));
    /// assert_eq!(given, StopReason::TimeLimit { seconds: 2.0 });
    /// ```
    pub fn with_time_limit(self, limit: Option<std::time::Duration>) -> StopReason {
        match (self, limit) {
            (StopReason::TimeLimit { .. }, Some(t)) => StopReason::TimeLimit {
                seconds: t.as_secs_f64(),
            },
            (r, _) => r,
        }
    }
}

impl fmt::Display for StopReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StopReason::MaxVertices { limit } => write!(f, "max_vertices ({limit})"),
            StopReason::TimeLimit { seconds } => write!(f, "time_limit ({seconds:.3} s)"),
            StopReason::Cancelled => write!(f, "cancelled"),
            StopReason::ManifoldStalled { passes, left } => write!(
                f,
                "manifold patch: no progress in {passes} passes ({left} non-manifold elements left)"
            ),
        }
    }
}

/// A criterion that does not hold on the output.
///
/// ```
/// use rdt_mesher::Unmet;
/// let u = Unmet::ControlPoints { missing: 1 };
/// assert_eq!(u.to_string(), "control points: 1 not on the mesh");
/// ```
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Unmet {
    /// Some ball is larger than sigma at its center.
    Size {
        /// max over the facets of r / sigma(c), > 1.
        max_r_over_sigma: f64,
    },
    /// Some facet has an angle below the bound.
    Angle {
        /// The smallest facet angle, degrees.
        min_angle_deg: f64,
        /// The bound, degrees.
        bound_deg: f64,
    },
    /// Some facet's circumcenter is farther than the distance bound from its ball's center.
    Distance {
        /// max over the facets of the distance over the bound, > 1.
        max_ratio: f64,
    },
    /// Facets at scaffold points were left out of the mesh (a run stopped early).
    Scaffold {
        /// How many.
        facets: usize,
    },
    /// Del_S(E) is not a closed 2-manifold.
    Manifold {
        /// Non-manifold or boundary edges.
        edges: usize,
        /// Non-manifold vertices.
        vertices: usize,
    },
    /// Control points (section 6.4.3) that are not vertices of the mesh.
    ControlPoints {
        /// How many.
        missing: usize,
    },
    /// The output was made a closed manifold by topological decisions
    /// ([`Stats::topology_decisions`]): there, it is not Del_S(E).
    Repaired {
        /// Decisions that cut, closed or dropped part of Del_S(E).
        decisions: usize,
    },
}

impl fmt::Display for Unmet {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Unmet::Size { max_r_over_sigma } => {
                write!(f, "size: max r/sigma = {max_r_over_sigma:.4} > 1")
            }
            Unmet::Angle {
                min_angle_deg,
                bound_deg,
            } => write!(f, "angle: min angle {min_angle_deg:.2} < {bound_deg}"),
            Unmet::Distance { max_ratio } => write!(f, "distance: max ratio {max_ratio:.4} > 1"),
            Unmet::Scaffold { facets } => write!(
                f,
                "scaffold: {facets} facets at scaffold points left out (run stopped early)"
            ),
            Unmet::Manifold { edges, vertices } => write!(
                f,
                "manifold: {edges} non-manifold or boundary edges, {vertices} non-manifold vertices"
            ),
            Unmet::ControlPoints { missing } => {
                write!(f, "control points: {missing} not on the mesh")
            }
            Unmet::Repaired { decisions } => write!(
                f,
                "manifold: {decisions} topological decision(s) where Del_S(E) was not a manifold \
                 (see topology_decisions)"
            ),
        }
    }
}

/// An output facet where a criterion does not hold: where it is, by how much and why, for
/// the report (see [`Stats::unmet_facets`]).
///
/// ```
/// use rdt_mesher::UnmetFacet;
/// let f = UnmetFacet { criterion: "size".into(), facet: 7, center: [0.0, 1.0, 2.0], value: 3.17,
///                      why: "within 0.01 of a sharp input edge".into() };
/// assert_eq!(f.to_string(), "size at facet 7 (0, 1, 2): 3.17; within 0.01 of a sharp input edge");
/// ```
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct UnmetFacet {
    /// `size` (value: r / sigma at the ball's center) or `angle` (value: the smallest angle,
    /// degrees).
    pub criterion: String,
    /// Index of the facet in the output mesh.
    pub facet: usize,
    /// Its surface Delaunay ball's center.
    pub center: [f64; 3],
    /// The measure that fails the criterion.
    pub value: f64,
    /// What is known about the cause.
    pub why: String,
}

impl fmt::Display for UnmetFacet {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let [x, y, z] = self.center;
        write!(
            f,
            "{} at facet {} ({x}, {y}, {z}): {}; {}",
            self.criterion, self.facet, self.value, self.why
        )
    }
}

/// Figures of a run, for the report.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct Stats {
    /// Vertices of the output mesh.
    pub vertices: usize,
    /// Facets of the output mesh.
    pub facets: usize,
    /// Points of the sample E (vertices of Del(E)).
    pub sample_points: usize,
    /// Control points E'_i used for initialization.
    pub control_points: usize,
    /// Control points that are not vertices of Del_S(E) at the end.
    pub control_points_missing: usize,
    /// Refinement insertions (centers of bad balls).
    pub refinement_insertions: usize,
    /// Points inserted by the rays of section 6.4.3.
    pub ray_insertions: usize,
    /// Refinement points not inserted because a sample point lies closer to them than half
    /// their ball's radius (an inexact construction, `crate::schedule::batch`).
    pub unsound_centers: usize,
    /// Insertions forced by the manifold patch.
    pub manifold_insertions: usize,
    /// Rounds of neck reseeding (images: scan components split in Del_S(E), see
    /// `crate::levels::necks`).
    pub neck_rounds: usize,
    /// Points inserted by the neck reseeding.
    pub neck_insertions: usize,
    /// Rounds of handle reseeding (images: Del_S(E) with fewer handles than the scan's level
    /// set, see `crate::levels::handles`).
    pub handle_rounds: usize,
    /// Points inserted by the handle reseeding.
    pub handle_insertions: usize,
    /// Rounds of coverage of the scan's crossings (images, `crate::levels::coverage`).
    pub cover_rounds: usize,
    /// Crossings inserted by the coverage rounds.
    pub cover_insertions: usize,
    /// Rounds of reseeding of scan components with no vertex of Del_S(E) (images,
    /// `crate::levels::missed`).
    pub missed_rounds: usize,
    /// Crossings inserted by those rounds.
    pub missed_insertions: usize,
    /// Edge flips of skinny triangles after the topological decisions (images,
    /// `crate::levels::skinny`).
    pub skinny_flips: usize,
    /// Edge collapses of skinny triangles after the topological decisions.
    pub skinny_collapses: usize,
    /// Vertices of skinny triangles moved on S after the topological decisions.
    pub skinny_moves: usize,
    /// Triangles below the angle bound before those edits (images with a resolution).
    pub skinny_before: usize,
    /// Triangles below the angle bound after them.
    pub skinny_after: usize,
    /// Restricted facets queued (forced) by the neck reseeding because their vertices lie on
    /// different scan components (a bridge between two components).
    pub bridge_facets: usize,
    /// Rounds in which bridge facets were queued.
    pub bridge_rounds: usize,
    /// Manifold checks performed.
    pub manifold_passes: usize,
    /// Oracle value evaluations made by the mesher (circumcenters).
    pub oracle_value_calls: u64,
    /// Oracle crossing (bipolar or intersection) queries.
    pub oracle_crossing_calls: u64,
    /// Batches of oracle calls that ran on several threads (they are chosen from measured
    /// call costs, so this varies from run to run; the mesh does not).
    pub parallel_oracle_batches: u64,
    /// Refinement points whose conflict zone overlapped an earlier one of the same batch and
    /// went back to the queue (see `crate::schedule`).
    pub batch_deferrals: u64,
    /// Refinement batches whose parallel sections ran on one thread: with several threads
    /// the mode is chosen from measured speed, and never changes the mesh (all batches are
    /// sequential on one thread).
    pub sequential_batches: u64,
    /// Refinement batches whose parallel sections ran on several threads.
    pub parallel_batches: u64,
    /// Scaffold points inserted (vertices of Del(E), not samples; see `MeshOptions::scaffold`).
    pub scaffold_points: usize,
    /// Times the final check of the scaffold failed and the triangulation was rebuilt from the
    /// samples alone (0 or 1).
    pub scaffold_rebuilds: usize,
    /// Wall time of the run, seconds.
    pub time_total_s: f64,
    /// Of which in the Delaunay triangulation (insertions, conflict zones).
    pub time_delaunay_s: f64,
    /// Of which in the oracle.
    pub time_oracle_s: f64,
    /// Everything else: circumcenters, restricted-facet tests and bookkeeping, criteria, queue.
    pub time_queue_s: f64,
    /// Of the total (across the three above), on images with a resolution (`crate::levels`;
    /// 0 elsewhere): the coverage rounds of the scan's crossings, insertions included.
    pub time_coverage_s: f64,
    /// The neck, bridge and handle rounds, insertions included.
    pub time_necks_s: f64,
    /// The separation of components that touch, then the topological repair.
    pub time_repair_s: f64,
    /// The bridges between the pieces of split components.
    pub time_bridges_s: f64,
    /// The fragment drops and the component decisions.
    pub time_components_s: f64,
    /// max over the output facets of r / sigma(c) (<= 1 when the size criterion holds).
    pub max_r_over_sigma: Option<f64>,
    /// Smallest facet angle of the output, degrees.
    pub min_angle_deg: f64,
    /// max over facets of distance(circumcenter, c) / distance bound.
    pub max_distance_ratio: Option<f64>,
    /// Every criterion holds on every output facet.
    pub criteria_met: bool,
    /// The budget that stopped the run early, if any.
    pub stopped_by: Option<StopReason>,
    /// Criteria that do not hold at the end (empty when the run completed).
    pub unmet: Vec<Unmet>,
    /// Where the size and angle criteria fail: the worst facets first, at most 20 (filled by
    /// `rdt_mesher::pipeline` for constant-size runs).
    pub unmet_facets: Vec<UnmetFacet>,
    /// How many facets fail the size or angle criterion in all.
    pub unmet_facets_total: usize,
    /// Edges of the output with other than two facets (0 for a closed 2-manifold).
    pub nonmanifold_edges: usize,
    /// Vertices with other than one umbrella (0 for a closed 2-manifold).
    pub nonmanifold_vertices: usize,
    /// Topological decisions taken on the output (images, `--min-component`): kind, where,
    /// size (see `MeshOptions::resolution`).
    pub topology_decisions: Vec<crate::TopologyDecision>,
    /// Images with a resolution: where the output's pieces differ from the voxel scan's
    /// components (split, joined, missed, dropped), each with its rule, place and size
    /// (`crate::levels::components`).
    pub component_decisions: Vec<crate::ComponentDecision>,
    /// Heap bytes of the mesher's structures at the end of the refinement
    /// (`crate::memory`).
    pub memory: Vec<crate::MemoryUse>,
}

impl Stats {
    /// The unmet criteria as one line, separated by "; " (empty when all hold).
    ///
    /// ```
    /// use rdt_mesher::{Stats, Unmet};
    /// let st = Stats {
    ///     unmet: vec![Unmet::Scaffold { facets: 2 }, Unmet::ControlPoints { missing: 1 }],
    ///     ..Default::default()
    /// };
    /// assert_eq!(
    ///     st.unmet_summary(),
    ///     "scaffold: 2 facets at scaffold points left out (run stopped early); \
    ///      control points: 1 not on the mesh"
    /// );
    /// ```
    pub fn unmet_summary(&self) -> String {
        let parts: Vec<String> = self.unmet.iter().map(Unmet::to_string).collect();
        parts.join("; ")
    }
}

/// The result of a run: the mesh of Del_S(E), one surface Delaunay ball per triangle, stats.
#[derive(Clone, Debug)]
pub struct MeshResult {
    /// Oriented triangles (counter-clockwise seen from outside, i.e. normals toward value > 0).
    pub mesh: TriMesh,
    /// `balls[i]` circumscribes `mesh.triangles[i]`.
    pub balls: Vec<SurfaceBall>,
    /// The sample E (the vertices of Del(E) on S: scaffold points left out), for two-pass
    /// sizing and reports.
    pub sample: Vec<DVec3>,
    /// Figures and outcome of the run.
    pub stats: Stats,
}

/// Progress of a run, passed to the callback of [`crate::mesh_with_progress`].
#[derive(Clone, Copy, Debug)]
pub struct Progress {
    /// Points of the sample E so far.
    pub sample_points: usize,
    /// Facets of Del_S(E) so far.
    pub restricted_facets: usize,
    /// Entries in the refinement queue (some may be stale).
    pub queue: usize,
}
