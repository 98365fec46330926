//! Profiling probe: `cargo run -p rdt-mesher --release --example probe -- NAME SIZE [distance]`.
use rdt_mesher::{Criteria, MeshOptions, Sizing, mesh};
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let name = args.get(1).map(String::as_str).unwrap_or("torus");
    let s: f64 = args.get(2).map(|s| s.parse().unwrap()).unwrap_or(0.0194);
    let d: Option<f64> = args.get(3).map(|s| s.parse().unwrap());
    let surf = oracle::catalog::surface(name).unwrap();
    let opts = MeshOptions {
        criteria: Criteria {
            size: Some(Sizing::Constant(s)),
            min_angle_deg: 30.0,
            max_distance: d,
        },
        ..Default::default()
    };
    let t = std::time::Instant::now();
    use oracle::Surface;
    let n = surf.seed_points(0).len();
    println!("seed_points: {n} in {:.3} s", t.elapsed().as_secs_f64());
    let t = std::time::Instant::now();
    let out = mesh(&surf, &opts).unwrap();
    println!(
        "{} vertices in {:.3} s: {:?}",
        out.stats.vertices,
        t.elapsed().as_secs_f64(),
        out.stats
    );
}
#[allow(dead_code)]
fn seeds_time() {}
