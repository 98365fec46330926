//! Write and read a ~1e6-triangle mesh in every format and print the timings.
//! `cargo run -p meshio --release --example io_speed`
use glam::DVec3;
use meshio::{Format, Options, TriMesh};
use std::time::Instant;

fn main() {
    let n = 708; // (n x n grid) x 2 triangles ~ 1e6
    let mut m = TriMesh::default();
    for i in 0..n {
        for j in 0..n {
            let (x, y) = (i as f64 / n as f64, j as f64 / n as f64);
            m.vertices
                .push(DVec3::new(x, y, (x * 7.0).sin() * (y * 5.0).cos() / 3.0));
        }
    }
    for i in 0..n - 1 {
        for j in 0..n - 1 {
            let a = (i * n + j) as u32;
            m.triangles.push([a, a + n as u32, a + 1]);
            m.triangles.push([a + 1, a + n as u32, a + n as u32 + 1]);
        }
    }
    println!(
        "{} vertices, {} triangles",
        m.vertices.len(),
        m.triangles.len()
    );
    let dir = std::env::temp_dir();
    for (f, ext, binary) in [
        (Format::Ply, "ply", true),
        (Format::Ply, "ply", false),
        (Format::Off, "off", false),
        (Format::Obj, "obj", false),
        (Format::Stl, "stl", true),
        (Format::Stl, "stl", false),
    ] {
        let p = dir.join(format!("meshio-speed-{}.{ext}", std::process::id()));
        let t0 = Instant::now();
        meshio::write_with(
            &p,
            &m,
            f,
            Options {
                binary,
                double: true,
            },
        )
        .unwrap();
        let t1 = Instant::now();
        let back = meshio::read(&p).unwrap();
        let t2 = Instant::now();
        let size = std::fs::metadata(&p).unwrap().len();
        std::fs::remove_file(&p).unwrap();
        println!(
            "{f} binary={binary}: write {:.2?}, read {:.2?}, {:.1} MB, {} triangles back",
            t1 - t0,
            t2 - t1,
            size as f64 / 1e6,
            back.triangles.len()
        );
    }
}
