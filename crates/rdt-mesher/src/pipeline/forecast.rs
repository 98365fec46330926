//! A run's cost before refining (ours; the refinement is section 6.1's at angle 30): the
//! surface area, estimated cheaply, then vertices ~ [`VERTICES_PER_AREA`] area / sigma^2 and
//! memory ~ [`BASE_BYTES`] + [`BYTES_PER_VERTEX`] per vertex.
//!
//! The area comes from the voxel edges crossed by the iso level (images, a Cauchy-Crofton
//! count), the input's triangles (meshes) or a coarse mesh at sigma = bounding radius / 20
//! (implicit surfaces, point sets, surfaces of the caller's). Every estimate is
//! deterministic: the same input gives the same forecast on any thread count.

use crate::{Criteria, MeshOptions, Sizing};
use glam::DVec3;
use oracle::Surface;
use oracle::image::ImageSurface;
use rayon::prelude::*;
use std::fmt;

/// Vertices per unit of area / sigma^2 at angle 30: measured 0.658 to 0.667 on the sphere,
/// torus, chair and tanglecube, the bunny and fertility, the phantom (0.66, 0.70 on the
/// nilearn motor map; 0.75 to 0.84 on a 1 mm white-matter mask at sigma 1 to 2, whose area
/// the coarse meshes under-estimate). CGAL reports about 0.7.
pub const VERTICES_PER_AREA: f64 = 0.66;

/// Peak memory per output vertex, verification included: measured 1,320 to 1,530 bytes on
/// runs of 78k to 420k vertices (1,352 on the 7.7M-vertex brain mask of issue 15); small runs
/// are dominated by [`BASE_BYTES`].
pub const BYTES_PER_VERTEX: f64 = 1_500.0;

/// Memory of a run before its first vertex (program, input), in bytes.
pub const BASE_BYTES: f64 = 16.0 * 1024.0 * 1024.0;

/// Where an area estimate comes from.
///
/// ```
/// use rdt_mesher::pipeline::AreaSource;
/// assert_eq!(AreaSource::InputTriangles.to_string(), "of the input triangles");
/// ```
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
#[serde(tag = "method", rename_all = "kebab-case")]
pub enum AreaSource {
    /// Voxel edges whose two ends lie on both sides of the iso level, each weighted by the
    /// area of its dual voxel face, over 1.5 (the mean of |n_x| + |n_y| + |n_z| over
    /// directions): exact on average for a surface resolved by the grid.
    VoxelCrossings {
        /// Voxel edges crossed.
        crossed_edges: u64,
    },
    /// The sum of the input mesh's triangle areas.
    InputTriangles,
    /// The area of a coarse mesh of the surface (an under-estimate where the surface has
    /// detail finer than `sigma`).
    CoarseMesh {
        /// Its size bound.
        sigma: f64,
        /// Its vertices.
        vertices: usize,
    },
}

impl fmt::Display for AreaSource {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            AreaSource::VoxelCrossings { crossed_edges } => write!(
                f,
                "from {} voxel edges crossed by the iso level",
                count(*crossed_edges)
            ),
            AreaSource::InputTriangles => f.write_str("of the input triangles"),
            AreaSource::CoarseMesh { sigma, vertices } => write!(
                f,
                "of a coarse mesh (sigma {}, {} vertices)",
                sig(*sigma),
                count(*vertices as u64)
            ),
        }
    }
}

/// An estimate of the surface's area.
///
/// ```
/// use rdt_mesher::pipeline::{AreaEstimate, AreaSource};
/// let a = AreaEstimate { area: 12.57, source: AreaSource::InputTriangles };
/// assert_eq!(a.to_string(), "surface area 12.6 of the input triangles");
/// ```
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct AreaEstimate {
    /// The area, in the surface's units squared.
    pub area: f64,
    /// How it was estimated.
    #[serde(flatten)]
    pub source: AreaSource,
}

impl fmt::Display for AreaEstimate {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "surface area {} {}", sig(self.area), self.source)
    }
}

/// What a run at a constant size sigma will cost.
///
/// ```
/// use rdt_mesher::pipeline::{AreaEstimate, AreaSource, Forecast};
/// let sphere = AreaEstimate { area: 4.0 * std::f64::consts::PI, source: AreaSource::InputTriangles };
/// let f = Forecast::at(sphere, 0.05);
/// assert_eq!(f.vertices, 3318); // measured: 3303
/// assert!((Forecast::size_for(sphere.area, f.vertices) - 0.05).abs() < 1e-4);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Forecast {
    /// The size bound forecast.
    pub sigma: f64,
    /// The area it is based on.
    pub area: AreaEstimate,
    /// Output vertices, about.
    pub vertices: u64,
    /// Peak memory, about, in bytes.
    pub memory_bytes: u64,
}

impl Forecast {
    /// The forecast at `sigma` (> 0) for a surface of this area.
    pub fn at(area: AreaEstimate, sigma: f64) -> Forecast {
        let v = (VERTICES_PER_AREA * area.area / (sigma * sigma)).round();
        let v = if v.is_finite() { v.min(1e18) } else { 1e18 };
        Forecast {
            sigma,
            area,
            vertices: v as u64,
            memory_bytes: memory_for(v as u64),
        }
    }

    /// A note when a run made more than twice the vertices forecast: the surface has parts
    /// thinner than sigma (sheets, necks, specks) that the refinement resolves beyond the size
    /// bound, which an area-only forecast does not count.
    ///
    /// ```
    /// use rdt_mesher::pipeline::{AreaEstimate, AreaSource, Forecast};
    /// let a = AreaEstimate { area: 4.0 * std::f64::consts::PI, source: AreaSource::InputTriangles };
    /// let f = Forecast::at(a, 0.05); // 3318 vertices
    /// assert!(f.overshoot(3303).is_none());
    /// assert!(f.overshoot(9000).unwrap().starts_with("9000 vertices, 2.7 times the forecast"));
    /// ```
    pub fn overshoot(&self, vertices: usize) -> Option<String> {
        let ratio = vertices as f64 / self.vertices.max(1) as f64;
        (ratio > 2.0).then(|| {
            format!(
                "{vertices} vertices, {ratio:.1} times the forecast: the surface has parts \
                 thinner than sigma (sheets, necks, specks) that the refinement resolves beyond \
                 the size bound, and the forecast counts area only; a coarser --size changes \
                 little there"
            )
        })
    }

    /// The size bound whose forecast is `vertices` on a surface of this area.
    pub fn size_for(area: f64, vertices: u64) -> f64 {
        (VERTICES_PER_AREA * area / vertices.max(1) as f64).sqrt()
    }
}

impl fmt::Display for Forecast {
    /// `about 62k vertices and 110 MiB at sigma 1.73 (surface area 2.2e5 from ...)`
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "about {} vertices and {} of memory at sigma {} ({})",
            count(self.vertices),
            bytes(self.memory_bytes),
            sig(self.sigma),
            self.area
        )
    }
}

/// The forecast peak memory of a run with `vertices` vertices, in bytes.
///
/// ```
/// assert_eq!(rdt_mesher::pipeline::memory_for(0), 16 << 20);
/// ```
pub fn memory_for(vertices: u64) -> u64 {
    (BASE_BYTES + BYTES_PER_VERTEX * vertices as f64).min(u64::MAX as f64 / 2.0) as u64
}

/// The vertices a memory budget affords (the inverse of [`memory_for`]).
///
/// ```
/// use rdt_mesher::pipeline::{memory_for, vertices_for_memory};
/// assert!(memory_for(vertices_for_memory(1 << 30)) <= 1 << 30);
/// ```
pub fn vertices_for_memory(bytes: u64) -> u64 {
    ((bytes as f64 - BASE_BYTES).max(0.0) / BYTES_PER_VERTEX).floor() as u64
}

/// The area of an image's iso surface from the voxel edges it crosses (see
/// [`AreaSource::VoxelCrossings`]); the voxels outside the image are background.
///
/// ```
/// use oracle::image::{ImageOptions, ImageSurface, Volume, Voxels};
/// use glam::{DAffine3, DVec3};
/// // A 20^3 binary ball of radius 7 voxels, spacing 1.
/// let n = 20;
/// let data: Vec<u8> = (0..n * n * n)
///     .map(|i| {
///         let p = DVec3::new((i % n) as f64, ((i / n) % n) as f64, (i / (n * n)) as f64);
///         (p.distance(DVec3::splat(9.5)) < 7.0) as u8
///     })
///     .collect();
/// let vol = Volume::new([n, n, n], Voxels::U8(data), DAffine3::IDENTITY).unwrap();
/// let img = ImageSurface::new(vol, &ImageOptions::default()).unwrap();
/// let a = rdt_mesher::pipeline::voxel_crossing_area(&img).area;
/// let exact = 4.0 * std::f64::consts::PI * 49.0;
/// assert!((a / exact - 1.0).abs() < 0.1, "{a} vs {exact}");
/// ```
pub fn voxel_crossing_area(img: &ImageSurface) -> AreaEstimate {
    let [nx, ny, nz] = img.volume().dims();
    let (px, py, pz) = (nx + 2, ny + 2, nz + 2);
    // Inside flags on the grid padded by one voxel of background.
    let mut inside = vec![false; px * py * pz];
    inside
        .par_chunks_mut(px * py)
        .enumerate()
        .for_each(|(k, slab)| {
            for j in 0..py {
                for i in 0..px {
                    let v = DVec3::new(i as f64 - 1.0, j as f64 - 1.0, k as f64 - 1.0);
                    slab[j * px + i] = img.value_voxel(v) < 0.0;
                }
            }
        });
    let at = |i: usize, j: usize, k: usize| inside[(k * py + j) * px + i];
    let counts: [u64; 3] = (0..pz)
        .into_par_iter()
        .map(|k| {
            let mut c = [0u64; 3];
            for j in 0..py {
                for i in 0..px {
                    let s = at(i, j, k);
                    c[0] += u64::from(i + 1 < px && s != at(i + 1, j, k));
                    c[1] += u64::from(j + 1 < py && s != at(i, j + 1, k));
                    c[2] += u64::from(k + 1 < pz && s != at(i, j, k + 1));
                }
            }
            c
        })
        .reduce(|| [0; 3], |a, b| [a[0] + b[0], a[1] + b[1], a[2] + b[2]]);
    let m = img.volume().affine().matrix3;
    let (a, b, c) = (m.x_axis, m.y_axis, m.z_axis);
    let faces = [
        b.cross(c).length(),
        a.cross(c).length(),
        a.cross(b).length(),
    ];
    let projected: f64 = (0..3).map(|d| counts[d] as f64 * faces[d]).sum();
    AreaEstimate {
        area: projected / 1.5,
        source: AreaSource::VoxelCrossings {
            crossed_edges: counts.iter().sum(),
        },
    }
}

/// Vertices of the coarse mesh of [`probe_area`] at most (it stops there).
pub const PROBE_MAX_VERTICES: usize = 20_000;

/// The area of a coarse mesh of `surface` at sigma = bounding radius / 20 (angle 30, no
/// manifold patch, at most [`PROBE_MAX_VERTICES`]), with `base`'s seed, control points and
/// oracle; `None` when that mesh fails or is empty.
///
/// ```
/// let s = oracle::catalog::surface("sphere").unwrap();
/// let a = rdt_mesher::pipeline::probe_area(&s, &Default::default()).unwrap();
/// assert!((a.area / (4.0 * std::f64::consts::PI) - 1.0).abs() < 0.05, "{a}");
/// ```
pub fn probe_area(surface: &dyn Surface, base: &MeshOptions) -> Option<AreaEstimate> {
    let sigma = surface.bounding_sphere().radius / 20.0;
    if !(sigma > 0.0 && sigma.is_finite()) {
        return None;
    }
    let opts = MeshOptions {
        criteria: Criteria {
            size: Some(Sizing::Constant(sigma)),
            min_angle_deg: 30.0,
            max_distance: None,
        },
        manifold: false,
        max_vertices: Some(PROBE_MAX_VERTICES),
        time_limit: None,
        initial_points: Vec::new(),
        ..base.clone()
    };
    let r = crate::mesh(surface, &opts).ok()?;
    let area = triangle_area(&r.mesh);
    (area > 0.0 && area.is_finite()).then_some(AreaEstimate {
        area,
        source: AreaSource::CoarseMesh {
            sigma,
            vertices: r.mesh.vertices.len(),
        },
    })
}

/// The sum of a mesh's triangle areas.
///
/// ```
/// use glam::DVec3;
/// let m = meshio::TriMesh { vertices: vec![DVec3::ZERO, DVec3::X, DVec3::Y],
///                           triangles: vec![[0, 1, 2]] };
/// assert_eq!(rdt_mesher::pipeline::triangle_area(&m), 0.5);
/// ```
pub fn triangle_area(m: &meshio::TriMesh) -> f64 {
    m.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| m.vertices[i as usize]);
            0.5 * (b - a).cross(c - a).length()
        })
        .sum()
}

/// A byte count from `2G`, `500M`, `1.5GiB`, `64k` or `1000000` (binary units: K = 1024;
/// a `B` or `iB` suffix is accepted, case is not significant). Positive, at most 1 PiB.
///
/// ```
/// use rdt_mesher::pipeline::parse_bytes;
/// assert_eq!(parse_bytes("2G"), Ok(2 << 30));
/// assert_eq!(parse_bytes("1.5 GiB"), Ok(3 << 29));
/// assert_eq!(parse_bytes("512m"), Ok(512 << 20));
/// assert!(parse_bytes("0").is_err() && parse_bytes("-1G").is_err() && parse_bytes("2X").is_err());
/// ```
pub fn parse_bytes(s: &str) -> Result<u64, String> {
    let t = s.trim().to_ascii_lowercase();
    let t = t.strip_suffix("ib").or(t.strip_suffix('b')).unwrap_or(&t);
    let (num, scale) = match t.char_indices().last() {
        Some((i, u @ ('k' | 'm' | 'g' | 't' | 'p'))) => {
            let p = "kmgtp".find(u).expect("a unit") as i32 + 1;
            (&t[..i], 1024f64.powi(p))
        }
        _ => (t, 1.0),
    };
    let v: f64 = num.trim().parse().map_err(|_| {
        format!("`{s}` is not an amount of memory (e.g. 2G, 500M, 1.5GiB; binary units)")
    })?;
    let b = v * scale;
    if !(b.is_finite() && b >= 1.0 && b <= 1024f64.powi(5)) {
        return Err(format!(
            "`{s}`: give a positive amount of memory, at most 1P (e.g. 2G, 500M)"
        ));
    }
    Ok(b.round() as u64)
}

/// `1.4 GiB`, `31 MiB`, `512 KiB`.
///
/// ```
/// assert_eq!(rdt_mesher::pipeline::bytes(3 << 29), "1.5 GiB");
/// ```
pub fn bytes(b: u64) -> String {
    let units = ["B", "KiB", "MiB", "GiB", "TiB", "PiB"];
    let mut v = b as f64;
    let mut u = 0;
    while v >= 1024.0 && u + 1 < units.len() {
        v /= 1024.0;
        u += 1;
    }
    if u == 0 || v >= 10.0 {
        format!("{v:.0} {}", units[u])
    } else {
        format!("{v:.1} {}", units[u])
    }
}

/// `850`, `3.3k`, `62k`, `1.2M`.
///
/// ```
/// use rdt_mesher::pipeline::count;
/// assert_eq!([count(850), count(3318), count(61_900), count(7_690_000)], ["850", "3.3k", "62k", "7.7M"]);
/// ```
pub fn count(n: u64) -> String {
    let v = n as f64;
    match n {
        0..1_000 => n.to_string(),
        1_000..10_000 => format!("{:.1}k", v / 1e3),
        10_000..999_500 => format!("{:.0}k", v / 1e3),
        _ => format!("{:.1}M", v / 1e6),
    }
}

/// Three significant digits: `0.0271`, `1.73`, `2.2e5`.
pub(crate) fn sig(x: f64) -> String {
    let a = x.abs();
    if a == 0.0 || !a.is_finite() {
        return format!("{x}");
    }
    if !(1e-3..1e5).contains(&a) {
        return format!("{x:.2e}");
    }
    let decimals = (2 - a.log10().floor() as i32).max(0) as usize;
    format!("{x:.decimals$}")
}

/// `x` rounded up to three significant digits (a size a user can type and get again).
///
/// ```
/// assert_eq!(rdt_mesher::pipeline::round_up_3(1.7234), 1.73);
/// ```
pub fn round_up_3(x: f64) -> f64 {
    if !(x > 0.0 && x.is_finite()) {
        return x;
    }
    let e = 10f64.powi(x.log10().floor() as i32 - 2);
    let r = (x / e).ceil() * e;
    // Printing r with the digits it has gives r back (e.g. 1.73, not 1.7300000000000002).
    sig(r).parse().unwrap_or(r)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sig_and_counts_read_well() {
        assert_eq!(sig(0.027), "0.0270");
        assert_eq!(sig(1.7234), "1.72");
        assert_eq!(sig(213_000.0), "2.13e5");
        assert_eq!(count(999_499), "999k");
        assert_eq!(count(999_500), "1.0M");
        assert_eq!(round_up_3(0.0901), 0.0901);
        assert_eq!(round_up_3(12345.0), 12400.0);
    }

    #[test]
    fn forecast_of_a_huge_area_saturates() {
        let a = AreaEstimate {
            area: 1e300,
            source: AreaSource::InputTriangles,
        };
        let f = Forecast::at(a, 1e-300);
        assert_eq!(f.vertices, 1e18 as u64);
        assert!(f.memory_bytes > 1 << 60);
    }
}
