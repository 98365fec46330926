use glam::DVec3;
use oracle::{BoundingSphere, Surface};
use rdt_mesher::{Criteria, MeshOptions, mesh};
struct Sphere;
impl Surface for Sphere {
    fn bounding_sphere(&self) -> BoundingSphere {
        BoundingSphere {
            center: DVec3::ZERO,
            radius: 2.0,
        }
    }
    fn value(&self, p: DVec3) -> f64 {
        p.length_squared() - 1.0
    }
}
fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .map(|s| s.parse().unwrap())
        .unwrap_or(2000);
    let s: f64 = std::env::args()
        .nth(2)
        .map(|s| s.parse().unwrap())
        .unwrap_or(0.1);
    let opts = MeshOptions {
        criteria: Criteria::uniform(s),
        max_vertices: Some(n),
        ..Default::default()
    };
    let mut o2 = opts.clone();
    o2.manifold = false;
    println!(
        "audit: {}",
        rdt_mesher::refine::audit(&Sphere, &o2).unwrap()
    );
    let out = mesh(&Sphere, &opts).unwrap();
    println!("{:#?}", out.stats);
}
