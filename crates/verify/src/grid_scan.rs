//! Grid scans of an implicit function (ours; P1 of section 6.6.2 carried from images to f):
//! the components and the total genus of S seen on two voxel grids, independently of the
//! mesher's sample.
//!
//! The mesher finds S from seed points and refines where its sample already is: a component
//! or a handle smaller than the size can be missed, and then a certificate made from the same
//! sample (the Voronoi poles of the mesh's own vertices, the points of S found near the mesh)
//! cannot see it. Here `f` is sampled on grids of `n` and `2n - 1` nodes per axis over the
//! bounding sphere's cube (nodes outside the ball count as outside: S lies inside it), and
//! each grid is read as an image: the voxel scan ([`oracle::image::Topology`]) gives the
//! components of its trilinear level set and their total genus exactly
//! ([`ImageSurface::scan_genus`]).
//!
//! The trilinear level set is S only where the grid resolves S: a neck or a gap thinner than
//! the step can be cut or closed by the sampling, in either direction. So a figure counts only
//! when both grids agree (the scan is stable under halving the step), and then:
//! - one point of each scan component, projected onto S with the oracle, joins the seeds of
//!   `components-sampled`: a point of S far from the mesh is a missed component whatever the
//!   grids are (the projection is on S);
//! - `grid-genus` FAILs a mesh with fewer handles than the stable scan (unless components
//!   were dropped or missed, whose genera are not known apart), PASSes an equal count, and
//!   says INFO when the mesh has more: a handle thinner than half the step is below both
//!   grids, so more handles are not proven wrong.
//!
//! # Invariant
//! No FAIL comes from the grids alone where they disagree with each other.

use glam::{DAffine3, DMat3, DVec3};
use oracle::Surface;
use oracle::image::{ImageOptions, ImageSurface, Volume, Voxels};
use rayon::prelude::*;

use crate::scan_components::{GenusComparison, NOT_A_MANIFOLD, ScanComponents, account};
use crate::{Report, Status};

/// Nodes per axis of the coarse grid in `verify` and `mesh` (the fine grid has `2n - 1`).
pub const DEFAULT_NODES: usize = 129;

/// The scans of `f` on the two grids.
pub struct GridScan {
    /// The fine grid read as an image (its voxel scan is the one compared with the mesh).
    pub fine: ImageSurface,
    /// Step of the fine grid (half the coarse one).
    pub step: f64,
    /// Surface components and total genus of the coarse scan.
    pub coarse_figures: (usize, Option<usize>),
    /// The same of the fine scan.
    pub fine_figures: (usize, Option<usize>),
    /// One point of S per fine scan component (its seed projected onto S by the oracle);
    /// components whose seed did not project are left out and counted in `unprojected`.
    pub seeds: Vec<DVec3>,
    /// Fine scan components whose point did not project onto S within two steps.
    pub unprojected: usize,
    /// Points of S from the fine grid: its edge crossings (the marching-cubes vertices of the
    /// trilinear level set) projected onto S by the oracle, those that land within two steps;
    /// the S -> mesh distances of `hausdorff` are measured from them too, so that parts of S
    /// away from the mesh count.
    pub surface_points: Vec<DVec3>,
}

impl GridScan {
    /// Both grids see the same number of components and the same total genus.
    pub fn stable(&self) -> bool {
        self.coarse_figures == self.fine_figures
    }
}

/// Why there is no scan.
#[derive(Debug)]
pub enum ScanError {
    /// `f` is NaN at a grid node inside the ball.
    Nan([f64; 3]),
    /// No node is inside the solid on the fine grid (every sample has `f >= 0`).
    NoInside,
    /// Fewer than 3 nodes per axis.
    TooCoarse(usize),
}

impl std::fmt::Display for ScanError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ScanError::Nan(p) => write!(
                f,
                "f is NaN at the grid node ({:.4}, {:.4}, {:.4})",
                p[0], p[1], p[2]
            ),
            ScanError::NoInside => write!(f, "no grid node has f < 0"),
            ScanError::TooCoarse(n) => write!(f, "{n} nodes per axis (at least 3)"),
        }
    }
}

/// `f` sampled on `n^3` nodes over the cube of `surface`'s bounding sphere, as `f32` with its
/// sign kept (a value that rounds to zero keeps its sign at the smallest normal magnitude);
/// nodes outside the ball get +1. Also the grid step.
fn sample(surface: &dyn Surface, n: usize) -> Result<(Volume, f64), ScanError> {
    let bs = surface.bounding_sphere();
    let step = 2.0 * bs.radius / (n as f64 - 1.0);
    let lo = bs.center - DVec3::splat(bs.radius);
    let affine = DAffine3::from_mat3_translation(DMat3::from_diagonal(DVec3::splat(step)), lo);
    let node = |p: usize| {
        let ijk = DVec3::new((p % n) as f64, ((p / n) % n) as f64, (p / (n * n)) as f64);
        affine.transform_point3(ijk)
    };
    let values: Vec<f32> = (0..n * n * n)
        .into_par_iter()
        .with_min_len(4096)
        .map(|p| {
            let x = node(p);
            if (x - bs.center).length() >= bs.radius {
                return 1.0;
            }
            let v = surface.value(x);
            let s = v as f32;
            if s == 0.0 && v != 0.0 {
                f32::MIN_POSITIVE.copysign(v as f32)
            } else {
                s
            }
        })
        .collect();
    if let Some(p) = values.iter().position(|v| v.is_nan()) {
        return Err(ScanError::Nan(node(p).to_array()));
    }
    if !values.iter().any(|&v| v < 0.0) {
        return Err(ScanError::NoInside);
    }
    let vol = Volume::new([n; 3], Voxels::F32(values), affine).expect("n >= 3, regular affine");
    Ok((vol, step))
}

/// `f` on `n^3` nodes over the cube of `surface`'s bounding sphere (nodes outside the ball
/// count as outside), read as an image at level 0 with the inside where `f < 0`; and the
/// grid step. Its voxel scan ([`ImageSurface::topology`]) gives the components of the
/// trilinear level set.
pub fn grid_image(surface: &dyn Surface, n: usize) -> Result<(ImageSurface, f64), ScanError> {
    if n < 3 {
        return Err(ScanError::TooCoarse(n));
    }
    let (vol, step) = sample(surface, n)?;
    Ok((image(vol).ok_or(ScanError::NoInside)?, step))
}

/// The grid read as an image at level 0, the inside where `f < 0`.
fn image(vol: Volume) -> Option<ImageSurface> {
    let opts = ImageOptions {
        iso: Some(0.0),
        dark_foreground: true,
        ..Default::default()
    };
    ImageSurface::new(vol, &opts).ok()
}

fn figures(img: &ImageSurface) -> (usize, Option<usize>) {
    (img.topology().surface_components, img.scan_genus())
}

/// Scan `surface`'s function on grids of `n` and `2n - 1` nodes per axis.
pub fn scan(surface: &dyn Surface, n: usize) -> Result<GridScan, ScanError> {
    let (coarse, fine) = rayon::join(|| grid_image(surface, n), || grid_image(surface, 2 * n - 1));
    let (fine, step) = fine?;
    let coarse_figures = match coarse {
        Ok((img, _)) => figures(&img),
        Err(ScanError::NoInside) => (0, Some(0)),
        Err(e) => return Err(e),
    };
    let fine_figures = figures(&fine);
    let topo = fine.topology();
    let projected: Vec<Option<DVec3>> = topo
        .component_seeds
        .par_iter()
        .zip(&topo.component_vanishing)
        .filter(|(_, v)| !**v)
        .map(|(p, _)| {
            surface
                .project(*p)
                .filter(|q| (*q - *p).length() <= 2.0 * step)
        })
        .collect();
    let unprojected = projected.iter().filter(|p| p.is_none()).count();
    let surface_points = crate::level_set::LevelSet::new(&fine)
        .edge_crossings()
        .par_iter()
        .filter_map(|p| {
            surface
                .project(*p)
                .filter(|q| q.is_finite() && (*q - *p).length() <= 2.0 * step)
        })
        .collect();
    Ok(GridScan {
        surface_points,
        step,
        coarse_figures,
        fine_figures,
        seeds: projected.into_iter().flatten().collect(),
        unprojected,
        fine,
    })
}

/// The `grid-genus` check (see the module doc); `scan` as [`scan`] gave it.
pub(crate) fn genus_check(
    r: &mut Report,
    mesh: &meshio::TriMesh,
    scan: &Result<GridScan, ScanError>,
    opts: &crate::Options,
) {
    let (status, detail) = match scan {
        Err(e) => (
            Status::Info,
            format!("not measured: the grid scan of f has no figure: {e}"),
        ),
        Ok(s) => {
            let acc = account(mesh, &s.fine, &opts.dropped_points, &opts.sliver_points);
            let acc = match &r.topology {
                Some(t) => acc.with_mesh_genus(t),
                None => acc,
            };
            compare(s, &acc)
        }
    };
    r.push("grid-genus", status, detail);
}

fn show(fig: (usize, Option<usize>)) -> String {
    let comps = match fig.0 {
        1 => "1 component".to_string(),
        n => format!("{n} components"),
    };
    match fig.1 {
        Some(g) => format!("{comps}, total genus {g}"),
        None => format!("{comps}, genus not told apart"),
    }
}

fn compare(s: &GridScan, acc: &ScanComponents) -> (Status, String) {
    let steps = format!("steps {:.3e} and {:.3e}", 2.0 * s.step, s.step);
    if !s.stable() {
        return (
            Status::Info,
            format!(
                "not compared: the grid scans of f at {steps} disagree ({} against {}): S has \
                 necks, gaps or parts near the grid step, which the scan does not resolve",
                show(s.coarse_figures),
                show(s.fine_figures)
            ),
        );
    }
    let found = format!("a grid scan of f at {steps} finds {}", show(s.fine_figures));
    match GenusComparison::of(acc) {
        GenusComparison::ScanUnknown => (
            Status::Info,
            format!(
                "not compared: the grid scan at {steps} found components of zero volume \
                 (f = 0 at nodes), whose genera it does not tell apart"
            ),
        ),
        GenusComparison::MeshUnknown => (Status::Info, NOT_A_MANIFOLD.into()),
        GenusComparison::Equal(mesh) => (Status::Pass, format!("total genus {mesh}; {found}")),
        GenusComparison::FewerExcused { mesh, gone, .. } => (
            Status::Info,
            format!(
                "total genus {mesh}; {found}: not compared, {gone} components dropped or \
                 missed may hold the difference"
            ),
        ),
        GenusComparison::Fewer { mesh, scan } => (
            Status::Fail,
            format!(
                "total genus {mesh}; {found}: {} handles of S are not resolved at this size \
                 (not the topology of S; a smaller --size resolves more)",
                scan - mesh
            ),
        ),
        // Unlike `scan-genus` (where the scan is the image's own level set): a handle
        // thinner than the fine step is below both grids, so more handles are not wrong.
        GenusComparison::More { mesh, scan } => (
            Status::Info,
            format!(
                "total genus {mesh}; {found}: {} more handles in the mesh, not decided (a \
                 handle thinner than {:.3e} is below both grids)",
                mesh - scan,
                s.step
            ),
        ),
    }
}

/// The scan that `opts` asks for (`Options::grid_scan`), `None` for images and without it.
pub(crate) fn run(
    surface: &dyn Surface,
    opts: &crate::Options,
) -> Option<Result<GridScan, ScanError>> {
    let n = opts.grid_scan?;
    if surface.as_image().is_some() {
        return None;
    }
    opts.stage("grid scan");
    Some(scan(surface, n))
}
