//! Profiling probe: `cargo run -p rdt-mesher --release --example probe -- NAME SIZE [distance] [repeats]`.
//!
//! NAME is a catalog surface, or a `.nii` volume (meshed at iso 0, inside = below the iso).
use rdt_mesher::{Criteria, MeshOptions, mesh, pipeline::cgal_criteria};
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let name = args.get(1).map(String::as_str).unwrap_or("torus");
    let s: f64 = args.get(2).map(|s| s.parse().unwrap()).unwrap_or(0.0194);
    let d: Option<f64> = args.get(3).map(|s| s.parse().unwrap());
    let reps: usize = args.get(4).map(|s| s.parse().unwrap()).unwrap_or(1);
    let opts = MeshOptions {
        // CGAL's criteria with radius s; the distance bound only when given.
        criteria: Criteria {
            max_distance: d,
            ..cgal_criteria(s)
        },
        ..Default::default()
    };
    use oracle::Surface;
    let surf: Box<dyn Fn() -> Box<dyn Surface>> = if name.ends_with(".nii") {
        let vol = std::sync::Arc::new(oracle::image::read_nifti(name).unwrap());
        let iso = oracle::image::ImageOptions {
            iso: Some(0.0),
            dark_foreground: true,
            ..Default::default()
        };
        Box::new(move || {
            Box::new(oracle::image::ImageSurface::new_shared(vol.clone(), &iso).unwrap())
        })
    } else {
        let name = name.to_string();
        Box::new(move || Box::new(oracle::catalog::surface(&name).unwrap()))
    };
    for _ in 0..reps {
        let surf = surf();
        let t = std::time::Instant::now();
        let n = surf.seed_points(0).len();
        println!("seed_points: {n} in {:.3} s", t.elapsed().as_secs_f64());
        let t = std::time::Instant::now();
        let out = mesh(&*surf, &opts).unwrap();
        println!(
            "{} vertices in {:.3} s: {:?}",
            out.stats.vertices,
            t.elapsed().as_secs_f64(),
            out.stats
        );
    }
}
