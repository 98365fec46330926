//! `cargo run --release -p delaunay3 --example bench_points -- N SEED cube|sphere`: builds the
//! triangulation of the same points as `benches/cgal_baseline.cpp` and prints one JSON line.

use delaunay3::{DVec3, Triangulation};
use geom::SplitMix64;
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 4 {
        eprintln!("usage: bench_points N SEED cube|sphere");
        std::process::exit(2);
    }
    let n: usize = args[1].parse().expect("N: a number of points");
    let mut r = SplitMix64(args[2].parse().expect("SEED: an integer"));
    let sphere = args[3] == "sphere";
    let pts: Vec<DVec3> = (0..n)
        .map(|_| {
            if sphere {
                // Rejection from [-1, 1)^3, 1e-6 < |p|^2 <= 1, then p / |p| (as the C++ side).
                r.unit_vector()
            } else {
                let (x, y, z) = (r.next_f64(), r.next_f64(), r.next_f64());
                DVec3::new(x, y, z)
            }
        })
        .collect();
    let t0 = Instant::now();
    let mut t = Triangulation::new();
    t.insert_bulk(&pts).expect("valid points");
    let s = t0.elapsed().as_secs_f64();
    let valid = if n <= 200_000 {
        if t.is_valid().is_ok() {
            "true"
        } else {
            "false"
        }
    } else {
        "null"
    };
    println!(
        "{{\"impl\":\"delaunay3\",\"points\":{n},\"vertices\":{},\"finite_cells\":{},\"seconds\":{s:.4},\"bytes_per_point\":{:.1},\"valid\":{valid}}}",
        t.num_vertices(),
        t.num_finite_cells(),
        t.memory_bytes() as f64 / n.max(1) as f64
    );
}
