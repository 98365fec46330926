//! The result of the voxel scan (P1 for images, section 6.6.2): component counts and on-surface seeds.

use crate::roots::SplitMix64;
use glam::DVec3;

/// Components of the level set found on the voxel grid, and on-surface seed points.
#[derive(Clone, Debug, PartialEq)]
pub struct Topology {
    /// Connected components of the inside (value < 0) region.
    pub inside_components: usize,
    /// Connected components of the outside region, including the unbounded one.
    pub outside_components: usize,
    /// Connected components of the surface: `inside + outside - 1`, less the vanishing ones.
    pub surface_components: usize,
    /// Outside regions of zero volume (every node at the iso value, no whole cell of them:
    /// punctures of the inside, see `vanishing`); counted in `outside_components`, not in
    /// `surface_components`.
    pub vanishing_components: usize,
    /// For each of `component_seeds`: whether its component vanishes (its outside region has
    /// zero volume). Such components get no seed tetrahedron and are left out of
    /// [`Topology::seed_points_within`].
    pub component_vanishing: Vec<bool>,
    /// Number of grid edges (including edges to the padding) with a sign change.
    pub crossing_edges: usize,
    /// One world-space point on each pair (inside component, outside component) that touch:
    /// at least one per surface component.
    pub component_seeds: Vec<DVec3>,
    /// Number of crossing edges of each pair of `component_seeds` (a size measure: about the
    /// component's area in voxel faces).
    pub component_edges: Vec<usize>,
    /// For each of `component_seeds`: empty, or three more points of its component that form
    /// with the seed a tetrahedron whose circumcentre lies in the region the component
    /// encloses, near the seed (see [`Topology::seed_points_within`]). Built for every
    /// component: around the whole component if it spans at most 8 voxels, else around its
    /// seed.
    pub component_tets: Vec<Vec<DVec3>>,
    /// Further crossing points (world space), at a regular stride over the grid.
    pub extra_seeds: Vec<DVec3>,
    /// The scan's regions, for [`Topology::component_at`] (`None` from the reference scan).
    pub(crate) labels: Option<std::sync::Arc<super::labels::Labels>>,
}

impl Topology {
    /// The component (index into [`Topology::component_seeds`]) of a point of S at voxel
    /// coordinates `v`, from the regions of its cell's corners: exact where the cell's corners
    /// meet one inside and one outside region, the nearest such pair otherwise. `None` if the
    /// labels are not kept or no pair of the cell's corners touches.
    pub fn component_at(&self, v: DVec3) -> Option<usize> {
        self.labels.as_ref()?.component_at(v)
    }

    /// [`Topology::seed_points_within`] the default budget [`Topology::SEED_BUDGET`] (64, the
    /// mesher's default number of control points).
    pub fn seed_points(&self, seed: u64) -> Vec<DVec3> {
        self.seed_points_within(seed, Self::SEED_BUDGET)
    }

    /// All component seeds (but the vanishing ones), then the tetrahedra ([`Topology::component_tets`]) of the
    /// components in increasing size (fewest crossing edges first), as many as two thirds of
    /// the budget left by the seeds allow (three points each), then extra seeds chosen from
    /// `seed` (deterministic), up to `budget` points in all (more only when there are more
    /// components).
    ///
    /// The mesher thins longer lists than its `MeshOptions::max_control_points` (64 by
    /// default) by farthest-point selection, which would drop the close points of a
    /// tetrahedron first: keep `budget` at most that. With at most 64 components every
    /// component seed is kept. The tetrahedra matter for components smaller than the size
    /// bound: from one seed alone, the section 6.4.3 rays must land several points on a blob
    /// of a voxel or two before one of its Voronoi vertices falls inside it (no facet is
    /// restricted before), and often gave up; the tetrahedron's circumcentre is such a Voronoi
    /// vertex from the start. The extra seeds (the last third) seed the far side of necks
    /// thinner than the size bound on big components: with all of the budget in tetrahedra,
    /// more of the nilearn fixture's surface stayed unmeshed at iso 2.
    /// [`Topology::full_seed_budget`] fits every tetrahedron.
    pub fn seed_points_within(&self, seed: u64, budget: usize) -> Vec<DVec3> {
        let vanishing = |i: usize| self.component_vanishing.get(i).copied().unwrap_or(false);
        let mut out: Vec<DVec3> = (0..self.component_seeds.len())
            .filter(|&i| !vanishing(i))
            .map(|i| self.component_seeds[i])
            .collect();
        let mut order: Vec<usize> = (0..self.component_seeds.len()).collect();
        order.sort_by_key(|&i| (self.component_edges.get(i).copied().unwrap_or(0), i));
        let mut room = budget.saturating_sub(out.len()) * 2 / 9;
        for i in order {
            if room == 0 {
                break;
            }
            if let Some(tet) = self.component_tets.get(i).filter(|t| !t.is_empty()) {
                out.extend_from_slice(tet);
                room -= 1;
            }
        }
        let k = budget.saturating_sub(out.len());
        let n = self.extra_seeds.len();
        if n <= k {
            out.extend_from_slice(&self.extra_seeds);
        } else if let Some(step) = n.checked_div(k) {
            let mut rng = SplitMix64(seed ^ 0x001A_A6E5_EED5);
            let start = (rng.next_u64() % n as u64) as usize;
            out.extend((0..k).map(|i| self.extra_seeds[(start + i * step) % n]));
        }
        out
    }

    /// The smallest budget for [`Topology::seed_points_within`] that takes every seed
    /// tetrahedron (at least [`Topology::SEED_BUDGET`]); pass the mesher as many control
    /// points.
    pub fn full_seed_budget(&self) -> usize {
        let n = self.component_vanishing.iter().filter(|&&v| !v).count();
        let tets = self.component_tets.iter().filter(|t| !t.is_empty()).count();
        Self::SEED_BUDGET.max(n + (9 * tets).div_ceil(2) + 1)
    }

    /// Total number of seed points [`Topology::seed_points`] aims at.
    pub const SEED_BUDGET: usize = 64;
}
