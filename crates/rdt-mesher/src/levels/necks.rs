//! Neck reseeding (ours), on images: a neck of the trilinear level set thinner than the
//! sample spacing meets no Voronoi edge, so Del_S(E) meshes the two sides as separate closed
//! pieces and the manifold patch sees nothing wrong. The voxel scan knows better: each piece
//! of Del_S(E) lies on one scan component, and a component with several pieces has a join of
//! the scan (two inside nodes joined by a grid edge, or by a face's saddle; for the wall of a
//! cavity, two nodes of the cavity too) between nodes nearest to different pieces. Around each such join a ring of points of S is inserted
//! (the first crossings of rays perpendicular to it, from points of the inside region on it:
//! the neck's wall, at the neck's own scale); the refinement of section 6.1 then resumes and
//! meshes the neck with the usual criteria (the rings' facets are small and skinny, their
//! surface Delaunay ball centres lie on the neck). The converse, a *bridge*: a restricted
//! facet whose vertices lie on different scan components (two components closer than the
//! sample spacing, e.g. a one-voxel speck beside a larger surface) is queued as the manifold
//! patch queues its facets (forced, down to the same floor), so that the refinement separates
//! them. At most [`NECK_ROUNDS`] rounds of each (6: on the image regress cases 3 left 1 to 4
//! more split pieces per case, 6 up to 2% more vertices); a bridge still there after them is
//! separated by the topological repair (`repair`, rule 0), and a component still split is
//! decided and reported by `components`.

use crate::error::MeshError;
use crate::state::Mesher;
use crate::topology::VertexUnion;
use glam::DVec3;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use oracle::Surface;
use oracle::image::{ImageSurface, Join, Node};
use rayon::prelude::*;
use rustc_hash::{FxHashMap, FxHashSet};
use std::cmp::Ordering;
use std::collections::BTreeMap;
use std::time::Instant;

/// Rounds of neck reseeding per run (and as many rounds of bridges).
pub(crate) const NECK_ROUNDS: u32 = 6;

/// A join and, for each of its nodes, the nearest piece and the distance to it.
type NearJoin = (Join, (usize, f64), (usize, f64));

/// Rays per ring.
const RING_RAYS: usize = 8;

/// The pieces of Del_S(E) that lie on one scan component: per piece, its vertices' points,
/// largest piece first.
type Split = Vec<Vec<DVec3>>;

impl Mesher<'_> {
    /// One round of neck reseeding (see the module docs) when the surface is an image and a
    /// resolution is set; returns whether a point was inserted or a bridge facet queued.
    pub(crate) fn reseed_necks(&mut self) -> Result<bool, MeshError> {
        let (Some(_), Some(img)) = (self.opts.resolution, self.s.as_image()) else {
            return Ok(false);
        };
        let rounds = NECK_ROUNDS as usize;
        if (self.stats.neck_rounds >= rounds && self.stats.bridge_rounds >= rounds)
            || self.budget_exceeded()
        {
            return Ok(false);
        }
        self.resolve_all_lazy()?;
        let t = Instant::now();
        let labels = self.vertex_labels(img);
        let splits = if self.stats.neck_rounds < rounds {
            self.split_components(&labels)
        } else {
            Default::default()
        };
        // Bridges once the pieces are joined (a neck's new facets may still carry mixed
        // labels while it is being meshed).
        let bridges = if splits.is_empty() && self.stats.bridge_rounds < rounds {
            self.push_bridges(&labels)
        } else {
            0
        };
        if splits.is_empty() && bridges == 0 {
            self.t_oracle += t.elapsed();
            return Ok(false);
        }
        if splits.is_empty() {
            self.stats.bridge_rounds += 1;
        } else {
            self.stats.neck_rounds += 1;
        }
        let mut pts: Vec<DVec3> = Vec::new();
        for (label, pieces) in splits {
            // The rings are a function of the pieces and the margin: when both are those of
            // the last round that looked at this component, its rings are in E already (each
            // would be a duplicate insertion), so they are not looked for again.
            let margin = margin_level(self.stats.neck_rounds);
            let last = self.scan.rings_seen.get(&label);
            if last.is_some_and(|(m, p)| *m == margin && *p == pieces) {
                continue;
            }
            pts.extend(ring_points(img, label, &pieces, self.stats.neck_rounds));
            self.scan.rings_seen.insert(label, (margin, pieces));
        }
        self.t_oracle += t.elapsed();
        let inserted = self.insert_points(pts)?;
        self.stats.neck_insertions += inserted;
        Ok(bridges > 0 || inserted > 0)
    }

    /// Queue (forced, as the manifold patch does) the restricted facets whose vertices lie on
    /// different scan components, down to the manifold floor: a bridge between two
    /// components closer than the sample spacing. Returns how many were queued.
    fn push_bridges(&mut self, labels: &[Option<usize>]) -> usize {
        let mut keys = Vec::new();
        for (idx, k, rf) in self.restricted.iter() {
            let l = k.map(|v| labels[v.index()]);
            let mixed = l.iter().all(Option::is_some) && (l[0] != l[1] || l[1] != l[2]);
            if mixed && rf.radius >= self.manifold_floor(rf.center) {
                keys.push((idx, *rf));
            }
        }
        let n = self.push_forced(keys);
        self.stats.bridge_facets += n;
        n
    }

    /// The scan component of every vertex of a restricted facet (`None` for the others and
    /// where the scan gives none). Each vertex's is computed once, in parallel (each
    /// independently: the result does not depend on the thread count), and kept in
    /// [`crate::levels::ScanCache::labels`].
    pub(super) fn vertex_labels(&mut self, img: &ImageSurface) -> Vec<Option<usize>> {
        let n = self.tri.num_vertices();
        let mut used = vec![false; n];
        for (_, k, _) in self.restricted.iter() {
            k.iter().for_each(|v| used[v.index()] = true);
        }
        let cache = &mut self.scan.labels;
        cache.resize(n, None);
        let todo: Vec<usize> = (0..n).filter(|&v| used[v] && cache[v].is_none()).collect();
        let tri = &self.tri;
        let found: Vec<Option<usize>> = todo
            .par_iter()
            .map(|&v| img.component_of(tri.point(delaunay3::VertexId::from_index(v))))
            .collect();
        for (v, l) in todo.into_iter().zip(found) {
            cache[v] = Some(l);
        }
        (0..n)
            .map(|v| if used[v] { cache[v].flatten() } else { None })
            .collect()
    }

    /// The scan components on which Del_S(E) has several pieces (each piece goes to the
    /// component most of its vertices are labelled with), in component order.
    fn split_components(&self, labels: &[Option<usize>]) -> Vec<(usize, Split)> {
        let n = self.tri.num_vertices();
        let mut union = VertexUnion::new(n);
        let mut used = vec![false; n];
        for (_, k, _) in self.restricted.iter() {
            let t = k.map(delaunay3::VertexId::to_u32);
            union.join_triangle(t);
            t.iter().for_each(|&v| used[v as usize] = true);
        }
        // Per piece (root): its vertices and the votes for each label.
        let mut pieces: BTreeMap<u32, (Vec<DVec3>, BTreeMap<usize, usize>)> = BTreeMap::new();
        for v in (0..n).filter(|&v| used[v]) {
            let p = self.tri.point(delaunay3::VertexId::from_index(v));
            let e = pieces.entry(union.find(v as u32)).or_default();
            e.0.push(p);
            if let Some(l) = labels[v] {
                *e.1.entry(l).or_default() += 1;
            }
        }
        let mut by_label: BTreeMap<usize, Split> = BTreeMap::new();
        for (_, (pts, votes)) in pieces {
            let best = votes
                .iter()
                .max_by_key(|(l, c)| (**c, std::cmp::Reverse(**l)));
            if let Some((&l, _)) = best {
                by_label.entry(l).or_default().push(pts);
            }
        }
        by_label
            .into_iter()
            .filter(|(_, p)| p.len() > 1)
            .map(|(l, mut p)| {
                super::components::sort_largest_first(&mut p, |&x| x, |x| x.to_array());
                (l, p)
            })
            .collect()
    }
}

/// The rings around the joins of component `label` near its pieces but the largest whose
/// nodes are nearest to different pieces. The joins are looked for in a box around each piece
/// but the largest, whose margin doubles with each round (from 1.5 voxels, up to 12: a larger
/// box made `mni_t1_half` at 4 voxels take twice the time for the same mesh): the join between
/// two pieces lies where the nearest piece changes along the component, which can be farther
/// from the small piece than the first margin (a strip of a sheet thinner than a voxel between
/// two pieces: with the fixed margin such a round inserted nothing).
fn ring_points(img: &ImageSurface, label: usize, pieces: &Split, round: usize) -> Vec<DVec3> {
    let mut coords: Vec<[f64; 3]> = Vec::new();
    let mut owner: Vec<usize> = Vec::new();
    for (i, p) in pieces.iter().enumerate() {
        coords.extend(p.iter().map(|q| q.to_array()));
        owner.extend(std::iter::repeat_n(i, p.len()));
    }
    let Ok(tree) = ImmutableKdTree::<f64, 3>::new_from_slice(&coords) else {
        return Vec::new();
    };
    let margin =
        1.5 * img.volume().spacing().max_element() * f64::from(1u32 << margin_level(round));
    // The boxes around the pieces but the largest.
    let boxes: Vec<(DVec3, DVec3)> = pieces[1..]
        .iter()
        .map(|piece| {
            let lo = piece.iter().fold(DVec3::INFINITY, |a, &p| a.min(p)) - DVec3::splat(margin);
            let hi =
                piece.iter().fold(DVec3::NEG_INFINITY, |a, &p| a.max(p)) + DVec3::splat(margin);
            (lo, hi)
        })
        .collect();
    // The piece of the vertex nearest each node that a join in a box can have, and the
    // distance to it: each node's once (nodes are shared by boxes and by up to 18 joins), in
    // parallel (each independently).
    let mut nodes: Vec<Node> = boxes
        .par_iter()
        .flat_map_iter(|&(lo, hi)| img.neck_nodes(label, lo, hi))
        .collect();
    nodes.sort_unstable_by_key(|n| n.index);
    nodes.dedup_by_key(|n| n.index);
    let near: FxHashMap<usize, (usize, f64)> = nodes
        .par_iter()
        .map(|n| {
            let r = tree
                .query(&n.at.to_array())
                .nearest_one::<SquaredEuclidean<f64>>()
                .execute();
            (n.index, (owner[r.item as usize], r.distance.sqrt()))
        })
        .collect();
    // The joins in the boxes (each box's in parallel, in piece order) whose nodes are nearest
    // to different pieces, without repeats (equal nodes: the same join).
    let found: Vec<Vec<NearJoin>> = boxes
        .par_iter()
        .map(|&(lo, hi)| {
            img.neck_joins_where(label, lo, hi, &mut |a, b| {
                near[&a.index].0 != near[&b.index].0
            })
            .into_iter()
            .map(|j| (j, near[&j.nodes[0]], near[&j.nodes[1]]))
            .collect()
        })
        .collect();
    let mut seen: FxHashSet<[usize; 2]> = FxHashSet::default();
    let joins: Vec<NearJoin> = found
        .into_iter()
        .flatten()
        .filter(|(j, _, _)| seen.insert(j.nodes))
        .collect();
    // Per pair of pieces, the join whose nodes are nearest to them (ties: the smaller nodes,
    // compared as coordinates).
    let coords = |j: &Join| (j.a.to_array(), j.b.to_array());
    let mut best: BTreeMap<(usize, usize), (f64, usize)> = BTreeMap::new();
    for (i, (j, (pa, da), (pb, db))) in joins.iter().enumerate() {
        let d = da + db;
        let e = best.entry((*pa.min(pb), *pa.max(pb))).or_insert((d, i));
        let better = d < e.0
            || (d == e.0 && coords(j).partial_cmp(&coords(&joins[e.1].0)) == Some(Ordering::Less));
        if better {
            *e = (d, i);
        }
    }
    let mut out = Vec::new();
    for (_, i) in best.values() {
        ring(img, &joins[*i].0, &mut out);
    }
    out
}

/// The margin of a round's boxes is 1.5 voxels times 2 to this power.
fn margin_level(round: usize) -> u32 {
    round.min(3) as u32
}

/// The first crossings of S of [`RING_RAYS`] rays perpendicular to the join, from points of
/// the inside region on it (a grid edge's quarter points, or a face's saddle), as long as the
/// join.
pub(super) fn ring(img: &ImageSurface, j: &Join, out: &mut Vec<DVec3>) {
    let axis = j.b - j.a;
    let len = axis.length();
    let Some(u) = axis.try_normalize() else {
        return;
    };
    let e1 = u.any_orthonormal_vector();
    let e2 = u.cross(e1);
    let centres: Vec<DVec3> = if j.diagonal {
        vec![j.via]
    } else {
        [0.25, 0.5, 0.75].map(|t| j.a + axis * t).to_vec()
    };
    let mut buf = Vec::new();
    for c in centres {
        for m in 0..RING_RAYS {
            let ang = m as f64 * std::f64::consts::TAU / RING_RAYS as f64;
            let d = e1 * ang.cos() + e2 * ang.sin();
            buf.clear();
            img.crossings(c, c + d * len, &mut buf);
            if let Some(&x) = buf.first() {
                out.push(x);
            }
        }
    }
}
