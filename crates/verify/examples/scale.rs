//! Timing of `verify::check` on a large UV sphere (default ~1e6 triangles).
//! `cargo run -p verify --release --example scale -- [n_lat]`
use glam::DVec3;
use meshio::TriMesh;
use std::f64::consts::PI;
use std::time::Instant;

fn uv_sphere(n_lat: usize, n_lon: usize) -> TriMesh {
    let mut v = vec![DVec3::Z];
    for i in 1..n_lat {
        let th = PI * i as f64 / n_lat as f64;
        for j in 0..n_lon {
            let ph = 2.0 * PI * j as f64 / n_lon as f64;
            v.push(DVec3::new(
                th.sin() * ph.cos(),
                th.sin() * ph.sin(),
                th.cos(),
            ));
        }
    }
    v.push(-DVec3::Z);
    let south = (v.len() - 1) as u32;
    let ring = |i: usize, j: usize| (1 + (i - 1) * n_lon + j % n_lon) as u32;
    let mut t = Vec::new();
    for j in 0..n_lon {
        t.push([0, ring(1, j), ring(1, j + 1)]);
        t.push([south, ring(n_lat - 1, j + 1), ring(n_lat - 1, j)]);
    }
    for i in 1..n_lat - 1 {
        for j in 0..n_lon {
            let (a, b, c, d) = (
                ring(i, j),
                ring(i, j + 1),
                ring(i + 1, j),
                ring(i + 1, j + 1),
            );
            t.push([a, c, d]);
            t.push([a, d, b]);
        }
    }
    TriMesh {
        vertices: v,
        triangles: t,
    }
}

fn main() {
    let n_lat: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(500);
    let mesh = uv_sphere(n_lat, 2 * n_lat);
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
}
