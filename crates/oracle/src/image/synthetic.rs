//! Volumes sampled from implicit functions (ours: test and bench fixtures).

use super::{Volume, Voxels};
use glam::{DAffine3, DMat3, DVec3};
use rayon::prelude::*;

/// Sample `f` (world coordinates) at the voxel centres `affine * (i, j, k)`, stored as `f32`.
/// Parallel over z-slices; deterministic.
///
/// # Panics
/// If a dim is zero or the affine is singular (test helper).
pub fn sample_implicit(
    f: impl Fn(DVec3) -> f64 + Sync,
    dims: [usize; 3],
    affine: DAffine3,
) -> Volume {
    let v = sample(&f, dims, affine, |x| x as f32);
    Volume::new(dims, Voxels::F32(v), affine).expect("valid dims and affine")
}

/// Binary `u8` volume: 1 where `f < 0`, 0 elsewhere.
pub fn sample_binary(
    f: impl Fn(DVec3) -> f64 + Sync,
    dims: [usize; 3],
    affine: DAffine3,
) -> Volume {
    let v = sample(&f, dims, affine, |x| (x < 0.0) as u8);
    Volume::new(dims, Voxels::U8(v), affine).expect("valid dims and affine")
}

fn sample<T: Send>(
    f: &(impl Fn(DVec3) -> f64 + Sync),
    dims: [usize; 3],
    affine: DAffine3,
    conv: impl Fn(f64) -> T + Sync,
) -> Vec<T> {
    let [nx, ny, nz] = dims;
    (0..nx * ny * nz)
        .into_par_iter()
        .with_min_len(4096)
        .map(|p| {
            let c = DVec3::new(
                (p % nx) as f64,
                ((p / nx) % ny) as f64,
                (p / (nx * ny)) as f64,
            );
            conv(f(affine.transform_point3(c)))
        })
        .collect()
}

/// Isotropic grid of `n^3` voxels covering the cube `[-half, half]^3` (voxel centres on the
/// faces).
pub fn cube_affine(n: usize, half: f64) -> DAffine3 {
    let h = 2.0 * half / (n as f64 - 1.0);
    DAffine3::from_mat3_translation(DMat3::from_diagonal(DVec3::splat(h)), DVec3::splat(-half))
}

/// The tanglecube `x⁴ - 5x² + y⁴ - 5y² + z⁴ - 5z² + 11.8` (genus 5, negative inside).
pub fn tanglecube(p: DVec3) -> f64 {
    let q = p * p;
    q.x * q.x - 5.0 * q.x + q.y * q.y - 5.0 * q.y + q.z * q.z - 5.0 * q.z + 11.8
}

/// The tanglecube sampled on `n^3` voxels over `[-2.6, 2.6]^3`, as `f32`. Mesh it with
/// `ImageOptions { iso: Some(0.0), dark_foreground: true, .. }` (the value is negative inside).
pub fn tanglecube_volume(n: usize) -> Volume {
    sample_implicit(tanglecube, [n; 3], cube_affine(n, 2.6))
}
