//! The default size of a mesh input, checked against the data (`pipeline::auto_size`): a
//! ball with a thin leg (radius 0.04, 1.5 long; the two closed pieces overlap, meshed as the
//! solid of their winding number) at its suggested size (bbox diagonal / 50 = 0.088) loses
//! most of the leg and `data-support` FAILs; without `--size` the size is halved once and the
//! output is one closed piece with the leg, every `verify` check PASS.

use glam::DVec3;
use meshio::TriMesh;
use rdt_mesher::pipeline::{Input, Request, SizeRequest, plan};
use std::f64::consts::{PI, TAU};
use verify::Status;

fn ball_with_leg() -> TriMesh {
    let mut m = TriMesh {
        vertices: vec![DVec3::Z, -DVec3::Z],
        triangles: Vec::new(),
    };
    let (rings, sectors) = (24, 48);
    for i in 1..rings {
        let ph = PI * i as f64 / rings as f64;
        for j in 0..sectors {
            let th = TAU * j as f64 / sectors as f64;
            m.vertices.push(DVec3::new(
                ph.sin() * th.cos(),
                ph.sin() * th.sin(),
                ph.cos(),
            ));
        }
    }
    let at = |i: usize, j: usize| (2 + (i - 1) * sectors + j % sectors) as u32;
    for j in 0..sectors {
        m.triangles.push([0, at(1, j), at(1, j + 1)]);
        m.triangles
            .push([1, at(rings - 1, j + 1), at(rings - 1, j)]);
        for i in 1..rings - 1 {
            m.triangles.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
            m.triangles.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
    // The leg: a capped cylinder along +x.
    let (x0, x1, r, n, k) = (0.9, 2.4, 0.04, 12, 30);
    let b = m.vertices.len();
    for i in 0..=k {
        let x = x0 + (x1 - x0) * i as f64 / k as f64;
        for j in 0..n {
            let a = TAU * j as f64 / n as f64;
            m.vertices.push(DVec3::new(x, r * a.cos(), r * a.sin()));
        }
    }
    let (c0, c1) = (m.vertices.len() as u32, m.vertices.len() as u32 + 1);
    m.vertices.push(DVec3::new(x0, 0.0, 0.0));
    m.vertices.push(DVec3::new(x1, 0.0, 0.0));
    let at = |i: usize, j: usize| (b + i * n + j % n) as u32;
    for j in 0..n {
        for i in 0..k {
            m.triangles.push([at(i, j), at(i, j + 1), at(i + 1, j + 1)]);
            m.triangles.push([at(i, j), at(i + 1, j + 1), at(i + 1, j)]);
        }
        m.triangles.push([c0, at(0, j + 1), at(0, j)]);
        m.triangles.push([c1, at(k, j), at(k, j + 1)]);
    }
    m
}

fn run(size: SizeRequest) -> rdt_mesher::pipeline::Outcome {
    let m = ball_with_leg();
    let input = Input::mesh(&m, "ball-with-leg", "ball-with-leg".into(), false).unwrap();
    let req = Request {
        size,
        ..Default::default()
    };
    plan(&input, &req).unwrap().execute(&mut |_| {}).unwrap()
}

#[test]
fn a_lost_leg_halves_the_default_size_and_a_requested_size_fails() {
    let m = ball_with_leg();
    let suggested = Input::mesh(&m, "b", "b".into(), false)
        .unwrap()
        .default_size
        .unwrap();
    // As asked: the leg is lost, and the check says so.
    let asked = run(SizeRequest::Size(suggested));
    let r = asked.report.as_ref().unwrap();
    let c = r.check("data-support").unwrap();
    assert_eq!(c.status, Status::Fail, "{}", c.detail);
    assert!(c.detail.contains("data regions lost"), "{}", c.detail);
    assert!(asked.size_halvings.is_empty());
    // Without a size: halved until nothing is lost.
    let auto = run(SizeRequest::Auto);
    assert_eq!(auto.size_halvings.len(), 1, "{:?}", auto.size_halvings);
    assert!(
        auto.size_halvings[0].contains("lost a part of the data"),
        "{:?}",
        auto.size_halvings
    );
    assert_eq!(auto.sigma, Some(0.5 * suggested));
    let r = auto.report.as_ref().unwrap();
    // Every check (the size criterion can be left unmet where the repair closes the
    // junction of the leg, a concave edge: measured r/sigma 1.35 on this in-memory mesh, 1.0
    // from its OFF file).
    assert!(r.passed(), "{:?}", r.failures());
    assert_eq!(r.status("data-support"), Some(Status::Pass));
    assert_eq!(r.topology.as_ref().unwrap().genera(), vec![Some(0)]);
    // The leg's tip is meshed.
    let tip = auto
        .mesh
        .vertices
        .iter()
        .map(|v| v.x)
        .fold(f64::MIN, f64::max);
    assert!(tip > 2.3, "{tip}");
}
