//! Scan-like test data from a closed mesh (not in the paper: test data for the point-set
//! backend of section 6.6.3): area-uniform samples with Gaussian noise, a density step
//! between two halves, an optional missing patch, with or without the exact normals.
//!
//! Invariants: deterministic (one [`SplitMix64`] stream from the seed, consumed in a fixed
//! order); noise, hole radius and positions scale with the mesh's bounding-box diagonal, so a
//! spec means the same on any model.

use geom::SplitMix64;
use glam::DVec3;
use meshio::TriMesh;

/// What to simulate.
#[derive(Clone, Debug, PartialEq)]
pub struct ScanSpec {
    /// Points kept (after the density thinning and the hole).
    pub points: usize,
    /// Per-coordinate standard deviation of the noise, as a fraction of the diagonal.
    pub noise: f64,
    /// Density ratio between the dense half (x above the box's center) and the sparse half
    /// (1: uniform).
    pub density_ratio: f64,
    /// Give the exact (face) normals.
    pub normals: bool,
    /// Radius of a missing patch (fraction of the diagonal, 0: none) about a surface point
    /// chosen from the seed.
    pub hole: f64,
    pub seed: u64,
}

impl Default for ScanSpec {
    fn default() -> Self {
        ScanSpec {
            points: 30_000,
            noise: 0.002,
            density_ratio: 1.0,
            normals: true,
            hole: 0.0,
            seed: 0,
        }
    }
}

/// A simulated scan.
#[derive(Clone, Debug, PartialEq)]
pub struct Scan {
    pub points: Vec<DVec3>,
    pub normals: Option<Vec<DVec3>>,
    /// The missing patch: its center (on the mesh) and radius.
    pub hole: Option<(DVec3, f64)>,
    /// The mesh's bounding-box diagonal.
    pub diagonal: f64,
}

/// Bounding-box diagonal of the vertices.
pub fn diagonal(mesh: &TriMesh) -> f64 {
    let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for &v in &mesh.vertices {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    (hi - lo).length()
}

/// A standard normal draw (Box-Muller, two uniforms per draw).
fn gauss(rng: &mut SplitMix64) -> f64 {
    let u = 1.0 - rng.next_f64(); // (0, 1]
    let v = rng.next_f64();
    (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
}

/// Simulate a scan of `mesh` (non-empty, valid). Returns an empty scan for a mesh of zero
/// area.
pub fn simulate(mesh: &TriMesh, spec: &ScanSpec) -> Scan {
    let v = &mesh.vertices;
    let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for &p in v {
        lo = lo.min(p);
        hi = hi.max(p);
    }
    let diag = (hi - lo).length();
    let cx = 0.5 * (lo.x + hi.x);
    // Cumulative areas for area-uniform triangle picks.
    let mut cum = Vec::with_capacity(mesh.triangles.len());
    let mut total = 0.0;
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| v[i as usize]);
        total += 0.5 * (b - a).cross(c - a).length();
        cum.push(total);
    }
    let mut rng = SplitMix64(spec.seed ^ 0x5CA1_AB1E);
    let mut scan = Scan {
        points: Vec::with_capacity(spec.points),
        normals: spec.normals.then(|| Vec::with_capacity(spec.points)),
        hole: None,
        diagonal: diag,
    };
    if total.is_nan() || total <= 0.0 || spec.points == 0 {
        return scan;
    }
    let pick = |rng: &mut SplitMix64| -> (DVec3, DVec3) {
        let x = rng.next_f64() * total;
        let t = cum.partition_point(|&c| c <= x).min(cum.len() - 1);
        let [a, b, c] = mesh.triangles[t].map(|i| v[i as usize]);
        let (mut r1, mut r2) = (rng.next_f64(), rng.next_f64());
        if r1 + r2 > 1.0 {
            (r1, r2) = (1.0 - r1, 1.0 - r2);
        }
        let n = (b - a).cross(c - a).normalize_or_zero();
        (a + (b - a) * r1 + (c - a) * r2, n)
    };
    if spec.hole > 0.0 {
        let (c, _) = pick(&mut rng);
        scan.hole = Some((c, spec.hole * diag));
    }
    let sigma = spec.noise * diag;
    let keep_sparse = 1.0 / spec.density_ratio.max(1.0);
    // Bounded tries: a hole covering everything cannot loop forever.
    let mut tries = 0usize;
    while scan.points.len() < spec.points && tries < 100 * spec.points {
        tries += 1;
        let (p, n) = pick(&mut rng);
        let u = rng.next_f64();
        let noise = DVec3::new(gauss(&mut rng), gauss(&mut rng), gauss(&mut rng));
        if p.x < cx && u >= keep_sparse {
            continue;
        }
        if let Some((c, r)) = scan.hole
            && (p - c).length() < r
        {
            continue;
        }
        scan.points.push(p + sigma * noise);
        if let Some(ns) = &mut scan.normals {
            ns.push(n);
        }
    }
    scan
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_meshes::octahedron;

    #[test]
    fn scans_are_deterministic_with_the_asked_density_noise_and_hole() {
        let m = octahedron();
        let spec = ScanSpec {
            points: 20_000,
            noise: 0.0,
            density_ratio: 10.0,
            hole: 0.2,
            ..Default::default()
        };
        let a = simulate(&m, &spec);
        assert_eq!(a, simulate(&m, &spec));
        assert_eq!(a.points.len(), 20_000);
        // On the surface |x|+|y|+|z| = 1 without noise.
        assert!(
            a.points
                .iter()
                .all(|p| (p.abs().element_sum() - 1.0).abs() < 1e-12)
        );
        // 10:1 density between the halves (without the hole).
        let b = simulate(
            &m,
            &ScanSpec {
                hole: 0.0,
                ..spec.clone()
            },
        );
        let dense = b.points.iter().filter(|p| p.x > 0.0).count() as f64;
        let ratio = dense / (b.points.len() as f64 - dense);
        assert!((8.5..11.5).contains(&ratio), "{ratio}");
        // No point in the hole.
        let (c, r) = a.hole.unwrap();
        assert!(a.points.iter().all(|p| (*p - c).length() >= r));
        // Noise: per-coordinate sigma as asked (measured on the x = 1 - |y| - |z| face).
        let noisy = simulate(
            &m,
            &ScanSpec {
                noise: 0.01,
                ..Default::default()
            },
        );
        let rms = (noisy
            .points
            .iter()
            .map(|p| (p.abs().element_sum() - 1.0).powi(2))
            .sum::<f64>()
            / noisy.points.len() as f64)
            .sqrt();
        // Along the face normal (1,1,1)/sqrt(3) the distance is |sum - 1| / sqrt(3).
        let sigma = rms / 3f64.sqrt();
        let want = 0.01 * diagonal(&m);
        assert!((sigma / want - 1.0).abs() < 0.1, "{sigma} vs {want}");
    }
}
