//! `cargo run --release -p delaunay3 --example bench_points -- N SEED cube|sphere`: builds the
//! triangulation of the same points as `benches/cgal_baseline.cpp` and prints one JSON line.

use delaunay3::{DVec3, Triangulation};
use std::time::Instant;

struct SplitMix(u64);
impl SplitMix {
    fn unit(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 4 {
        eprintln!("usage: bench_points N SEED cube|sphere");
        std::process::exit(2);
    }
    let n: usize = args[1].parse().expect("N: a number of points");
    let mut r = SplitMix(args[2].parse().expect("SEED: an integer"));
    let sphere = args[3] == "sphere";
    let pts: Vec<DVec3> = (0..n)
        .map(|_| {
            if sphere {
                loop {
                    let p = DVec3::new(
                        r.unit() * 2.0 - 1.0,
                        r.unit() * 2.0 - 1.0,
                        r.unit() * 2.0 - 1.0,
                    );
                    let l = p.length_squared();
                    if l > 1e-6 && l <= 1.0 {
                        break p / l.sqrt();
                    }
                }
            } else {
                let (x, y, z) = (r.unit(), r.unit(), r.unit());
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
