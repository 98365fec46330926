//! Scaffold points (ours): an acceleration of section 6.1's refinement that leaves its
//! output unchanged.
//!
//! The 3D Delaunay triangulation of a sample of a surface with tunnels or thin parts (a
//! torus, the tanglecube) is full of long cells joining opposite sides of the solid, whose
//! large circumballs put ~35 cells in the conflict zone of every refinement point. A few
//! points inside the solid, far from S (the *scaffold*), cut those cells up: on the catalog
//! torus at sigma = 0.0194 the refinement takes about 40% fewer cycles on one thread.
//!
//! Scaffold points are vertices of Del(E) but not samples, and never appear in the output:
//! - a restricted facet with a scaffold vertex is always bad (`Mesher::known_badness`), so
//!   the refinement keeps inserting surface points until no Voronoi edge of a scaffold point
//!   meets S (it terminates: such a facet's ball has radius at least the scaffold point's
//!   distance to S, which is positive);
//! - at the end, `Scaffold::is_clear` checks that every Voronoi vertex of every scaffold
//!   point (the circumcenters of its cells, whose values are known) is on the scaffold point's
//!   side of S. If that holds, S does not enter a scaffold point's Voronoi cell through its
//!   vertices or edges, and Del_S(E) is the restricted Delaunay triangulation of the samples
//!   alone. If it fails, the triangulation is rebuilt from the samples alone and the
//!   refinement resumes (`Mesher::drop_scaffold`): the paper's algorithm, unaccelerated.
//!
//! The points: nodes of a grid over a box around the initial sample, inside S (value < 0), on
//! the ridges of the half-width of the largest all-inside block of nodes around them (a
//! discrete medial axis of the solid), where that block is at least twice sigma wide (so that
//! the scaffold stays clear of the final sample's balls and adds no refinement of its own),
//! thinned to about their distance to S apart. Outside points were measured to slow the torus
//! and the image down, not up.

use crate::criteria::Criteria;
use crate::restricted::Restricted;
use crate::voronoi::Voronoi;
use delaunay3::{Insertion, Triangulation, VertexId};
use glam::DVec3;
use oracle::Surface;
use rayon::prelude::*;
use std::time::{Duration, Instant};

/// The scaffold points among the vertices of Del(E).
///
/// Invariant: `count` is the number of nonzero entries of `sign`.
#[derive(Default)]
pub(crate) struct Scaffold {
    /// By vertex id: 0 for a sample, else the sign of the surface's value at a scaffold point.
    sign: Vec<i8>,
    /// Scaffold vertices currently in Del(E).
    count: usize,
}

impl Scaffold {
    /// Scaffold vertices in Del(E).
    #[inline]
    pub fn count(&self) -> usize {
        self.count
    }

    /// Whether vertex `v` is a scaffold point.
    #[inline]
    pub fn contains(&self, v: VertexId) -> bool {
        self.sign.get(v.index()).is_some_and(|&s| s != 0)
    }

    /// Forget the scaffold (the triangulation was rebuilt without it).
    pub fn clear(&mut self) {
        self.sign.clear();
        self.count = 0;
    }

    /// Insert the scaffold points of `s` for `criteria` into `tri` and record their signs.
    /// `extent`: a box around the initial sample (the grid's domain). Returns the time spent
    /// inserting.
    pub fn insert(
        &mut self,
        s: &dyn Surface,
        criteria: &Criteria,
        extent: (DVec3, DVec3),
        tri: &mut Triangulation,
    ) -> Result<Duration, delaunay3::Error> {
        let pts = scaffold_points(s, criteria, Some(extent));
        let t = Instant::now();
        for p in pts {
            let sign = if s.value(p) < 0.0 { -1 } else { 1 };
            if let Insertion::New(v) = tri.insert(p)? {
                let v = v.index();
                if self.sign.len() <= v {
                    self.sign.resize(v + 1, 0);
                }
                self.sign[v] = sign;
                self.count += 1;
            }
        }
        Ok(t.elapsed())
    }

    /// The final check (see the module docs): no restricted facet has a scaffold vertex, and
    /// every Voronoi vertex of a scaffold point (the circumcenters of its cells, whose values
    /// are cached) is on its side of S.
    pub fn is_clear(&self, restricted: &Restricted, tri: &Triangulation, vor: &Voronoi) -> bool {
        (0..self.sign.len()).all(|v| {
            let sign = self.sign[v];
            if sign == 0 {
                return true;
            }
            if restricted.facets_at(VertexId::from_index(v)) != 0 {
                return false;
            }
            tri.incident_cells(VertexId::from_index(v))
                .iter()
                .all(|&c| {
                    let f = vor.value_or_nan(c);
                    if sign < 0 { f < 0.0 } else { f > 0.0 }
                })
        })
    }
}

/// Grid nodes per axis over the grid's cube (see `scaffold_points`).
pub(crate) const GRID: usize = 32;
/// Largest block half-width (in grid steps) measured around a node.
const MAX_BLOCK: usize = 8;

/// Scaffold points of `s` for the size bound of `criteria` (see the module docs), in a deterministic order:
/// on a `GRID` grid, or a finer one when that finds fewer than `FEW` points (thin solids).
/// The grid covers `extent` (a box around the initial sample, enlarged by 10%), or the
/// bounding ball's cube.
pub(crate) fn scaffold_points(
    s: &dyn Surface,
    criteria: &Criteria,
    extent: Option<(DVec3, DVec3)>,
) -> Vec<DVec3> {
    let ball = s.bounding_sphere();
    let (center, half) = match extent {
        Some((lo, hi)) if (lo.is_finite() && hi.is_finite() && hi.cmpge(lo).all()) => {
            let half = (0.55 * (hi - lo).max_element()).min(ball.radius);
            (0.5 * (lo + hi), half)
        }
        _ => (ball.center, ball.radius),
    };
    if half.is_nan() || half <= 0.0 {
        return Vec::new();
    }
    let pts = scaffold_on_grid(s, criteria, center, half, GRID);
    if pts.len() >= FEW {
        return pts;
    }
    scaffold_on_grid(s, criteria, center, half, FINE_GRID)
}

/// Finer grid of `scaffold_points`.
const FINE_GRID: usize = 48;
/// Fewer scaffold points than this on the `GRID` grid: try the `FINE_GRID` one.
const FEW: usize = 16;

/// `n`^3 nodes over the cube of center `center` and half-side `half`.
fn scaffold_on_grid(
    s: &dyn Surface,
    criteria: &Criteria,
    center: DVec3,
    half: f64,
    n: usize,
) -> Vec<DVec3> {
    let g = 2.0 * half / (n - 1) as f64;
    let lo = center - DVec3::splat(half);
    let node = |i: usize, j: usize, k: usize| lo + DVec3::new(i as f64, j as f64, k as f64) * g;
    // Inside nodes (value < 0); NaN and 0 count as not inside.
    let inside: Vec<bool> = (0..n * n * n)
        .into_par_iter()
        .map(|p| s.value(node(p % n, (p / n) % n, p / (n * n))) < 0.0)
        .collect();
    // Prefix sums of the inside nodes, for block counts in O(1).
    let m = n + 1;
    let at = |i: usize, j: usize, k: usize| i + m * (j + m * k);
    let mut sum = vec![0u32; m * m * m];
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let v = u32::from(inside[i + n * (j + n * k)]);
                sum[at(i + 1, j + 1, k + 1)] = v
                    + sum[at(i, j + 1, k + 1)]
                    + sum[at(i + 1, j, k + 1)]
                    + sum[at(i + 1, j + 1, k)]
                    - sum[at(i, j, k + 1)]
                    - sum[at(i, j + 1, k)]
                    - sum[at(i + 1, j, k)]
                    + sum[at(i, j, k)];
            }
        }
    }
    // Inside nodes with a <= index < b on every axis.
    let block = |a: [usize; 3], b: [usize; 3]| -> u32 {
        let (x0, y0, z0, x1, y1, z1) = (a[0], a[1], a[2], b[0], b[1], b[2]);
        sum[at(x1, y1, z1)] + sum[at(x0, y0, z1)] + sum[at(x0, y1, z0)] + sum[at(x1, y0, z0)]
            - sum[at(x0, y1, z1)]
            - sum[at(x1, y0, z1)]
            - sum[at(x1, y1, z0)]
            - sum[at(x0, y0, z0)]
    };
    // Half-width of the largest all-inside block around each inside node (0: none).
    let width: Vec<u8> = (0..n * n * n)
        .into_par_iter()
        .map(|p| {
            let (i, j, k) = (p % n, (p / n) % n, p / (n * n));
            if !inside[p] {
                return 0;
            }
            let mut w = 0;
            for r in 1..=MAX_BLOCK {
                if i < r || j < r || k < r || i + r >= n || j + r >= n || k + r >= n {
                    break;
                }
                let full = (2 * r + 1).pow(3) as u32;
                if block([i - r, j - r, k - r], [i + r + 1, j + r + 1, k + r + 1]) != full {
                    break;
                }
                w = r;
            }
            w as u8
        })
        .collect();
    // Keep the ridges of the width (a discrete medial axis of the inside), where the block is
    // at least twice sigma wide.
    let mut out: Vec<(usize, DVec3)> = Vec::new();
    for k in 1..n - 1 {
        for j in 1..n - 1 {
            for i in 1..n - 1 {
                let p = i + n * (j + n * k);
                let w = width[p] as usize;
                if w == 0 {
                    continue;
                }
                let q = node(i, j, k);
                let sigma = criteria.sigma_at(q).unwrap_or(0.0);
                if !(sigma.is_finite() && sigma >= 0.0) || (w as f64) * g < 2.0 * sigma {
                    continue;
                }
                let ridge = [1, n, n * n]
                    .iter()
                    .all(|&o| width[p - o] as usize <= w && width[p + o] as usize <= w);
                if ridge {
                    out.push((w, q));
                }
            }
        }
    }
    // Thin the ridge to points about `SPACING` x (their block half-width + 1), i.e. about their
    // distance to S, apart, widest first (ridges of a grid are thick and broken, and more
    // points than that slow the refinement down again).
    out.sort_by_key(|&(w, _)| std::cmp::Reverse(w)); // stable: grid order among equals
    let mut kept: Vec<DVec3> = Vec::new();
    for (w, q) in out {
        let r = SPACING * (w + 1) as f64 * g;
        if kept.iter().all(|p| p.distance_squared(q) >= r * r) {
            kept.push(q);
        }
    }
    kept
}

/// Spacing of the kept scaffold points, in multiples of their block half-width + 1.
const SPACING: f64 = 1.0;

#[cfg(test)]
mod tests {
    use super::*;
    use oracle::BoundingSphere;

    struct Shell;
    impl Surface for Shell {
        fn bounding_sphere(&self) -> BoundingSphere {
            BoundingSphere {
                center: DVec3::ZERO,
                radius: 2.0,
            }
        }
        fn value(&self, p: DVec3) -> f64 {
            // A thick spherical shell 0.5 < |p| < 1.5 (negative inside the shell).
            (p.length() - 1.0).abs() - 0.5
        }
    }

    #[test]
    fn scaffold_points_are_inside_and_clear_of_the_surface() {
        let s = Shell;
        let g = 4.0 / (GRID - 1) as f64;
        for sigma in [0.01, 0.05, 0.1] {
            let pts = scaffold_points(&s, &Criteria::uniform(sigma), None);
            assert!(!pts.is_empty(), "sigma {sigma}");
            for p in &pts {
                // Inside the wall 0.5 < |p| < 1.5, at least a grid step and 2 sigma from S.
                assert!(s.value(*p) < 0.0);
                let d = (p.length() - 0.5).abs().min((p.length() - 1.5).abs());
                assert!(
                    d >= g && d >= 2.0 * sigma - 1e-12,
                    "{p} at {d} from S, sigma {sigma}"
                );
            }
        }
        // A wall too thin for the size: no scaffold.
        assert!(scaffold_points(&s, &Criteria::uniform(0.6), None).is_empty());
    }
}
