//! Coverage of the voxel scan's crossings (ours, images; the two-sided distance of issue 14).
//!
//! A part of S thinner than the sample spacing (a sheet, a finger, the strip between two
//! pieces of a split component) can meet no Voronoi edge at all: Del_S(E) has no facet there,
//! so neither the refinement of section 6.1 nor the manifold patch sees it. The grid edges of
//! the image do: each edge between nodes of strictly opposite signs holds an exact point of S
//! (the level set is linear along it; marching cubes' vertex,
//! [`verify::level_set::LevelSet::edge_crossings`]). A crossing farther than
//! `tau(x) = h + sigma(x)` from every vertex of Del_S(E) (h the resolution) is a part of S the
//! mesh does not reach; such crossings, thinned to a net of spacing `tau / 2` (shrinking 4x a
//! round), are inserted and the refinement resumes, for at most [`COVER_ROUNDS`] rounds.
//!
//! A crossing still far after [`STAR_FROM`] rounds lies on a part of S that its own point,
//! once inserted, did not bring into Del_S(E): a strand or a bump about a voxel thick, whose
//! piece of S lies inside the Voronoi cell of that point and meets none of its edges. From
//! that round on, the crossings within [`STAR_RADIUS`] voxels of each far crossing are
//! inserted too (its *star*: the strand sampled at the voxel's own scale), so that Voronoi
//! edges cross it. Measured on the image suite (`cargo xtask regress --filter @`, 42 cases):
//! S -> mesh gaps on 15 rows before, on none with the star, the bridged sub-voxel pieces
//! (`bridges`) and the fragment rule (`components`), for 4% more vertices; the star from the
//! first round instead (every far crossing) doubled the vertices on `mni-crop`.
//!
//! Invariant kept: when a round finds no such crossing, every crossing is within its `tau` of
//! a vertex of Del_S(E), hence of the mesh (the S -> mesh bound of the image regress suite).
//! The repair and the component decisions that follow may still change the mesh.

use crate::error::MeshError;
use crate::state::Mesher;
use delaunay3::VertexId;
use glam::DVec3;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;
use rustc_hash::FxHashMap;
use std::time::Instant;

/// Rounds of coverage per run.
pub(crate) const COVER_ROUNDS: usize = 8;

/// The first round (counted from 0) whose far crossings get their star.
const STAR_FROM: usize = 3;

/// Radius of a star, in voxels.
const STAR_RADIUS: f64 = 1.5;

impl Mesher<'_> {
    /// One round of coverage (see the module docs) when the surface is an image and a
    /// resolution is set; returns whether a point was inserted.
    pub(crate) fn cover_crossings(&mut self) -> Result<bool, MeshError> {
        let (Some(h), Some(img)) = (self.opts.resolution, self.s.as_image()) else {
            return Ok(false);
        };
        if self.stats.cover_rounds >= COVER_ROUNDS || self.budget_exceeded() {
            return Ok(false);
        }
        self.resolve_all_lazy()?;
        let t = Instant::now();
        let n = self.tri.num_vertices();
        let mut used = vec![false; n];
        for (_, k, _) in self.restricted.iter() {
            k.iter().for_each(|v| used[v.index()] = true);
        }
        // A node at the iso value is a crossing only where it is on the boundary of the
        // regularized solid (the inside and an outside with volume both reach it: the tip of
        // a sheet that ends on a plateau of ties); a puncture of the inside is none.
        let crossings: &Vec<DVec3> = self
            .scan
            .crossings
            .get_or_insert_with(|| verify::level_set::LevelSet::new(img).edge_crossings());
        let nearest = &mut self.scan.nearest;
        if nearest.len() != crossings.len() {
            *nearest = vec![(u32::MAX, f64::INFINITY); crossings.len()];
        }
        let tau = |p: DVec3| h + self.opts.criteria.sigma_at(p).unwrap_or(h);
        let tri = &self.tri;
        // A crossing within tau of the vertex found nearest to it last time, if that vertex
        // is still on Del_S(E), is covered (vertices do not move, so the squared distance kept
        // with it is still the distance); the others are looked up again among the vertices
        // of Del_S(E). The far set is the same as with every crossing looked up.
        let unsure: Vec<usize> = (0..crossings.len())
            .into_par_iter()
            .filter(|&i| {
                let (v, d2) = nearest[i];
                let t = tau(crossings[i]);
                v == u32::MAX || !used[v as usize] || d2 > t * t
            })
            .collect();
        // The crossings to look up are tested against the vertices of Del_S(E): by a tree when
        // they are many (the first round), by a grid of them when few (the later calls, after
        // a neck round or a manifold pass, need none or a few hundred; a tree of all the
        // vertices took 8-20 ms a call on the MNI T1). The far set is the same either way: a
        // crossing is far when no vertex of Del_S(E) lies within its tau; the vertex kept to
        // check it next time is any within tau (the nearest, or the least id by the grid).
        let far: Vec<(DVec3, f64)> = if unsure.is_empty() {
            Vec::new()
        } else {
            let ids: Vec<u32> = (0..n as u32).filter(|&v| used[v as usize]).collect();
            let point = |v: u32| tri.point(VertexId::from_index(v as usize));
            let taus: Vec<f64> = unsure.iter().map(|&i| tau(crossings[i])).collect();
            let pts: Vec<DVec3> = unsure.iter().map(|&i| crossings[i]).collect();
            let found: Vec<Option<(u32, f64)>> = if unsure.len() * 27 < ids.len() {
                witnesses_near(&pts, &taus, &ids, point)
            } else {
                let coords: Vec<[f64; 3]> = ids.iter().map(|&v| point(v).to_array()).collect();
                match ImmutableKdTree::<f64, 3>::new_from_slice(&coords) {
                    Ok(tree) if !coords.is_empty() => (0..pts.len())
                        .into_par_iter()
                        .map(|k| {
                            let r = tree
                                .query(&pts[k].to_array())
                                .nearest_one::<SquaredEuclidean<f64>>()
                                .execute();
                            let v = ids[r.item as usize];
                            let d2 = point(v).distance_squared(pts[k]);
                            (d2 <= taus[k] * taus[k]).then_some((v, d2))
                        })
                        .collect(),
                    _ => vec![None; pts.len()],
                }
            };
            let mut far = Vec::new();
            for (k, w) in found.into_iter().enumerate() {
                let i = unsure[k];
                nearest[i] = w.unwrap_or((u32::MAX, f64::INFINITY));
                if w.is_none() {
                    far.push((pts[k], taus[k]));
                }
            }
            far
        };
        let shrink = 0.25f64.powi(self.stats.cover_rounds as i32);
        let mut pts = net(&far, shrink);
        if self.stats.cover_rounds >= STAR_FROM {
            // The net's points are left out of the stars: inserted again they would add no
            // point, but the duplicate's walk moves the triangulation's next start, hence
            // the new cells' ids and the refinement's order (measured: other meshes).
            pts.extend(stars(crossings, &far, STAR_RADIUS * h, &pts));
        }
        self.t_oracle += t.elapsed();
        if pts.is_empty() {
            return Ok(false);
        }
        self.stats.cover_rounds += 1;
        let inserted = self.insert_points(pts)?;
        self.stats.cover_insertions += inserted;
        Ok(inserted > 0)
    }
}

/// A net of `far` (points with their tau), in order: a point is kept when no kept point lies
/// within `shrink * tau / 2` of it (a hash grid of cells of the least such radius).
fn net(far: &[(DVec3, f64)], shrink: f64) -> Vec<DVec3> {
    let Some(g) = far
        .iter()
        .map(|x| 0.5 * shrink * x.1)
        .min_by(f64::total_cmp)
    else {
        return Vec::new();
    };
    let cell = |p: DVec3| cell_of(p, g);
    let mut grid: FxHashMap<[i64; 3], Vec<DVec3>> = FxHashMap::default();
    let mut out = Vec::new();
    for &(p, t) in far {
        let r = 0.5 * shrink * t;
        let k = (r / g).ceil() as i64;
        let c = cell(p);
        let near = (-k..=k).any(|dz| {
            (-k..=k).any(|dy| {
                (-k..=k).any(|dx| {
                    grid.get(&[c[0] + dx, c[1] + dy, c[2] + dz])
                        .is_some_and(|v| v.iter().any(|q| q.distance_squared(p) <= r * r))
                })
            })
        });
        if !near {
            grid.entry(c).or_default().push(p);
            out.push(p);
        }
    }
    out
}

/// The stars of the far crossings (module docs): every crossing within `radius` of one of
/// `far`, in the order of `crossings`, each once, those already in `taken` left out.
fn stars(crossings: &[DVec3], far: &[(DVec3, f64)], radius: f64, taken: &[DVec3]) -> Vec<DVec3> {
    if far.is_empty() {
        return Vec::new();
    }
    // Each far crossing in the 27 cells around its own: a crossing looks up its own cell only.
    let cell = |p: DVec3| cell_of(p, radius);
    let grid = spread_grid(far.iter().map(|&(p, _)| (p, p)), radius);
    let near_far = |q: DVec3| {
        grid.get(&cell(q))
            .is_some_and(|v| v.iter().any(|p| p.distance_squared(q) <= radius * radius))
    };
    let taken: rustc_hash::FxHashSet<[u64; 3]> = taken
        .iter()
        .map(|p| p.to_array().map(f64::to_bits))
        .collect();
    crossings
        .par_iter()
        .filter(|&&q| near_far(q) && !taken.contains(&q.to_array().map(f64::to_bits)))
        .copied()
        .collect()
}

/// The cell of side `side` that holds `p`.
pub(super) fn cell_of(p: DVec3, side: f64) -> [i64; 3] {
    (p / side).floor().as_i64vec3().to_array()
}

/// A grid of cells of side `side` in which each item is listed in the 27 cells around the
/// cell of its point, in the items' order: any point within `side` of an item's point finds
/// the item in its own cell.
pub(super) fn spread_grid<T>(
    items: impl Iterator<Item = (DVec3, T)>,
    side: f64,
) -> FxHashMap<[i64; 3], Vec<T>>
where
    T: Copy,
{
    let mut grid: FxHashMap<[i64; 3], Vec<T>> = FxHashMap::default();
    for (p, t) in items {
        let c = cell_of(p, side);
        for dz in -1..=1 {
            for dy in -1..=1 {
                for dx in -1..=1 {
                    grid.entry([c[0] + dx, c[1] + dy, c[2] + dz])
                        .or_default()
                        .push(t);
                }
            }
        }
    }
    grid
}

/// For each point `pts[k]`, a vertex among `ids` within `taus[k]` of it (the least such id)
/// and its squared distance, if any: the points are put in the cells of a grid of side the
/// largest tau, each in the 27 cells around its own, and one pass over the vertices looks
/// each up in its own cell.
fn witnesses_near(
    pts: &[DVec3],
    taus: &[f64],
    ids: &[u32],
    point: impl Fn(u32) -> DVec3 + Sync,
) -> Vec<Option<(u32, f64)>> {
    let side = taus.iter().copied().fold(0.0f64, f64::max);
    if side <= 0.0 || !side.is_finite() {
        return vec![None; pts.len()];
    }
    let cell = |p: DVec3| cell_of(p, side);
    let grid = spread_grid(pts.iter().enumerate().map(|(k, &p)| (p, k as u32)), side);
    let hits: Vec<(u32, u32, f64)> = ids
        .par_iter()
        .flat_map_iter(|&v| {
            let q = point(v);
            grid.get(&cell(q))
                .into_iter()
                .flatten()
                .map(move |&k| (k, v, pts[k as usize].distance_squared(q)))
                .filter(|&(k, _, d2)| d2 <= taus[k as usize] * taus[k as usize])
        })
        .collect();
    let mut out: Vec<Option<(u32, f64)>> = vec![None; pts.len()];
    for (k, v, d2) in hits {
        let o = &mut out[k as usize];
        if o.is_none_or(|(w, _)| v < w) {
            *o = Some((v, d2));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// The grid finds a vertex within tau exactly when one exists, and the least such id:
        /// the far set of the coverage does not depend on how the crossings are looked up.
        #[test]
        fn the_grid_finds_the_least_vertex_within_tau(
            pts in prop::collection::vec((-4.0f64..4.0, -4.0f64..4.0, -4.0f64..4.0, 0.1f64..1.5), 1..40),
            verts in prop::collection::vec((-4.0f64..4.0, -4.0f64..4.0, -4.0f64..4.0), 0..200),
        ) {
            let p: Vec<DVec3> = pts.iter().map(|&(x, y, z, _)| DVec3::new(x, y, z)).collect();
            let taus: Vec<f64> = pts.iter().map(|t| t.3).collect();
            let v: Vec<DVec3> = verts.iter().map(|&(x, y, z)| DVec3::new(x, y, z)).collect();
            // Every other vertex is off Del_S(E): the ids are not 0..n.
            let ids: Vec<u32> = (0..v.len() as u32).filter(|i| i % 2 == 0).collect();
            let got = witnesses_near(&p, &taus, &ids, |i| v[i as usize]);
            for k in 0..p.len() {
                let want = ids
                    .iter()
                    .copied()
                    .find(|&i| v[i as usize].distance_squared(p[k]) <= taus[k] * taus[k])
                    .map(|i| (i, v[i as usize].distance_squared(p[k])));
                prop_assert_eq!(got[k], want);
            }
        }
    }
}
