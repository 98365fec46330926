//! The Voronoi vertices of Vor(E) (section 6.1: the duals of the cells of Del(E)), cached per
//! cell with the surface's value there: the ends of every Voronoi edge the facet test clips.
//!
//! # Invariant (kept by the facet tests of `crate::restricted`)
//! `Voronoi::get(c)` holds the circumcenter of every live finite cell `c` and the surface
//! value there (or +inf: outside the bounding ball, or an infinite cell); it is recomputed
//! for every created cell.

use crate::error::MeshError;
use crate::schedule::Exec;
use delaunay3::{CellId, Triangulation, VertexId};
use glam::DVec3;
use oracle::{BoundingSphere, OracleError, Surface};

/// The Voronoi vertex of a cell (its circumcenter) and the surface value there.
#[derive(Clone, Copy, Default)]
pub(crate) struct CellInfo {
    /// The circumcenter (a stand-in far point for a flat cell, see `flat_cell_center`).
    pub cc: DVec3,
    /// Surface value at `cc`, or +inf when `cc` is outside the bounding ball; NaN while
    /// "not evaluated yet" (see [`Voronoi::eval`]).
    pub f: f64,
}

/// Placeholder id of a point being inserted in `Cavity::new_cells`.
pub(crate) const NEW: VertexId = VertexId::NONE;

/// The cache of Voronoi vertices, by cell id.
#[derive(Default)]
pub(crate) struct Voronoi {
    cells: Vec<CellInfo>,
}

impl Voronoi {
    /// The cached info of cell `c` (which must have been set).
    #[inline]
    pub fn get(&self, c: CellId) -> CellInfo {
        self.cells[c.index()]
    }

    /// The cached value at cell `c`'s Voronoi vertex, NaN if `c` was never set.
    #[inline]
    pub fn value_or_nan(&self, c: CellId) -> f64 {
        self.cells.get(c.index()).map_or(f64::NAN, |i| i.f)
    }

    /// Set the info of cell `c`.
    pub fn set(&mut self, c: CellId, info: CellInfo) {
        let idx = c.index();
        if idx >= self.cells.len() {
            // Only up to `idx`: the vector's own growth amortizes the resizes, and the spare
            // capacity it keeps is never written, so it costs no resident memory (a 1.5x
            // over-resize here wrote defaults into it: 678 bytes per output vertex on the
            // torus at 1e5 vertices, against 208 for the cells in use).
            self.cells.resize(idx + 1, CellInfo::default());
        }
        self.cells[idx] = info;
    }

    /// Heap bytes allocated.
    pub fn heap_bytes(&self) -> usize {
        self.cells.capacity() * std::mem::size_of::<CellInfo>()
    }

    /// Forget every cell (the triangulation was rebuilt).
    pub fn clear(&mut self) {
        self.cells.clear();
    }

    /// Evaluate the surface at the Voronoi vertices of `cells` left pending (f = NaN), on
    /// `exec`'s threads. Returns how many values were computed, or the NaN error of the
    /// first (in `cells` order) that is not a number.
    pub fn eval(
        &mut self,
        s: &dyn Surface,
        cells: &[CellId],
        exec: Exec,
    ) -> Result<u64, MeshError> {
        let info = &self.cells;
        let vals: Vec<f64> = exec.map(cells, |&c| {
            let i = info[c.index()];
            if i.f.is_nan() { s.value(i.cc) } else { i.f }
        });
        let mut evaluated = 0;
        for (&c, v) in cells.iter().zip(vals) {
            let info = self.cells[c.index()];
            if info.f.is_nan() {
                evaluated += 1;
                if v.is_nan() {
                    return Err(OracleError::NaN(info.cc.x, info.cc.y, info.cc.z).into());
                }
                self.cells[c.index()].f = v;
            }
        }
        Ok(evaluated)
    }
}

/// Circumcenter and pending value of the cell with vertices `v` (`NEW` stands for the point
/// `new`, not yet a vertex): f = NaN ("not evaluated yet", see [`Voronoi::eval`]) inside the
/// bounding ball, +inf outside it or for an infinite cell. The same arithmetic on the same
/// points in the same order, whether called on a live cell or on a planned one.
pub(crate) fn cell_info_of(
    tri: &Triangulation,
    ball: &BoundingSphere,
    v: [VertexId; 4],
    new: DVec3,
) -> CellInfo {
    if v.contains(&VertexId::INFINITE) {
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
