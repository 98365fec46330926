#![allow(dead_code)]
use glam::DVec3;
use meshio::TriMesh;
use std::path::PathBuf;

/// A unique temporary path for one test file.
pub fn tmp(name: &str) -> PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("meshio-tests-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

pub fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/meshes")
        .join(name)
}

/// An octahedron with irrational-looking coordinates (not exactly representable as f32).
pub fn octahedron() -> TriMesh {
    let s = 1.0 / 3.0_f64;
    // Two pyramids over the ring +x, +y, -x, -y: apex 4 (+z) then apex 5 (-z), outward.
    let ring = [0, 2, 1, 3];
    let up = (0..4).map(|i| [ring[i], ring[(i + 1) % 4], 4]);
    let down = (0..4).map(|i| [ring[(i + 1) % 4], ring[i], 5]);
    let triangles = up.chain(down).collect();
    TriMesh {
        vertices: vec![
            DVec3::new(1.0 + s, 0.1, -0.2),
            DVec3::new(-1.0, 0.0, 1e-7),
            DVec3::new(0.0, 1.0 / 7.0, 0.0),
            DVec3::new(0.0, -1.0, 0.0),
            DVec3::new(0.0, 0.0, 1.234_567_890_123),
            DVec3::new(-0.0, 0.0, -1.0),
        ],
        triangles,
    }
}

/// Coordinates of each triangle corner, in order (compares meshes up to vertex renumbering).
pub fn soup(m: &TriMesh) -> Vec<[DVec3; 3]> {
    m.triangles
        .iter()
        .map(|t| t.map(|i| m.vertices[i as usize]))
        .collect()
}

pub fn close_f32(a: DVec3, b: DVec3) -> bool {
    (0..3).all(|k| (a[k] - b[k]).abs() <= f32::EPSILON as f64 * a[k].abs().max(1e-30) * 1.0001)
}
