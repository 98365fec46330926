//! The output's topology against a closed input mesh's (ours; the paper's theorem 4.7 gives
//! the topology of S only when sigma resolves S): the `input-topology` check. A closed,
//! oriented, manifold input mesh has known components and genera; the output must have the
//! same (as multisets), or the check FAILs and its detail says why not, from what the input
//! itself shows at the mesh size sigma:
//!
//! - *thin parts*: input triangles whose inward normal segment of length sigma crosses the
//!   surface again (the solid is thinner than sigma there, so a ball of radius sigma sees
//!   both sides);
//! - *narrow gaps*: the same outward (two parts of the surface closer than sigma);
//! - *small components*: input components whose bounding box is under 2 sigma across.
//!
//! Probes are the centroids of at most [`MAX_PROBES`] triangles (a fixed stride), so the
//! result is deterministic; they run only when the topologies differ.

use glam::DVec3;
use meshio::TriMesh;
use oracle::Surface;
use rayon::prelude::*;

/// Triangles probed for thin parts and gaps.
pub const MAX_PROBES: usize = 20_000;

/// A closed input mesh's topology (kept by [`super::Input::mesh`]).
#[derive(Clone, Debug)]
pub struct SourceTopology {
    /// Genus of each component, sorted.
    pub genera: Vec<i64>,
    /// Bounding-box diagonal of each component (in the order of `genera`'s components
    /// before sorting; used for the small-component reason).
    extents: Vec<f64>,
    /// The welded input (the probes' triangles).
    mesh: TriMesh,
}

impl SourceTopology {
    /// The topology of `welded` when it is a closed, oriented, manifold mesh with a genus for
    /// every component; `None` otherwise (no claim is made for broken inputs).
    pub fn of(welded: &TriMesh) -> Option<SourceTopology> {
        let topo = verify::topology::analyze(welded, 0);
        if !topo.is_closed_oriented_manifold() || topo.components.is_empty() {
            return None;
        }
        let mut genera: Vec<i64> = topo.genera().into_iter().collect::<Option<_>>()?;
        genera.sort_unstable();
        let extents = verify::topology::vertex_components(welded)
            .iter()
            .map(|c| {
                let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
                for &i in c {
                    lo = lo.min(welded.vertices[i]);
                    hi = hi.max(welded.vertices[i]);
                }
                (hi - lo).length()
            })
            .collect();
        Some(SourceTopology {
            genera,
            extents,
            mesh: welded.clone(),
        })
    }

    /// Components of the input.
    pub fn components(&self) -> usize {
        self.genera.len()
    }
}

/// What the probes found: the share of the probed area, and the worst place.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Narrow {
    /// Share of the probed area where the other side (thin) or another part (gap) is within
    /// sigma.
    pub share: f64,
    /// The narrowest probe: its centroid and the distance found.
    pub worst: Option<(DVec3, f64)>,
}

/// Thin parts (inward) and narrow gaps (outward) of `src` at `sigma`, probed on `surface`
/// (the input's oracle: its value is negative inside).
pub fn narrow_parts(src: &SourceTopology, surface: &dyn Surface, sigma: f64) -> [Narrow; 2] {
    let m = &src.mesh;
    let stride = m.triangles.len().div_ceil(MAX_PROBES).max(1);
    // Per probe: (area, inward distance, outward distance); infinity when none within sigma.
    let probes: Vec<(DVec3, f64, [f64; 2])> = m
        .triangles
        .par_iter()
        .step_by(stride)
        .map(|t| {
            let [a, b, c] = t.map(|i| m.vertices[i as usize]);
            let cr = (b - a).cross(c - a);
            let area = 0.5 * cr.length();
            let ctr = (a + b + c) / 3.0;
            let n = cr.normalize_or_zero();
            let mut dist = [f64::INFINITY; 2];
            if n == DVec3::ZERO {
                return (ctr, 0.0, dist);
            }
            let delta = 1e-6 * sigma;
            let mut out = Vec::new();
            for s in [1.0, -1.0] {
                let d = s * n;
                let start = ctr + delta * d;
                let inside = surface.value(start) < 0.0;
                out.clear();
                surface.crossings(start, ctr + sigma * d, &mut out);
                if let Some(x) = out
                    .iter()
                    .map(|x| (*x - ctr).length())
                    .filter(|&l| l > 2.0 * delta)
                    .min_by(f64::total_cmp)
                {
                    let k = usize::from(!inside);
                    dist[k] = dist[k].min(x);
                }
            }
            (ctr, area, dist)
        })
        .collect();
    let total: f64 = probes.iter().map(|p| p.1).sum();
    let mut res = [Narrow::default(); 2];
    for (k, r) in res.iter_mut().enumerate() {
        let hit: f64 = probes
            .iter()
            .filter(|p| p.2[k].is_finite())
            .map(|p| p.1)
            .sum();
        r.share = if total > 0.0 { hit / total } else { 0.0 };
        r.worst = probes
            .iter()
            .filter(|p| p.2[k].is_finite())
            .min_by(|a, b| a.2[k].total_cmp(&b.2[k]))
            .map(|p| (p.0, p.2[k]));
    }
    res
}

/// The `input-topology` check of `report` (whose `topology` is the output's) against `src`.
pub fn add_check(
    report: &mut verify::Report,
    src: &SourceTopology,
    surface: &dyn Surface,
    sigma: f64,
) {
    let Some(topo) = &report.topology else {
        return;
    };
    let out: Option<Vec<i64>> = topo.genera().into_iter().collect();
    let mut out_sorted = out.clone().unwrap_or_default();
    out_sorted.sort_unstable();
    let fmt_g = |g: &[i64]| {
        g.iter()
            .map(|x| x.to_string())
            .collect::<Vec<_>>()
            .join(", ")
    };
    let said = format!(
        "input: {} component{} of genus [{}]",
        src.components(),
        if src.components() == 1 { "" } else { "s" },
        fmt_g(&src.genera)
    );
    let (status, detail) = match out {
        Some(_) if out_sorted == src.genera => (
            verify::Status::Pass,
            format!("{said}; the output has the same"),
        ),
        _ => {
            let got = match topo.is_closed_oriented_manifold() {
                true => format!(
                    "output: {} component{} of genus [{}]",
                    out_sorted.len(),
                    if out_sorted.len() == 1 { "" } else { "s" },
                    fmt_g(&out_sorted)
                ),
                false => format!(
                    "output: {} components, not a closed oriented manifold",
                    topo.components.len()
                ),
            };
            let why = reasons(src, surface, sigma);
            (verify::Status::Fail, format!("{said}; {got}; why: {why}"))
        }
    };
    report.checks.push(verify::Check {
        name: "input-topology".into(),
        status,
        detail,
    });
}

/// Why the topologies may differ at `sigma`, in words.
fn reasons(src: &SourceTopology, surface: &dyn Surface, sigma: f64) -> String {
    let fmt_p = |p: DVec3| format!("({:.4}, {:.4}, {:.4})", p.x, p.y, p.z);
    let mut why = Vec::new();
    let small: Vec<f64> = src
        .extents
        .iter()
        .copied()
        .filter(|&e| e < 2.0 * sigma)
        .collect();
    if let Some(e) = small.iter().copied().min_by(f64::total_cmp) {
        why.push(format!(
            "{} input components under 2 sigma across (smallest {e:.3e})",
            small.len()
        ));
    }
    let [thin, gap] = narrow_parts(src, surface, sigma);
    for (n, what) in [(thin, "thinner than"), (gap, "facing another part within")] {
        if let Some((p, d)) = n.worst {
            why.push(format!(
                "{:.2}% of the input's area is {what} sigma = {sigma:.3e} (narrowest {d:.3e} at {})",
                100.0 * n.share,
                fmt_p(p)
            ));
        }
    }
    if why.is_empty() {
        format!(
            "no thin part, narrow gap or small component below sigma = {sigma:.3e} found (unexplained)"
        )
    } else {
        why.join("; ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two unit cubes (as 12 triangles each) at distance `gap` along x.
    fn two_cubes(gap: f64) -> TriMesh {
        let cube = |o: DVec3| -> (Vec<DVec3>, Vec<[u32; 3]>) {
            let v: Vec<DVec3> = (0..8)
                .map(|i| {
                    o + DVec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64)
                })
                .collect();
            let t = vec![
                [0, 2, 1],
                [1, 2, 3],
                [4, 5, 6],
                [5, 7, 6],
                [0, 1, 4],
                [1, 5, 4],
                [2, 6, 3],
                [3, 6, 7],
                [0, 4, 2],
                [2, 4, 6],
                [1, 3, 5],
                [3, 7, 5],
            ];
            (v, t)
        };
        let (mut v, mut t) = cube(DVec3::ZERO);
        let (v2, t2) = cube(DVec3::new(1.0 + gap, 0.0, 0.0));
        t.extend(t2.iter().map(|f| f.map(|i| i + 8)));
        v.extend(v2);
        TriMesh {
            vertices: v,
            triangles: t,
        }
    }

    #[test]
    fn gaps_and_components_are_measured() {
        let m = two_cubes(0.05);
        let src = SourceTopology::of(&m).expect("closed");
        assert_eq!(src.genera, vec![0, 0]);
        let poly = oracle::polyhedron::PolyhedronSurface::new(&m).unwrap();
        let [thin, gap] = narrow_parts(&src, &poly, 0.1);
        // Two facing faces of 2 x 12 triangles (all the same area): 4 of 24 probes.
        assert!((gap.share - 4.0 / 24.0).abs() < 1e-9, "{gap:?}");
        assert!((gap.worst.unwrap().1 - 0.05).abs() < 1e-9, "{gap:?}");
        assert_eq!(thin.share, 0.0);
        // At sigma 1.5, the cubes (1 thick) are thin everywhere.
        let [thin, _] = narrow_parts(&src, &poly, 1.5);
        assert!((thin.share - 1.0).abs() < 1e-9, "{thin:?}");
        let why = reasons(&src, &poly, 0.01);
        assert!(why.contains("unexplained"), "{why}");
        let why = reasons(&src, &poly, 0.9);
        assert!(why.contains("2 input components under 2 sigma"), "{why}");
    }

    #[test]
    fn open_meshes_make_no_claim() {
        let mut m = two_cubes(0.5);
        m.triangles.pop();
        assert!(SourceTopology::of(&m).is_none());
    }
}
