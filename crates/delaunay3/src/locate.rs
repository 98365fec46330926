//! Point location (ours, after Devillers, Pion & Teillaud, "Walking in a triangulation"): the
//! randomized visibility walk, [`Triangulation::locate`] and
//! [`Triangulation::nearest_vertex`] (a greedy walk on Delaunay edges).

use glam::DVec3;

use crate::ids::{CellId, VertexId};
use crate::predicates::{Sign, orient3d};
use crate::sort::Rng;
use crate::tds::FACET;
use crate::triangulation::{Error, Triangulation, check_point};

/// Where a point lies, as found by [`Triangulation::locate`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Location {
    /// The point is this vertex.
    Vertex(VertexId),
    /// The point is in this finite cell (closed: possibly on its boundary, never a vertex).
    Cell(CellId),
    /// The point is outside the convex hull, strictly beyond the hull facet of this infinite
    /// cell.
    Outside(CellId),
    /// The triangulation is not 3D yet.
    NoCells,
}

/// The end of a walk.
pub(crate) enum Walk {
    Vertex(VertexId),
    Inside(CellId),
    Outside(CellId),
}

impl Triangulation {
    /// Locates `p` by a visibility walk from `hint` (or the last created cell). Does not
    /// modify the triangulation. Errors on invalid coordinates.
    pub fn locate(&self, p: DVec3, hint: Option<CellId>) -> Result<Location, Error> {
        check_point(p)?;
        if !self.built {
            return Ok(Location::NoCells);
        }
        let mut rng = Rng(p.x.to_bits() ^ p.y.to_bits().rotate_left(21) ^ p.z.to_bits());
        Ok(match self.walk(p, self.start_cell(hint), &mut rng) {
            Walk::Vertex(v) => Location::Vertex(v),
            Walk::Inside(c) => Location::Cell(c),
            Walk::Outside(c) => Location::Outside(c),
        })
    }

    /// Nearest vertex to `p` (Euclidean, f64 distances; ties go to the first found), by
    /// locating `p` and walking greedily on Delaunay edges. `None` when empty or on bad input.
    pub fn nearest_vertex(&self, p: DVec3, hint: Option<CellId>) -> Option<VertexId> {
        if self.points.is_empty() || check_point(p).is_err() {
            return None;
        }
        if !self.built {
            return (0..self.points.len() as u32)
                .min_by(|&a, &b| {
                    let (da, db) = (
                        self.points[a as usize].distance_squared(p),
                        self.points[b as usize].distance_squared(p),
                    );
                    da.partial_cmp(&db).unwrap()
                })
                .map(VertexId);
        }
        let c = match self.locate(p, hint).ok()? {
            Location::Vertex(v) => return Some(v),
            Location::Cell(c) | Location::Outside(c) => c,
            Location::NoCells => return None,
        };
        // Keeps the nearer of `best` and the finite vertex `v`; true when `v` is nearer.
        let offer = |v: VertexId, best: &mut (VertexId, f64)| {
            if v == VertexId::INFINITE {
                return false;
            }
            let d = self.pt(v).distance_squared(p);
            let nearer = d < best.1;
            if nearer {
                *best = (v, d);
            }
            nearer
        };
        let mut best = (VertexId::INFINITE, f64::INFINITY);
        for &v in &self.tds.cell(c).v {
            offer(v, &mut best);
        }
        loop {
            let mut improved = false;
            for c in self.incident_cells(best.0) {
                for &w in &self.tds.cell(c).v {
                    improved |= offer(w, &mut best);
                }
            }
            if !improved {
                return Some(best.0);
            }
        }
    }

    /// Visibility walk from `start` (randomized facet order).
    pub(crate) fn walk(&self, p: DVec3, start: CellId, rng: &mut Rng) -> Walk {
        let cells = &self.tds.cells;
        let mut c = start;
        let mut prev = CellId::NONE;
        {
            let v = cells[c.index()].v;
            if let Some(k) = v.iter().position(|&w| w == VertexId::INFINITE) {
                let [a, b, d] = FACET[k].map(|i| self.pt(v[i]));
                if orient3d(a, b, d, p) == Sign::Positive {
                    return Walk::Outside(c);
                }
                prev = c;
                c = cells[c.index()].n[k];
            }
        }
        'walk: loop {
            let cell = cells[c.index()];
            let r = (rng.next_u64() >> 62) as usize;
            for t in 0..4 {
                let i = (r + t) & 3;
                let n = cell.n[i];
                if n == prev {
                    continue;
                }
                let [a, b, d] = FACET[i];
                let pts = &self.points;
                if orient3d(
                    pts[cell.v[a].index()],
                    pts[cell.v[b].index()],
                    pts[cell.v[d].index()],
                    p,
                ) == Sign::Negative
                {
                    prev = c;
                    c = n;
                    if cells[n.index()].is_infinite() {
                        return Walk::Outside(n);
                    }
                    continue 'walk;
                }
            }
            if let Some(&w) = cell.v.iter().find(|&&w| self.points[w.index()] == p) {
                return Walk::Vertex(w);
            }
            return Walk::Inside(c);
        }
    }
}
