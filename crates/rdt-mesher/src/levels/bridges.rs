//! Bridging the pieces of a split component (ours, images; issue 14), after the repair: a
//! scan component meshed in several closed pieces has a neck that neither the neck rounds
//! (`necks`) nor the repair's joined necks (`repair`, rule 3') left in the mesh. The scan
//! knows where it is: a join (two inside nodes joined by a grid edge or a face saddle, see
//! [`ImageSurface::neck_joins`]) whose nodes are nearest to different pieces, looked for in
//! a box around the smaller piece whose margin doubles up to [`ROUNDS`] times (from 1.5
//! voxels). At the join, a triangle of each piece is removed and the two triangle-shaped loops
//! are joined by a tube (`repair`'s zipper), so the component is one piece again (`bridge`
//! decisions): of the [`NEAR`] triangles of each piece nearest the join, the pair with the
//! nearest centroids whose tube intersects no other triangle (exact test) and has no triangle
//! whose circumball exceeds the size bound sigma there (the loose epsilon-sample certificate
//! measures every triangle). A tube is six triangles, or runs through up to [`MAX_RINGS`]
//! rings of three new points of S (projected from the tube's axis onto the neck's wall), six
//! triangles per stage: shorter stages have smaller circumballs. Only when no such tube
//! fits, the same pairs with straight rings (off S: across a neck thinner than a voxel, S has
//! no wall there), from one triangle's shape to the other's in stages about as long as their
//! edges ([`straight::straight_rings`]): their stages are within sigma where a six-triangle tube
//! between two tips was oversized (since 2026-12-05; `bridge_over_size` decisions went from
//! 22 to 0 on `nibabel_example4d_vol0` at iso 420.5, `--size 2`). A tube within sigma with
//! triangles below the angle bound is replaced by a straight one of its pair or the pairs
//! just before it when that has fewer ([`fewer_skinny`]). When no pair gives one, the
//! pairs among the [`NEAR_WIDE`] nearest triangles of each side are tried; when none of those
//! does either, the least oversized tube that crosses nothing is taken if its circumballs are
//! within [`MAX_OVERSIZE`] sigma (`bridge_over_size`, with its r / sigma: a size bound
//! missed and reported, rather than a wrong topology); otherwise the piece stays split and is
//! reported as such.
//!
//! The pieces are taken largest first and bridging repeats until no bridge is added: a piece
//! whose nearest join led to a smaller piece is bridged again, as part of their group,
//! towards another group (on `sheet` at 1 voxel, a strip first met a sliver of the sheet).
//! The triangles of a piece are not limited to a distance from the join: the tube's size
//! bound limits its length.
//!
//! Invariant kept: the mesh stays a closed, oriented 2-manifold without self-intersections
//! (the two loops are on pieces of different groups, so the tube adds no existing edge; the
//! tube's triangles are checked against all others).

use super::repair::{DecisionKind, TopologyDecision};
use crate::stats::MeshResult;
use glam::DVec3;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use oracle::image::{ImageSurface, Join, Node};
use rayon::prelude::*;
use rustc_hash::FxHashMap;
use std::collections::BTreeMap;

mod straight;
#[cfg(test)]
use straight::{MAX_STRAIGHT, straight_rings};
use straight::{Rings, straight_variants};

/// Doublings of the search box's margin.
const ROUNDS: u32 = 6;

/// Doublings for a piece below a voxel (margins up to 6 voxels; wider found none on the T1).
const SMALL_ROUNDS: u32 = 3;

/// Triangles of each piece tried first, nearest the join first.
const NEAR: usize = 8;

/// Triangles of each piece tried when no pair of the first [`NEAR`] gives a tube within
/// sigma (before an oversized tube is taken).
const NEAR_WIDE: usize = 20;

/// When no candidate tube is within sigma, the least oversized one that crosses nothing is
/// taken if its largest circumradius is at most this many times sigma (a split component is
/// a wrong topology; an oversized tube is a size bound missed, reported as such).
const MAX_OVERSIZE: f64 = 3.0;

/// Intermediate rings of points of S tried in a tube (0 first).
const MAX_RINGS: usize = 2;

/// Pairs (counted back from the chosen tube's) whose straight tubes [`fewer_skinny`] tries.
const SKINNY_PAIRS: usize = 4;

/// `first`, the first tube within sigma that crosses nothing, or, when some of its triangles
/// are below the angle bound, the straight tube with the fewest (then the largest smallest
/// angle) when it beats `first` so, among those of `first`'s pair and the [`SKINNY_PAIRS`] -
/// 1 pairs before it in `before` (the candidates met before `first`), within sigma and
/// crossing nothing: never more triangles below the bound than `first`.
fn fewer_skinny<E>(
    first: Candidate,
    before: &[(usize, usize, Rings, bool)],
    evaluate: &E,
    mesh: &meshio::TriMesh,
    criteria: &crate::Criteria,
) -> Candidate
where
    E: Fn(&(usize, usize, Rings, bool)) -> Option<(Candidate, Option<f64>, bool)> + Sync,
{
    let bound = criteria.min_angle_deg;
    let skinny = |c: &Candidate| {
        c.tube
            .iter()
            .map(|t| crate::criteria::min_angle_deg(t.map(|v| position(mesh, &c.ring_pts, v))))
            .fold((0usize, f64::INFINITY), |(n, m), a| {
                (n + usize::from(a < bound), m.min(a))
            })
    };
    let (below, angle) = skinny(&first);
    if below == 0 {
        return first;
    }
    // The pairs: `first`'s and those before it, nearest first.
    let mut pairs: Vec<(usize, usize)> = vec![(first.removed[0], first.removed[1])];
    for &(ta, tb, _, _) in before.iter().rev() {
        if pairs.len() == SKINNY_PAIRS {
            break;
        }
        if !pairs.contains(&(ta, tb)) {
            pairs.push((ta, tb));
        }
    }
    let tries: Vec<(usize, usize, Rings, bool)> = pairs
        .iter()
        .flat_map(|&(ta, tb)| straight_variants(mesh, ta, tb))
        .collect();
    let found: Vec<_> = tries.par_iter().map(evaluate).collect();
    let mut best = (below, angle, first);
    for (c, _, _) in found
        .into_iter()
        .flatten()
        .filter(|(_, over, crosses)| over.is_none() && !crosses)
    {
        let (b, a) = skinny(&c);
        if b < best.0 || (b == best.0 && a > best.1) {
            best = (b, a, c);
        }
    }
    best.2
}

/// Bridge the split components of a run on an image with a resolution set (the pipeline's
/// images) and record the decisions in its figures; nothing otherwise.
pub(crate) fn apply(
    out: &mut MeshResult,
    surface: &dyn oracle::Surface,
    opts: &crate::MeshOptions,
) {
    let (Some(_), Some(img)) = (opts.resolution, surface.as_image()) else {
        return;
    };
    let d = bridge_splits(out, img, &opts.criteria);
    super::components::record(out, opts, d);
}

/// Bridge every piece but the largest of each split scan component to another piece of it,
/// where the scan shows the join (see the module docs). Returns the decisions.
fn bridge_splits(
    out: &mut MeshResult,
    img: &ImageSurface,
    criteria: &crate::Criteria,
) -> Vec<TopologyDecision> {
    let h = img.volume().spacing().min_element();
    let mut decisions = Vec::new();
    let mut by_label: BTreeMap<usize, Vec<Vec<u32>>> = BTreeMap::new();
    for (vs, l) in super::components::pieces(&out.mesh, img) {
        if let Some(l) = l {
            by_label.entry(l).or_default().push(vs);
        }
    }
    for (label, mut ps) in by_label {
        if ps.len() < 2 {
            continue;
        }
        super::components::sort_pieces_largest_first(&out.mesh, &mut ps);
        // The nearest piece (and distance) of a point, over the component's vertices (the
        // bridges keep every vertex where it is, so one tree serves the whole component).
        let mut coords: Vec<[f64; 3]> = Vec::new();
        let mut owner: Vec<usize> = Vec::new();
        for (k, piece) in ps.iter().enumerate() {
            coords.extend(
                piece
                    .iter()
                    .map(|&v| out.mesh.vertices[v as usize].to_array()),
            );
            owner.extend(std::iter::repeat_n(k, piece.len()));
        }
        let Ok(tree) = ImmutableKdTree::<f64, 3>::new_from_slice(&coords) else {
            continue;
        };
        let nearest = |p: DVec3| -> (usize, f64) {
            let r = tree
                .query(&p.to_array())
                .nearest_one::<SquaredEuclidean<f64>>()
                .execute();
            (owner[r.item as usize], r.distance.sqrt())
        };
        // Each grid node's nearest piece, once (a node is shared by up to 18 joins and by
        // the boxes of several pieces and rounds).
        let mut memo: FxHashMap<usize, (usize, f64)> = FxHashMap::default();
        let mut node_piece = |n: Node| *memo.entry(n.index).or_insert_with(|| nearest(n.at));
        // Which pieces are merged by the bridges built so far (a root per piece).
        let mut merged: Vec<usize> = (0..ps.len()).collect();
        // Passes until no bridge is added: a piece bridged to a smaller one first is bridged
        // again, as part of their group, towards the largest piece.
        let mut progress = true;
        while progress {
            progress = false;
            for i in 1..ps.len() {
                if root_of(&merged, i) == 0 {
                    continue;
                }
                // Sub-voxel pieces too (dropped, their part of S could be beyond h + sigma).
                let bbox = ps[i]
                    .iter()
                    .map(|&v| out.mesh.vertices[v as usize])
                    .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
                        (lo.min(p), hi.max(p))
                    });
                let Some((j, join)) = find_join(img, label, &mut node_piece, i, bbox, &merged, h)
                else {
                    continue;
                };
                // Below a voxel, only the nearest pairs (wide failures: 60 ms each on the T1).
                let wide = bbox.0.distance(bbox.1) >= h;
                let made = bridge(
                    out,
                    img,
                    &ps[i],
                    &ps[j],
                    &join,
                    criteria,
                    wide,
                    [join.via; 2],
                )
                .or_else(|| {
                    let keep = wide
                        && !super::components::is_fragment(&out.mesh, &ps[i], &ps[0], h, criteria);
                    let anchors =
                        mutual_anchors(&out.mesh, &ps[i], &ps[j], join.via).filter(|_| keep)?;
                    bridge(out, img, &ps[i], &ps[j], &join, criteria, wide, anchors)
                });
                if let Some(d) = made {
                    let (ri, rj) = (root_of(&merged, i), root_of(&merged, j));
                    merged[ri.max(rj)] = ri.min(rj);
                    decisions.push(d);
                    progress = true;
                }
            }
        }
    }
    decisions
}

/// The join of the scan between piece `i` (box `(lo, hi)`) and another piece not yet merged
/// with it, nearest to both by `nearest` (the piece of a point and its distance), in a box
/// around piece `i` whose margin doubles: that piece and the join.
fn find_join(
    img: &ImageSurface,
    label: usize,
    nearest: &mut dyn FnMut(Node) -> (usize, f64),
    i: usize,
    (lo, hi): (DVec3, DVec3),
    merged: &[usize],
    h: f64,
) -> Option<(usize, Join)> {
    let root = root_of(merged, i);
    let small = lo.distance(hi) < h;
    for r in 0..if small { SMALL_ROUNDS } else { ROUNDS } {
        let m = DVec3::splat(1.5 * h * f64::from(1u32 << r));
        let mut best: Option<(f64, usize, Join)> = None;
        // The other piece of a join between piece i and a piece not merged with it (the
        // only candidates), and the join's distance to both.
        let mut other_of = |a: Node, b: Node| {
            let ((pa, da), (pb, db)) = (nearest(a), nearest(b));
            let other = match (pa == i, pb == i) {
                (true, false) => pb,
                (false, true) => pa,
                _ => return None,
            };
            (root_of(merged, other) != root).then_some((other, da + db))
        };
        let joins =
            img.neck_joins_where(label, lo - m, hi + m, &mut |a, b| other_of(a, b).is_some());
        for j in joins {
            let end = |k: usize| Node {
                index: j.nodes[k],
                at: if k == 0 { j.a } else { j.b },
            };
            let Some((other, d)) = other_of(end(0), end(1)) else {
                continue;
            };
            if best.as_ref().is_none_or(|b| d < b.0) {
                best = Some((d, other, j));
            }
        }
        if let Some((_, other, j)) = best {
            return Some((other, j));
        }
    }
    None
}

/// A second try for [`bridge`], for a piece the fragment rule would keep (over a voxel
/// across, not hanging at the component's largest piece: `components::is_fragment`; a
/// fragment is better dropped than tied by a tube of needles): where a piece is refined far
/// below the size at the join (a sub-voxel tip reaching for a face saddle, its triangles a hundredth of a voxel), the
/// triangles of that piece nearest the join are all on its tip, and every tube from them to
/// the other piece crosses the piece itself (`nibabel_anatomical` at iso 9444.5, `--size 1`:
/// a piece of 946 triangles on the image's border, 1.4 mm from the rest of its component).
/// The anchors are then, for each piece, the centroid of the other piece's triangle nearest
/// the join: the candidates face each other across the gap.
fn mutual_anchors(mesh: &meshio::TriMesh, a: &[u32], b: &[u32], via: DVec3) -> Option<[DVec3; 2]> {
    let nearest_centroid = |piece: &[u32]| -> Option<DVec3> {
        let mut on = vec![false; mesh.vertices.len()];
        piece.iter().for_each(|&v| on[v as usize] = true);
        mesh.triangles
            .iter()
            .filter(|t| on[t[0] as usize])
            .map(|t| t.iter().map(|&v| mesh.vertices[v as usize]).sum::<DVec3>() / 3.0)
            .min_by(|x, y| x.distance_squared(via).total_cmp(&y.distance_squared(via)))
    };
    let (ca, cb) = (nearest_centroid(a)?, nearest_centroid(b)?);
    Some([cb, ca])
}

/// Replace a triangle of piece `a` and one of piece `b` near the join by a tube between
/// their loops: of the [`NEAR`] triangles of `a` nearest `anchors[0]` and of `b` nearest
/// `anchors[1]` (both the join `j.via` first; then see [`mutual_anchors`]), the pairs by
/// increasing distance between their centroids, each with 0 to [`MAX_RINGS`] rings of points
/// of S and either zipper (`tube_with_rings`), the first tube whose circumballs are within
/// sigma and which intersects no other triangle (then, `wide`, the wider pairs). `None` (the
/// mesh unchanged) when there is none.
#[allow(clippy::too_many_arguments)]
fn bridge(
    out: &mut MeshResult,
    img: &ImageSurface,
    a: &[u32],
    b: &[u32],
    j: &Join,
    criteria: &crate::Criteria,
    wide: bool,
    anchors: [DVec3; 2],
) -> Option<TopologyDecision> {
    let (pairs, region) = candidate_pairs(&out.mesh, a, b, j, anchors, wide);
    // The candidates in order (pairs, then variants), evaluated in parallel a chunk at a time
    // (each independently of the others: the choice below is the sequential one): the first
    // within sigma that crosses nothing is taken; the oversized ones are kept for later.
    let mesh = &out.mesh;
    // Every tube on S first (pairs, then rings), then the straight ones.
    let on_s = pairs.iter().flat_map(|&(_, ta, tb)| {
        (0..=MAX_RINGS).flat_map(move |r| [false, true].map(move |s| (ta, tb, Rings::OnS(r), s)))
    });
    let straight = pairs
        .iter()
        .flat_map(|&(_, ta, tb)| straight_variants(mesh, ta, tb));
    let order: Vec<(usize, usize, Rings, bool)> = on_s.chain(straight).collect();
    let evaluate = |&(ta, tb, rings, superimposed): &(usize, usize, Rings, bool)| {
        let (fa, fb) = (mesh.triangles[ta], mesh.triangles[tb]);
        let (tube, ring_pts) = tube_with_rings(mesh, img, (fa, fb), j.via, rings, superimposed)?;
        let pos = |v: u32| position(mesh, &ring_pts, v);
        // Within the size bound, as a restricted facet would be (the loose epsilon-sample
        // certificate measures every triangle's ball).
        let balls: Vec<_> = tube
            .iter()
            .map(|t| super::repair::circumball(t.map(pos)))
            .collect();
        let over = balls
            .iter()
            .any(|b| criteria.sigma_at(b.center).is_some_and(|s| b.radius > s))
            .then(|| {
                balls
                    .iter()
                    .filter_map(|b| criteria.sigma_at(b.center).map(|s| b.radius / s))
                    .fold(0.0f64, f64::max)
            });
        let crosses = over.is_none() && tube_crosses(mesh, &ring_pts, [ta, tb], &tube, &region);
        let c = Candidate {
            removed: [ta, tb],
            tube,
            ring_pts,
            balls,
        };
        Some((c, over, crosses))
    };
    // Oversized tubes (at most the cap): (r / sigma, order, tube).
    let mut oversized: Vec<(f64, usize, Candidate)> = Vec::new();
    const CHUNK: usize = 24;
    for (k, chunk) in order.chunks(CHUNK).enumerate() {
        let evals: Vec<_> = chunk.par_iter().map(evaluate).collect();
        for (m, e) in evals.into_iter().enumerate() {
            match e {
                Some((c, None, false)) => {
                    // The first tube within sigma, or a straight one with fewer triangles
                    // below the angle bound.
                    let c = fewer_skinny(c, &order[..k * CHUNK + m], &evaluate, mesh, criteria);
                    return Some(c.apply(out, DecisionKind::Bridge));
                }
                Some((c, Some(over), _)) if over <= MAX_OVERSIZE => {
                    oversized.push((over, k * CHUNK + m, c))
                }
                _ => {}
            }
        }
    }
    // None within sigma: the least oversized that crosses nothing (ties: the first in order).
    oversized.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
    let mesh = &out.mesh;
    let pick = oversized
        .into_iter()
        .find(|(_, _, c)| !tube_crosses(mesh, &c.ring_pts, c.removed, &c.tube, &region))?;
    let (over, _, c) = pick;
    Some(c.apply(
        out,
        DecisionKind::BridgeOverSize {
            max_r_over_sigma: over,
        },
    ))
}

/// The candidate pairs of triangles (squared distance between centroids, triangle of `a`,
/// triangle of `b`): those among the [`NEAR`] triangles of each piece nearest its anchor (the
/// join, or see [`mutual_anchors`]) first,
/// then, `with_wide`, the others among the [`NEAR_WIDE`] nearest, each group by increasing
/// distance; and the region of the triangles that may cross their tubes.
fn candidate_pairs(
    mesh: &meshio::TriMesh,
    a: &[u32],
    b: &[u32],
    j: &Join,
    anchors: [DVec3; 2],
    with_wide: bool,
) -> (Vec<(f64, usize, usize)>, Region) {
    // Which piece each vertex is on (1: a, 2: b), and each piece's triangles by distance to
    // the join, in one parallel pass (the order is total: distance, then index).
    let mut side = vec![0u8; mesh.vertices.len()];
    a.iter().for_each(|&v| side[v as usize] = 1);
    b.iter().for_each(|&v| side[v as usize] = 2);
    let centroid = |t: &[u32; 3]| t.iter().map(|&v| mesh.vertices[v as usize]).sum::<DVec3>() / 3.0;
    let tagged: Vec<(u8, f64, usize)> = mesh
        .triangles
        .par_iter()
        .enumerate()
        .filter(|(_, t)| side[t[0] as usize] != 0)
        .map(|(k, t)| {
            let tag = side[t[0] as usize];
            (
                tag,
                centroid(t).distance_squared(anchors[usize::from(tag - 1)]),
                k,
            )
        })
        .collect();
    let near = |tag: u8| {
        let mut v: Vec<(f64, usize)> = tagged
            .iter()
            .filter(|x| x.0 == tag)
            .map(|x| (x.1, x.2))
            .collect();
        let by = |x: &(f64, usize), y: &(f64, usize)| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1));
        if v.len() > NEAR_WIDE {
            v.select_nth_unstable_by(NEAR_WIDE, by);
            v.truncate(NEAR_WIDE);
        }
        v.sort_by(by);
        v
    };
    let (na, nb) = (near(1), near(2));
    let mut pairs: Vec<(f64, usize, usize)> = Vec::new();
    let mut wide: Vec<(f64, usize, usize)> = Vec::new();
    for (ia, &(_, ta)) in na.iter().enumerate() {
        for (ib, &(_, tb)) in nb.iter().enumerate() {
            let d = centroid(&mesh.triangles[ta]).distance_squared(centroid(&mesh.triangles[tb]));
            if ia < NEAR && ib < NEAR {
                pairs.push((d, ta, tb));
            } else {
                wide.push((d, ta, tb));
            }
        }
    }
    let by_distance = |x: &(f64, usize, usize), y: &(f64, usize, usize)| {
        x.0.total_cmp(&y.0).then((x.1, x.2).cmp(&(y.1, y.2)))
    };
    pairs.sort_by(by_distance);
    wide.sort_by(by_distance);
    if with_wide {
        pairs.extend(wide);
    }
    // The candidate tubes lie near the two sets of triangles and the join (their rings within
    // three tube lengths of the axis): the triangles that may cross them, listed once.
    let region = {
        let (mut lo, mut hi) = (j.via, j.via);
        let mut reach = 0.0f64;
        for &(_, k) in na.iter().chain(&nb) {
            for &v in &mesh.triangles[k] {
                lo = lo.min(mesh.vertices[v as usize]);
                hi = hi.max(mesh.vertices[v as usize]);
            }
        }
        for &(d2, _, _) in &pairs {
            reach = reach.max(3.0 * d2.sqrt());
        }
        Region::new(mesh, lo - DVec3::splat(reach), hi + DVec3::splat(reach))
    };
    (pairs, region)
}

/// A tube that replaces two triangles of the mesh: the new points (numbered from the mesh's
/// vertex count), the tube's triangles and their circumballs.
struct Candidate {
    removed: [usize; 2],
    tube: Vec<[u32; 3]>,
    ring_pts: Vec<DVec3>,
    balls: Vec<crate::stats::SurfaceBall>,
}

impl Candidate {
    /// Put the tube in the mesh (and its balls in the result's); the decision taken.
    fn apply(self, out: &mut MeshResult, kind: DecisionKind) -> TopologyDecision {
        let [ta, tb] = self.removed;
        let (hi, lo) = (ta.max(tb), ta.min(tb));
        let mesh = &mut out.mesh;
        mesh.vertices.extend(&self.ring_pts);
        mesh.triangles.swap_remove(hi);
        mesh.triangles.swap_remove(lo);
        mesh.triangles.extend(&self.tube);
        out.balls.swap_remove(hi);
        out.balls.swap_remove(lo);
        out.balls.extend(self.balls);
        let (lo_p, hi_p) = self
            .tube
            .iter()
            .flatten()
            .map(|&v| mesh.vertices[v as usize])
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(l, h), p| {
                (l.min(p), h.max(p))
            });
        TopologyDecision {
            kind,
            center: 0.5 * (lo_p + hi_p),
            size: lo_p.distance(hi_p),
            facets_removed: 2,
            facets_added: self.tube.len(),
        }
    }
}

/// The tube from triangle `fa` to triangle `fb` through `rings` intermediate rings of three
/// new points (numbered from the mesh's vertex count), and those points. With
/// [`Rings::OnS`], ring `i` of `n` is `fb` moved by `i / (n + 1)` of the way from `fb`'s
/// centroid to `fa`'s, each point projected on S as the first crossing of the ray from the
/// axis (the line through `via`, inside the component, along the tube) away from it; `None`
/// when a ray meets no crossing within three tube lengths. With [`Rings::Straight`], each
/// vertex of `fb` goes that far towards the vertex of `fa` it faces, off S.
fn tube_with_rings(
    mesh: &meshio::TriMesh,
    img: &ImageSurface,
    (fa, fb): ([u32; 3], [u32; 3]),
    via: DVec3,
    rings: Rings,
    superimposed: bool,
) -> Option<(Vec<[u32; 3]>, Vec<DVec3>)> {
    let (rings, on_s) = match rings {
        Rings::OnS(n) => (n, true),
        Rings::Straight(n) => (n, false),
    };
    use oracle::Surface;
    let at = |v: u32| mesh.vertices[v as usize];
    let ca = fa.iter().map(|&v| at(v)).sum::<DVec3>() / 3.0;
    let cb = fb.iter().map(|&v| at(v)).sum::<DVec3>() / 3.0;
    let mut pts: Vec<DVec3> = Vec::new();
    let mut buf = Vec::new();
    // Loops from `fb`'s side to `fa`'s, each in `fb`'s order.
    let mut loops: Vec<Vec<u32>> = vec![fb.to_vec()];
    let axis = (ca - cb).normalize_or_zero();
    if axis == DVec3::ZERO {
        return None;
    }
    let reach = 3.0 * ca.distance(cb);
    // A straight tube's rings go from `fb`'s shape to `fa`'s: `fb`'s vertex `k` towards the
    // vertex of `fa` it faces (`fa` reversed: the two face each other), the cyclic pairing
    // whose offsets from the centroids agree best.
    let facing: [DVec3; 3] = {
        let rev = [at(fa[0]), at(fa[2]), at(fa[1])];
        let cost = |s: usize| {
            (0..3)
                .map(|k| ((at(fb[k]) - cb) - (rev[(k + s) % 3] - ca)).length_squared())
                .sum::<f64>()
        };
        let s = (0..3)
            .min_by(|&x, &y| cost(x).total_cmp(&cost(y)))
            .unwrap_or(0);
        [0, 1, 2].map(|k| rev[(k + s) % 3])
    };
    for i in (1..=rings).rev() {
        let t = i as f64 / (rings + 1) as f64;
        let shift = (ca - cb) * (1.0 - t);
        let centre = cb + shift;
        let mut ring = Vec::with_capacity(3);
        for (k, &v) in fb.iter().enumerate() {
            let x = at(v) + shift;
            if !on_s {
                ring.push((mesh.vertices.len() + pts.len()) as u32);
                pts.push(at(v).lerp(facing[k], 1.0 - t));
                continue;
            }
            // Out from the axis (the line through `via` along `fb` -> `fa`), at `x`'s place
            // along it, towards `x` as seen from the ring's centre.
            let o = via + axis * (x - via).dot(axis);
            let d = x - centre;
            let d = (d - axis * d.dot(axis)).normalize_or_zero();
            if d == DVec3::ZERO {
                return None;
            }
            buf.clear();
            img.crossings(o, o + d * reach, &mut buf);
            let p = *buf.first()?;
            ring.push((mesh.vertices.len() + pts.len()) as u32);
            pts.push(p);
        }
        loops.push(ring);
    }
    // `fa`, then each ring from `fa`'s side reversed (its edges used the other way), zipped to
    // the next loop towards `fb`. The zipper picks its diagonals by length, as they are or
    // with the loops `superimposed` (`p` moved onto `q`'s centroid): along a tube longer than
    // its loops are wide, the raw lengths can favour one loop's steps and twist the tube into
    // itself (the tests' octahedra).
    // The zipper runs on a local table of the loops' vertices (no copy of the mesh's).
    let mut local: Vec<u32> = fa.to_vec();
    loops.iter().for_each(|l| local.extend(l));
    local.sort_unstable();
    local.dedup();
    let pos = |v: u32| {
        let n = mesh.vertices.len() as u32;
        if v < n {
            mesh.vertices[v as usize]
        } else {
            pts[(v - n) as usize]
        }
    };
    let id = |v: u32| local.binary_search(&v).expect("a loop vertex") as u32;
    let centroid = |l: &[u32]| l.iter().map(|&v| pos(v)).sum::<DVec3>() / 3.0;
    let mut edges = rustc_hash::FxHashSet::default();
    let mut tube = Vec::new();
    let mut p: Vec<u32> = fa.to_vec();
    for q in loops.iter().rev() {
        let shift = if superimposed {
            centroid(q) - centroid(&p)
        } else {
            DVec3::ZERO
        };
        let moved: Vec<DVec3> = local
            .iter()
            .map(|&v| pos(v) + if p.contains(&v) { shift } else { DVec3::ZERO })
            .collect();
        let (lp, lq): (Vec<u32>, Vec<u32>) = (
            p.iter().map(|&v| id(v)).collect(),
            q.iter().map(|&v| id(v)).collect(),
        );
        let t = super::repair::tube(&lp, &lq, &moved, &mut edges);
        tube.extend(t.into_iter().map(|t| t.map(|v| local[v as usize])));
        p = q.iter().rev().copied().collect();
    }
    Some((tube, pts))
}

/// Whether the tube (on `mesh`'s vertices and then `extra`) intersects itself or a triangle of
/// `mesh` other than `removed` (exact tests, on the triangles whose boxes meet the tube's).
///
/// `region`: a box and the triangles whose boxes meet it, listed in mesh order; used instead
/// of a scan of the whole mesh when it holds the tube's box (the same triangles then).
fn tube_crosses(
    mesh: &meshio::TriMesh,
    extra: &[DVec3],
    removed: [usize; 2],
    tube: &[[u32; 3]],
    region: &Region,
) -> bool {
    let pos = |v: u32| position(mesh, extra, v);
    let (lo, hi) = tube
        .iter()
        .flatten()
        .map(|&v| pos(v))
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(l, h), p| {
            (l.min(p), h.max(p))
        });
    let meets = |t: &[u32; 3]| {
        let (a, b) = t
            .iter()
            .map(|&v| pos(v))
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(l, h), p| {
                (l.min(p), h.max(p))
            });
        a.cmple(hi).all() && b.cmpge(lo).all()
    };
    let inside = region.lo.cmple(lo).all() && hi.cmple(region.hi).all();
    let near: Vec<[u32; 3]> = if inside {
        region
            .tris
            .iter()
            .filter(|k| !removed.contains(k))
            .map(|&k| mesh.triangles[k])
            .filter(meets)
            .collect()
    } else {
        mesh.triangles
            .iter()
            .enumerate()
            .filter(|(k, t)| !removed.contains(k) && meets(t))
            .map(|(_, t)| *t)
            .collect()
    };
    // A local mesh of those and the tube, vertices renumbered (shared vertices stay shared).
    let mut ids: Vec<u32> = near.iter().chain(tube).flatten().copied().collect();
    ids.sort_unstable();
    ids.dedup();
    let id = |v: u32| ids.binary_search(&v).expect("a listed vertex") as u32;
    let local = meshio::TriMesh {
        vertices: ids.iter().map(|&v| pos(v)).collect(),
        triangles: near.iter().chain(tube).map(|t| t.map(id)).collect(),
    };
    any_intersection(&local, near.len())
}

/// Whether a triangle from `first_new` on is degenerate or intersects another triangle of
/// `mesh`: [`super::repair::intersecting_vertices`] is not empty, decided at the first such
/// triangle (one thread: the candidate tubes are already evaluated in parallel).
fn any_intersection(mesh: &meshio::TriMesh, first_new: usize) -> bool {
    use verify::intersect::{corners, pair_intersects};
    let new = super::new_triangles::NewTriangles::of(mesh, first_new);
    if !new.degenerate.is_empty() {
        return true;
    }
    if new.queried.is_empty() {
        return false;
    }
    let mut hit = false;
    for j in 0..mesh.triangles.len() {
        let b = geom::bvh::Aabb::from_points(&corners(mesh, j));
        new.bvh.for_each_overlap(&b, |k| {
            let i = new.queried[k as usize] as usize;
            hit = hit || (j != i && pair_intersects(mesh, i, j));
        });
        if hit {
            return true;
        }
    }
    false
}

/// The point of vertex `v`: the mesh's, or the new points `extra` numbered after them.
fn position(mesh: &meshio::TriMesh, extra: &[DVec3], v: u32) -> DVec3 {
    let n = mesh.vertices.len();
    let v = v as usize;
    if v < n {
        mesh.vertices[v]
    } else {
        extra[v - n]
    }
}

/// A box and the triangles of a mesh whose boxes meet it (closed boxes), in mesh order.
struct Region {
    lo: DVec3,
    hi: DVec3,
    tris: Vec<usize>,
}

impl Region {
    fn new(mesh: &meshio::TriMesh, lo: DVec3, hi: DVec3) -> Region {
        let tris = (0..mesh.triangles.len())
            .into_par_iter()
            .filter(|&k| {
                let (a, b) = mesh.triangles[k]
                    .iter()
                    .map(|&v| mesh.vertices[v as usize])
                    .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(l, h), p| {
                        (l.min(p), h.max(p))
                    });
                a.cmple(hi).all() && b.cmpge(lo).all()
            })
            .collect();
        Region { lo, hi, tris }
    }
}

/// The root of piece `i` in the merge forest `m` (each entry points to a smaller index).
fn root_of(m: &[usize], mut i: usize) -> usize {
    while m[i] != i {
        i = m[i];
    }
    i
}

#[cfg(test)]
mod tests;
