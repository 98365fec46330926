//! Short handles of a closed mesh (ours, not in the paper; used by the data-support check):
//! a handle (a tunnel through the surface, or a hole through a thin part) whose tunnel fits in
//! a small geodesic ball.
//!
//! From a seed vertex `s`, the geodesic ball (Dijkstra over the edges, lengths exact in f64)
//! grows one vertex at a time; the region is the vertices added, the edges and the triangles
//! whose vertices all are. Its Euler characteristic `chi = V - E + F` is 1 while the region
//! is a disk. It drops to 0 or below when the front meets itself: around a thin part (a
//! finger: the loop where the front met separates the surface) or around a tunnel (the loop
//! does not separate it: a handle). The two are told apart by the complement: the rest of the
//! seed's component is connected (through vertices outside the region) exactly when the
//! region's boundary loops do not separate it. The first radius at which the ball of `s` is
//! a non-disk with a connected complement is `s`'s *handle radius*; a handle whose tunnel has
//! length `L` has seeds with a handle radius of about `L / 2`.
//!
//! Only components of genus at least 1 are searched (a sphere has no handle), and each seed's
//! ball stops at its own limit (the caller's scale: the data's band there). Invariants: the
//! result depends only on the mesh and the limits (each seed is independent; seeds are
//! reported in increasing vertex order), not on the thread count.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use meshio::TriMesh;
use rayon::prelude::*;

use crate::topology::Dsu;

/// At most this many complement tests per seed (each visits the seed's component once): a
/// ball around a thin part tests once per separating event.
const MAX_TESTS_PER_SEED: usize = 4;

/// A seed whose geodesic ball holds a handle.
#[derive(Clone, Debug, PartialEq)]
pub struct ShortHandle {
    /// The seed vertex.
    pub seed: u32,
    /// The ball's radius when its complement stayed connected around a non-disk region.
    pub radius: f64,
    /// A loop through the tunnel (closed: the last vertex is joined to the first): from the
    /// seed along the ball's shortest paths to the vertex whose addition closed the loop,
    /// and back along the other side. Cutting along it removes the handle.
    pub loop_vertices: Vec<u32>,
}

/// The short-handle search on one mesh (its graph built once).
pub struct ShortLoops {
    g: Graph,
}

impl ShortLoops {
    /// The search on `mesh`; `None` unless every edge of it is in exactly two triangles
    /// (a closed mesh: the Euler characteristics and balls below assume it).
    pub fn new(mesh: &TriMesh) -> Option<ShortLoops> {
        Graph::new(mesh).map(|g| ShortLoops { g })
    }

    /// Whether some component has genus at least 1 (else there is no handle to look for).
    pub fn has_handles(&self) -> bool {
        self.g.comp_genus.iter().any(|&g| g >= 1)
    }

    /// The seeds (vertices of components of genus at least 1) whose geodesic ball of radius
    /// at most `limit(seed)` contains a handle (see the module docs), in increasing vertex
    /// order.
    pub fn handles(&self, limit: &(dyn Fn(u32) -> f64 + Sync)) -> Vec<ShortHandle> {
        let g = &self.g;
        let n = g.comp.len();
        let seeds: Vec<u32> = (0..n as u32)
            .filter(|&v| g.comp_genus_positive(v))
            .collect();
        seeds
            .par_iter()
            .map_init(
                || Scratch::new(n),
                |sc, &s| {
                    let r = g.handle_radius(s, limit(s), sc);
                    r.map(|(radius, loop_vertices)| ShortHandle {
                        seed: s,
                        radius,
                        loop_vertices,
                    })
                },
            )
            .collect::<Vec<_>>()
            .into_iter()
            .flatten()
            .collect()
    }

    /// The vertices within geodesic distance `radius` of `seed` (Dijkstra over the edges,
    /// as the search), in the order reached.
    pub fn ball(&self, seed: u32, radius: f64) -> Vec<u32> {
        let g = &self.g;
        let mut sc = Scratch::new(g.comp.len());
        let mut heap = BinaryHeap::new();
        sc.set_dist(seed, 0.0);
        heap.push(Reverse((Key(0.0), seed)));
        while let Some(Reverse((Key(d), u))) = heap.pop() {
            if sc.inside[u as usize] || d > sc.dist[u as usize] || d > radius {
                continue;
            }
            sc.add(u);
            for &(w, len) in g.neighbours(u) {
                if !sc.inside[w as usize] && d + len < sc.dist[w as usize] {
                    sc.set_dist(w, d + len);
                    heap.push(Reverse((Key(d + len), w)));
                }
            }
        }
        sc.region
    }

    /// The triangles (mesh indices, increasing) whose three corners are within geodesic
    /// distance `radius` of `seed` ([`ShortLoops::ball`]).
    pub fn ball_triangles(&self, seed: u32, radius: f64) -> Vec<u32> {
        let g = &self.g;
        let ball = self.ball(seed, radius);
        let mut inside = vec![false; g.comp.len()];
        ball.iter().for_each(|&v| inside[v as usize] = true);
        let mut out: Vec<u32> = ball
            .iter()
            .flat_map(|&v| {
                let r = g.tri_start[v as usize]..g.tri_start[v as usize + 1];
                g.tris[r.clone()].iter().zip(&g.tri_ids[r])
            })
            .filter(|(t, _)| t.iter().all(|&w| inside[w as usize]))
            .map(|(_, &k)| k)
            .collect();
        out.sort_unstable();
        out.dedup();
        out
    }
}

/// Vertex adjacency (with edge lengths) and vertex-triangle incidence, in compressed rows,
/// and each vertex's component.
struct Graph {
    nb_start: Vec<usize>,
    nb: Vec<(u32, f64)>,
    tri_start: Vec<usize>,
    tris: Vec<[u32; 3]>,
    /// The index in the mesh of each entry of `tris`.
    tri_ids: Vec<u32>,
    comp: Vec<u32>,
    comp_size: Vec<usize>,
    comp_genus: Vec<i64>,
}

impl Graph {
    fn new(mesh: &TriMesh) -> Option<Graph> {
        let n = mesh.vertices.len();
        if mesh.triangles.iter().flatten().any(|&v| v as usize >= n) {
            return None;
        }
        let mut edges: Vec<(u32, u32)> = mesh
            .triangles
            .iter()
            .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
            .map(|(a, b)| (a.min(b), a.max(b)))
            .collect();
        edges.sort_unstable();
        // Closed: every edge twice (and no triangle with a repeated corner).
        if !edges.len().is_multiple_of(2)
            || edges.chunks(2).any(|p| p[0] != p[1] || p[0].0 == p[0].1)
            || edges.windows(3).any(|w| w[0] == w[2])
        {
            return None;
        }
        edges.dedup();
        let mut deg = vec![0usize; n + 1];
        for &(a, b) in &edges {
            deg[a as usize + 1] += 1;
            deg[b as usize + 1] += 1;
        }
        let nb_start = prefix(deg);
        let mut fill = nb_start.clone();
        let mut nb = vec![(0u32, 0.0f64); nb_start[n]];
        for &(a, b) in &edges {
            let w = mesh.vertices[a as usize].distance(mesh.vertices[b as usize]);
            nb[fill[a as usize]] = (b, w);
            fill[a as usize] += 1;
            nb[fill[b as usize]] = (a, w);
            fill[b as usize] += 1;
        }
        let mut tdeg = vec![0usize; n + 1];
        for t in &mesh.triangles {
            t.iter().for_each(|&v| tdeg[v as usize + 1] += 1);
        }
        let tri_start = prefix(tdeg);
        let mut fill = tri_start.clone();
        let mut tris = vec![[0u32; 3]; tri_start[n]];
        let mut tri_ids = vec![0u32; tri_start[n]];
        for (k, t) in mesh.triangles.iter().enumerate() {
            for &v in t {
                tris[fill[v as usize]] = *t;
                tri_ids[fill[v as usize]] = k as u32;
                fill[v as usize] += 1;
            }
        }
        // Components and their Euler characteristics (closed: genus = (2 - chi) / 2).
        let mut dsu = Dsu::new(n);
        for t in &mesh.triangles {
            dsu.union(t[0], t[1]);
            dsu.union(t[0], t[2]);
        }
        let mut root_id = vec![u32::MAX; n];
        let mut comp = vec![u32::MAX; n];
        let mut chi: Vec<i64> = Vec::new();
        let mut comp_size: Vec<usize> = Vec::new();
        for v in 0..n {
            if nb_start[v] == nb_start[v + 1] {
                continue;
            }
            let r = dsu.find(v as u32) as usize;
            if root_id[r] == u32::MAX {
                root_id[r] = chi.len() as u32;
                chi.push(0);
                comp_size.push(0);
            }
            let c = root_id[r];
            comp[v] = c;
            chi[c as usize] += 1;
            comp_size[c as usize] += 1;
        }
        for &(a, _) in &edges {
            chi[comp[a as usize] as usize] -= 1;
        }
        for t in &mesh.triangles {
            chi[comp[t[0] as usize] as usize] += 1;
        }
        let comp_genus = chi.iter().map(|&x| (2 - x) / 2).collect();
        Some(Graph {
            nb_start,
            nb,
            tri_start,
            tris,
            tri_ids,
            comp,
            comp_size,
            comp_genus,
        })
    }

    fn comp_genus_positive(&self, v: u32) -> bool {
        let c = self.comp[v as usize];
        c != u32::MAX && self.comp_genus[c as usize] >= 1
    }

    fn neighbours(&self, v: u32) -> &[(u32, f64)] {
        &self.nb[self.nb_start[v as usize]..self.nb_start[v as usize + 1]]
    }

    fn triangles(&self, v: u32) -> &[[u32; 3]] {
        &self.tris[self.tri_start[v as usize]..self.tri_start[v as usize + 1]]
    }

    /// The handle radius of seed `s` if at most `limit` (module docs), and a loop through
    /// the tunnel ([`ShortHandle::loop_vertices`]).
    fn handle_radius(&self, s: u32, limit: f64, sc: &mut Scratch) -> Option<(f64, Vec<u32>)> {
        sc.reset();
        let mut heap = BinaryHeap::new();
        sc.set_dist(s, 0.0);
        heap.push(Reverse((Key(0.0), s)));
        let (mut v_in, mut e_in, mut f_in) = (0i64, 0i64, 0i64);
        let mut tests = 0;
        let mut found = None;
        while let Some(Reverse((Key(d), u))) = heap.pop() {
            if sc.inside[u as usize] || d > sc.dist[u as usize] {
                continue;
            }
            if d > limit {
                break;
            }
            sc.add(u);
            v_in += 1;
            e_in += self
                .neighbours(u)
                .iter()
                .filter(|&&(w, _)| sc.inside[w as usize])
                .count() as i64;
            f_in += self
                .triangles(u)
                .iter()
                .filter(|t| t.iter().all(|&w| sc.inside[w as usize]))
                .count() as i64;
            if v_in - e_in + f_in <= 0 && tests < MAX_TESTS_PER_SEED {
                tests += 1;
                if self.complement_connected(s, v_in as usize, sc) {
                    found = Some((d, self.loop_through(u, sc)));
                    break;
                }
            }
            for &(w, len) in self.neighbours(u) {
                let nd = d + len;
                if !sc.inside[w as usize] && nd < sc.dist[w as usize] {
                    sc.set_dist(w, nd);
                    sc.parent[w as usize] = u;
                    heap.push(Reverse((Key(nd), w)));
                }
            }
        }
        found
    }

    /// The loop closed by adding `u` to the region: `u`'s neighbours in the region fall in
    /// two or more fans (runs joined by the region's triangles at `u`: that is how the
    /// Euler characteristic dropped); the shortest paths from the least vertex of the first
    /// two fans back to where they meet, joined through `u`.
    fn loop_through(&self, u: u32, sc: &Scratch) -> Vec<u32> {
        let inn: Vec<u32> = self
            .neighbours(u)
            .iter()
            .map(|&(w, _)| w)
            .filter(|&w| sc.inside[w as usize])
            .collect();
        // Fans: the region's neighbours of `u` joined by the region's triangles at `u`.
        let mut fan: Vec<usize> = (0..inn.len()).collect();
        fn root(f: &mut [usize], mut i: usize) -> usize {
            while f[i] != i {
                f[i] = f[f[i]];
                i = f[i];
            }
            i
        }
        for t in self.triangles(u) {
            let others: Vec<usize> = t
                .iter()
                .filter(|&&w| w != u)
                .filter_map(|w| inn.iter().position(|x| x == w))
                .collect();
            if let [a, b] = others[..] {
                let (ra, rb) = (root(&mut fan, a), root(&mut fan, b));
                fan[ra.max(rb)] = ra.min(rb);
            }
        }
        let mut firsts: Vec<(usize, u32)> = Vec::new();
        for (i, &w) in inn.iter().enumerate() {
            let r = root(&mut fan, i);
            match firsts.iter_mut().find(|x| x.0 == r) {
                Some(x) => x.1 = x.1.min(w),
                None => firsts.push((r, w)),
            }
        }
        firsts.sort_by_key(|x| x.1);
        let (Some(&(_, a)), Some(&(_, b))) = (firsts.first(), firsts.get(1)) else {
            return vec![u];
        };
        let path = |mut v: u32| {
            let mut p = vec![v];
            while sc.parent[v as usize] != u32::MAX {
                v = sc.parent[v as usize];
                p.push(v);
            }
            p
        };
        let (pa, pb) = (path(a), path(b));
        // Drop the common tail (towards the seed) but its first vertex: where they meet.
        let common = pa
            .iter()
            .rev()
            .zip(pb.iter().rev())
            .take_while(|(x, y)| x == y)
            .count();
        let mut lp: Vec<u32> = pa[..pa.len() - common + 1].to_vec();
        lp.extend(pb[..pb.len() - common].iter().rev());
        lp.push(u);
        lp
    }

    /// Whether the vertices of `s`'s component outside the region (`sc.inside`, `inside`
    /// of them) are connected by edges between them.
    fn complement_connected(&self, s: u32, inside: usize, sc: &mut Scratch) -> bool {
        let total = self.comp_size[self.comp[s as usize] as usize];
        let outside = total - inside;
        // A start: a neighbour of the region outside it.
        let Some(start) = sc
            .region
            .iter()
            .flat_map(|&u| self.neighbours(u))
            .map(|&(w, _)| w)
            .find(|&w| !sc.inside[w as usize])
        else {
            return false;
        };
        sc.stamp += 1;
        let stamp = sc.stamp;
        sc.seen[start as usize] = stamp;
        sc.stack.clear();
        sc.stack.push(start);
        let mut reached = 1;
        while let Some(u) = sc.stack.pop() {
            for &(w, _) in self.neighbours(u) {
                if !sc.inside[w as usize] && sc.seen[w as usize] != stamp {
                    sc.seen[w as usize] = stamp;
                    reached += 1;
                    sc.stack.push(w);
                }
            }
        }
        reached == outside
    }
}

/// Exclusive prefix sums of counts shifted by one (`c[v + 1]` is `v`'s count).
fn prefix(mut c: Vec<usize>) -> Vec<usize> {
    for i in 1..c.len() {
        c[i] += c[i - 1];
    }
    c
}

/// A distance ordered by `total_cmp` (the heap's key; distances are finite).
#[derive(Clone, Copy, PartialEq)]
struct Key(f64);
impl Eq for Key {}
impl PartialOrd for Key {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Key {
    fn cmp(&self, o: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&o.0)
    }
}

/// Per-thread buffers, reset between seeds through the lists of what was touched.
struct Scratch {
    dist: Vec<f64>,
    /// Each reached vertex's predecessor on its shortest path (`u32::MAX`: the seed).
    parent: Vec<u32>,
    inside: Vec<bool>,
    seen: Vec<u32>,
    stamp: u32,
    touched: Vec<u32>,
    region: Vec<u32>,
    stack: Vec<u32>,
}

impl Scratch {
    fn new(n: usize) -> Scratch {
        Scratch {
            dist: vec![f64::INFINITY; n],
            parent: vec![u32::MAX; n],
            inside: vec![false; n],
            seen: vec![0; n],
            stamp: 0,
            touched: Vec::new(),
            region: Vec::new(),
            stack: Vec::new(),
        }
    }

    fn reset(&mut self) {
        for &v in &self.touched {
            self.dist[v as usize] = f64::INFINITY;
            self.parent[v as usize] = u32::MAX;
        }
        for &v in &self.region {
            self.inside[v as usize] = false;
        }
        self.touched.clear();
        self.region.clear();
        if self.stamp > u32::MAX - 8 {
            self.seen.iter_mut().for_each(|x| *x = 0);
            self.stamp = 0;
        }
    }

    fn set_dist(&mut self, v: u32, d: f64) {
        if self.dist[v as usize] == f64::INFINITY {
            self.touched.push(v);
        }
        self.dist[v as usize] = d;
    }

    fn add(&mut self, v: u32) {
        self.inside[v as usize] = true;
        self.region.push(v);
    }
}

#[cfg(test)]
mod tests;
