//! Triangle quality: angles, radius-edge ratios, area and enclosed volume.

use glam::DVec3;
use meshio::TriMesh;
use rayon::prelude::*;
use serde::Serialize;

/// Quality statistics over the triangles with non-zero area (computed in f64).
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Quality {
    pub min_angle_deg: f64,
    pub max_angle_deg: f64,
    /// Width of a histogram bin in degrees.
    pub angle_bin_deg: f64,
    /// `angle_histogram[k]` counts angles in `[k*bin, (k+1)*bin)` (180 in the last bin).
    pub angle_histogram: Vec<usize>,
    /// Circumradius / shortest edge (1/sqrt(3) ~ 0.577 for the equilateral triangle).
    pub radius_edge_min: f64,
    pub radius_edge_max: f64,
    pub radius_edge_mean: f64,
    /// Index of the triangle with the largest radius-edge ratio.
    pub worst_radius_edge_triangle: Option<usize>,
    pub total_area: f64,
    /// Signed enclosed volume by the divergence theorem (positive for a closed mesh
    /// oriented outward), computed relative to the bounding-box centre.
    pub volume: f64,
    /// Triangles with zero computed area (skipped by the angle statistics).
    pub zero_area_triangles: usize,
}

/// The smallest angle of a triangle in degrees, 0 for a degenerate one (what the `angles`
/// check counts against its bound).
pub fn smallest_angle_deg(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    triangle_shape(a, b, c).map_or(0.0, |(angles, _, _)| {
        angles
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min)
            .to_degrees()
    })
}

/// The three angles (radians), circumradius/shortest-edge and area of a triangle.
pub fn triangle_shape(a: DVec3, b: DVec3, c: DVec3) -> Option<([f64; 3], f64, f64)> {
    let (ab, bc, ca) = (b - a, c - b, a - c);
    let cross = ab.cross(-ca);
    let twice_area = cross.length();
    if twice_area.is_nan() || twice_area <= 0.0 {
        return None;
    }
    let angle = |u: DVec3, v: DVec3| u.cross(v).length().atan2(u.dot(v));
    let angles = [angle(ab, -ca), angle(bc, -ab), angle(ca, -bc)];
    let (la, lb, lc) = (ab.length(), bc.length(), ca.length());
    let r = la * lb * lc / (2.0 * twice_area);
    Some((angles, r / la.min(lb).min(lc), 0.5 * twice_area))
}

/// Quality statistics of a valid mesh; `bin_deg` is the histogram bin width (default 10
/// when not in (0, 180]).
pub fn analyze(mesh: &TriMesh, bin_deg: f64) -> Quality {
    let bin_deg = if bin_deg > 0.0 && bin_deg <= 180.0 {
        bin_deg
    } else {
        10.0
    };
    let nbins = (180.0 / bin_deg).ceil() as usize;
    let shapes: Vec<Option<([f64; 3], f64, f64)>> = mesh
        .triangles
        .par_iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| mesh.vertices[i as usize]);
            triangle_shape(a, b, c)
        })
        .collect();
    let mut q = Quality {
        min_angle_deg: f64::INFINITY,
        max_angle_deg: 0.0,
        angle_bin_deg: bin_deg,
        angle_histogram: vec![0; nbins],
        radius_edge_min: f64::INFINITY,
        radius_edge_max: 0.0,
        radius_edge_mean: 0.0,
        worst_radius_edge_triangle: None,
        total_area: 0.0,
        volume: 0.0,
        zero_area_triangles: 0,
    };
    let mut n = 0usize;
    for (ti, s) in shapes.iter().enumerate() {
        let Some((angles, re, area)) = s else {
            q.zero_area_triangles += 1;
            continue;
        };
        n += 1;
        for a in angles {
            let d = a.to_degrees();
            q.min_angle_deg = q.min_angle_deg.min(d);
            q.max_angle_deg = q.max_angle_deg.max(d);
            q.angle_histogram[((d / bin_deg) as usize).min(nbins - 1)] += 1;
        }
        q.radius_edge_min = q.radius_edge_min.min(*re);
        if *re > q.radius_edge_max {
            q.radius_edge_max = *re;
            q.worst_radius_edge_triangle = Some(ti);
        }
        q.radius_edge_mean += re;
        q.total_area += area;
    }
    if n > 0 {
        q.radius_edge_mean /= n as f64;
    } else {
        q.min_angle_deg = 0.0;
        q.radius_edge_min = 0.0;
    }
    let bb = geom::bvh::Aabb::from_points(&mesh.vertices);
    let o = if mesh.vertices.is_empty() {
        DVec3::ZERO
    } else {
        bb.center()
    };
    q.volume = mesh
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| mesh.vertices[i as usize] - o);
            a.dot(b.cross(c))
        })
        .sum::<f64>()
        / 6.0;
    q
}
