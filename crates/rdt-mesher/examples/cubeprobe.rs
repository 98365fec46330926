//! Probe: an implicit cube (flat faces, sharp edges): stats and the update audit.
use glam::DVec3;
use oracle::{BoundingSphere, implicit::ImplicitSurface};
use rdt_mesher::{Criteria, MeshOptions, Sizing, mesh};
fn main() {
    let s: f64 = std::env::args().nth(1).unwrap().parse().unwrap();
    let cube = ImplicitSurface::from_fn(
        |p: DVec3| p.x.abs().max(p.y.abs()).max(p.z.abs()) - 0.5,
        BoundingSphere {
            center: DVec3::ZERO,
            radius: 1.5,
        },
    )
    .unwrap();
    let opts = MeshOptions {
        criteria: Criteria {
            size: Some(Sizing::Constant(s)),
            min_angle_deg: 30.0,
            max_distance: None,
        },
        manifold: false,
        max_vertices: Some(20000),
        ..Default::default()
    };
    println!("audit {}", rdt_mesher::refine::audit(&cube, &opts).unwrap());
    let out = mesh(&cube, &opts).unwrap();
    let (e, v) = rdt_mesher::topology::nonmanifold_elements(&out.mesh.triangles);
    println!(
        "{} vertices, {} facets, bad edges {}, bad vertices {}, {:?}",
        out.stats.vertices,
        out.stats.facets,
        e.len(),
        v.len(),
        out.stats.unmet
    );
}
