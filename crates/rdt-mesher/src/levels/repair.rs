//! The topological repair (ours), after section 6.6.1's manifold patch gives up on a sampled
//! surface (an image): where Del_S(E) is still not an oriented 2-manifold (sub-voxel necks,
//! trilinear saddles, sheets touching at a point or an edge), a stated rule decides.
//!
//! Rules, in order:
//! 1. **Cut**: every triangle at a bad vertex (a vertex whose oriented link is not one path or
//!    one cycle, see `links`) is removed, until none is left; what remains is an oriented
//!    manifold with boundary. A neck pinched to a vertex or an edge is thereby cut, two sheets
//!    touching there are separated.
//! 2. **Drop a sliver**: a piece with boundary and no interior vertex (its triangles would be
//!    covered twice by any closing) is removed.
//! 3. **Close**: every boundary loop (of the cuts, or a hole Del_S(E) had) is closed by the
//!    least-area triangulation adding no existing edge (`holes`), so the result is a closed,
//!    oriented 2-manifold on the same vertices (a centroid vertex when no such triangulation
//!    exists). A closing triangle that intersects another triangle (exact test) marks the
//!    vertices of both bad, and rules 1 to 3 run again around them (up to 16 rounds).
//!    On an image, rule 3' comes first: when the triangles removed around one place leave
//!    exactly two boundary loops, on two pieces of the mesh that the cut disconnected, and
//!    most vertices of both loops lie on the same component of the voxel scan, the cut was a
//!    neck of that component pinched in Del_S(E) (S itself is connected there: near a
//!    trilinear saddle it is a tube, whichever side of it the inside is): the two loops are
//!    joined by a tube (the zipper of the two loops, shortest diagonal first) rather than
//!    closed apart, so the component stays one piece (`join_neck` decisions). A tube that
//!    intersects another triangle is cut again in the next round like any closing. Of the two
//!    zippers (raw positions, or the loops superimposed), the first whose circumballs are all
//!    within sigma is taken, else the raw one (the certificate reports its ball).
//! 4. **Drop a small component** (`--min-component`): closed components enclosing less than
//!    the given volume are removed.
//!
//! On an image, rule 0 comes first: 0. **Separate**: the vertices of every triangle whose
//! corners lie on different components of the voxel scan, one of them with no piece of its
//! own (a bridge across a gap of S that the bridge rounds of `necks` could not refine away
//! above the floor hides that component: two components of the trilinear level set are
//! disjoint, so such a triangle is never part of a faithful mesh), are bad in the first
//! round: rule 1 cuts their stars, so every triangle left there has corners on one component
//! and so has every boundary loop, which rule 3 closes on its own side. (A piece left with no
//! interior vertex, e.g. a one-voxel speck, is then a sliver, rule 2.) A mixed triangle
//! between components that both have pieces of their own changes no count and is left alone
//! (its labels may come from the nearest corners of an ambiguous cell; cutting there only
//! made skinny closings: the motor map at 1 voxel fell from 30 to 16 degrees).
//!
//! Each decision is reported ([`TopologyDecision`]): its kind, where (the center of the
//! bounding box of the triangles removed and added) and its size (that box's diagonal). The
//! new triangles are not restricted Delaunay facets: their balls are their circumballs.

use super::holes::close_loop;
use super::links::{Link, Links};
use super::new_triangles::NewTriangles;
use super::tubes::tube_within;
pub(super) use super::tubes::{circumball, tube};
use crate::stats::SurfaceBall;
use glam::DVec3;
use meshio::TriMesh;
use rustc_hash::FxHashSet as HashSet;

/// What a topological decision did (see the module docs).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum DecisionKind {
    /// Triangles at non-manifold vertices removed and the `loops` boundary loops left closed:
    /// two or more loops cut a neck or separate sheets; one closes a hole.
    Cut {
        /// Boundary loops closed.
        loops: usize,
    },
    /// Triangles at non-manifold vertices removed and the two boundary loops left joined by
    /// a tube instead of closed each on its own (rule 3'): a neck of one scan component
    /// pinched to a vertex or an edge, kept.
    JoinNeck,
    /// A hole of Del_S(E) (boundary edges, no triangle removed) closed.
    Close,
    /// Two pieces of one split scan component joined by a tube at the scan's join between
    /// them, one triangle of each replaced (`crate::levels::bridges`).
    Bridge,
    /// As [`DecisionKind::Bridge`], with a tube over the size bound: no candidate tube was
    /// within sigma, and this one, the least oversized that crosses nothing, was taken
    /// (`crate::levels::bridges`, at most 3 sigma).
    BridgeOverSize {
        /// The largest circumradius of its triangles over sigma there.
        max_r_over_sigma: f64,
    },
    /// Triangles joining two components of the voxel scan removed (rule 0) and the `loops`
    /// boundary loops left closed.
    Separate {
        /// Boundary loops closed.
        loops: usize,
    },
    /// A piece with boundary and no interior vertex removed.
    DropSliver,
    /// A closed piece smaller than a voxel of a scan component meshed in several pieces,
    /// not its largest, removed (`crate::levels::components`).
    DropFragment,
    /// A closed component enclosing less than `--min-component` removed.
    DropSmallComponent {
        /// The volume it enclosed, in the surface's units cubed.
        volume: f64,
        /// One of its vertices (a point of S: names the component it stood for).
        vertex: DVec3,
    },
    /// Point sets and meshes: a component the input data does not support, removed
    /// (`crate::pipeline`'s rule; `--keep-unsupported` keeps it), with the `data-support`
    /// check's figures on the raw output.
    DropUnsupportedComponent(verify::data_support::ComponentSupport),
    /// Point sets and meshes: a handle of the output the input data does not show (a tunnel
    /// within half the data's band, or facing against the data normals), cut: the stars of
    /// its ball's vertices removed and the `loops` boundary loops left closed apart
    /// (`crate::pipeline`'s rule; `--keep-unsupported` keeps it), with the `data-support`
    /// check's figures on the raw output.
    CutUnsupportedHandle {
        /// Boundary loops closed.
        loops: usize,
        /// The handle, as the check measured it.
        handle: verify::data_support::UnsupportedHandle,
    },
}

/// One decision of the topological repair, with where it was taken.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct TopologyDecision {
    /// What was done.
    #[serde(flatten)]
    pub kind: DecisionKind,
    /// Center of the bounding box of the triangles removed and added.
    pub center: DVec3,
    /// Diagonal of that box.
    pub size: f64,
    /// Triangles removed.
    pub facets_removed: usize,
    /// Triangles added.
    pub facets_added: usize,
}

/// Rounds of cut-and-close before giving up (each leaves a closed manifold; later rounds
/// only grow the cuts around closings that intersect the mesh). The count of closings that
/// intersect need not fall every round: `boxes_shared_edge.off` at `--size 0.015` (the two
/// boxes' shared edge) goes 61, 93, 89, ..., 16, 11, 12, 15, 26, 16, 0 and is clear at round
/// 20; with 16 rounds its output kept 9 intersecting pairs (`verify` FAILed it).
const ROUNDS: usize = 64;

/// Make `mesh` a closed oriented 2-manifold by the rules of the module docs; `balls` follow
/// the triangles. Returns the decisions (empty if the mesh was one and no component is below
/// `min_volume`).
/// `separate`: the vertices of rule 0 (sorted), bad in the first round; `labels`: the scan
/// component of each vertex (rule 3'; empty, or shorter than the vertices, for none).
pub(crate) fn repair(
    mesh: &mut TriMesh,
    balls: &mut Vec<SurfaceBall>,
    min_volume: Option<f64>,
    separate: &[u32],
    labels: &[Option<usize>],
    criteria: Option<&crate::Criteria>,
) -> Vec<TopologyDecision> {
    let mut decisions = Vec::new();
    let mut forced: Vec<u32> = separate.to_vec();
    let mut sep = vec![false; mesh.vertices.len()];
    separate.iter().for_each(|&v| sep[v as usize] = true);
    for _ in 0..ROUNDS {
        if mesh.triangles.is_empty() {
            break;
        }
        let links = Links::new(&mesh.triangles, mesh.vertices.len());
        let closed =
            (0..mesh.vertices.len() as u32).all(|v| !links.used(v) || links.kind(v) == Link::Cycle);
        if closed && forced.is_empty() {
            break;
        }
        let (d, first_new) = cut_and_close(mesh, balls, &forced, &sep, labels, criteria);
        sep.iter_mut().for_each(|b| *b = false);
        decisions.extend(d);
        forced = intersecting_vertices(mesh, first_new);
    }
    if let Some(v) = min_volume {
        decisions.extend(drop_small(mesh, balls, v));
    }
    if !decisions.is_empty() {
        compact(mesh);
    }
    decisions
}

/// The vertices of the triangles from `first_new` on that intersect another triangle (or are
/// degenerate), and of the triangles they intersect, sorted.
pub(super) fn intersecting_vertices(mesh: &TriMesh, first_new: usize) -> Vec<u32> {
    if first_new >= mesh.triangles.len() {
        return Vec::new();
    }
    use rayon::prelude::*;
    let new = NewTriangles::of(mesh, first_new);
    let (queried, bvh) = (&new.queried, &new.bvh);
    let mut out: Vec<u32> = new
        .degenerate
        .iter()
        .flat_map(|&i| mesh.triangles[i])
        .collect();
    let hits: Vec<u32> = (0..mesh.triangles.len())
        .into_par_iter()
        .flat_map_iter(|j| {
            let mut hit = Vec::new();
            let b = geom::bvh::Aabb::from_points(&verify::intersect::corners(mesh, j));
            bvh.for_each_overlap(&b, |k| {
                let i = queried[k as usize] as usize;
                if j != i && verify::intersect::pair_intersects(mesh, i, j) {
                    hit.extend(mesh.triangles[i]);
                    hit.extend(mesh.triangles[j]);
                }
            });
            hit
        })
        .collect();
    out.extend(hits);
    out.sort_unstable();
    out.dedup();
    out
}

/// Rules 1 to 3 once, `forced` bad as well; returns the decisions and the index of the first
/// closing triangle.
fn cut_and_close(
    mesh: &mut TriMesh,
    balls: &mut Vec<SurfaceBall>,
    forced: &[u32],
    sep: &[bool],
    labels: &[Option<usize>],
    criteria: Option<&crate::Criteria>,
) -> (Vec<TopologyDecision>, usize) {
    let n = mesh.vertices.len();
    let mut live = vec![true; mesh.triangles.len()];
    cut_bad_stars(mesh, &mut live, forced);
    let cut: Vec<usize> = (0..live.len()).filter(|&i| !live[i]).collect();
    // Rule 2: pieces with boundary and no interior vertex.
    let slivers = drop_slivers(mesh, &mut live);
    let kept = live_tris(&mesh.triangles, &live);
    let links = Links::new(&kept, n);
    // Rule 3: close every boundary loop (traced in vertex order: deterministic).
    let mut edges: HashSet<[u32; 2]> = HashSet::default();
    for t in &kept {
        for i in 0..3 {
            let (a, b) = (t[i], t[(i + 1) % 3]);
            edges.insert([a.min(b), a.max(b)]);
        }
    }
    let mut seen = vec![false; n];
    let mut traced: Vec<Vec<u32>> = Vec::new();
    for v0 in 0..n as u32 {
        if seen[v0 as usize] || !matches!(links.kind(v0), Link::Path { .. }) {
            continue;
        }
        let mut lp = Vec::new();
        let mut v = v0;
        while !seen[v as usize] {
            seen[v as usize] = true;
            lp.push(v);
            let Link::Path { first } = links.kind(v) else {
                break;
            };
            v = first;
        }
        lp.reverse();
        traced.push(lp);
    }
    // Rule 3': the pairs of loops to join by a tube (image labels only).
    let pairs = neck_pairs(&mesh.triangles, &cut, &kept, &traced, labels, n);
    let mut partner = vec![usize::MAX; traced.len()];
    let mut tubes: Vec<Vec<[u32; 3]>> = vec![Vec::new(); traced.len()];
    for &(a, b) in &pairs {
        partner[a] = b;
        partner[b] = a;
        tubes[a.min(b)] = tube_within(&traced[a.min(b)], &traced[a.max(b)], mesh, criteria);
    }
    let mut loops: Vec<(Vec<u32>, Vec<[u32; 3]>)> = Vec::new();
    let mut joined = vec![false; traced.len()];
    for (k, lp) in traced.iter().enumerate() {
        let added = match partner[k] {
            j if j == usize::MAX => close_loop(lp, &mut mesh.vertices, &mut edges),
            j if j > k => {
                joined[k] = true;
                joined[j] = true;
                let t = std::mem::take(&mut tubes[k]);
                add_edges(&t, &mut edges);
                t
            }
            _ => Vec::new(),
        };
        loops.push((lp.clone(), added));
    }
    let out = report(mesh, &cut, &slivers, &loops, &joined, sep);
    let first_new = kept.len();
    // The new triangle list: the kept ones in order, then the closings.
    let mut tris = Vec::with_capacity(kept.len());
    let mut bs = Vec::with_capacity(kept.len());
    for (i, l) in live.iter().enumerate() {
        if *l {
            tris.push(mesh.triangles[i]);
            bs.push(balls[i]);
        }
    }
    for (_, added) in &loops {
        for t in added {
            tris.push(*t);
            bs.push(circumball(t.map(|v| mesh.vertices[v as usize])));
        }
    }
    mesh.triangles = tris;
    *balls = bs;
    (out, first_new)
}

/// The triangles still live.
/// Rule 1: remove (mark not `live`) the stars of bad vertices until none is left, `forced`
/// bad in the first round. Only the vertices of removed triangles change links, so after the
/// first classification only they are looked at again (a bad vertex loses its whole star: it
/// is unused, hence not bad, afterwards).
fn cut_bad_stars(mesh: &TriMesh, live: &mut [bool], forced: &[u32]) {
    let n = mesh.vertices.len();
    let star = stars(&mesh.triangles, n);
    let links = Links::new(&mesh.triangles, n);
    let mut bad: Vec<u32> = (0..n as u32)
        .filter(|&v| links.used(v) && links.kind(v) == Link::Bad)
        .collect();
    bad.extend(forced);
    bad.sort_unstable();
    bad.dedup();
    let mut link: Vec<[u32; 2]> = Vec::new();
    while !bad.is_empty() {
        let mut touched: Vec<u32> = Vec::new();
        for &v in &bad {
            for &t in star.of(v) {
                if std::mem::replace(&mut live[t as usize], false) {
                    touched.extend(mesh.triangles[t as usize]);
                }
            }
        }
        touched.sort_unstable();
        touched.dedup();
        bad = touched
            .into_iter()
            .filter(|&v| {
                link.clear();
                for &t in star.of(v) {
                    if live[t as usize] {
                        link.push(super::links::link_edge(mesh.triangles[t as usize], v));
                    }
                }
                link.sort_unstable();
                !link.is_empty() && super::links::classify(&link) == Link::Bad
            })
            .collect();
    }
}

/// The triangles at each vertex (compressed rows, ascending triangle order).
struct Stars {
    start: Vec<u32>,
    tris: Vec<u32>,
}

impl Stars {
    fn of(&self, v: u32) -> &[u32] {
        &self.tris[self.start[v as usize] as usize..self.start[v as usize + 1] as usize]
    }
}

/// [`Stars`] of `tris` over vertices `0..n`.
fn stars(tris: &[[u32; 3]], n: usize) -> Stars {
    let start = crate::topology::bucket_starts(tris, n);
    let mut fill = start.clone();
    let mut out = vec![0u32; start[n] as usize];
    for (k, t) in tris.iter().enumerate() {
        for &v in t {
            out[fill[v as usize] as usize] = k as u32;
            fill[v as usize] += 1;
        }
    }
    Stars { start, tris: out }
}

fn live_tris(tris: &[[u32; 3]], live: &[bool]) -> Vec<[u32; 3]> {
    tris.iter()
        .zip(live)
        .filter(|(_, l)| **l)
        .map(|(t, _)| *t)
        .collect()
}

/// Components (by shared vertices) of the triangles `which` of `tris`, as lists of triangle
/// indices, in order of their first triangle.
fn components(tris: &[[u32; 3]], which: &[usize], n: usize) -> Vec<Vec<usize>> {
    let mut parent = crate::topology::VertexUnion::new(n);
    for &i in which {
        parent.join_triangle(tris[i]);
    }
    let mut index: std::collections::BTreeMap<u32, usize> = Default::default();
    let mut out: Vec<Vec<usize>> = Vec::new();
    for &i in which {
        let r = parent.find(tris[i][0]);
        let k = *index.entry(r).or_insert_with(|| {
            out.push(Vec::new());
            out.len() - 1
        });
        out[k].push(i);
    }
    out
}

/// Rule 2: remove (from `live`) the pieces with boundary whose vertices are all on it;
/// returns the removed triangles by piece.
fn drop_slivers(mesh: &TriMesh, live: &mut [bool]) -> Vec<Vec<usize>> {
    let n = mesh.vertices.len();
    let which: Vec<usize> = (0..live.len()).filter(|&i| live[i]).collect();
    let kept = live_tris(&mesh.triangles, live);
    let links = Links::new(&kept, n);
    let kinds: Vec<Link> = (0..n as u32).map(|v| links.kind(v)).collect();
    let mut out = Vec::new();
    for comp in components(&mesh.triangles, &which, n) {
        let verts = comp.iter().flat_map(|&i| mesh.triangles[i]);
        let interior = verts.clone().any(|v| kinds[v as usize] == Link::Cycle);
        let boundary = verts
            .clone()
            .any(|v| matches!(kinds[v as usize], Link::Path { .. }));
        if boundary && !interior {
            for &i in &comp {
                live[i] = false;
            }
            out.push(comp);
        }
    }
    out
}

/// The decisions of one cut-and-close: one per cluster of removed and added triangles.
fn report(
    mesh: &TriMesh,
    cut: &[usize],
    slivers: &[Vec<usize>],
    loops: &[(Vec<u32>, Vec<[u32; 3]>)],
    joined: &[bool],
    sep: &[bool],
) -> Vec<TopologyDecision> {
    let n = mesh.vertices.len();
    // Clusters: the cut triangles and the closings, joined by shared vertices.
    let mut tris: Vec<[u32; 3]> = cut.iter().map(|&i| mesh.triangles[i]).collect();
    let mut owner: Vec<Option<usize>> = vec![None; tris.len()];
    // (The second loop of a tube adds nothing: the tube, on both loops' vertices, is its
    // partner's.)
    for (k, (_, added)) in loops.iter().enumerate() {
        tris.extend(added);
        owner.extend(std::iter::repeat_n(Some(k), added.len()));
    }
    let all: Vec<usize> = (0..tris.len()).collect();
    let mut out = Vec::new();
    for comp in components(&tris, &all, n) {
        let mut lps: Vec<usize> = comp.iter().filter_map(|&i| owner[i]).collect();
        lps.dedup();
        let removed = comp.iter().filter(|&&i| owner[i].is_none()).count();
        let separated = comp.iter().any(|&i| {
            owner[i].is_none() && tris[i].iter().any(|&v| sep.get(v as usize) == Some(&true))
        });
        let kind = if lps.iter().any(|&k| joined[k]) {
            DecisionKind::JoinNeck
        } else if removed == 0 {
            DecisionKind::Close
        } else if separated {
            DecisionKind::Separate { loops: lps.len() }
        } else {
            DecisionKind::Cut { loops: lps.len() }
        };
        out.push(decision(mesh, &tris, &comp, kind, removed));
    }
    for s in slivers {
        let tris: Vec<[u32; 3]> = s.iter().map(|&i| mesh.triangles[i]).collect();
        let all: Vec<usize> = (0..tris.len()).collect();
        out.push(decision(
            mesh,
            &tris,
            &all,
            DecisionKind::DropSliver,
            s.len(),
        ));
    }
    out
}

/// A decision of kind `kind` over the triangles `which` of `tris` (`removed` of them removed).
fn decision(
    mesh: &TriMesh,
    tris: &[[u32; 3]],
    which: &[usize],
    kind: DecisionKind,
    removed: usize,
) -> TopologyDecision {
    let (lo, hi) = which
        .iter()
        .flat_map(|&i| tris[i])
        .map(|v| mesh.vertices[v as usize])
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p), hi.max(p))
        });
    TopologyDecision {
        kind,
        center: 0.5 * (lo + hi),
        size: (hi - lo).length(),
        facets_removed: removed,
        facets_added: which.len() - removed,
    }
}

/// Rule 4: remove the closed components enclosing less than `min_volume`.
fn drop_small(
    mesh: &mut TriMesh,
    balls: &mut Vec<SurfaceBall>,
    min_volume: f64,
) -> Vec<TopologyDecision> {
    let all: Vec<usize> = (0..mesh.triangles.len()).collect();
    let mut live = vec![true; mesh.triangles.len()];
    let mut out = Vec::new();
    for comp in components(&mesh.triangles, &all, mesh.vertices.len()) {
        let volume = enclosed_volume(mesh, &comp);
        if volume < min_volume {
            for &i in &comp {
                live[i] = false;
            }
            let vertex = mesh.vertices[mesh.triangles[comp[0]][0] as usize];
            let kind = DecisionKind::DropSmallComponent { volume, vertex };
            out.push(decision(mesh, &mesh.triangles, &comp, kind, comp.len()));
        }
    }
    retain_marked(&mut mesh.triangles, balls, &live);
    out
}

/// The volume enclosed by the closed triangles `comp` (absolute value of the signed volume,
/// relative to their first vertex).
pub(crate) fn enclosed_volume(mesh: &TriMesh, comp: &[usize]) -> f64 {
    let Some(&first) = comp.first() else {
        return 0.0;
    };
    let o = mesh.vertices[mesh.triangles[first][0] as usize];
    let s: f64 = comp
        .iter()
        .map(|&i| {
            let [a, b, c] = mesh.triangles[i].map(|v| mesh.vertices[v as usize] - o);
            a.dot(b.cross(c))
        })
        .sum();
    (s / 6.0).abs()
}

/// Apply the repair to a run's result when `opts` asks for it (rules 1 to 3 only with a
/// resolution, i.e. on images; rule 4 with `min_component`), and bring its figures up to
/// date: the non-manifold counts are measured again on the repaired mesh, and the decisions
/// that changed Del_S(E) are reported unmet (the mesh is not Del_S(E) there).
/// `separate`: the vertices of rule 0 (`crate::levels::components::bridge_vertices`).
/// `labels`: the scan component of each vertex (rule 3'; empty for none).
pub(crate) fn apply(
    out: &mut crate::MeshResult,
    opts: &crate::MeshOptions,
    separate: &[u32],
    labels: &[Option<usize>],
) {
    let decisions = match (opts.resolution, opts.min_component) {
        (Some(_), m) => repair(
            &mut out.mesh,
            &mut out.balls,
            m,
            separate,
            labels,
            Some(&opts.criteria),
        ),
        (None, Some(m)) => {
            let d = drop_small(&mut out.mesh, &mut out.balls, m);
            if !d.is_empty() {
                compact(&mut out.mesh);
            }
            d
        }
        (None, None) => return,
    };
    if decisions.is_empty() {
        return;
    }
    let st = &mut out.stats;
    let (e, v) = crate::topology::nonmanifold_elements(&out.mesh.triangles);
    st.vertices = out.mesh.vertices.len();
    st.facets = out.mesh.triangles.len();
    st.nonmanifold_edges = e.len();
    st.nonmanifold_vertices = v.len();
    st.unmet
        .retain(|u| !matches!(u, crate::Unmet::Manifold { .. }));
    if st.nonmanifold_edges + st.nonmanifold_vertices > 0 {
        st.unmet.push(crate::Unmet::Manifold {
            edges: st.nonmanifold_edges,
            vertices: st.nonmanifold_vertices,
        });
    }
    let changed = decisions
        .iter()
        .filter(|d| !matches!(d.kind, DecisionKind::DropSmallComponent { .. }))
        .count();
    if changed > 0 {
        st.unmet.push(crate::Unmet::Repaired { decisions: changed });
        st.criteria_met = false;
    }
    st.topology_decisions = decisions;
    if changed > 0 {
        measure_angles(out, opts);
    }
}

/// The smallest angle and the largest r / sigma of a run's mesh measured again after
/// triangles that are not restricted facets were added (closings, tubes), and `unmet: angle`
/// and `unmet: size` brought up to date with them.
pub(super) fn measure_angles(out: &mut crate::MeshResult, opts: &crate::MeshOptions) {
    measure_sizes(out, opts);
    let min_angle = out
        .mesh
        .triangles
        .iter()
        .map(|t| crate::criteria::min_angle_deg(t.map(|v| out.mesh.vertices[v as usize])))
        .fold(f64::INFINITY, f64::min);
    if !min_angle.is_finite() {
        return;
    }
    out.stats.min_angle_deg = min_angle;
    record_min_angle(&mut out.stats, opts.criteria.min_angle_deg);
}

/// The smallest angle of the mesh written (`st.min_angle_deg`, measured) against `bound`,
/// into `unmet: angle` (replaced, or removed when the bound holds).
pub(crate) fn record_min_angle(st: &mut crate::Stats, bound: f64) {
    let min_angle = st.min_angle_deg;
    if min_angle >= bound {
        // Edits after the decisions (`skinny`) can bring every triangle back over the bound.
        st.unmet
            .retain(|u| !matches!(u, crate::Unmet::Angle { .. }));
        return;
    }
    let mut has_angle = false;
    for u in st.unmet.iter_mut() {
        if let crate::Unmet::Angle { min_angle_deg, .. } = u {
            *min_angle_deg = min_angle;
            has_angle = true;
        }
    }
    if bound > 0.0 && min_angle < bound && !has_angle {
        st.unmet.push(crate::Unmet::Angle {
            min_angle_deg: min_angle,
            bound_deg: bound,
        });
    }
}

/// The largest r / sigma over the balls of the mesh's triangles (circumballs for the
/// triangles the repair and the bridges added), into the figures and `unmet: size`.
fn measure_sizes(out: &mut crate::MeshResult, opts: &crate::MeshOptions) {
    if out.balls.len() != out.mesh.triangles.len() {
        return;
    }
    let Some(m) = out
        .balls
        .iter()
        .filter_map(|b| opts.criteria.sigma_at(b.center).map(|s| b.radius / s))
        .reduce(f64::max)
    else {
        return;
    };
    record_max_r_over_sigma(&mut out.stats, m);
}

/// `m`, the largest r / sigma measured on the mesh written, into the figures and
/// `unmet: size` (which it replaces).
pub(crate) fn record_max_r_over_sigma(st: &mut crate::Stats, m: f64) {
    st.max_r_over_sigma = Some(m);
    st.unmet.retain(|u| !matches!(u, crate::Unmet::Size { .. }));
    if m > 1.0 {
        st.unmet.insert(
            0,
            crate::Unmet::Size {
                max_r_over_sigma: m,
            },
        );
        st.criteria_met = false;
    }
}

/// Rule 3': the pairs of loops (indices into `loops`) to join by a tube: the only two loops
/// of one cluster of cut triangles, on two different components of the kept triangles, whose
/// vertices' most frequent scan label is the same component.
fn neck_pairs(
    tris: &[[u32; 3]],
    cut: &[usize],
    kept: &[[u32; 3]],
    loops: &[Vec<u32>],
    labels: &[Option<usize>],
    n: usize,
) -> Vec<(usize, usize)> {
    if labels.is_empty() || loops.len() < 2 {
        return Vec::new();
    }
    let mut clusters = crate::topology::VertexUnion::new(n);
    for &i in cut {
        clusters.join_triangle(tris[i]);
    }
    let mut pieces = crate::topology::VertexUnion::new(n);
    for t in kept {
        pieces.join_triangle(*t);
    }
    // The most frequent label of a loop's vertices (ties to the lowest), if any.
    let label = |lp: &[u32]| {
        let mut votes: std::collections::BTreeMap<usize, usize> = Default::default();
        for &v in lp {
            if let Some(Some(l)) = labels.get(v as usize) {
                *votes.entry(*l).or_default() += 1;
            }
        }
        votes
            .into_iter()
            .max_by_key(|&(l, c)| (c, std::cmp::Reverse(l)))
            .map(|(l, _)| l)
    };
    let mut by_cluster: std::collections::BTreeMap<u32, Vec<usize>> = Default::default();
    for (k, lp) in loops.iter().enumerate() {
        if lp.len() >= 3 {
            by_cluster.entry(clusters.find(lp[0])).or_default().push(k);
        }
    }
    let mut out = Vec::new();
    for ks in by_cluster.values() {
        let &[a, b] = ks.as_slice() else {
            continue;
        };
        // The cut must have disconnected them.
        if pieces.find(loops[a][0]) == pieces.find(loops[b][0]) {
            continue;
        }
        match (label(&loops[a]), label(&loops[b])) {
            (Some(x), Some(y)) if x == y => out.push((a, b)),
            _ => {}
        }
    }
    out
}

/// Add the edges of `tris` to `edges`.
fn add_edges(tris: &[[u32; 3]], edges: &mut HashSet<[u32; 2]>) {
    for t in tris {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            edges.insert([a.min(b), a.max(b)]);
        }
    }
}

/// Keep the triangles that `keep` marks and their balls (`balls` parallel to `triangles`).
pub(crate) fn retain_marked(
    triangles: &mut Vec<[u32; 3]>,
    balls: &mut Vec<SurfaceBall>,
    keep: &[bool],
) {
    let mut k = 0;
    triangles.retain(|_| {
        k += 1;
        keep[k - 1]
    });
    let mut k = 0;
    balls.retain(|_| {
        k += 1;
        keep[k - 1]
    });
}

/// Drop the vertices no triangle uses (keeping the order of the others).
pub(crate) fn compact(mesh: &mut TriMesh) {
    let mut remap = vec![u32::MAX; mesh.vertices.len()];
    for t in &mesh.triangles {
        for &v in t {
            remap[v as usize] = 0;
        }
    }
    let mut verts = Vec::new();
    for (v, r) in remap.iter_mut().enumerate() {
        if *r == 0 {
            *r = verts.len() as u32;
            verts.push(mesh.vertices[v]);
        }
    }
    for t in mesh.triangles.iter_mut() {
        *t = t.map(|v| remap[v as usize]);
    }
    mesh.vertices = verts;
}

#[cfg(test)]
mod tests;
