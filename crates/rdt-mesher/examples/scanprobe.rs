//! Diagnostics of a simulated scan (issue 16): `cargo run -p rdt-mesher --release --example
//! scanprobe -- MODEL NOISE DENSITY NRM(0/1) SEED [mesh]`.
//!
//! Prints, per half (sparse: x below the split), the spacing, kernel radius and neighbour
//! counts at the data, the kernel weight and the IMLS distance estimate `f/|∇f|` at samples of
//! the source surface; with `mesh`, meshes the scan as `cargo xtask scans` does and prints
//! the mesh-to-source distances per half and the worst places, writing `/tmp/scan/NAME.ply`.
//! `SCANPROBE_DUMP=FILE` (estimated normals): writes each point, its estimated normal and its
//! exact normal, nine numbers a line.
use glam::DVec3;
use oracle::Surface;
use oracle::pointset::{PointSetParams, PointSetSurface};
use rdt_mesher::pipeline::{Input, Request, SizeRequest, plan};
use verify::scan_sim::{ScanSpec, diagonal, simulate};

fn pct(v: &mut [f64], q: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * q) as usize]
}

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let model = a.get(1).map(String::as_str).unwrap_or("bunny");
    let noise: f64 = a.get(2).map_or(0.001, |s| s.parse().unwrap());
    let dens: f64 = a.get(3).map_or(10.0, |s| s.parse().unwrap());
    let nrm = a.get(4).is_none_or(|s| s == "1");
    let seed: u64 = a.get(5).map_or(0, |s| s.parse().unwrap());
    let do_mesh = a.get(6).is_some_and(|s| s == "mesh");
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");
    let source = meshio::read(format!("{root}/fixtures/models/{model}.ply")).unwrap();
    let diag = diagonal(&source);
    let spec = ScanSpec {
        // `SCANPROBE_POINTS=N`: the scan's size (default 40,000, the table's).
        points: std::env::var("SCANPROBE_POINTS")
            .ok()
            .and_then(|h| h.parse().ok())
            .unwrap_or(40_000),
        noise,
        density_ratio: dens,
        normals: nrm,
        // `SCANPROBE_HOLE=0.05`: a missing patch of that radius (fraction of the diagonal).
        hole: std::env::var("SCANPROBE_HOLE")
            .ok()
            .and_then(|h| h.parse().ok())
            .unwrap_or(0.0),
        seed,
    };
    let scan = simulate(&source, &spec);
    if let Some((c, r)) = scan.hole {
        println!("hole at {c:?}, radius {r}");
    }
    let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for &v in &source.vertices {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    let cx = 0.5 * (lo.x + hi.x);
    let params = PointSetParams::scan();
    let t = std::time::Instant::now();
    let s = PointSetSurface::new(&scan.points, scan.normals.as_deref(), &params).unwrap();
    println!(
        "{model} n{noise} d{dens} nrm{nrm} s{seed}: diag {diag:.4e}, build {:.2} s, {:?}",
        t.elapsed().as_secs_f64(),
        s.stats()
    );
    // Estimated normals against the exact ones (the same points with `normals: true`).
    if !nrm {
        let exact = simulate(
            &source,
            &ScanSpec {
                normals: true,
                ..spec.clone()
            },
        );
        if exact.points == scan.points {
            let en = exact.normals.as_ref().unwrap();
            if let Ok(path) = std::env::var("SCANPROBE_DUMP") {
                use std::fmt::Write as _;
                let mut out = String::new();
                for (i, p) in scan.points.iter().enumerate() {
                    let (a, b) = (s.normals()[i], en[i]);
                    let _ = writeln!(
                        out,
                        "{} {} {} {} {} {} {} {} {}",
                        p.x, p.y, p.z, a.x, a.y, a.z, b.x, b.y, b.z
                    );
                }
                std::fs::write(path, out).unwrap();
            }
            for half in [true, false] {
                let (mut flipped, mut total, mut badly) = (0, 0, 0);
                let mut at = Vec::new();
                for (i, p) in scan.points.iter().enumerate() {
                    if (p.x < cx) == half {
                        total += 1;
                        if s.normals()[i].dot(en[i]) < -0.5 {
                            badly += 1;
                        }
                        if s.normals()[i].dot(en[i]) < 0.0 {
                            flipped += 1;
                            at.push(*p);
                        }
                    }
                }
                println!(
                    "{} half: {flipped} of {total} estimated normals point inward ({badly} by more \
                     than 120 degrees from the source's); e.g. {:?}",
                    if half { "sparse" } else { "dense" },
                    at.iter()
                        .step_by((at.len() / 4).max(1))
                        .take(4)
                        .collect::<Vec<_>>()
                );
            }
        }
    }
    // Source samples: IMLS distance estimate and kernel weight per half.
    let samples = verify::data_support::mesh_samples(&source, 40_000);
    for half in [true, false] {
        let (mut d, mut den, mut cnt) = (Vec::new(), Vec::new(), Vec::new());
        let mut worst = (0.0, DVec3::ZERO);
        for &y in samples.iter().filter(|y| (y.x < cx) == half) {
            let f = s.value(y);
            let g = s.gradient(y);
            let e = (f / g.length()).abs() / diag;
            if e > worst.0 {
                worst = (e, y);
            }
            d.push(e);
            let (w, _, c) = s.kernel_weight(y);
            den.push(w);
            cnt.push(c as f64);
        }
        let lowden = den.iter().filter(|&&w| w < 1.0).count();
        println!(
            "{} half: {} samples; |f/grad| %diag p50 {:.3} p99 {:.3} p99.9 {:.3} max {:.3} at {:?}; weight p1 {:.2} p50 {:.2}, <1: {}; support count p1 {} p50 {}",
            if half { "sparse" } else { "dense" },
            d.len(),
            100.0 * pct(&mut d, 0.5),
            100.0 * pct(&mut d, 0.99),
            100.0 * pct(&mut d, 0.999),
            100.0 * pct(&mut d, 1.0),
            worst.1,
            pct(&mut den, 0.01),
            pct(&mut den, 0.5),
            lowden,
            pct(&mut cnt, 0.01),
            pct(&mut cnt, 0.5),
        );
    }
    if a.get(6).is_some_and(|s| s == "near") {
        let q = DVec3::new(
            a[7].parse().unwrap(),
            a[8].parse().unwrap(),
            a[9].parse().unwrap(),
        );
        let dir = a.get(10).map(|_| {
            DVec3::new(
                a[10].parse().unwrap(),
                a[11].parse().unwrap(),
                a[12].parse().unwrap(),
            )
            .normalize()
        });
        let mut tris: Vec<(f64, DVec3, DVec3)> = source
            .triangles
            .iter()
            .map(|t| {
                let [p, q2, r] = t.map(|i| source.vertices[i as usize]);
                let c = (p + q2 + r) / 3.0;
                ((c - q).length(), c, (q2 - p).cross(r - p).normalize())
            })
            .collect();
        tris.sort_by(|x, y| x.0.total_cmp(&y.0));
        for t in tris.iter().take(12) {
            println!("src tri {:.4} c {:.4} n {:.3}", t.0, t.1, t.2);
        }
        let mut pts: Vec<(f64, usize)> = scan
            .points
            .iter()
            .enumerate()
            .map(|(i, p)| ((*p - q).length(), i))
            .collect();
        pts.sort_by(|x, y| x.0.total_cmp(&y.0));
        for &(d, i) in pts.iter().take(12) {
            println!(
                "data {d:.4} p {:.4} n {:.3}",
                scan.points[i],
                s.normals()[i]
            );
        }
        if let Some(dir) = dir {
            let step = 0.001 * diag;
            for k in -40..=40 {
                let x = q + dir * (k as f64 * step);
                let (w, b2, c) = s.kernel_weight(x);
                let g = s.gradient(x);
                println!(
                    "t {:+.4} f {:+.4e} |g| {:.3} g.dir {:+.3} weight {w:.2} band {:.2} count {c} winding {:.3}",
                    k as f64 * step,
                    s.value(x),
                    g.length(),
                    g.normalize().dot(dir),
                    b2.sqrt(),
                    s.winding_number(x)
                );
            }
        }
        return;
    }
    if !do_mesh {
        return;
    }
    let name = format!(
        "{model}-n{noise}-d{dens}-{}-s{seed}",
        if nrm { "nrm" } else { "est" }
    );
    let cloud = oracle::pointset::PointCloud {
        points: scan.points.clone(),
        normals: scan.normals.clone(),
    };
    let input = Input::point_cloud(cloud, &name, name.clone()).unwrap();
    let req = Request {
        size: SizeRequest::Size(0.006 * diag),
        ..Default::default()
    };
    let t = std::time::Instant::now();
    let out = plan(&input, &req).unwrap().execute(&mut |_| {}).unwrap();
    let topo = out.report.as_ref().unwrap().topology.as_ref().unwrap();
    println!(
        "mesh: {} vertices in {:.1} s, genus {:?}, verify {}",
        out.mesh.vertices.len(),
        t.elapsed().as_secs_f64(),
        topo.genera(),
        out.report.as_ref().unwrap().passed()
    );
    let _ = std::fs::create_dir_all("/tmp/scan");
    meshio::write(format!("/tmp/scan/{name}.ply"), &out.mesh).unwrap();
    let bvh = verify::intersect::triangle_bvh(&source);
    let md = verify::MeshDistance::new(&source, &bvh);
    let ms = verify::data_support::mesh_samples(&out.mesh, 200_000);
    for half in [true, false] {
        let mut d: Vec<(f64, DVec3)> = ms
            .iter()
            .filter(|y| (y.x < cx) == half)
            .map(|&y| (md.nearest(y).unwrap().1 / diag, y))
            .collect();
        d.sort_by(|a, b| b.0.total_cmp(&a.0));
        let mut v: Vec<f64> = d.iter().map(|x| x.0).collect();
        println!(
            "mesh->source {}: p50 {:.3} p99 {:.3} max {:.3}; worst: {:?}",
            if half { "sparse" } else { "dense" },
            100.0 * pct(&mut v, 0.5),
            100.0 * pct(&mut v, 0.99),
            100.0 * pct(&mut v, 1.0),
            d.iter()
                .take(5)
                .map(|(e, y)| format!("{:.3}@({:.4},{:.4},{:.4})", 100.0 * e, y.x, y.y, y.z))
                .collect::<Vec<_>>()
        );
    }
    let bvh2 = verify::intersect::triangle_bvh(&out.mesh);
    let md2 = verify::MeshDistance::new(&out.mesh, &bvh2);
    let ss = verify::data_support::mesh_samples(&source, 200_000);
    let mut d: Vec<(f64, DVec3)> = ss
        .iter()
        .map(|&y| (md2.nearest(y).unwrap().1 / diag, y))
        .collect();
    d.sort_by(|a, b| b.0.total_cmp(&a.0));
    println!(
        "source->mesh worst: {:?}",
        d.iter()
            .take(5)
            .map(|(e, y)| format!("{:.3}@({:.4},{:.4},{:.4})", 100.0 * e, y.x, y.y, y.z))
            .collect::<Vec<_>>()
    );
}
