//! Refinement steps of section 6.1 in batches (ours): the insertions of one batch are those
//! of a sequential run, in queue order, with their conflict-zone searches done at once.
//!
//! A step takes up to `batch_size()` fresh entries from the queue (worst first), finds their
//! conflict zones at once (in parallel when the tuner says so: a read-only search), inserts
//! in queue order those whose cells and outside neighbors include no cell destroyed by a
//! zone inserted before them in the batch (the others go back to the queue), and leaves the
//! cells created for the next step to process (Del_S(E) and its queue are updated then, while
//! that step's zones are searched). Such zones stay exact after the earlier insertions (they
//! may share outside neighbors; proof in `delaunay3::Triangulation::insert_cavity`). The
//! batches depend only on the queue, never on the thread count, so the mesh is the same on
//! any number of threads.

use crate::error::MeshError;
use crate::queue::Popped;
use crate::restricted::RFacet;
use crate::state::Mesher;
use crate::voronoi::{CellInfo, NEW, cell_info_of};
use delaunay3::{Cavity, CellId, Changes, Insertion};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Two refinement points closer than this many times the sum of their balls' radii are not
/// put in the same batch (their conflict zones would likely overlap).
const NEAR_FACTOR: f64 = 3.0;

/// Largest batch.
const MAX_BATCH: usize = 32;

/// A batch point's conflict zone, and the `cell_info` of the cells its insertion will create
/// (`Cavity::new_cells` order, which is `Changes::created` order).
#[derive(Default)]
struct Zone {
    cav: Cavity,
    infos: Vec<CellInfo>,
    /// The point is closer than [`EMPTY_BALL_SLACK`] times its ball's radius to a vertex of
    /// its zone's boundary (see [`unsound_center`]).
    unsound: bool,
}

/// A refinement point is the center of a surface Delaunay ball B(c, r): a ball through the
/// facet's vertices that holds no sample point, so every sample point is at least r from c.
/// A point found closer than this fraction of r to one (its nearest sample point is a vertex
/// of its conflict zone's boundary, a Delaunay neighbour) comes from an inexact construction,
/// not from the ball: the circumcenters of cells with nearly coincident vertices, which f64
/// cannot place. Inserting it made such clusters grow without end (nibabel's example4d at
/// iso 495, `--size 2`: 1.4 million vertices within 2e-12 voxel of one crossing, stopped by
/// the 2-million budget). It is not inserted; its facet stays, reported by the final checks.
const EMPTY_BALL_SLACK: f64 = 0.5;

/// Whether the refinement point `p` of a ball of radius `r`, whose conflict zone is `cav`,
/// is nearer than `EMPTY_BALL_SLACK * r` to a sample point (see [`EMPTY_BALL_SLACK`]).
fn unsound_center(tri: &delaunay3::Triangulation, cav: &Cavity, p: glam::DVec3, r: f64) -> bool {
    let r2 = (EMPTY_BALL_SLACK * r).powi(2);
    cav.new_cells(NEW).any(|v| {
        v.iter().any(|&u| {
            u != NEW && u != delaunay3::VertexId::INFINITE && tri.point(u).distance_squared(p) < r2
        })
    })
}

/// The batch scheduler of one refinement loop: its batch and the cells the last batch
/// created (see the module docs).
///
/// Invariant: between steps, `pending` are the cells created by the last batch whose
/// circumcenters, values and facets are not processed yet, with their `pending_infos`
/// (computed during the search); both empty when the loop ends.
#[derive(Default)]
pub(crate) struct Scheduler {
    batch: Vec<(Popped, RFacet)>,
    zones: Vec<Zone>,
    pending: Vec<CellId>,
    pending_infos: Vec<CellInfo>,
    /// The cells destroyed by the zones inserted in this batch (a set the size of a batch's
    /// zones, where a stamp per cell slot cost 4 bytes a cell).
    touched: rustc_hash::FxHashSet<u32>,
    changes: Changes,
}

impl Scheduler {
    /// Cells created by the last batch are not processed yet.
    pub fn has_pending(&self) -> bool {
        !self.pending.is_empty()
    }

    /// One refinement step (see the module docs). Returns false when the queue is empty or
    /// a budget stopped the run (then Del_S(E) is up to date).
    pub fn step(&mut self, m: &mut Mesher, since_progress: &mut usize) -> Result<bool, MeshError> {
        let batch_start = Instant::now();
        self.take_batch(m)?;
        if self.batch.is_empty() {
            if self.pending.is_empty() {
                return Ok(false);
            }
            // The last batch's cells may queue new bad balls.
            self.process_pending(m)?;
            return Ok(true);
        }
        let found = self.search_and_process(m)?;
        let (inserted, stop, result) = self.insert_disjoint(m, &found, since_progress);
        m.policy.tuner.end_batch(inserted, batch_start.elapsed());
        result?;
        if stop {
            // The run ends here: bring Del_S(E) up to date with the triangulation.
            self.process_pending(m)?;
        }
        Ok(!stop)
    }

    /// Fill `batch` with up to `batch_size` fresh entries, worst first (lazy balls resolved),
    /// leaving for the next batch, without a search, those close to one already taken.
    fn take_batch(&mut self, m: &mut Mesher) -> Result<(), MeshError> {
        let k = batch_size(m);
        if !m.queue.is_spatial() && m.tri.num_vertices() >= m.opts.spatial_order_from {
            let (tri, ball) = (&m.tri, &m.ball);
            m.queue
                .go_spatial((ball.center, ball.radius), &m.restricted, |v| tri.point(v));
        }
        m.queue.purge_stale(&m.restricted);
        self.batch.clear();
        let mut near = Vec::new();
        while self.batch.len() < k {
            let Some((e, mut rf)) = m.queue.pop_fresh(&m.restricted) else {
                break;
            };
            if rf.lazy {
                rf = m.resolve_lazy(e.idx(), rf)?;
            }
            if e.forced() && rf.radius < m.manifold_floor(rf.center) {
                continue;
            }
            // A point close to one already in the batch has overlapping conflict zones.
            if self.batch.iter().any(|(_, b)| {
                b.center.distance_squared(rf.center)
                    < (NEAR_FACTOR * (b.radius + rf.radius)).powi(2)
            }) {
                near.push(e);
                continue;
            }
            self.batch.push((e, rf));
        }
        m.stats.batch_deferrals += near.len() as u64;
        // The batch's entries stay out: those deferred are the last taken from the queue
        // apart from them, so they are its largest (`Queue::defer`).
        m.queue.defer(&near);
        Ok(())
    }

    /// `Mesher::process_created` on the pending cells, then clear them.
    fn process_pending(&mut self, m: &mut Mesher) -> Result<(), MeshError> {
        let r = m.process_created(&self.pending, &self.pending_infos);
        self.pending.clear();
        self.pending_infos.clear();
        r
    }

    /// The conflict zones of this batch (read-only on the triangulation), while the cells
    /// created by the previous batch are processed (which reads the triangulation and writes
    /// only the mesher's own state). This batch was taken from the queue before those cells'
    /// facets were registered: a fixed one-step delay, the same on any number of threads.
    /// Its entries stay valid: processing creates no cell and removes no facet.
    fn search_and_process(
        &mut self,
        m: &mut Mesher,
    ) -> Result<Vec<Result<(), delaunay3::Error>>, MeshError> {
        if self.zones.len() < self.batch.len() {
            self.zones.resize_with(self.batch.len(), Zone::default);
        }
        let tri = Arc::clone(&m.tri);
        let ball = m.ball;
        let exec = m.policy.batch();
        let (batch, zones) = (&self.batch, &mut self.zones);
        let search_all = move || {
            let t = Instant::now();
            // The zone, then the circumcenters of the cells it will create: their points
            // were just read by the search.
            let found = exec.map_zip_mut(batch, zones, |(e, rf), z| {
                let seed = 0x9E37_79B9_7F4A_7C15 ^ u64::from(e.version());
                tri.find_cavity(rf.center, Some(rf.cell), seed, &mut z.cav)?;
                z.infos.clear();
                let p = z.cav.point();
                z.infos.extend(
                    z.cav
                        .new_cells(NEW)
                        .map(|v| cell_info_of(&tri, &ball, v, p)),
                );
                z.unsound = unsound_center(&tri, &z.cav, p, rf.radius);
                Ok(())
            });
            (found, t.elapsed())
        };
        let (pending, pending_infos) = (&self.pending, &self.pending_infos);
        // The processing first, on this thread: it reads the cells this thread's insertions
        // just wrote, still in its cache; the searches go to the other thread. Run the other
        // way round, the cells crossed between the cores and the processing was the slower
        // branch (the 886k-vertex torus: the join 8.8 s -> 7.7-8.0 s of wall time).
        let (processed, (found, dt)): (_, (_, Duration)) =
            exec.join(|| m.process_created(pending, pending_infos), search_all);
        m.t_delaunay += dt;
        self.pending.clear();
        self.pending_infos.clear();
        processed?;
        Ok(found)
    }

    /// Insert, in queue order, the zones found that no earlier insertion of the batch
    /// touched (the others go back to the queue), until a budget is exhausted. Returns the
    /// insertions, whether a budget stopped the run, and the first search error.
    fn insert_disjoint(
        &mut self,
        m: &mut Mesher,
        found: &[Result<(), delaunay3::Error>],
        since_progress: &mut usize,
    ) -> (usize, bool, Result<(), MeshError>) {
        self.touched.clear();
        let mut inserted = 0usize;
        for (i, (&(e, _), res)) in self.batch.iter().zip(found).enumerate() {
            if let Err(err) = res {
                return (inserted, false, Err(MeshError::from(err.clone())));
            }
            let z = &self.zones[i];
            if z.cav.duplicate().is_some() {
                continue;
            }
            if z.unsound {
                m.stats.unsound_centers += 1;
                continue;
            }
            if z.cav
                .touched_cells()
                .any(|c| self.touched.contains(&c.to_u32()))
            {
                m.queue.requeue(e); // its zone overlaps an earlier one: next batch
                m.stats.batch_deferrals += 1;
                continue;
            }
            if m.budget_exceeded() {
                // The rest of the batch stays queued (for a caller that continues).
                for &(e, _) in &self.batch[i..] {
                    m.queue.requeue(e);
                }
                return (inserted, true, Ok(()));
            }
            // Only destroyed cells invalidate later zones (see `insert_cavity`).
            self.touched
                .extend(z.cav.cells().iter().map(|c| c.to_u32()));
            let t = Instant::now();
            let ins = m.tri_mut().insert_cavity(&z.cav, Some(&mut self.changes));
            m.t_delaunay += t.elapsed();
            debug_assert!(matches!(ins, Insertion::New(_)));
            m.remove_destroyed(&self.changes);
            debug_assert_eq!(self.changes.created.len(), z.infos.len());
            self.pending.extend_from_slice(&self.changes.created);
            self.pending_infos.extend_from_slice(&z.infos);
            m.count_insertion(e.forced(), since_progress);
            inserted += 1;
        }
        (inserted, false, Ok(()))
    }
}

/// Batch size: 1 while the triangulation is small (zones overlap), up to `MAX_BATCH`. A
/// function of the state only (never of the thread count).
fn batch_size(m: &Mesher) -> usize {
    (m.tri.num_vertices() / 128).clamp(1, MAX_BATCH)
}
