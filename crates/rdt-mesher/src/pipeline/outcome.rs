//! What a pipeline run returns (ours): the mesh with its surface Delaunay balls (section 6.1),
//! the statistics, the two-pass details (section 6.5), the `verify` report and the verdict.
//!
//! Invariant: `verdict` is [`Verdict::Pass`] iff the report (when verification ran) passed
//! and no pass stopped on a budget (single pass: and no criterion is unmet).

use crate::{MeshResult, Stats, SurfaceBall, Unmet, UnmetFacet};
use glam::DVec3;
use meshio::TriMesh;
use std::fmt;

/// Which meshing pass of a run.
///
/// ```
/// use rdt_mesher::pipeline::Stage;
/// assert_eq!(Stage::Second.to_string(), "second pass");
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    /// The one pass of a constant-size run.
    Single,
    /// The uniform first pass of the two-pass mode.
    First,
    /// The adaptive second pass of the two-pass mode (the output).
    Second,
}

impl fmt::Display for Stage {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Stage::Single => "pass",
            Stage::First => "first pass",
            Stage::Second => "second pass",
        })
    }
}

/// One reason a run did not pass.
///
/// ```
/// use rdt_mesher::pipeline::{Failure, Stage};
/// let f = Failure::Stopped(Stage::First); // its reason: outcome.stats_of(Stage::First).stopped_by
/// assert_ne!(f, Failure::Unmet(Stage::First));
/// ```
#[derive(Clone, Debug, PartialEq)]
pub enum Failure {
    /// The verification failed these checks.
    Verification(Vec<String>),
    /// A budget stopped this pass (see its `Stats::stopped_by` and `unmet`).
    Stopped(Stage),
    /// The pass completed with criteria unmet (see its `Stats::unmet`).
    Unmet(Stage),
}

/// The verdict of a run: what `cargo xtask mesh --strict` exits on (status 3 on a failure).
///
/// ```
/// use rdt_mesher::pipeline::{run, Input, Request, SizeRequest, Verdict};
/// let input = Input::open("implicit:sphere", &Default::default()).unwrap();
/// let out = run(&input, &Request { size: SizeRequest::Size(0.3), ..Default::default() })
///     .unwrap();
/// assert_eq!(out.verdict, Verdict::Pass);
/// assert!(out.verdict.passed());
/// ```
#[derive(Clone, Debug, PartialEq)]
pub enum Verdict {
    /// Verified (or not asked to verify), every criterion met, no budget hit.
    Pass,
    /// The reasons, in the order the CLI reports them.
    Fail(Vec<Failure>),
}

impl Verdict {
    /// `Pass`.
    ///
    /// ```
    /// use rdt_mesher::pipeline::{Failure, Stage, Verdict};
    /// assert!(!Verdict::Fail(vec![Failure::Unmet(Stage::Single)]).passed());
    /// ```
    pub fn passed(&self) -> bool {
        matches!(self, Verdict::Pass)
    }

    fn from(failures: Vec<Failure>) -> Verdict {
        if failures.is_empty() {
            Verdict::Pass
        } else {
            Verdict::Fail(failures)
        }
    }
}

/// Details of a two-pass run (section 6.5).
///
/// ```
/// use rdt_mesher::pipeline::{run, Input, Request, SizeRequest};
/// let input = Input::open("implicit:sphere", &Default::default()).unwrap();
/// let req = Request { size: SizeRequest::Epsilon { epsilon: 0.4, dm_inf: None },
///                     verify: false, ..Default::default() };
/// let tp = run(&input, &req).unwrap().two_pass.unwrap();
/// assert!((tp.sigma0 - 0.4).abs() < 1e-12); // eps * d_M^inf, d_M^inf = 1
/// assert!(tp.first_pass_uniform());
/// ```
#[derive(Clone, Debug)]
pub struct TwoPassOutcome {
    /// The requested epsilon.
    pub epsilon: f64,
    /// The d_M^inf used.
    pub dm_inf: f64,
    /// The first pass's constant size, epsilon * d_M^inf.
    pub sigma0: f64,
    /// The second pass's factor eps' (0.9 epsilon).
    pub eps_prime: f64,
    /// Lower bound of the second pass's size field.
    pub floor: f64,
    /// Medial points of the d_M estimate (after thinning).
    pub medial_points: usize,
    /// The first pass's estimate of d_M^inf.
    pub dm_inf_estimate: f64,
    /// The first pass.
    pub first: MeshResult,
    /// No second pass ran: the first used the whole time limit (or was interrupted), and the
    /// output is its mesh (the estimate fields are then empty: no medial point, +inf).
    pub second_skipped: bool,
}

impl TwoPassOutcome {
    /// The first pass's own d_M estimate confirms d_M^inf (its minimum is at least 0.9
    /// d_M^inf); otherwise the first pass was not a uniform epsilon-sample (give a smaller
    /// d_M^inf) and the second pass follows the estimate.
    ///
    /// ```
    /// # use rdt_mesher::pipeline::{run, Input, Request, SizeRequest};
    /// # let input = Input::open("implicit:sphere", &Default::default()).unwrap();
    /// # let req = Request { size: SizeRequest::Epsilon { epsilon: 0.4, dm_inf: None },
    /// #                     verify: false, ..Default::default() };
    /// let tp = run(&input, &req).unwrap().two_pass.unwrap();
    /// assert!(tp.first_pass_uniform());
    /// ```
    pub fn first_pass_uniform(&self) -> bool {
        // (An estimate of NaN is no evidence against it.)
        self.dm_inf_estimate.partial_cmp(&(0.9 * self.dm_inf)) != Some(std::cmp::Ordering::Less)
    }
}

/// Details of an adaptive run ([`crate::adaptive`]).
#[derive(Clone, Debug, serde::Serialize)]
pub struct AdaptiveOutcome {
    /// The requested epsilon.
    pub epsilon: f64,
    /// eps' = 0.9 epsilon.
    pub eps_prime: f64,
    /// The constant size of round 0.
    pub sigma0: f64,
    /// Floor of the output's size function.
    pub floor: f64,
    /// The last estimate of d_M^inf.
    pub dm_inf_estimate: f64,
    /// The rounds after round 0.
    pub rounds: Vec<crate::adaptive::Round>,
    /// The last of `rounds` is an estimate whose round was not run
    /// ([`crate::adaptive::Adaptive::last_estimate_only`]).
    pub last_estimate_only: bool,
    /// Stopped on a stable estimate (not on a budget or the round limit).
    pub converged: bool,
    /// Why the rounds stopped before the next one (the output is the last complete round).
    pub early_stop: Option<crate::adaptive::EarlyStop>,
}

/// Sharp edges of a mesh input and how far the output is from them.
///
/// ```
/// use rdt_mesher::pipeline::{run, Input, Request, SizeRequest};
/// let dir = env!("CARGO_MANIFEST_DIR");
/// let cube = Input::open(&format!("{dir}/../../fixtures/meshes/cube.off"), &Default::default())
///     .unwrap();
/// let out = run(&cube, &Request { verify: false, ..Default::default() }).unwrap();
/// let s = out.sharp_edges.unwrap();
/// assert_eq!(s.input_edges, 12);
/// assert!(s.to_string().starts_with("sharp edges: 12 input edges"));
/// ```
#[derive(Clone, Debug)]
pub struct SharpEdges {
    /// Sharp edges of the input.
    pub input_edges: usize,
    /// Largest distance from them to the output, or why it was not measured.
    pub deviation: Result<f64, String>,
    /// Diagonal of the bounding box of the edges and the output.
    pub bbox_diagonal: f64,
    /// The edges, to locate unmet facets near them.
    pub(crate) edges: Vec<(DVec3, DVec3)>,
}

impl SharpEdges {
    pub(crate) fn measure(
        edges: &[(DVec3, DVec3)],
        input_edges: usize,
        mesh: &TriMesh,
        sigma: f64,
    ) -> SharpEdges {
        let dev = oracle::polyhedron::PolyhedronSurface::new(mesh)
            .map(|out| oracle::polyhedron::sharp_edge_deviation(edges, &out, sigma / 4.0))
            .map_err(|e| e.to_string());
        let (lo, hi) = edges.iter().fold(
            (DVec3::INFINITY, DVec3::NEG_INFINITY),
            |(lo, hi), &(a, b)| (lo.min(a).min(b), hi.max(a).max(b)),
        );
        let diag = mesh
            .vertices
            .iter()
            .fold((lo, hi), |(lo, hi), &v| (lo.min(v), hi.max(v)));
        SharpEdges {
            input_edges,
            deviation: dev,
            bbox_diagonal: (diag.1 - diag.0).length(),
            edges: edges.to_vec(),
        }
    }
}

impl fmt::Display for SharpEdges {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.deviation {
            Ok(d) => write!(
                f,
                "sharp edges: {} input edges (normals > {} deg apart), largest distance to the output {d:.3e} ({:.3}% of the output's bbox diagonal)",
                self.input_edges,
                super::SHARP_DEG,
                100.0 * d / self.bbox_diagonal
            ),
            Err(e) => write!(f, "sharp edges: deviation not measured ({e})"),
        }
    }
}

/// The result of [`run`](super::run).
///
/// ```
/// use rdt_mesher::pipeline::{run, Input, Request, SizeRequest};
/// let input = Input::open("implicit:torus", &Default::default()).unwrap();
/// let out = run(&input, &Request { size: SizeRequest::Size(0.2), ..Default::default() })
///     .unwrap();
/// assert_eq!(out.balls.len(), out.mesh.triangles.len()); // one ball per facet
/// assert_eq!(out.stats.vertices, out.mesh.vertices.len());
/// assert!(out.report.as_ref().unwrap().passed());
/// ```
#[derive(Clone, Debug)]
pub struct Outcome {
    /// The output: oriented triangles of Del_S(E).
    pub mesh: TriMesh,
    /// `balls[i]` is the surface Delaunay ball of `mesh.triangles[i]`.
    pub balls: Vec<SurfaceBall>,
    /// The sample E (the mesher's points on S).
    pub sample: Vec<DVec3>,
    /// The (last) pass's statistics.
    pub stats: Stats,
    /// The constant size used (`None` in two-pass mode).
    pub sigma: Option<f64>,
    /// Two-pass mode: its details and first pass.
    pub two_pass: Option<TwoPassOutcome>,
    /// Adaptive mode: its rounds.
    pub adaptive: Option<AdaptiveOutcome>,
    /// The input's notes and the size chosen.
    pub notes: Vec<String>,
    /// Meshes and point sets without a requested size: one note per halving of the
    /// suggested size because its mesh lost a part of the data (also in `notes`; see the
    /// pipeline's `auto_size` module). Empty otherwise.
    pub size_halvings: Vec<String>,
    /// Mesh input with sharp edges (single pass): the output's distance to them.
    pub sharp_edges: Option<SharpEdges>,
    /// The verification report, when requested.
    pub report: Option<verify::Report>,
    /// Pass or the reasons of failure.
    pub verdict: Verdict,
    /// Point sets and meshes: the triangles of the components dropped because the data does
    /// not support them (`drop_unsupported_component` decisions; empty otherwise).
    pub dropped_triangles: Vec<[DVec3; 3]>,
}

impl Outcome {
    pub(crate) fn new(result: MeshResult) -> Outcome {
        Outcome {
            mesh: result.mesh,
            balls: result.balls,
            sample: result.sample,
            stats: result.stats,
            sigma: None,
            two_pass: None,
            adaptive: None,
            notes: Vec::new(),
            size_halvings: Vec::new(),
            sharp_edges: None,
            report: None,
            verdict: Verdict::Pass,
            dropped_triangles: Vec::new(),
        }
    }

    /// The statistics of one pass (`Single` and `Second` are the output's).
    ///
    /// ```
    /// use rdt_mesher::pipeline::{run, Input, Request, SizeRequest, Stage};
    /// let input = Input::open("implicit:sphere", &Default::default()).unwrap();
    /// let out = run(&input, &Request { size: SizeRequest::Size(0.3), verify: false,
    ///                                  ..Default::default() }).unwrap();
    /// assert!(out.stats_of(Stage::Single).stopped_by.is_none());
    /// ```
    pub fn stats_of(&self, stage: Stage) -> &Stats {
        match (stage, &self.two_pass) {
            (Stage::First, Some(tp)) => &tp.first.stats,
            _ => &self.stats,
        }
    }

    /// The verification line the CLI prints: `verify: PASS (N checks)`, `verify: PASS with
    /// unmet criteria (...) (N checks)` when the checks pass but the mesher left a criterion
    /// unmet or stopped on a budget (never a bare PASS beside an unmet criterion), or
    /// `verify: FAIL: names`. `None` without verification.
    ///
    /// ```
    /// use rdt_mesher::pipeline::{run, Input, Request, SizeRequest};
    /// let input = Input::open("implicit:sphere", &Default::default()).unwrap();
    /// let out = run(&input, &Request { size: SizeRequest::Size(0.3), ..Default::default() })
    ///     .unwrap();
    /// assert!(out.verify_line().unwrap().starts_with("verify: PASS ("));
    /// ```
    pub fn verify_line(&self) -> Option<String> {
        let r = self.report.as_ref()?;
        if !r.passed() {
            return Some(format!("verify: FAIL: {}", r.failures().join(", ")));
        }
        let mut unmet = Vec::new();
        let passes: Vec<&Stats> = match &self.two_pass {
            Some(tp) => vec![&tp.first.stats, &self.stats],
            None => vec![&self.stats],
        };
        for st in passes {
            if let Some(s) = &st.stopped_by {
                unmet.push(format!("stopped by {s}"));
            }
            for u in &st.unmet {
                unmet.push(match u {
                    Unmet::Size { max_r_over_sigma } => format!(
                        "size: {}, max r/sigma {max_r_over_sigma:.2}",
                        count(st, "size")
                    ),
                    Unmet::Angle { min_angle_deg, .. } => format!(
                        "angle: {}, min angle {min_angle_deg:.2} deg",
                        count(st, "angle")
                    ),
                    other => other.to_string(),
                });
            }
        }
        let where_ = if self.stats.unmet_facets.is_empty() {
            ""
        } else {
            "; where: the report's stats.unmet_facets"
        };
        let caveat = if r.dm_estimate_contradicted {
            "; the theorems: no guarantee, S is thinner than the d_M^inf estimate somewhere \
             (see loose-epsilon)"
        } else {
            ""
        };
        Some(if unmet.is_empty() {
            format!("verify: PASS ({} checks{caveat})", r.checks.len())
        } else {
            format!(
                "verify: PASS with unmet criteria ({}) ({} checks{where_}{caveat})",
                unmet.join("; "),
                r.checks.len()
            )
        })
    }

    /// Sets the verdict from the report and the stats (the rule of the module's invariant),
    /// and locates the facets that fail the size and angle criteria.
    pub(crate) fn decide(&mut self) {
        self.locate_unmet();
        let mut failures = Vec::new();
        if let Some(r) = &self.report
            && !r.passed()
        {
            failures.push(Failure::Verification(
                r.failures().iter().map(|f| f.to_string()).collect(),
            ));
        }
        match &self.two_pass {
            None => {
                if self.stats.stopped_by.is_some() {
                    failures.push(Failure::Stopped(Stage::Single));
                } else if !self.stats.unmet.is_empty() {
                    failures.push(Failure::Unmet(Stage::Single));
                }
            }
            Some(tp) => {
                for (stage, st) in [
                    (Stage::First, &tp.first.stats),
                    (Stage::Second, &self.stats),
                ] {
                    if st.stopped_by.is_some() {
                        failures.push(Failure::Stopped(stage));
                    }
                }
            }
        }
        self.verdict = Verdict::from(failures);
    }
}

/// The facets of `st` failing `criterion`: "N facets", "N facets (M listed)", or "some
/// facets" when they were not located (two-pass runs).
fn count(st: &Stats, criterion: &str) -> String {
    let listed = st
        .unmet_facets
        .iter()
        .filter(|f| f.criterion == criterion)
        .count();
    let both = st
        .unmet
        .iter()
        .filter(|u| matches!(u, Unmet::Size { .. } | Unmet::Angle { .. }))
        .count()
        > 1;
    let total = st.unmet_facets_total;
    match listed {
        0 => "some facets".into(),
        _ if total > listed && both => {
            format!("{total} facets fail size or angle ({listed} listed for {criterion})")
        }
        _ if total > listed => format!("{total} facets ({listed} listed)"),
        _ => format!("{listed} facets"),
    }
}

/// At most this many unmet facets are listed.
const MAX_LISTED: usize = 20;

impl Outcome {
    /// Fill `stats.unmet_facets` (constant-size runs): the facets whose ball is larger than
    /// sigma and those with an angle below the bound, worst first, with the distance of the
    /// ball's center to the nearest sharp input edge when the input has some, and the
    /// context of the run (stopped by a budget or not, manifold patch insertions).
    fn locate_unmet(&mut self) {
        let Some(sigma) = self.sigma else { return };
        let st = &self.stats;
        let size = st.unmet.iter().any(|u| matches!(u, Unmet::Size { .. }));
        let angle = st.unmet.iter().find_map(|u| match u {
            Unmet::Angle { bound_deg, .. } => Some(*bound_deg),
            _ => None,
        });
        if !size && angle.is_none() {
            return;
        }
        let mut bad: Vec<(String, usize, f64, f64)> = Vec::new();
        for (i, (b, t)) in self.balls.iter().zip(&self.mesh.triangles).enumerate() {
            let rs = b.radius / sigma;
            if size && rs > 1.0 {
                bad.push(("size".into(), i, rs, -rs));
            }
            if let Some(bound) = angle {
                let a = crate::criteria::min_angle_deg(t.map(|v| self.mesh.vertices[v as usize]));
                if a < bound {
                    bad.push(("angle".into(), i, a, a));
                }
            }
        }
        bad.sort_by(|x, y| x.3.total_cmp(&y.3).then(x.1.cmp(&y.1)));
        let context = match (&st.stopped_by, st.manifold_insertions) {
            (Some(s), _) => format!("the run was stopped by {s}"),
            (None, 0) => {
                "the refinement ended with this ball in place (no budget stopped it)".into()
            }
            (None, n) => format!(
                "the refinement ended with this ball in place (no budget stopped it; the \
                 manifold patch inserted {n} points)"
            ),
        };
        let edges = self.sharp_edges.as_ref().map(|s| s.edges.as_slice());
        let listed: Vec<UnmetFacet> = bad
            .iter()
            .take(MAX_LISTED)
            .map(|(criterion, i, v, _)| {
                let c = self.balls[*i].center;
                let near = edges.filter(|e| !e.is_empty()).map(|e| {
                    e.iter()
                        .map(|&(a, b)| (geom::closest::closest_point_segment(c, a, b) - c).length())
                        .fold(f64::INFINITY, f64::min)
                });
                let why = match near {
                    Some(d) if d <= 2.0 * sigma => format!(
                        "ball center {d:.3e} from a sharp input edge (within 2 sigma: the \
                         input is not smooth there, where the theorems do not apply); {context}"
                    ),
                    Some(d) => format!("nearest sharp input edge {d:.3e} away; {context}"),
                    None => context.clone(),
                };
                UnmetFacet {
                    criterion: criterion.clone(),
                    facet: *i,
                    center: c.to_array(),
                    value: *v,
                    why,
                }
            })
            .collect();
        self.stats.unmet_facets_total = bad.len();
        self.stats.unmet_facets = listed;
    }
}

/// The mesher's surface Delaunay balls in `verify`'s form (one per output triangle).
///
/// ```
/// use rdt_mesher::{SurfaceBall, pipeline::verify_balls};
/// let b = verify_balls(&[SurfaceBall { center: glam::DVec3::ZERO, radius: 0.1 }]);
/// assert_eq!(b.len(), 1);
/// ```
pub fn verify_balls(balls: &[SurfaceBall]) -> Vec<verify::SurfaceBall> {
    verify::SurfaceBall::per_facet(balls.iter().map(|b| (b.center, b.radius)))
}
