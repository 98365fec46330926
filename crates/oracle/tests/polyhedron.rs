//! Polyhedron oracle: exact crossings (shared edges/vertices counted once), winding number,
//! holes, seeds, projection, sharp edges and input errors.

use glam::DVec3;
use meshio::TriMesh;
use oracle::Surface;
use oracle::polyhedron::{
    PolyhedronError, PolyhedronSurface, distance_to_sharp_edges, sharp_edge_deviation,
};
use proptest::prelude::*;

/// Read a PLY triangle mesh with the project's reader.
fn read_ply(path: &str) -> TriMesh {
    meshio::read(path).expect("fixture mesh")
}

fn bunny() -> TriMesh {
    read_ply(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../fixtures/models/bunny.ply"
    ))
}

/// Unit cube [0,1]^3, 12 triangles, counter-clockwise seen from outside.
fn cube() -> TriMesh {
    let v: Vec<DVec3> = (0..8)
        .map(|i| DVec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64))
        .collect();
    // Quads (outward CCW) split along a diagonal.
    let quads = [
        [0, 2, 3, 1], // z = 0, normal -z
        [4, 5, 7, 6], // z = 1
        [0, 1, 5, 4], // y = 0
        [2, 6, 7, 3], // y = 1
        [0, 4, 6, 2], // x = 0
        [1, 3, 7, 5], // x = 1
    ];
    let mut t = Vec::new();
    for q in quads {
        t.push([q[0], q[1], q[2]]);
        t.push([q[0], q[2], q[3]]);
    }
    TriMesh {
        vertices: v,
        triangles: t,
    }
}

/// Icosphere of radius 1 with `k` subdivisions (outward CCW).
fn icosphere(k: usize) -> TriMesh {
    let p = (1.0 + 5f64.sqrt()) / 2.0;
    let mut v: Vec<DVec3> = [
        [-1.0, p, 0.0],
        [1.0, p, 0.0],
        [-1.0, -p, 0.0],
        [1.0, -p, 0.0],
        [0.0, -1.0, p],
        [0.0, 1.0, p],
        [0.0, -1.0, -p],
        [0.0, 1.0, -p],
        [p, 0.0, -1.0],
        [p, 0.0, 1.0],
        [-p, 0.0, -1.0],
        [-p, 0.0, 1.0],
    ]
    .iter()
    .map(|a| DVec3::from_array(*a).normalize())
    .collect();
    let mut t: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..k {
        let mut mid = std::collections::BTreeMap::new();
        let mut nt = Vec::new();
        let mut m = |a: u32, b: u32, v: &mut Vec<DVec3>| {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                v.push((v[a as usize] + v[b as usize]).normalize());
                (v.len() - 1) as u32
            })
        };
        for [a, b, c] in t {
            let ab = m(a, b, &mut v);
            let bc = m(b, c, &mut v);
            let ca = m(c, a, &mut v);
            nt.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        t = nt;
    }
    TriMesh {
        vertices: v,
        triangles: t,
    }
}

fn count(s: &PolyhedronSurface, a: DVec3, b: DVec3) -> usize {
    let mut out = Vec::new();
    s.crossings(a, b, &mut out);
    out.len()
}

#[test]
fn cube_crossings_through_faces_edges_and_vertices_are_counted_once() {
    let s = PolyhedronSurface::new(&cube()).unwrap();
    let d = DVec3::new;
    // Through two faces (interior of triangles).
    assert_eq!(count(&s, d(0.3, 0.4, -1.0), d(0.3, 0.4, 2.0)), 2);
    // Through the diagonals of the quads (edge shared by the two triangles of a face).
    assert_eq!(count(&s, d(0.5, 0.5, -1.0), d(0.5, 0.5, 2.0)), 2);
    assert_eq!(count(&s, d(0.25, 0.25, -1.0), d(0.25, 0.25, 2.0)), 2);
    // Through cube edges (shared by two faces at 90 degrees), transversally.
    assert_eq!(count(&s, d(-1.0, -1.0, 0.5), d(2.0, 2.0, 0.5)), 2);
    assert_eq!(count(&s, d(0.5, -1.0, -1.0), d(0.5, 2.0, 2.0)), 2);
    // Through two opposite vertices (main diagonal): each vertex counted once.
    assert_eq!(count(&s, d(-1.0, -1.0, -1.0), d(2.0, 2.0, 2.0)), 2);
    assert_eq!(count(&s, d(2.0, -1.0, -1.0), d(-1.0, 2.0, 2.0)), 2);
    // Crossing points are on the cube.
    let mut xs = Vec::new();
    s.crossings(d(-1.0, -1.0, -1.0), d(2.0, 2.0, 2.0), &mut xs);
    assert!((xs[0] - DVec3::ZERO).length() < 1e-12 && (xs[1] - DVec3::ONE).length() < 1e-12);
    // Entering and leaving through two cube edges (the diagonal planes x+z=1, x+y=1).
    assert_eq!(count(&s, d(-0.5, 0.5, 1.5), d(1.5, 0.5, -0.5)), 2);
    assert_eq!(count(&s, d(1.5, -0.5, 0.5), d(-0.5, 1.5, 0.5)), 2);
    // Grazing a convex edge from outside (touches the cube only along x=z=1): 0 or 2, never 1.
    let n = count(&s, d(2.0, 0.5, 0.0), d(0.0, 0.5, 2.0));
    assert!(n.is_multiple_of(2), "edge graze {n}");
    // Touching a vertex only from outside.
    let n = count(&s, d(2.0, 0.0, 1.0), d(0.0, 2.0, 1.0));
    assert!(n.is_multiple_of(2), "vertex graze {n}");
    // Lying in a face's plane: not a crossing of that face.
    assert_eq!(count(&s, d(-1.0, 0.5, 0.0), d(2.0, 0.5, 0.0)) % 2, 0);
    // Ending exactly on a face: a consistent answer, whichever the side.
    let n1 = count(&s, d(0.3, 0.3, -1.0), d(0.3, 0.3, 0.0));
    let n2 = count(&s, d(0.3, 0.3, 0.0), d(0.3, 0.3, 0.5));
    assert_eq!(n1 + n2, 1, "split at the surface: {n1} + {n2}");
}

#[test]
fn sphere_crossings_through_vertices_and_edges() {
    let m = icosphere(3);
    let s = PolyhedronSurface::new(&m).unwrap();
    // Lines through the center and through each vertex / each edge midpoint.
    for (i, v) in m.vertices.iter().enumerate() {
        assert_eq!(count(&s, -2.0 * *v, 2.0 * *v), 2, "vertex {i}");
    }
    for t in m.triangles.iter().take(300) {
        let mid = 0.5 * (m.vertices[t[0] as usize] + m.vertices[t[1] as usize]);
        assert_eq!(count(&s, -3.0 * mid, 3.0 * mid), 2);
        // And a line through the edge midpoint, not through the center.
        let dir = (m.vertices[t[2] as usize] - mid).cross(mid).normalize();
        let a = mid + 0.5 * dir - 0.7 * mid;
        let b = mid - 0.5 * dir + 0.7 * mid;
        assert_eq!(count(&s, a, b), 1);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]
    /// Parity of crossings equals whether the end points are on different sides, for random
    /// segments with end points on a grid that hits vertices, edges and faces of the cube.
    #[test]
    fn cube_parity_matches_inside_test(a in prop::array::uniform3(-2i32..=6), b in prop::array::uniform3(-2i32..=6)) {
        let s = PolyhedronSurface::new(&cube()).unwrap();
        let p = |c: [i32; 3]| DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64) / 4.0;
        let (pa, pb) = (p(a), p(b));
        let strict_in = |q: DVec3| q.cmpgt(DVec3::ZERO).all() && q.cmplt(DVec3::ONE).all();
        let strict_out = |q: DVec3| q.cmplt(DVec3::ZERO).any() || q.cmpgt(DVec3::ONE).any();
        // Only judge segments whose end points are off the surface.
        prop_assume!((strict_in(pa) || strict_out(pa)) && (strict_in(pb) || strict_out(pb)));
        let n = count(&s, pa, pb);
        prop_assert_eq!(n % 2 == 1, strict_in(pa) != strict_in(pb), "n = {}", n);
        prop_assert!(n <= 2 || pa == pb);
    }

    /// Parity is additive even when the end and split points lie on faces, edges or vertices
    /// of the cube (all three are perturbed in the same direction, so they are classified
    /// consistently).
    #[test]
    fn cube_parity_is_additive_at_degenerate_points(
        a in prop::array::uniform3(-1i32..=5),
        m in prop::array::uniform3(0i32..=4),
        b in prop::array::uniform3(-1i32..=5),
    ) {
        let s = PolyhedronSurface::new(&cube()).unwrap();
        let p = |c: [i32; 3]| DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64) / 4.0;
        let (pa, pm, pb) = (p(a), p(m), p(b));
        prop_assume!(pa != pm && pm != pb && pa != pb);
        let n1 = count(&s, pa, pm);
        let n2 = count(&s, pm, pb);
        let n = count(&s, pa, pb);
        prop_assert_eq!((n1 + n2) % 2, n % 2, "{} + {} vs {}", n1, n2, n);
        prop_assert_eq!(count(&s, pb, pa) % 2, n % 2);
    }

    /// Splitting a segment at any point conserves the crossing count (no double counting at
    /// the split point, whatever lies there).
    #[test]
    fn sphere_count_is_additive(a in prop::array::uniform3(-2.0f64..2.0), b in prop::array::uniform3(-2.0f64..2.0), t in 0.0f64..1.0) {
        let s = PolyhedronSurface::new(&icosphere(1)).unwrap();
        let (pa, pb) = (DVec3::from_array(a), DVec3::from_array(b));
        let pm = pa.lerp(pb, t);
        let whole = count(&s, pa, pb);
        let split = count(&s, pa, pm) + count(&s, pm, pb);
        // The split point is a generic point: it is on the surface with probability 0.
        prop_assert_eq!(whole, split);
    }
}

#[test]
fn winding_number_inside_outside_and_with_a_hole() {
    let m = icosphere(3);
    let s = PolyhedronSurface::new(&m).unwrap();
    for p in [
        DVec3::ZERO,
        DVec3::new(0.5, 0.2, -0.3),
        DVec3::new(0.0, 0.0, 0.95),
    ] {
        // The far field is approximated (second-order expansion, beta = 2): ~6% at worst (the
        // sphere center, where every node is at the same distance).
        assert!(
            (s.winding_number(p) - 1.0).abs() < 0.1,
            "{p}: {}",
            s.winding_number(p)
        );
        assert!(s.value(p) < 0.0);
    }
    for p in [
        DVec3::splat(2.0),
        DVec3::new(0.0, 0.0, 1.05),
        DVec3::new(5.0, 0.0, 0.0),
    ] {
        assert!(s.winding_number(p).abs() < 0.1, "{p}");
        assert!(s.value(p) > 0.0);
    }
    // Reversed orientation gives the same values (normalized by the signed volume).
    let mut r = m.clone();
    for t in &mut r.triangles {
        t.swap(1, 2);
    }
    let sr = PolyhedronSurface::new(&r).unwrap();
    assert!((sr.winding_number(DVec3::ZERO) - 1.0).abs() < 0.1);
    // A hole: remove two adjacent triangles. Inside/outside still right away from the hole.
    let mut h = m.clone();
    h.triangles.drain(0..4); // the 4 children of one triangle of the previous level
    let sh = PolyhedronSurface::new(&h).unwrap();
    assert_eq!(sh.stats().boundary_edges, 6);
    assert!(sh.value(DVec3::ZERO) < 0.0);
    assert!(sh.value(DVec3::new(0.3, -0.4, 0.2)) < 0.0);
    assert!(sh.value(DVec3::splat(1.5)) > 0.0);
    assert!((sh.winding_number(DVec3::ZERO) - 1.0).abs() < 0.1);
    // Hierarchical evaluation agrees with an exact O(n) sum.
    let exact = |p: DVec3| {
        m.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| m.vertices[i as usize] - p);
                let (la, lb, lc) = (a.length(), b.length(), c.length());
                2.0 * a
                    .dot(b.cross(c))
                    .atan2(la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb)
            })
            .sum::<f64>()
            / (4.0 * std::f64::consts::PI)
    };
    for p in [
        DVec3::new(0.1, 0.9, 0.1),
        DVec3::new(1.2, 0.3, 0.0),
        DVec3::splat(0.57),
    ] {
        assert!((exact(p) - s.winding_number(p)).abs() < 0.06, "{p}");
    }
}

#[test]
fn bipolar_crossing_is_on_the_surface_and_between_the_ends() {
    let s = PolyhedronSurface::new(&icosphere(3)).unwrap();
    let a = DVec3::new(0.1, 0.2, 0.0);
    let b = DVec3::new(1.7, -0.3, 0.4);
    let x = s.crossing(a, s.value(a), b, s.value(b));
    assert!((s.closest_point(x).0 - x).length() < 1e-12);
    // A segment with three crossings (out, in, out, in): the returned one changes the sign.
    let c = PolyhedronSurface::new(&cube()).unwrap();
    let mut two = cube();
    let off = DVec3::new(3.0, 0.0, 0.0);
    let n = two.vertices.len() as u32;
    two.vertices
        .extend(cube().vertices.iter().map(|v| *v + off));
    two.triangles
        .extend(cube().triangles.iter().map(|t| t.map(|i| i + n)));
    let s2 = PolyhedronSurface::new(&two).unwrap();
    assert_eq!(s2.stats().components, 2);
    let (a, b) = (DVec3::new(0.5, 0.5, 0.5), DVec3::new(3.5, 0.5, 0.5));
    assert_eq!(count(&s2, a, b), 2);
    let (a, b) = (DVec3::new(0.5, 0.5, 0.5), DVec3::new(5.0, 0.5, 0.5));
    assert_eq!(count(&s2, a, b), 3);
    let x = s2.crossing(a, s2.value(a), b, s2.value(b));
    assert!((x - DVec3::new(1.0, 0.5, 0.5)).length() < 1e-12, "{x}");
    let _ = c;
}

#[test]
fn duplicates_and_degenerate_faces_are_tolerated_and_counted() {
    let mut m = cube();
    // Split the mesh at vertex 0: faces using it now use a duplicate, as in an STL soup.
    m.vertices.push(DVec3::ZERO);
    for t in m.triangles.iter_mut().take(2) {
        for i in t.iter_mut() {
            if *i == 0 {
                *i = 8;
            }
        }
    }
    m.triangles.push([1, 1, 2]); // repeated index
    m.vertices.push(DVec3::new(0.5, 0.0, 0.0));
    m.triangles.push([0, 9, 1]); // collinear
    let s = PolyhedronSurface::new(&m).unwrap();
    let st = s.stats();
    assert_eq!(st.duplicate_vertices, 1);
    assert_eq!(st.degenerate_triangles, 2);
    assert_eq!(st.components, 1);
    assert_eq!(st.boundary_edges, 0);
    assert_eq!(count(&s, DVec3::splat(-1.0), DVec3::splat(2.0)), 2);
    assert!(s.value(DVec3::splat(0.5)) < 0.0);
}

#[test]
fn bad_input_gives_clear_errors() {
    let e = PolyhedronSurface::new(&TriMesh::default()).unwrap_err();
    assert_eq!(e, PolyhedronError::NoVertices);
    let mut m = cube();
    m.triangles.clear();
    assert!(matches!(
        PolyhedronSurface::new(&m),
        Err(PolyhedronError::NoTriangles { vertices: 8 })
    ));
    let mut m = cube();
    m.vertices[3].y = f64::NAN;
    let e = PolyhedronSurface::new(&m).unwrap_err();
    assert!(matches!(e, PolyhedronError::NonFinite { index: 3, .. }));
    assert!(e.to_string().contains("vertex 3"));
    let mut m = cube();
    m.triangles[5][1] = 42;
    let e = PolyhedronSurface::new(&m).unwrap_err();
    assert_eq!(
        e,
        PolyhedronError::BadIndex {
            face: 5,
            index: 42,
            vertices: 8
        }
    );
    assert!(e.to_string().contains("triangle 5 references vertex 42"));
    let m = TriMesh {
        vertices: vec![DVec3::ZERO, DVec3::X, DVec3::X * 2.0],
        triangles: vec![[0, 1, 2]],
    };
    assert!(matches!(
        PolyhedronSurface::new(&m),
        Err(PolyhedronError::AllDegenerate { triangles: 1 })
    ));
    let mut m = cube();
    m.vertices[0].x = 1e300;
    assert!(matches!(
        PolyhedronSurface::new(&m),
        Err(PolyhedronError::OutOfRange { index: 0, .. })
    ));
}

#[test]
fn sharp_edges_of_the_cube_and_projection() {
    let s = PolyhedronSurface::new(&cube()).unwrap();
    // 12 cube edges at 90 degrees; the 6 face diagonals are flat.
    assert_eq!(s.sharp_edges(30.0).len(), 12);
    assert_eq!(s.sharp_edges(95.0).len(), 0);
    let e = s.sharp_edges(30.0);
    let d = distance_to_sharp_edges(&e, &[DVec3::new(0.5, 0.5, 0.5), DVec3::new(0.5, 0.0, 0.0)]);
    assert!((d[0] - 0.5f64.sqrt()).abs() < 1e-12 && d[1] == 0.0);
    // The cube against itself: no deviation; against a sphere: the corners stick out.
    assert_eq!(sharp_edge_deviation(&e, &s, 0.1), 0.0);
    let (q, _) = s.closest_point(DVec3::new(0.5, 0.5, 3.0));
    assert!((q - DVec3::new(0.5, 0.5, 1.0)).length() < 1e-15);
    let (q, _) = s.closest_point(DVec3::new(2.0, 2.0, 2.0));
    assert!((q - DVec3::ONE).length() < 1e-15);
    let q = s.project(DVec3::new(0.5, 0.2, 0.3)).unwrap();
    assert!((q - DVec3::new(0.5, 0.0, 0.3)).length() < 1e-15);
    assert!(
        s.gradient(DVec3::new(0.5, 0.5, 1.2))
            .abs_diff_eq(DVec3::Z, 1e-12)
    );
    // Near a corner: the vertex pseudonormal, along the diagonal.
    let g = s.gradient(DVec3::splat(1.2));
    assert!(g.abs_diff_eq(DVec3::ONE.normalize(), 1e-12), "{g}");
    // A smooth sphere has no sharp edge at 30 degrees.
    assert!(
        PolyhedronSurface::new(&icosphere(2))
            .unwrap()
            .sharp_edges(30.0)
            .is_empty()
    );
}

#[test]
fn bunny_seeds_are_on_it_and_its_inside_is_inside() {
    let m = bunny();
    let s = PolyhedronSurface::new(&m).unwrap();
    let st = s.stats();
    assert_eq!((st.vertices, st.triangles), (3485, 6966));
    assert_eq!(
        (st.components, st.boundary_edges, st.nonmanifold_edges),
        (1, 0, 0)
    );
    let seeds = s.seed_points(7);
    assert!(seeds.len() >= 2);
    assert_eq!(seeds, s.seed_points(7), "deterministic");
    for p in &seeds {
        assert!((s.closest_point(*p).0 - *p).length() < 1e-12);
    }
    // Center of mass of the solid (signed tetrahedra).
    let (mut vol, mut c) = (0.0, DVec3::ZERO);
    for t in &m.triangles {
        let [a, b, d] = t.map(|i| m.vertices[i as usize]);
        let v = a.dot(b.cross(d)) / 6.0;
        vol += v;
        c += v * (a + b + d) / 4.0;
    }
    let c = c / vol;
    assert!((s.winding_number(c) - 1.0).abs() < 0.02);
    assert!(s.value(c) < 0.0);
    let bs = s.bounding_sphere();
    for k in 0..50 {
        let dir = DVec3::new(
            (k as f64).sin(),
            (k as f64 * 1.3).cos(),
            (k as f64 * 0.7).sin(),
        )
        .normalize();
        assert!(s.value(bs.center + dir * bs.radius) > 0.0);
        // A chord through the centroid crosses an even number >= 2 of times.
        let n = count(&s, bs.center + dir * bs.radius, c);
        assert!(n % 2 == 1, "ray {k}: {n}");
    }
    assert!(s.suggested_size() > 0.0 && s.suggested_size() < 0.01);
}

#[test]
fn bunny_as_a_soup_with_a_hole_still_classifies_inside_and_outside() {
    let m = bunny();
    // Soup: every triangle has its own three vertices.
    let mut soup = TriMesh::default();
    for t in &m.triangles {
        let n = soup.vertices.len() as u32;
        soup.vertices.extend(t.map(|i| m.vertices[i as usize]));
        soup.triangles.push([n, n + 1, n + 2]);
    }
    // A hole: drop every triangle around vertex 100 (a one-ring).
    let ring: Vec<usize> = (0..m.triangles.len())
        .filter(|&f| m.triangles[f].contains(&100))
        .collect();
    assert!(ring.len() >= 3);
    let mut holed = soup.clone();
    for &f in ring.iter().rev() {
        holed.triangles.remove(f);
    }
    let s = PolyhedronSurface::new(&soup).unwrap();
    let h = PolyhedronSurface::new(&holed).unwrap();
    let exact = PolyhedronSurface::new(&m).unwrap();
    assert_eq!(s.stats().duplicate_vertices, 3 * 6966 - 3485);
    assert_eq!(s.stats().components, 1);
    assert_eq!(h.stats().boundary_edges, ring.len());
    let (lo, hi) = exact.bbox();
    let mut rng = oracle::roots::SplitMix64(2);
    let mut agree = 0;
    for _ in 0..400 {
        let q = lo + (hi - lo) * DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
        let truth = exact.value(q) < 0.0;
        assert_eq!(s.value(q) < 0.0, truth, "soup at {q}");
        // Exact parity of crossings from outside the bounding sphere agrees with the sign.
        let far = exact.bounding_sphere().center + DVec3::X * exact.bounding_sphere().radius;
        assert_eq!(count(&s, far, q) % 2 == 1, truth, "parity at {q}");
        agree += usize::from((h.value(q) < 0.0) == truth);
    }
    // With the hole, the winding number is still right everywhere but next to the hole.
    assert!(agree >= 398, "{agree} of 400");
}

#[test]
fn watertight_meshes_give_a_signed_distance() {
    let s = PolyhedronSurface::new(&cube()).unwrap();
    assert!(s.is_watertight());
    let d = DVec3::new;
    let r3 = 3f64.sqrt();
    for (p, want) in [
        (d(0.5, 0.5, 0.5), -0.5),
        (d(1.01, 0.5, 0.5), 0.01),
        (d(2.0, 0.5, 0.5), 1.0),
        (d(0.9, 0.9, 0.9), -0.1),
        (d(1.1, 1.1, 0.5), 0.1 * 2f64.sqrt()), // edge region
        (d(1.1, 1.1, 1.1), 0.1 * r3),          // vertex region
        (d(-0.1, -0.1, -0.1), 0.1 * r3),
        (d(0.5, 0.5, 0.0), 0.0),
    ] {
        let sd = s.signed_distance(p).unwrap();
        assert!((sd - want).abs() < 1e-12, "{p}: {sd} vs {want}");
        // value: the same near the surface, the sign (and a constant) farther.
        let v = s.value(p);
        assert!(
            v == sd || (sd.abs() > s.suggested_size() && v * sd > 0.0),
            "{p}: {v}"
        );
    }
    // Sign agrees with the winding number, for the bunny, its soup and an inverted copy.
    let m = bunny();
    let mut inv = m.clone();
    for t in &mut inv.triangles {
        t.swap(1, 2);
    }
    let b = PolyhedronSurface::new(&m).unwrap();
    let bi = PolyhedronSurface::new(&inv).unwrap();
    assert!(b.is_watertight() && bi.is_watertight());
    let (lo, hi) = b.bbox();
    let mut rng = oracle::roots::SplitMix64(8);
    for _ in 0..2000 {
        let q = lo + (hi - lo) * 1.2 * DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64())
            - (hi - lo) * 0.1;
        let w = b.winding_number(q);
        let v = b.value(q);
        assert_eq!(v < 0.0, w > 0.5, "{q}: value {v} w {w}");
        assert!((bi.value(q) - v).abs() < 1e-12);
        let sd = b.signed_distance(q).unwrap();
        assert_eq!(sd < 0.0, v < 0.0);
        let dist = (b.closest_point(q).0 - q).length();
        assert!((sd.abs() - dist).abs() < 1e-15);
        if dist < b.suggested_size() {
            assert_eq!(v, sd);
        }
    }
    // A mesh with a hole is not watertight: the winding number decides.
    let mut h = icosphere(2);
    h.triangles.pop();
    let sh = PolyhedronSurface::new(&h).unwrap();
    assert!(!sh.is_watertight() && sh.signed_distance(DVec3::ZERO).is_none());
    assert!((sh.value(DVec3::ZERO) - (0.5 - sh.winding_number(DVec3::ZERO))).abs() < 1e-15);
}
