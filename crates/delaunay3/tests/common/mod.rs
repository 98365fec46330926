#![allow(dead_code)]
use delaunay3::{DVec3, Triangulation};
use std::collections::BTreeSet;

/// The workspace's one seeded generator (SplitMix64) for test data.
pub use geom::SplitMix64 as Rng;

/// A uniform point of the unit cube: three draws of [`Rng::next_f64`] (x, y, z).
pub fn cube_point(r: &mut Rng) -> DVec3 {
    DVec3::new(r.next_f64(), r.next_f64(), r.next_f64())
}

/// Distinct points (bitwise after -0 normalization) of `pts`.
pub fn distinct(pts: &[DVec3]) -> usize {
    let s: BTreeSet<[u64; 3]> = pts
        .iter()
        .map(|p| (*p + DVec3::ZERO).to_array().map(f64::to_bits))
        .collect();
    s.len()
}

/// The finite tetrahedra as sorted tuples of point coordinates (bits): comparable across
/// triangulations with different vertex numbering.
pub fn tets_by_points(t: &Triangulation) -> BTreeSet<[[u64; 3]; 4]> {
    t.finite_cells()
        .map(|c| {
            let mut q = t
                .cell_vertices(c)
                .map(|v| (t.point(v) + DVec3::ZERO).to_array().map(f64::to_bits));
            q.sort_unstable();
            q
        })
        .collect()
}

/// Builds with `insert` one by one and checks validity and vertex coverage.
pub fn build_checked(pts: &[DVec3]) -> Triangulation {
    let mut t = Triangulation::new();
    for &p in pts {
        let r = t.insert(p).expect("valid point");
        let v = match r {
            delaunay3::Insertion::New(v) | delaunay3::Insertion::Duplicate(v) => v,
        };
        assert_eq!(t.point(v), p);
    }
    if let Err(e) = t.is_valid() {
        panic!("invalid triangulation of {} points: {e}", pts.len());
    }
    assert_eq!(t.num_vertices(), distinct(pts));
    t
}

/// Exact-enough brute force (for general position only): all 4-subsets whose circumsphere
/// contains no other point, using the crate's exact predicates.
pub fn brute_force(pts: &[DVec3]) -> BTreeSet<[[u64; 3]; 4]> {
    use delaunay3::predicates::{Sign, insphere, orient3d};
    let n = pts.len();
    let mut out = BTreeSet::new();
    for a in 0..n {
        for b in a + 1..n {
            for c in b + 1..n {
                for d in c + 1..n {
                    let mut q = [pts[a], pts[b], pts[c], pts[d]];
                    match orient3d(q[0], q[1], q[2], q[3]) {
                        Sign::Zero => continue,
                        Sign::Negative => q.swap(0, 1),
                        Sign::Positive => {}
                    }
                    let empty = (0..n)
                        .filter(|&e| ![a, b, c, d].contains(&e))
                        .all(|e| insphere(q[0], q[1], q[2], q[3], pts[e]) == Sign::Negative);
                    if empty {
                        let mut k = q.map(|p| p.to_array().map(f64::to_bits));
                        k.sort_unstable();
                        out.insert(k);
                    }
                }
            }
        }
    }
    out
}

/// All integer points with x^2 + y^2 + z^2 = r2, scaled by `s` and shifted by `o` (both
/// chosen so that the arithmetic is exact): exactly cospherical points.
pub fn sphere_points(r2: i64, s: f64, o: DVec3) -> Vec<DVec3> {
    let r = (r2 as f64).sqrt() as i64 + 1;
    let mut v = Vec::new();
    for x in -r..=r {
        for y in -r..=r {
            for z in -r..=r {
                if x * x + y * y + z * z == r2 {
                    v.push(DVec3::new(x as f64, y as f64, z as f64) * s + o);
                }
            }
        }
    }
    v
}

/// Checks that bulk insertion of `pts` gives a valid triangulation with the same tetrahedra
/// as one-by-one insertion ([`build_checked`], returned) and maps every input to its point.
pub fn bulk_agrees_with_one_by_one(pts: &[DVec3]) -> Triangulation {
    let t = build_checked(pts);
    let mut b = Triangulation::new();
    let ids = b.insert_bulk(pts).unwrap();
    assert!(b.is_valid().is_ok());
    for (i, &v) in ids.iter().enumerate() {
        assert_eq!(b.point(v), pts[i]);
    }
    // Unique triangulation: same tetrahedra whatever the insertion order.
    assert_eq!(tets_by_points(&t), tets_by_points(&b));
    t
}

/// The integer grid `{0..n}^3`, x slowest, z fastest.
pub fn grid(n: u32) -> Vec<DVec3> {
    let mut pts = Vec::new();
    for x in 0..n {
        for y in 0..n {
            for z in 0..n {
                pts.push(DVec3::new(x as f64, y as f64, z as f64));
            }
        }
    }
    pts
}
