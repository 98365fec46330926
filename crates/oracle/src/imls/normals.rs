//! Normals of an unoriented point set (ours, after Hoppe et al. 1992): PCA on the `k` nearest
//! neighbours, oriented by propagation along a minimum spanning tree of the kNN graph, one
//! tree per graph component, rooted at its highest point whose normal points up (+z).

use super::linalg;
use glam::DVec3;
use rayon::prelude::*;

/// Estimate normals by PCA and orient them by MST propagation; returns the normals and the
/// root (highest point) of each component of the kNN graph.
pub(super) fn estimate_normals(
    points: &[DVec3],
    knn: &[Vec<u32>],
    k: usize,
) -> (Vec<DVec3>, Vec<usize>) {
    let mut normals: Vec<DVec3> = knn
        .par_iter()
        .enumerate()
        .map(|(i, nb)| {
            let m = k.min(nb.len());
            let it = std::iter::once(points[i]).chain(nb[..m].iter().map(|&j| points[j as usize]));
            let (cov, _) = linalg::covariance(it);
            let (_, vecs) = linalg::sym_eigen(cov);
            vecs[0]
        })
        .collect();
    let roots = propagate(points, knn, k.min(K_GRAPH), &mut normals);
    (normals, roots)
}

/// Components of the kNN graph (its first `k` neighbours, symmetrized), as the highest point
/// (largest z, then smallest index) of each, in decreasing z order.
pub(super) fn components_roots(points: &[DVec3], knn: &[Vec<u32>], k: usize) -> Vec<usize> {
    let n = points.len();
    let mut uf: Vec<u32> = (0..n as u32).collect();
    fn find(uf: &mut [u32], mut x: u32) -> u32 {
        while uf[x as usize] != x {
            uf[x as usize] = uf[uf[x as usize] as usize];
            x = uf[x as usize];
        }
        x
    }
    for (i, nb) in knn.iter().enumerate() {
        for &j in &nb[..k.min(nb.len())] {
            let (a, b) = (find(&mut uf, i as u32), find(&mut uf, j));
            if a != b {
                uf[a.max(b) as usize] = a.min(b);
            }
        }
    }
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| points[b].z.total_cmp(&points[a].z).then(a.cmp(&b)));
    let mut seen = vec![false; n];
    let mut roots = Vec::new();
    for i in order {
        let r = find(&mut uf, i as u32) as usize;
        if !seen[r] {
            seen[r] = true;
            roots.push(i);
        }
    }
    roots
}

/// Neighbours per point in the orientation graph (Hoppe et al. use about 8).
pub(super) const K_GRAPH: usize = 8;

/// Prim's (approximate) minimum spanning tree over the symmetric kNN graph with weights
/// `1 − |n_i·n_j|` (plus a penalty for edges along the normals),
/// flipping each normal to agree with its parent. Components are started from their highest
/// point (largest z, then smallest index), whose normal is oriented to +z.
fn propagate(points: &[DVec3], knn: &[Vec<u32>], k: usize, normals: &mut [DVec3]) -> Vec<usize> {
    let n = points.len();
    // Symmetric adjacency (CSR).
    let mut deg = vec![0u32; n + 1];
    for (i, nb) in knn.iter().enumerate() {
        for &j in &nb[..k.min(nb.len())] {
            deg[i] += 1;
            deg[j as usize] += 1;
        }
    }
    let mut start = vec![0usize; n + 1];
    for i in 0..n {
        start[i + 1] = start[i] + deg[i] as usize;
    }
    let mut fill = start.clone();
    let mut adj = vec![0u32; start[n]];
    for (i, nb) in knn.iter().enumerate() {
        for &j in &nb[..k.min(nb.len())] {
            adj[fill[i]] = j;
            fill[i] += 1;
            adj[fill[j as usize]] = i as u32;
            fill[j as usize] += 1;
        }
    }
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| points[b].z.total_cmp(&points[a].z).then(a.cmp(&b)));
    let mut visited = vec![false; n];
    let mut roots = Vec::new();
    // Prim's algorithm with a bucket queue (weights in [0, 2] quantized to 1/128): an
    // approximate minimum spanning tree, enough for orientation and O(1) per edge. Buckets are
    // stacks, so the order is deterministic.
    const BUCKETS: usize = 257;
    let mut buckets: Vec<Vec<(u32, u32)>> = vec![Vec::new(); BUCKETS];
    for &root in &order {
        if visited[root] {
            continue;
        }
        roots.push(root);
        visited[root] = true;
        if normals[root].z < 0.0 {
            normals[root] = -normals[root];
        }
        let push = |buckets: &mut [Vec<(u32, u32)>],
                    i: usize,
                    normals: &[DVec3],
                    visited: &[bool],
                    cur: &mut usize| {
            for &j in &adj[start[i]..start[i + 1]] {
                if !visited[j as usize] {
                    // Hoppe's 1 − |n_i·n_j|, plus a penalty for edges along the normals: those
                    // jump across thin parts (two sheets with parallel normals), where copying
                    // the orientation is wrong.
                    let (ni, nj) = (normals[i], normals[j as usize]);
                    let d = (points[j as usize] - points[i]).normalize_or_zero();
                    let w = 1.0 - ni.dot(nj).abs() + 0.5 * (ni.dot(d).abs() + nj.dot(d).abs());
                    let b = ((w * 128.0) as usize).min(BUCKETS - 1);
                    buckets[b].push((j, i as u32));
                    *cur = (*cur).min(b);
                }
            }
        };
        let mut cur = BUCKETS;
        push(&mut buckets, root, normals, &visited, &mut cur);
        loop {
            while cur < BUCKETS && buckets[cur].is_empty() {
                cur += 1;
            }
            if cur == BUCKETS {
                break;
            }
            let (j, i) = buckets[cur].pop().expect("non-empty bucket");
            let j = j as usize;
            if visited[j] {
                continue;
            }
            visited[j] = true;
            if normals[i as usize].dot(normals[j]) < 0.0 {
                normals[j] = -normals[j];
            }
            push(&mut buckets, j, normals, &visited, &mut cur);
        }
    }
    roots
}
