//! Exact triangle-triangle tests against an independent exact reference (separating axes
//! in integer arithmetic), and the BVH search against brute force.
use glam::{DVec3, I64Vec3};
use meshio::TriMesh;
use proptest::prelude::*;
use verify::predicates::triangles_intersect;

/// Closed triangles with integer corners intersect iff no axis strictly separates them.
/// Candidate axes: both normals, the 9 edge-edge cross products and the in-plane edge
/// normals (needed when the triangles are coplanar). All arithmetic exact in i64.
fn sat(t: [I64Vec3; 3], u: [I64Vec3; 3]) -> bool {
    let edges = |x: [I64Vec3; 3]| [x[1] - x[0], x[2] - x[1], x[0] - x[2]];
    let (et, eu) = (edges(t), edges(u));
    let (nt, nu) = (et[0].cross(et[1]), eu[0].cross(eu[1]));
    let mut axes = vec![nt, nu];
    for a in et {
        for b in eu {
            axes.push(a.cross(b));
        }
        axes.push(nt.cross(a));
    }
    for b in eu {
        axes.push(nu.cross(b));
    }
    for ax in axes {
        if ax == I64Vec3::ZERO {
            continue;
        }
        let p = |x: [I64Vec3; 3]| {
            let d = x.map(|v| v.dot(ax));
            (d[0].min(d[1]).min(d[2]), d[0].max(d[1]).max(d[2]))
        };
        let ((a0, a1), (b0, b1)) = (p(t), p(u));
        if a1 < b0 || b1 < a0 {
            return false;
        }
    }
    true
}

fn tri() -> impl Strategy<Value = [I64Vec3; 3]> {
    prop::array::uniform3(prop::array::uniform3(-3i64..=3).prop_map(I64Vec3::from_array))
        .prop_filter("non-degenerate", |t| {
            (t[1] - t[0]).cross(t[2] - t[0]) != I64Vec3::ZERO
        })
}

fn f(t: [I64Vec3; 3]) -> [DVec3; 3] {
    t.map(|v| v.as_dvec3())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(3000))]
    #[test]
    fn triangle_triangle_matches_separating_axes(t in tri(), u in tri()) {
        let want = sat(t, u);
        prop_assert_eq!(triangles_intersect(f(t), f(u)), want);
        prop_assert_eq!(triangles_intersect(f(u), f(t)), want);
        let r = [t[1], t[2], t[0]];
        let m = [t[0], t[2], t[1]];
        prop_assert_eq!(triangles_intersect(f(r), f(u)), want);
        prop_assert_eq!(triangles_intersect(f(m), f(u)), want);
        // Exact under scaling by a power of two and a representable translation.
        let s = |x: [DVec3; 3]| x.map(|v| v * 0.125 + DVec3::new(1e3, -7.5, 0.25));
        prop_assert_eq!(triangles_intersect(s(f(t)), s(f(u))), want);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    #[test]
    fn bvh_search_finds_every_intersecting_pair(tris in prop::collection::vec(tri(), 1..40)) {
        let mesh = TriMesh {
            vertices: tris.iter().flat_map(|t| f(*t)).collect(),
            triangles: (0..tris.len() as u32).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect(),
        };
        let bvh = verify::intersect::triangle_bvh(&mesh);
        let got = verify::intersect::self_intersections(&mesh, &bvh, usize::MAX);
        let mut want = Vec::new();
        for i in 0..tris.len() {
            for j in i + 1..tris.len() {
                if sat(tris[i], tris[j]) {
                    want.push([i, j]);
                }
            }
        }
        prop_assert_eq!(got.pairs_total, want.len());
        prop_assert_eq!(got.pairs, want);
    }

    #[test]
    fn shared_vertex_pairs_are_judged_beyond_the_vertex(t in tri(), u in tri()) {
        // u shares t's first vertex by index. The pair intersects improperly iff the opposite
        // edge of one triangle meets the other; the reference decides the segment tests by
        // separating axes in exact integer arithmetic.
        let v = t[0];
        let u2 = [v, u[1], u[2]];
        if (u2[1] - u2[0]).cross(u2[2] - u2[0]) == I64Vec3::ZERO {
            return Ok(());
        }
        let mesh = TriMesh {
            vertices: vec![f(t)[0], f(t)[1], f(t)[2], f(u2)[1], f(u2)[2]],
            triangles: vec![[0, 1, 2], [0, 3, 4]],
        };
        let got = verify::intersect::pair_intersects(&mesh, 0, 1);
        let seg = |a: I64Vec3, b: I64Vec3, x: [I64Vec3; 3]| sat_segment(a, b, x);
        let want = seg(t[1], t[2], u2) || seg(u2[1], u2[2], t);
        prop_assert_eq!(got, want);
    }
}

/// Closed segment [a, b] against a closed triangle, by separating axes (exact in i64).
fn sat_segment(a: I64Vec3, b: I64Vec3, x: [I64Vec3; 3]) -> bool {
    let e = b - a;
    let ex = [x[1] - x[0], x[2] - x[1], x[0] - x[2]];
    let n = ex[0].cross(ex[1]);
    let mut axes = vec![n];
    for d in ex {
        axes.push(e.cross(d));
        axes.push(n.cross(d));
    }
    // In-plane normal of the segment for the coplanar case, and one orthogonal to it.
    axes.push(n.cross(e));
    axes.push(e.cross(n.cross(e)));
    for ax in axes {
        if ax == I64Vec3::ZERO {
            continue;
        }
        let (pa, pb) = (a.dot(ax), b.dot(ax));
        let d = x.map(|v| v.dot(ax));
        let (s0, s1) = (pa.min(pb), pa.max(pb));
        let (t0, t1) = (d[0].min(d[1]).min(d[2]), d[0].max(d[1]).max(d[2]));
        if s1 < t0 || t1 < s0 {
            return false;
        }
    }
    true
}

#[test]
fn many_grid_pairs_agree_with_separating_axes_and_cover_both_answers() {
    let mut s: u64 = 12345;
    let mut next = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 33) % 5) as i64 - 2
    };
    let mut tri = || loop {
        let t = [0; 3].map(|_| I64Vec3::new(next(), next(), next()));
        if (t[1] - t[0]).cross(t[2] - t[0]) != I64Vec3::ZERO {
            return t;
        }
    };
    let (mut yes, mut no, mut coplanar) = (0, 0, 0);
    for _ in 0..50_000 {
        let (t, u) = (tri(), tri());
        let want = sat(t, u);
        assert_eq!(triangles_intersect(f(t), f(u)), want, "{t:?} {u:?}");
        if want {
            yes += 1
        } else {
            no += 1
        }
        let n = (t[1] - t[0]).cross(t[2] - t[0]);
        if u.iter().all(|p| (*p - t[0]).dot(n) == 0) {
            coplanar += 1;
        }
    }
    assert!(
        yes > 5000 && no > 5000 && coplanar > 50,
        "{yes} {no} {coplanar}"
    );
}
