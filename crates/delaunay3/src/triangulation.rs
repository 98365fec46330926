//! The triangulation (ours): the point array over the [`crate::tds`] topology, point
//! validation, and the read-only queries (cells, facets, stars, Voronoi duals).

use std::collections::HashMap;

use glam::DVec3;

use crate::construct::circumcenter;
use crate::ids::{CellId, Facet, VertexId};
use crate::sort::Rng;
use crate::tds::{Boundary, DEAD, FACET, Tds};

/// Why a point could not be inserted (the triangulation is left unchanged).
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum Error {
    /// A coordinate is not finite or outside the safe range of the exact predicates.
    #[error(
        "point {0:?} has a non-finite or out-of-range coordinate: every coordinate must be \
         finite, at most 2^200 in magnitude, and either 0 or at least 2^-140 in magnitude \
         (the range where the exact predicates cannot overflow); remove or rescale the point"
    )]
    InvalidPoint([f64; 3]),
}

/// The Voronoi dual of a Delaunay facet.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Dual {
    /// Between the circumcenters of the two finite cells sharing the facet.
    Segment(DVec3, DVec3),
    /// Hull facet: from the circumcenter of its finite cell, away from the hull.
    Ray {
        /// The circumcenter of the finite cell.
        origin: DVec3,
        /// The outward normal of the hull facet (not normalized).
        direction: DVec3,
    },
}

/// Checks that `p` can be inserted: finite coordinates, each 0 or of magnitude within
/// `[2^-140, 2^200]` (the range where the exact predicates cannot overflow or underflow).
pub fn validate_point(p: DVec3) -> Result<(), Error> {
    check_point(p)
}

pub(crate) fn check_point(p: DVec3) -> Result<(), Error> {
    const MAX: f64 = 1.606_938_044_258_990_3e60; // 2^200
    const MIN: f64 = 7.174_648_137_343_063e-43; // 2^-140
    for x in p.to_array() {
        let a = x.abs();
        if !x.is_finite() || a > MAX || (a != 0.0 && a < MIN) {
            return Err(Error::InvalidPoint(p.to_array()));
        }
    }
    Ok(())
}

/// An exact, incremental 3D Delaunay triangulation (see the crate docs).
#[derive(Default, Clone)]
pub struct Triangulation {
    pub(crate) points: Vec<DVec3>,
    pub(crate) tds: Tds,
    /// Whether the triangulation is 3D (has cells).
    pub(crate) built: bool,
    pub(crate) rng: Rng,
    // Before the triangulation is 3D: the held points and an affinely independent subset.
    pub(crate) held_map: HashMap<[u64; 3], VertexId>,
    pub(crate) basis: Vec<VertexId>,
    // Reusable per-insertion buffers.
    pub(crate) cavity: Vec<CellId>,
    pub(crate) stack: Vec<CellId>,
    pub(crate) boundary: Vec<Boundary>,
}

impl Triangulation {
    /// An empty triangulation.
    pub fn new() -> Self {
        Self::default()
    }

    /// 3 once four affinely independent points were inserted, else less (-1 when empty).
    pub fn dimension(&self) -> i32 {
        if self.built {
            3
        } else {
            self.basis.len() as i32 - 1
        }
    }

    /// Heap bytes by structure (allocated capacity, not only what is used): the points, the
    /// cells (4 vertices, 4 neighbours and a mark each), the free-cell list, the vertex ->
    /// cell index, and the per-insertion buffers with the edge map. Measured, for memory
    /// accounting (issue 21); the held points of a triangulation that is not yet 3D are not
    /// counted.
    pub fn memory(&self) -> Vec<(&'static str, usize)> {
        use std::mem::size_of;
        let [cells, free, vertex_cell, edges] = self.tds.heap_bytes();
        vec![
            ("points", self.points.capacity() * size_of::<DVec3>()),
            ("cells", cells),
            ("free cells", free),
            ("vertex to cell", vertex_cell),
            (
                "insertion buffers",
                edges
                    + (self.cavity.capacity() + self.stack.capacity()) * size_of::<CellId>()
                    + self.boundary.capacity() * size_of::<Boundary>()
                    + self.basis.capacity() * size_of::<VertexId>(),
            ),
        ]
    }

    /// Number of finite vertices (distinct points inserted).
    pub fn num_vertices(&self) -> usize {
        self.points.len()
    }

    /// The finite points, indexed by [`VertexId::index`].
    pub fn points(&self) -> &[DVec3] {
        &self.points
    }

    /// The finite vertices, `0..num_vertices()` in id order.
    pub fn vertices(&self) -> impl ExactSizeIterator<Item = VertexId> + use<> {
        (0..self.points.len() as u32).map(VertexId)
    }

    /// Panics if `v` is not a finite vertex.
    pub fn point(&self, v: VertexId) -> DVec3 {
        self.points[v.index()]
    }

    #[inline]
    pub(crate) fn pt(&self, v: VertexId) -> DVec3 {
        self.points[v.index()]
    }

    /// The four vertices of cell `c`, positively oriented for a finite cell (one of them is
    /// [`VertexId::INFINITE`] for an infinite cell).
    pub fn cell_vertices(&self, c: CellId) -> [VertexId; 4] {
        self.tds.cell(c).v
    }

    /// The cell across the facet of `c` opposite its `i`-th vertex.
    pub fn neighbor(&self, c: CellId, i: usize) -> CellId {
        self.tds.cell(c).n[i]
    }

    /// Local index (0..4) of vertex `v` in cell `c`, if present.
    pub fn vertex_index(&self, c: CellId, v: VertexId) -> Option<usize> {
        self.tds.cell(c).v.iter().position(|&w| w == v)
    }

    /// Whether cell `c` has the infinite vertex (it lies outside the convex hull).
    pub fn is_infinite(&self, c: CellId) -> bool {
        self.tds.cell(c).is_infinite()
    }

    /// Whether `c` is a live cell slot.
    pub fn is_cell(&self, c: CellId) -> bool {
        self.tds.is_cell(c)
    }

    /// The same facet seen from the neighbor cell.
    pub fn mirror_facet(&self, f: Facet) -> Facet {
        let n = self.tds.cell(f.cell).n[f.index as usize];
        let j = self.tds.mirror_index(n, f.cell);
        Facet {
            cell: n,
            index: j as u8,
        }
    }

    /// The three vertices of facet `f`, ordered so that the normal `(b - a) x (c - a)` points
    /// OUT of `f.cell` (away from its vertex `f.index`, toward the mirror cell). For the hull
    /// facet of an infinite cell that normal points into the hull.
    pub fn facet_vertices(&self, f: Facet) -> [VertexId; 3] {
        let v = self.tds.cell(f.cell).v;
        FACET[f.index as usize].map(|k| v[k])
    }

    /// Circumcenter of the finite cell `c` (its Voronoi vertex), computed relative to one
    /// vertex, with a double-double fallback for nearly flat cells ([`circumcenter`]).
    /// Panics if `c` is infinite or dead.
    pub fn circumcenter(&self, c: CellId) -> DVec3 {
        let v = self.tds.cell(c).v;
        assert!(
            !v.contains(&VertexId::INFINITE) && v[0] != DEAD,
            "circumcenter of infinite or dead cell {c}"
        );
        let p = v.map(|i| self.points[i.index()]);
        circumcenter(p[0], p[1], p[2], p[3])
    }

    /// The Voronoi dual of facet `f`: `None` if the facet contains the infinite vertex;
    /// `Segment(cc(f.cell), cc(mirror))` if both cells are finite (possibly of zero length);
    /// otherwise a ray from the circumcenter of the finite cell along the outward normal of
    /// the hull facet (not normalized).
    pub fn dual(&self, f: Facet) -> Option<Dual> {
        let cv = self.tds.cell(f.cell).v;
        let inf = cv.iter().position(|&w| w == VertexId::INFINITE);
        match inf {
            Some(k) if k != f.index as usize => None,
            Some(_) => {
                let m = self.mirror_facet(f);
                Some(self.ray(m))
            }
            None => {
                let m = self.mirror_facet(f);
                if self.is_infinite(m.cell) {
                    Some(self.ray(f))
                } else {
                    Some(Dual::Segment(
                        self.circumcenter(f.cell),
                        self.circumcenter(m.cell),
                    ))
                }
            }
        }
    }

    /// Ray dual of the hull facet `f` seen from its finite cell.
    fn ray(&self, f: Facet) -> Dual {
        let [a, b, c] = self.facet_vertices(f).map(|v| self.points[v.index()]);
        Dual::Ray {
            origin: self.circumcenter(f.cell),
            direction: (b - a).cross(c - a),
        }
    }

    /// Live finite cells, in slot order.
    pub fn finite_cells(&self) -> impl Iterator<Item = CellId> + '_ {
        self.tds
            .cells
            .iter()
            .enumerate()
            .filter_map(|(i, c)| (c.v[0] != DEAD && !c.is_infinite()).then_some(CellId(i as u32)))
    }

    /// Every facet not containing the infinite vertex (those with a Voronoi dual), once each,
    /// seen from the cell with the smaller id. Hull facets are included (their dual is a ray).
    pub fn finite_facets(&self) -> impl Iterator<Item = Facet> + '_ {
        self.live_cells().flat_map(move |c| {
            let cell = *self.tds.cell(c);
            (0..4u8).filter_map(move |i| {
                let inf = cell.v.iter().position(|&w| w == VertexId::INFINITE);
                let finite = inf.is_none_or(|k| k == i as usize);
                (finite && c < cell.n[i as usize]).then_some(Facet { cell: c, index: i })
            })
        })
    }

    /// Live cells (finite and infinite), in slot order.
    pub fn live_cells(&self) -> impl Iterator<Item = CellId> + '_ {
        self.tds.live_cells()
    }

    /// Number of live cells without the infinite vertex (tetrahedra of the hull).
    pub fn num_finite_cells(&self) -> usize {
        self.tds.n_finite
    }

    /// Live cells, finite and infinite.
    pub fn num_cells(&self) -> usize {
        self.tds.n_live
    }

    /// A cell incident to `v` ([`VertexId::INFINITE`] allowed), or `None` before the
    /// triangulation is 3D.
    pub fn vertex_cell(&self, v: VertexId) -> Option<CellId> {
        if !self.built {
            return None;
        }
        if v == VertexId::INFINITE {
            return Some(self.tds.infinite_cell);
        }
        let c = *self.tds.vertex_cell.get(v.index())?;
        (c != CellId::NONE).then_some(c)
    }

    /// All cells incident to `v` (finite vertex or [`VertexId::INFINITE`]), in a
    /// deterministic order (breadth-first from [`Triangulation::vertex_cell`]).
    pub fn incident_cells(&self, v: VertexId) -> Vec<CellId> {
        let mut out = Vec::new();
        let Some(c0) = self.vertex_cell(v) else {
            return out;
        };
        // Stars have tens to hundreds of cells: a fast hash (cell ids are not adversarial).
        let mut seen = rustc_hash::FxHashSet::default();
        out.push(c0);
        seen.insert(c0);
        let mut k = 0;
        while k < out.len() {
            let c = out[k];
            k += 1;
            let cell = *self.tds.cell(c);
            for i in 0..4 {
                if cell.v[i] == v {
                    continue;
                }
                let n = cell.n[i];
                if seen.insert(n) {
                    out.push(n);
                }
            }
        }
        out
    }

    /// Facets incident to the finite vertex `v`, each reported once (from the side with the
    /// smaller `(cell, index)`).
    pub fn incident_facets(&self, v: VertexId) -> Vec<Facet> {
        let mut out = Vec::new();
        for c in self.incident_cells(v) {
            let cell = *self.tds.cell(c);
            for i in 0..4 {
                if cell.v[i] == v {
                    continue;
                }
                let f = Facet {
                    cell: c,
                    index: i as u8,
                };
                if f < self.mirror_facet(f) {
                    out.push(f);
                }
            }
        }
        out
    }

    /// Bytes held by the triangulation's vectors (capacities), excluding the small hash map
    /// used before the triangulation is 3D.
    pub fn memory_bytes(&self) -> usize {
        self.memory().iter().map(|m| m.1).sum()
    }

    /// The start of a walk: `hint` if it is a live cell, else the last created cell, else
    /// some infinite cell.
    pub(crate) fn start_cell(&self, hint: Option<CellId>) -> CellId {
        match hint {
            Some(c) if self.tds.is_cell(c) => c,
            _ => {
                if self.tds.is_cell(self.tds.last_cell) {
                    self.tds.last_cell
                } else {
                    self.tds.infinite_cell
                }
            }
        }
    }
}
