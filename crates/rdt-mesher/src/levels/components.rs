//! Component decisions (ours; P1 for images, section 6.6.2): where the output's pieces differ
//! from the voxel scan's surface components after the bounded refinement, each difference is
//! stated with its rule, where it is and how large, never left silent.
//!
//! The neck and bridge rounds (`necks`) refine down to the manifold floor (an eighth of a
//! voxel) and for at most `NECK_ROUNDS` rounds each; the topological repair separates what
//! stays bridged (`repair`, rule 0). What they leave is decided by these rules, on the output
//! mesh (after the topological repair):
//! - **drop a fragment** (a mesh change, reported as a [`TopologyDecision`] of kind
//!   `drop_fragment`): a piece of a scan component meshed in several pieces, not its largest,
//!   that no bridge joined (`bridges`), and either whose box diagonal is below the resolution
//!   h (a voxel: a sub-voxel piece cut off by a neck thinner than the floor, or by the
//!   repair's cut, which no sample of the size bound resolves) or whose every vertex lies
//!   within h + sigma of a vertex of the component's largest piece (a piece hanging at a
//!   neck no tube could join: without it, its part of S is still within the two-sided
//!   distance of the image suite, h + sigma, of the mesh). The piece is closed, so the mesh
//!   stays a closed manifold.
//! - **split**: a scan component meshed as several pieces (a neck the rounds did not mesh)
//!   keeps its pieces; each piece but the largest is one decision (its box).
//! - **joined**: a scan component with vertices of the mesh on it but no piece of its own (a
//!   gap of S narrower than the floor, e.g. a one-voxel speck at a trilinear saddle beside
//!   another surface) stays part of the piece that holds most of its vertices (`with`: that
//!   piece's component); the box of its vertices.
//! - **dropped**: a scan component without a piece whose pieces the repair removed (a sliver)
//!   or `--min-component` did (a vertex or the centre of what was removed lies on it); its
//!   seed point.
//! - **missed**: a scan component no vertex lies on (no sample point reached it), not dropped
//!   and not of zero volume; its seed point.
//!
//! Each piece goes to the scan component most of its vertices lie on
//! ([`ImageSurface::component_of`], ties to the lowest index), as `verify`'s accounting does;
//! so, the scan's components of zero volume left aside, pieces = scan components - joined -
//! missed - dropped + split + the pieces on no component (none where the scan is right), exactly.

use crate::levels::repair::{DecisionKind, TopologyDecision};
use crate::stats::MeshResult;
use crate::topology::VertexUnion;
use glam::DVec3;
use oracle::image::ImageSurface;
use std::collections::BTreeMap;

/// What a component decision states.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum ComponentKind {
    /// One more piece of the component (a neck not meshed).
    Split,
    /// No piece of its own: its vertices belong to a piece of component `with` (a gap
    /// narrower than the floor).
    Joined {
        /// The scan component of the piece that holds most of its vertices.
        with: usize,
    },
    /// No vertex on it.
    Missed,
    /// Its pieces were removed: by the repair (a sliver) or on request (`--min-component`).
    Dropped,
}

/// One component decision: the scan component, the rule, where and how large.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ComponentDecision {
    /// The rule applied.
    #[serde(flatten)]
    pub kind: ComponentKind,
    /// Index of the scan component ([`oracle::image::Topology::component_seeds`]).
    pub component: usize,
    /// Center of the box of the piece (split) or of the component's vertices (joined); the
    /// component's seed point (missed, dropped).
    pub center: DVec3,
    /// Diagonal of that box (0 for missed and dropped).
    pub size: f64,
    /// Voxel edges the scan component crosses (about its area in voxel faces).
    pub crossing_edges: usize,
}

/// The box (center, diagonal) of `pts`.
fn bbox(pts: impl Iterator<Item = DVec3>) -> (DVec3, f64) {
    let (lo, hi) = pts.fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
        (lo.min(p), hi.max(p))
    });
    if lo.x > hi.x {
        return (DVec3::ZERO, 0.0);
    }
    (0.5 * (lo + hi), lo.distance(hi))
}

/// Orders the pieces of one scan component largest first: by the diagonal of their box, then
/// by vertex count, then by their first vertex (`key` gives a piece's first point's
/// coordinates for the last tie). The largest piece is the component's main body, which the
/// others are bridged to, dropped beside or reported as split from: by box, not by vertex
/// count, because a sub-voxel fragment refined down to the floor can hold more vertices than
/// the coarse piece it broke off (nibabel's `anatomical.nii` at iso 9444.5, `--size 2`: a
/// 0.12 mm fragment of 114 vertices beside an 8.8 mm piece of 43).
pub(crate) fn sort_largest_first<T>(
    pieces: &mut [Vec<T>],
    point: impl Fn(&T) -> DVec3,
    key: impl Fn(&T) -> [f64; 3],
) {
    let mut keyed: Vec<(f64, usize, [f64; 3], Vec<T>)> = pieces
        .iter_mut()
        .map(|p| {
            let size = bbox(p.iter().map(&point)).1;
            let first = p.first().map(&key).unwrap_or_default();
            (size, p.len(), first, std::mem::take(p))
        })
        .collect();
    keyed.sort_by(|a, b| {
        b.0.total_cmp(&a.0)
            .then(b.1.cmp(&a.1))
            .then(a.2.partial_cmp(&b.2).unwrap_or(std::cmp::Ordering::Equal))
    });
    for (slot, (_, _, _, p)) in pieces.iter_mut().zip(keyed) {
        *slot = p;
    }
}

/// [`sort_largest_first`] on pieces given as vertex ids of `mesh` (the last tie: the first
/// vertex id).
pub(crate) fn sort_pieces_largest_first(mesh: &meshio::TriMesh, pieces: &mut [Vec<u32>]) {
    sort_largest_first(
        pieces,
        |&v| mesh.vertices[v as usize],
        |&v| [f64::from(v), 0.0, 0.0],
    );
}

/// The pieces of `mesh` (by shared vertices; roots ascending): their vertices and the scan
/// component most of them lie on (lowest index on ties; `None`: no vertex on any).
pub(crate) fn pieces(mesh: &meshio::TriMesh, img: &ImageSurface) -> Vec<(Vec<u32>, Option<usize>)> {
    use rayon::prelude::*;
    let nc = img.topology().component_seeds.len();
    let n = mesh.vertices.len();
    let mut union = VertexUnion::new(n);
    let mut used = vec![false; n];
    for &t in &mesh.triangles {
        union.join_triangle(t);
        t.iter().for_each(|&v| used[v as usize] = true);
    }
    let labels: Vec<Option<usize>> = (0..n)
        .into_par_iter()
        .map(|v| {
            used[v]
                .then(|| img.component_of(mesh.vertices[v]))
                .flatten()
                .filter(|&c| c < nc)
        })
        .collect();
    let mut by_root: BTreeMap<u32, (Vec<u32>, BTreeMap<usize, usize>)> = BTreeMap::new();
    for v in (0..n).filter(|&v| used[v]) {
        let e = by_root.entry(union.find(v as u32)).or_default();
        e.0.push(v as u32);
        if let Some(l) = labels[v] {
            *e.1.entry(l).or_default() += 1;
        }
    }
    by_root
        .into_values()
        .map(|(vs, votes)| {
            let l = votes
                .iter()
                .max_by(|a, b| a.1.cmp(b.1).then(b.0.cmp(a.0)))
                .map(|(&l, _)| l);
            (vs, l)
        })
        .collect()
}

/// The fragment rule (module docs): remove the closed pieces, not the largest of their scan
/// component, whose box diagonal is below `h` or whose vertices are all within `h + sigma`
/// of the largest piece's; one decision per piece removed.
fn drop_fragments(
    out: &mut MeshResult,
    img: &ImageSurface,
    h: f64,
    criteria: &crate::Criteria,
) -> Vec<TopologyDecision> {
    let mesh = &out.mesh;
    let mut by_label: BTreeMap<usize, Vec<Vec<u32>>> = BTreeMap::new();
    for (vs, l) in pieces(mesh, img) {
        if let Some(l) = l {
            by_label.entry(l).or_default().push(vs);
        }
    }
    let mut dead = vec![false; mesh.vertices.len()];
    let mut found: Vec<(DVec3, f64, Vec<u32>)> = Vec::new();
    for (_, mut ps) in by_label {
        if ps.len() < 2 {
            continue;
        }
        sort_pieces_largest_first(mesh, &mut ps);
        let mut near_largest: Option<NearestVertex> = None;
        for p in &ps[1..] {
            let (center, size) = bbox(p.iter().map(|&v| mesh.vertices[v as usize]));
            let hanging = || {
                near_largest
                    .get_or_insert_with(|| NearestVertex::new(mesh, &ps[0]))
                    .holds(mesh, p, h, criteria)
            };
            if fragment_rule(size, h, hanging) {
                p.iter().for_each(|&v| dead[v as usize] = true);
                found.push((center, size, p.clone()));
            }
        }
    }
    if found.is_empty() {
        return Vec::new();
    }
    let mut out_d = Vec::new();
    for (center, size, vs) in &found {
        let removed = mesh.triangles.iter().filter(|t| vs.contains(&t[0])).count();
        out_d.push(TopologyDecision {
            kind: DecisionKind::DropFragment,
            center: *center,
            size: *size,
            facets_removed: removed,
            facets_added: 0,
        });
    }
    let keep: Vec<bool> = out
        .mesh
        .triangles
        .iter()
        .map(|t| !dead[t[0] as usize])
        .collect();
    crate::levels::repair::retain_marked(&mut out.mesh.triangles, &mut out.balls, &keep);
    crate::levels::repair::compact(&mut out.mesh);
    out_d
}

/// Whether the fragment rule would drop `piece`, a piece of a scan component whose largest
/// piece is `largest` (module docs): its box diagonal is below `h`, or it hangs within
/// `h + sigma` of `largest`.
pub(super) fn is_fragment(
    mesh: &meshio::TriMesh,
    piece: &[u32],
    largest: &[u32],
    h: f64,
    criteria: &crate::Criteria,
) -> bool {
    let (_, size) = bbox(piece.iter().map(|&v| mesh.vertices[v as usize]));
    fragment_rule(size, h, || {
        NearestVertex::new(mesh, largest).holds(mesh, piece, h, criteria)
    })
}

/// The fragment rule on a piece whose box diagonal is `size`: below `h`, or `hanging` (every
/// vertex within `h + sigma` of the largest piece; evaluated only when needed).
fn fragment_rule(size: f64, h: f64, hanging: impl FnOnce() -> bool) -> bool {
    size < h || hanging()
}

/// The distance from a point to the nearest of some vertices of a mesh (the largest piece of
/// a split component: the fragment rule).
struct NearestVertex(Option<kiddo::ImmutableKdTree<f64, 3>>);

impl NearestVertex {
    fn new(mesh: &meshio::TriMesh, vertices: &[u32]) -> Self {
        let coords: Vec<[f64; 3]> = vertices
            .iter()
            .map(|&v| mesh.vertices[v as usize].to_array())
            .collect();
        Self(kiddo::ImmutableKdTree::new_from_slice(&coords).ok())
    }

    /// Whether every vertex of `piece` is within `h + sigma` of these vertices (the fragment
    /// rule's *hanging* piece).
    fn holds(
        &self,
        mesh: &meshio::TriMesh,
        piece: &[u32],
        h: f64,
        criteria: &crate::Criteria,
    ) -> bool {
        piece.iter().all(|&v| {
            let x = mesh.vertices[v as usize];
            self.distance(x) <= h + criteria.sigma_at(x).unwrap_or(h)
        })
    }

    /// Infinite when there is no vertex.
    fn distance(&self, p: DVec3) -> f64 {
        self.0.as_ref().map_or(f64::INFINITY, |t| {
            t.query(&p.to_array())
                .nearest_one::<kiddo::SquaredEuclidean<f64>>()
                .execute()
                .distance
                .sqrt()
        })
    }
}

/// The component decisions of `out` against `img`'s voxel scan (see the module docs), in
/// component order (splits by piece order).
pub(crate) fn decide(out: &MeshResult, img: &ImageSurface) -> Vec<ComponentDecision> {
    let topo = img.topology();
    let nc = topo.component_seeds.len();
    let mesh = &out.mesh;
    let all = pieces(mesh, img);
    // The piece of every vertex, and the label of every vertex.
    let mut piece_of = vec![usize::MAX; mesh.vertices.len()];
    for (i, (vs, _)) in all.iter().enumerate() {
        vs.iter().for_each(|&v| piece_of[v as usize] = i);
    }
    let labels: Vec<Option<usize>> = {
        use rayon::prelude::*;
        (0..mesh.vertices.len())
            .into_par_iter()
            .map(|v| {
                (piece_of[v] != usize::MAX)
                    .then(|| img.component_of(mesh.vertices[v]))
                    .flatten()
                    .filter(|&c| c < nc)
            })
            .collect()
    };
    let n = mesh.vertices.len();
    let mut own: Vec<Vec<&Vec<u32>>> = vec![Vec::new(); nc];
    for (vs, l) in &all {
        if let Some(l) = l {
            own[*l].push(vs);
        }
    }
    // Components whose pieces were removed: the repair's dropped slivers and small
    // components (a vertex or the centre of what was removed lies on them).
    let mut excused = vec![false; nc];
    for d in &out.stats.topology_decisions {
        let p = match d.kind {
            DecisionKind::DropSmallComponent { vertex, .. } => vertex,
            DecisionKind::DropSliver => d.center,
            _ => continue,
        };
        if let Some(c) = img.component_of(p).filter(|&c| c < nc) {
            excused[c] = true;
        }
    }
    let mut out_d = Vec::new();
    for c in 0..nc {
        let crossing_edges = topo.component_edges.get(c).copied().unwrap_or(0);
        if own[c].len() > 1 {
            let mut ps: Vec<Vec<u32>> = own[c].iter().map(|p| p.to_vec()).collect();
            sort_pieces_largest_first(mesh, &mut ps);
            for p in &ps[1..] {
                let (center, size) = bbox(p.iter().map(|&v| mesh.vertices[v as usize]));
                out_d.push(ComponentDecision {
                    kind: ComponentKind::Split,
                    component: c,
                    center,
                    size,
                    crossing_edges,
                });
            }
            continue;
        }
        if !own[c].is_empty() || topo.component_vanishing.get(c) == Some(&true) {
            continue;
        }
        // A component with no mesh vertex: reported at its seed.
        let at_seed = |kind| ComponentDecision {
            kind,
            component: c,
            center: topo.component_seeds[c],
            size: 0.0,
            crossing_edges,
        };
        if excused[c] {
            out_d.push(at_seed(ComponentKind::Dropped));
            continue;
        }
        let mine: Vec<usize> = (0..n).filter(|&v| labels[v] == Some(c)).collect();
        if mine.is_empty() {
            out_d.push(at_seed(ComponentKind::Missed));
            continue;
        }
        // The piece holding most of its vertices (lowest piece on ties).
        let mut hold: BTreeMap<usize, usize> = BTreeMap::new();
        for &v in &mine {
            *hold.entry(piece_of[v]).or_default() += 1;
        }
        let with = hold
            .iter()
            .max_by(|a, b| a.1.cmp(b.1).then(b.0.cmp(a.0)))
            .and_then(|(&i, _)| all[i].1)
            .unwrap_or(c);
        let (center, size) = bbox(mine.iter().map(|&v| mesh.vertices[v]));
        out_d.push(ComponentDecision {
            kind: ComponentKind::Joined { with },
            component: c,
            center,
            size,
            crossing_edges,
        });
    }
    out_d
}

/// Rule 0: the vertices (sorted) of the triangles whose corners lie on two different
/// components of `img`'s voxel scan, one of them *joined* (vertices on it, but no piece whose
/// majority it is: a bridge that hides a component; a mixed triangle between components that
/// have their own pieces changes no count and is left alone). Corners on no component are
/// left out.
fn bridge_vertices(
    mesh: &meshio::TriMesh,
    img: &ImageSurface,
    labels: &[Option<usize>],
) -> Vec<u32> {
    let nc = img.topology().component_seeds.len();
    let mut own = vec![false; nc];
    for (_, l) in pieces(mesh, img) {
        if let Some(l) = l {
            own[l] = true;
        }
    }
    let joined = |c: usize| c < nc && !own[c];
    let mut out: Vec<u32> = Vec::new();
    for t in &mesh.triangles {
        let l: Vec<usize> = t.iter().filter_map(|&v| labels[v as usize]).collect();
        if l.iter().any(|&x| x != l[0]) && l.iter().any(|&x| joined(x)) {
            out.extend(t);
        }
    }
    out.sort_unstable();
    out.dedup();
    out
}

/// What the repair needs of the voxel scan (empty unless the surface is an image and a
/// resolution is set): rule 0's vertices, and the scan component of every vertex (rule 3').
#[derive(Default)]
pub(crate) struct Separation {
    /// Rule 0's vertices, sorted.
    pub vertices: Vec<u32>,
    /// The scan component of each mesh vertex.
    pub labels: Vec<Option<usize>>,
}

/// [`Separation`] for `out`.
pub(crate) fn separation(
    out: &MeshResult,
    surface: &dyn oracle::Surface,
    opts: &crate::MeshOptions,
) -> Separation {
    use rayon::prelude::*;
    match (opts.resolution, surface.as_image()) {
        (Some(_), Some(img)) => {
            let labels: Vec<Option<usize>> = out
                .mesh
                .vertices
                .par_iter()
                .map(|&p| img.component_of(p))
                .collect();
            Separation {
                vertices: bridge_vertices(&out.mesh, img, &labels),
                labels,
            }
        }
        _ => Separation::default(),
    }
}

/// Record the component decisions of a run on an image with a resolution set (the pipeline's
/// images); nothing otherwise.
pub(crate) fn apply(
    out: &mut MeshResult,
    surface: &dyn oracle::Surface,
    opts: &crate::MeshOptions,
) {
    let (Some(_), Some(img)) = (opts.resolution, surface.as_image()) else {
        return;
    };
    if let Some(h) = opts.resolution {
        let d = drop_fragments(out, img, h, &opts.criteria);
        record(out, opts, d);
    }
    out.stats.component_decisions = decide(out, img);
}

/// Record the decisions `d` that changed a run's mesh after the repair (bridges, dropped
/// fragments) in its figures: vertices, facets, `unmet: repaired`, and the smallest angle
/// measured again on the mesh (their triangles are not restricted facets), `unmet: angle`
/// when it is below the bound.
pub(crate) fn record(out: &mut MeshResult, opts: &crate::MeshOptions, d: Vec<TopologyDecision>) {
    if d.is_empty() {
        return;
    }
    let st = &mut out.stats;
    st.vertices = out.mesh.vertices.len();
    st.facets = out.mesh.triangles.len();
    match st.unmet.iter_mut().find_map(|u| match u {
        crate::Unmet::Repaired { decisions } => Some(decisions),
        _ => None,
    }) {
        Some(n) => *n += d.len(),
        None => st.unmet.push(crate::Unmet::Repaired { decisions: d.len() }),
    }
    st.criteria_met = false;
    st.topology_decisions.extend(d);
    super::repair::measure_angles(out, opts);
}
