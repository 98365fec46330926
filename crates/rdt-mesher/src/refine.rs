//! The refinement loop of section 6.1, with the control-point initialization of section 6.4.3
//! and the manifold patch of section 6.6.1.
//!
//! # Invariants kept by `Refiner` (private)
//! - `cells[c]` holds the circumcenter of every live finite cell `c` and the surface value
//!   there (or "outside the bounding ball"); it is recomputed for every created cell.
//! - `restricted` holds exactly the facets of Del(E) whose (clipped) dual Voronoi edge meets S
//!   according to the oracle, keyed by their sorted vertex triple (see `crate::restricted`).
//!   After an insertion, every facet of a destroyed cell is removed, and every facet of a
//!   created cell (new facets and the boundary facets of the cavity, whose duals changed) is
//!   re-tested: nothing else changed.
//! - A queue entry (slot, version) is fresh iff that slot is live with that version; stale
//!   entries are skipped when popped.
//! - `vertex_facets[v]` counts the restricted facets incident to `v`.

use crate::criteria::Criteria;
use crate::restricted::{RFacet, Restricted};
use crate::tuner::Tuner;
use delaunay3::{
    Cavity, CellId, Changes, Facet, INFINITE_VERTEX, Insertion, Triangulation, VertexId,
};
use glam::DVec3;
use meshio::TriMesh;
use oracle::{BoundingSphere, OracleError, Surface, roots::SplitMix64};
use std::cmp::Ordering;
use std::collections::BinaryHeap;
use std::sync::Arc;
use std::time::{Duration, Instant};

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
    /// Insert scaffold points far from S before refining (see `crate::scaffold`): several
    /// times faster on surfaces with tunnels or thin parts, same guarantees, never in the
    /// output. Default on.
    pub scaffold: bool,
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
        }
    }
}

/// Errors of a meshing run.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    #[error(
        "invalid size bound sigma = {0}: it must be a positive finite number (e.g. --size 0.05)"
    )]
    InvalidSize(f64),
    #[error("the size function returned {value} at ({}, {}, {}): sigma must be positive and finite on S", .at.x, .at.y, .at.z)]
    InvalidSizeField { value: f64, at: DVec3 },
    #[error(
        "invalid angle bound {0} degrees: use a value in [0, 35) (30 has a termination proof; 0 disables it)"
    )]
    InvalidAngle(f64),
    #[error("invalid distance bound {0}: it must be positive and finite")]
    InvalidDistance(f64),
    #[error("no criterion given: set a size (--size), an angle or a distance bound")]
    NoCriterion,
    #[error(
        "no point of the surface was found inside the bounding sphere (center {center:?}, radius {radius}); check the bounding sphere or pass seed points"
    )]
    NoSeeds { center: DVec3, radius: f64 },
    #[error(
        "the initial sample is degenerate (all {0} seed points are coplanar); pass more seed points"
    )]
    DegenerateSeeds(usize),
    #[error(transparent)]
    Oracle(#[from] OracleError),
    #[error("Delaunay triangulation: {0}")]
    Delaunay(#[from] delaunay3::Error),
}

/// A surface Delaunay ball B(c, r) circumscribing a restricted facet.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct SurfaceBall {
    pub center: DVec3,
    pub radius: f64,
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
    /// Insertions forced by the manifold patch.
    pub manifold_insertions: usize,
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
    /// went back to the queue (see `refine_batch`).
    pub batch_deferrals: u64,
    /// Refinement batches whose parallel sections ran on one thread and on several: with
    /// several threads the mode is chosen from measured speed, and never changes the mesh
    /// (all batches are sequential on one thread).
    pub sequential_batches: u64,
    pub parallel_batches: u64,
    /// Scaffold points inserted (vertices of Del(E), not samples; see `MeshOptions::scaffold`).
    pub scaffold_points: usize,
    /// Times the final check of the scaffold failed and the triangulation was rebuilt from the
    /// samples alone (0 or 1).
    pub scaffold_rebuilds: usize,
    pub time_total_s: f64,
    pub time_delaunay_s: f64,
    pub time_oracle_s: f64,
    /// Everything else: circumcenters, restricted-facet tests and bookkeeping, criteria, queue.
    pub time_queue_s: f64,
    /// max over the output facets of r / sigma(c) (<= 1 when the size criterion holds).
    pub max_r_over_sigma: Option<f64>,
    /// Smallest facet angle of the output, degrees.
    pub min_angle_deg: f64,
    /// max over facets of distance(circumcenter, c) / distance bound.
    pub max_distance_ratio: Option<f64>,
    /// Every criterion holds on every output facet.
    pub criteria_met: bool,
    /// The budget that stopped the run early, if any.
    pub stopped_by: Option<String>,
    /// Criteria that do not hold at the end (empty when the run completed).
    pub unmet: Vec<String>,
    /// Edges of the output with other than two facets, and vertices with other than one
    /// umbrella (0 and 0 for a closed 2-manifold).
    pub nonmanifold_edges: usize,
    pub nonmanifold_vertices: usize,
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
    pub stats: Stats,
}

/// Progress of a run, passed to the callback of [`mesh_with_progress`].
#[derive(Clone, Copy, Debug)]
pub struct Progress {
    pub sample_points: usize,
    pub restricted_facets: usize,
    pub queue: usize,
}

#[derive(Clone, Copy, Default)]
struct CellInfo {
    cc: DVec3,
    /// Surface value at `cc`, or +inf when `cc` is outside the bounding ball.
    f: f64,
}

#[derive(Clone, Copy, PartialEq)]
struct QEntry {
    bad: f64,
    /// Slot in `Refiner::restricted`.
    idx: u32,
    version: u32,
    forced: bool,
}
impl Eq for QEntry {}
impl Ord for QEntry {
    fn cmp(&self, o: &Self) -> Ordering {
        // `bad` > 0, so its bits order like its value; versions are unique, so the order is
        // total and deterministic (older entries first among equals).
        (self.bad.to_bits(), o.version).cmp(&(o.bad.to_bits(), self.version))
    }
}
impl PartialOrd for QEntry {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}

/// A facet test between its geometric and its oracle half (see `Refiner::test_facets`).
#[derive(Clone, Copy, Debug)]
struct PendingFacet {
    f: Facet,
    m: Facet,
    verts: [VertexId; 3],
    p: DVec3,
    fp: f64,
    q: DVec3,
    fq: f64,
    /// A lower bound of the facet's badness known without its ball, and the facet's
    /// circumcenter (see `Refiner::known_badness`).
    lb: f64,
    cc: DVec3,
    /// Bad anyway (`lb > LAZY_MIN`, bipolar oracle): its crossing is delayed.
    lazy: bool,
}

/// Running mean of the wall time of one oracle call (over the last ~thousand batches).
/// Only used to choose between a sequential and a parallel batch, never for results.
#[derive(Clone, Copy, Debug, Default)]
struct CostEstimate {
    ns: f64,
    calls: f64,
}

impl CostEstimate {
    fn observe(&mut self, dt: Duration, n: usize) {
        const DECAY: f64 = 0.999;
        self.ns = self.ns * DECAY + dt.as_nanos() as f64;
        self.calls = self.calls * DECAY + n as f64;
    }
    fn ns_per_call(&self) -> f64 {
        if self.calls > 0.0 {
            self.ns / self.calls
        } else {
            0.0
        }
    }
}

/// Two refinement points closer than this many times the sum of their balls' radii are not
/// put in the same batch (their conflict zones would likely overlap).
const NEAR_FACTOR: f64 = 3.0;

/// Largest batch of `Refiner::refine_batch`.
const MAX_BATCH: usize = 32;

/// Circumcenters of at least this many created cells are computed in parallel.
const PARALLEL_CELLS: usize = 256;

/// Badness of a restricted facet with a scaffold vertex (refined before anything else).
const SCAFFOLD_BAD: f64 = 1e300;

/// A facet whose badness is known to exceed this without its ball is registered lazily
/// (`RFacet::lazy`): the margin above 1 covers the rounding of r >= circumradius.
const LAZY_MIN: f64 = 1.0 + 1e-9;

/// Queue length below which `Refiner::purge_stale` leaves stale entries alone.
const PURGE_MIN: usize = 4096;

/// A batch of oracle calls runs in parallel when it is expected to take longer than this.
const PARALLEL_BATCH_NS: f64 = 20_000.0;

/// Rounds of random rays (section 6.4.3) per control point before it is reported missing.
const MAX_RAY_ROUNDS: u32 = 16;

/// Manifold passes without a decrease of the non-manifold count before the patch gives up.
const MANIFOLD_STALL_PASSES: u32 = 6;

#[inline]
fn inside(f: f64) -> bool {
    f < 0.0
}

#[inline]
fn sorted3(mut v: [VertexId; 3]) -> [VertexId; 3] {
    if v[0] > v[1] {
        v.swap(0, 1);
    }
    if v[1] > v[2] {
        v.swap(1, 2);
    }
    if v[0] > v[1] {
        v.swap(0, 1);
    }
    v
}

/// Mesh `surface` with `opts`. See [`mesh_with_progress`].
pub fn mesh(surface: &dyn Surface, opts: &MeshOptions) -> Result<MeshResult, MeshError> {
    mesh_with_progress(surface, opts, &mut |_| {})
}

/// Mesh `surface` with `opts`, calling `progress` every few hundred insertions.
pub fn mesh_with_progress(
    surface: &dyn Surface,
    opts: &MeshOptions,
    progress: &mut (dyn FnMut(Progress) + Send),
) -> Result<MeshResult, MeshError> {
    validate(opts)?;
    // The refinement loop runs on a thread of rayon's pool, so that its parallel sections
    // (`refine_batch`, `process_created`, `test_facets`) are split by work stealing with the
    // other workers instead of each waking the pool from outside.
    rayon::scope(|_| {
        let mut r = Refiner::new(surface, opts);
        r.run(progress)?;
        r.finish()
    })
}

/// Run, then recompute Del_S(E) from scratch and return how many facets the incremental
/// update got wrong (must be 0). For tests of the update invariant.
#[doc(hidden)]
pub fn audit(surface: &dyn Surface, opts: &MeshOptions) -> Result<usize, MeshError> {
    validate(opts)?;
    let mut r = Refiner::new(surface, opts);
    r.run(&mut |_| {})?;
    r.audit()
}

fn validate(opts: &MeshOptions) -> Result<(), MeshError> {
    let c = &opts.criteria;
    if let Some(crate::Sizing::Constant(s)) = &c.size
        && !(*s > 0.0 && s.is_finite())
    {
        return Err(MeshError::InvalidSize(*s));
    }
    if !(c.min_angle_deg >= 0.0 && c.min_angle_deg < 35.0) {
        return Err(MeshError::InvalidAngle(c.min_angle_deg));
    }
    if let Some(d) = c.max_distance
        && !(d > 0.0 && d.is_finite())
    {
        return Err(MeshError::InvalidDistance(d));
    }
    if c.size.is_none() && c.min_angle_deg == 0.0 && c.max_distance.is_none() && !opts.manifold {
        return Err(MeshError::NoCriterion);
    }
    Ok(())
}

pub(crate) struct Refiner<'a> {
    s: &'a dyn Surface,
    opts: &'a MeshOptions,
    ball: BoundingSphere,
    /// Shared with the conflict-zone searches of the next batch while the cells created by
    /// the previous one are processed (`refine_batch`); mutated only through `tri_mut`.
    tri: Arc<Triangulation>,
    /// Cells created by the last batch whose circumcenters, values and facets are not
    /// processed yet (see `refine_batch`); empty outside the main loop.
    pending_created: Vec<CellId>,
    /// `cell_info` of each `pending_created` cell, computed during the batch's search (see
    /// `zone_infos`); empty when the cells came from elsewhere.
    pending_infos: Vec<CellInfo>,
    /// Per batch zone: the `cell_info` of the cells its insertion will create
    /// (`Cavity::new_cells` order, which is `Changes::created` order).
    zone_infos: Vec<Vec<CellInfo>>,
    /// The last (clean) result of `nonmanifold_elements`, with the vertex count it was
    /// computed at.
    last_nonmanifold: Option<NonManifold>,
    cells: Vec<CellInfo>,
    restricted: Restricted,
    vertex_facets: Vec<u32>,
    queue: BinaryHeap<QEntry>,
    /// About how many entries of `queue` are stale (see `purge_stale`).
    stale_in_queue: usize,
    /// By vertex id: 0 for a sample, else the sign of the surface's value at a scaffold point.
    scaffold: Vec<i8>,
    /// Scaffold vertices currently in Del(E).
    scaffold_count: usize,
    version: u32,
    changes: Changes,
    created_stamp: Vec<u32>,
    /// Bit i of `facet_mask[c]`: facet i of cell c may be registered in `restricted`.
    /// Set on both cells of a facet when it is registered; a set bit without an entry is
    /// harmless (a missed lookup), a registered facet always has its bits set.
    facet_mask: Vec<u8>,
    manifold_best: usize,
    manifold_stall: u32,
    ray_attempts: Vec<u32>,
    round: u32,
    crossings_buf: Vec<DVec3>,
    pending_buf: Vec<PendingFacet>,
    hits_buf: Vec<Option<(DVec3, bool)>>,
    pairs_buf: Vec<(Facet, Facet)>,
    batch_buf: Vec<(QEntry, RFacet)>,
    cavities: Vec<Cavity>,
    /// `touched[c] == touch_round`: cell c was destroyed by a zone inserted in this batch.
    touched: Vec<u32>,
    touch_round: u32,
    /// Measured costs of the oracle's calls, to decide when a batch runs in parallel.
    value_cost: CostEstimate,
    crossing_cost: CostEstimate,
    /// Whether the parallel sections run on several threads now (see `crate::tuner`).
    tuner: Tuner,
    control: Vec<VertexId>,
    rng: SplitMix64,
    stats: Stats,
    t_delaunay: Duration,
    t_oracle: Duration,
    start: Instant,
    values: u64,
    crossing_calls: u64,
    /// Delay the crossing of facets known bad without it (`RFacet::lazy`; bipolar oracle).
    /// Off only in tests that compare with the eager computation.
    lazy_balls: bool,
    /// `opts.criteria.two_sin_min_angle()`.
    two_sin: f64,
}

impl<'a> Refiner<'a> {
    fn new(s: &'a dyn Surface, opts: &'a MeshOptions) -> Self {
        Refiner {
            s,
            opts,
            ball: s.bounding_sphere(),
            tri: Arc::new(Triangulation::new()),
            pending_created: Vec::new(),
            pending_infos: Vec::new(),
            zone_infos: Vec::new(),
            last_nonmanifold: None,
            cells: Vec::new(),
            restricted: Restricted::default(),
            vertex_facets: Vec::new(),
            queue: BinaryHeap::new(),
            stale_in_queue: 0,
            scaffold: Vec::new(),
            scaffold_count: 0,
            version: 0,
            changes: Changes::default(),
            created_stamp: Vec::new(),
            facet_mask: Vec::new(),
            manifold_best: usize::MAX,
            manifold_stall: 0,
            ray_attempts: Vec::new(),
            round: 0,
            crossings_buf: Vec::new(),
            pending_buf: Vec::new(),
            hits_buf: Vec::new(),
            pairs_buf: Vec::new(),
            batch_buf: Vec::new(),
            cavities: Vec::new(),
            touched: Vec::new(),
            touch_round: 0,
            value_cost: CostEstimate::default(),
            crossing_cost: CostEstimate::default(),
            tuner: Tuner::new(rayon::current_num_threads(), true),
            control: Vec::new(),
            rng: SplitMix64(opts.seed ^ 0xA076_1D64_78BD_642F),
            stats: Stats::default(),
            t_delaunay: Duration::ZERO,
            t_oracle: Duration::ZERO,
            start: Instant::now(),
            values: 0,
            crossing_calls: 0,
            lazy_balls: true,
            two_sin: opts.criteria.two_sin_min_angle(),
        }
    }

    /// The triangulation, for an insertion. Invariant: no other reference to it is alive
    /// outside the `rayon::join` of `refine_batch`, so this never clones it.
    fn tri_mut(&mut self) -> &mut Triangulation {
        Arc::get_mut(&mut self.tri).expect("the triangulation is not shared between steps")
    }

    fn eval(&mut self, p: DVec3) -> Result<f64, MeshError> {
        self.values += 1;
        let v = self.s.value(p);
        if v.is_nan() {
            return Err(OracleError::NaN(p.x, p.y, p.z).into());
        }
        Ok(v)
    }

    /// Control points: the oracle's seeds (or the user's), thinned by farthest-point selection.
    fn control_points(&self) -> Vec<DVec3> {
        let mut pts = match &self.opts.control_points {
            Some(p) => p.clone(),
            None => self.s.seed_points(self.opts.seed),
        };
        pts.retain(|p| p.is_finite());
        let k = self.opts.max_control_points.max(4);
        if pts.len() <= k {
            return pts;
        }
        // Farthest-point selection, deterministic (starts from the first point).
        let mut chosen = vec![pts[0]];
        let mut dist: Vec<f64> = pts.iter().map(|p| p.distance_squared(pts[0])).collect();
        while chosen.len() < k {
            let (i, _) = dist
                .iter()
                .enumerate()
                .max_by(|a, b| a.1.total_cmp(b.1).then(b.0.cmp(&a.0)))
                .unwrap();
            let p = pts[i];
            chosen.push(p);
            for (d, q) in dist.iter_mut().zip(&pts) {
                *d = d.min(q.distance_squared(p));
            }
        }
        chosen
    }

    fn initialize(&mut self) -> Result<(), MeshError> {
        let mut control = self.control_points();
        if self.opts.initialization == Initialization::PersistentFacets {
            // E_i replaces E'_i; the control-point loop is not used (lemma 6.1 instead).
            control = crate::init::persistent_facet_points(self.s, &control, self.opts)?;
        }
        let mut pts: Vec<DVec3> = control.clone();
        pts.extend(self.opts.initial_points.iter().copied());
        if pts.is_empty() {
            return Err(MeshError::NoSeeds {
                center: self.ball.center,
                radius: self.ball.radius,
            });
        }
        // Too few points for a 3D triangulation: add crossings of more random lines.
        let mut extra_seed = self.opts.seed;
        let mut tries = 0;
        while pts.len() < 8 && tries < 8 {
            extra_seed = extra_seed.wrapping_add(0x9E37);
            pts.extend(oracle::roots::random_line_seeds(self.s, 64, extra_seed));
            tries += 1;
        }
        let t = Instant::now();
        let mut ids = Vec::with_capacity(pts.len());
        for p in &pts {
            ids.push(match self.tri_mut().insert(*p)? {
                Insertion::New(v) | Insertion::Duplicate(v) => v,
            });
        }
        self.t_delaunay += t.elapsed();
        if self.tri.dimension() < 3 {
            return Err(MeshError::DegenerateSeeds(pts.len()));
        }
        self.control = if self.opts.initialization == Initialization::PersistentFacets {
            Vec::new()
        } else {
            ids[..control.len()].to_vec()
        };
        self.control.sort_unstable();
        self.control.dedup();
        self.stats.control_points = self.control.len();
        if self.opts.scaffold {
            let lo = pts.iter().fold(DVec3::INFINITY, |a, &p| a.min(p));
            let hi = pts.iter().fold(DVec3::NEG_INFINITY, |a, &p| a.max(p));
            self.insert_scaffold((lo, hi))?;
        }
        self.ensure_vertex_slots();
        // Full scan of Del(E).
        self.full_scan()?;
        Ok(())
    }

    /// Insert the scaffold points (see `crate::scaffold`) and record their signs.
    /// `extent`: a box around the initial sample (the grid's domain).
    fn insert_scaffold(&mut self, extent: (DVec3, DVec3)) -> Result<(), MeshError> {
        let pts = crate::scaffold::scaffold_points(
            self.s,
            self.opts.criteria.size.as_ref(),
            Some(extent),
        );
        let t = Instant::now();
        for p in pts {
            let sign = if self.s.value(p) < 0.0 { -1 } else { 1 };
            if let Insertion::New(v) = self.tri_mut().insert(p)? {
                let v = v as usize;
                if self.scaffold.len() <= v {
                    self.scaffold.resize(v + 1, 0);
                }
                self.scaffold[v] = sign;
                self.scaffold_count += 1;
            }
        }
        self.t_delaunay += t.elapsed();
        self.stats.scaffold_points = self.scaffold_count;
        Ok(())
    }

    #[inline]
    fn is_scaffold(&self, v: VertexId) -> bool {
        self.scaffold.get(v as usize).is_some_and(|&s| s != 0)
    }

    /// The final check of `crate::scaffold`: no restricted facet has a scaffold vertex, and
    /// every Voronoi vertex of a scaffold point (the circumcenters of its cells, whose values
    /// are cached) is on its side of S.
    fn scaffold_clear(&self) -> bool {
        (0..self.scaffold.len()).all(|v| {
            let sign = self.scaffold[v];
            if sign == 0 {
                return true;
            }
            if self.vertex_facets.get(v).copied().unwrap_or(0) != 0 {
                return false;
            }
            self.tri.incident_cells(v as VertexId).iter().all(|&c| {
                let f = self.cells.get(c as usize).map_or(f64::NAN, |i| i.f);
                if sign < 0 { f < 0.0 } else { f > 0.0 }
            })
        })
    }

    /// Rebuild Del(E) from the samples alone (the scaffold dropped) and re-scan it: the
    /// refinement then resumes as the paper's algorithm.
    fn drop_scaffold(&mut self) -> Result<(), MeshError> {
        let t = Instant::now();
        let n = self.tri.num_vertices();
        let mut new_id = vec![VertexId::MAX; n];
        let mut tri = Triangulation::new();
        for v in 0..n as VertexId {
            if self.is_scaffold(v) {
                continue;
            }
            new_id[v as usize] = match tri.insert(self.tri.point(v))? {
                Insertion::New(w) | Insertion::Duplicate(w) => w,
            };
        }
        self.t_delaunay += t.elapsed();
        self.tri = Arc::new(tri);
        for c in self.control.iter_mut() {
            *c = new_id[*c as usize];
        }
        self.scaffold.clear();
        self.scaffold_count = 0;
        self.stats.scaffold_rebuilds += 1;
        self.cells.clear();
        self.restricted.clear();
        self.facet_mask.clear();
        self.created_stamp.clear();
        self.touched.clear();
        self.vertex_facets.clear();
        self.queue.clear();
        self.stale_in_queue = 0;
        self.last_nonmanifold = None;
        self.ensure_vertex_slots();
        self.full_scan()
    }

    /// Compute every cell's circumcenter and value, and test every facet of Del(E) once.
    fn full_scan(&mut self) -> Result<(), MeshError> {
        for c in self.tri.live_cells().collect::<Vec<_>>() {
            self.update_cell(c)?; // infinite cells get f = +inf
        }
        let cells: Vec<CellId> = self.tri.finite_cells().collect();
        self.eval_cells(&cells)?;
        let mut pairs = Vec::new();
        for &c in &cells {
            for i in 0..4u8 {
                let f = Facet { cell: c, index: i };
                let m = self.tri.mirror_facet(f);
                if self.tri.is_infinite(m.cell) || c < m.cell {
                    pairs.push((f, m));
                }
            }
        }
        for chunk in pairs.chunks(4096) {
            self.test_facets(chunk)?;
        }
        Ok(())
    }

    fn update_cell(&mut self, c: CellId) -> Result<(), MeshError> {
        let info = self.cell_info(c);
        self.set_cell(c, info);
        Ok(())
    }

    fn set_cell(&mut self, c: CellId, info: CellInfo) {
        let idx = c as usize;
        if idx >= self.cells.len() {
            self.cells.resize(idx + 1 + idx / 2, CellInfo::default());
        }
        self.cells[idx] = info;
    }

    /// Circumcenter of live cell `c`, with f = NaN ("value not evaluated yet", see
    /// `eval_cells`) inside the bounding ball and +inf outside it or for an infinite cell.
    fn cell_info(&self, c: CellId) -> CellInfo {
        cell_info_of(&self.tri, &self.ball, self.tri.cell_vertices(c), DVec3::NAN)
    }

    /// Evaluate the surface at the circumcenters of `cells` left pending by `update_cell`
    /// (timed as oracle time).
    fn eval_cells(&mut self, cells: &[CellId]) -> Result<(), MeshError> {
        let t = Instant::now();
        let n = cells.len();
        if self.count_parallel(self.parallel_worthwhile(n, self.value_cost)) {
            use rayon::prelude::*;
            let (s, info) = (self.s, &self.cells);
            let vals: Vec<f64> = cells
                .par_iter()
                .map(|&c| {
                    let i = info[c as usize];
                    if i.f.is_nan() { s.value(i.cc) } else { i.f }
                })
                .collect();
            for (&c, v) in cells.iter().zip(vals) {
                let info = self.cells[c as usize];
                if info.f.is_nan() {
                    self.values += 1;
                    if v.is_nan() {
                        return Err(OracleError::NaN(info.cc.x, info.cc.y, info.cc.z).into());
                    }
                    self.cells[c as usize].f = v;
                }
            }
        } else {
            for &c in cells {
                let info = self.cells[c as usize];
                if info.f.is_nan() {
                    self.cells[c as usize].f = self.eval(info.cc)?;
                }
            }
        }
        let dt = t.elapsed();
        self.t_oracle += dt;
        self.value_cost.observe(dt, n);
        Ok(())
    }

    /// The dual of facet `f` as a segment oriented from `f.cell`'s side to the mirror side,
    /// clipped to the bounding ball, with the values at its ends (+inf = on the ball's
    /// boundary or beyond, where the value is positive by the oracle's contract).
    fn clipped_dual(
        &self,
        f: Facet,
        m: Facet,
        verts: [VertexId; 3],
    ) -> Option<(DVec3, f64, DVec3, f64)> {
        let ci = self.tri.is_infinite(f.cell);
        let mi = self.tri.is_infinite(m.cell);
        let (p, fp, q, fq) = match (ci, mi) {
            (false, false) => {
                let a = self.cells[f.cell as usize];
                let b = self.cells[m.cell as usize];
                (a.cc, a.f, b.cc, b.f)
            }
            (false, true) | (true, false) => {
                let [a, b, c] = verts.map(|v| self.tri.point(v));
                // Normal out of f.cell.
                let n = (b - a).cross(c - a);
                let nl = n.length();
                if nl.is_nan() || nl <= 0.0 {
                    return None;
                }
                let n = n / nl;
                let fin = if ci { m.cell } else { f.cell };
                let info = self.cells[fin as usize];
                let far_len = 2.0 * ((info.cc - self.ball.center).length() + self.ball.radius);
                if ci {
                    // Outward of the hull is out of the finite mirror cell, i.e. -n.
                    (info.cc - n * far_len, f64::INFINITY, info.cc, info.f)
                } else {
                    (info.cc, info.f, info.cc + n * far_len, f64::INFINITY)
                }
            }
            (true, true) => return None,
        };
        if !(p.is_finite() && q.is_finite()) {
            return None;
        }
        let (pc, qc) = self.ball.clip_segment(p, q)?;
        // An end moved by the clipping lies on the ball's boundary, where the value is
        // positive by the oracle's contract. (`clip_segment` returns unclipped ends exactly,
        // so both sides of a facet see the same values.)
        let fp = if pc == p { fp } else { f64::INFINITY };
        let fq = if qc == q { fq } else { f64::INFINITY };
        Some((pc, fp, qc, fq))
    }

    /// First half of a facet test: orient `(f, m)` from a finite cell, reject it from the
    /// cached signs (bipolar oracle), and clip its dual. `None` = not restricted.
    fn prepare_facet(&self, f: Facet, m: Facet) -> Option<PendingFacet> {
        // Always look from a finite cell: only finite cells' facet orientation is used.
        let (f, m) = if self.tri.is_infinite(f.cell) {
            (m, f)
        } else {
            (f, m)
        };
        let bipolar = self.opts.oracle == OracleKind::Bipolar;
        // Cheap rejection from the cached signs (infinite cells have f = +inf, so a facet of
        // two infinite cells, which has the infinite vertex, is rejected here). An end outside
        // the bounding ball (or a hull facet's ray, which ends outside it) counts as outside,
        // exactly as its clipped end on the ball's boundary would.
        if bipolar && inside(self.cells[f.cell as usize].f) == inside(self.cells[m.cell as usize].f)
        {
            return None;
        }
        let verts = self.tri.facet_vertices(f);
        if verts.contains(&INFINITE_VERTEX) {
            return None;
        }
        let (p, fp, q, fq) = self.clipped_dual(f, m, verts)?;
        if bipolar && inside(fp) == inside(fq) {
            return None;
        }
        let (lb, cc) = self.known_badness(verts);
        // Only with the bipolar oracle: its facet orientation is known without the crossing.
        let lazy = self.lazy_balls && bipolar && lb > LAZY_MIN;
        Some(PendingFacet {
            f,
            m,
            verts,
            p,
            fp,
            q,
            fq,
            lb,
            cc,
            lazy,
        })
    }

    /// A lower bound of the badness of any surface Delaunay ball of the facet `verts` (a
    /// facet at a scaffold point is always bad, else [`crate::Criteria::badness_lower_bound`]),
    /// and its circumcenter.
    fn known_badness(&self, verts: [VertexId; 3]) -> (f64, DVec3) {
        let (mut lb, cc) = self
            .opts
            .criteria
            .facet_bound(verts.map(|v| self.tri.point(v)), self.two_sin);
        if self.scaffold_count > 0 && verts.iter().any(|&v| self.is_scaffold(v)) {
            lb = SCAFFOLD_BAD;
        }
        (lb, cc)
    }

    /// Compute the surface Delaunay ball of the lazy facet in slot `idx` (`RFacet::lazy`)
    /// and store it. Its cells are live (a fresh entry's facet is registered, and a
    /// destroyed cell's facets are removed), so its dual is the one it was registered with.
    /// Returns the resolved facet.
    fn resolve_lazy(&mut self, idx: u32, rf: RFacet) -> Result<RFacet, MeshError> {
        debug_assert!(rf.lazy);
        let f = rf.facet;
        let m = self.tri.mirror_facet(f);
        let verts = self.tri.facet_vertices(f);
        let (p, fp, q, fq) = self
            .clipped_dual(f, m, verts)
            .expect("a registered facet has a clipped dual");
        let (lb, cc) = self.known_badness(verts);
        let pf = PendingFacet {
            f,
            m,
            verts,
            p,
            fp,
            q,
            fq,
            lb,
            cc,
            lazy: false,
        };
        self.crossing_calls += 1;
        let t = Instant::now();
        let hit = self.resolve_facet(&pf, &mut Vec::new());
        self.t_oracle += t.elapsed();
        let (center, _) = hit.expect("the bipolar oracle always finds a crossing");
        if !center.is_finite() {
            return Err(OracleError::NaN(center.x, center.y, center.z).into());
        }
        let (radius, bad) = self.ball_badness(verts, (lb, cc), center)?;
        let slot = self
            .restricted
            .get_mut(idx, rf.version)
            .expect("resolve_lazy takes a live facet");
        slot.center = center;
        slot.radius = radius;
        // Bad anyway (the bound was > 1), up to rounding: then it stays a bad facet.
        slot.bad = bad.max(rf.bad);
        slot.lazy = false;
        Ok(*slot)
    }

    /// Resolve every lazy facet left (after a budget stop, or before a pass that reads the
    /// balls of all facets).
    fn resolve_all_lazy(&mut self) -> Result<(), MeshError> {
        let lazy: Vec<(u32, RFacet)> = self
            .restricted
            .iter()
            .filter(|(_, _, rf)| rf.lazy)
            .map(|(i, _, rf)| (i, *rf))
            .collect();
        for (idx, rf) in lazy {
            self.resolve_lazy(idx, rf)?;
        }
        Ok(())
    }

    /// The radius and badness of the surface Delaunay ball of `verts` centered at `center`,
    /// from the facet's `known_badness`.
    fn ball_badness(
        &self,
        verts: [VertexId; 3],
        bound: (f64, DVec3),
        center: DVec3,
    ) -> Result<(f64, f64), MeshError> {
        let pts = verts.map(|v| self.tri.point(v));
        let radius = pts.iter().map(|v| v.distance(center)).fold(0.0, f64::max);
        let sigma = self.opts.criteria.size.as_ref().map(|s| s.at(center));
        if let (Some(crate::Sizing::Field(_)), Some(s)) = (&self.opts.criteria.size, sigma)
            && !(s > 0.0 && s.is_finite())
        {
            return Err(MeshError::InvalidSizeField {
                value: s,
                at: center,
            });
        }
        // The bound includes SCAFFOLD_BAD for a facet at a scaffold point: never kept (see
        // `crate::scaffold`).
        let bad = self
            .opts
            .criteria
            .badness_from_bound(bound, center, radius, sigma);
        Ok((radius, bad))
    }

    /// The oracle half of a facet test (pure: may run on any thread): the surface Delaunay
    /// ball's center and whether the dual leaves `f.cell` outward (from inside S to outside).
    /// A lazy facet (`pf.lazy`) gets a NaN center: its crossing is delayed.
    fn resolve_facet(&self, pf: &PendingFacet, buf: &mut Vec<DVec3>) -> Option<(DVec3, bool)> {
        let PendingFacet { p, fp, q, fq, .. } = *pf;
        if pf.lazy {
            return Some((DVec3::NAN, inside(fp)));
        }
        match self.opts.oracle {
            OracleKind::Bipolar => {
                // Values on the ball boundary are positive by contract; pass a finite one.
                let fpv = if fp.is_finite() { fp } else { 1.0 };
                let fqv = if fq.is_finite() { fq } else { 1.0 };
                Some((self.s.crossing(p, fpv, q, fqv), inside(fp)))
            }
            OracleKind::Intersection => {
                buf.clear();
                self.s.crossings(p, q, buf);
                let pts = pf.verts.map(|v| self.tri.point(v));
                let mut best: Option<(DVec3, bool, f64)> = None;
                for (k, c) in buf.iter().enumerate() {
                    let r = pts.iter().map(|v| v.distance(*c)).fold(0.0, f64::max);
                    // Inside before crossing k: parity of the crossings before it.
                    let before_inside = inside(fp) != (k % 2 == 1);
                    if best.is_none_or(|b| r > b.2) {
                        best = Some((*c, before_inside, r));
                    }
                }
                best.map(|(c, o, _)| (c, o))
            }
        }
    }

    /// Test the facets `pairs` (each with its mirror facet) and insert an entry for each
    /// restricted one, in the order given. The caller has removed any previous entry of these
    /// facets (all facets of destroyed cells are removed first). The oracle calls of one
    /// batch run in parallel when they are expensive enough to pay for it; the result does
    /// not depend on it (each call is a pure function of its segment).
    fn test_facets(&mut self, pairs: &[(Facet, Facet)]) -> Result<(), MeshError> {
        let mut pending = std::mem::take(&mut self.pending_buf);
        pending.clear();
        if pairs.len() >= PARALLEL_CELLS && self.tuner.parallel() {
            use rayon::prelude::*;
            let this = &*self;
            let prepared: Vec<Option<PendingFacet>> = pairs
                .par_iter()
                .map(|&(f, m)| this.prepare_facet(f, m))
                .collect();
            pending.extend(prepared.into_iter().flatten());
        } else {
            pending.extend(pairs.iter().filter_map(|&(f, m)| self.prepare_facet(f, m)));
        }
        if pending.is_empty() {
            self.pending_buf = pending;
            return Ok(());
        }
        let eager = pending.iter().filter(|pf| !pf.lazy).count();
        self.crossing_calls += eager as u64;
        let t = Instant::now();
        let mut hits = std::mem::take(&mut self.hits_buf);
        hits.clear();
        if self.count_parallel(self.parallel_worthwhile(eager, self.crossing_cost)) {
            use rayon::prelude::*;
            let this = &*self;
            pending
                .par_iter()
                .map_init(Vec::new, |buf, pf| this.resolve_facet(pf, buf))
                .collect_into_vec(&mut hits);
        } else {
            let mut buf = std::mem::take(&mut self.crossings_buf);
            for pf in &pending {
                hits.push(self.resolve_facet(pf, &mut buf));
            }
            self.crossings_buf = buf;
        }
        let dt = t.elapsed();
        self.t_oracle += dt;
        self.crossing_cost.observe(dt, eager);
        for (pf, hit) in pending.iter().zip(&hits) {
            if let Some(hit) = *hit {
                self.register_facet(pf, hit)?;
            }
        }
        self.pending_buf = pending;
        self.hits_buf = hits;
        Ok(())
    }

    /// Whether a batch of `n` oracle calls of the measured `cost` is worth spreading over
    /// threads (only when there are several, and the batch takes long enough to pay rayon's
    /// fork-join, a few microseconds).
    fn parallel_worthwhile(&self, n: usize, cost: CostEstimate) -> bool {
        n >= 2 && self.tuner.parallel() && cost.ns_per_call() * n as f64 > PARALLEL_BATCH_NS
    }

    fn count_parallel(&mut self, parallel: bool) -> bool {
        self.stats.parallel_oracle_batches += parallel as u64;
        parallel
    }

    /// Last half of a facet test: register a restricted facet and queue it if bad.
    fn register_facet(
        &mut self,
        pf: &PendingFacet,
        (center, outward_from_cell): (DVec3, bool),
    ) -> Result<(), MeshError> {
        let PendingFacet { f, m, verts, .. } = *pf;
        let key = sorted3(verts);
        let lazy = pf.lazy;
        let (center, radius, bad) = if lazy {
            // Never read before `resolve_lazy`.
            (DVec3::NAN, 0.0, pf.lb)
        } else {
            if !center.is_finite() {
                return Err(OracleError::NaN(center.x, center.y, center.z).into());
            }
            let (radius, bad) = self.ball_badness(verts, (pf.lb, pf.cc), center)?;
            (center, radius, bad)
        };
        let oriented = if outward_from_cell {
            verts
        } else {
            [verts[0], verts[2], verts[1]]
        };
        self.version = self.version.wrapping_add(1);
        let rf = RFacet {
            facet: f,
            oriented,
            center,
            radius,
            bad,
            version: self.version,
            lazy,
        };
        let idx = self.restricted.insert(key, rf, m);
        let need = f.cell.max(m.cell) as usize + 1;
        if self.facet_mask.len() < need {
            self.facet_mask.resize(need + need / 2, 0);
        }
        self.facet_mask[f.cell as usize] |= 1 << f.index;
        self.facet_mask[m.cell as usize] |= 1 << m.index;
        for v in key {
            self.vertex_facets[v as usize] += 1;
        }
        if bad > 1.0 {
            self.queue.push(QEntry {
                bad,
                idx,
                version: rf.version,
                forced: false,
            });
        }
        Ok(())
    }

    /// Remove the facet `key`, facet `i` of cell `c`, if registered.
    fn remove_facet(&mut self, c: CellId, i: u8, key: [VertexId; 3]) {
        if let Some(rf) = self.restricted.remove(c, i, key) {
            // Its queue entry, if any, is stale now (forced entries are not counted: rare).
            self.stale_in_queue += usize::from(rf.bad > 1.0);
            for v in key {
                self.vertex_facets[v as usize] -= 1;
            }
        }
    }

    fn ensure_vertex_slots(&mut self) {
        let n = self.tri.num_vertices();
        if self.vertex_facets.len() < n {
            self.vertex_facets.resize(n, 0);
        }
    }

    /// Insert `p` and update Del_S(E). Returns false if `p` was already a vertex.
    fn insert(&mut self, p: DVec3, hint: Option<CellId>) -> Result<bool, MeshError> {
        let t = Instant::now();
        let mut changes = std::mem::take(&mut self.changes);
        debug_assert!(self.pending_created.is_empty());
        let res = self.tri_mut().insert_with(p, hint, Some(&mut changes));
        self.t_delaunay += t.elapsed();
        let res = match res {
            Ok(r) => r,
            Err(e) => {
                self.changes = changes;
                return Err(e.into());
            }
        };
        if let Insertion::Duplicate(_) = res {
            self.changes = changes;
            return Ok(false);
        }
        self.remove_destroyed(&changes);
        let r = self.process_created(&changes.created, &[]);
        self.changes = changes;
        r?;
        Ok(true)
    }

    /// Remove the restricted facets of the cells an insertion destroyed (registered facets
    /// have their bits in `facet_mask`; this includes the cavity's boundary facets, whose duals
    /// changed).
    fn remove_destroyed(&mut self, changes: &Changes) {
        self.ensure_vertex_slots();
        for (cell, &id) in changes.removed.iter().zip(&changes.removed_cells) {
            let mask = self.facet_mask.get(id as usize).copied().unwrap_or(0);
            if mask == 0 {
                continue;
            }
            for i in 0..4 {
                if mask & (1 << i) == 0 {
                    continue;
                }
                let mut f = [0; 3];
                let mut k = 0;
                for (j, &v) in cell.iter().enumerate() {
                    if j != i {
                        f[k] = v;
                        k += 1;
                    }
                }
                if !f.contains(&INFINITE_VERTEX) {
                    self.remove_facet(id, i as u8, sorted3(f));
                }
            }
        }
    }

    /// Compute the circumcenters and values of `created` cells and test every facet of them
    /// (new facets and the boundary facets of the cavities, whose duals changed).
    fn process_created(&mut self, created: &[CellId], infos: &[CellInfo]) -> Result<(), MeshError> {
        self.round = self.round.wrapping_add(1);
        if infos.len() == created.len() {
            // Computed during the search (`zone_infos`).
            for (&c, &info) in created.iter().zip(infos) {
                debug_assert_eq!(
                    (info.cc.to_array(), info.f.is_nan()),
                    {
                        let i = self.cell_info(c);
                        (i.cc.to_array(), i.f.is_nan())
                    },
                    "planned cell info differs"
                );
                self.set_cell(c, info);
            }
        } else if created.len() >= PARALLEL_CELLS && self.tuner.parallel() {
            use rayon::prelude::*;
            let this = &*self;
            let infos: Vec<CellInfo> = created.par_iter().map(|&c| this.cell_info(c)).collect();
            for (&c, info) in created.iter().zip(infos) {
                self.set_cell(c, info);
            }
        } else {
            for &c in created {
                let info = self.cell_info(c);
                self.set_cell(c, info);
            }
        }
        for &c in created {
            if let Some(m) = self.facet_mask.get_mut(c as usize) {
                *m = 0;
            }
        }
        self.eval_cells(created)?;
        for &c in created {
            let idx = c as usize;
            if idx >= self.created_stamp.len() {
                self.created_stamp.resize(idx + 1 + idx / 2, 0);
            }
            self.created_stamp[idx] = self.round;
        }
        let mut pairs = std::mem::take(&mut self.pairs_buf);
        pairs.clear();
        if created.len() >= PARALLEL_CELLS && self.tuner.parallel() {
            use rayon::prelude::*;
            let this = &*self;
            let parts: Vec<Vec<(Facet, Facet)>> = created
                .par_chunks(64)
                .map(|chunk| {
                    let mut v = Vec::new();
                    this.facets_to_test(chunk, &mut v);
                    v
                })
                .collect();
            for v in parts {
                pairs.extend(v);
            }
        } else {
            self.facets_to_test(created, &mut pairs);
        }
        let r = self.test_facets(&pairs);
        self.pairs_buf = pairs;
        r
    }

    /// `process_created` on the cells left pending by the last batch, then clear them.
    fn process_pending(&mut self) -> Result<(), MeshError> {
        let pending = std::mem::take(&mut self.pending_created);
        let infos = std::mem::take(&mut self.pending_infos);
        let r = self.process_created(&pending, &infos);
        self.pending_created = pending;
        self.pending_created.clear();
        self.pending_infos = infos;
        self.pending_infos.clear();
        r
    }

    /// The facets of `cells` (created in this round) to test, each with its mirror facet,
    /// once each: a facet between two created cells is taken from the smaller id.
    fn facets_to_test(&self, cells: &[CellId], out: &mut Vec<(Facet, Facet)>) {
        let bipolar = self.opts.oracle == OracleKind::Bipolar;
        for &c in cells {
            let fc = self.cells[c as usize].f;
            for i in 0..4u8 {
                let n = self.tri.neighbor(c, i as usize);
                let n_created = (n as usize) < self.created_stamp.len()
                    && self.created_stamp[n as usize] == self.round;
                if n_created && n < c {
                    continue; // tested from n's side
                }
                // Invariant (kept by `full_scan` and `process_created`): every live cell has
                // its entry in `cells`, with f = +inf for infinite cells. So the bipolar sign
                // rejection of `prepare_facet` can run here before the mirror facet is built.
                if bipolar && inside(fc) == inside(self.cells[n as usize].f) {
                    continue;
                }
                let f = Facet { cell: c, index: i };
                out.push((f, self.tri.mirror_facet(f)));
            }
        }
    }

    /// Refinement steps in batches: take up to `batch_size()` fresh entries from the queue
    /// (worst first), find their conflict zones at once (in parallel when there are several
    /// threads: a read-only search), insert in queue order those whose cells and outside
    /// neighbors include no cell destroyed by a zone inserted before them in the batch (the
    /// others go back to the queue), then update Del_S(E) for all created cells at once. Such
    /// zones stay exact after the earlier insertions (they may share outside neighbors; proof
    /// in `delaunay3::Triangulation::insert_cavity`). The batches
    /// depend only on the queue, never on the thread count, so the mesh is the same on any
    /// number of threads. Returns false when the queue is empty or a budget stopped the run.
    fn refine_batch(&mut self, since_progress: &mut usize) -> Result<bool, MeshError> {
        let batch_start = Instant::now();
        let k = self.batch_size();
        self.purge_stale();
        let mut batch = std::mem::take(&mut self.batch_buf);
        batch.clear();
        let mut near = Vec::new();
        let sep = NEAR_FACTOR;
        while batch.len() < k {
            let Some(e) = self.queue.pop() else { break };
            let Some(mut rf) = self.restricted.get(e.idx, e.version).copied() else {
                self.stale_in_queue = self.stale_in_queue.saturating_sub(1);
                continue;
            };
            if rf.lazy {
                rf = self.resolve_lazy(e.idx, rf)?;
            }
            if e.forced && rf.radius < self.manifold_floor(rf.center) {
                continue;
            }
            // A point close to one already in the batch has overlapping conflict zones:
            // leave it for the next batch without searching.
            if batch.iter().any(|(_, b): &(QEntry, RFacet)| {
                b.center.distance_squared(rf.center) < (sep * (b.radius + rf.radius)).powi(2)
            }) {
                near.push(e);
                continue;
            }
            batch.push((e, rf));
        }
        self.stats.batch_deferrals += near.len() as u64;
        for e in near {
            self.queue.push(e);
        }
        if batch.is_empty() {
            self.batch_buf = batch;
            if self.pending_created.is_empty() {
                return Ok(false);
            }
            // The last batch's cells may queue new bad balls.
            let r = self.process_pending();
            r?;
            return Ok(true);
        }
        // Conflict zones of this batch (read-only on the triangulation), while the cells
        // created by the previous batch are processed (which reads the triangulation and
        // writes only the refiner's own state). This batch was taken from the queue before
        // those cells' facets were registered: a fixed one-step delay, the same on any number
        // of threads. Its entries stay valid: processing creates no cell and removes no facet.
        let mut cavs = std::mem::take(&mut self.cavities);
        if cavs.len() < batch.len() {
            cavs.resize_with(batch.len(), Cavity::default);
        }
        let mut zone_infos = std::mem::take(&mut self.zone_infos);
        if zone_infos.len() < batch.len() {
            zone_infos.resize_with(batch.len(), Vec::new);
        }
        let pending = std::mem::take(&mut self.pending_created);
        let pending_infos = std::mem::take(&mut self.pending_infos);
        let tri = Arc::clone(&self.tri);
        let ball = self.ball;
        let parallel = self.tuner.parallel();
        let search_all = {
            let (batch, cavs, zone_infos) = (&batch, &mut cavs, &mut zone_infos);
            move || {
                let t = Instant::now();
                // The zone, then the circumcenters of the cells it will create: their points
                // were just read by the search.
                let search =
                    |(e, rf): &(QEntry, RFacet),
                     (cav, infos): (&mut Cavity, &mut Vec<CellInfo>)| {
                        let seed = 0x9E37_79B9_7F4A_7C15 ^ u64::from(e.version);
                        tri.find_cavity(rf.center, Some(rf.facet.cell), seed, cav)?;
                        infos.clear();
                        let p = cav.point();
                        infos.extend(cav.new_cells(NEW).map(|v| cell_info_of(&tri, &ball, v, p)));
                        Ok(())
                    };
                let found: Vec<Result<(), delaunay3::Error>> = if parallel {
                    use rayon::prelude::*;
                    batch
                        .par_iter()
                        .zip(cavs.par_iter_mut().zip(zone_infos.par_iter_mut()))
                        .map(|(b, z)| search(b, z))
                        .collect()
                } else {
                    batch
                        .iter()
                        .zip(cavs.iter_mut().zip(zone_infos.iter_mut()))
                        .map(|(b, z)| search(b, z))
                        .collect()
                };
                (found, t.elapsed())
            }
        };
        let ((found, dt), processed) = if parallel {
            rayon::join(search_all, || {
                self.process_created(&pending, &pending_infos)
            })
        } else {
            // `search_all` is consumed (it holds a clone of the triangulation's `Arc`).
            fn call<R>(f: impl FnOnce() -> R) -> R {
                f()
            }
            let found = call(search_all);
            (found, self.process_created(&pending, &pending_infos))
        };
        self.t_delaunay += dt;
        self.pending_created = pending;
        self.pending_created.clear();
        self.pending_infos = pending_infos;
        self.pending_infos.clear();
        if let Err(e) = processed {
            self.cavities = cavs;
            self.zone_infos = zone_infos;
            self.batch_buf = batch;
            return Err(e);
        }
        // Insert the disjoint ones in queue order.
        self.touch_round = self.touch_round.wrapping_add(1);
        if self.touch_round == 0 {
            self.touched.iter_mut().for_each(|x| *x = 0);
            self.touch_round = 1;
        }
        let mut created = std::mem::take(&mut self.pending_created);
        let mut created_infos = std::mem::take(&mut self.pending_infos);
        let mut changes = std::mem::take(&mut self.changes);
        let mut stop = false;
        let mut inserted = 0usize;
        let mut result = Ok(());
        for (i, (&(e, _), res)) in batch.iter().zip(&found).enumerate() {
            if let Err(err) = res {
                result = Err(MeshError::from(err.clone()));
                break;
            }
            let cav = &cavs[i];
            if cav.duplicate().is_some() {
                continue;
            }
            let round = self.touch_round;
            if cav
                .touched_cells()
                .any(|c| self.touched.get(c as usize).is_some_and(|&r| r == round))
            {
                self.queue.push(e); // its zone overlaps an earlier one: next batch
                self.stats.batch_deferrals += 1;
                continue;
            }
            if self.budget_exceeded() {
                stop = true;
                // The rest of the batch stays queued (for a caller that continues).
                for &(e, _) in &batch[i..] {
                    self.queue.push(e);
                }
                break;
            }
            // Only destroyed cells invalidate later zones (see `insert_cavity`).
            for &c in cav.cells() {
                let c = c as usize;
                if c >= self.touched.len() {
                    self.touched.resize(c + 1 + c / 2, 0);
                }
                self.touched[c] = round;
            }
            let t = Instant::now();
            let ins = self.tri_mut().insert_cavity(cav, Some(&mut changes));
            self.t_delaunay += t.elapsed();
            debug_assert!(matches!(ins, Insertion::New(_)));
            self.remove_destroyed(&changes);
            debug_assert_eq!(changes.created.len(), zone_infos[i].len());
            created.extend_from_slice(&changes.created);
            created_infos.extend_from_slice(&zone_infos[i]);
            self.count_insertion(e.forced, since_progress);
            inserted += 1;
        }
        self.tuner.end_batch(inserted, batch_start.elapsed());
        self.changes = changes;
        self.cavities = cavs;
        self.zone_infos = zone_infos;
        self.pending_infos = created_infos;
        self.batch_buf = batch;
        self.pending_created = created;
        result?;
        if stop {
            // The run ends here: bring Del_S(E) up to date with the triangulation.
            self.process_pending()?;
        }
        Ok(!stop)
    }

    /// Drop the stale entries of the queue (facets removed since) once they are about half of
    /// it: most popped entries are stale, and each pop costs a walk down the heap. The pop order is unchanged (a total order on fresh entries).
    fn purge_stale(&mut self) {
        if self.stale_in_queue > PURGE_MIN && 2 * self.stale_in_queue > self.queue.len() {
            let r = &self.restricted;
            self.queue.retain(|e| r.get(e.idx, e.version).is_some());
            self.stale_in_queue = 0;
        }
    }

    /// Batch size of `refine_batch`: 1 while the triangulation is small (zones overlap), up
    /// to `MAX_BATCH`. A function of the state only (never of the thread count).
    fn batch_size(&self) -> usize {
        (self.tri.num_vertices() / 128).clamp(1, MAX_BATCH)
    }

    fn count_insertion(&mut self, forced: bool, since_progress: &mut usize) {
        if forced {
            self.stats.manifold_insertions += 1;
        } else {
            self.stats.refinement_insertions += 1;
        }
        *since_progress += 1;
    }

    fn budget_exceeded(&mut self) -> bool {
        if let Some(m) = self.opts.max_vertices
            && self.tri.num_vertices() >= m
        {
            self.stats.stopped_by = Some(format!("max_vertices ({m})"));
            return true;
        }
        if let Some(t) = self.opts.time_limit
            && self.start.elapsed() >= t
        {
            self.stats.stopped_by = Some(format!("time_limit ({:.3} s)", t.as_secs_f64()));
            return true;
        }
        false
    }

    fn run(&mut self, progress: &mut (dyn FnMut(Progress) + Send)) -> Result<(), MeshError> {
        self.initialize()?;
        self.refine_loop(progress)
    }

    /// The refinement proper, from the current state (see `run`).
    fn refine_loop(
        &mut self,
        progress: &mut (dyn FnMut(Progress) + Send),
    ) -> Result<(), MeshError> {
        self.ensure_vertex_slots();
        let mut since_progress = 0usize;
        loop {
            // Main loop: refine bad balls, worst first (in batches).
            while !self.queue.is_empty() || !self.pending_created.is_empty() {
                if !self.refine_batch(&mut since_progress)? {
                    if self.stats.stopped_by.is_some() {
                        return Ok(());
                    }
                    continue;
                }
                if since_progress >= 500 {
                    since_progress = 0;
                    progress(Progress {
                        sample_points: self.tri.num_vertices() - self.scaffold_count,
                        restricted_facets: self.restricted.len(),
                        queue: self.queue.len(),
                    });
                }
            }
            // Section 6.4.3: every control point must be a vertex of Del_S(E).
            if self.shoot_control_rays()? {
                continue;
            }
            // Section 6.6.1: the manifold patch.
            if self.opts.manifold && self.push_nonmanifold()? > 0 {
                continue;
            }
            if self.scaffold_count > 0 && !self.scaffold_clear() {
                self.drop_scaffold()?;
                continue;
            }
            return Ok(());
        }
    }

    /// For each control point not on Del_S(E), insert the first crossings of a random ray and
    /// of its opposite. Returns whether anything was inserted.
    fn shoot_control_rays(&mut self) -> Result<bool, MeshError> {
        let mut any = false;
        let control = self.control.clone();
        if self.ray_attempts.len() < control.len() {
            self.ray_attempts.resize(control.len(), 0);
        }
        for (k, v) in control.into_iter().enumerate() {
            if self.vertex_facets.get(v as usize).copied().unwrap_or(0) > 0 {
                continue;
            }
            // Lemma 6.6 needs a smooth surface; near a singular point a control point may
            // never become a vertex and the rays would insert points without end: give up
            // after a few rounds and report the control point as missing.
            if self.ray_attempts[k] >= MAX_RAY_ROUNDS {
                continue;
            }
            self.ray_attempts[k] += 1;
            if self.budget_exceeded() {
                return Ok(false);
            }
            let x = self.tri.point(v);
            let dir = self.rng.unit_vector();
            for d in [dir, -dir] {
                let start = x + d * (100.0 * self.s.tolerance());
                let Some((a, b)) = self.ball.clip_ray(start, d) else {
                    continue;
                };
                let mut buf = Vec::new();
                let t = Instant::now();
                self.crossing_calls += 1;
                self.s.crossings(a, b, &mut buf);
                self.t_oracle += t.elapsed();
                if let Some(&c) = buf.first()
                    && self.insert(c, None)?
                {
                    self.stats.ray_insertions += 1;
                    any = true;
                }
            }
        }
        Ok(any)
    }

    /// Queue (forced) every restricted facet at a non-manifold edge or vertex, or at a
    /// boundary edge. Returns how many facets were queued.
    fn push_nonmanifold(&mut self) -> Result<usize, MeshError> {
        self.resolve_all_lazy()?;
        self.stats.manifold_passes += 1;
        let (bad_edges, bad_vertices) = self.nonmanifold_elements();
        if bad_edges.is_empty() && bad_vertices.is_empty() {
            // Del_S(E) changes only with the vertices: `finish` reuses this.
            self.last_nonmanifold = Some((self.tri.num_vertices(), (bad_edges, bad_vertices)));
            return Ok(0);
        }
        let mut keys: Vec<(u32, RFacet)> = Vec::new();
        for (idx, k, rf) in self.restricted.iter() {
            let e = [[k[0], k[1]], [k[1], k[2]], [k[0], k[2]]];
            if e.iter().any(|e| bad_edges.binary_search(e).is_ok())
                || k.iter().any(|v| bad_vertices.binary_search(v).is_ok())
            {
                keys.push((idx, *rf));
            }
        }
        // Termination (section 6.6.1's patch can refine forever at sharp edges and singular
        // points): stop when the count of bad elements has not decreased for
        // `MANIFOLD_STALL_PASSES` passes, and never force facets smaller than the floor.
        let bad = bad_edges.len() + bad_vertices.len();
        if bad < self.manifold_best {
            self.manifold_best = bad;
            self.manifold_stall = 0;
        } else {
            self.manifold_stall += 1;
            if self.manifold_stall >= MANIFOLD_STALL_PASSES {
                self.stats.stopped_by = Some(format!(
                    "manifold patch: no progress in {MANIFOLD_STALL_PASSES} passes ({bad} non-manifold elements left)"
                ));
                return Ok(0);
            }
        }
        keys.retain(|(_, rf)| rf.radius >= self.manifold_floor(rf.center));
        let n = keys.len();
        // The queue's order is total (badness, then version): push order does not matter.
        for (idx, rf) in keys {
            self.queue.push(QEntry {
                bad: 1.0 + rf.radius,
                idx,
                version: rf.version,
                forced: true,
            });
        }
        Ok(n)
    }

    /// Facets smaller than this are not refined by the manifold patch: a tenth of sigma(c)
    /// with a size criterion, else 1e-3 of the bounding radius (and always 100 x the oracle's
    /// tolerance).
    fn manifold_floor(&self, c: DVec3) -> f64 {
        let base = match &self.opts.criteria.size {
            Some(s) => 0.1 * s.at(c),
            None => 1e-3 * self.ball.radius,
        };
        base.max(100.0 * self.s.tolerance())
    }

    fn sorted_facets(&self) -> Vec<([VertexId; 3], RFacet)> {
        // Sort the (unique) keys with their slots, then gather: cheaper than moving facets.
        let mut keys: Vec<([VertexId; 3], u32)> =
            self.restricted.iter().map(|(i, k, _)| (k, i)).collect();
        keys.sort_unstable();
        keys.into_iter()
            .map(|(k, i)| (k, *self.restricted.slot(i)))
            .collect()
    }

    /// Edges (sorted pairs) with other than two restricted facets, and vertices whose link is
    /// not a single cycle. Both lists sorted.
    fn nonmanifold_elements(&self) -> (Vec<[VertexId; 2]>, Vec<VertexId>) {
        // The order of the triangles does not matter to the result.
        let tris: Vec<[VertexId; 3]> = self.restricted.iter().map(|(_, k, _)| k).collect();
        crate::topology::nonmanifold_elements_with(&tris, self.tuner.parallel())
    }

    /// Recompute Del_S(E) from scratch and count the facets on which the incremental
    /// structure disagrees (0 when the invariants hold). For tests.
    fn audit(&mut self) -> Result<usize, MeshError> {
        // The triangulation itself (combinatorics, orientation, local Delaunay property).
        let invalid = usize::from(self.tri.is_valid().is_err());
        let before: Vec<([VertexId; 3], RFacet)> = self.sorted_facets();
        self.restricted.clear();
        self.facet_mask.clear();
        for v in self.vertex_facets.iter_mut() {
            *v = 0;
        }
        self.queue.clear();
        self.full_scan()?;
        let after = self.sorted_facets();
        let a: Vec<_> = before.iter().map(|x| x.0).collect();
        let b: Vec<_> = after.iter().map(|x| x.0).collect();
        let missing = b.iter().filter(|k| a.binary_search(k).is_err()).count();
        let extra = a.iter().filter(|k| b.binary_search(k).is_err()).count();
        Ok(missing + extra + invalid)
    }

    fn finish(mut self) -> Result<MeshResult, MeshError> {
        // Lazy facets are left only by a budget stop: they are in the mesh, with their balls.
        self.resolve_all_lazy()?;
        let mut facets = self.sorted_facets();
        // A run stopped by a budget may still have facets at scaffold points: not part of
        // the mesh of S (the stop is reported; the criteria are unmet anyway).
        let before = facets.len();
        if self.scaffold_count > 0 {
            facets.retain(|(k, _)| !k.iter().any(|&v| self.is_scaffold(v)));
        }
        let scaffold_dropped = before - facets.len();
        // The vertices of the facets, in id order.
        let mut remap = vec![u32::MAX; self.tri.num_vertices()];
        for (k, _) in &facets {
            for &v in k {
                remap[v as usize] = 0;
            }
        }
        let mut used: Vec<VertexId> = Vec::new();
        for (v, r) in remap.iter_mut().enumerate() {
            if *r == 0 {
                *r = used.len() as u32;
                used.push(v as VertexId);
            }
        }
        let vertices: Vec<DVec3> = used.iter().map(|&v| self.tri.point(v)).collect();
        let triangles: Vec<[u32; 3]> = facets
            .iter()
            .map(|(_, rf)| rf.oriented.map(|v| remap[v as usize]))
            .collect();
        let balls: Vec<SurfaceBall> = facets
            .iter()
            .map(|(_, rf)| SurfaceBall {
                center: rf.center,
                radius: rf.radius,
            })
            .collect();
        // Per-facet measures (in parallel when the tuner says it pays), then min / max
        // (order-independent).
        let measures: Vec<(f64, Option<f64>, Option<f64>, bool)> = {
            use rayon::prelude::*;
            let (tri, criteria) = (&self.tri, &self.opts.criteria);
            let measure = |(_, rf): &([VertexId; 3], RFacet)| {
                let pts = rf.oriented.map(|v| tri.point(v));
                let rs = criteria.size.as_ref().map(|s| rf.radius / s.at(rf.center));
                let dist = criteria.max_distance.map(|d| {
                    let (cc, _) = crate::criteria::triangle_circumcircle(pts);
                    (cc - rf.center).length() / d
                });
                (crate::criteria::min_angle_deg(pts), rs, dist, rf.bad > 1.0)
            };
            if self.tuner.parallel() {
                facets.par_iter().map(measure).collect()
            } else {
                facets.iter().map(measure).collect()
            }
        };
        let max_opt = |a: Option<f64>, b: Option<f64>| match (a, b) {
            (Some(x), Some(y)) => Some(x.max(y)),
            (x, None) | (None, x) => x,
        };
        let mut max_rs: Option<f64> = None;
        let mut max_dist: Option<f64> = None;
        let mut min_angle = f64::INFINITY;
        let mut all_good = true;
        for &(angle, rs, dist, bad) in &measures {
            min_angle = min_angle.min(angle);
            max_rs = max_opt(max_rs, rs);
            max_dist = max_opt(max_dist, dist);
            all_good &= !bad;
        }
        let (bad_edges, bad_vertices) = match self.last_nonmanifold.take() {
            Some((n, r)) if n == self.tri.num_vertices() => r,
            _ => self.nonmanifold_elements(),
        };
        let missing = self
            .control
            .iter()
            .filter(|&&v| self.vertex_facets.get(v as usize).copied().unwrap_or(0) == 0)
            .count();
        let st = &mut self.stats;
        st.vertices = vertices.len();
        st.facets = triangles.len();
        st.sample_points = self.tri.num_vertices() - self.scaffold_count;
        st.control_points_missing = missing;
        st.oracle_value_calls = self.values;
        st.oracle_crossing_calls = self.crossing_calls;
        [st.sequential_batches, st.parallel_batches] = self.tuner.batches;
        st.time_total_s = self.start.elapsed().as_secs_f64();
        st.time_delaunay_s = self.t_delaunay.as_secs_f64();
        st.time_oracle_s = self.t_oracle.as_secs_f64();
        st.time_queue_s = (st.time_total_s - st.time_delaunay_s - st.time_oracle_s).max(0.0);
        st.max_r_over_sigma = max_rs;
        st.max_distance_ratio = max_dist;
        st.min_angle_deg = if min_angle.is_finite() {
            min_angle
        } else {
            0.0
        };
        st.nonmanifold_edges = bad_edges.len();
        st.nonmanifold_vertices = bad_vertices.len();
        let mut unmet = Vec::new();
        if max_rs.is_some_and(|m| m > 1.0) {
            unmet.push(format!("size: max r/sigma = {:.4} > 1", max_rs.unwrap()));
        }
        let a = self.opts.criteria.min_angle_deg;
        if a > 0.0 && !all_good && st.min_angle_deg < a {
            unmet.push(format!("angle: min angle {:.2} < {a}", st.min_angle_deg));
        }
        if max_dist.is_some_and(|m| m > 1.0) {
            unmet.push(format!("distance: max ratio {:.4} > 1", max_dist.unwrap()));
        }
        if scaffold_dropped > 0 {
            unmet.push(format!(
                "scaffold: {scaffold_dropped} facets at scaffold points left out (run stopped early)"
            ));
        }
        if self.opts.manifold && (!bad_edges.is_empty() || !bad_vertices.is_empty()) {
            unmet.push(format!(
                "manifold: {} non-manifold or boundary edges, {} non-manifold vertices",
                bad_edges.len(),
                bad_vertices.len()
            ));
        }
        if missing > 0 {
            unmet.push(format!("control points: {missing} not on the mesh"));
        }
        st.criteria_met = all_good && unmet.is_empty();
        st.unmet = unmet;
        let sample = (0..self.tri.num_vertices() as u32)
            .filter(|&v| !self.is_scaffold(v))
            .map(|v| self.tri.point(v))
            .collect();
        Ok(MeshResult {
            mesh: TriMesh {
                vertices,
                triangles,
            },
            balls,
            sample,
            stats: self.stats,
        })
    }
}

/// Circumcenter and pending value of the cell with vertices `v` (`NEW` stands for the point
/// `new`, not yet a vertex): f = NaN ("not evaluated yet", see `eval_cells`) inside the
/// bounding ball, +inf outside it or for an infinite cell. The same arithmetic on the same
/// points in the same order, whether called on a live cell or on a planned one.
fn cell_info_of(
    tri: &Triangulation,
    ball: &BoundingSphere,
    v: [VertexId; 4],
    new: DVec3,
) -> CellInfo {
    if v.contains(&INFINITE_VERTEX) {
        return CellInfo {
            cc: DVec3::ZERO,
            f: f64::INFINITY,
        };
    }
    let p = v.map(|x| if x == NEW { new } else { tri.point(x) });
    let mut cc = delaunay3::circumcenter(p[0], p[1], p[2], p[3]);
    if !cc.is_finite() {
        cc = flat_cell_center(ball, p);
    }
    let f = if cc.is_finite() && ball.contains(cc) {
        f64::NAN
    } else {
        f64::INFINITY
    };
    CellInfo { cc, f }
}

/// Vertex count, then bad edges and bad vertices (see `Refiner::nonmanifold_elements`).
type NonManifold = (usize, (Vec<[VertexId; 2]>, Vec<VertexId>));

/// Placeholder id of a point being inserted in `Cavity::new_cells`.
const NEW: VertexId = INFINITE_VERTEX - 1;

/// A stand-in circumcenter for a cell whose four vertices are exactly coplanar (it exists
/// under the symbolic perturbation; common on planar parts of polyhedra). Its circumsphere
/// degenerates to the plane, and its center goes to infinity along the plane's normal, on
/// the side fixed by the cell's (perturbed, positive) orientation: return a point on that
/// side far outside the bounding ball, so that the duals of its facets behave as rays.
fn flat_cell_center(ball: &BoundingSphere, p: [DVec3; 4]) -> DVec3 {
    let (a, b, d) = (p[1] - p[0], p[2] - p[0], p[3] - p[0]);
    let (bd, da, ab) = (b.cross(d), d.cross(a), a.cross(b));
    let mut n = bd;
    for x in [da, ab] {
        if x.length_squared() > n.length_squared() {
            n = x;
        }
    }
    let n = n.normalize_or_zero();
    let num = bd * a.length_squared() + da * b.length_squared() + ab * d.length_squared();
    let s = num.dot(n);
    // cc - p0 = num / (2 det) with det -> 0 from below (positive cells have det < 0).
    let dir = if s > 0.0 { -n } else { n };
    let centroid = (p[0] + p[1] + p[2] + p[3]) * 0.25;
    let far = 4.0 * ball.radius + (centroid - ball.center).length();
    centroid + dir * far
}

#[cfg(test)]
mod tests {
    use super::*;
    use oracle::catalog;

    fn torus_opts() -> MeshOptions {
        MeshOptions {
            criteria: Criteria {
                size: Some(crate::Sizing::Constant(0.05)),
                min_angle_deg: 30.0,
                max_distance: None,
            },
            ..Default::default()
        }
    }

    /// The scaffold is used on the torus, and its fallback (the triangulation rebuilt from the
    /// samples alone, refinement resumed) leaves a consistent Del_S(E) and a valid mesh.
    #[test]
    fn scaffold_rebuild_resumes_the_plain_algorithm() {
        let s = catalog::surface("torus").unwrap();
        let opts = torus_opts();
        let mut r = Refiner::new(&s, &opts);
        r.run(&mut |_| {}).unwrap();
        assert!(r.stats.scaffold_points > 0);
        assert!(r.scaffold_clear());
        let samples = r.tri.num_vertices() - r.scaffold_count;
        r.drop_scaffold().unwrap();
        assert_eq!(r.tri.num_vertices(), samples);
        assert_eq!(r.scaffold_count, 0);
        r.refine_loop(&mut |_| {}).unwrap();
        assert_eq!(r.stats.scaffold_rebuilds, 1);
        assert_eq!(
            r.audit().unwrap(),
            0,
            "incremental Del_S(E) differs from a full scan"
        );
        let out = r.finish().unwrap();
        assert!(out.stats.criteria_met, "{:?}", out.stats.unmet);
        assert_eq!(
            crate::topology::nonmanifold_elements(&out.mesh.triangles),
            (vec![], vec![])
        );
        let v = out.mesh.vertices.len() as i64;
        let f = out.mesh.triangles.len() as i64;
        assert_eq!(v - f / 2, 0, "Euler characteristic of a torus"); // V - E + F, E = 3F/2
        for p in &out.mesh.vertices {
            assert!(s.value(*p).abs() < 1e-5);
        }
    }

    /// A run stopped early by a budget, while facets at scaffold points remain, leaves them out
    /// of the mesh (every output vertex is on S) and says so among the unmet criteria.
    #[test]
    fn budget_stop_leaves_scaffold_facets_out() {
        let s = catalog::surface("torus").unwrap();
        let mut saw_scaffold_facets = false;
        for max in [120, 200, 400, 800] {
            let out = mesh(
                &s,
                &MeshOptions {
                    max_vertices: Some(max),
                    ..torus_opts()
                },
            )
            .unwrap();
            assert!(out.stats.stopped_by.is_some());
            assert!(out.stats.scaffold_points > 0);
            for p in out.mesh.vertices.iter().chain(&out.sample) {
                assert!(s.value(*p).abs() < 1e-5, "{p} is not on S");
            }
            saw_scaffold_facets |= out.stats.unmet.iter().any(|u| u.starts_with("scaffold"));
        }
        assert!(
            saw_scaffold_facets,
            "no budget stopped with facets at scaffold points"
        );
    }

    /// Every surface Delaunay ball of `out` is centered on S and passes through its facet's
    /// vertices (a lazy facet resolved: no NaN or placeholder left).
    fn assert_balls_on_s(s: &dyn Surface, out: &MeshResult) {
        assert_eq!(out.balls.len(), out.mesh.triangles.len());
        for (t, b) in out.mesh.triangles.iter().zip(&out.balls) {
            assert!(b.center.is_finite() && b.radius > 0.0, "{b:?}");
            assert!(s.value(b.center).abs() < 1e-5, "center {} off S", b.center);
            for &v in t {
                let d = out.mesh.vertices[v as usize].distance(b.center);
                assert!(
                    (d - b.radius).abs() <= 1e-9 * b.radius.max(1.0),
                    "{d} vs {b:?}"
                );
            }
        }
    }

    /// Delaying the crossing of facets known bad without it changes the refinement order
    /// only: both runs meet the criteria with a valid Del_S(E) (audit) and balls on S, at
    /// sizes within 5%, and the lazy run calls the crossing oracle less.
    #[test]
    fn lazy_balls_change_the_order_not_the_guarantees() {
        let s = catalog::surface("torus").unwrap();
        let opts = torus_opts();
        let mut runs = Vec::new();
        for lazy in [false, true] {
            let mut r = Refiner::new(&s, &opts);
            r.lazy_balls = lazy;
            r.run(&mut |_| {}).unwrap();
            assert_eq!(r.audit().unwrap(), 0, "lazy {lazy}: Del_S(E) differs");
            // The audit's full scan registered everything again, lazily or not: refine the
            // facets it queued (none should be bad), then finish.
            r.refine_loop(&mut |_| {}).unwrap();
            let out = r.finish().unwrap();
            assert!(out.stats.criteria_met, "lazy {lazy}: {:?}", out.stats.unmet);
            assert_balls_on_s(&s, &out);
            runs.push((out.stats.vertices, out.stats.oracle_crossing_calls));
        }
        let (eager, lazy) = (runs[0], runs[1]);
        let ratio = lazy.0 as f64 / eager.0 as f64;
        assert!(
            (0.95..=1.05).contains(&ratio),
            "sizes {eager:?} vs {lazy:?}"
        );
        assert!(lazy.1 < eager.1, "crossing calls {eager:?} vs {lazy:?}");
    }

    /// A budget stop leaves lazy facets in Del_S(E): `finish` computes their balls.
    #[test]
    fn budget_stop_resolves_lazy_balls() {
        let s = catalog::surface("torus").unwrap();
        for max in [150, 700] {
            let opts = MeshOptions {
                max_vertices: Some(max),
                scaffold: false,
                ..torus_opts()
            };
            let mut r = Refiner::new(&s, &opts);
            r.run(&mut |_| {}).unwrap();
            let lazy = r.restricted.iter().filter(|(_, _, f)| f.lazy).count();
            assert!(lazy > 0, "max {max}: no lazy facet left to resolve");
            let out = r.finish().unwrap();
            assert!(out.stats.stopped_by.is_some());
            assert_balls_on_s(&s, &out);
        }
    }

    /// Scaffold or not, the output is a mesh of S: every vertex on S, the same topology, and
    /// sizes within a few percent.
    #[test]
    fn scaffold_changes_speed_not_the_result() {
        let s = catalog::surface("torus").unwrap();
        let on = mesh(&s, &torus_opts()).unwrap();
        let off = mesh(
            &s,
            &MeshOptions {
                scaffold: false,
                ..torus_opts()
            },
        )
        .unwrap();
        assert!(on.stats.scaffold_points > 0);
        assert_eq!(off.stats.scaffold_points, 0);
        for out in [&on, &off] {
            assert!(out.stats.criteria_met);
            assert_eq!(out.stats.sample_points, out.mesh.vertices.len());
            assert_eq!(out.sample.len(), out.stats.sample_points);
            for p in out.mesh.vertices.iter().chain(&out.sample) {
                assert!(s.value(*p).abs() < 1e-5);
            }
        }
        let (a, b) = (
            on.mesh.vertices.len() as f64,
            off.mesh.vertices.len() as f64,
        );
        assert!((a / b - 1.0).abs() < 0.05, "{a} vs {b} vertices");
    }
}
