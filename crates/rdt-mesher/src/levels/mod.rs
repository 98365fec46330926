//! What runs after the queue of section 6.1 empties, level by level (as CGAL's surface mesher
//! layers its refinement): on images, the coverage of the scan's crossings (`coverage`,
//! ours), the reseeding of missed scan components (`missed`, ours), the neck reseeding
//! (`necks`, ours) and the handle reseeding (`handles`, ours), the manifold patch
//! of section 6.6.1 (`manifold`), and the final
//! check of the scaffold (`scaffold`, ours), which may rebuild Del(E) without it; on sampled
//! surfaces (images), the topological repair of what the patch leaves (`repair`, ours, with
//! `links` and `holes`), the bridges between the pieces of a split scan component
//! (`bridges`, ours), then the component decisions on what the scan and the output still
//! disagree about (`components`, ours).

pub(crate) mod bridges;
pub(crate) mod components;
mod coverage;
mod handles;
mod holes;
mod links;
pub(crate) mod manifold;
mod missed;
pub(crate) mod necks;
mod new_triangles;
pub(crate) mod repair;
pub(crate) mod scaffold;
pub(crate) mod skinny;
mod tubes;

use crate::error::MeshError;
use crate::state::Mesher;
use delaunay3::{Insertion, Triangulation, VertexId};
use glam::DVec3;
use std::sync::Arc;
use std::time::Instant;

/// What the rounds on images keep between them (each a function of the image and of
/// vertices' points only, so keeping it changes no result).
///
/// Invariant: the vertex-indexed entries refer to the vertices of the current Del(E); they
/// are cleared when Del(E) is rebuilt ([`Mesher::drop_scaffold`]).
#[derive(Default)]
pub(crate) struct ScanCache {
    /// The voxel-edge crossings of S, computed by the first coverage round (`coverage`).
    pub crossings: Option<Vec<DVec3>>,
    /// Per crossing, the vertex of Del_S(E) found nearest to it by the last coverage round
    /// that looked for one (`u32::MAX`: none yet) and its squared distance to the crossing.
    pub nearest: Vec<(u32, f64)>,
    /// Per vertex of Del(E), its scan component once computed (`necks`): `None` not yet,
    /// `Some(None)` on no component.
    pub labels: Vec<Option<Option<usize>>>,
    /// Per scan component, the margin level and the pieces (points, largest first) of the
    /// last neck round that looked for its rings (`necks`).
    pub rings_seen: std::collections::BTreeMap<usize, (u32, Vec<Vec<DVec3>>)>,
    /// The scan's joins through saddles and their sides (`handles`), listed once.
    pub saddles: Option<Vec<(oracle::image::Join, bool)>>,
}

impl ScanCache {
    /// Forget what refers to vertex indices (Del(E) is rebuilt).
    fn clear_vertex_data(&mut self) {
        self.nearest.clear();
        self.labels.clear();
    }
}

impl Mesher<'_> {
    /// Insert `pts` in order (points of S found by a level's round) until a budget is
    /// exhausted; returns how many were new vertices.
    pub(crate) fn insert_points(&mut self, pts: Vec<DVec3>) -> Result<usize, MeshError> {
        let mut inserted = 0;
        for p in pts {
            if self.budget_exceeded() {
                break;
            }
            if self.insert(p, None)? {
                inserted += 1;
            }
        }
        Ok(inserted)
    }

    /// Rebuild Del(E) from the samples alone (the scaffold dropped) and re-scan it: the
    /// refinement then resumes as the paper's algorithm.
    pub(crate) fn drop_scaffold(&mut self) -> Result<(), MeshError> {
        let t = Instant::now();
        let n = self.tri.num_vertices();
        let mut new_id = vec![VertexId::INFINITE; n];
        let mut tri = Triangulation::new();
        for v in (0..n).map(VertexId::from_index) {
            if self.scaffold.contains(v) {
                continue;
            }
            new_id[v.index()] = match tri.insert(self.tri.point(v))? {
                Insertion::New(w) | Insertion::Duplicate(w) => w,
            };
        }
        self.t_delaunay += t.elapsed();
        self.tri = Arc::new(tri);
        for c in self.control.vertices.iter_mut() {
            *c = new_id[(*c).index()];
        }
        self.scaffold.clear();
        self.scan.clear_vertex_data();
        self.stats.scaffold_rebuilds += 1;
        self.voronoi.clear();
        self.restricted.clear();
        self.queue.clear();
        self.vertex_sizes.clear();
        self.manifold.last = None;
        self.ensure_vertex_slots();
        self.full_scan()
    }
}
