//! Point-set oracle: normal estimation and orientation, IMLS zero set, signs far away, seeds,
//! local feature size, `.xyz` reading and input errors.

mod common;

use glam::DVec3;
use meshio::TriMesh;
use oracle::Surface;
use oracle::pointset::{
    PointSetError, PointSetParams, PointSetSurface, XyzError, read_xyz, read_xyz_from,
};
use oracle::polyhedron::PolyhedronSurface;
use oracle::roots::SplitMix64;
use proptest::prelude::*;

fn gauss(rng: &mut SplitMix64) -> f64 {
    // Box-Muller.
    let u = rng.next_f64().max(1e-300);
    let v = rng.next_f64();
    (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
}

/// `n` uniform points on the sphere (center, radius) with isotropic Gaussian noise `sigma`.
fn noisy_sphere(n: usize, center: DVec3, radius: f64, sigma: f64, seed: u64) -> Vec<DVec3> {
    let mut rng = SplitMix64(seed);
    (0..n)
        .map(|_| {
            let u = rng.unit_vector();
            let e = DVec3::new(gauss(&mut rng), gauss(&mut rng), gauss(&mut rng)) * sigma;
            center + u * radius + e
        })
        .collect()
}

/// Construction (kNN, normals, far-field flood fill) and queries give the same bits with 1
/// and 3 threads; the far field has the inside and the outside as separate regions.
/// How many of the `estimated` normals have a cosine above `min_cos` with the `truth` ones.
fn agreeing(estimated: &[DVec3], truth: &[DVec3], min_cos: f64) -> usize {
    let agree = |(n, t): &(&DVec3, &DVec3)| n.dot(**t) > min_cos;
    estimated.iter().zip(truth).filter(agree).count()
}

#[test]
fn results_do_not_depend_on_thread_count() {
    let mut pts = noisy_sphere(6000, DVec3::ZERO, 1.0, 0.004, 9);
    pts.extend(noisy_sphere(
        1500,
        DVec3::new(2.6, 0.0, 0.0),
        0.5,
        0.004,
        10,
    ));
    let run = |threads| {
        common::with_threads(threads, || {
            let s = PointSetSurface::new(&pts, None, &PointSetParams::default()).unwrap();
            let mut rng = SplitMix64(4);
            let vals: Vec<u64> = (0..3000)
                .map(|_| {
                    let x = rng.unit_vector() * 3.5 * rng.next_f64();
                    let c = s.crossing(DVec3::ZERO, s.value(DVec3::ZERO), x * 1.5, 1.0);
                    s.value(x).to_bits() ^ c.x.to_bits().rotate_left(7)
                })
                .collect();
            (s.stats().clone(), vals, s.seed_points(2), s.dm_inf_hint())
        })
    };
    let one = run(1);
    assert!(one.0.far_components >= 3, "{:?}", one.0);
    assert_eq!(one, run(3));
}

#[test]
fn noisy_sphere_without_normals() {
    let sigma = 0.005;
    let pts = noisy_sphere(10_000, DVec3::ZERO, 1.0, sigma, 1);
    let s = PointSetSurface::new(&pts, None, &PointSetParams::default()).unwrap();
    assert!(s.stats().estimated_normals);
    assert_eq!(s.stats().components, 1);
    // Orientation: outward for > 99% of the points.
    let radial: Vec<DVec3> = pts.iter().map(|p| p.normalize()).collect();
    let good = agreeing(s.normals(), &radial, 0.0);
    assert!(good as f64 > 0.99 * pts.len() as f64, "{good} outward");
    // And accurate: within ~25 degrees of the true normal for 95% of the points.
    let close = agreeing(s.normals(), &radial, 0.9);
    assert!(close as f64 > 0.95 * pts.len() as f64, "{close} accurate");
    // Zero set within a few sigma of the unit sphere at many projected points.
    let mut rng = SplitMix64(9);
    let mut worst: f64 = 0.0;
    for _ in 0..300 {
        let q = rng.unit_vector() * (0.85 + 0.3 * rng.next_f64());
        let x = s.project(q).expect("projection converges");
        assert!(s.value(x).abs() < 1e-6);
        worst = worst.max((x.length() - 1.0).abs());
    }
    assert!(worst < 3.0 * sigma, "worst deviation {worst}");
    // Signs: inside negative (also deep inside, out of the kernel support), outside positive.
    for p in [
        DVec3::ZERO,
        DVec3::new(0.3, -0.2, 0.5),
        DVec3::new(0.0, 0.0, 0.9),
    ] {
        assert!(s.value(p) < 0.0, "{p}");
    }
    for p in [
        DVec3::splat(1.0),
        DVec3::new(0.0, 0.0, 1.1),
        DVec3::new(5.0, 0.0, 0.0),
    ] {
        assert!(s.value(p) > 0.0, "{p}");
    }
    let bs = s.bounding_sphere();
    let mut rng = SplitMix64(3);
    for _ in 0..100 {
        let u = rng.unit_vector();
        assert!(s.value(bs.center + u * bs.radius) > 0.0);
        // The value is continuous in sign along rays from inside: exactly one sign change.
        let (a, b) = (DVec3::ZERO, bs.center + u * bs.radius);
        let mut xs = Vec::new();
        s.crossings(a, b, &mut xs);
        assert_eq!(xs.len(), 1, "ray {u}");
        assert!((xs[0].length() - 1.0).abs() < 3.0 * sigma);
        assert!(s.value(xs[0]).abs() < 1e-6);
        let x = s.crossing(a, s.value(a), b, s.value(b));
        assert!(s.value(x).abs() < 1e-6 && (x - xs[0]).length() < 1e-5);
    }
    // Seeds on the surface, deterministic.
    let seeds = s.seed_points(5);
    assert!(seeds.len() >= 20);
    assert_eq!(seeds, s.seed_points(5));
    for x in &seeds {
        assert!(s.value(*x).abs() < 1e-6 && (x.length() - 1.0).abs() < 3.0 * sigma);
    }
    // P2 proxy: the unit sphere's distance to its medial axis (its center) is 1.
    let h = s.dm_inf_hint().unwrap();
    // A conservative proxy: noise shrinks the balls (the sphere is the worst case, every point
    // lies on the medial ball), so the 5th percentile is around half the true value.
    assert!(h > 0.4 && h < 1.3, "dm_inf_hint {h}");
    let l = s.estimate_local_feature_size(DVec3::new(0.0, 1.0, 0.0));
    assert!(l > 0.4 && l < 1.3, "lfs {l}");
    assert!(s.gradient(DVec3::new(0.0, 0.0, 1.0)).dot(DVec3::Z) > 0.99);
}

#[test]
fn two_spheres_with_given_and_estimated_normals() {
    let c2 = DVec3::new(3.0, 0.5, 0.2);
    let mut pts = noisy_sphere(3000, DVec3::ZERO, 1.0, 0.0, 2);
    pts.extend(noisy_sphere(1500, c2, 0.5, 0.0, 3));
    let outward: Vec<DVec3> = pts
        .iter()
        .map(|p| {
            if p.x > 1.5 {
                (*p - c2).normalize()
            } else {
                p.normalize()
            }
        })
        .collect();
    let est = PointSetSurface::new(&pts, None, &PointSetParams::default()).unwrap();
    assert_eq!(est.stats().components, 2);
    let good = agreeing(est.normals(), &outward, 0.0);
    assert!(good as f64 > 0.99 * pts.len() as f64, "{good}");
    let cloud = oracle::pointset::PointCloud {
        points: pts.clone(),
        normals: Some(outward.clone()),
    };
    let given = PointSetSurface::from_cloud(&cloud, &PointSetParams::default()).unwrap();
    assert!(!given.stats().estimated_normals);
    for s in [&est, &given] {
        assert!(s.value(c2) < 0.0 && s.value(DVec3::ZERO) < 0.0);
        assert!(s.value(DVec3::new(1.75, 0.25, 0.1)) > 0.0);
        // Seeds on both components.
        let seeds = s.seed_points(1);
        assert!(seeds.iter().any(|x| (x.length() - 1.0).abs() < 0.01));
        assert!(
            seeds
                .iter()
                .any(|x| ((*x - c2).length() - 0.5).abs() < 0.01)
        );
    }
}

/// Read a PLY triangle mesh with the project's reader.
fn read_ply(path: &str) -> TriMesh {
    meshio::read(path).expect("fixture mesh")
}

#[test]
fn noisy_bunny_samples_without_normals() {
    let m = read_ply(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../fixtures/models/bunny.ply"
    ));
    let poly = PolyhedronSurface::new(&m).unwrap();
    let (lo, hi) = poly.bbox();
    let diag = (hi - lo).length();
    // 20k area-uniform samples with noise 0.002 × diagonal, as bunny_points.ply (50k) has.
    let areas: Vec<f64> = m
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| m.vertices[i as usize]);
            0.5 * (b - a).cross(c - a).length()
        })
        .collect();
    let total: f64 = areas.iter().sum();
    let mut cdf = Vec::with_capacity(areas.len());
    let mut acc = 0.0;
    for a in &areas {
        acc += a / total;
        cdf.push(acc);
    }
    let mut rng = SplitMix64(11);
    let (mut pts, mut nrm) = (Vec::new(), Vec::new());
    for _ in 0..20_000 {
        let u = rng.next_f64();
        let f = cdf.partition_point(|&c| c < u).min(cdf.len() - 1);
        let [a, b, c] = m.triangles[f].map(|i| m.vertices[i as usize]);
        let (mut r1, mut r2) = (rng.next_f64(), rng.next_f64());
        if r1 + r2 > 1.0 {
            (r1, r2) = (1.0 - r1, 1.0 - r2);
        }
        let e = DVec3::new(gauss(&mut rng), gauss(&mut rng), gauss(&mut rng)) * 0.002 * diag;
        pts.push(a + (b - a) * r1 + (c - a) * r2 + e);
        nrm.push((b - a).cross(c - a).normalize());
    }
    let s = PointSetSurface::new(&pts, None, &PointSetParams::default()).unwrap();
    let good = agreeing(s.normals(), &nrm, 0.0);
    assert!(
        good as f64 > 0.97 * pts.len() as f64,
        "{good} of {} outward",
        pts.len()
    );
    // Projected points lie within 1% of the diagonal of the mesh.
    let mut worst: f64 = 0.0;
    for p in pts.iter().step_by(100) {
        let x = s.project(*p).expect("projection converges");
        worst = worst.max((poly.closest_point(x).0 - x).length());
    }
    assert!(worst < 0.01 * diag, "worst {} of diag", worst / diag);
    // Inside/outside agree with the mesh's winding number away from the surface.
    let mut rng = SplitMix64(4);
    let mut checked = 0;
    for _ in 0..3000 {
        let q = lo + (hi - lo) * DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
        if (poly.closest_point(q).0 - q).length() < 0.01 * diag {
            continue;
        }
        checked += 1;
        assert_eq!(s.value(q) < 0.0, poly.value(q) < 0.0, "{q}");
    }
    assert!(checked > 2000);
    let h = s.dm_inf_hint().unwrap();
    assert!(h > 0.0 && h < 0.2 * diag, "{h}");
}

#[test]
fn bad_point_sets_give_clear_errors() {
    let p = DVec3::new;
    let nine: Vec<DVec3> = (0..9)
        .map(|i| p(i as f64, (i * i) as f64, (i % 3) as f64))
        .collect();
    let e = PointSetSurface::new(&nine, None, &PointSetParams::default()).unwrap_err();
    assert_eq!(e, PointSetError::TooFewPoints(9));
    assert!(e.to_string().contains("at least 10"));
    let plane: Vec<DVec3> = (0..100)
        .map(|i| p((i % 10) as f64, (i / 10) as f64, 0.0))
        .collect();
    let e = PointSetSurface::new(&plane, None, &PointSetParams::default()).unwrap_err();
    assert!(matches!(e, PointSetError::Coplanar { .. }), "{e}");
    // Tilted plane (not axis-aligned) is coplanar too.
    let tilted: Vec<DVec3> = plane
        .iter()
        .map(|q| p(q.x, q.y, 0.3 * q.x - 0.7 * q.y))
        .collect();
    assert!(matches!(
        PointSetSurface::new(&tilted, None, &PointSetParams::default()),
        Err(PointSetError::Coplanar { .. })
    ));
    let mut pts = noisy_sphere(50, DVec3::ZERO, 1.0, 0.0, 1);
    pts[17].z = f64::NAN;
    let e = PointSetSurface::new(&pts, None, &PointSetParams::default()).unwrap_err();
    assert!(matches!(e, PointSetError::NonFinitePoint { index: 17, .. }));
    assert!(e.to_string().contains("point 17"));
    let pts = noisy_sphere(50, DVec3::ZERO, 1.0, 0.0, 1);
    let short = vec![DVec3::Z; 49];
    assert_eq!(
        PointSetSurface::new(&pts, Some(&short), &PointSetParams::default()).unwrap_err(),
        PointSetError::NormalCount {
            points: 50,
            normals: 49
        }
    );
    let mut ns = vec![DVec3::Z; 50];
    ns[3] = DVec3::ZERO;
    assert!(matches!(
        PointSetSurface::new(&pts, Some(&ns), &PointSetParams::default()),
        Err(PointSetError::BadNormal { index: 3, .. })
    ));
    let bad = PointSetParams {
        bandwidth: -1.0,
        ..Default::default()
    };
    assert!(matches!(
        PointSetSurface::new(&pts, None, &bad),
        Err(PointSetError::BadParameter {
            name: "bandwidth",
            ..
        })
    ));
    // A robust pass needs a positive finite σ_n (0 made every weight NaN); the trust weight a
    // positive number (0 would trust the IMLS value where no point reaches, a NaN nowhere).
    for v in [0.0, -0.5, f64::NAN, f64::INFINITY] {
        for (name, bad) in [
            (
                "robust_sigma_n",
                PointSetParams {
                    robust_sigma_n: v,
                    ..PointSetParams::scan()
                },
            ),
            (
                "min_weight",
                PointSetParams {
                    min_weight: v,
                    ..PointSetParams::scan()
                },
            ),
        ] {
            assert!(
                matches!(
                    PointSetSurface::new(&pts, None, &bad),
                    Err(PointSetError::BadParameter { name: n, .. }) if n == name
                ),
                "{name} = {v}"
            );
        }
    }
    // Without a robust pass σ_n is unused.
    let unused = PointSetParams {
        robust_sigma_n: 0.0,
        ..Default::default()
    };
    assert!(!matches!(
        PointSetSurface::new(&pts, None, &unused),
        Err(PointSetError::BadParameter { .. })
    ));
}

#[test]
fn xyz_reader() {
    let text = "# comment\n0 0 0\n1 2 3\n\n1.5,2.5,-3e-2\n";
    let c = read_xyz_from(text.as_bytes(), "a.xyz").unwrap();
    assert_eq!(c.points.len(), 3);
    assert_eq!(c.points[2], DVec3::new(1.5, 2.5, -0.03));
    assert!(c.normals.is_none());
    let c = read_xyz_from("0 0 0 0 0 1\n1 0 0\t1 0 0\n".as_bytes(), "b.xyz").unwrap();
    assert_eq!(c.normals.unwrap()[1], DVec3::X);
    let e = read_xyz_from("0 0 0\n1 2\n".as_bytes(), "c.xyz").unwrap_err();
    assert!(matches!(
        e,
        XyzError::Columns {
            line: 2,
            found: 2,
            ..
        }
    ));
    assert!(e.to_string().starts_with("c.xyz:2:"), "{e}");
    let e = read_xyz_from("0 0 0\n1 2 3 0 0 1\n".as_bytes(), "d.xyz").unwrap_err();
    assert!(matches!(
        e,
        XyzError::Inconsistent {
            line: 2,
            expected: 3,
            ..
        }
    ));
    let e = read_xyz_from("0 0 zero\n".as_bytes(), "e.xyz").unwrap_err();
    assert!(e.to_string().contains("e.xyz:1: column 3 is `zero`"), "{e}");
    let e = read_xyz_from("0 nan 0\n".as_bytes(), "f.xyz").unwrap_err();
    assert!(matches!(e, XyzError::NonFinite { column: 2, .. }));
    let e = read_xyz_from("# nothing\n".as_bytes(), "g.xyz").unwrap_err();
    assert!(matches!(e, XyzError::Empty { .. }));
    let e = read_xyz("/nonexistent/dir/h.xyz").unwrap_err();
    assert!(e.to_string().contains("h.xyz"));
    // Round trip through a file.
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("oracle-xyz-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("s.xyz");
    let pts = noisy_sphere(20, DVec3::ZERO, 1.0, 0.0, 3);
    let body: String = pts
        .iter()
        .map(|p| format!("{} {} {}\n", p.x, p.y, p.z))
        .collect();
    std::fs::write(&path, body).unwrap();
    assert_eq!(read_xyz(&path).unwrap().points, pts);
    std::fs::remove_dir_all(&dir).unwrap();
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    /// Any finite points (and normals) written with `{}` read back bit-exactly.
    #[test]
    fn xyz_round_trip(pts in prop::collection::vec(prop::array::uniform6(-1e300f64..1e300), 1..40), with_normals: bool) {
        let body: String = pts
            .iter()
            .map(|v| if with_normals {
                format!("{} {} {} {} {} {}\n", v[0], v[1], v[2], v[3], v[4], v[5])
            } else {
                format!("{}\t{}\t{}\n", v[0], v[1], v[2])
            })
            .collect();
        let c = read_xyz_from(body.as_bytes(), "p.xyz").unwrap();
        let want: Vec<DVec3> = pts.iter().map(|v| DVec3::new(v[0], v[1], v[2])).collect();
        prop_assert_eq!(c.points, want);
        prop_assert_eq!(c.normals.is_some(), with_normals);
    }

    /// Non-finite query points give NaN or None, never a panic.
    #[test]
    fn nan_queries_do_not_panic(i in 0usize..3) {
        let pts = noisy_sphere(200, DVec3::ZERO, 1.0, 0.0, 1);
        let s = PointSetSurface::new(&pts, None, &PointSetParams::default()).unwrap();
        let q = [DVec3::NAN, DVec3::new(f64::INFINITY, 0.0, 0.0), DVec3::new(0.0, f64::NEG_INFINITY, 1.0)][i];
        prop_assert!(s.value(q).is_nan());
        prop_assert!(s.project(q).is_none());
    }
}
