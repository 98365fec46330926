//! The (inside region, outside region) pairs met by the voxel scan (ours, P1 of section 6.6.2), each with its first and
//! extreme crossing edges, and the [`Topology`] they give.

use super::seeds::Topology;
use super::tets::{first_crossing, seed_tet};
use crate::image::ImageSurface;
use glam::{DAffine3, DVec3};
use std::collections::BTreeMap;

/// An edge with a sign change: node `p`, axis and direction `axd` (±1, ±2, ±3 for x, y, z),
/// the other node `q` (or `usize::MAX` for the padding), and the runs of `p` and `q`.
pub(super) type Edge = (usize, isize, usize);

/// Directions (in voxel axes) along which [`PairInfo`] keeps the extreme crossing edges: the
/// three axes and the four body diagonals.
pub(super) const DIRS: [[i64; 3]; 7] = [
    [1, 0, 0],
    [0, 1, 0],
    [0, 0, 1],
    [1, 1, 1],
    [1, 1, -1],
    [1, -1, 1],
    [-1, 1, 1],
];

/// Components whose crossing edges span at most this many voxels along every axis are
/// *small*: their seed tetrahedron ([`Topology::component_tets`]) is chosen around the whole
/// component, else around its first crossing edge.
pub(super) const SMALL_EXTENT_VOXELS: i64 = 8;

/// Per (inside region, outside region) pair that touch: the first crossing edge in scan order,
/// the number of crossing edges, and the extreme edges along [`DIRS`].
pub(super) struct PairInfo {
    first: Edge,
    edges: usize,
    /// For direction `d`: `ext[2d]` has the lowest crossing (edge midpoint in half voxels,
    /// projected on `DIRS[d]`), `ext[2d + 1]` the highest; ties keep the first edge in scan
    /// order.
    ext: [(i64, Edge); 14],
}

/// The pairs met while scanning the crossing edges, keyed by their (inside, outside) roots.
#[derive(Default)]
pub(super) struct Pairs {
    index: BTreeMap<(u32, u32), usize>,
    info: Vec<PairInfo>,
    last: Option<((u32, u32), usize)>,
}

impl Pairs {
    /// The pairs' keys, sorted (the order of [`Topology::component_seeds`]).
    pub fn keys(&self) -> Vec<(u32, u32)> {
        self.index.keys().copied().collect()
    }

    /// Record the crossing edge `e` (from node `c`, voxel coordinates) of the pair `key`.
    #[inline]
    pub fn add(&mut self, key: (u32, u32), e: Edge, c: [usize; 3]) {
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
    /// unbounded outside region; then the numbers of inside and outside regions.
    pub fn finish(
        self,
        s: &ImageSurface,
        exterior: u32,
        (inside_components, outside_components): (usize, usize),
        edges: usize,
        extra_edges: Vec<Edge>,
        vanishing: &super::vanishing::Vanishing,
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
        // A tetrahedron for every component, whatever their number (bounded cost: up to a
        // few thousand circumcentres each, local to the first crossing edge on large ones).
        let order: Vec<usize> = (0..pairs.len()).collect();
        let mut tets: Vec<Option<[DVec3; 4]>> = vec![None; pairs.len()];
        for &i in order.iter() {
            let (key, info) = pairs[i];
            if !vanishing.contains(key.1) {
                tets[i] = component_tet(s, aff, [nx, ny], key, info, &depth, &point);
            }
        }
        let vanishing_components = vanishing.count();
        let mut topo = Topology {
            inside_components,
            outside_components,
            surface_components: (inside_components + outside_components)
                .saturating_sub(1 + vanishing_components),
            vanishing_components,
            component_vanishing: pairs.iter().map(|(k, _)| vanishing.contains(k.1)).collect(),
            crossing_edges: edges,
            component_seeds: Vec::with_capacity(pairs.len()),
            component_edges: Vec::with_capacity(pairs.len()),
            component_tets: Vec::with_capacity(pairs.len()),
            extra_seeds: extra_edges.into_iter().map(point).collect(),
            labels: None,
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

/// The seed tetrahedron of the component between the regions `key` (see [`seed_tet`]), from
/// its candidate crossings (`point` maps an edge to its crossing) and rays from its deepest
/// node; `depth` is each region's depth from the exterior.
fn component_tet(
    s: &ImageSurface,
    aff: DAffine3,
    [nx, ny]: [usize; 2],
    key: (u32, u32),
    info: &PairInfo,
    depth: &BTreeMap<u32, usize>,
    point: &impl Fn(Edge) -> DVec3,
) -> Option<[DVec3; 4]> {
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
    // The deepest enclosed node among the candidate edges' ends; when none is enclosed,
    // among their edge neighbours. That happens where the ends are ties (nodes at the iso
    // value, outside by the scan's convention): a cavity of a few voxels around one node
    // strictly below the iso value, whose crossings sit at tied nodes next to it (the uint8
    // MNI T1 at `--iso 171`). Without its node the seed was a tied node, the tip of one of the
    // cavity's spikes, from which the refinement never reached the cavity.
    let deepest = |nodes: &mut dyn Iterator<Item = usize>| {
        let mut centre: Option<(f64, usize)> = None;
        for n in nodes {
            let v = sign * s.node_value(n);
            if v > 0.0 && centre.is_none_or(|c| v > c.0) {
                centre = Some((v, n));
            }
        }
        centre
    };
    let ends = || {
        cand.iter()
            .flat_map(|&(p, _, q)| [p, q])
            .filter(|&n| n != usize::MAX)
    };
    let dims = s.dims_isize().map(|d| d as usize);
    let centre = deepest(&mut ends())
        .or_else(|| deepest(&mut ends().flat_map(|n| crate::grid::neighbours6(n, dims))));
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
    seed_tet(s, &pts, sign)
}
