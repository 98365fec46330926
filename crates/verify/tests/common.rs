#![allow(dead_code)]
//! Meshes and surfaces built independently of the mesher.

use glam::DVec3;
use meshio::TriMesh;
use oracle::{BoundingSphere, Surface};
use std::f64::consts::PI;
use std::path::PathBuf;

/// Asserts that check `name` of `r` has status `want` (the summary in the message).
pub fn assert_status(r: &verify::Report, name: &str, want: verify::Status) {
    assert_eq!(r.status(name), Some(want), "{name}: {}", r.summary());
}

/// The corners of each triangle of `m`, in order.
pub fn corners(m: &TriMesh) -> impl Iterator<Item = [DVec3; 3]> + '_ {
    m.triangles
        .iter()
        .map(|t| t.map(|i| m.vertices[i as usize]))
}

pub fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/meshes")
        .join(name)
}

pub fn cube() -> TriMesh {
    meshio::read(fixture("cube.off")).unwrap()
}

pub fn tetrahedron() -> TriMesh {
    meshio::read(fixture("tetrahedron.ply")).unwrap()
}

/// UV sphere: `n_lat` bands (>= 2), `n_lon` sectors, outward oriented, poles as fans.
pub fn uv_sphere(center: DVec3, radius: f64, n_lat: usize, n_lon: usize) -> TriMesh {
    let mut v = vec![center + DVec3::Z * radius];
    for i in 1..n_lat {
        let th = PI * i as f64 / n_lat as f64;
        for j in 0..n_lon {
            let ph = 2.0 * PI * j as f64 / n_lon as f64;
            v.push(
                center + radius * DVec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos()),
            );
        }
    }
    v.push(center - DVec3::Z * radius);
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

/// Parametric torus (major radius `big`, minor `small`), outward oriented.
pub fn torus(big: f64, small: f64, nu: usize, nv: usize) -> TriMesh {
    let mut v = Vec::new();
    for i in 0..nu {
        let u = 2.0 * PI * i as f64 / nu as f64;
        for j in 0..nv {
            let w = 2.0 * PI * j as f64 / nv as f64;
            let r = big + small * w.cos();
            v.push(DVec3::new(r * u.cos(), r * u.sin(), small * w.sin()));
        }
    }
    let id = |i: usize, j: usize| ((i % nu) * nv + j % nv) as u32;
    let mut t = Vec::new();
    for i in 0..nu {
        for j in 0..nv {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            t.push([a, b, c]);
            t.push([a, c, d]);
        }
    }
    TriMesh {
        vertices: v,
        triangles: t,
    }
}

/// Disjoint union of meshes.
pub fn union(meshes: &[TriMesh]) -> TriMesh {
    let mut m = TriMesh::default();
    for x in meshes {
        let o = m.vertices.len() as u32;
        m.vertices.extend(&x.vertices);
        m.triangles
            .extend(x.triangles.iter().map(|t| t.map(|i| i + o)));
    }
    m
}

/// The unit sphere as an analytic oracle: value |p| - 1, projection p/|p|, d_M = 1 on S.
pub struct UnitSphere;

impl Surface for UnitSphere {
    fn bounding_sphere(&self) -> BoundingSphere {
        BoundingSphere::at_origin(2.0)
    }
    fn value(&self, p: DVec3) -> f64 {
        p.length() - 1.0
    }
    fn project(&self, p: DVec3) -> Option<DVec3> {
        let l = p.length();
        (l > 0.0).then(|| p / l)
    }
    fn gradient(&self, p: DVec3) -> DVec3 {
        p.normalize_or_zero()
    }
    fn seed_points(&self, _seed: u64) -> Vec<DVec3> {
        vec![DVec3::X, -DVec3::Z]
    }
    fn dm_inf_hint(&self) -> Option<f64> {
        Some(1.0)
    }
}

/// Fibonacci points on the unit sphere.
pub fn fibonacci_sphere(n: usize) -> Vec<DVec3> {
    let golden = PI * (3.0 - 5.0_f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
            let r = (1.0 - z * z).sqrt();
            let ph = golden * i as f64;
            DVec3::new(r * ph.cos(), r * ph.sin(), z)
        })
        .collect()
}

/// The torus with major radius `big` and minor `small` around the z axis, with its exact
/// closest-point projection; d_M = `small` on S when big >= 2 small.
pub struct Torus {
    pub big: f64,
    pub small: f64,
}

impl Torus {
    fn core_point(&self, p: DVec3) -> DVec3 {
        let q = DVec3::new(p.x, p.y, 0.0);
        let l = q.length();
        let dir = if l > 0.0 { q / l } else { DVec3::X };
        dir * self.big
    }
}

impl Surface for Torus {
    fn bounding_sphere(&self) -> BoundingSphere {
        BoundingSphere::at_origin(1.5 * (self.big + self.small))
    }
    fn value(&self, p: DVec3) -> f64 {
        (p - self.core_point(p)).length() - self.small
    }
    fn project(&self, p: DVec3) -> Option<DVec3> {
        let c = self.core_point(p);
        let d = p - c;
        let l = d.length();
        (l > 0.0).then(|| c + d / l * self.small)
    }
    fn gradient(&self, p: DVec3) -> DVec3 {
        (p - self.core_point(p)).normalize_or_zero()
    }
    fn seed_points(&self, _seed: u64) -> Vec<DVec3> {
        vec![
            DVec3::X * (self.big + self.small),
            DVec3::Y * (self.big - self.small),
        ]
    }
    fn dm_inf_hint(&self) -> Option<f64> {
        Some(self.small)
    }
}
