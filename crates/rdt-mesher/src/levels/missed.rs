//! Scan components that Del_S(E) does not reach (ours, images: P1 of section 6.6.2 and the
//! component accounting of issue 14).
//!
//! Every component of the voxel scan gets seed points (`oracle`'s `Topology`: a crossing and,
//! when one is found, a tetrahedron whose circumcentre lies in the region the component
//! encloses). A component thinner than a voxel in one direction (a cavity of a voxel or two
//! around one node below the iso value, flattened between brighter neighbours, whose
//! crossings sit at nodes equal to the iso value: the uint8 MNI T1 at `--iso 171`) may have
//! no such tetrahedron, and from its one seed no Voronoi vertex of the sample falls inside
//! it: no facet of it is ever restricted, or only facets that bridge it to a neighbouring
//! component (which the repair's `separate` rule cuts), and the component is missed. Here,
//! once the queue is empty, every scan component with no vertex of Del_S(E) whose restricted
//! facets all lie on it (by the scan's labels, `ImageSurface::component_of`) gets all of its voxel-edge crossings within a few voxels of
//! its seed inserted (exact points of S, the marching-cubes vertices of that component), and
//! the refinement resumes; at most [`MISSED_ROUNDS`] rounds.
//!
//! Invariant kept: only points of S that the scan labels with the missed component are
//! inserted, so the rounds add no vertex anywhere else; a component reached by no vertex
//! after the rounds is reported as `missed` by the component decisions.

use crate::error::MeshError;
use crate::state::Mesher;
use glam::DVec3;
use rayon::prelude::*;

use super::coverage::{cell_of, spread_grid};

/// Rounds of reseeding of missed components per run.
pub(crate) const MISSED_ROUNDS: usize = 2;

/// The crossings inserted for a missed component lie within this many voxels of its seed,
/// plus the square root of its number of crossing edges (about its extent in voxels).
const REACH_VOXELS: f64 = 3.0;

impl Mesher<'_> {
    /// One round of reseeding of the missed scan components (see the module docs); returns
    /// whether a point was inserted.
    pub(crate) fn reseed_missed(&mut self) -> Result<bool, MeshError> {
        let (Some(h), Some(img)) = (self.opts.resolution, self.s.as_image()) else {
            return Ok(false);
        };
        if self.stats.missed_rounds >= MISSED_ROUNDS || self.budget_exceeded() {
            return Ok(false);
        }
        self.resolve_all_lazy()?;
        let topo = img.topology();
        let nc = topo.component_seeds.len();
        // Reached: a vertex of Del_S(E) on the component whose restricted facets all have
        // their three vertices on it. The repair's `separate` rule cuts every vertex of a
        // facet that bridges two components, so a component whose every vertex is on such a
        // facet can vanish whole (measured: the MNI crop at iso 171, 1 mm, component 49).
        // The labels are kept per vertex between rounds (`necks`' cache): each vertex is
        // labelled once in the run.
        let label: Vec<u32> = self
            .vertex_labels(img)
            .into_iter()
            .map(|l| l.filter(|&c| c < nc).map_or(u32::MAX, |c| c as u32))
            .collect();
        let n = label.len();
        let mut mixed = vec![false; n];
        for (_, k, _) in self.restricted.iter() {
            let l = label[k[0].index()];
            if l == u32::MAX || k.iter().any(|v| label[v.index()] != l) {
                k.iter().for_each(|v| mixed[v.index()] = true);
            }
        }
        let mut has = vec![false; nc];
        for v in 0..n {
            if !mixed[v] && label[v] != u32::MAX {
                has[label[v] as usize] = true;
            }
        }
        let missed: Vec<(DVec3, f64, usize)> = (0..nc)
            .filter(|&c| !has[c] && !topo.component_vanishing.get(c).copied().unwrap_or(false))
            .map(|c| {
                let edges = topo.component_edges.get(c).copied().unwrap_or(0) as f64;
                (
                    topo.component_seeds[c],
                    h * (REACH_VOXELS + edges.sqrt()),
                    c,
                )
            })
            .collect();
        if missed.is_empty() {
            return Ok(false);
        }
        let crossings: &Vec<DVec3> = self
            .scan
            .crossings
            .get_or_insert_with(|| verify::level_set::LevelSet::new(img).edge_crossings());
        let side = missed.iter().map(|m| m.1).fold(0.0, f64::max);
        let grid = spread_grid(missed.iter().map(|&m| (m.0, m)), side);
        // In the crossings' order (deterministic): each crossing near a missed seed whose
        // component the scan says it lies on.
        let pts: Vec<DVec3> = crossings
            .par_iter()
            .filter(|&&q| {
                grid.get(&cell_of(q, side)).is_some_and(|ms| {
                    ms.iter().any(|&(p, r, c)| {
                        p.distance_squared(q) <= r * r && img.component_of(q) == Some(c)
                    })
                })
            })
            .copied()
            .collect();
        self.stats.missed_rounds += 1;
        let inserted = self.insert_points(pts)?;
        self.stats.missed_insertions += inserted;
        Ok(inserted > 0)
    }
}
