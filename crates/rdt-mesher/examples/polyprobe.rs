//! Probe: remesh a mesh file with the polyhedron oracle, report stats and the update audit.
use rdt_mesher::{Criteria, MeshOptions, Sizing, mesh};
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let m = meshio::read(&args[1]).unwrap();
    let s: f64 = args[2].parse().unwrap();
    let poly = oracle::polyhedron::PolyhedronSurface::new(&m).unwrap();
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
    println!("audit {}", rdt_mesher::refine::audit(&poly, &opts).unwrap());
    let out = mesh(&poly, &opts).unwrap();
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
