//! Generated hard volumes for the image regression suite (ours; section 6.6.2's images at
//! their worst): many small blobs, sheets and tubes thinner than a voxel, noise, checkerboard
//! saddles, and an integer volume meshed at one of its own values. Deterministic (a fixed
//! seed per case), 1 mm voxels, the grid centred on the origin.

use geom::SplitMix64;
use glam::{DAffine3, DVec3};
use oracle::image::{Volume, Voxels};

/// A generated case: name, volume, iso value.
pub struct Hard {
    pub name: &'static str,
    pub volume: Volume,
    pub iso: f64,
}

/// A volume of `n`^3 f32 voxels of 1 mm with values `f(voxel index position)`.
fn sample(n: usize, f: impl Fn(DVec3) -> f64) -> Volume {
    let mut d = Vec::with_capacity(n * n * n);
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                d.push(f(DVec3::new(i as f64, j as f64, k as f64)) as f32);
            }
        }
    }
    let half = 0.5 * (n - 1) as f64;
    Volume::new(
        [n; 3],
        Voxels::F32(d),
        DAffine3::from_translation(DVec3::splat(-half)),
    )
    .expect("a valid generated volume")
}

/// The case `name` at `iso`: `n`^3 voxels with values `f(voxel index position)`.
fn case(name: &'static str, iso: f64, n: usize, f: impl Fn(DVec3) -> f64) -> Hard {
    Hard {
        name,
        volume: sample(n, f),
        iso,
    }
}

/// `n`^3 values drawn in voxel order by `draw` from the seed `seed`, looked up by voxel index
/// position.
fn random_table(
    n: usize,
    seed: u64,
    draw: impl Fn(&mut SplitMix64) -> f64,
) -> impl Fn(DVec3) -> f64 {
    let mut rng = SplitMix64(seed);
    let vals: Vec<f64> = (0..n * n * n).map(|_| draw(&mut rng)).collect();
    move |p| vals[p.x as usize + n * (p.y as usize + n * p.z as usize)]
}

/// Every generated case.
pub fn all() -> Vec<Hard> {
    vec![
        blobs(),
        sheet(),
        tube(),
        noise(),
        checkerboard(),
        integer_levels(),
    ]
}

/// 80 blobs of radius 0.3 to 3 voxels in a 36^3 grid (specks below a voxel among them).
fn blobs() -> Hard {
    let mut rng = SplitMix64(11);
    let n = 36;
    let blobs: Vec<(DVec3, f64)> = (0..80)
        .map(|_| {
            let c = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 30.0
                + DVec3::splat(3.0);
            (c, 0.3 + 2.7 * rng.next_f64() * rng.next_f64())
        })
        .collect();
    case("blobs", 0.5, n, |p| {
        blobs
            .iter()
            .map(|(c, r)| (-(p - *c).length_squared() / (r * r)).exp())
            .fold(0.0, f64::max)
    })
}

/// A tilted slab 0.7 voxel thick, curved (its voxel samples break it up).
fn sheet() -> Hard {
    let n = 28;
    let nrm = DVec3::new(0.3, 0.5, 1.0).normalize();
    let c = DVec3::splat(13.5);
    case("sheet", 0.0, n, |p| {
        let q = p - c;
        let d = q.dot(nrm) - 0.02 * q.length_squared();
        let r = (q - nrm * q.dot(nrm)).length();
        if r > 11.0 { 0.0 } else { 1.0 - d.abs() / 0.35 }
    })
}

/// A helix-shaped tube of radius 0.4 voxel.
fn tube() -> Hard {
    let n = 28;
    let pts: Vec<DVec3> = (0..2000)
        .map(|i| {
            let t = i as f64 / 2000.0 * std::f64::consts::TAU * 3.0;
            DVec3::new(
                13.5 + 8.0 * t.cos(),
                13.5 + 8.0 * t.sin(),
                4.0 + 20.0 * t / 18.85,
            )
        })
        .collect();
    case("tube", 0.0, n, |p| {
        let d = pts
            .iter()
            .map(|q| q.distance(p))
            .fold(f64::INFINITY, f64::min);
        0.4 - d
    })
}

/// Uniform noise on 20^3 voxels at the median.
fn noise() -> Hard {
    let n = 20;
    case("noise", 0.5, n, random_table(n, 5, |rng| rng.next_f64()))
}

/// A checkerboard of +-1 perturbed by up to 0.1 (every face a saddle near the iso value 0),
/// inside a ball. (The exact checkerboard, whose saddles are all at the iso value, makes S
/// itself non-manifold: not a case for a manifold mesher.)
fn checkerboard() -> Hard {
    let n = 14;
    let c = DVec3::splat(6.5);
    let jitter = random_table(n, 3, |rng| 0.2 * rng.next_f64() - 0.1);
    case("checker", 0.0, n, |p| {
        if p.distance(c) > 5.5 {
            return -1.0;
        }
        jitter(p)
            + if (p.x + p.y + p.z) as i64 % 2 == 0 {
                1.0
            } else {
                -1.0
            }
    })
}

/// A smooth integer-valued volume (values 0 to 4) meshed at 2, one of its values.
fn integer_levels() -> Hard {
    let n = 24;
    let c = DVec3::splat(11.5);
    case("integer", 2.0, n, |p| {
        let q = p - c;
        let f = 4.0 * (1.0 - q.length() / 12.0) + 0.8 * (q.x * 0.7).sin() * (q.y * 0.5).cos();
        f.round().clamp(0.0, 4.0)
    })
}
