//! Joins of the voxel scan (ours, P1 of section 6.6.2): where two grid nodes of one inside
//! region are connected (6-neighbours, the diagonal of a face joined through its bilinear
//! saddle, or two corners of a cell joined through its interior: `super::interior`), the
//! trilinear inside region passes from one to the other. A join between nodes
//! that a mesh puts on different pieces of one surface component is a neck the mesh missed;
//! the mesher samples S around it (`rdt_mesher`'s neck reseeding).

use super::labels::Labels;
use crate::image::ImageSurface;
use glam::{DAffine3, DVec3};

/// A join of the voxel scan between two nodes of one region (world space).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Join {
    /// One node.
    pub a: DVec3,
    /// The other node.
    pub b: DVec3,
    /// A point of the region between them: the midpoint of a grid edge, the saddle of the
    /// face whose diagonal `a`-`b` is, or for a cell's interior the saddle of the slice
    /// that joins them.
    pub via: DVec3,
    /// Whether `a`-`b` is the diagonal of a face or of a cell (else a grid edge).
    pub diagonal: bool,
    /// The indices in the volume of the nodes at `a` and `b` (as [`Node::index`]).
    pub nodes: [usize; 2],
}

impl ImageSurface {
    /// The joins of the inside region of the scan component `component` (index into
    /// [`super::Topology::component_seeds`]) between nodes in the box `[lo, hi]` (world space;
    /// the nodes of the voxel box covering it), in node order. Empty when the scan kept no
    /// labels or the index is out of range.
    pub fn inside_joins(&self, component: usize, lo: DVec3, hi: DVec3) -> Vec<Join> {
        self.joins(component, true, lo, hi)
    }

    /// [`ImageSurface::inside_joins`], then the joins of the component's outside region when
    /// it is bounded (a cavity, whose wall the component is: a neck of the wall can be a
    /// tunnel of the outside), not the unbounded one.
    pub fn neck_joins(&self, component: usize, lo: DVec3, hi: DVec3) -> Vec<Join> {
        self.neck_joins_where(component, lo, hi, &mut |_, _| true)
    }

    /// The joins of [`ImageSurface::neck_joins`] whose two nodes `keep` accepts (asked
    /// before anything else is computed for the join: world positions, saddles), in the same
    /// order.
    pub fn neck_joins_where(
        &self,
        component: usize,
        lo: DVec3,
        hi: DVec3,
        keep: &mut dyn FnMut(Node, Node) -> bool,
    ) -> Vec<Join> {
        let mut out = Vec::new();
        for side in self.neck_sides(component) {
            if let Some(mask) = RegionMask::new(self, component, side, lo, hi) {
                mask.joins(self, keep, &mut out);
            }
        }
        out
    }

    /// Every node of the regions of [`ImageSurface::neck_joins`] that a join in the box can
    /// have (the box's nodes and their neighbours), in node order per region: the nodes whose
    /// data a [`ImageSurface::neck_joins_where`] filter may want first.
    pub fn neck_nodes(&self, component: usize, lo: DVec3, hi: DVec3) -> Vec<Node> {
        let mut out = Vec::new();
        for side in self.neck_sides(component) {
            if let Some(mask) = RegionMask::new(self, component, side, lo, hi) {
                mask.nodes(&mut out);
            }
        }
        out
    }

    /// The sides whose regions carry the component's necks: inside, and outside when that
    /// region is bounded.
    fn neck_sides(&self, component: usize) -> Vec<bool> {
        let topo = self.topology();
        let bounded = topo.labels.as_deref().is_some_and(|l| {
            l.pairs
                .get(component)
                .is_some_and(|&(_, o)| o != l.exterior)
        });
        if bounded {
            vec![true, false]
        } else {
            vec![true]
        }
    }

    /// The joins of the component's inside (`inside`) or outside region in the box.
    fn joins(&self, component: usize, inside: bool, lo: DVec3, hi: DVec3) -> Vec<Join> {
        let mut out = Vec::new();
        if let Some(mask) = RegionMask::new(self, component, inside, lo, hi) {
            mask.joins(self, &mut |_, _| true, &mut out);
        }
        out
    }
}

/// A grid node of a join: its index in the volume (`i + nx (j + ny k)`) and its world
/// position.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Node {
    /// Index of the node in the volume.
    pub index: usize,
    /// World position.
    pub at: DVec3,
}

/// Which nodes of a box (the voxel box of a world box, one node wider on every side: the
/// nodes a join from the box can reach) belong to one region of the scan. Filled row by row
/// from the scan's runs, so each membership test is one read.
struct RegionMask {
    /// The box's nodes: first node, then the last.
    lo: [i64; 3],
    hi: [i64; 3],
    /// Node range whose joins are listed (the voxel box).
    inner: ([i64; 3], [i64; 3]),
    /// Membership of each node of `lo..=hi`, x fastest.
    inside: Vec<bool>,
    dims: [i64; 3],
    side: bool,
    /// Voxel to world.
    to_world: DAffine3,
}

impl RegionMask {
    fn new(s: &ImageSurface, component: usize, side: bool, lo: DVec3, hi: DVec3) -> Option<Self> {
        let topo = s.topology();
        let labels = topo.labels.as_deref()?;
        let &(ins, outs) = labels.pairs.get(component)?;
        let root = if side { ins } else { outs };
        let (vlo, vhi) = voxel_box(s, lo, hi);
        if (0..3).any(|a| vlo[a] > vhi[a]) {
            return None;
        }
        let dims = labels.dims.map(|d| d as i64);
        let blo = vlo.map(|x| x - 1);
        let bhi = vhi.map(|x| x + 1);
        let size = (0..3).map(|a| (bhi[a] - blo[a] + 1) as usize);
        let mut inside = vec![false; size.product()];
        let (sx, sy) = (
            (bhi[0] - blo[0] + 1) as usize,
            (bhi[1] - blo[1] + 1) as usize,
        );
        for k in blo[2].max(0)..=bhi[2].min(dims[2] - 1) {
            for j in blo[1].max(0)..=bhi[1].min(dims[1] - 1) {
                let r = (j + dims[1] * k) as usize;
                let base = sx * ((j - blo[1]) as usize + sy * (k - blo[2]) as usize);
                let (x0, x1) = (blo[0].max(0), bhi[0].min(dims[0] - 1));
                // The runs of row r meeting [x0, x1]: run t covers run_x[t]..run_x[t + 1].
                let (first, last) = (labels.row_first[r], labels.row_first[r + 1]);
                let xs = &labels.run_x[first..last];
                let mut t = first + xs.partition_point(|&x| x as i64 <= x0) - 1;
                while t < last && labels.run_x[t] as i64 <= x1 {
                    let end = if t + 1 < last {
                        labels.run_x[t + 1] as i64 - 1
                    } else {
                        dims[0] - 1
                    };
                    if labels.run_root[t] == root && labels.run_ins[t] == side {
                        let (a, b) = (x0.max(labels.run_x[t] as i64), x1.min(end));
                        for x in a..=b {
                            inside[base + (x - blo[0]) as usize] = true;
                        }
                    }
                    t += 1;
                }
            }
        }
        Some(Self {
            lo: blo,
            hi: bhi,
            inner: (vlo, vhi),
            inside,
            dims,
            side,
            to_world: s.inv.inverse(),
        })
    }

    /// Whether node `p` (within `lo..=hi`) is in the region.
    #[inline]
    fn has(&self, p: [i64; 3]) -> bool {
        let sx = self.hi[0] - self.lo[0] + 1;
        let sy = self.hi[1] - self.lo[1] + 1;
        let (x, y, z) = (p[0] - self.lo[0], p[1] - self.lo[1], p[2] - self.lo[2]);
        self.inside[(x + sx * (y + sy * z)) as usize]
    }

    fn node(&self, p: [i64; 3]) -> Node {
        Node {
            index: (p[0] + self.dims[0] * (p[1] + self.dims[1] * p[2])) as usize,
            at: self.to_world.transform_point3(node(p)),
        }
    }

    /// The region's nodes in the box (all of `lo..=hi`), in node order.
    fn nodes(&self, out: &mut Vec<Node>) {
        for k in self.lo[2]..=self.hi[2] {
            for j in self.lo[1]..=self.hi[1] {
                for i in self.lo[0]..=self.hi[0] {
                    if self.has([i, j, k]) {
                        out.push(self.node([i, j, k]));
                    }
                }
            }
        }
    }

    /// The joins from the nodes of the voxel box, in node order (per node: the three grid
    /// edges, then the face diagonals), that `keep` accepts.
    fn joins(
        &self,
        s: &ImageSurface,
        keep: &mut dyn FnMut(Node, Node) -> bool,
        out: &mut Vec<Join>,
    ) {
        let topo = s.topology();
        let Some(labels) = topo.labels.as_deref() else {
            return;
        };
        let to_world = self.to_world;
        let (vlo, vhi) = self.inner;
        for k in vlo[2]..=vhi[2] {
            for j in vlo[1]..=vhi[1] {
                for i in vlo[0]..=vhi[0] {
                    let p = [i, j, k];
                    if !self.has(p) {
                        continue;
                    }
                    let np = self.node(p);
                    for axis in 0..3 {
                        let mut q = p;
                        q[axis] += 1;
                        if !self.has(q) {
                            continue;
                        }
                        let nq = self.node(q);
                        if keep(np, nq) {
                            let (a, b) = (node(p), node(q));
                            out.push(Join {
                                a: np.at,
                                b: nq.at,
                                via: to_world.transform_point3(0.5 * (a + b)),
                                diagonal: false,
                                nodes: [np.index, nq.index],
                            });
                        }
                    }
                    for (u, v) in [(0, 1), (0, 2), (1, 2)] {
                        for (du, dv) in [(1i64, 1i64), (1, -1)] {
                            let q = offset(p, u, du, v, dv);
                            let side_nodes = [offset(p, u, du, v, 0), offset(p, u, 0, v, dv)];
                            if !in_grid(q, self.dims)
                                || !self.has(q)
                                || side_nodes.iter().any(|&n| self.has(n))
                            {
                                continue;
                            }
                            let nq = self.node(q);
                            if !keep(np, nq) {
                                continue;
                            }
                            if let Some(x) = saddle(s, labels, p, q, side_nodes, self.side) {
                                out.push(Join {
                                    a: np.at,
                                    b: nq.at,
                                    via: to_world.transform_point3(x),
                                    diagonal: true,
                                    nodes: [np.index, nq.index],
                                });
                            }
                        }
                    }
                    self.interior_joins(s, p, keep, out);
                }
            }
        }
    }

    /// The joins through the interior of the cell whose first corner is `p` between two of
    /// its corners in the region (see [`super::interior`]), that `keep` accepts.
    fn interior_joins(
        &self,
        s: &ImageSurface,
        p: [i64; 3],
        keep: &mut dyn FnMut(Node, Node) -> bool,
        out: &mut Vec<Join>,
    ) {
        let corner = |c: u8| {
            [
                p[0] + i64::from(c & 1),
                p[1] + i64::from((c >> 1) & 1),
                p[2] + i64::from(c >> 2),
            ]
        };
        if !in_grid(corner(7), self.dims) || (0..8).filter(|&c| self.has(corner(c))).count() < 2 {
            return;
        }
        let g: [f64; 8] = std::array::from_fn(|c| s.node_value(self.node(corner(c as u8)).index));
        for j in super::interior::interior_joins(&g) {
            let (ca, cb) = (corner(j.a), corner(j.b));
            if (g[j.a as usize] < 0.0) != self.side || !self.has(ca) || !self.has(cb) {
                continue;
            }
            let (na, nb) = (self.node(ca), self.node(cb));
            if keep(na, nb) {
                out.push(Join {
                    a: na.at,
                    b: nb.at,
                    via: self
                        .to_world
                        .transform_point3(node(p) + DVec3::from_array(j.via)),
                    diagonal: true,
                    nodes: [na.index, nb.index],
                });
            }
        }
    }
}

/// The node range (clamped to the grid) of the voxel box covering the world box `[lo, hi]`.
fn voxel_box(s: &ImageSurface, lo: DVec3, hi: DVec3) -> ([i64; 3], [i64; 3]) {
    let mut vlo = DVec3::INFINITY;
    let mut vhi = DVec3::NEG_INFINITY;
    for c in 0..8 {
        let w = DVec3::new(
            if c & 1 == 0 { lo.x } else { hi.x },
            if c & 2 == 0 { lo.y } else { hi.y },
            if c & 4 == 0 { lo.z } else { hi.z },
        );
        let v = s.inv.transform_point3(w);
        vlo = vlo.min(v);
        vhi = vhi.max(v);
    }
    let n = s.n;
    let clamp = |x: f64, d: isize| x.clamp(0.0, (d - 1).max(0) as f64) as i64;
    if !(vlo.is_finite() && vhi.is_finite()) {
        return ([0; 3], [-1; 3]);
    }
    (
        [
            clamp(vlo.x.floor(), n[0]),
            clamp(vlo.y.floor(), n[1]),
            clamp(vlo.z.floor(), n[2]),
        ],
        [
            clamp(vhi.x.ceil(), n[0]),
            clamp(vhi.y.ceil(), n[1]),
            clamp(vhi.z.ceil(), n[2]),
        ],
    )
}

fn node(p: [i64; 3]) -> DVec3 {
    DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64)
}

fn offset(p: [i64; 3], u: usize, du: i64, v: usize, dv: i64) -> [i64; 3] {
    let mut q = p;
    q[u] += du;
    q[v] += dv;
    q
}

fn in_grid(p: [i64; 3], dims: [i64; 3]) -> bool {
    (0..3).all(|i| p[i] >= 0 && p[i] < dims[i])
}

/// The saddle (voxel coordinates) of the face with diagonal `p`-`q` (both on the side
/// `inside`) and the other corners `side` (on the other side), when the asymptotic decider
/// joins `p` and `q` (the saddle value is on their side, as in the scan).
fn saddle(
    s: &ImageSurface,
    labels: &Labels,
    p: [i64; 3],
    q: [i64; 3],
    side: [[i64; 3]; 2],
    inside: bool,
) -> Option<DVec3> {
    let nx = labels.dims[0] as i64;
    let ny = labels.dims[1] as i64;
    let idx = |p: [i64; 3]| (p[0] + nx * (p[1] + ny * p[2])) as usize;
    // Bilinear f on the face: f00 at p, f11 at q, f10 at side[0], f01 at side[1].
    let (f00, f11) = (s.node_value(idx(p)), s.node_value(idx(q)));
    let (f10, f01) = (s.node_value(idx(side[0])), s.node_value(idx(side[1])));
    let den = f00 + f11 - f10 - f01;
    let value = if den != 0.0 {
        (f00 * f11 - f10 * f01) / den
    } else {
        0.0
    };
    if (value < 0.0) != inside || den == 0.0 {
        return None;
    }
    // Stationary point: u along side[0] - p, v along side[1] - p.
    let u = (f00 - f01) / den;
    let v = (f00 - f10) / den;
    let (a, e0, e1) = (node(p), node(side[0]) - node(p), node(side[1]) - node(p));
    Some(a + e0 * u.clamp(0.0, 1.0) + e1 * v.clamp(0.0, 1.0))
}

#[cfg(test)]
mod tests {
    use crate::image::{ImageOptions, ImageSurface, Volume, Voxels};
    use glam::{DAffine3, DVec3};

    /// 5^3 voxels of -1 (outside at iso 0) with the given nodes set to `v`.
    fn grid(nodes: &[([usize; 3], f32)]) -> ImageSurface {
        grid_of(-1.0, nodes)
    }

    /// 5^3 voxels of `bg` with the given nodes set to `v`, at iso 0.
    fn grid_of(bg: f32, nodes: &[([usize; 3], f32)]) -> ImageSurface {
        let n = 5;
        let mut d = vec![bg; n * n * n];
        for &([i, j, k], v) in nodes {
            d[i + n * (j + n * k)] = v;
        }
        let vol = Volume::new([n; 3], Voxels::F32(d), DAffine3::IDENTITY).unwrap();
        let opts = ImageOptions {
            iso: Some(0.0),
            ..Default::default()
        };
        ImageSurface::new(vol, &opts).unwrap()
    }

    #[test]
    fn grid_edges_and_saddle_diagonals_are_joins() {
        // Two 6-neighbours: one join along the edge, its midpoint between.
        let s = grid(&[([1, 2, 2], 1.0), ([2, 2, 2], 1.0)]);
        assert_eq!(s.component_count(), 1);
        let c = s.component_of(s.topology().component_seeds[0]).unwrap();
        let j = s.inside_joins(c, DVec3::ZERO, DVec3::splat(4.0));
        assert_eq!(j.len(), 1);
        assert!(!j[0].diagonal && j[0].via == DVec3::new(1.5, 2.0, 2.0));
        // A face diagonal whose saddle is inside (values 3, 3 against -1, -1: saddle 1 > 0).
        let s = grid(&[([1, 1, 2], 3.0), ([2, 2, 2], 3.0)]);
        assert_eq!(s.component_count(), 1);
        let c = s.component_of(s.topology().component_seeds[0]).unwrap();
        let j = s.inside_joins(c, DVec3::ZERO, DVec3::splat(4.0));
        assert_eq!(j.len(), 1);
        assert!(j[0].diagonal && j[0].via.distance(DVec3::new(1.5, 1.5, 2.0)) < 1e-12);
        // Not joined through the saddle (values 0.5: saddle -0.25): two components, no join.
        let s = grid(&[([1, 1, 2], 0.5), ([2, 2, 2], 0.5)]);
        assert_eq!(s.component_count(), 2);
        let c = s.component_of(s.topology().component_seeds[0]).unwrap();
        assert!(s.inside_joins(c, DVec3::ZERO, DVec3::splat(4.0)).is_empty());
        // Out of range: nothing.
        assert!(s.inside_joins(99, DVec3::ZERO, DVec3::ONE).is_empty());
    }

    #[test]
    fn a_cavity_has_the_joins_of_its_outside_region_too() {
        // Inside everywhere (1) but two 6-neighbours (-1): a cavity of two nodes, whose wall
        // is the component of the outside region that is not the unbounded one.
        let s = grid_of(1.0, &[([1, 2, 2], -1.0), ([2, 2, 2], -1.0)]);
        let t = s.topology();
        let cavity = t
            .component_seeds
            .iter()
            .filter_map(|p| s.component_of(*p))
            .find(|&c| {
                let j = s.neck_joins(c, DVec3::ZERO, DVec3::splat(4.0));
                j.len() > s.inside_joins(c, DVec3::ZERO, DVec3::splat(4.0)).len()
            })
            .expect("the cavity's wall has an outside join");
        let all = s.neck_joins(cavity, DVec3::ZERO, DVec3::splat(4.0));
        assert!(
            all.iter()
                .any(|j| !j.diagonal && j.via == DVec3::new(1.5, 2.0, 2.0))
        );
    }
}
