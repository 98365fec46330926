//! Issue 3 / 4 acceptance on the catalog surfaces (`oracle::catalog`), checked with `verify`:
//! closed oriented 2-manifolds of the right genus, every facet angle >= 30 degrees, every
//! surface Delaunay ball radius <= sigma, same topology with both oracles; heart (not smooth)
//! terminates and is a manifold; two disjoint spheres give two components; the sphere's
//! Hausdorff estimate against the analytic distance and its loose-epsilon certificate;
//! determinism of the mesh and of the verify report (1 thread vs the default pool).
//!
//! The sizes give roughly 2k vertices (found with `cargo xtask mesh implicit:NAME --size S`);
//! they are the `2k` sizes of `cargo xtask regress`.

use glam::DVec3;
use meshio::TriMesh;
use oracle::{BoundingSphere, Surface, catalog, implicit::ImplicitSurface};
use rdt_mesher::{Criteria, MeshOptions, MeshResult, OracleKind, mesh};

/// (name, sigma for ~2k vertices, genus).
const SMOOTH: &[(&str, f64, i64)] = &[
    ("sphere", 0.065, 0),
    ("ellipsoid", 0.042, 0),
    ("torus", 0.063, 1),
    ("double_torus", 0.043, 2),
    ("tanglecube", 0.18, 5),
    ("chair", 0.29, 3),
    ("blobs", 0.039, 0),
];

fn run(s: &dyn Surface, sigma: f64, oracle: OracleKind) -> MeshResult {
    let opts = MeshOptions {
        criteria: Criteria::uniform(sigma),
        oracle,
        // A safety budget far above the expected counts: hitting it fails the test below.
        max_vertices: Some(200_000),
        ..Default::default()
    };
    mesh(s, &opts).expect("meshing succeeds")
}

/// Smallest angle of a triangle, degrees (independent of the mesher's and verify's code).
fn min_angle_deg(m: &TriMesh) -> f64 {
    let mut worst = 180.0f64;
    for t in &m.triangles {
        let p = t.map(|i| m.vertices[i as usize]);
        for k in 0..3 {
            let (a, b, c) = (p[k], p[(k + 1) % 3], p[(k + 2) % 3]);
            let ang = (b - a).angle_between(c - a).to_degrees();
            worst = worst.min(ang);
        }
    }
    worst
}

/// Genera of the components (sorted), asserting a closed oriented 2-manifold.
fn manifold_genera(name: &str, r: &MeshResult) -> Vec<i64> {
    let rep = verify::check(&r.mesh, &verify::Options::default());
    let t = rep.topology.as_ref().expect("topology report");
    assert!(
        t.is_closed_oriented_manifold(),
        "{name}: not a closed oriented 2-manifold:\n{}",
        rep.summary()
    );
    assert_eq!(rep.status("self-intersections"), Some(verify::Status::Pass));
    let mut g: Vec<i64> = t
        .genera()
        .into_iter()
        .map(|g| g.expect("genus of a closed orientable component"))
        .collect();
    g.sort_unstable();
    g
}

fn assert_criteria(name: &str, r: &MeshResult, sigma: f64) {
    assert!(
        r.stats.stopped_by.is_none(),
        "{name}: stopped by {:?}",
        r.stats.stopped_by
    );
    assert!(r.stats.criteria_met, "{name}: unmet {:?}", r.stats.unmet);
    assert_eq!(r.balls.len(), r.mesh.triangles.len());
    let a = min_angle_deg(&r.mesh);
    assert!(a >= 30.0, "{name}: min angle {a} < 30");
    let rmax = r.balls.iter().map(|b| b.radius).fold(0.0, f64::max);
    assert!(rmax <= sigma, "{name}: ball radius {rmax} > sigma {sigma}");
}

#[test]
fn smooth_catalog_surfaces_both_oracles() {
    for &(name, sigma, genus) in SMOOTH {
        let s = catalog::surface(name).unwrap();
        let mut topo = Vec::new();
        for oracle in [OracleKind::Bipolar, OracleKind::Intersection] {
            let tag = format!("{name} ({oracle:?})");
            let r = run(&s, sigma, oracle);
            let n = r.mesh.vertices.len();
            assert!(
                (1000..4000).contains(&n),
                "{tag}: {n} vertices, expected ~2k"
            );
            assert_criteria(&tag, &r, sigma);
            let g = manifold_genera(&tag, &r);
            assert_eq!(g, vec![genus], "{tag}: genera");
            // Every vertex lies on S (within the oracle's precision, relative to |grad f|).
            for &p in r.mesh.vertices.iter().step_by(17) {
                let d = s.value(p).abs() / s.gradient(p).length();
                assert!(d < 1e-5, "{tag}: vertex {p} at distance ~{d} from S");
            }
            topo.push(g);
        }
        assert_eq!(topo[0], topo[1], "{name}: oracles disagree on the topology");
    }
}

#[test]
fn heart_terminates_and_is_a_manifold() {
    let s = catalog::surface("heart").unwrap();
    for oracle in [OracleKind::Bipolar, OracleKind::Intersection] {
        let r = run(&s, 0.062, oracle);
        assert_criteria("heart", &r, 0.062);
        assert_eq!(manifold_genera("heart", &r), vec![0]);
    }
}

fn two_spheres() -> ImplicitSurface {
    let (c1, c2) = (DVec3::new(-1.5, 0.0, 0.0), DVec3::new(1.5, 0.0, 0.0));
    let bs = BoundingSphere::at_origin(3.0);
    ImplicitSurface::from_fn(move |p| (p - c1).length().min((p - c2).length()) - 1.0, bs).unwrap()
}

#[test]
fn two_disjoint_spheres_yield_both_components() {
    let s = two_spheres();
    for oracle in [OracleKind::Bipolar, OracleKind::Intersection] {
        let r = run(&s, 0.092, oracle);
        assert_criteria("two spheres", &r, 0.092);
        assert_eq!(manifold_genera("two spheres", &r), vec![0, 0]);
        let left = r.mesh.vertices.iter().filter(|p| p.x < 0.0).count();
        let right = r.mesh.vertices.len() - left;
        assert!(left > 500 && right > 500, "{left} left, {right} right");
        for p in &r.mesh.vertices {
            let d = (p.x.abs() - 1.5).hypot(p.y.hypot(p.z)) - 1.0;
            assert!(d.abs() < 1e-6, "vertex {p} off both spheres");
        }
    }
}

fn balls_for_verify(r: &MeshResult) -> Vec<verify::SurfaceBall> {
    verify::SurfaceBall::per_facet(r.balls.iter().map(|b| (b.center, b.radius)))
}

/// max over the vertices and a dense barycentric grid (n subdivisions per edge, plus each
/// triangle's centroid) of | |p| - 1 |: the exact mesh -> sphere distance. For a mesh that is
/// star-shaped around the origin (checked by the orientation of every facet), it is also the
/// two-sided Hausdorff distance: every point s of S is within | |p| - 1 | of the mesh point p on
/// its ray.
fn analytic_sphere_hausdorff(m: &TriMesh, n: usize) -> f64 {
    let mut h = m
        .vertices
        .iter()
        .map(|p| (p.length() - 1.0).abs())
        .fold(0.0, f64::max);
    for t in &m.triangles {
        let [a, b, c] = t.map(|i| m.vertices[i as usize]);
        assert!(
            (b - a).cross(c - a).dot(a + b + c) > 0.0,
            "facet not seen from the origin"
        );
        let mut pts = vec![(a + b + c) / 3.0];
        for i in 0..=n {
            for j in 0..=n - i {
                let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                pts.push(a + (b - a) * u + (c - a) * v);
            }
        }
        for p in pts {
            h = h.max((p.length() - 1.0).abs());
        }
    }
    h
}

#[test]
fn sphere_hausdorff_estimate_matches_the_analytic_distance() {
    let s = catalog::surface("sphere").unwrap();
    let r = run(&s, 0.065, OracleKind::Bipolar);
    let opts = verify::Options {
        surface_balls: Some(balls_for_verify(&r)),
        ..Default::default()
    };
    let rep = verify::check_against(&r.mesh, &s, &opts);
    assert!(rep.passed(), "{}", rep.summary());
    let est = rep.geometry.as_ref().unwrap().hausdorff;
    let exact = analytic_sphere_hausdorff(&r.mesh, 16);
    assert!(exact > 1e-4, "analytic distance {exact} suspiciously small");
    let rel = (est - exact).abs() / exact;
    eprintln!("sphere Hausdorff: estimate {est:.6e}, analytic {exact:.6e}");
    assert!(
        rel <= 0.05,
        "Hausdorff estimate {est} vs analytic {exact}: {:.1}% apart",
        100.0 * rel
    );
}

#[test]
fn sphere_certificate_at_sigma_0_09() {
    let s = catalog::surface("sphere").unwrap();
    assert_eq!(s.dm_inf_hint(), Some(1.0));
    let r = run(&s, 0.09, OracleKind::Bipolar);
    let opts = verify::Options {
        surface_balls: Some(balls_for_verify(&r)),
        epsilon: Some(0.09),
        dm: verify::DmSource::Constant(1.0),
        ..Default::default()
    };
    let rep = verify::check_against(&r.mesh, &s, &opts);
    let cert = rep.certificate.as_ref().expect("certificate");
    assert_eq!(cert.balls, r.mesh.triangles.len());
    assert_eq!(cert.facets_without_ball, 0);
    eprintln!(
        "sphere certificate at sigma 0.09: eps {}",
        cert.eps_achieved
    );
    assert!(
        cert.eps_achieved <= 0.09,
        "achieved eps {}",
        cert.eps_achieved
    );
    assert!(
        cert.eps_achieved > 0.08,
        "achieved eps {}",
        cert.eps_achieved
    );
    assert_eq!(rep.status("loose-epsilon"), Some(verify::Status::Pass));
    // Theorem 4.7 applies (eps < 0.096) and holds.
    assert_eq!(rep.status("theorem-4.7"), Some(verify::Status::Pass));
    // Lemma 3.1 applies (rho < 1/7): facet normals within its bound of the sphere's normals.
    let bound = verify::certificate::normal_bound_deg(cert.eps_achieved).unwrap();
    let nd = &rep.geometry.as_ref().unwrap().normals;
    eprintln!(
        "sphere normals: max {} deg (bound {bound} deg)",
        nd.max_line_deg
    );
    assert!(nd.max_line_deg <= bound && nd.max_line_deg > 0.0);
    assert_eq!(rep.status("normals"), Some(verify::Status::Pass));
    // A stricter request fails: the certificate can fail.
    let strict = verify::Options {
        epsilon: Some(0.05),
        ..opts
    };
    let rep = verify::check_against(&r.mesh, &s, &strict);
    assert_eq!(rep.status("loose-epsilon"), Some(verify::Status::Fail));
}

#[test]
fn same_seed_same_mesh() {
    let s = catalog::surface("torus").unwrap();
    for oracle in [OracleKind::Bipolar, OracleKind::Intersection] {
        let a = run(&s, 0.063, oracle);
        let b = run(&s, 0.063, oracle);
        assert_eq!(a.mesh.triangles, b.mesh.triangles);
        let bits = |m: &TriMesh| -> Vec<[u64; 3]> {
            m.vertices
                .iter()
                .map(|p| p.to_array().map(f64::to_bits))
                .collect()
        };
        assert_eq!(bits(&a.mesh), bits(&b.mesh));
        assert_eq!(a.balls, b.balls);
    }
}

const REPORT_ENV: &str = "RDT_CATALOG_PRINT_REPORT";

fn torus_report() -> String {
    let s = catalog::surface("torus").unwrap();
    let r = run(&s, 0.063, OracleKind::Bipolar);
    let opts = verify::Options {
        surface_balls: Some(balls_for_verify(&r)),
        ..Default::default()
    };
    verify::check_against(&r.mesh, &s, &opts).to_json()
}

/// Helper of `verify_report_independent_of_thread_count` (run in a child process, whose
/// rayon pool size is set by RAYON_NUM_THREADS); does nothing otherwise.
#[test]
fn print_torus_report_for_child_process() {
    if std::env::var_os(REPORT_ENV).is_some() {
        println!("<<<REPORT\n{}\nREPORT>>>", torus_report());
    }
}

#[test]
fn verify_report_independent_of_thread_count() {
    let exe = std::env::current_exe().unwrap();
    let report = |threads: Option<&str>| -> String {
        let mut cmd = std::process::Command::new(&exe);
        cmd.args([
            "--exact",
            "print_torus_report_for_child_process",
            "--nocapture",
            "--test-threads=1",
        ])
        .env(REPORT_ENV, "1");
        match threads {
            Some(t) => cmd.env("RAYON_NUM_THREADS", t),
            None => cmd.env_remove("RAYON_NUM_THREADS"),
        };
        let out = cmd.output().expect("run the test binary");
        assert!(out.status.success(), "child failed: {out:?}");
        let text = String::from_utf8(out.stdout).unwrap();
        let start = text.find("<<<REPORT\n").expect("report start") + 10;
        let end = text.find("\nREPORT>>>").expect("report end");
        text[start..end].to_string()
    };
    let one = report(Some("1"));
    let many = report(Some("3"));
    let default = report(None);
    assert!(one.contains("\"checks\""));
    assert_eq!(one, many, "verify report differs between 1 and 3 threads");
    assert_eq!(
        one, default,
        "verify report differs between 1 and default threads"
    );
    // And the same as in this process.
    assert_eq!(one, torus_report());
}
