//! The state of one run of section 6.1's refinement (ours): Del(E), its Voronoi vertices,
//! Del_S(E), the queue, the parallel policy, and what the levels keep between passes.
//!
//! The steps are written where a reader of the paper looks for them, each as an `impl Mesher`
//! block: the facet test and lazy balls in `crate::restricted`, the batches in
//! `crate::schedule`, initialization and control rays in `crate::init`, the scaffold and the
//! manifold patch in `crate::levels`, the output in `crate::output`, the loop in
//! `crate::mesher`.

use crate::levels::scaffold::Scaffold;
use crate::options::MeshOptions;
use crate::queue::Queue;
use crate::restricted::{Restricted, VertexSizes};
use crate::schedule::Policy;
use crate::stats::{Stats, StopReason};
use crate::voronoi::Voronoi;
use delaunay3::{Triangulation, VertexId};
use geom::SplitMix64;
use oracle::{BoundingSphere, Surface};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Vertex count, then bad edges and bad vertices (see `Mesher::nonmanifold_elements`).
pub(crate) type NonManifold = (usize, (Vec<[VertexId; 2]>, Vec<VertexId>));

/// What the manifold patch (section 6.6.1) keeps between its passes.
pub(crate) struct ManifoldProgress {
    /// The smallest count of bad elements seen.
    pub best: usize,
    /// Passes since that count last decreased.
    pub stall: u32,
    /// The last (clean) result of `nonmanifold_elements`, with the vertex count it was
    /// computed at.
    pub last: Option<NonManifold>,
}

/// The control points of section 6.4.3 and their rays.
pub(crate) struct Control {
    /// Their vertex ids, sorted.
    pub vertices: Vec<VertexId>,
    /// Rounds of rays shot from each (by index in `vertices`).
    pub ray_attempts: Vec<u32>,
    /// The rays' directions.
    pub rng: SplitMix64,
}

/// `Mesher::tri_mut` on the field alone (so that other fields stay borrowable).
pub(crate) fn unique(tri: &mut Arc<Triangulation>) -> &mut Triangulation {
    Arc::get_mut(tri).expect("the triangulation is not shared between steps")
}

/// One meshing run (see the module docs).
pub(crate) struct Mesher<'a> {
    /// The surface S (its oracle).
    pub s: &'a dyn Surface,
    /// The run's options.
    pub opts: &'a MeshOptions,
    /// S's bounding ball: Voronoi edges are clipped to it.
    pub ball: BoundingSphere,
    /// Del(E). Shared with the conflict-zone searches of the next batch while the cells
    /// created by the previous one are processed (`crate::schedule::batch`); mutated only
    /// through `tri_mut`.
    pub tri: Arc<Triangulation>,
    /// The Voronoi vertices of Del(E)'s cells, with the surface values there.
    pub voronoi: Voronoi,
    /// Del_S(E).
    pub restricted: Restricted,
    /// Bad facets, worst first.
    pub queue: Queue,
    /// sigma at the vertices, for a Lipschitz size field (`crate::restricted::vertex_sizes`).
    pub vertex_sizes: VertexSizes,
    /// Where the parallel sections run.
    pub policy: Policy,
    /// Which vertices of Del(E) are scaffold points.
    pub scaffold: Scaffold,
    /// The manifold patch's progress.
    pub manifold: ManifoldProgress,
    /// The control points.
    pub control: Control,
    /// The figures of the run so far.
    pub stats: Stats,
    /// Time in the triangulation.
    pub t_delaunay: Duration,
    /// Time in the oracle.
    pub t_oracle: Duration,
    /// When the run started.
    pub start: Instant,
    /// Oracle value calls.
    pub values: u64,
    /// Oracle crossing calls.
    pub crossing_calls: u64,
    /// Delay the crossing of facets known bad without it (`RFacet::lazy`; bipolar oracle).
    /// Off only in tests that compare with the eager computation.
    pub lazy_balls: bool,
    /// `opts.criteria.two_sin_min_angle()`.
    pub two_sin: f64,
    /// Images: what the coverage and neck rounds keep between rounds (`crate::levels`).
    pub scan: crate::levels::ScanCache,
}

impl<'a> Mesher<'a> {
    /// A run on `s` with `opts` (validated by the caller), before initialization.
    pub fn new(s: &'a dyn Surface, opts: &'a MeshOptions) -> Self {
        Mesher {
            s,
            opts,
            ball: s.bounding_sphere(),
            tri: Arc::new(Triangulation::new()),
            voronoi: Voronoi::default(),
            restricted: Restricted::default(),
            queue: Queue::default(),
            vertex_sizes: VertexSizes::default(),
            policy: Policy::new(),
            scaffold: Scaffold::default(),
            manifold: ManifoldProgress {
                best: usize::MAX,
                stall: 0,
                last: None,
            },
            control: Control {
                vertices: Vec::new(),
                ray_attempts: Vec::new(),
                rng: SplitMix64(opts.seed ^ 0xA076_1D64_78BD_642F),
            },
            stats: Stats::default(),
            t_delaunay: Duration::ZERO,
            t_oracle: Duration::ZERO,
            start: Instant::now(),
            values: 0,
            crossing_calls: 0,
            lazy_balls: true,
            two_sin: opts.criteria.two_sin_min_angle(),
            scan: Default::default(),
        }
    }

    /// The triangulation, for an insertion. Invariant: no other reference to it is alive
    /// outside the `join` of a batch, so this never clones it.
    pub fn tri_mut(&mut self) -> &mut Triangulation {
        unique(&mut self.tri)
    }

    /// Make room in Del_S(E)'s indexes for every vertex of Del(E).
    pub fn ensure_vertex_slots(&mut self) {
        self.restricted.ensure_vertices(self.tri.num_vertices());
    }

    /// Points of the sample E so far (scaffold points left out).
    pub fn sample_points(&self) -> usize {
        self.tri.num_vertices() - self.scaffold.count()
    }

    /// Whether a budget is exhausted (then `stats.stopped_by` says which).
    pub fn budget_exceeded(&mut self) -> bool {
        if let Some(m) = self.opts.max_vertices
            && self.tri.num_vertices() >= m
        {
            self.stats.stopped_by = Some(StopReason::MaxVertices { limit: m });
            return true;
        }
        if let Some(t) = self.opts.time_limit
            && self.start.elapsed() >= t
        {
            self.stats.stopped_by = Some(StopReason::TimeLimit {
                seconds: t.as_secs_f64(),
            });
            return true;
        }
        if let Some(c) = &self.opts.cancel
            && c.is_cancelled()
        {
            self.stats.stopped_by = Some(StopReason::Cancelled);
            return true;
        }
        false
    }

    /// Count one insertion of a ball's center.
    pub fn count_insertion(&mut self, forced: bool, since_progress: &mut usize) {
        if forced {
            self.stats.manifold_insertions += 1;
        } else {
            self.stats.refinement_insertions += 1;
        }
        *since_progress += 1;
    }
}
