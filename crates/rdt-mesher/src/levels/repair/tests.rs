use super::*;

/// A closed, outward-oriented tetrahedron on vertices `o..o + 4` at `at`.
fn tet(at: DVec3, o: u32) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let v = vec![at, at + DVec3::X, at + DVec3::Y, at + DVec3::Z];
    let t = vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
    (
        v,
        t.into_iter().map(|f: [u32; 3]| f.map(|x| x + o)).collect(),
    )
}

fn closed_oriented(m: &TriMesh) -> bool {
    let l = Links::new(&m.triangles, m.vertices.len());
    (0..m.vertices.len() as u32).all(|v| l.kind(v) == Link::Cycle)
}

fn run(mut m: TriMesh, min_volume: Option<f64>) -> (TriMesh, Vec<TopologyDecision>) {
    let mut balls = unit_balls(m.triangles.len());
    let d = repair(&mut m, &mut balls, min_volume, &[], &[], None);
    assert_eq!(balls.len(), m.triangles.len());
    (m, d)
}

/// [`run`] without a volume threshold on `vertices`, `triangles`, checking that the output is
/// closed and oriented.
fn run_closed(vertices: Vec<DVec3>, triangles: Vec<[u32; 3]>) -> (TriMesh, Vec<TopologyDecision>) {
    let (out, d) = run(
        TriMesh {
            vertices,
            triangles,
        },
        None,
    );
    assert!(closed_oriented(&out), "{d:?}");
    (out, d)
}

#[test]
fn a_closed_manifold_is_left_alone() {
    let (vertices, triangles) = tet(DVec3::ZERO, 0);
    let m = TriMesh {
        vertices,
        triangles,
    };
    let (out, d) = run(m.clone(), None);
    assert!(d.is_empty());
    assert_eq!(out, m);
}

#[test]
fn a_hole_is_closed() {
    let (vertices, mut triangles) = tet(DVec3::ZERO, 0);
    triangles.remove(3);
    let (out, d) = run_closed(vertices, triangles);
    assert_eq!(out.triangles.len(), 4);
    assert_eq!(d.len(), 1);
    assert_eq!(
        (d[0].kind.clone(), d[0].facets_added),
        (DecisionKind::Close, 1)
    );
}

/// Two octahedra sharing one vertex, the upper one's -Z and the lower one's +Z, at the
/// origin (a neck pinched to a vertex): 11 vertices (index 5 shared), 16 triangles; the
/// upper one's vertices are 0..6.
fn pinched() -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let oct =
        |c: DVec3| -> Vec<DVec3> { crate::topology::OCTAHEDRON_VERTICES.map(|a| c + a).to_vec() };
    let faces = crate::topology::OCTAHEDRON;
    let mut vertices = oct(DVec3::Z);
    vertices[5] = DVec3::ZERO;
    let mut lower = oct(-DVec3::Z);
    lower[4] = DVec3::ZERO; // its +Z vertex at the origin: shared with vertex 5
    vertices.extend(lower);
    let mut triangles: Vec<[u32; 3]> = faces.to_vec();
    triangles.extend(
        faces
            .iter()
            .map(|f| f.map(|v| if v == 4 { 5 } else { v + 6 })),
    );
    (vertices, triangles)
}

/// The pinch with no scan labels (or two components): cut, two caps.
#[test]
fn a_pinch_is_cut_into_two_closed_pieces() {
    let (vertices, triangles) = pinched();
    let (out, d) = run_closed(vertices.clone(), triangles.clone());
    assert_eq!(d.len(), 1, "{d:?}");
    assert_eq!(d[0].kind, DecisionKind::Cut { loops: 2 });
    assert_eq!(d[0].facets_removed, 8);
    // Two closed pieces, each of the 4 upper (lower) faces and a 2-triangle cap.
    assert_eq!(out.triangles.len(), 12);
    assert_eq!(out.vertices.len(), 10);
    // Labelled as two scan components: cut as well.
    let labels: Vec<Option<usize>> = (0..vertices.len())
        .map(|v| Some(usize::from(v >= 6)))
        .collect();
    let (out2, d2) = run_labelled(vertices, triangles, &labels);
    assert_eq!(d2[0].kind, DecisionKind::Cut { loops: 2 });
    assert_eq!(pieces_of(&out2), 2);
}

/// The pinch on one scan component (rule 3'): the two loops left by the cut are joined by a
/// tube, one closed oriented piece without self-intersections.
#[test]
fn a_pinched_neck_of_one_component_is_joined_by_a_tube() {
    let (vertices, triangles) = pinched();
    let labels = vec![Some(0); vertices.len()];
    let (out, d) = run_labelled(vertices, triangles, &labels);
    assert_eq!(d.len(), 1, "{d:?}");
    assert_eq!(d[0].kind, DecisionKind::JoinNeck);
    assert_eq!(d[0].facets_removed, 8);
    // 8 faces kept, the tube between two 4-vertex loops: 8 triangles; one piece.
    assert_eq!(out.triangles.len(), 16);
    assert_eq!(pieces_of(&out), 1);
    assert!(intersecting_vertices(&out, 0).is_empty());
    // Genus 1 would be a handle; a tube between two pieces keeps genus 0: V - E + F = 2.
    let (v, f) = (out.vertices.len() as i64, out.triangles.len() as i64);
    assert_eq!(v - 3 * f / 2 + f, 2);
}

/// [`run_closed`] with scan labels.
fn run_labelled(
    vertices: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
    labels: &[Option<usize>],
) -> (TriMesh, Vec<TopologyDecision>) {
    let mut m = TriMesh {
        vertices,
        triangles,
    };
    let mut balls = unit_balls(m.triangles.len());
    let d = repair(&mut m, &mut balls, None, &[], labels, None);
    assert_eq!(balls.len(), m.triangles.len());
    assert!(closed_oriented(&m), "{d:?}");
    (m, d)
}

/// Pieces of a triangle mesh (by shared vertices).
fn pieces_of(m: &TriMesh) -> usize {
    let mut u = crate::topology::VertexUnion::new(m.vertices.len());
    m.triangles.iter().for_each(|t| u.join_triangle(*t));
    let mut roots: Vec<u32> = m.triangles.iter().map(|t| u.find(t[0])).collect();
    roots.sort_unstable();
    roots.dedup();
    roots.len()
}

#[test]
fn two_tetrahedra_on_an_edge_and_a_lone_triangle() {
    let (mut vertices, mut triangles) = tet(DVec3::ZERO, 0);
    // A second tetrahedron sharing the edge (0, 1), on the other side.
    vertices.extend([-DVec3::Y, -DVec3::Z]);
    triangles.extend([[0, 1, 4], [0, 5, 1], [0, 4, 5], [1, 5, 4]]);
    // A lone triangle far away: a sliver.
    vertices.extend([
        DVec3::splat(5.0),
        DVec3::new(6.0, 5.0, 5.0),
        DVec3::new(5.0, 6.0, 5.0),
    ]);
    triangles.push([6, 7, 8]);
    let (out, d) = run_closed(vertices, triangles);
    assert!(d.iter().any(|x| x.kind == DecisionKind::DropSliver));
    assert!(!out.vertices.contains(&DVec3::splat(5.0)));
}

#[test]
fn small_components_are_dropped_on_request() {
    let (mut vertices, mut triangles) = tet(DVec3::ZERO, 0);
    let (v2, t2) = tet(DVec3::splat(3.0), 4);
    vertices.extend(
        v2.iter()
            .map(|p| DVec3::splat(3.0) + (*p - DVec3::splat(3.0)) * 0.1),
    );
    triangles.extend(t2);
    let m = TriMesh {
        vertices,
        triangles,
    };
    let (out, d) = run(m.clone(), Some(0.01));
    assert_eq!(out.triangles.len(), 4);
    assert!(matches!(
        d[0].kind,
        DecisionKind::DropSmallComponent { volume, .. } if (volume - 1e-3 / 6.0).abs() < 1e-12
    ));
    let (out, d) = run(m, Some(1e-6));
    assert!(d.is_empty() && out.triangles.len() == 8);
}

#[test]
fn rule_0_cuts_the_stars_of_the_separated_vertices_and_closes_them() {
    // An octahedron, its north pole (vertex 4) to be separated (as if its triangles bridged
    // two scan components): the star of the pole goes, the equator is closed.
    let vertices = crate::topology::OCTAHEDRON_VERTICES.to_vec();
    let triangles: Vec<[u32; 3]> = crate::topology::OCTAHEDRON.to_vec();
    let mut m = TriMesh {
        vertices,
        triangles,
    };
    let mut balls = unit_balls(m.triangles.len());
    // Without rule 0 the closed octahedron is left alone.
    let d = repair(&mut m.clone(), &mut balls.clone(), None, &[], &[], None);
    assert!(d.is_empty());
    let d = repair(&mut m, &mut balls, None, &[4], &[], None);
    assert!(closed_oriented(&m), "{d:?}");
    assert_eq!(d.len(), 1, "{d:?}");
    assert_eq!(d[0].kind, DecisionKind::Separate { loops: 1 });
    assert_eq!((d[0].facets_removed, d[0].facets_added), (4, 2));
    assert_eq!(m.triangles.len(), 6);
    assert!(!m.vertices.contains(&DVec3::Z), "the pole is gone");
    assert_eq!(balls.len(), m.triangles.len());
}

/// The tube between two loops of every pair of lengths 3 to 7, at pseudo-random positions:
/// an oriented annulus (each loop edge once, in the loop's order; each diagonal twice, in
/// opposite directions), `m + n` triangles.
#[test]
fn a_tube_is_an_oriented_annulus_for_any_loop_lengths() {
    let mut seed = 7u64;
    let mut next = || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    for m in 3..8usize {
        for n in 3..8usize {
            let mut pts = Vec::new();
            for k in 0..m {
                let t = k as f64 / m as f64 * std::f64::consts::TAU;
                pts.push(DVec3::new(t.cos(), t.sin(), 0.0) + DVec3::splat(0.3 * next()));
            }
            for k in 0..n {
                let t = -(k as f64) / n as f64 * std::f64::consts::TAU + next();
                pts.push(DVec3::new(t.cos(), t.sin(), 1.0) * (0.5 + next()));
            }
            let p: Vec<u32> = (0..m as u32).collect();
            let q: Vec<u32> = (m as u32..(m + n) as u32).collect();
            let mut edges = HashSet::default();
            let t = tube(&p, &q, &pts, &mut edges);
            assert_eq!(t.len(), m + n, "{m} {n}");
            let mut directed: std::collections::HashMap<(u32, u32), usize> = Default::default();
            for f in &t {
                for k in 0..3 {
                    *directed.entry((f[k], f[(k + 1) % 3])).or_default() += 1;
                }
            }
            assert!(
                directed.values().all(|&c| c == 1),
                "{m} {n}: a directed edge twice"
            );
            for &(a, b) in directed.keys() {
                let on_p = a < m as u32 && b < m as u32;
                let on_q = a >= m as u32 && b >= m as u32;
                if on_p || on_q {
                    // A loop edge: only in the loop's order.
                    let lp = if on_p { &p } else { &q };
                    let i = lp.iter().position(|&v| v == a).unwrap();
                    assert_eq!(lp[(i + 1) % lp.len()], b, "{m} {n}: loop edge reversed");
                } else {
                    assert!(
                        directed.contains_key(&(b, a)),
                        "{m} {n}: diagonal without twin"
                    );
                }
            }
        }
    }
}

/// `n` placeholder balls (the repair carries them along with the triangles).
fn unit_balls(n: usize) -> Vec<SurfaceBall> {
    vec![
        SurfaceBall {
            center: DVec3::ZERO,
            radius: 1.0
        };
        n
    ]
}
