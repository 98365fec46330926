use super::*;
use crate::levels::links::{Link, Links};
use proptest::prelude::*;

/// The unit sphere.
struct Sphere;

impl oracle::Surface for Sphere {
    fn bounding_sphere(&self) -> oracle::BoundingSphere {
        oracle::BoundingSphere {
            center: DVec3::ZERO,
            radius: 2.0,
        }
    }
    fn value(&self, p: DVec3) -> f64 {
        p.length() - 1.0
    }
}

/// The octahedron subdivided `levels` times, its vertices on the unit sphere (outward).
fn sphere_mesh(levels: usize) -> TriMesh {
    let mut vertices = crate::topology::OCTAHEDRON_VERTICES.to_vec();
    let mut triangles = crate::topology::OCTAHEDRON.to_vec();
    for _ in 0..levels {
        let mut mid = std::collections::HashMap::new();
        let mut split = |a: u32, b: u32, v: &mut Vec<DVec3>| {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                v.push(((v[a as usize] + v[b as usize]) * 0.5).normalize());
                v.len() as u32 - 1
            })
        };
        let mut next = Vec::new();
        for [a, b, c] in triangles {
            let (ab, bc, ca) = (
                split(a, b, &mut vertices),
                split(b, c, &mut vertices),
                split(c, a, &mut vertices),
            );
            next.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
        }
        triangles = next;
    }
    TriMesh {
        vertices,
        triangles,
    }
}

/// Split the edge of triangle `t` after its corner `k` at parameter `s` (a point of the
/// sphere close to one end for small `s`): two needles on each side.
fn split_edge(m: &mut TriMesh, t: usize, k: usize, s: f64) {
    let tr = m.triangles[t];
    let (a, b) = (tr[k], tr[(k + 1) % 3]);
    let Some(u) = m
        .triangles
        .iter()
        .position(|o| (0..3).any(|i| o[i] == b && o[(i + 1) % 3] == a))
    else {
        return;
    };
    let c = tr[(k + 2) % 3];
    let d = m.triangles[u]
        .into_iter()
        .find(|&v| v != a && v != b)
        .unwrap();
    let p = m.vertices[a as usize]
        .lerp(m.vertices[b as usize], s)
        .normalize();
    m.vertices.push(p);
    let x = m.vertices.len() as u32 - 1;
    m.triangles[t] = [a, x, c];
    m.triangles[u] = [b, x, d];
    m.triangles.push([x, b, c]);
    m.triangles.push([x, a, d]);
}

fn min_angle(m: &TriMesh) -> f64 {
    m.triangles
        .iter()
        .map(|&t| angle(&m.vertices, t))
        .fold(f64::INFINITY, f64::min)
}

fn below(m: &TriMesh, bound: f64) -> usize {
    m.triangles
        .iter()
        .filter(|&&t| angle(&m.vertices, t) < bound)
        .count()
}

/// The output invariants of the module docs: a closed oriented manifold of Euler
/// characteristic `chi`, no self-intersection, the worst angle no worse than `before`,
/// every vertex on the sphere, one ball per triangle.
fn assert_invariants(m: &TriMesh, balls: &[SurfaceBall], chi: i64, before: f64) {
    let l = Links::new(&m.triangles, m.vertices.len());
    assert!((0..m.vertices.len() as u32).all(|v| l.kind(v) == Link::Cycle));
    let (v, f) = (m.vertices.len() as i64, m.triangles.len() as i64);
    assert_eq!(v - f * 3 / 2 + f, chi);
    let bvh = verify::intersect::triangle_bvh(m);
    assert_eq!(
        verify::intersect::self_intersections(m, &bvh, 4).pairs_total,
        0
    );
    assert!(min_angle(m) >= before, "{} < {before}", min_angle(m));
    for p in &m.vertices {
        assert!((p.length() - 1.0).abs() < 1e-6, "{p} is off the sphere");
    }
    assert_eq!(balls.len(), m.triangles.len());
}

#[test]
fn needles_on_a_sphere_are_removed_and_it_stays_a_sphere() {
    let mut m = sphere_mesh(2);
    for (i, t) in [3usize, 17, 40, 71, 100, 121].into_iter().enumerate() {
        split_edge(&mut m, t, i % 3, 0.04);
    }
    let before = min_angle(&m);
    assert!(before < 5.0 && below(&m, 30.0) >= 12);
    let mut balls = vec![
        SurfaceBall {
            center: DVec3::ZERO,
            radius: 1.0
        };
        m.triangles.len()
    ];
    let e = improve(&mut m, &mut balls, &Sphere, 30.0, 0.5);
    assert!(e.made() > 0 && e.below_before >= 12);
    assert_invariants(&m, &balls, 2, before);
    assert_eq!(below(&m, 30.0), 0, "{e:?}, min {}", min_angle(&m));
    assert_eq!(e.below_after, 0);
    assert_eq!(e.below_after, 0);
}

#[test]
fn a_mesh_with_every_angle_above_the_bound_is_unchanged() {
    let m0 = sphere_mesh(2);
    assert!(min_angle(&m0) > 30.0);
    let mut m = m0.clone();
    let mut balls = vec![
        SurfaceBall {
            center: DVec3::ZERO,
            radius: 1.0
        };
        m.triangles.len()
    ];
    assert_eq!(
        improve(&mut m, &mut balls, &Sphere, 30.0, 0.5),
        Edits::default()
    );
    assert_eq!(m, m0);
}

#[test]
fn no_edit_moves_the_surface_more_than_its_bound() {
    // The needle's short edge (0.016) is longer than `max_move`, no vertex can move that far
    // and a flip there would move the surface by more: it is left as it is.
    let mut m = sphere_mesh(2);
    split_edge(&mut m, 40, 0, 0.04);
    let m0 = m.clone();
    let mut balls = vec![
        SurfaceBall {
            center: DVec3::ZERO,
            radius: 1.0
        };
        m.triangles.len()
    ];
    let e = improve(&mut m, &mut balls, &Sphere, 30.0, 1e-4);
    assert_eq!((e.made(), e.below_before, e.below_after), (0, 2, 2));
    assert_eq!(m, m0);
}

/// The torus of radii 1 and `r` around the z axis.
struct Torus(f64);

impl oracle::Surface for Torus {
    fn bounding_sphere(&self) -> oracle::BoundingSphere {
        oracle::BoundingSphere {
            center: DVec3::ZERO,
            radius: 2.0,
        }
    }
    fn value(&self, p: DVec3) -> f64 {
        let q = DVec3::new(p.x, p.y, 0.0).normalize_or_zero();
        (p - q).length() - self.0
    }
}

/// A triangulated tube: `n` rings of three vertices around the circle of radius 1, each
/// ring on the torus of tube radius `r` (every pair of vertices of a ring is an edge).
fn thin_torus(n: usize, r: f64) -> TriMesh {
    let mut vertices = Vec::new();
    for i in 0..n {
        let u = std::f64::consts::TAU * i as f64 / n as f64;
        let (c, s) = (u.cos(), u.sin());
        for j in 0..3 {
            let v = std::f64::consts::TAU * (j as f64 + 0.5 * i as f64) / 3.0;
            let rad = 1.0 + r * v.cos();
            vertices.push(DVec3::new(rad * c, rad * s, r * v.sin()));
        }
    }
    let id = |i: usize, j: usize| (3 * (i % n) + j % 3) as u32;
    let mut triangles = Vec::new();
    for i in 0..n {
        for j in 0..3 {
            triangles.push([id(i, j), id(i + 1, j), id(i, j + 1)]);
            triangles.push([id(i, j + 1), id(i + 1, j), id(i + 1, j + 1)]);
        }
    }
    TriMesh {
        vertices,
        triangles,
    }
}

#[test]
fn a_collapse_that_would_pinch_a_thin_tube_is_not_made() {
    // Every triangle is a needle (ring edges 0.035, edges along the tube 0.26) and every ring
    // edge is shorter than `max_move`; collapsing one would pinch the tube to an edge (its
    // ends share the ring's third vertex): the link condition forbids it.
    let mut m = thin_torus(24, 0.02);
    let orient = m
        .triangles
        .iter()
        .map(|&t| normal(&m.vertices, t))
        .collect::<Vec<_>>();
    let mid = |t: &[u32; 3]| t.iter().map(|&v| m.vertices[v as usize]).sum::<DVec3>() / 3.0;
    let outward = m.triangles.iter().zip(&orient).all(|(t, n)| {
        let c = mid(t);
        n.dot(c - DVec3::new(c.x, c.y, 0.0).normalize()) > 0.0
    });
    assert!(outward && below(&m, 30.0) == m.triangles.len());
    let before = min_angle(&m);
    let mut balls = vec![
        SurfaceBall {
            center: DVec3::ZERO,
            radius: 1.0
        };
        m.triangles.len()
    ];
    improve(&mut m, &mut balls, &Torus(0.02), 30.0, 0.1);
    let l = Links::new(&m.triangles, m.vertices.len());
    assert!((0..m.vertices.len() as u32).all(|v| !l.used(v) || l.kind(v) == Link::Cycle));
    let (v, f) = (m.vertices.len() as i64, m.triangles.len() as i64);
    assert_eq!(v - f * 3 / 2 + f, 0, "the torus lost its handle");
    let bvh = verify::intersect::triangle_bvh(&m);
    assert_eq!(
        verify::intersect::self_intersections(&m, &bvh, 4).pairs_total,
        0
    );
    assert!(min_angle(&m) >= before);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn edits_keep_a_closed_manifold_without_intersections(
        splits in prop::collection::vec((0usize..128, 0usize..3, 0.005f64..0.3), 1..12),
    ) {
        let mut m = sphere_mesh(2);
        for (t, k, s) in splits {
            let t = t % m.triangles.len();
            split_edge(&mut m, t, k, s);
        }
        let before = min_angle(&m);
        let mut balls = vec![SurfaceBall { center: DVec3::ZERO, radius: 1.0 }; m.triangles.len()];
        improve(&mut m, &mut balls, &Sphere, 30.0, 0.5);
        assert_invariants(&m, &balls, 2, before);
    }
}
