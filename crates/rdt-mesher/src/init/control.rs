//! Control points and rays (section 6.4.3): the control points E'_i (the oracle's seeds, at
//! least one per component) start the sample; after the queue empties, a random ray and its
//! opposite are shot from every control point that is not yet a vertex of Del_S(E), and their
//! first crossings of S are inserted, until every control point is a vertex (lemma 6.6).

use crate::error::MeshError;
use crate::options::{Initialization, MeshOptions};
use crate::state::Mesher;
use delaunay3::Insertion;
use glam::DVec3;
use oracle::Surface;
use std::time::Instant;

/// Rounds of random rays (section 6.4.3) per control point before it is reported missing.
const MAX_RAY_ROUNDS: u32 = 16;

/// Control points: the oracle's seeds (or the user's), thinned by farthest-point selection.
pub(crate) fn control_points(s: &dyn Surface, opts: &MeshOptions) -> Vec<DVec3> {
    let mut pts = match &opts.control_points {
        Some(p) => p.clone(),
        None => s.seed_points(opts.seed),
    };
    pts.retain(|p| p.is_finite());
    let pts = merge_coincident(pts, s.tolerance());
    let k = opts.max_control_points.max(4);
    if pts.len() <= k {
        return pts;
    }
    // Farthest-point selection, deterministic (starts from the first point, ties to the
    // lowest index).
    geom::farthest::farthest_points(&[], &pts, k, None)
        .into_iter()
        .map(|i| pts[i])
        .collect()
}

/// The points, each one within `tol` of an earlier point (and not equal to it) replaced by
/// that point: an exact copy, which the triangulation inserts once (`Insertion::Duplicate`).
/// The list keeps its length and order, so the farthest-point thinning and the meshes of
/// inputs without such pairs are unchanged.
///
/// Invariant kept: no two distinct control points are closer than the oracle's precision. Two
/// seeds of one point of S found by two routes (a label's voxel-scan crossing at a grid edge's
/// midpoint, (4, 344, 600), and a random line's crossing 9e-16 from it, on the connectomics
/// review's Voronoi label 214626287) are distinct to the exact predicates: both became
/// vertices, every restricted facet on their edge was a sliver, and the refinement ran away
/// there (1,638 vertices within 1 nm of it, 64 within 1e-12 nm; minimum angle 0.4 degrees,
/// `short-edges` FAIL; 14,785 vertices, 12,911 without the cluster). The refinement's own
/// points are kept apart by the unsound-centre test; the seeds were not.
pub(crate) fn merge_coincident(mut pts: Vec<DVec3>, tol: f64) -> Vec<DVec3> {
    use std::collections::HashMap;
    if !(tol > 0.0 && tol.is_finite()) {
        return pts;
    }
    let cell = |p: DVec3| (p / tol).floor().as_i64vec3();
    let mut grid: HashMap<glam::I64Vec3, Vec<DVec3>> = HashMap::new();
    for p in &mut pts {
        let c = cell(*p);
        let mut near = None;
        'cells: for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let key = c + glam::I64Vec3::new(dx, dy, dz);
                    if let Some(q) = grid
                        .get(&key)
                        .and_then(|v| v.iter().copied().find(|q| q.distance(*p) <= tol))
                    {
                        near = Some(q);
                        break 'cells;
                    }
                }
            }
        }
        match near {
            Some(q) => *p = q,
            None => grid.entry(c).or_default().push(*p),
        }
    }
    pts
}

impl Mesher<'_> {
    /// The initial sample (control points or persistent facets, the given points, and a few
    /// random-line seeds if needed for a 3D triangulation), the scaffold, and a full scan of
    /// Del(E).
    pub(crate) fn initialize(&mut self) -> Result<(), MeshError> {
        let mut control = control_points(self.s, self.opts);
        let persistent = self.opts.initialization == Initialization::PersistentFacets;
        if persistent {
            // E_i replaces E'_i; the control-point loop is not used (lemma 6.1 instead).
            control = super::persistent_facet_points(self.s, &control, self.opts)?;
        }
        let mut pts: Vec<DVec3> = control.clone();
        pts.extend(self.opts.initial_points.iter().copied());
        if pts.is_empty() {
            return Err(MeshError::NoSeeds {
                center: self.ball.center,
                radius: self.ball.radius,
            });
        }
        // Too few points for a 3D triangulation: add crossings of more random lines.
        let mut extra_seed = self.opts.seed;
        let mut tries = 0;
        while pts.len() < 8 && tries < 8 {
            extra_seed = extra_seed.wrapping_add(0x9E37);
            pts.extend(oracle::roots::random_line_seeds(self.s, 64, extra_seed));
            tries += 1;
        }
        let t = Instant::now();
        let mut ids = Vec::with_capacity(pts.len());
        for p in &pts {
            ids.push(match self.tri_mut().insert(*p)? {
                Insertion::New(v) | Insertion::Duplicate(v) => v,
            });
        }
        self.t_delaunay += t.elapsed();
        if self.tri.dimension() < 3 {
            return Err(MeshError::DegenerateSeeds(pts.len()));
        }
        let vertices = &mut self.control.vertices;
        *vertices = if persistent {
            Vec::new()
        } else {
            ids[..control.len()].to_vec()
        };
        vertices.sort_unstable();
        vertices.dedup();
        self.stats.control_points = vertices.len();
        if self.opts.scaffold {
            let lo = pts.iter().fold(DVec3::INFINITY, |a, &p| a.min(p));
            let hi = pts.iter().fold(DVec3::NEG_INFINITY, |a, &p| a.max(p));
            let tri = crate::state::unique(&mut self.tri);
            self.t_delaunay += self
                .scaffold
                .insert(self.s, &self.opts.criteria, (lo, hi), tri)?;
            self.stats.scaffold_points = self.scaffold.count();
        }
        self.ensure_vertex_slots();
        self.full_scan()
    }

    /// For each control point not on Del_S(E), insert the first crossings of a random ray and
    /// of its opposite. Returns whether anything was inserted.
    pub(crate) fn shoot_control_rays(&mut self) -> Result<bool, MeshError> {
        let mut any = false;
        let control = self.control.vertices.clone();
        if self.control.ray_attempts.len() < control.len() {
            self.control.ray_attempts.resize(control.len(), 0);
        }
        for (k, v) in control.into_iter().enumerate() {
            if self.restricted.facets_at(v) > 0 {
                continue;
            }
            // Lemma 6.6 needs a smooth surface; near a singular point a control point may
            // never become a vertex and the rays would insert points without end: give up
            // after a few rounds and report the control point as missing.
            if self.control.ray_attempts[k] >= MAX_RAY_ROUNDS {
                continue;
            }
            self.control.ray_attempts[k] += 1;
            if self.budget_exceeded() {
                return Ok(false);
            }
            let x = self.tri.point(v);
            let dir = self.control.rng.unit_vector();
            for d in [dir, -dir] {
                let start = x + d * (100.0 * self.s.tolerance());
                let Some((a, b)) = self.ball.clip_ray(start, d) else {
                    continue;
                };
                let mut buf = Vec::new();
                let t = Instant::now();
                self.crossing_calls += 1;
                self.s.crossings(a, b, &mut buf);
                self.t_oracle += t.elapsed();
                if let Some(&c) = buf.first()
                    && self.insert(c, None)?
                {
                    self.stats.ray_insertions += 1;
                    any = true;
                }
            }
        }
        Ok(any)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_closer_than_the_precision_become_the_earlier_one() {
        let a = DVec3::new(4.0, 344.0, 600.0);
        let b = DVec3::new(3.999999999999999, 344.0, 600.0);
        let c = DVec3::new(4.0 + 2e-5, 344.0, 600.0);
        let pts = merge_coincident(vec![a, c, b, a, c + DVec3::splat(1e-6)], 1e-5);
        // The list keeps its length and order; b and the copy of a become a, the point
        // 1.7e-6 from c becomes c; c itself (2e-5 away) stays.
        assert_eq!(pts, vec![a, c, a, a, c]);
        // No precision: unchanged.
        assert_eq!(merge_coincident(vec![a, b], 0.0), vec![a, b]);
    }
}
