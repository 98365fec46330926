//! Voronoi poles (Amenta & Bern, "Surface reconstruction by Voronoi filtering"; used for the
//! d_M estimate of paper section 6.5): the poles of a sample point are the farthest vertex
//! of its Voronoi cell and the farthest one on the other side of the point. For a dense
//! sample of a surface S they lie near the medial axis of S, so the distance to the nearest
//! pole estimates d_M. The section 6.5 lambda-medial axis is made of Voronoi vertices too:
//! [`Triangulation::voronoi_vertices`] gives the vertices of one Voronoi cell.

use glam::DVec3;

use crate::ids::{CellId, VertexId};
use crate::triangulation::Triangulation;

/// A pole: a Voronoi vertex (a circumcenter) and its squared distance to the sample point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pole {
    /// The Voronoi vertex.
    pub point: DVec3,
    /// Its squared distance to the sample point.
    pub distance_squared: f64,
}

/// The (at most two) finite poles of one sample vertex, on the two sides of a reference
/// direction: a given normal, else the outward hull direction for a hull vertex (whose
/// Voronoi cell is unbounded: its pole on that side is at infinity, so `plus` is `None`),
/// else the direction of the farthest Voronoi vertex (then `plus` is that vertex).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct VertexPoles {
    /// The farthest Voronoi vertex on the positive side of the reference direction.
    pub plus: Option<Pole>,
    /// The farthest Voronoi vertex on the negative side.
    pub minus: Option<Pole>,
}

impl Triangulation {
    /// The poles of every finite vertex (indexed by [`VertexId::index`]); `normal(v)` is an
    /// optional reference direction per vertex (outward or inward normal), used to pick the
    /// two poles on opposite sides. See [`poles_from_centers`] (this computes the
    /// circumcenters of [`Triangulation::finite_cells`] first).
    pub fn poles(&self, normal: impl Fn(VertexId) -> Option<DVec3>) -> Vec<VertexPoles> {
        let cells: Vec<CellId> = self.finite_cells().collect();
        let centers: Vec<DVec3> = cells.iter().map(|&c| self.circumcenter(c)).collect();
        poles_from_centers(self, &cells, &centers, normal)
    }

    /// The vertices of the Voronoi cell of the finite vertex `v`: the circumcenters of its
    /// finite incident cells, in [`Triangulation::incident_cells`] order, and whether the
    /// cell is bounded (no incident infinite cell, i.e. `v` is not on the hull).
    pub fn voronoi_vertices(&self, v: VertexId) -> (Vec<DVec3>, bool) {
        let mut bounded = true;
        let mut out = Vec::new();
        for c in self.incident_cells(v) {
            if self.is_infinite(c) {
                bounded = false;
            } else {
                out.push(self.circumcenter(c));
            }
        }
        (out, bounded)
    }
}

/// [`Triangulation::poles`] from precomputed circumcenters: `centers[i]` is the
/// circumcenter of the finite cell `cells[i]`, and `cells` are the finite cells in
/// [`Triangulation::finite_cells`] order (ties between equally far Voronoi vertices go to the
/// first in that order; the hull facets are those of every finite cell). Non-finite
/// circumcenters (flat cells) are skipped.
pub fn poles_from_centers(
    t: &Triangulation,
    cells: &[CellId],
    centers: &[DVec3],
    normal: impl Fn(VertexId) -> Option<DVec3>,
) -> Vec<VertexPoles> {
    poles_of_range(t, cells, centers, normal, 0..t.num_vertices())
}

/// [`poles_from_centers`] for the vertices whose index is in `range` only (`out[i]` is vertex
/// `range.start + i`): each vertex's poles depend on its own cells alone, visited in the same
/// order, so the results are those of [`poles_from_centers`], bit for bit. Lets a caller
/// split the vertices among threads (every call reads all of `cells`, and works on its own
/// vertices).
pub fn poles_of_range(
    t: &Triangulation,
    cells: &[CellId],
    centers: &[DVec3],
    normal: impl Fn(VertexId) -> Option<DVec3>,
    range: std::ops::Range<usize>,
) -> Vec<VertexPoles> {
    assert_eq!(cells.len(), centers.len(), "one circumcenter per cell");
    let nv = t.num_vertices();
    assert!(range.start <= range.end && range.end <= nv, "vertex range");
    let (lo, len) = (range.start, range.len());
    // The local index of a vertex of the range.
    let local = |v: VertexId| v.index().wrapping_sub(lo);
    let point = |v: VertexId| t.point(v);
    // Pass 1: per vertex, its farthest Voronoi vertex.
    let mut far = vec![(0.0f64, DVec3::ZERO); len];
    for (&c, &cc) in cells.iter().zip(centers) {
        if !cc.is_finite() {
            continue;
        }
        for v in t.cell_vertices(c) {
            let i = local(v);
            if i < len {
                let d = (cc - point(v)).length_squared();
                if d > far[i].0 {
                    far[i] = (d, cc);
                }
            }
        }
    }
    // The outward direction of the hull facets at each vertex: the sum of their unit normals,
    // added in the order of (finite cell, local index) as a scan of `cells` would (the
    // facets are found from the infinite cells, without reading four neighbors per cell).
    let mut hull: Vec<(CellId, usize)> = t
        .live_cells()
        .filter(|&c| t.is_infinite(c))
        .filter_map(|c| {
            let k = t
                .cell_vertices(c)
                .iter()
                .position(|&v| v == VertexId::INFINITE)?;
            let f = t.mirror_facet(crate::ids::Facet {
                cell: c,
                index: k as u8,
            });
            let vs = t.cell_vertices(f.cell);
            vs.iter()
                .any(|&v| local(v) < len)
                .then_some((f.cell, f.index as usize))
        })
        .collect();
    hull.sort_unstable_by_key(|&(c, k)| (c.0, k));
    let mut hull_dir = vec![DVec3::ZERO; len];
    for (c, k) in hull {
        let vs = t.cell_vertices(c);
        // Hull facet opposite vs[k]: its outward normal points away from vs[k].
        let n = hull_normal(vs.map(point), k);
        for j in (0..4).filter(|&j| j != k) {
            let w = local(vs[j]);
            if w < len {
                hull_dir[w] += n;
            }
        }
    }
    // The reference direction per vertex, and whether a pole on its positive side is finite.
    let reference: Vec<(DVec3, bool)> = (lo..lo + len)
        .map(|i| {
            let v = VertexId::from_index(i);
            if let Some(n) = normal(v) {
                (n, true)
            } else if hull_dir[i - lo] != DVec3::ZERO {
                (hull_dir[i - lo], false)
            } else {
                (far[i - lo].1 - point(v), true)
            }
        })
        .collect();
    // Pass 2: the farthest Voronoi vertex on each side.
    let mut out = vec![VertexPoles::default(); len];
    for (&c, &cc) in cells.iter().zip(centers) {
        if !cc.is_finite() {
            continue;
        }
        for v in t.cell_vertices(c) {
            let i = local(v);
            if i >= len {
                continue;
            }
            offer(&mut out[i], point(v), cc, reference[i]);
        }
    }
    out
}

/// Pass 2 for one Voronoi vertex `cc` of the sample point `p`: it becomes the pole on its
/// side of the reference direction `dir` (the positive side only if `plus_finite`) when it
/// is farther than the pole kept there (the first of equally far ones stays).
fn offer(out: &mut VertexPoles, p: DVec3, cc: DVec3, (dir, plus_finite): (DVec3, bool)) {
    let d = (cc - p).length_squared();
    let side = (cc - p).dot(dir);
    let slot = if side > 0.0 && plus_finite {
        &mut out.plus
    } else if side < 0.0 {
        &mut out.minus
    } else {
        return;
    };
    if d > slot.map_or(0.0, |s| s.distance_squared) {
        *slot = Some(Pole {
            point: cc,
            distance_squared: d,
        });
    }
}

/// The outward unit normal of the hull facet of the cell with points `pts` opposite
/// `pts[k]` (pointing away from it).
fn hull_normal(pts: [DVec3; 4], k: usize) -> DVec3 {
    let f: Vec<DVec3> = (0..4).filter(|&j| j != k).map(|j| pts[j]).collect();
    let mut n = (f[1] - f[0]).cross(f[2] - f[0]);
    if n.dot(pts[k] - f[0]) > 0.0 {
        n = -n;
    }
    n.normalize_or_zero()
}

/// The poles of the vertices `vs` alone (`out[i]` is `vs[i]`'s), from their own cells:
/// bit for bit those of [`poles_from_centers`] (each vertex's cells are visited in increasing
/// id, the order of [`Triangulation::finite_cells`], their circumcenters computed by
/// [`Triangulation::circumcenter`], and its hull facets summed in (cell, index) order), at a
/// cost proportional to the vertices' stars: for a caller that knows which stars changed.
pub fn poles_of_vertices(
    t: &Triangulation,
    vs: &[VertexId],
    normal: impl Fn(VertexId) -> Option<DVec3>,
) -> Vec<VertexPoles> {
    vs.iter().map(|&v| poles_of_vertex(t, v, &normal)).collect()
}

/// [`poles_of_vertices`] of one vertex.
fn poles_of_vertex(
    t: &Triangulation,
    v: VertexId,
    normal: &impl Fn(VertexId) -> Option<DVec3>,
) -> VertexPoles {
    let mut cells = t.incident_cells(v);
    cells.retain(|&c| !t.is_infinite(c));
    cells.sort_unstable_by_key(|c| c.0);
    let centers: Vec<DVec3> = cells.iter().map(|&c| t.circumcenter(c)).collect();
    let p = t.point(v);
    let mut far = (0.0f64, DVec3::ZERO);
    for &cc in centers.iter().filter(|cc| cc.is_finite()) {
        let d = (cc - p).length_squared();
        if d > far.0 {
            far = (d, cc);
        }
    }
    let mut hull_dir = DVec3::ZERO;
    for &c in &cells {
        let vs = t.cell_vertices(c);
        for k in 0..4 {
            if vs[k] == v || !t.is_infinite(t.neighbor(c, k)) {
                continue;
            }
            hull_dir += hull_normal(vs.map(|w| t.point(w)), k);
        }
    }
    let (dir, plus_finite) = if let Some(n) = normal(v) {
        (n, true)
    } else if hull_dir != DVec3::ZERO {
        (hull_dir, false)
    } else {
        (far.1 - p, true)
    };
    let mut out = VertexPoles::default();
    for &cc in centers.iter().filter(|cc| cc.is_finite()) {
        offer(&mut out, p, cc, (dir, plus_finite));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Points near the unit sphere (a golden-angle spiral, radii slightly varied so that no
    /// five are cospherical) plus its center region empty: the medial axis is the center.
    fn sphere(n: usize) -> Vec<DVec3> {
        let ga = std::f64::consts::PI * (3.0 - 5f64.sqrt());
        (0..n)
            .map(|i| {
                let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
                let r = (1.0 - z * z).sqrt();
                let a = ga * i as f64;
                let s = 1.0 + 1e-3 * ((i * 7919 % 13) as f64 / 13.0);
                DVec3::new(r * a.cos(), r * a.sin(), z) * s
            })
            .collect()
    }

    /// The poles of chosen vertices from their own stars are those of the scan over every
    /// cell, bit for bit, for hull and interior vertices, with and without normals, and
    /// with cospherical points (a grid: ties between equally far Voronoi vertices).
    #[test]
    fn poles_of_some_vertices_are_those_of_all() {
        let mut pts = sphere(300);
        let mut r = geom_like_rng(7);
        pts.extend((0..300).map(|_| DVec3::new(r(), r(), r()) * 0.8 - DVec3::splat(0.4)));
        pts.extend(
            (0..64).map(|i| DVec3::new((i % 4) as f64, (i / 4 % 4) as f64, (i / 16) as f64) * 0.1),
        );
        let mut t = Triangulation::new();
        t.insert_bulk(&pts).unwrap();
        let all: Vec<VertexId> = t.vertices().collect();
        let some: Vec<VertexId> = all.iter().copied().step_by(3).collect();
        for with_normal in [false, true] {
            let normal = |v: VertexId| with_normal.then(|| t.point(v));
            let full = t.poles(normal);
            let part = poles_of_vertices(&t, &some, normal);
            for (v, got) in some.iter().zip(&part) {
                assert_eq!(*got, full[v.index()], "vertex {v:?}");
            }
        }
    }

    /// A small deterministic generator in [0, 1).
    fn geom_like_rng(seed: u64) -> impl FnMut() -> f64 {
        let mut s = seed;
        move || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    #[test]
    fn poles_are_the_farthest_voronoi_vertices_and_near_the_medial_axis() {
        let pts = sphere(400);
        let mut t = Triangulation::new();
        t.insert_bulk(&pts).unwrap();
        let poles = t.poles(|_| None);
        assert_eq!(poles.len(), t.num_vertices());
        for v in t.vertices() {
            let (vor, bounded) = t.voronoi_vertices(v);
            // Every sample is on the hull: its Voronoi cell is unbounded, only the inner
            // pole is finite, and it is the farthest Voronoi vertex (all are inside).
            assert!(!bounded);
            let vp = poles[v.index()];
            assert!(vp.plus.is_none());
            let inner = vp.minus.expect("inner pole");
            let p = t.point(v);
            let farthest = vor
                .iter()
                .filter(|c| c.is_finite())
                .map(|&c| (c - p).length_squared())
                .fold(0.0, f64::max);
            assert_eq!(inner.distance_squared, farthest);
            // The medial axis of a sphere is its center.
            assert!(inner.point.length() < 0.2, "pole {:?}", inner.point);
        }
    }

    #[test]
    fn a_normal_picks_the_sides_and_interior_vertices_have_bounded_cells() {
        let mut pts = sphere(200);
        pts.push(DVec3::new(0.01, 0.02, 0.03));
        let mut t = Triangulation::new();
        let ids = t.insert_bulk(&pts).unwrap();
        let center = ids[200];
        assert!(
            t.voronoi_vertices(center).1,
            "the inner point's cell is bounded"
        );
        let poles = t.poles(|v| Some(t.point(v)));
        // With the outward normal as reference the outer pole is finite for the samples
        // whose Voronoi vertices lie on both sides; the inner one exists for all.
        for &v in &ids[..200] {
            let vp = poles[v.index()];
            let inner = vp.minus.expect("inner pole");
            assert!((inner.point - t.point(v)).dot(t.point(v)) < 0.0);
            if let Some(outer) = vp.plus {
                assert!((outer.point - t.point(v)).dot(t.point(v)) > 0.0);
            }
        }
        let same = poles_from_centers(
            &t,
            &t.finite_cells().collect::<Vec<_>>(),
            &t.finite_cells()
                .map(|c| t.circumcenter(c))
                .collect::<Vec<_>>(),
            |v| Some(t.point(v)),
        );
        assert_eq!(same, poles);
        // Split in vertex ranges, the same poles (the hull vertices' directions included).
        let cells: Vec<CellId> = t.finite_cells().collect();
        let centers: Vec<DVec3> = cells.iter().map(|&c| t.circumcenter(c)).collect();
        let nv = t.num_vertices();
        for parts in [2, 3, 7] {
            let step = nv.div_ceil(parts);
            let split: Vec<VertexPoles> = (0..nv)
                .step_by(step)
                .flat_map(|a| poles_of_range(&t, &cells, &centers, |_| None, a..(a + step).min(nv)))
                .collect();
            assert_eq!(split, t.poles(|_| None), "{parts} ranges");
        }
    }
}
