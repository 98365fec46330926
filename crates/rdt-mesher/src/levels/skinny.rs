//! Skinny triangles at the topological decisions (ours; section 6.1's angle criterion, which
//! the repair's closings and tubes and the bridges do not keep): local edits of the output,
//! on images, after every decision.
//!
//! The triangles the repair and the bridges add are not restricted facets and the refinement
//! never judged them; a least-area closing of a pinched loop is full of needles (one short
//! edge) and caps (one angle near 180 degrees). Each triangle below the angle bound is
//! offered three kinds of edit, worst triangle first, in passes until a pass changes nothing
//! (at most [`PASSES`]), and the one whose created triangles have the largest smallest angle
//! is made:
//! - **collapse** one of its edges shorter than `max_move` (half a voxel) into one of its
//!   ends, or into the crossing of S nearest to its midpoint (along the mean normal of its
//!   two triangles);
//! - **move** one of its corners to S: from its position, all or half of the way to the mean
//!   of its neighbours, then along its star's normal to the nearest crossing of S (the
//!   oracle's intersection oracle, section 6.4.2), so every vertex stays a point of S (or,
//!   for the repair's centroid vertices, becomes one), on an image on the same component of
//!   the voxel scan;
//! - **flip** one of its edges, when the two triangles at it are nearly coplanar.
//!
//! An edit is made only when all of these hold (the invariants the output keeps):
//! - the smallest angle of the triangles it creates is larger than that of the triangles it
//!   removes (so the worst angle of the mesh never gets worse, and the passes end);
//! - the result is a closed oriented 2-manifold of the same topology (components and genus):
//!   a collapse keeps the
//!   link condition (the two ends share exactly the two opposite vertices), no created
//!   triangle repeats an existing one, no created triangle is degenerate (exact test);
//! - no created triangle turns by more than [`MAX_TURN_DEG`] from the one it replaces
//!   (collapse, move) or from the pair's mean normal (flip), and a flip's two triangles are
//!   within [`MAX_FLIP_DIHEDRAL_DEG`] of coplanar;
//! - the surface moves by at most `max_move` (half a voxel): the collapsed edge, the moved
//!   vertex's displacement and the distance between a flip's two diagonals are at most that;
//! - no created triangle intersects another triangle of the mesh (exact test).
//!
//! A triangle that no edit improves is left as it is: `verify`'s `angles` check still sees it.

use crate::stats::SurfaceBall;
use geom::bvh::{Aabb, Bvh};
use glam::DVec3;
use meshio::TriMesh;

/// Passes over the skinny triangles (each pass edits every one it can; a pass with no edit
/// ends the loop earlier).
const PASSES: usize = 12;
/// The largest turn of a created triangle's normal (see the module docs).
const MAX_TURN_DEG: f64 = 60.0;
/// The largest dihedral turn between the two triangles of a flipped edge.
const MAX_FLIP_DIHEDRAL_DEG: f64 = 45.0;

/// What [`improve`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Edits {
    pub flips: usize,
    pub collapses: usize,
    pub moves: usize,
    /// Triangles below the bound before the edits and after them.
    pub below_before: usize,
    pub below_after: usize,
}

impl Edits {
    /// The edits made.
    pub fn made(&self) -> usize {
        self.flips + self.collapses + self.moves
    }
}

/// The kinds of edit (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    Flip,
    Collapse,
    Move,
}

/// One candidate edit: the triangles it removes and those it creates (oriented).
struct Edit {
    remove: Vec<u32>,
    create: Vec<[u32; 3]>,
    kind: Kind,
}

/// The mesh being edited: triangles are never moved, only marked dead or appended.
struct Work<'s> {
    /// Positions: the mesh's, then the candidate positions of relocated vertices.
    verts: Vec<DVec3>,
    surface: &'s dyn oracle::Surface,
    tris: Vec<[u32; 3]>,
    alive: Vec<bool>,
    /// The live triangles at each vertex.
    star: Vec<Vec<u32>>,
    /// Boxes of the triangles there at the start.
    bvh: Bvh,
    initial: usize,
    /// The triangles created since, by the cells of a grid their boxes overlap.
    created: Grid,
}

/// A uniform grid of triangle boxes (the created triangles: few, small, added one by one).
struct Grid {
    cell: f64,
    cells: rustc_hash::FxHashMap<[i64; 3], Vec<u32>>,
}

impl Grid {
    fn range(&self, b: &Aabb) -> impl Iterator<Item = [i64; 3]> + use<> {
        let lo = (b.min / self.cell).floor().as_i64vec3();
        let hi = (b.max / self.cell).floor().as_i64vec3();
        (lo.x..=hi.x).flat_map(move |x| {
            (lo.y..=hi.y).flat_map(move |y| (lo.z..=hi.z).map(move |z| [x, y, z]))
        })
    }

    fn insert(&mut self, b: &Aabb, t: u32) {
        for k in self.range(b).collect::<Vec<_>>() {
            self.cells.entry(k).or_default().push(t);
        }
    }

    /// Every triangle whose cells meet `b`'s (some more than once).
    fn near(&self, b: &Aabb) -> Vec<u32> {
        self.range(b)
            .filter_map(|k| self.cells.get(&k))
            .flatten()
            .copied()
            .collect()
    }
}

/// On an image (a run with a resolution h) with topological decisions: [`improve`] with the run's angle bound and
/// collapses and moves up to h / 2, its edits counted in the figures (`skinny_flips`,
/// `skinny_collapses`, `skinny_moves`), the vertices, facets, smallest angle and largest r / sigma measured
/// again.
pub(crate) fn apply(
    out: &mut crate::MeshResult,
    surface: &dyn oracle::Surface,
    opts: &crate::MeshOptions,
) {
    let Some(h) = opts.resolution else {
        return;
    };
    if out.stats.topology_decisions.is_empty() {
        // Every triangle is a restricted facet, judged by the refinement.
        return;
    }
    let bound = opts.criteria.min_angle_deg;
    let e = improve(&mut out.mesh, &mut out.balls, surface, bound, 0.5 * h);
    let st = &mut out.stats;
    st.skinny_before = e.below_before;
    st.skinny_after = e.below_after;
    if e.made() == 0 {
        return;
    }
    st.skinny_flips = e.flips;
    st.skinny_collapses = e.collapses;
    st.skinny_moves = e.moves;
    st.vertices = out.mesh.vertices.len();
    st.facets = out.mesh.triangles.len();
    super::repair::measure_angles(out, opts);
}

/// Improve the triangles of `mesh` whose smallest angle is below `bound_deg` by the edits of
/// the module docs; `balls` follow the triangles (a created triangle gets its circumball).
/// Unreferenced vertices are removed. `mesh` must be a closed oriented 2-manifold.
pub(crate) fn improve(
    mesh: &mut TriMesh,
    balls: &mut Vec<SurfaceBall>,
    surface: &dyn oracle::Surface,
    bound_deg: f64,
    max_move: f64,
) -> Edits {
    let mut edits = Edits::default();
    use rayon::prelude::*;
    let below = |m: &TriMesh| {
        m.triangles
            .par_iter()
            .filter(|t| angle(&m.vertices, **t) < bound_deg)
            .count()
    };
    if bound_deg <= 0.0 {
        return edits;
    }
    edits.below_before = below(mesh);
    edits.below_after = edits.below_before;
    if edits.below_before == 0 {
        return edits;
    }
    // The grid's cell: the triangles' mean longest edge (a created triangle meets a few cells).
    let longest = |t: &[u32; 3]| {
        let p = t.map(|v| mesh.vertices[v as usize]);
        (0..3)
            .map(|i| p[i].distance(p[(i + 1) % 3]))
            .fold(0.0, f64::max)
    };
    let cell = mesh.triangles.iter().map(longest).sum::<f64>() / mesh.triangles.len() as f64;
    let mut w = Work::new(&mesh.vertices, &mesh.triangles, surface, cell.max(max_move));
    // A triangle's corners never move (a moved vertex is a new one), so the skinny ones of a
    // pass are those of the last pass still alive and the skinny ones created since.
    let (mut bad, mut scanned) = (Vec::<(f64, u32)>::new(), 0);
    // When each skinny triangle was last offered edits (the triangle count then): it is
    // offered them again only when a triangle was created at one of its corners since.
    let mut tried = rustc_hash::FxHashMap::<u32, u32>::default();
    for _ in 0..PASSES {
        bad.retain(|&(_, t)| w.alive[t as usize]);
        let fresh: Vec<(f64, u32)> = (scanned as u32..w.tris.len() as u32)
            .into_par_iter()
            .filter(|&t| w.alive[t as usize])
            .map(|t| (angle(&w.verts, w.tris[t as usize]), t))
            .filter(|&(a, _)| a < bound_deg)
            .collect();
        bad.extend(fresh);
        scanned = w.tris.len();
        bad.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
        let before = edits.made();
        for &(_, t) in &bad {
            if !w.alive[t as usize] || !w.changed_since(t, &tried) {
                continue;
            }
            tried.insert(t, w.tris.len() as u32);
            if let Some(e) = w.best_edit(t, max_move) {
                match e.kind {
                    Kind::Flip => edits.flips += 1,
                    Kind::Collapse => edits.collapses += 1,
                    Kind::Move => edits.moves += 1,
                }
                w.apply(e);
            }
        }
        if edits.made() == before {
            break;
        }
    }
    if edits.made() == 0 {
        return edits;
    }
    let old_balls = std::mem::take(balls);
    let mut tris = Vec::with_capacity(w.tris.len());
    for (i, t) in w.tris.iter().enumerate() {
        if !w.alive[i] {
            continue;
        }
        tris.push(*t);
        balls.push(match old_balls.get(i) {
            Some(b) if i < w.initial => *b,
            _ => super::repair::circumball(t.map(|v| w.verts[v as usize])),
        });
    }
    mesh.triangles = tris;
    mesh.vertices = w.verts;
    super::repair::compact(mesh);
    edits.below_after = below(mesh);
    edits
}

/// The smallest angle of triangle `t`, in degrees.
fn angle(verts: &[DVec3], t: [u32; 3]) -> f64 {
    crate::criteria::min_angle_deg(t.map(|v| verts[v as usize]))
}

/// The unit normal of `t` (zero when degenerate).
fn normal(verts: &[DVec3], t: [u32; 3]) -> DVec3 {
    let [a, b, c] = t.map(|v| verts[v as usize]);
    (b - a).cross(c - a).normalize_or_zero()
}

impl<'s> Work<'s> {
    /// `cell`: the created triangles' grid cell (about their size).
    fn new(
        verts: &[DVec3],
        tris: &[[u32; 3]],
        surface: &'s dyn oracle::Surface,
        cell: f64,
    ) -> Self {
        let mut star = vec![Vec::new(); verts.len()];
        for (i, t) in tris.iter().enumerate() {
            t.iter().for_each(|&v| star[v as usize].push(i as u32));
        }
        use rayon::prelude::*;
        let boxes = tris
            .par_iter()
            .map(|t| Aabb::from_points(&t.map(|v| verts[v as usize])))
            .collect();
        Work {
            verts: verts.to_vec(),
            surface,
            tris: tris.to_vec(),
            alive: vec![true; tris.len()],
            star,
            bvh: Bvh::new(boxes),
            initial: tris.len(),
            created: Grid {
                cell,
                cells: Default::default(),
            },
        }
    }

    /// Was a triangle created at a corner of `t` since `t` was last offered edits?
    fn changed_since(&self, t: u32, tried: &rustc_hash::FxHashMap<u32, u32>) -> bool {
        tried.get(&t).is_none_or(|&then| {
            self.tris[t as usize]
                .iter()
                .any(|&v| self.star[v as usize].iter().any(|&s| s >= then))
        })
    }

    /// The live triangle holding the directed edge `a -> b`.
    fn with_edge(&self, a: u32, b: u32) -> Option<u32> {
        self.star[a as usize].iter().copied().find(|&t| {
            let tr = self.tris[t as usize];
            (0..3).any(|i| tr[i] == a && tr[(i + 1) % 3] == b)
        })
    }

    /// The third vertex of `t` beside `a` and `b`.
    fn third(&self, t: u32, a: u32, b: u32) -> u32 {
        let tr = self.tris[t as usize];
        tr.into_iter().find(|&v| v != a && v != b).unwrap_or(a)
    }

    fn neighbours(&self, v: u32) -> Vec<u32> {
        let mut n: Vec<u32> = self.star[v as usize]
            .iter()
            .flat_map(|&t| self.tris[t as usize])
            .filter(|&u| u != v)
            .collect();
        n.sort_unstable();
        n.dedup();
        n
    }

    /// The best edit of triangle `t` (largest smallest angle created) that improves it.
    fn best_edit(&mut self, t: u32, max_move: f64) -> Option<Edit> {
        let tr = self.tris[t as usize];
        let mut candidates = Vec::new();
        for i in 0..3 {
            let (a, b) = (tr[i], tr[(i + 1) % 3]);
            candidates.push(self.flip(a, b, max_move));
            candidates.push(self.relocate(a, 1.0, max_move));
            candidates.push(self.relocate(a, 0.5, max_move));
            if self.verts[a as usize].distance(self.verts[b as usize]) <= max_move {
                candidates.push(self.collapse(b, a));
                candidates.push(self.collapse(a, b));
                candidates.push(self.collapse_to_middle(a, b, max_move));
            }
        }
        // The exact tests only for the best gains, in decreasing order (ties: the first).
        let mut ranked: Vec<(f64, Edit)> = candidates
            .into_iter()
            .flatten()
            .filter_map(|e| Some((self.gain(&e)?, e)))
            .collect();
        ranked.sort_by(|x, y| y.0.total_cmp(&x.0));
        ranked.into_iter().map(|(_, e)| e).find(|e| self.valid(e))
    }

    /// Flip the edge `a -> b` (of a live triangle) if its two triangles are nearly coplanar
    /// and the new diagonal passes within `max_move` of the old one.
    fn flip(&self, a: u32, b: u32, max_move: f64) -> Option<Edit> {
        let (t1, t2) = (self.with_edge(a, b)?, self.with_edge(b, a)?);
        let (c, d) = (self.third(t1, a, b), self.third(t2, a, b));
        if c == d || self.neighbours(c).binary_search(&d).is_ok() {
            return None;
        }
        let (n1, n2) = (
            normal(&self.verts, self.tris[t1 as usize]),
            normal(&self.verts, self.tris[t2 as usize]),
        );
        if n1.dot(n2) < MAX_FLIP_DIHEDRAL_DEG.to_radians().cos() {
            return None;
        }
        // The two diagonals' distance: how far the flip moves the surface.
        let [pa, pb, pc, pd] = [a, b, c, d].map(|v| self.verts[v as usize]);
        let axis = (pb - pa).cross(pd - pc);
        if axis.length() == 0.0 || (pc - pa).dot(axis).abs() > max_move * axis.length() {
            return None;
        }
        let create = vec![[a, d, c], [d, b, c]];
        let mean = (n1 + n2).normalize_or_zero();
        let turn = MAX_TURN_DEG.to_radians().cos();
        if create
            .iter()
            .any(|&n| normal(&self.verts, n).dot(mean) < turn)
        {
            return None;
        }
        Some(Edit {
            remove: vec![t1, t2],
            create,
            kind: Kind::Flip,
        })
    }

    /// Move vertex `v` by `step` of the way to the mean of its neighbours, then along the
    /// normal of its star to the nearest point of S, if that is within `max_move` of it (a
    /// new vertex takes its triangles: `v` is left unreferenced).
    fn relocate(&mut self, v: u32, step: f64, max_move: f64) -> Option<Edit> {
        let link = self.neighbours(v);
        if link.is_empty() {
            return None;
        }
        let mean = link.iter().map(|&u| self.verts[u as usize]).sum::<DVec3>() / link.len() as f64;
        let q = self.verts[v as usize].lerp(mean, step);
        let n = self.star[v as usize]
            .iter()
            .map(|&t| {
                let [a, b, c] = self.tris[t as usize].map(|u| self.verts[u as usize]);
                (b - a).cross(c - a)
            })
            .sum::<DVec3>()
            .normalize_or_zero();
        let reach = link
            .iter()
            .map(|&u| self.verts[u as usize].distance(q))
            .sum::<f64>()
            / link.len() as f64;
        let p = self.project_along(q, n, reach)?;
        let old = self.verts[v as usize];
        if p.distance(old) > max_move || p == old || !self.same_part(v, p) {
            return None;
        }
        let w = self.add_vertex(p);
        self.replace_vertices(&[v], w, &[], Kind::Move)
    }

    /// The crossing of S nearest to `q` on the segment of half-length `reach` along `n`.
    fn project_along(&self, q: DVec3, n: DVec3, reach: f64) -> Option<DVec3> {
        if n == DVec3::ZERO {
            return None;
        }
        let mut hits = Vec::new();
        self.surface
            .crossings(q - reach * n, q + reach * n, &mut hits);
        hits.into_iter()
            .min_by(|x, y| x.distance_squared(q).total_cmp(&y.distance_squared(q)))
    }

    /// A new vertex at `p` (unreferenced until an edit that uses it is made).
    fn add_vertex(&mut self, p: DVec3) -> u32 {
        self.verts.push(p);
        self.star.push(Vec::new());
        self.verts.len() as u32 - 1
    }

    /// The edit that gives the triangles of the stars of `vs` but those of `skip` the vertex
    /// `w` in place of any of `vs` (and removes the whole stars), if no triangle turns by
    /// more than [`MAX_TURN_DEG`].
    fn replace_vertices(&self, vs: &[u32], w: u32, skip: &[u32], kind: Kind) -> Option<Edit> {
        let turn = MAX_TURN_DEG.to_radians().cos();
        let mut remove: Vec<u32> = vs
            .iter()
            .flat_map(|&v| self.star[v as usize].iter().copied())
            .collect();
        remove.sort_unstable();
        remove.dedup();
        let mut create = Vec::new();
        for &t in &remove {
            if skip.contains(&t) {
                continue;
            }
            let old = self.tris[t as usize];
            let new = old.map(|u| if vs.contains(&u) { w } else { u });
            if normal(&self.verts, new).dot(normal(&self.verts, old)) < turn {
                return None;
            }
            create.push(new);
        }
        Some(Edit {
            remove,
            create,
            kind,
        })
    }

    /// On an image, does `p` lie on the voxel scan's component of vertex `v` (or, when `v`
    /// is on none, such as a closing's centroid vertex, on one of its neighbours')? A move
    /// must not carry a vertex to another component of S (a speck within half a voxel):
    /// that would join the two (the repair's rule 0).
    fn same_part(&self, v: u32, p: DVec3) -> bool {
        let Some(img) = self.surface.as_image() else {
            return true;
        };
        let to = img.component_of(p);
        match img.component_of(self.verts[v as usize]) {
            Some(c) => to == Some(c),
            None => {
                to.is_some()
                    && self
                        .neighbours(v)
                        .iter()
                        .any(|&u| img.component_of(self.verts[u as usize]) == to)
            }
        }
    }

    /// Collapse the edge `a b` into the crossing of S nearest to its midpoint along the
    /// mean normal of its two triangles, if the link condition holds and neither end moves
    /// by more than `max_move`.
    fn collapse_to_middle(&mut self, a: u32, b: u32, max_move: f64) -> Option<Edit> {
        let (t1, t2) = self.collapsible(a, b)?;
        let (pa, pb) = (self.verts[a as usize], self.verts[b as usize]);
        let n = (normal(&self.verts, self.tris[t1 as usize])
            + normal(&self.verts, self.tris[t2 as usize]))
        .normalize_or_zero();
        let mid = 0.5 * (pa + pb);
        let p = self.project_along(mid, n, max_move)?;
        if p.distance(pa).max(p.distance(pb)) > max_move || !self.same_part(a, p) {
            return None;
        }
        let w = self.add_vertex(p);
        self.replace_vertices(&[a, b], w, &[t1, t2], Kind::Collapse)
    }

    /// The two triangles at the edge `a b` when it may be collapsed: the link condition
    /// (the ends share exactly the two opposite vertices).
    fn collapsible(&self, a: u32, b: u32) -> Option<(u32, u32)> {
        let (t1, t2) = (self.with_edge(a, b)?, self.with_edge(b, a)?);
        let (c, d) = (self.third(t1, a, b), self.third(t2, a, b));
        let nb = self.neighbours(b);
        let common: Vec<u32> = self
            .neighbours(a)
            .into_iter()
            .filter(|v| nb.binary_search(v).is_ok())
            .collect();
        let mut want = [c, d];
        want.sort_unstable();
        (c != d && common == want).then_some((t1, t2))
    }

    /// Collapse vertex `b` into its neighbour `a`, if the link condition holds.
    fn collapse(&self, b: u32, a: u32) -> Option<Edit> {
        let (t1, t2) = self.collapsible(a, b)?;
        self.replace_vertices(&[b], a, &[t1, t2], Kind::Collapse)
    }

    /// The smallest angle `e` creates, if it is larger than the smallest angle of the
    /// triangles it removes (for a collapse, the removed end's star).
    fn gain(&self, e: &Edit) -> Option<f64> {
        let removed_min = e
            .remove
            .iter()
            .map(|&t| angle(&self.verts, self.tris[t as usize]))
            .fold(f64::INFINITY, f64::min);
        let created_min = e
            .create
            .iter()
            .map(|&t| angle(&self.verts, t))
            .fold(f64::INFINITY, f64::min);
        (created_min > removed_min && created_min.is_finite()).then_some(created_min)
    }

    /// The exact conditions of the module docs: no created triangle is degenerate, repeats a
    /// triangle or crosses one.
    fn valid(&self, e: &Edit) -> bool {
        let p = |v: u32| self.verts[v as usize];
        let flat = e
            .create
            .iter()
            .any(|t| geom::predicates::collinear(p(t[0]), p(t[1]), p(t[2])));
        !flat && !self.repeats(e) && !self.crosses(e)
    }

    /// Does a created triangle repeat a live one (not removed) or another created one?
    fn repeats(&self, e: &Edit) -> bool {
        let key = |t: [u32; 3]| {
            let mut k = t;
            k.sort_unstable();
            k
        };
        let created: Vec<[u32; 3]> = e.create.iter().map(|&t| key(t)).collect();
        for (i, k) in created.iter().enumerate() {
            if created[..i].contains(k) {
                return true;
            }
            let live = self.star[k[0] as usize]
                .iter()
                .any(|&t| e.remove.binary_search(&t).is_err() && key(self.tris[t as usize]) == *k);
            if live {
                return true;
            }
        }
        false
    }

    /// Does a created triangle intersect a live triangle (not removed) or another created
    /// one, other than along shared vertices and edges (exact)?
    fn crosses(&self, e: &Edit) -> bool {
        use verify::intersect::triangles_intersect;
        let kept = |t: u32| self.alive[t as usize] && e.remove.binary_search(&t).is_err();
        for (i, &n) in e.create.iter().enumerate() {
            if e.create[..i]
                .iter()
                .any(|&m| triangles_intersect(&self.verts, n, m))
            {
                return true;
            }
            let bx = Aabb::from_points(&n.map(|v| self.verts[v as usize]));
            let mut hit = false;
            self.bvh.for_each_overlap(&bx, |t| {
                hit =
                    hit || (kept(t) && triangles_intersect(&self.verts, n, self.tris[t as usize]));
            });
            if hit {
                return true;
            }
            for t in self.created.near(&bx) {
                let tr = self.tris[t as usize];
                if kept(t) && triangles_intersect(&self.verts, n, tr) {
                    return true;
                }
            }
        }
        false
    }

    fn apply(&mut self, e: Edit) {
        for &t in &e.remove {
            self.alive[t as usize] = false;
            for v in self.tris[t as usize] {
                self.star[v as usize].retain(|&s| s != t);
            }
        }
        for t in e.create {
            let id = self.tris.len() as u32;
            self.tris.push(t);
            self.alive.push(true);
            t.iter().for_each(|&v| self.star[v as usize].push(id));
            let b = Aabb::from_points(&t.map(|v| self.verts[v as usize]));
            self.created.insert(&b, id);
        }
    }
}

#[cfg(test)]
mod tests;
