//! The conflict zone (Bowyer-Watson, for the paper's "insert c into E and update Del(E)",
//! section 6.1): the cells whose circumball contains the point, the conflict test and ONE
//! search, used by every insertion path.
//!
//! The search grows the zone from the cell containing the point over neighbors in conflict
//! and records the zone's boundary facets. It is generic over two choices that do not change
//! *which* cells are found, only the order and the bookkeeping:
//! - how decided cells are remembered: stamps in the cells themselves ([`Stamps`], for the
//!   in-place insertion, which owns the triangulation) or a private hash set ([`Private`],
//!   for read-only searches that may run concurrently on a shared triangulation);
//! - the visiting order: depth-first (the in-place insertion and bulk insertion) or
//!   breadth-first ([`Triangulation::find_cavity`], [`Triangulation::conflict_zone`]). The
//!   order fixes the order of the created cells and so the cell ids; each path keeps the
//!   order it always had, so triangulations (and meshes built on them) do not change.
//!
//! Invariant: the zone is connected and contains the start cell (the located cell is in
//! conflict), so growing over neighbors finds all of it.

use glam::DVec3;

use crate::hash::SeenCells;
use crate::ids::{CellId, Facet, VertexId};
use crate::locate::{Location, Walk};
use crate::predicates::{self, Sign, incircle_facet_perturbed, orient3d};
use crate::semi_static;
use crate::sort::Rng;
use crate::tds::{Boundary, Cell, FACET, boundary_facet, mirror_index};
use crate::triangulation::{Error, Triangulation, check_point};

/// Whether `p` (not a vertex of `c`) is in conflict with the live cell `c` (perturbed): in
/// its circumball, or for an infinite cell strictly beyond its hull facet, or on the facet's
/// plane and in the perturbed circumdisk of the facet. The semi-static in-sphere filter
/// inline, every other case in [`in_conflict_slow`].
#[inline(always)]
pub(crate) fn in_conflict(cells: &[Cell], points: &[DVec3], c: CellId, p: DVec3) -> bool {
    let v = cells[c.index()].v.map(|w| w.0);
    let infinite =
        (v[0] == u32::MAX) | (v[1] == u32::MAX) | (v[2] == u32::MAX) | (v[3] == u32::MAX);
    if !infinite && let Some(inside) = semi_static::insphere_decide(points, v, p) {
        return inside;
    }
    in_conflict_slow(cells, points, c, p)
}

/// [`in_conflict`] in a search that counts, in `misses`, the semi-static filter's
/// consecutive failures: after [`MAX_MISSES`] of them (nearly cospherical input, e.g.
/// points on a sphere, where it almost never decides) the search goes straight to the later
/// stages. Exact either way: only the speed depends on `misses`.
#[inline(always)]
fn in_conflict_counted(
    cells: &[Cell],
    points: &[DVec3],
    c: CellId,
    p: DVec3,
    misses: &mut u32,
) -> bool {
    let v = cells[c.index()].v.map(|w| w.0);
    let infinite =
        (v[0] == u32::MAX) | (v[1] == u32::MAX) | (v[2] == u32::MAX) | (v[3] == u32::MAX);
    if !infinite && *misses < MAX_MISSES {
        if let Some(inside) = semi_static::insphere_decide(points, v, p) {
            *misses = 0;
            return inside;
        }
        *misses += 1;
    }
    in_conflict_slow(cells, points, c, p)
}

/// See [`in_conflict_counted`].
const MAX_MISSES: u32 = 4;

/// [`in_conflict`] for infinite cells and the in-sphere tests the semi-static filter left.
#[inline(never)]
fn in_conflict_slow(cells: &[Cell], points: &[DVec3], c: CellId, p: DVec3) -> bool {
    let cell = &cells[c.index()];
    let v = cell.v;
    let pt = |w: VertexId| points[w.index()];
    if let Some(k) = v.iter().position(|&w| w == VertexId::INFINITE) {
        let f = FACET[k];
        let (a, b, d) = (pt(v[f[0]]), pt(v[f[1]]), pt(v[f[2]]));
        match orient3d(a, b, d, p) {
            Sign::Positive => true,
            Sign::Negative => false,
            Sign::Zero => {
                let m = cell.n[k];
                let mc = &cells[m.index()];
                let j = mirror_index(cells, m, c);
                let mp = mc.v.map(pt);
                incircle_facet_perturbed(&mp, j, p)
            }
        }
    } else {
        // The semi-static filter failed (in `in_conflict`): the later stages directly.
        let (a, b, d, e) = (pt(v[0]), pt(v[1]), pt(v[2]), pt(v[3]));
        match predicates::insphere_undecided(a, b, d, e, p) {
            Sign::Positive => true,
            Sign::Negative => false,
            Sign::Zero => predicates::insphere_tie(&[a, b, d, e], p),
        }
    }
}

/// How a search remembers the cells it has decided.
pub(crate) trait Decided {
    /// The cells searched.
    fn cells(&self) -> &[Cell];
    /// `Some(in_conflict)` if `c` was decided by this search.
    fn get(&self, c: CellId) -> Option<bool>;
    /// Records the decision for `c`.
    fn set(&mut self, c: CellId, inside: bool);
}

/// Decisions stored as stamps in the cells (`inside`: in conflict, `inside + 1`: not), from
/// [`crate::tds::Tds::next_stamp`].
pub(crate) struct Stamps<'a> {
    pub(crate) cells: &'a mut [Cell],
    pub(crate) inside: u32,
}

impl Decided for Stamps<'_> {
    #[inline]
    fn cells(&self) -> &[Cell] {
        self.cells
    }
    #[inline]
    fn get(&self, c: CellId) -> Option<bool> {
        let m = self.cells[c.index()].mark;
        if m == self.inside {
            Some(true)
        } else if m == self.inside + 1 {
            Some(false)
        } else {
            None
        }
    }
    #[inline]
    fn set(&mut self, c: CellId, inside: bool) {
        self.cells[c.index()].mark = self.inside + u32::from(!inside);
    }
}

/// Decisions stored in a private hash set (read-only searches).
pub(crate) struct Private<'a> {
    pub(crate) cells: &'a [Cell],
    pub(crate) seen: &'a mut SeenCells,
}

impl Decided for Private<'_> {
    #[inline]
    fn cells(&self) -> &[Cell] {
        self.cells
    }
    #[inline]
    fn get(&self, c: CellId) -> Option<bool> {
        self.seen.get(c)
    }
    #[inline]
    fn set(&mut self, c: CellId, inside: bool) {
        self.seen.insert(c, inside);
    }
}

/// The conflict-zone search: from `c0` (in conflict with `p`), appends the zone's cells to
/// `zone` (in visiting order, `c0` first) and its boundary facets to `boundary` (in the order
/// they are met; seen from inside, oriented out of the zone). Depth-first with `stack` if
/// `DEPTH_FIRST`, else breadth-first (`stack` unused). The buffers must be empty.
pub(crate) fn search<D: Decided, const DEPTH_FIRST: bool>(
    d: &mut D,
    points: &[DVec3],
    p: DVec3,
    c0: CellId,
    zone: &mut Vec<CellId>,
    stack: &mut Vec<CellId>,
    boundary: &mut Vec<Boundary>,
) {
    d.set(c0, true);
    zone.push(c0);
    if DEPTH_FIRST {
        stack.push(c0);
    }
    let mut k = 0;
    let mut misses = 0;
    loop {
        let c = if DEPTH_FIRST {
            match stack.pop() {
                Some(c) => c,
                None => break,
            }
        } else {
            if k == zone.len() {
                break;
            }
            k += 1;
            zone[k - 1]
        };
        for i in 0..4 {
            let n = d.cells()[c.index()].n[i];
            let inside = match d.get(n) {
                Some(b) => b,
                None => {
                    let b = in_conflict_counted(d.cells(), points, n, p, &mut misses);
                    d.set(n, b);
                    if b {
                        // Its neighbors are read when it is popped: start loading them.
                        for &m in &d.cells()[n.index()].n {
                            prefetch(d.cells(), m);
                        }
                        zone.push(n);
                        if DEPTH_FIRST {
                            stack.push(n);
                        }
                    }
                    b
                }
            };
            if !inside {
                boundary.push(boundary_facet(d.cells(), c, i, n));
            }
        }
    }
}

/// Hints the CPU to load cell `c` into the cache (no effect on results).
#[inline(always)]
#[allow(unsafe_code)]
fn prefetch(cells: &[Cell], c: CellId) {
    #[cfg(all(target_arch = "x86_64", target_feature = "sse"))]
    if let Some(cell) = cells.get(c.index()) {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        // SAFETY: `_mm_prefetch` only requires the SSE feature, statically enabled here (the
        // `cfg` above; it is in the x86_64 baseline). A prefetch is a hint: it never faults
        // and changes no memory, and the pointer is to a live element of `cells` anyway.
        unsafe { _mm_prefetch::<_MM_HINT_T0>(std::ptr::from_ref(cell).cast()) };
    }
}

/// The conflict zone of a point, found by [`Triangulation::find_cavity`] (read-only) and
/// applied by [`Triangulation::insert_cavity`]. Reusable: searches clear it.
#[derive(Clone, Debug, Default)]
pub struct Cavity {
    pub(crate) p: DVec3,
    pub(crate) cells: Vec<CellId>,
    pub(crate) boundary: Vec<Boundary>,
    pub(crate) duplicate: Option<VertexId>,
    seen: SeenCells,
}

impl Cavity {
    /// The point searched for.
    pub fn point(&self) -> DVec3 {
        self.p
    }

    /// The existing vertex equal to the point, if any (then the zone is empty).
    pub fn duplicate(&self) -> Option<VertexId> {
        self.duplicate
    }

    /// The cells in conflict with the point (destroyed by its insertion).
    pub fn cells(&self) -> &[CellId] {
        &self.cells
    }

    /// The cells in conflict and their neighbors across the zone's boundary. A zone stays
    /// valid after other zones were inserted as long as none of its touched cells was
    /// destroyed by them, i.e. its touched cells avoid their [`Cavity::cells`] (sharing an
    /// outside neighbor is fine: see [`Triangulation::insert_cavity`]).
    pub fn touched_cells(&self) -> impl Iterator<Item = CellId> + '_ {
        self.cells
            .iter()
            .copied()
            .chain(self.boundary.iter().map(|b| b.out))
    }

    /// The vertices of the cells that [`Triangulation::insert_cavity`] will create, in the
    /// order of [`crate::Changes::created`] and with the same vertex order as
    /// [`Triangulation::cell_vertices`]; `new` stands for the inserted point's vertex id,
    /// unknown before the insertion (pass a placeholder such as [`VertexId::NONE`]). Lets a
    /// caller compute per-cell data (circumcenters) during the parallel search, while the
    /// boundary's points are in cache.
    ///
    /// ```
    /// use delaunay3::{Cavity, Changes, Triangulation, VertexId};
    /// use glam::DVec3;
    /// let mut t = Triangulation::new();
    /// for p in [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z, DVec3::ONE] {
    ///     t.insert(p).unwrap();
    /// }
    /// let mut cav = Cavity::default();
    /// t.find_cavity(DVec3::splat(0.3), None, 1, &mut cav).unwrap();
    /// let planned: Vec<[VertexId; 4]> = cav.new_cells(VertexId::NONE).collect();
    /// let mut ch = Changes::default();
    /// let delaunay3::Insertion::New(v) = t.insert_cavity(&cav, Some(&mut ch)) else {
    ///     unreachable!()
    /// };
    /// let made: Vec<[VertexId; 4]> = ch.created.iter().map(|&c| t.cell_vertices(c)).collect();
    /// let planned: Vec<[VertexId; 4]> = planned
    ///     .iter()
    ///     .map(|q| q.map(|x| if x == VertexId::NONE { v } else { x }))
    ///     .collect();
    /// assert_eq!(made, planned);
    /// ```
    pub fn new_cells(&self, new: VertexId) -> impl ExactSizeIterator<Item = [VertexId; 4]> + '_ {
        // The star makes one cell per boundary facet, in boundary order.
        self.boundary
            .iter()
            .map(move |b| [b.v[0], b.v[1], b.v[2], new])
    }
}

impl Triangulation {
    /// Whether `p` is in conflict with the live cell `c` (see [`in_conflict`]).
    pub(crate) fn in_conflict(&self, c: CellId, p: DVec3) -> bool {
        in_conflict(&self.tds.cells, &self.points, c, p)
    }

    /// Finds, without changing the triangulation, the conflict zone of `p`: the cells whose
    /// circumsphere contains it (perturbed), from a point location started at `hint` with a
    /// walk randomized by `seed`. Several searches may run at once on a shared triangulation;
    /// [`Triangulation::insert_cavity`] applies one. The triangulation must be 3D.
    ///
    /// Errors: [`Error::InvalidPoint`] for non-finite or out-of-range coordinates.
    pub fn find_cavity(
        &self,
        p: DVec3,
        hint: Option<CellId>,
        seed: u64,
        out: &mut Cavity,
    ) -> Result<(), Error> {
        check_point(p)?;
        assert!(self.built, "find_cavity needs a 3D triangulation");
        out.p = p;
        out.cells.clear();
        out.boundary.clear();
        out.duplicate = None;
        out.seen.clear();
        let mut rng = Rng(seed);
        let c0 = match self.walk(p, self.start_cell(hint), &mut rng) {
            Walk::Vertex(v) => {
                out.duplicate = Some(v);
                return Ok(());
            }
            Walk::Inside(c) | Walk::Outside(c) => c,
        };
        let mut d = Private {
            cells: &self.tds.cells,
            seen: &mut out.seen,
        };
        search::<_, false>(
            &mut d,
            &self.points,
            p,
            c0,
            &mut out.cells,
            &mut Vec::new(),
            &mut out.boundary,
        );
        Ok(())
    }

    /// The conflict zone of `p` without modifying anything: the cells whose (perturbed)
    /// circumsphere contains `p` and the boundary facets of that cavity (seen from the cells
    /// inside it). Both are empty if `p` is an existing vertex or the triangulation is not
    /// 3D yet. The cells are exactly those an insertion of `p` would destroy.
    pub fn conflict_zone(
        &self,
        p: DVec3,
        hint: Option<CellId>,
    ) -> Result<(Vec<CellId>, Vec<Facet>), Error> {
        let c0 = match self.locate(p, hint)? {
            Location::Cell(c) | Location::Outside(c) => c,
            Location::Vertex(_) | Location::NoCells => return Ok((vec![], vec![])),
        };
        let mut seen = SeenCells::default();
        seen.clear();
        let mut d = Private {
            cells: &self.tds.cells,
            seen: &mut seen,
        };
        let (mut cells, mut boundary) = (Vec::new(), Vec::new());
        search::<_, false>(
            &mut d,
            &self.points,
            p,
            c0,
            &mut cells,
            &mut Vec::new(),
            &mut boundary,
        );
        let facets = boundary
            .iter()
            .map(|b| {
                let c = self.tds.cell(b.out).n[b.j as usize];
                Facet {
                    cell: c,
                    index: self.tds.mirror_index(c, b.out) as u8,
                }
            })
            .collect();
        Ok((cells, facets))
    }
}
