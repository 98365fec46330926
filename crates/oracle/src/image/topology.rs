//! P1 for images: components of the trilinear level set from the voxel grid, and seed points.
//!
//! Grid nodes (voxel centres) are *inside* when their value is `< 0`. The grid is padded by
//! one layer of background nodes (outside), all joined into one *exterior* node.
//!
//! **Connectivity.** Two nodes of the same sign are joined when they are 6-neighbours (the grid
//! edge between them is linear, so it never leaves their side), or when they are the diagonal
//! of an ambiguous face and the bilinear saddle of that face is on their side (the asymptotic
//! decider: the inside pair is joined if the saddle value is `< 0`, the outside pair otherwise).
//! These are exact connections of the trilinear interpolant's inside and outside regions, so
//! every component of the node sets lies in one true region. The only connection not detected
//! is an interior tunnel through a cell (a body-diagonal pair joined through the cell's
//! interior), so the counts are exact except in that rare case, where they are too high.
//!
//! **Surface components.** The regions of R³ \ S form a tree (each closed surface separates
//! space in two), so #surface components = #inside regions + #outside regions - 1.
//!
//! **Seeds.** Every surface component crosses a grid edge (the trilinear interpolant is
//! harmonic, so a component inside one cell would break the maximum principle; a component
//! meeting only face interiors would give a closed curve inside a face, same argument). For
//! every pair (inside component, outside component) joined by a sign-changing edge we keep the
//! first such edge in scan order; its crossing (exact: the interpolant is linear along an
//! edge) lies on the unique surface component separating the two regions, so every surface
//! component gets a seed. Up to 4096 other crossings are kept at a regular stride for extra
//! seeds.
//!
//! **Seed tetrahedra.** A component is meshed only once one of its facets is restricted,
//! i.e. a Voronoi vertex of the sample lies in the region it encloses. For the smallest
//! components the seed is replaced by four points of the component (crossings of its extreme
//! grid edges, and of rays from its deepest node) whose circumcentre lies in that region:
//! the tetrahedron's four facets are restricted from the first insertion. On the nilearn
//! fixture at iso 3 (10 components, 7 of them 1 to 13 voxels), the mesher missed 1 to 4
//! components with a single seed each (seeds 0-7), none with the tetrahedra. The scan of node signs runs in parallel (rayon); union-find and the collection are
//! sequential in index order, so the result does not depend on the thread count.

use super::ImageSurface;
use crate::Surface;
use crate::roots::SplitMix64;
use glam::DVec3;
use std::collections::BTreeMap;

/// Components of the level set found on the voxel grid, and on-surface seed points.
#[derive(Clone, Debug, PartialEq)]
pub struct Topology {
    /// Connected components of the inside (value < 0) region.
    pub inside_components: usize,
    /// Connected components of the outside region, including the unbounded one.
    pub outside_components: usize,
    /// Connected components of the surface: `inside + outside - 1`.
    pub surface_components: usize,
    /// Number of grid edges (including edges to the padding) with a sign change.
    pub crossing_edges: usize,
    /// One world-space point on each pair (inside component, outside component) that touch:
    /// at least one per surface component.
    pub component_seeds: Vec<DVec3>,
    /// Number of crossing edges of each pair of `component_seeds` (a size measure: about the
    /// component's area in voxel faces).
    pub component_edges: Vec<usize>,
    /// For each of `component_seeds`: empty, or three more points of its component that form
    /// with the seed a tetrahedron whose circumcentre lies in the region the component
    /// encloses, near the seed (see [`Topology::seed_points_within`]). Built for the 256
    /// components with the fewest crossing edges: around the whole component if it spans at
    /// most 8 voxels, else around its seed.
    pub component_tets: Vec<Vec<DVec3>>,
    /// Further crossing points (world space), at a regular stride over the grid.
    pub extra_seeds: Vec<DVec3>,
}

impl Topology {
    /// [`Topology::seed_points_within`] the default budget [`Topology::SEED_BUDGET`] (64, the
    /// mesher's default number of control points).
    pub fn seed_points(&self, seed: u64) -> Vec<DVec3> {
        self.seed_points_within(seed, Self::SEED_BUDGET)
    }

    /// All component seeds, then the tetrahedra ([`Topology::component_tets`]) of the
    /// components in increasing size (fewest crossing edges first), as many as two thirds of
    /// the budget left by the seeds allow (three points each), then extra seeds chosen from
    /// `seed` (deterministic), up to `budget` points in all (more only when there are more
    /// components).
    ///
    /// The mesher thins longer lists than its `MeshOptions::max_control_points` (64 by
    /// default) by farthest-point selection, which would drop the close points of a
    /// tetrahedron first: keep `budget` at most that. With at most 64 components every
    /// component seed is kept. The tetrahedra matter for components smaller than the size
    /// bound: from one seed alone, the section 6.4.3 rays must land several points on a blob
    /// of a voxel or two before one of its Voronoi vertices falls inside it (no facet is
    /// restricted before), and often gave up; the tetrahedron's circumcentre is such a Voronoi
    /// vertex from the start. The extra seeds (the last third) seed the far side of necks
    /// thinner than the size bound on big components: with all of the budget in tetrahedra,
    /// more of the nilearn fixture's surface stayed unmeshed at iso 2.
    /// [`Topology::full_seed_budget`] fits every tetrahedron.
    pub fn seed_points_within(&self, seed: u64, budget: usize) -> Vec<DVec3> {
        let mut out = self.component_seeds.clone();
        let mut order: Vec<usize> = (0..self.component_seeds.len()).collect();
        order.sort_by_key(|&i| (self.component_edges.get(i).copied().unwrap_or(0), i));
        let mut room = budget.saturating_sub(out.len()) * 2 / 9;
        for i in order {
            if room == 0 {
                break;
            }
            if let Some(tet) = self.component_tets.get(i).filter(|t| !t.is_empty()) {
                out.extend_from_slice(tet);
                room -= 1;
            }
        }
        let k = budget.saturating_sub(out.len());
        let n = self.extra_seeds.len();
        if n <= k {
            out.extend_from_slice(&self.extra_seeds);
        } else if let Some(step) = n.checked_div(k) {
            let mut rng = SplitMix64(seed ^ 0x001A_A6E5_EED5);
            let start = (rng.next_u64() % n as u64) as usize;
            out.extend((0..k).map(|i| self.extra_seeds[(start + i * step) % n]));
        }
        out
    }

    /// The smallest budget for [`Topology::seed_points_within`] that takes every seed
    /// tetrahedron (at least [`Topology::SEED_BUDGET`]); pass the mesher as many control
    /// points.
    pub fn full_seed_budget(&self) -> usize {
        let n = self.component_seeds.len();
        let tets = self.component_tets.iter().filter(|t| !t.is_empty()).count();
        Self::SEED_BUDGET.max(n + (9 * tets).div_ceil(2) + 1)
    }

    /// Total number of seed points [`Topology::seed_points`] aims at.
    pub const SEED_BUDGET: usize = 64;
}

struct Dsu(Vec<u32>);
impl Dsu {
    #[inline]
    fn find(&mut self, mut x: u32) -> u32 {
        while self.0[x as usize] != x {
            let p = self.0[x as usize];
            self.0[x as usize] = self.0[p as usize];
            x = p;
        }
        x
    }
    #[inline]
    fn union(&mut self, a: u32, b: u32) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            let (lo, hi) = if ra < rb { (ra, rb) } else { (rb, ra) };
            self.0[hi as usize] = lo;
        }
    }
}

#[cfg(test)]
#[inline]
fn bit(bits: &[u64], i: usize) -> bool {
    (bits[i >> 6] >> (i & 63)) & 1 == 1
}

/// Node-by-node reference implementation (tests cross-check the run-based one against it).
#[cfg(test)]
pub(crate) fn compute_reference(s: &ImageSurface) -> Topology {
    let [nx, ny, nz] = s.dims_isize().map(|v| v as usize);
    let n = nx * ny * nz;
    let bits = s.inside_bits();
    let ins = |i: usize| bit(&bits, i);
    let ext = n as u32; // the exterior (padding) node
    let mut dsu = Dsu((0..=n as u32).collect());
    let (sy, sz) = (nx, nx * ny);
    // Asymptotic decider on the face with corners p00, p10 = p00 + u, p01 = p00 + v, p11.
    let face = |dsu: &mut Dsu, p00: usize, u: usize, v: usize| {
        let (a, b, c, d) = (ins(p00), ins(p00 + u), ins(p00 + v), ins(p00 + u + v));
        if a == d && b == c && a != b {
            let (f00, f10, f01, f11) = (
                s.node_value(p00),
                s.node_value(p00 + u),
                s.node_value(p00 + v),
                s.node_value(p00 + u + v),
            );
            let den = f00 + f11 - f10 - f01;
            let saddle = if den != 0.0 {
                (f00 * f11 - f10 * f01) / den
            } else {
                0.0
            };
            let inside_joined = saddle < 0.0;
            if inside_joined == a {
                dsu.union(p00 as u32, (p00 + u + v) as u32);
            } else {
                dsu.union((p00 + u) as u32, (p00 + v) as u32);
            }
        }
    };
    for k in 0..nz {
        for j in 0..ny {
            let row = j * sy + k * sz;
            for i in 0..nx {
                let p = row + i;
                let a = ins(p);
                let border =
                    i == 0 || j == 0 || k == 0 || i + 1 == nx || j + 1 == ny || k + 1 == nz;
                if border && !a {
                    dsu.union(p as u32, ext);
                }
                if i + 1 < nx && ins(p + 1) == a {
                    dsu.union(p as u32, (p + 1) as u32);
                }
                if j + 1 < ny && ins(p + sy) == a {
                    dsu.union(p as u32, (p + sy) as u32);
                }
                if k + 1 < nz && ins(p + sz) == a {
                    dsu.union(p as u32, (p + sz) as u32);
                }
                if i + 1 < nx && j + 1 < ny {
                    face(&mut dsu, p, 1, sy);
                }
                if i + 1 < nx && k + 1 < nz {
                    face(&mut dsu, p, 1, sz);
                }
                if j + 1 < ny && k + 1 < nz {
                    face(&mut dsu, p, sy, sz);
                }
            }
        }
    }
    // Count components: roots among inside nodes / outside nodes (+ exterior).
    let mut inside_components = 0;
    let mut outside_components = 0;
    for p in 0..=n {
        if dsu.find(p as u32) == p as u32 {
            if p < n && ins(p) {
                inside_components += 1;
            } else {
                outside_components += 1;
            }
        }
    }
    // Crossing edges: count, then collect pair seeds and strided extras.
    let mut edges = 0usize;
    let for_each_crossing = |f: &mut dyn FnMut(usize, isize, usize, [usize; 3])| {
        // (node p inside, axis, neighbour q or usize::MAX for padding, direction sign)
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    let p = i + j * sy + k * sz;
                    let a = ins(p);
                    let c = [i, j, k];
                    let dims = [nx, ny, nz];
                    let st = [1, sy, sz];
                    for ax in 0..3 {
                        // + direction: grid edge or padding.
                        if c[ax] + 1 < dims[ax] {
                            let q = p + st[ax];
                            if ins(q) != a {
                                f(p, ax as isize + 1, q, c);
                            }
                        } else if a {
                            f(p, ax as isize + 1, usize::MAX, c);
                        }
                        // - direction: padding only (grid edges are seen from the other end).
                        if c[ax] == 0 && a {
                            f(p, -(ax as isize) - 1, usize::MAX, c);
                        }
                    }
                }
            }
        }
    };
    for_each_crossing(&mut |_, _, _, _| edges += 1);
    let stride = edges.div_ceil(4096).max(1);
    let mut pairs = Pairs::default();
    let mut extra_edges = Vec::new();
    let mut count = 0usize;
    for_each_crossing(&mut |p, axd, q, c| {
        let rp = dsu.find(p as u32);
        let rq = if q == usize::MAX {
            dsu.find(ext)
        } else {
            dsu.find(q as u32)
        };
        let key = if ins(p) { (rp, rq) } else { (rq, rp) };
        pairs.add(key, (p, axd, q), c);
        if count.is_multiple_of(stride) {
            extra_edges.push((p, axd, q));
        }
        count += 1;
    });
    pairs.finish(
        s,
        dsu.find(ext),
        inside_components,
        outside_components,
        edges,
        extra_edges,
    )
}

/// An edge with a sign change: node `p`, axis and direction `axd` (±1, ±2, ±3 for x, y, z),
/// the other node `q` (or `usize::MAX` for the padding), and the runs of `p` and `q`.
type Edge = (usize, isize, usize);

/// Directions (in voxel axes) along which [`PairInfo`] keeps the extreme crossing edges: the
/// three axes and the four body diagonals.
const DIRS: [[i64; 3]; 7] = [
    [1, 0, 0],
    [0, 1, 0],
    [0, 0, 1],
    [1, 1, 1],
    [1, 1, -1],
    [1, -1, 1],
    [-1, 1, 1],
];

/// Seed tetrahedra are built for at most this many components (the smallest).
const MAX_TETS: usize = 256;

/// Components whose crossing edges span at most this many voxels along every axis are
/// *small*: their seed tetrahedron ([`Topology::component_tets`]) is chosen around the whole
/// component, else around its first crossing edge.
const SMALL_EXTENT_VOXELS: i64 = 8;

/// Per (inside region, outside region) pair that touch: the first crossing edge in scan order,
/// the number of crossing edges, and the extreme edges along [`DIRS`].
struct PairInfo {
    first: Edge,
    edges: usize,
    /// For direction `d`: `ext[2d]` has the lowest crossing (edge midpoint in half voxels,
    /// projected on `DIRS[d]`), `ext[2d + 1]` the highest; ties keep the first edge in scan
    /// order.
    ext: [(i64, Edge); 14],
}

/// The pairs met while scanning the crossing edges, keyed by their (inside, outside) roots.
#[derive(Default)]
struct Pairs {
    index: BTreeMap<(u32, u32), usize>,
    info: Vec<PairInfo>,
    last: Option<((u32, u32), usize)>,
}

impl Pairs {
    /// Record the crossing edge `e` (from node `c`, voxel coordinates) of the pair `key`.
    #[inline]
    fn add(&mut self, key: (u32, u32), e: Edge, c: [usize; 3]) {
        let eax = e.1.unsigned_abs() - 1;
        let mut m = [2 * c[0] as i64, 2 * c[1] as i64, 2 * c[2] as i64];
        m[eax] += e.1.signum() as i64;
        let proj = |d: usize| DIRS[d][0] * m[0] + DIRS[d][1] * m[1] + DIRS[d][2] * m[2];
        let i = match self.last {
            Some((k, i)) if k == key => i,
            _ => {
                let i = *self.index.entry(key).or_insert_with(|| {
                    self.info.push(PairInfo {
                        first: e,
                        edges: 0,
                        ext: std::array::from_fn(|k| (proj(k / 2), e)),
                    });
                    self.info.len() - 1
                });
                self.last = Some((key, i));
                i
            }
        };
        let p = &mut self.info[i];
        p.edges += 1;
        for d in 0..DIRS.len() {
            let v = proj(d);
            if v < p.ext[2 * d].0 {
                p.ext[2 * d] = (v, e);
            }
            if v > p.ext[2 * d + 1].0 {
                p.ext[2 * d + 1] = (v, e);
            }
        }
    }

    /// The topology, with pairs in key order (deterministic). `exterior` is the root of the
    /// unbounded outside region.
    fn finish(
        self,
        s: &ImageSurface,
        exterior: u32,
        inside_components: usize,
        outside_components: usize,
        edges: usize,
        extra_edges: Vec<Edge>,
    ) -> Topology {
        let [nx, ny, _] = s.dims_isize().map(|v| v as usize);
        let bg = s.background_value();
        let aff = s.volume().affine();
        let point = |(p, axd, q): Edge| -> DVec3 {
            let fp = s.node_value(p);
            let fq = if q == usize::MAX { bg } else { s.node_value(q) };
            let t = if fp != fq {
                (fp / (fp - fq)).clamp(0.0, 1.0)
            } else {
                0.5
            };
            let ax = axd.unsigned_abs() - 1;
            let mut dir = DVec3::ZERO;
            dir[ax] = axd.signum() as f64;
            let c = DVec3::new(
                (p % nx) as f64,
                ((p / nx) % ny) as f64,
                (p / (nx * ny)) as f64,
            );
            aff.transform_point3(c + dir * t)
        };
        let pairs: Vec<((u32, u32), &PairInfo)> = self
            .index
            .iter()
            .map(|(k, &i)| (*k, &self.info[i]))
            .collect();
        let depth = region_depths(pairs.iter().map(|p| p.0), exterior);
        // Tetrahedra for the smallest components, as many as the seed budget can take.
        let mut order: Vec<usize> = (0..pairs.len()).collect();
        order.sort_by_key(|&i| (pairs[i].1.edges, i));
        // Tetrahedra for the smallest components (bounded cost: up to a few thousand
        // circumcentres each).
        let room = MAX_TETS;
        let mut tets: Vec<Option<[DVec3; 4]>> = vec![None; pairs.len()];
        for &i in order.iter().take(room) {
            let (key, info) = pairs[i];
            // Small: the whole component is at most SMALL_EXTENT_VOXELS across; the tetrahedron
            // is chosen among its extreme crossings and rays from its deepest node. Otherwise
            // it is local to the first crossing edge (a small lobe there may be joined to the
            // rest by a neck thinner than the size bound, and missed like a small component).
            let extent = (0..3)
                .map(|a| info.ext[2 * a + 1].0 - info.ext[2 * a].0)
                .max()
                .unwrap_or(0);
            let small = extent <= 2 * SMALL_EXTENT_VOXELS;
            // The enclosed side is the region farther from the exterior.
            let d = |r: u32| depth.get(&r).copied().unwrap_or(0);
            // Sign of the value in the enclosed region: an inside blob or a cavity.
            let sign = if d(key.0) > d(key.1) { -1.0 } else { 1.0 };
            let mut cand: Vec<Edge> = vec![info.first];
            if small {
                for &(_, e) in &info.ext {
                    if !cand.contains(&e) {
                        cand.push(e);
                    }
                }
            }
            // The deepest enclosed node among the candidate edges' ends.
            let mut centre: Option<(f64, usize)> = None;
            for &(p, _, q) in &cand {
                for n in [p, q] {
                    if n == usize::MAX {
                        continue;
                    }
                    let v = sign * s.node_value(n);
                    if v > 0.0 && centre.is_none_or(|c| v > c.0) {
                        centre = Some((v, n));
                    }
                }
            }
            let mut pts: Vec<DVec3> = cand.into_iter().map(point).collect();
            if let Some((_, n)) = centre {
                // Crossings of rays from that node along the axes and body diagonals.
                let m = DVec3::new(
                    (n % nx) as f64,
                    ((n / nx) % ny) as f64,
                    (n / (nx * ny)) as f64,
                );
                let len = if small {
                    extent as f64 * 0.5 + 2.0
                } else {
                    3.0
                };
                for d in DIRS {
                    let u = DVec3::new(d[0] as f64, d[1] as f64, d[2] as f64).normalize();
                    for u in [u, -u] {
                        if let Some(c) = first_crossing(s, aff, m, u, len) {
                            pts.push(c);
                        }
                    }
                }
            }
            tets[i] = seed_tet(s, &pts, sign);
        }
        let mut topo = Topology {
            inside_components,
            outside_components,
            surface_components: (inside_components + outside_components).saturating_sub(1),
            crossing_edges: edges,
            component_seeds: Vec::with_capacity(pairs.len()),
            component_edges: Vec::with_capacity(pairs.len()),
            component_tets: Vec::with_capacity(pairs.len()),
            extra_seeds: extra_edges.into_iter().map(point).collect(),
        };
        for ((_, info), tet) in pairs.iter().zip(tets) {
            topo.component_edges.push(info.edges);
            match tet {
                Some(t) => {
                    topo.component_seeds.push(t[0]);
                    topo.component_tets.push(vec![t[1], t[2], t[3]]);
                }
                None => {
                    topo.component_seeds.push(point(info.first));
                    topo.component_tets.push(Vec::new());
                }
            }
        }
        topo
    }
}

/// The first crossing of S on the ray from voxel position `m` along `u` (unit, voxel space),
/// within `len` voxels: quarter-voxel steps, then bisection down to adjacent floats (so the
/// point is on S to rounding, like the grid-edge crossings). In world space.
fn first_crossing(
    s: &ImageSurface,
    aff: glam::DAffine3,
    m: DVec3,
    u: DVec3,
    len: f64,
) -> Option<DVec3> {
    let steps = (len * 4.0).ceil().max(1.0) as usize;
    let mut a = aff.transform_point3(m);
    let mut fa = s.value(a);
    for i in 1..=steps {
        let b = aff.transform_point3(m + u * (len * i as f64 / steps as f64));
        let fb = s.value(b);
        if (fa < 0.0) != (fb < 0.0) {
            let c = crate::roots::bisect(|p| s.value(p), a, fa, b, fb, 0.0);
            return c.is_finite().then_some(c);
        }
        (a, fa) = (b, fb);
    }
    None
}

/// Depth of every region in the tree of regions (nodes: inside and outside regions; edges:
/// the touching pairs), from the exterior region (depth 0). Breadth-first, deterministic.
fn region_depths(pairs: impl Iterator<Item = (u32, u32)>, exterior: u32) -> BTreeMap<u32, usize> {
    let mut adj: BTreeMap<u32, Vec<u32>> = BTreeMap::new();
    for (a, b) in pairs {
        adj.entry(a).or_default().push(b);
        adj.entry(b).or_default().push(a);
    }
    let mut depth = BTreeMap::new();
    depth.insert(exterior, 0usize);
    let mut queue = std::collections::VecDeque::from([exterior]);
    while let Some(r) = queue.pop_front() {
        let d = depth[&r];
        for &n in adj.get(&r).map_or(&[][..], |v| &v[..]) {
            if let std::collections::btree_map::Entry::Vacant(e) = depth.entry(n) {
                e.insert(d + 1);
                queue.push_back(n);
            }
        }
    }
    depth
}

/// Of the 4-point subsets of `pts` (points of one small component) that make a tetrahedron
/// of radius-edge ratio at most 4, the one whose circumcentre lies deepest in the enclosed
/// region (`sign * value > 0`: `sign = -1` for an inside blob, `1` for a cavity) and within
/// the points' bounding box: with these four points in the initial sample, that circumcentre
/// is a Voronoi vertex inside the component, so the four facets of the tetrahedron are
/// restricted at once. `None` if no subset qualifies.
fn seed_tet(s: &ImageSurface, pts: &[DVec3], sign: f64) -> Option<[DVec3; 4]> {
    let (lo, hi) = pts
        .iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(*p), hi.max(*p))
        });
    let n = pts.len();
    let mut best: Option<(f64, [usize; 4])> = None;
    for i in 0..n {
        for j in i + 1..n {
            for k in j + 1..n {
                for l in k + 1..n {
                    let (a, b, c) = (pts[j] - pts[i], pts[k] - pts[i], pts[l] - pts[i]);
                    let det = a.dot(b.cross(c));
                    let scale = a.length() * b.length() * c.length();
                    if !(det.abs() > 1e-3 * scale) {
                        continue;
                    }
                    let cc = pts[i]
                        + (b.cross(c) * a.length_squared()
                            + c.cross(a) * b.length_squared()
                            + a.cross(b) * c.length_squared())
                            / (2.0 * det);
                    if !(cc.cmpge(lo).all() && cc.cmple(hi).all()) {
                        continue;
                    }
                    let r2 = (cc - pts[i]).length_squared();
                    let e2 = [a, b, c, b - a, c - a, c - b]
                        .iter()
                        .map(|e| e.length_squared())
                        .fold(f64::INFINITY, f64::min);
                    if !(16.0 * e2 >= r2) {
                        continue;
                    }
                    let score = sign * s.value(cc);
                    if score > 0.0 && best.is_none_or(|b| score > b.0) {
                        best = Some((score, [i, j, k, l]));
                    }
                }
            }
        }
    }
    best.map(|(_, ix)| ix.map(|i| pts[i]))
}

/// Run-based implementation: the grid rows (along x) are cut into runs of equal sign, the
/// union-find works on runs, and sign changes between rows are found 64 nodes at a time.
// Run indices are union-find ids and index several arrays: plain index loops are clearer.
#[allow(clippy::needless_range_loop)]
///
/// `bits` are the node signs from [`ImageSurface::inside_bits_rows`].
pub(crate) fn compute(s: &ImageSurface, bits: &[u64]) -> Topology {
    let [nx, ny, nz] = s.dims_isize().map(|v| v as usize);
    let w = nx.div_ceil(64);
    let rows = ny * nz;
    let word = |r: usize, wi: usize| bits[r * w + wi];
    let get = |r: usize, x: usize| (bits[r * w + (x >> 6)] >> (x & 63)) & 1 == 1;
    // Valid node positions (x < nx) and transition positions (x < nx - 1) in word wi.
    let mask_below = |wi: usize, lim: usize| -> u64 {
        let lo = wi * 64;
        if lim >= lo + 64 {
            !0
        } else if lim <= lo {
            0
        } else {
            (1u64 << (lim - lo)) - 1
        }
    };
    let trans = |r: usize, wi: usize| -> u64 {
        let a = word(r, wi);
        let next = if wi + 1 < w { word(r, wi + 1) << 63 } else { 0 };
        (a ^ ((a >> 1) | next)) & mask_below(wi, nx - 1)
    };
    // Runs: start x of each run, its sign, first run of each row.
    let mut run_x: Vec<u32> = Vec::new();
    let mut run_ins: Vec<bool> = Vec::new();
    let mut row_first: Vec<usize> = Vec::with_capacity(rows + 1);
    for r in 0..rows {
        row_first.push(run_x.len());
        run_x.push(0);
        run_ins.push(get(r, 0));
        for wi in 0..w {
            let mut t = trans(r, wi);
            while t != 0 {
                let x = wi * 64 + t.trailing_zeros() as usize + 1;
                run_x.push(x as u32);
                run_ins.push(get(r, x));
                t &= t - 1;
            }
        }
    }
    row_first.push(run_x.len());
    let nruns = run_x.len();
    let ext = nruns as u32;
    let run_of = |r: usize, x: usize| -> u32 {
        let (lo, hi) = (row_first[r], row_first[r + 1]);
        let k = run_x[lo..hi].partition_point(|&s| s as usize <= x);
        (lo + k - 1) as u32
    };
    let run_end = |t: usize, r: usize| -> usize {
        if t + 1 < row_first[r + 1] {
            run_x[t + 1] as usize - 1
        } else {
            nx - 1
        }
    };
    let node = |r: usize, x: usize| r * nx + x;
    let mut dsu = Dsu((0..=ext).collect());
    // Asymptotic decider on a face with corners p00, p10, p01, p11 (p00 ~ p11 and p10 ~ p01
    // are the diagonals); returns whether the diagonal p00-p11 is joined.
    let decide = |p00: usize, p10: usize, p01: usize, p11: usize, a: bool| -> bool {
        let (f00, f10, f01, f11) = (
            s.node_value(p00),
            s.node_value(p10),
            s.node_value(p01),
            s.node_value(p11),
        );
        let den = f00 + f11 - f10 - f01;
        let saddle = if den != 0.0 {
            (f00 * f11 - f10 * f01) / den
        } else {
            0.0
        };
        (saddle < 0.0) == a
    };
    let link_rows = |dsu: &mut Dsu, a: usize, b: usize| {
        // 6-neighbours across rows: overlapping runs of equal sign.
        let (mut i, ie) = (row_first[a], row_first[a + 1]);
        let (mut k, ke) = (row_first[b], row_first[b + 1]);
        while i < ie && k < ke {
            if run_ins[i] == run_ins[k] {
                dsu.union(i as u32, k as u32);
            }
            let (ei, ek) = (run_end(i, a), run_end(k, b));
            if ei <= ek {
                i += 1;
            }
            if ek <= ei {
                k += 1;
            }
        }
        // Face diagonals in the plane of the two rows: both rows change sign between x and
        // x + 1, with opposite signs.
        for wi in 0..w {
            let mut c = trans(a, wi) & trans(b, wi) & (word(a, wi) ^ word(b, wi));
            while c != 0 {
                let x = wi * 64 + c.trailing_zeros() as usize;
                c &= c - 1;
                let (p00, p10, p01, p11) = (node(a, x), node(a, x + 1), node(b, x), node(b, x + 1));
                if decide(p00, p10, p01, p11, get(a, x)) {
                    dsu.union(run_of(a, x), run_of(b, x + 1));
                } else {
                    dsu.union(run_of(a, x + 1), run_of(b, x));
                }
            }
        }
    };
    for r in 0..rows {
        let (j, k) = (r % ny, r / ny);
        let border_row = j == 0 || k == 0 || j + 1 == ny || k + 1 == nz;
        let (lo, hi) = (row_first[r], row_first[r + 1]);
        for t in lo..hi {
            if !run_ins[t] && (border_row || t == lo || t + 1 == hi) {
                dsu.union(t as u32, ext);
            }
        }
        if j + 1 < ny {
            link_rows(&mut dsu, r, r + 1);
        }
        if k + 1 < nz {
            link_rows(&mut dsu, r, r + ny);
        }
        if j + 1 < ny && k + 1 < nz {
            // yz faces: rows A = (j, k), B = (j+1, k), C = (j, k+1), D = (j+1, k+1).
            let (ra, rb, rc, rd) = (r, r + 1, r + ny, r + ny + 1);
            for wi in 0..w {
                let (a, b, c, d) = (word(ra, wi), word(rb, wi), word(rc, wi), word(rd, wi));
                let mut amb = !(a ^ d) & !(b ^ c) & (a ^ b) & mask_below(wi, nx);
                while amb != 0 {
                    let x = wi * 64 + amb.trailing_zeros() as usize;
                    amb &= amb - 1;
                    let (p00, p10, p01, p11) = (node(ra, x), node(rb, x), node(rc, x), node(rd, x));
                    if decide(p00, p10, p01, p11, get(ra, x)) {
                        dsu.union(run_of(ra, x), run_of(rd, x));
                    } else {
                        dsu.union(run_of(rb, x), run_of(rc, x));
                    }
                }
            }
        }
    }
    let mut inside_components = 0;
    let mut outside_components = 0;
    for t in 0..=nruns {
        if dsu.find(t as u32) == t as u32 {
            if t < nruns && run_ins[t] {
                inside_components += 1;
            } else {
                outside_components += 1;
            }
        }
    }
    // Sign-changing edges, in a fixed order: per row, x edges, y edges, z edges, padding.
    let for_each_edge = |f: &mut dyn FnMut(Edge, [usize; 3], u32, u32)| {
        let pad = usize::MAX;
        for r in 0..rows {
            let (j, k) = (r % ny, r / ny);
            for t in row_first[r] + 1..row_first[r + 1] {
                let x = run_x[t] as usize - 1;
                f(
                    (node(r, x), 1, node(r, x + 1)),
                    [x, j, k],
                    t as u32 - 1,
                    t as u32,
                );
            }
            for (dr, ok, axd) in [(1usize, j + 1 < ny, 2isize), (ny, k + 1 < nz, 3)] {
                if !ok {
                    continue;
                }
                for wi in 0..w {
                    let mut c = (word(r, wi) ^ word(r + dr, wi)) & mask_below(wi, nx);
                    while c != 0 {
                        let x = wi * 64 + c.trailing_zeros() as usize;
                        c &= c - 1;
                        let e = (node(r, x), axd, node(r + dr, x));
                        f(e, [x, j, k], run_of(r, x), run_of(r + dr, x));
                    }
                }
            }
            let (lo, hi) = (row_first[r], row_first[r + 1]);
            if run_ins[lo] {
                f((node(r, 0), -1, pad), [0, j, k], lo as u32, ext);
            }
            if run_ins[hi - 1] {
                f(
                    (node(r, nx - 1), 1, pad),
                    [nx - 1, j, k],
                    hi as u32 - 1,
                    ext,
                );
            }
            for (on, axd) in [
                (j == 0, -2isize),
                (j + 1 == ny, 2),
                (k == 0, -3),
                (k + 1 == nz, 3),
            ] {
                if !on {
                    continue;
                }
                for t in lo..hi {
                    if run_ins[t] {
                        for x in run_x[t] as usize..=run_end(t, r) {
                            f((node(r, x), axd, pad), [x, j, k], t as u32, ext);
                        }
                    }
                }
            }
        }
    };
    let mut edges = 0usize;
    for_each_edge(&mut |_, _, _, _| edges += 1);
    let stride = edges.div_ceil(4096).max(1);
    let mut pairs = Pairs::default();
    let mut extra_edges = Vec::new();
    let mut count = 0usize;
    for_each_edge(&mut |e, c, tp, tq| {
        let (rp, rq) = (dsu.find(tp), dsu.find(tq));
        let key = if run_ins[tp as usize] {
            (rp, rq)
        } else {
            (rq, rp)
        };
        pairs.add(key, e, c);
        if count.is_multiple_of(stride) {
            extra_edges.push(e);
        }
        count += 1;
    });
    let exterior = dsu.find(ext);
    pairs.finish(
        s,
        exterior,
        inside_components,
        outside_components,
        edges,
        extra_edges,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::image::{ImageOptions, Volume, Voxels};
    use crate::roots::SplitMix64;
    use glam::DAffine3;

    fn check(dims: [usize; 3], data: Vec<f32>, iso: f64) -> usize {
        let vol = Volume::new(dims, Voxels::F32(data), DAffine3::IDENTITY).unwrap();
        let Ok(s) = ImageSurface::new(
            vol,
            &ImageOptions {
                iso: Some(iso),
                ..Default::default()
            },
        ) else {
            return 0;
        };
        let (a, b) = (compute(&s, &s.inside_bits_rows()), compute_reference(&s));
        assert_eq!(
            (a.inside_components, a.outside_components, a.crossing_edges),
            (b.inside_components, b.outside_components, b.crossing_edges),
            "dims {dims:?}"
        );
        assert_eq!(a.component_seeds.len(), b.component_seeds.len());
        for p in a.component_seeds.iter().chain(&a.extra_seeds) {
            assert!(crate::Surface::value(&s, *p).abs() < 1e-9);
        }
        a.surface_components
    }

    #[test]
    fn run_based_matches_node_based() {
        let mut rng = SplitMix64(77);
        let mut many = 0;
        for case in 0..300 {
            let dims = [
                1 + (rng.next_u64() % 70) as usize,
                1 + (rng.next_u64() % 6) as usize,
                1 + (rng.next_u64() % 6) as usize,
            ];
            let n = dims[0] * dims[1] * dims[2];
            // Sparse or dense random binary-ish data with random values (ambiguous faces).
            let density = [0.1, 0.3, 0.5, 0.8][case % 4];
            let data: Vec<f32> = (0..n)
                .map(|_| {
                    if rng.next_f64() < density {
                        0.5 + rng.next_f64() as f32
                    } else {
                        rng.next_f64() as f32 * 0.5
                    }
                })
                .collect();
            many += (check(dims, data, 0.5) > 3) as usize;
        }
        assert!(many > 100, "too few cases with several components: {many}");
    }
}
