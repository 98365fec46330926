//! Greedy farthest-point selection (ours; Gonzalez 1985): well-spread subsets of seed points
//! (the oracles' P1 seeds, the mesher's control points E'_i of section 6.4.3, component
//! representatives).

use glam::DVec3;

/// Greedy farthest-point order: up to `k` indices into `pool`, each the pool point farthest
/// from `fixed` and from the points already chosen (squared Euclidean distance, with no
/// `fixed` points the first pick is index 0). Ties go to the lowest index, so the result is
/// deterministic.
///
/// With `min_sep = Some(s)` the selection stops when the next point would be within `s` of
/// the chosen ones (duplicates). With `None` it always makes `k.min(pool.len())` picks: once
/// every point is at distance 0 (duplicates in `pool`), already chosen indices come again.
///
/// ```
/// use glam::DVec3;
/// let pool = [DVec3::ZERO, DVec3::X, DVec3::splat(3.0), DVec3::X];
/// assert_eq!(geom::farthest::farthest_points(&[], &pool, 4, None), vec![0, 2, 1, 0]);
/// assert_eq!(geom::farthest::farthest_points(&[], &pool, 4, Some(0.0)), vec![0, 2, 1]);
/// ```
pub fn farthest_points(
    fixed: &[DVec3],
    pool: &[DVec3],
    k: usize,
    min_sep: Option<f64>,
) -> Vec<usize> {
    let mut out = Vec::new();
    let k = k.min(pool.len());
    if k == 0 {
        return out;
    }
    // d2[i]: squared distance from pool[i] to the fixed and chosen points (+inf if none).
    let mut d2: Vec<f64> = pool
        .iter()
        .map(|p| {
            fixed
                .iter()
                .map(|q| (*p - *q).length_squared())
                .fold(f64::INFINITY, f64::min)
        })
        .collect();
    let sep2 = min_sep.map(|s| s * s);
    while out.len() < k {
        let mut best = 0;
        for i in 1..pool.len() {
            if d2[i] > d2[best] {
                best = i;
            }
        }
        if sep2.is_some_and(|s| d2[best] <= s) {
            break;
        }
        out.push(best);
        let q = pool[best];
        for (p, d) in pool.iter().zip(d2.iter_mut()) {
            *d = d.min((*p - q).length_squared());
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// Each pick maximises the distance to the fixed and earlier picks (lowest index on
        /// ties), and no index is picked twice while an unpicked point is farther.
        #[test]
        fn each_pick_is_the_farthest(
            pts in prop::collection::vec(prop::array::uniform3(-4i32..4), 1..40),
            nfixed in 0usize..3,
            k in 0usize..45,
        ) {
            let pool: Vec<DVec3> = pts.iter().map(|p| DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64)).collect();
            let fixed: Vec<DVec3> = pool.iter().take(nfixed).map(|p| *p + 0.5).collect();
            let got = farthest_points(&fixed, &pool, k, None);
            prop_assert_eq!(got.len(), k.min(pool.len()));
            let mut chosen = fixed.clone();
            for &g in &got {
                let dist = |i: usize| chosen.iter().map(|q| (pool[i] - *q).length_squared()).fold(f64::INFINITY, f64::min);
                let best = (0..pool.len()).map(dist).fold(f64::NEG_INFINITY, f64::max);
                prop_assert_eq!(dist(g), best);
                prop_assert!((0..g).all(|i| dist(i) < best));
                chosen.push(pool[g]);
            }
            let sep = farthest_points(&fixed, &pool, k, Some(0.0));
            prop_assert!(sep.len() <= got.len() && got[..sep.len()] == sep[..]);
            let mut uniq = sep.clone();
            uniq.sort_unstable();
            uniq.dedup();
            prop_assert_eq!(uniq.len(), sep.len());
        }
    }
}
