//! Tests of the bridges between the pieces of a split component.
use super::*;
use glam::DAffine3;
use oracle::image::{ImageOptions, Volume, Voxels};

/// A cylinder of radius 3 voxels along x through (·, 12, 12), 28 x 24 x 24 voxels of 1 mm.
fn cylinder() -> ImageSurface {
    let n = [28usize, 24, 24];
    let mut d = Vec::new();
    for k in 0..n[2] {
        for j in 0..n[1] {
            for _ in 0..n[0] {
                let r = ((j as f64 - 12.0).powi(2) + (k as f64 - 12.0).powi(2)).sqrt();
                d.push((3.0 - r) as f32);
            }
        }
    }
    let vol = Volume::new(n, Voxels::F32(d), DAffine3::IDENTITY).unwrap();
    let opts = ImageOptions {
        iso: Some(0.0),
        ..Default::default()
    };
    ImageSurface::new(vol, &opts).unwrap()
}

/// Two outward octahedra of radius 2 centred at `(x, 12, 12)` for each `x`.
fn octahedra(xs: &[f64]) -> meshio::TriMesh {
    let mut m = meshio::TriMesh {
        vertices: Vec::new(),
        triangles: Vec::new(),
    };
    for &x in xs {
        let c = DVec3::new(x, 12.0, 12.0);
        let o = m.vertices.len() as u32;
        let octahedron = crate::topology::OCTAHEDRON;
        m.vertices
            .extend(crate::topology::OCTAHEDRON_VERTICES.map(|a| c + 2.0 * a));
        // Upper and lower triangle of each equator edge in turn (the order the tests ran with).
        for k in 0..4 {
            for t in [octahedron[k], octahedron[k + 4]] {
                m.triangles.push(t.map(|v| o + v));
            }
        }
    }
    m
}

/// `m` (two octahedra) with triangles `removed` replaced by `tube` (on `m`'s vertices and
/// then `pts`), checked to be one closed, oriented sphere (V - E + F = 2) without
/// self-intersection; `what` names the case in failures.
fn joined_sphere(
    m: &meshio::TriMesh,
    removed: [usize; 2],
    tube: &[[u32; 3]],
    pts: &[DVec3],
    what: &str,
) -> meshio::TriMesh {
    let mut m = m.clone();
    m.vertices.extend(pts);
    let [ta, tb] = removed;
    m.triangles.swap_remove(ta.max(tb));
    m.triangles.swap_remove(ta.min(tb));
    m.triangles.extend(tube);
    let rep = verify::check(&m, &verify::Options::default());
    for name in verify::CLOSED_MANIFOLD_CHECKS {
        assert_eq!(
            rep.status(name),
            Some(verify::Status::Pass),
            "{what}: {name}: {:?}",
            rep.check(name)
        );
    }
    let (v, f) = (m.vertices.len() as i64, m.triangles.len() as i64);
    assert_eq!(v - f / 2, 2, "{what}");
    m
}

#[test]
fn a_tube_with_rings_on_s_joins_two_closed_pieces_into_one_sphere() {
    let img = cylinder();
    let via = DVec3::new(10.0, 12.0, 12.0);
    for rings in 0..=MAX_RINGS {
        let m = octahedra(&[5.0, 15.0]);
        // The triangles facing each other: (+x, +y, +z) of the first, (-x, +y, +z) of the
        // second.
        let ta = m.triangles.iter().position(|t| *t == [0, 2, 4]).unwrap();
        let tb = m.triangles.iter().position(|t| *t == [8, 7, 10]).unwrap();
        let (fa, fb) = (m.triangles[ta], m.triangles[tb]);
        let (tube, pts) =
            tube_with_rings(&m, &img, (fa, fb), via, Rings::OnS(rings), true).unwrap();
        assert_eq!(pts.len(), 3 * rings);
        for p in &pts {
            // Each ring point is on S: the cylinder's wall.
            let r = ((p.y - 12.0).powi(2) + (p.z - 12.0).powi(2)).sqrt();
            assert!(
                (r - 3.0).abs() < 0.05,
                "rings {rings}: {p} off the wall ({r})"
            );
        }
        let m = joined_sphere(&m, [ta, tb], &tube, &pts, &format!("rings {rings}"));
        assert!(
            super::super::repair::intersecting_vertices(&m, m.triangles.len() - tube.len())
                .is_empty()
        );
        assert_eq!(tube.len(), 6 * (rings + 1));
    }
}

#[test]
fn a_split_is_bridged_within_sigma_else_oversized_up_to_the_cap_else_left() {
    let img = cylinder();
    let join = Join {
        a: DVec3::new(9.0, 12.0, 12.0),
        b: DVec3::new(10.0, 12.0, 12.0),
        via: DVec3::new(9.5, 12.0, 12.0),
        diagonal: false,
        nodes: [usize::MAX; 2],
    };
    let (mut within, mut over, mut none) = (0, 0, 0);
    for k in 0..40 {
        let sigma = 20.0 * 0.8f64.powi(k);
        let mesh = octahedra(&[5.0, 15.0]);
        let balls = mesh
            .triangles
            .iter()
            .map(|t| super::super::repair::circumball(t.map(|v| mesh.vertices[v as usize])))
            .collect();
        let mut out = MeshResult {
            mesh,
            balls,
            sample: Vec::new(),
            stats: Default::default(),
        };
        let (a, b): (Vec<u32>, Vec<u32>) = ((0..6).collect(), (6..12).collect());
        let criteria = crate::Criteria::uniform(sigma);
        let Some(d) = bridge(
            &mut out,
            &img,
            &a,
            &b,
            &join,
            &criteria,
            true,
            [join.via; 2],
        ) else {
            // Left split only when every tube is over the cap.
            none += 1;
            assert!(
                over > 0,
                "sigma {sigma}: no tube, yet none oversized before"
            );
            continue;
        };
        // Whatever the kind: one closed sphere, no self-intersection, balls per triangle.
        let m = &out.mesh;
        let rep = verify::check(m, &verify::Options::default());
        for name in verify::CLOSED_MANIFOLD_CHECKS {
            assert_eq!(
                rep.status(name),
                Some(verify::Status::Pass),
                "sigma {sigma}: {name}"
            );
        }
        assert_eq!(out.balls.len(), m.triangles.len());
        let (v, f) = (m.vertices.len() as i64, m.triangles.len() as i64);
        assert_eq!(v - f / 2, 2, "sigma {sigma}");
        // The tube's balls follow the 14 triangles kept.
        let worst = out.balls[14..]
            .iter()
            .map(|b| b.radius / sigma)
            .fold(0.0f64, f64::max);
        match d.kind {
            DecisionKind::Bridge => {
                within += 1;
                assert_eq!(
                    over + none,
                    0,
                    "sigma {sigma}: within after a smaller sigma failed"
                );
                assert!(worst <= 1.0, "sigma {sigma}: {worst}");
            }
            DecisionKind::BridgeOverSize { max_r_over_sigma } => {
                over += 1;
                assert_eq!(none, 0);
                assert!(max_r_over_sigma > 1.0 && max_r_over_sigma <= MAX_OVERSIZE);
                assert!((worst - max_r_over_sigma).abs() < 1e-9 * worst, "{worst}");
            }
            k => panic!("{k:?}"),
        }
    }
    assert!(within > 0 && over > 0 && none > 0, "{within} {over} {none}");
}

/// Across a gap with no wall of S (two octahedra 22 voxels apart in the cylinder, joined
/// through its axis), a straight tube with the rings of `straight_rings` keeps the mesh a
/// sphere and its angles three times the ringless tube's needles; at a sigma that every tube
/// on S exceeds, `bridge` takes a straight one within sigma (a `bridge`, not a
/// `bridge_over_size`).
#[test]
fn a_straight_tube_crosses_a_gap_within_sigma() {
    let img = cylinder();
    let via = DVec3::new(14.0, 12.0, 12.0);
    let m0 = octahedra(&[3.0, 25.0]);
    let ta = m0.triangles.iter().position(|t| *t == [0, 2, 4]).unwrap();
    let tb = m0.triangles.iter().position(|t| *t == [8, 7, 10]).unwrap();
    let n = straight_rings(&m0, ta, tb);
    assert!((4..=MAX_STRAIGHT).contains(&n), "{n}");
    let smallest = |rings: Rings| {
        let (tube, pts) = tube_with_rings(
            &m0,
            &img,
            (m0.triangles[ta], m0.triangles[tb]),
            via,
            rings,
            true,
        )
        .unwrap();
        let m = joined_sphere(&m0, [ta, tb], &tube, &pts, &format!("{rings:?}"));
        tube.iter()
            .map(|t| crate::criteria::min_angle_deg(t.map(|v| m.vertices[v as usize])))
            .fold(f64::INFINITY, f64::min)
    };
    let straight = smallest(Rings::Straight(n));
    let ringless = smallest(Rings::Straight(0));
    // 5.7 and 18.4 degrees: the end faces are inclined on the axis (an octahedron's), so the
    // first and last stages are sheared; other pairs of faces do better (below).
    assert!(ringless < 10.0 && straight > 15.0, "{ringless} {straight}");
    // `bridge` picks a tube meeting the bound.
    let balls = m0
        .triangles
        .iter()
        .map(|t| super::super::repair::circumball(t.map(|v| m0.vertices[v as usize])))
        .collect();
    let mut out = MeshResult {
        mesh: m0.clone(),
        balls,
        sample: Vec::new(),
        stats: Default::default(),
    };
    let join = Join {
        a: DVec3::new(13.0, 12.0, 12.0),
        b: DVec3::new(14.0, 12.0, 12.0),
        via,
        diagonal: false,
        nodes: [usize::MAX; 2],
    };
    let (a, b): (Vec<u32>, Vec<u32>) = ((0..6).collect(), (6..12).collect());
    let d = bridge(
        &mut out,
        &img,
        &a,
        &b,
        &join,
        &crate::Criteria::uniform(5.0),
        true,
        [join.via; 2],
    )
    .expect("a tube");
    assert!(matches!(d.kind, DecisionKind::Bridge), "{:?}", d.kind);
    let m = &out.mesh;
    assert!(m.vertices.len() > 12, "no ring");
    let rep = verify::check(m, &verify::Options::default());
    for name in verify::CLOSED_MANIFOLD_CHECKS {
        assert_eq!(rep.status(name), Some(verify::Status::Pass), "{name}");
    }
    // The tube's balls (after the 14 triangles kept) within sigma; its angles far from needles.
    assert!(out.balls[14..].iter().all(|b| b.radius <= 5.0));
    let worst = m
        .triangles
        .iter()
        .map(|t| crate::criteria::min_angle_deg(t.map(|v| m.vertices[v as usize])))
        .fold(f64::INFINITY, f64::min);
    assert!(worst > 15.0, "{worst}");
}

/// `fewer_skinny` never returns a tube with more triangles below the angle bound than the
/// one it is given (a ringless tube of needles between octahedra 22 voxels apart, or a
/// straight one).
#[test]
fn fewer_skinny_never_takes_more_triangles_below_the_bound() {
    let img = cylinder();
    let via = DVec3::new(14.0, 12.0, 12.0);
    let mesh = octahedra(&[3.0, 25.0]);
    let ta = mesh.triangles.iter().position(|t| *t == [0, 2, 4]).unwrap();
    let tb = mesh
        .triangles
        .iter()
        .position(|t| *t == [8, 7, 10])
        .unwrap();
    let criteria = crate::Criteria::uniform(50.0);
    let region = Region::new(&mesh, DVec3::splat(-100.0), DVec3::splat(100.0));
    let evaluate = |&(ta, tb, rings, s): &(usize, usize, Rings, bool)| {
        let (fa, fb) = (mesh.triangles[ta], mesh.triangles[tb]);
        let (tube, ring_pts) = tube_with_rings(&mesh, &img, (fa, fb), via, rings, s)?;
        let crosses = tube_crosses(&mesh, &ring_pts, [ta, tb], &tube, &region);
        let c = Candidate {
            removed: [ta, tb],
            tube,
            ring_pts,
            balls: Vec::new(),
        };
        Some((c, None, crosses))
    };
    let below = |c: &Candidate| {
        c.tube
            .iter()
            .filter(|t| {
                crate::criteria::min_angle_deg(t.map(|v| position(&mesh, &c.ring_pts, v))) < 30.0
            })
            .count()
    };
    let (first, _, crosses) = evaluate(&(ta, tb, Rings::OnS(0), true)).unwrap();
    assert!(!crosses);
    let needles = below(&first);
    assert!(needles > 0);
    let c = fewer_skinny(first, &[], &evaluate, &mesh, &criteria);
    // Here the straight tubes' sheared end stages hold more triangles below the bound than
    // the six needles: the ringless tube stays.
    assert!(below(&c) <= needles, "{} > {needles}", below(&c));
    // A tube already meeting the bound is kept as it is.
    let (good, _, _) =
        evaluate(&(ta, tb, Rings::Straight(straight_rings(&mesh, ta, tb)), true)).unwrap();
    let kept = below(&good);
    let again = fewer_skinny(good, &[], &evaluate, &mesh, &criteria);
    assert!(below(&again) <= kept);
}
