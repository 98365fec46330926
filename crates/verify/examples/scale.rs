//! Timing of `verify::check` on a large UV sphere (default ~1e6 triangles).
//! `cargo run -p verify --release --example scale -- [n_lat]`
use glam::DVec3;
use std::time::Instant;

// The test suite's mesh builders (the UV sphere).
#[path = "../tests/common.rs"]
mod common;

fn main() {
    let n_lat: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(500);
    let mesh = common::uv_sphere(DVec3::ZERO, 1.0, n_lat, 2 * n_lat);
    println!(
        "{} vertices, {} triangles, {} threads",
        mesh.vertices.len(),
        mesh.triangles.len(),
        rayon::current_num_threads()
    );
    let t0 = Instant::now();
    let topo = verify::topology::analyze(&mesh, 20);
    let t1 = Instant::now();
    let bvh = verify::intersect::triangle_bvh(&mesh);
    let t2 = Instant::now();
    let si = verify::intersect::self_intersections(&mesh, &bvh, 20);
    let t3 = Instant::now();
    let q = verify::quality::analyze(&mesh, 10.0);
    let t4 = Instant::now();
    println!(
        "topology {:.2?} (genus {:?}), bvh {:.2?}, self-intersections {:.2?} ({} pairs, {} candidates), quality {:.2?} (min angle {:.3})",
        t1 - t0,
        topo.genera(),
        t2 - t1,
        t3 - t2,
        si.pairs_total,
        si.candidate_pairs,
        t4 - t3,
        q.min_angle_deg
    );
    let t5 = Instant::now();
    let r = verify::check(&mesh, &verify::Options::default());
    println!("check total {:.2?}; passed {}", t5.elapsed(), r.passed());
    let t6 = Instant::now();
    let opts = verify::Options {
        self_intersections: false,
        samples_per_edge: 2,
        ..Default::default()
    };
    let r = verify::check_against(&mesh, &UnitSphere, &opts);
    let g = r.geometry.as_ref().unwrap();
    println!(
        "check_against (6 samples/triangle, no self-intersection pass) {:.2?}: hausdorff {:.3e}, eps {:.4}",
        t6.elapsed(),
        g.hausdorff,
        r.certificate.as_ref().map_or(f64::NAN, |c| c.eps_achieved)
    );
}

struct UnitSphere;
impl oracle::Surface for UnitSphere {
    fn bounding_sphere(&self) -> oracle::BoundingSphere {
        oracle::BoundingSphere::at_origin(2.0)
    }
    fn value(&self, p: DVec3) -> f64 {
        p.length() - 1.0
    }
    fn project(&self, p: DVec3) -> Option<DVec3> {
        Some(p.normalize_or_zero())
    }
    fn gradient(&self, p: DVec3) -> DVec3 {
        p.normalize_or_zero()
    }
    fn dm_inf_hint(&self) -> Option<f64> {
        Some(1.0)
    }
}
