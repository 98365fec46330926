//! Acceptance tests (issue 4): verdicts on meshes the mesher did not make.
mod common;
use common::*;
use glam::DVec3;
use meshio::TriMesh;
use verify::{Options, Status, check};

fn opts() -> Options {
    Options::default()
}

#[test]
fn closed_cube_is_a_genus_0_manifold_of_volume_1() {
    let r = check(&cube(), &opts());
    assert!(r.passed(), "{}", r.summary());
    let t = r.topology.as_ref().unwrap();
    assert!(t.is_closed_oriented_manifold());
    assert_eq!(t.components.len(), 1);
    let c = &t.components[0];
    assert_eq!((c.vertices, c.edges, c.triangles), (8, 18, 12));
    assert_eq!(c.euler_characteristic, 2);
    assert_eq!(c.genus, Some(0));
    let q = r.quality.as_ref().unwrap();
    assert_eq!(q.volume, 1.0);
    assert!((q.total_area - 6.0).abs() < 1e-12);
    assert!((q.min_angle_deg - 45.0).abs() < 1e-9 && (q.max_angle_deg - 90.0).abs() < 1e-9);
    assert_eq!(q.angle_histogram.iter().sum::<usize>(), 36);
    assert_eq!(q.angle_histogram[4], 24); // 45 degrees
    assert_eq!(q.angle_histogram[9], 12); // 90 degrees
    assert_eq!(r.self_intersections.as_ref().unwrap().pairs_total, 0);
    for name in verify::CLOSED_MANIFOLD_CHECKS {
        assert_eq!(r.status(name), Some(Status::Pass), "{name}");
    }
    // The OBJ quad cube reads to the same verdict.
    let r2 = check(&meshio::read(fixture("cube_quads.obj")).unwrap(), &opts());
    assert!(r2.passed(), "{}", r2.summary());
}

#[test]
fn cube_with_a_face_removed_has_a_boundary() {
    let mut m = cube();
    m.triangles.drain(2..4); // the top face (two triangles)
    let r = check(&m, &opts());
    assert_status(&r, "closed", Status::Fail);
    let t = r.topology.as_ref().unwrap();
    assert_eq!(t.boundary_edges_total, 4);
    let mut b = t.boundary_edges.clone();
    b.sort();
    assert_eq!(b, vec![[4, 5], [4, 7], [5, 6], [6, 7]]);
    assert_eq!(t.components[0].boundary_loops, 1);
    assert_eq!(
        t.components[0].genus,
        Some(0),
        "a disk: chi = 1, one boundary loop"
    );
    assert!(t.is_edge_manifold() && t.is_vertex_manifold() && t.is_consistently_oriented());
    assert!(!r.passed());
    assert!(r.summary().contains("FAIL closed"), "{}", r.summary());
}

#[test]
fn two_tetrahedra_sharing_a_vertex_are_not_vertex_manifold() {
    let a = tetrahedron();
    let mut b = tetrahedron();
    for v in &mut b.vertices {
        *v = -*v; // point reflection through vertex 0 (the origin)
    }
    // A point reflection reverses orientation; flip the triangles back to outward.
    for t in &mut b.triangles {
        t.swap(1, 2);
    }
    let mut m = union(&[a, b]);
    // Merge b's copy of the origin (index 4) into vertex 0.
    for t in &mut m.triangles {
        for i in t.iter_mut() {
            if *i == 4 {
                *i = 0;
            }
        }
    }
    m.vertices.remove(4);
    for t in &mut m.triangles {
        for i in t.iter_mut() {
            if *i > 4 {
                *i -= 1;
            }
        }
    }
    let r = check(&m, &opts());
    let t = r.topology.as_ref().unwrap();
    assert_status(&r, "vertex-manifold", Status::Fail);
    assert_eq!(t.non_manifold_vertices, vec![0]);
    assert!(t.is_closed() && t.is_edge_manifold() && t.is_consistently_oriented());
    assert_eq!(t.components.len(), 1, "joined at the vertex");
    assert_eq!(
        t.components[0].genus, None,
        "genus undefined at a non-manifold vertex"
    );
    assert_eq!(
        r.self_intersections.as_ref().unwrap().pairs_total,
        0,
        "{}",
        r.summary()
    );
    assert!((r.quality.as_ref().unwrap().volume - 2.0 / 6.0).abs() < 1e-15);
}

#[test]
fn flipped_facet_is_an_orientation_error() {
    let mut m = cube();
    m.triangles[5].swap(0, 1);
    let r = check(&m, &opts());
    assert_status(&r, "oriented", Status::Fail);
    let t = r.topology.as_ref().unwrap();
    assert_eq!(
        t.inconsistent_edges_total, 3,
        "the three edges of the flipped facet"
    );
    assert!(
        t.components[0].orientable,
        "the surface is orientable, only this facet is wrong"
    );
    assert!(t.is_closed() && t.is_edge_manifold() && t.is_vertex_manifold());
    assert!(r.quality.as_ref().unwrap().volume < 1.0);
}

#[test]
fn interpenetrating_spheres_self_intersect_a_single_sphere_does_not() {
    let one = uv_sphere(DVec3::ZERO, 1.0, 12, 24);
    let r = check(&one, &opts());
    assert!(r.passed(), "{}", r.summary());
    assert_eq!(r.topology.as_ref().unwrap().genera(), vec![Some(0)]);

    let two = union(&[
        one.clone(),
        uv_sphere(DVec3::new(1.0, 0.1, 0.05), 1.0, 12, 24),
    ]);
    let r = check(&two, &opts());
    assert_status(&r, "self-intersections", Status::Fail);
    let si = r.self_intersections.as_ref().unwrap();
    assert!(
        si.pairs_total >= 24,
        "the intersection curve crosses many facets: {}",
        si.pairs_total
    );
    let n = one.triangles.len();
    for [i, j] in &si.pairs {
        assert!(*i < n && *j >= n, "pairs are across the two spheres");
    }
    // Topology is still fine: two genus-0 components.
    assert_eq!(
        r.topology.as_ref().unwrap().genera(),
        vec![Some(0), Some(0)]
    );

    // Two spheres that are far apart do not intersect.
    let apart = union(&[
        one.clone(),
        uv_sphere(DVec3::new(2.5, 0.0, 0.0), 1.0, 12, 24),
    ]);
    assert_eq!(
        check(&apart, &opts()).status("self-intersections"),
        Some(Status::Pass)
    );
    // Touching at one point (a vertex of each): an intersection.
    let touch = union(&[one, uv_sphere(DVec3::new(0.0, 0.0, 2.0), 1.0, 12, 24)]);
    let r = check(&touch, &opts());
    assert_eq!(
        r.self_intersections.as_ref().unwrap().pairs_total,
        24 * 24,
        "{}",
        r.summary()
    );
}

#[test]
fn torus_has_genus_1() {
    let m = torus(2.0, 0.5, 48, 16);
    let r = check(&m, &opts());
    assert!(r.passed(), "{}", r.summary());
    let t = r.topology.as_ref().unwrap();
    assert_eq!(t.components[0].euler_characteristic, 0);
    assert_eq!(t.genera(), vec![Some(1)]);
    // Two tori and a sphere: three components.
    let mut far = torus(2.0, 0.5, 24, 12);
    for v in &mut far.vertices {
        *v += DVec3::new(10.0, 0.0, 0.0);
    }
    let s = uv_sphere(DVec3::new(0.0, 10.0, 0.0), 1.0, 6, 8);
    let r = check(&union(&[m, far, s]), &opts());
    assert_eq!(
        r.topology.as_ref().unwrap().genera(),
        vec![Some(1), Some(1), Some(0)]
    );
    assert!(r.passed(), "{}", r.summary());
}

#[test]
fn duplicate_unreferenced_degenerate_and_bad_input() {
    let mut m = cube();
    m.vertices.push(m.vertices[3]); // duplicate of 3, unreferenced
    m.vertices.push(DVec3::new(0.5, 0.5, 0.5)); // unreferenced
    m.triangles.push([0, 1, 1]); // repeated index
    let n = m.vertices.len() as u32;
    m.vertices.push(DVec3::new(2.0, 2.0, 2.0));
    m.vertices.push(DVec3::new(3.0, 3.0, 3.0));
    m.triangles.push([n - 1, n, n + 1]); // collinear (exact)
    let r = check(&m, &opts());
    let t = r.topology.as_ref().unwrap();
    assert_eq!(t.duplicate_vertices, vec![[3, 8]]);
    assert_eq!(t.unreferenced_vertices, vec![8]);
    assert_eq!(t.degenerate_triangles, vec![12, 13]);
    assert_eq!(r.status("duplicate-vertices"), Some(Status::Fail));
    assert_eq!(r.status("degenerate-triangles"), Some(Status::Fail));

    // Bad input: the `input` check FAILs with the reason, and nothing else is checked.
    let one_triangle = |vertices: Vec<DVec3>| TriMesh {
        vertices,
        triangles: vec![[0, 1, 2]],
    };
    for (bad, reason) in [
        (
            one_triangle(vec![DVec3::ZERO]),
            "face 0 uses vertex index 1",
        ),
        (
            one_triangle(vec![DVec3::ZERO, DVec3::X, DVec3::new(0.0, f64::NAN, 0.0)]),
            "vertex 2",
        ),
        (
            one_triangle(vec![DVec3::ZERO, DVec3::X * 1e300, DVec3::Y]),
            "vertex 1 has a coordinate outside the range",
        ),
    ] {
        let r = check(&bad, &opts());
        assert_eq!(r.status("input"), Some(Status::Fail));
        let why = r.input_error.as_deref().unwrap_or("");
        assert!(why.contains(reason), "{reason:?} not in {why:?}");
        assert!(r.topology.is_none());
    }
}

#[test]
fn report_is_json_and_summary_has_one_line_per_check() {
    let r = check(&cube(), &opts());
    let v: serde_json::Value = serde_json::from_str(&r.to_json()).unwrap();
    assert_eq!(v["topology"]["components"][0]["genus"], 0);
    assert_eq!(v["checks"][0]["status"], "PASS");
    let s = r.summary();
    assert_eq!(s.lines().count(), r.checks.len() + 2);
    assert!(s.ends_with("verdict: PASS\n"), "{s}");
}

/// `Options::progress` hears every stage of a check against a surface, in order (the CLI's
/// spinner names them: a large mesh against a surface takes minutes), and only those of a
/// check without one.
#[test]
fn progress_names_each_stage_in_order() {
    use std::sync::{Arc, Mutex};
    let heard = Arc::new(Mutex::new(Vec::<String>::new()));
    let h = heard.clone();
    let o = Options {
        progress: Some(verify::Progress(Arc::new(move |s: &str| {
            h.lock().unwrap().push(s.to_string())
        }))),
        ..opts()
    };
    let sphere = oracle::catalog::surface("sphere").expect("the catalog sphere");
    let m = uv_sphere(DVec3::ZERO, 1.0, 12, 24);
    verify::check_against(&m, &sphere, &o);
    let all = [
        "topology",
        "self-intersections",
        "quality",
        "distances",
        "certificate",
        "components",
    ];
    assert_eq!(*heard.lock().unwrap(), all);
    heard.lock().unwrap().clear();
    verify::check(&m, &o);
    assert_eq!(*heard.lock().unwrap(), all[..3]);
}

/// `solid`: an inside-out sphere and two nested spheres facing the same way fail; a hollow
/// shell (the cavity facing inward) and two disjoint spheres pass; both failures passed
/// `verify` before (issue found by a CGAL user's broken inputs, 2026-12-07).
#[test]
fn each_component_must_face_out_of_the_solid() {
    let flip = |m: &TriMesh| TriMesh {
        vertices: m.vertices.clone(),
        triangles: m.triangles.iter().map(|&[a, b, c]| [a, c, b]).collect(),
    };
    let outer = uv_sphere(DVec3::ZERO, 1.0, 16, 24);
    let inner = uv_sphere(DVec3::ZERO, 0.5, 12, 18);
    let far = uv_sphere(DVec3::new(3.0, 0.0, 0.0), 0.5, 12, 18);
    let r = check(&outer, &opts());
    assert_status(&r, "solid", Status::Pass);
    let r = check(&flip(&outer), &opts());
    assert_status(&r, "solid", Status::Fail);
    assert!(r.summary().contains("inside out"), "{}", r.summary());
    let r = check(&union(&[outer.clone(), inner.clone()]), &opts());
    assert_status(&r, "solid", Status::Fail);
    assert!(r.summary().contains("nested"), "{}", r.summary());
    let r = check(&union(&[outer.clone(), flip(&inner)]), &opts());
    assert_status(&r, "solid", Status::Pass);
    let r = check(&union(&[outer, far]), &opts());
    assert_status(&r, "solid", Status::Pass);
    // Not a closed manifold: not measured.
    let mut open = cube();
    open.triangles.pop();
    assert_status(&check(&open, &opts()), "solid", Status::Info);
}

/// `short-edges`: an edge under 1e-9 of the extent (numerically one point) fails, even where
/// every other check passes; the cube passes.
#[test]
fn numerically_coincident_vertices_fail_short_edges() {
    assert_status(&check(&cube(), &opts()), "short-edges", Status::Pass);
    // A sphere's first triangle moved to a copy of its first corner 1e-12 away, the two
    // corners joined by a sliver triangle.
    let mut m = uv_sphere(DVec3::ZERO, 1.0, 8, 12);
    let [a, b, c] = m.triangles[0];
    let p = m.vertices[a as usize] + DVec3::new(1e-12, 0.0, 0.0);
    m.vertices.push(p);
    let q = (m.vertices.len() - 1) as u32;
    m.triangles[0] = [q, b, c];
    m.triangles.push([a, q, c]);
    let r = check(&m, &opts());
    assert_status(&r, "short-edges", Status::Fail);
    assert_eq!(
        r.topology.as_ref().unwrap().short_edges_total,
        1,
        "{}",
        r.summary()
    );
}
