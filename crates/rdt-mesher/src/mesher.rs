//! The algorithm of section 6.1 from start to end: initialize (sections 6.2 / 6.4.3), refine
//! bad surface Delaunay balls worst first until none is left, shoot the control rays of
//! section 6.4.3, apply the manifold patch of section 6.6.1, check the scaffold, output.

use crate::error::MeshError;
use crate::options::MeshOptions;
use crate::schedule::batch::Scheduler;
use crate::state::Mesher;
use crate::stats::{MeshResult, Progress};
use oracle::Surface;

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
    opts.validate()?;
    // The refinement loop runs on a thread of rayon's pool, so that its parallel sections
    // (`crate::schedule`) are split by work stealing with the other workers instead of each
    // waking the pool from outside.
    rayon::scope(|_| {
        let mut r = Mesher::new(surface, opts);
        r.run(progress)?;
        let mut out = r.finish()?;
        after_refinement(&mut out, surface, opts);
        Ok(out)
    })
}

/// What runs on the output once the refinement has ended (on images with a resolution; the
/// rule 4 drop with `min_component` elsewhere): the separation of touching components and
/// the topological repair, the bridges, the component decisions (`crate::levels`). Each
/// phase's wall time goes to its own figure and to the run's total ("everything else").
fn after_refinement(out: &mut MeshResult, surface: &dyn Surface, opts: &MeshOptions) {
    use std::time::Instant;
    let t = Instant::now();
    let sep = crate::levels::components::separation(out, surface, opts);
    crate::levels::repair::apply(out, opts, &sep.vertices, &sep.labels);
    let t_repair = t.elapsed().as_secs_f64();
    let t = Instant::now();
    crate::levels::bridges::apply(out, surface, opts);
    let t_bridges = t.elapsed().as_secs_f64();
    let t = Instant::now();
    crate::levels::components::apply(out, surface, opts);
    crate::levels::skinny::apply(out, surface, opts);
    let t_components = t.elapsed().as_secs_f64();
    let st = &mut out.stats;
    st.time_repair_s = t_repair;
    st.time_bridges_s = t_bridges;
    st.time_components_s = t_components;
    let dt = t_repair + t_bridges + t_components;
    st.time_total_s += dt;
    st.time_queue_s += dt;
}

/// What [`mesh_in_rounds`] shows its callback between two rounds.
pub(crate) struct RoundEnd<'r> {
    /// The sample: the vertices of Del(E), scaffold points left out, in vertex order.
    pub sample: &'r [glam::DVec3],
    /// Del(E) when it has no scaffold point (then the Delaunay triangulation of the sample).
    pub tri: Option<&'r delaunay3::Triangulation>,
    /// sigma at each sample point under the size function of the round that ended, when it
    /// is a [`crate::Sizing::Lipschitz`] field (else empty).
    pub sizes: &'r [f64],
}

/// The callback of [`mesh_in_rounds`] between two rounds: `None` to stop, or go on with the
/// size function it has changed, and that function's values at the sample points when it
/// computed them (empty, or NaN at a point, when not: the mesher evaluates them).
pub(crate) type Between<'b> =
    dyn FnMut(RoundEnd<'_>) -> Result<Option<Vec<f64>>, MeshError> + Send + 'b;

/// [`mesh_with_progress`] in rounds (not in the paper; the adaptive mode of
/// `crate::adaptive`): after each complete refinement, `between` sees the sample, Del(E)
/// when it has no scaffold point, and sigma at the sample ([`RoundEnd`]), and says whether
/// to go on; it may change the size function that `opts.criteria` reads (a field whose
/// values change only inside `between`). Then every restricted facet is re-judged and the
/// refinement continues on the same Del(E). A budget stop ends the rounds.
pub(crate) fn mesh_in_rounds(
    surface: &dyn Surface,
    opts: &MeshOptions,
    progress: &mut (dyn FnMut(Progress) + Send),
    between: &mut Between<'_>,
) -> Result<MeshResult, MeshError> {
    opts.validate()?;
    rayon::scope(|_| {
        let mut r = Mesher::new(surface, opts);
        r.run(progress)?;
        while r.stats.stopped_by.is_none() {
            let ids: Vec<delaunay3::VertexId> = (0..r.tri.num_vertices())
                .map(delaunay3::VertexId::from_index)
                .filter(|&v| !r.scaffold.contains(v))
                .collect();
            let sample: Vec<glam::DVec3> = ids.iter().map(|&v| r.tri.point(v)).collect();
            let sizes = r.vertex_sizes_at(&ids);
            let tri = (r.scaffold.count() == 0).then_some(&*r.tri);
            let end = RoundEnd {
                sample: &sample,
                tri,
                sizes: &sizes,
            };
            let Some(next) = between(end)? else {
                break;
            };
            r.requeue_all(&ids, &next)?;
            r.refine_loop(progress)?;
        }
        let mut out = r.finish()?;
        after_refinement(&mut out, surface, opts);
        Ok(out)
    })
}

/// Insertions between two calls of the progress callback.
const PROGRESS_EVERY: usize = 500;

impl Mesher<'_> {
    /// Initialize, then refine (see the module docs).
    pub(crate) fn run(
        &mut self,
        progress: &mut (dyn FnMut(Progress) + Send),
    ) -> Result<(), MeshError> {
        self.initialize()?;
        self.refine_loop(progress)
    }

    /// The refinement proper, from the current state (see `run`).
    pub(crate) fn refine_loop(
        &mut self,
        progress: &mut (dyn FnMut(Progress) + Send),
    ) -> Result<(), MeshError> {
        self.ensure_vertex_slots();
        let mut sched = Scheduler::default();
        let mut since_progress = 0usize;
        loop {
            // Main loop: refine bad balls, worst first (in batches).
            while !self.queue.is_empty() || sched.has_pending() {
                if !sched.step(self, &mut since_progress)? {
                    if self.stats.stopped_by.is_some() {
                        return Ok(());
                    }
                    continue;
                }
                if since_progress >= PROGRESS_EVERY {
                    since_progress = 0;
                    progress(Progress {
                        sample_points: self.sample_points(),
                        restricted_facets: self.restricted.len(),
                        queue: self.queue.len(),
                    });
                }
            }
            // Section 6.4.3: every control point must be a vertex of Del_S(E).
            if self.shoot_control_rays()? {
                continue;
            }
            // Images: parts of S the sample does not reach (ours, `crate::levels::coverage`).
            let t = std::time::Instant::now();
            let covered = self.cover_crossings()?;
            self.stats.time_coverage_s += t.elapsed().as_secs_f64();
            if covered {
                continue;
            }
            // Images: scan components that no vertex reaches (ours, `crate::levels::missed`).
            if self.reseed_missed()? {
                continue;
            }
            // Images: necks thinner than the sample (ours, `crate::levels::necks`).
            let t = std::time::Instant::now();
            let reseeded = self.reseed_necks()?;
            self.stats.time_necks_s += t.elapsed().as_secs_f64();
            if reseeded {
                continue;
            }
            // Images: handles thinner than the sample (ours, `crate::levels::handles`).
            let t = std::time::Instant::now();
            let reseeded = self.reseed_handles()?;
            self.stats.time_necks_s += t.elapsed().as_secs_f64();
            if reseeded {
                continue;
            }
            // Section 6.6.1: the manifold patch.
            if self.opts.manifold && self.push_nonmanifold()? > 0 {
                continue;
            }
            if self.scaffold.count() > 0
                && !self
                    .scaffold
                    .is_clear(&self.restricted, &self.tri, &self.voronoi)
            {
                self.drop_scaffold()?;
                continue;
            }
            return Ok(());
        }
    }
}

#[cfg(test)]
mod tests;
