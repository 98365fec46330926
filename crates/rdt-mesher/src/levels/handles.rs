//! Handle reseeding (ours), on images: a handle of the trilinear level set thinner than the
//! sample (a tunnel of the outside through the inside, or a loop of the inside) meets no
//! Voronoi edge, so Del_S(E) fills or cuts it and keeps its components: the neck reseeding
//! sees nothing, the manifold patch neither. The voxel scan knows the level set's total genus
//! (`ImageSurface::scan_genus`, from the grid's Euler characteristic); when Del_S(E) has
//! fewer handles, the scan's joins through saddles
//! (`ImageSurface::saddle_joins`: where a region passes between two nodes only through a
//! saddle, the narrowest place of such a handle) are checked against Del(E): a saddle whose
//! Delaunay cell has its circumcentre (its Voronoi vertex) on the other side of S is one that
//! the mesh puts on the wrong side, and a ring of points of S is inserted around it, as the
//! neck reseeding does at a join, when the neck is not thinner than the manifold patch's
//! floor (the ring's nearest crossing is its radius). The refinement of section 6.1 then
//! resumes. At most
//! [`HANDLE_ROUNDS`] rounds; what is left is counted by `verify`'s `scan-genus`.
//!
//! Invariant: nothing here runs unless Del_S(E)'s genus (`(2 C - χ) / 2`) is below the
//! scan's, so a mesh with the scan's genus is unchanged.

use crate::error::MeshError;
use crate::state::Mesher;
use crate::topology::VertexUnion;
use delaunay3::{CellId, Location};
use oracle::image::ImageSurface;
use rustc_hash::FxHashMap;
use std::time::Instant;

/// A handle is reseeded when its neck's radius is at least this many manifold floors.
const NECK_FLOORS: f64 = 1.0;

/// Rounds of handle reseeding per run.
pub(crate) const HANDLE_ROUNDS: usize = 4;

impl Mesher<'_> {
    /// One round of handle reseeding (see the module docs) when the surface is an image, a
    /// resolution is set and Del_S(E) has fewer handles than the scan's level set; returns
    /// whether a point was inserted.
    pub(crate) fn reseed_handles(&mut self) -> Result<bool, MeshError> {
        let (Some(_), Some(img)) = (self.opts.resolution, self.s.as_image()) else {
            return Ok(false);
        };
        if self.stats.handle_rounds >= HANDLE_ROUNDS || self.budget_exceeded() {
            return Ok(false);
        }
        let Some(scan) = img.scan_genus() else {
            return Ok(false);
        };
        self.resolve_all_lazy()?;
        let t = Instant::now();
        let short = self.restricted_genus().is_some_and(|g| g < scan);
        let pts = if short {
            self.wrong_side_rings(img)
        } else {
            Vec::new()
        };
        self.t_oracle += t.elapsed();
        if pts.is_empty() {
            return Ok(false);
        }
        self.stats.handle_rounds += 1;
        let inserted = self.insert_points(pts)?;
        self.stats.handle_insertions += inserted;
        Ok(inserted > 0)
    }

    /// The total genus of Del_S(E), `(2 C - χ) / 2` over its `C` pieces: exact when it is a
    /// closed manifold; with an edge in more than two facets (before the topological repair)
    /// each such edge counts once, so the figure is at most the genus of the surface the
    /// repair will cut it into, and a deficit is not missed.
    fn restricted_genus(&self) -> Option<usize> {
        let n = self.tri.num_vertices();
        let mut union = VertexUnion::new(n);
        let mut used = vec![false; n];
        let mut edges: FxHashMap<(u32, u32), u8> = FxHashMap::default();
        let mut faces = 0i64;
        for (_, k, _) in self.restricted.iter() {
            let t = k.map(delaunay3::VertexId::to_u32);
            union.join_triangle(t);
            faces += 1;
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                *edges.entry((a.min(b), a.max(b))).or_default() += 1;
                used[a as usize] = true;
            }
        }
        let vertices = used.iter().filter(|&&u| u).count() as i64;
        let mut roots: Vec<u32> = (0..n as u32)
            .filter(|&v| used[v as usize])
            .map(|v| union.find(v))
            .collect();
        roots.sort_unstable();
        roots.dedup();
        let chi = vertices - edges.len() as i64 + faces;
        usize::try_from((2 * roots.len() as i64 - chi) / 2).ok()
    }

    /// The rings around the scan's saddles whose Delaunay cell's circumcentre is on the other
    /// side of S (in the scan's cell order: deterministic).
    fn wrong_side_rings(&mut self, img: &ImageSurface) -> Vec<glam::DVec3> {
        if self.scan.saddles.is_none() {
            self.scan.saddles = Some(img.saddle_joins());
        }
        let saddles = self.scan.saddles.as_deref().unwrap_or_default();
        let mut hint: Option<CellId> = None;
        let mut out = Vec::new();
        for (j, inside) in saddles {
            let Ok(Location::Cell(c)) = self.tri.locate(j.via, hint) else {
                continue;
            };
            hint = Some(c);
            if self.tri.is_infinite(c) {
                continue;
            }
            let meshed_inside = self.s.value(self.tri.circumcenter(c)) < 0.0;
            if meshed_inside != *inside {
                // The ring's nearest crossing is the neck's radius: below the manifold
                // patch's floor the refinement could not mesh it (it would stall there and
                // leave it to the topological decisions), so such a handle is left.
                let before = out.len();
                super::necks::ring(img, j, &mut out);
                let radius = out[before..]
                    .iter()
                    .map(|p| p.distance(j.via))
                    .fold(f64::INFINITY, f64::min);
                if radius < NECK_FLOORS * self.manifold_floor(j.via) {
                    out.truncate(before);
                }
            }
        }
        out
    }
}
