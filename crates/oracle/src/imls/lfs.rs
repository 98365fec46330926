//! P2 for point sets (section 6.6.3): the local feature size estimated by *shrinking balls*
//! (Ma, Bae & Choi 2012), whose radii converge to the Voronoi poles' medial balls.
//!
//! Neighbours closer than `rho` (about the kernel radius) are ignored so that noise does not
//! shrink the balls.

use glam::DVec3;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;
use std::num::NonZeroUsize;

/// Local feature size estimated on a subsample (at most about 1024 input points).
pub(super) struct LfsSample {
    /// The subsample.
    pub points: Vec<DVec3>,
    /// The estimate at each subsample point: the smaller of its two shrinking balls.
    pub lfs: Vec<f64>,
    /// A kd-tree of `points`.
    pub tree: ImmutableKdTree<f64, 3>,
}

impl LfsSample {
    /// The estimate on every `⌈n / 1024⌉`-th input point (in parallel): the smaller of the
    /// inner and outer shrinking balls along `normal(i)` (a unit normal at input point `i`),
    /// ignoring neighbours within `rho`, capped at `cap`. `tree` is a kd-tree of `points`.
    pub fn build(
        points: &[DVec3],
        tree: &ImmutableKdTree<f64, 3>,
        rho: f64,
        cap: f64,
        normal: impl Fn(usize) -> DVec3 + Sync,
    ) -> LfsSample {
        let n = points.len();
        let step = n.div_ceil(1024).max(1);
        let idx: Vec<usize> = (0..n).step_by(step).collect();
        let lfs: Vec<f64> = idx
            .par_iter()
            .map(|&i| {
                let n = normal(i);
                let inner = shrinking_ball(points, tree, i, -n, rho, cap);
                let outer = shrinking_ball(points, tree, i, n, rho, cap);
                inner.min(outer)
            })
            .collect();
        let points: Vec<DVec3> = idx.iter().map(|&i| points[i]).collect();
        let coords: Vec<[f64; 3]> = points.iter().map(|p| p.to_array()).collect();
        let tree = ImmutableKdTree::<f64, 3>::new_from_slice(&coords)
            .expect("kd-tree construction from finite points");
        LfsSample { points, lfs, tree }
    }

    /// The estimate at the subsample point nearest to `x`.
    pub fn at(&self, x: DVec3) -> f64 {
        let r = self
            .tree
            .query(&x.to_array())
            .nearest_one::<SquaredEuclidean<f64>>()
            .execute();
        self.lfs[r.item as usize]
    }
}

/// Radius of the ball tangent at point `i` with center on the side of the unit vector `n`
/// that contains no input point farther than `rho` from point `i`, capped at `cap`.
fn shrinking_ball(
    points: &[DVec3],
    tree: &ImmutableKdTree<f64, 3>,
    i: usize,
    n: DVec3,
    rho: f64,
    cap: f64,
) -> f64 {
    let p = points[i];
    let mut r = cap;
    let kq = NonZeroUsize::new(32.min(points.len())).expect("nonzero");
    for _ in 0..40 {
        let c = p + n * r;
        // The nearest point to c that is not a near neighbour of p (usually the nearest).
        let j = tree
            .query(&c.to_array())
            .nearest_one::<SquaredEuclidean<f64>>()
            .execute()
            .item as usize;
        let q = if (points[j] - p).length_squared() > rho * rho {
            Some(points[j])
        } else {
            tree.query(&c.to_array())
                .nearest_n::<SquaredEuclidean<f64>>(kq)
                .execute()
                .iter()
                .map(|x| points[x.item as usize])
                .find(|q| (*q - p).length_squared() > rho * rho)
        };
        let Some(q) = q else { break };
        if (q - c).length() >= r * (1.0 - 1e-9) {
            break;
        }
        let pq = q - p;
        let den = 2.0 * n.dot(pq);
        if den.is_nan() || den <= 0.0 {
            break;
        }
        let r_new = pq.length_squared() / den;
        if r_new.is_nan() || r_new >= r {
            break;
        }
        r = r_new;
    }
    r
}
