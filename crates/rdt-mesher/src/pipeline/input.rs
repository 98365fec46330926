//! Opening a surface by spec (ours): catalog names and expressions (`implicit:...`), images
//! (section 6.6.2's voxel oracle), triangle meshes and point sets, with what the pipeline
//! needs to know about each (its d_M^inf, a suggested size, seed points, notes).
//!
//! Invariant: an [`Input`] always holds a surface; its d_M^inf is either fixed at opening or,
//! for images, the surface's own `dm_inf_hint()`, computed on first use only.

use super::error::PipelineError;
use super::forecast::{AreaEstimate, AreaSource};
use glam::DVec3;
use oracle::image::{ImageOptions, ImageSurface, LoadOptions};
use oracle::{BoundingSphere, Surface};
use std::path::Path;

/// Sharp-edge threshold of a mesh input: the two face normals of an edge differ by more than
/// this (degrees), i.e. the dihedral angle is below 180 degrees minus it.
///
/// ```
/// assert_eq!(rdt_mesher::pipeline::SHARP_DEG, 30.0);
/// ```
pub const SHARP_DEG: f64 = 30.0;

/// How to read a `.ply` (which may hold a mesh or a point set).
///
/// ```
/// use rdt_mesher::pipeline::{InputOptions, ReadAs};
/// let o = InputOptions { read_as: Some(ReadAs::Points), ..Default::default() };
/// assert_eq!(o.read_as, Some(ReadAs::Points));
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ReadAs {
    /// A triangle mesh (the polyhedron oracle).
    Mesh,
    /// A point set (the point-set oracle), faces ignored.
    Points,
}

/// Options of [`Input::open`] for the kinds of input that need them.
///
/// ```
/// use rdt_mesher::pipeline::InputOptions;
/// use oracle::image::ImageOptions;
/// // An image meshed at iso value 300 (inside: above it).
/// let o = InputOptions { image: ImageOptions { iso: Some(300.0), ..Default::default() },
///                        ..Default::default() };
/// assert_eq!(o.image.iso, Some(300.0));
/// ```
#[derive(Clone, Debug, Default)]
pub struct InputOptions {
    /// Bounding sphere of an expression (`implicit:"EXPR"`), or another one for a catalog name.
    pub bounding_sphere: Option<BoundingSphere>,
    /// Images: the iso value or label and the side of the foreground.
    pub image: ImageOptions,
    /// Images: voxel spacing of stacks and raw volumes, the layout of a raw volume.
    pub load: LoadOptions,
    /// How to read a `.ply` (default: a point set when it has no faces).
    pub read_as: Option<ReadAs>,
    /// Mesh input: mesh a smooth IMLS approximation of the polyhedron (rounds sharp edges by
    /// about one kernel radius) instead of the exact triangles (the default).
    pub smooth_polyhedron: bool,
}

/// Which backend an [`Input`] uses.
///
/// ```
/// use rdt_mesher::pipeline::{Input, InputKind};
/// let t = Input::open("implicit:torus", &Default::default()).unwrap();
/// assert_eq!(t.kind, InputKind::Implicit);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InputKind {
    /// A catalog surface or an expression.
    Implicit,
    /// A voxel image.
    Image,
    /// A triangle mesh (exact or smoothed).
    Polyhedron,
    /// A point set.
    PointSet,
    /// A surface given by the caller ([`Input::new`], [`Input::borrowed`]).
    Custom,
}

/// What was measured on an input when opening it (the report's `input_stats`).
///
/// ```
/// use rdt_mesher::pipeline::Input;
/// let dir = env!("CARGO_MANIFEST_DIR");
/// let cube = Input::open(&format!("{dir}/../../fixtures/meshes/cube.off"), &Default::default())
///     .unwrap();
/// let p = cube.stats.polyhedron.as_ref().unwrap();
/// assert_eq!((p.vertices, p.triangles, cube.stats.sharp_edges), (8, 12, Some(12)));
/// ```
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct InputStats {
    /// `implicit`, `image`, `polyhedron`, `point-set` or `custom`.
    pub kind: &'static str,
    /// Images.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub image: Option<ImageStats>,
    /// Meshes: what the polyhedron oracle found in the input.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub polyhedron: Option<oracle::polyhedron::PolyhedronStats>,
    /// Meshes: edges whose normals are more than [`SHARP_DEG`] apart.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sharp_edges: Option<usize>,
    /// Point sets.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub points: Option<PointStats>,
}

/// An image input's figures.
#[derive(Clone, Debug, serde::Serialize)]
pub struct ImageStats {
    /// Voxels along x, y, z.
    pub dims: [usize; 3],
    /// Voxel spacing along x, y, z, in world units.
    pub spacing: [f64; 3],
    /// The iso value in scaled units (0.5 for a label's indicator).
    pub iso: f64,
    /// Smallest and largest value (scaled).
    pub range: [f64; 2],
    /// Surface components found by the voxel scan.
    pub components: usize,
    /// Seed points given to the mesher.
    pub seed_points: usize,
    /// The voxel-to-world affine as three rows `[a, b, c, t]` (world = rows x (i, j, k, 1)),
    /// in the image readers' RAS+ world (see `oracle::image`'s format modules).
    pub affine: [[f64; 4]; 3],
}

/// A point-set input's figures.
#[derive(Clone, Debug, serde::Serialize)]
pub struct PointStats {
    /// Points read.
    pub points: usize,
    /// Normals were in the file (else estimated).
    pub normals_given: bool,
}

enum Held<'s> {
    Owned(Box<dyn Surface + 's>),
    Borrowed(&'s dyn Surface),
}

/// Where an input's d_M^inf comes from.
#[derive(Clone, Copy, Debug)]
enum DmInf {
    Known(Option<f64>),
    /// The surface's `dm_inf_hint()`, asked on each use (images compute it once, on first use:
    /// it costs about 1 s at 256^3 and a given size does not need it).
    FromSurface,
}

/// A surface and what the pipeline knows about it: what [`run`](super::run) meshes.
///
/// ```
/// use rdt_mesher::pipeline::Input;
/// let dir = env!("CARGO_MANIFEST_DIR");
/// let cube = Input::open(&format!("{dir}/../../fixtures/meshes/cube.off"), &Default::default())
///     .unwrap();
/// assert_eq!(cube.name, "cube");
/// assert!(cube.default_size.is_some()); // bbox diagonal / 50
/// assert_eq!(cube.sharp_edges.len(), 12);
/// ```
pub struct Input<'s> {
    surface: Held<'s>,
    dm_inf: DmInf,
    /// Short name, for default output paths and messages (catalog name, file stem).
    pub name: String,
    /// The backend.
    pub kind: InputKind,
    /// The size used when none is requested (meshes and point sets; otherwise 0.09 d_M^inf).
    pub default_size: Option<f64>,
    /// Catalog genus, if known.
    pub genus: Option<u32>,
    /// Catalog component count, or the components found by an image's voxel scan.
    pub components: Option<u32>,
    /// Control points E'_i for the mesher (`None`: the surface's seed points).
    pub control_points: Option<Vec<DVec3>>,
    /// The mesher's `max_control_points` (64 by default; images: room for a seed tetrahedron
    /// on every small component).
    pub max_control_points: usize,
    /// What was found when opening (printed by the CLI as `note:` lines).
    pub notes: Vec<String>,
    /// Mesh input: its sharp edges (normals more than [`SHARP_DEG`] apart); on a broken mesh
    /// (open, crossing itself), only their parts on the boundary of the solid that is meshed.
    pub sharp_edges: Vec<(DVec3, DVec3)>,
    /// What was measured when opening.
    pub stats: InputStats,
    /// The surface's area when opening measured it (images, meshes); else the forecast
    /// meshes coarsely.
    pub area: Option<AreaEstimate>,
    /// Images: the voxel spacing (geometric mean over the axes), in world units.
    pub voxel_spacing: Option<f64>,
    /// Images: the smallest voxel spacing (of the three axes), in world units.
    pub voxel_spacing_min: Option<f64>,
    /// Point sets and meshes: the data the output must be supported by (the points; samples
    /// of the input triangles), for `verify`'s `data-support` check.
    pub support_data: Option<Vec<DVec3>>,
    /// Point sets: the oriented (outward) normals of `support_data` (given, or estimated and
    /// oriented), for the orientation agreement of the `data-support` check.
    pub support_normals: Option<Vec<DVec3>>,
    /// A closed, oriented, manifold input mesh: its components and genera, which the output
    /// must match (`verify`'s `input-topology` check) or say why not.
    pub source_topology: Option<super::source_topology::SourceTopology>,
    /// Mesh input meshed as its exact triangles (not `InputOptions::smooth_polyhedron`):
    /// d_M = 0 at every edge that is not flat, so no loose eps-sample of it exists and
    /// [`super::plan`] refuses an `--epsilon` that would estimate d_M from it.
    pub exact_polyhedron: bool,
}

impl std::fmt::Debug for Input<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Input")
            .field("name", &self.name)
            .field("kind", &self.kind)
            .field("dm_inf", &self.dm_inf)
            .field("default_size", &self.default_size)
            .field("genus", &self.genus)
            .field("components", &self.components)
            .field("max_control_points", &self.max_control_points)
            .field("notes", &self.notes)
            .field("sharp_edges", &self.sharp_edges.len())
            .finish_non_exhaustive()
    }
}

impl<'s> Input<'s> {
    fn with(surface: Held<'s>, name: String, kind: InputKind, dm_inf: DmInf) -> Self {
        Input {
            surface,
            dm_inf,
            name,
            kind,
            default_size: None,
            genus: None,
            components: None,
            control_points: None,
            max_control_points: crate::MeshOptions::default().max_control_points,
            notes: Vec::new(),
            sharp_edges: Vec::new(),
            stats: InputStats {
                kind: match kind {
                    InputKind::Implicit => "implicit",
                    InputKind::Image => "image",
                    InputKind::Polyhedron => "polyhedron",
                    InputKind::PointSet => "point-set",
                    InputKind::Custom => "custom",
                },
                ..Default::default()
            },
            area: None,
            voxel_spacing: None,
            voxel_spacing_min: None,
            support_data: None,
            support_normals: None,
            source_topology: None,
            exact_polyhedron: false,
        }
    }

    /// A surface of the caller's (d_M^inf: its `dm_inf_hint()`).
    ///
    /// ```
    /// use rdt_mesher::pipeline::Input;
    /// let s = oracle::catalog::surface("sphere").unwrap();
    /// let input = Input::new(s);
    /// assert_eq!(input.dm_inf(), Some(1.0));
    /// ```
    pub fn new(surface: impl Surface + 's) -> Self {
        Self::with(
            Held::Owned(Box::new(surface)),
            "surface".into(),
            InputKind::Custom,
            DmInf::FromSurface,
        )
    }

    /// A borrowed surface of the caller's (for a `&dyn Surface`).
    ///
    /// ```
    /// use rdt_mesher::pipeline::Input;
    /// use oracle::Surface;
    /// let s = oracle::catalog::surface("torus").unwrap();
    /// let r: &dyn Surface = &s;
    /// assert_eq!(Input::borrowed(r).dm_inf(), Some(0.3));
    /// ```
    pub fn borrowed(surface: &'s dyn Surface) -> Self {
        Self::with(
            Held::Borrowed(surface),
            "surface".into(),
            InputKind::Custom,
            DmInf::FromSurface,
        )
    }

    /// The surface.
    ///
    /// ```
    /// use rdt_mesher::pipeline::Input;
    /// let s = Input::open("implicit:sphere", &Default::default()).unwrap();
    /// assert!(s.surface().value(glam::DVec3::ZERO) < 0.0);
    /// ```
    pub fn surface(&self) -> &dyn Surface {
        match &self.surface {
            Held::Owned(b) => b.as_ref(),
            Held::Borrowed(r) => *r,
        }
    }

    /// Known or estimated d_M^inf (images: the distance-transform estimate, computed now if
    /// it was not yet). `None` for meshes and surfaces that know none.
    ///
    /// ```
    /// use rdt_mesher::pipeline::Input;
    /// let t = Input::open("implicit:torus", &Default::default()).unwrap();
    /// assert_eq!(t.dm_inf(), Some(0.3));
    /// ```
    pub fn dm_inf(&self) -> Option<f64> {
        match self.dm_inf {
            DmInf::Known(d) => d,
            DmInf::FromSurface => self.surface().dm_inf_hint(),
        }
    }
}

impl Input<'static> {
    /// Open a surface by spec, with the CLI's defaults: `implicit:NAME` (catalog),
    /// `implicit:EXPR` (with `opts.bounding_sphere`), an image (`.nii`, `.nii.gz`, `.nrrd`,
    /// `.nhdr`, `.mha`, `.mhd`, `.tif`, `.tiff`, `.raw`, an OME-Zarr folder, a folder of slices,
    /// or any file with `opts.load.raw`), a mesh (`.ply` `.off` `.obj` `.stl` `.glb` `.vtk`
    /// `.vtp` `.gii`) or a point set (`.xyz`, a `.ply` without faces).
    ///
    /// ```
    /// use rdt_mesher::pipeline::{Input, InputKind, InputOptions};
    /// use oracle::image::ImageOptions;
    /// let dir = env!("CARGO_MANIFEST_DIR");
    /// let opts = InputOptions {
    ///     image: ImageOptions { iso: Some(300.0), ..Default::default() },
    ///     ..Default::default()
    /// };
    /// let img = Input::open(&format!("{dir}/../../fixtures/images/phantom_i16_32.nii.gz"), &opts)
    ///     .unwrap();
    /// assert_eq!((img.kind, img.name.as_str()), (InputKind::Image, "phantom_i16_32"));
    /// assert!(img.components.unwrap() >= 1);
    /// ```
    pub fn open(spec: &str, opts: &InputOptions) -> Result<Self, PipelineError> {
        if let Some(rest) = spec.strip_prefix("implicit:") {
            return open_implicit(rest, opts.bounding_sphere);
        }
        let path = Path::new(spec);
        if !path.exists() {
            return Err(PipelineError::NoSuchInput {
                spec: spec.to_string(),
                names: oracle::catalog::names(),
            });
        }
        let lower = spec.to_lowercase();
        if is_image_spec(spec, opts.load.raw.is_some()) {
            return open_image(spec, opts);
        }
        if let Some((what, how)) = oracle::image::unsupported_volume_format(spec) {
            return Err(PipelineError::UnsupportedVolume {
                spec: spec.to_string(),
                what,
                how,
            });
        }
        let as_points = match opts.read_as {
            Some(ReadAs::Points) => true,
            Some(ReadAs::Mesh) => false,
            None => lower.ends_with(".xyz") || (lower.ends_with(".ply") && ply_has_no_faces(path)),
        };
        if as_points {
            open_point_set(spec, lower.ends_with(".xyz"))
        } else {
            open_mesh(spec, opts.smooth_polyhedron)
        }
    }
}

/// Whether [`Input::open`] reads the (existing) file or folder `spec` as an image: a folder (a
/// DICOM series, a slice stack, an OME-Zarr store), an image extension
/// ([`oracle::image::IMAGE_EXTENSIONS`]), a DICOM file of any name, or `raw` (a layout given).
///
/// ```
/// use rdt_mesher::pipeline::is_image_spec;
/// assert!(is_image_spec("brain.nii.gz", false));
/// assert!(!is_image_spec("bunny.ply", false));
/// assert!(is_image_spec("volume.bin", true));
/// ```
pub fn is_image_spec(spec: &str, raw: bool) -> bool {
    let p = Path::new(spec);
    raw || p.is_dir() || oracle::image::is_image_file_name(spec) || oracle::image::is_dicom_file(p)
}

fn open_implicit(rest: &str, bs: Option<BoundingSphere>) -> Result<Input<'static>, PipelineError> {
    let entry = oracle::catalog::entry(rest.trim());
    if entry.is_none() && bs.is_none() {
        return Err(PipelineError::UnknownName {
            name: rest.to_string(),
            names: oracle::catalog::names(),
        });
    }
    let s = oracle::catalog::resolve(rest, bs).map_err(PipelineError::read)?;
    let name = entry
        .as_ref()
        .map(|e| e.name.to_string())
        .unwrap_or_else(|| "implicit".into());
    let dm = s.dm_inf_hint();
    let mut input = Input::with(
        Held::Owned(Box::new(s)),
        name,
        InputKind::Implicit,
        DmInf::Known(dm),
    );
    input.genus = entry.as_ref().and_then(|e| e.genus);
    input.components = entry.as_ref().and_then(|e| e.components);
    Ok(input)
}

fn open_image(spec: &str, opts: &InputOptions) -> Result<Input<'static>, PipelineError> {
    let path = Path::new(spec);
    let img = ImageSurface::open(path, &opts.load, &opts.image)
        .map_err(|e| PipelineError::opening_image(spec, e))?;
    Ok(Input::image(img, stem(path)))
}

impl Input<'static> {
    /// An image surface of the caller's (a volume built in memory, e.g. from a numpy array),
    /// opened exactly as [`Input::open`] opens an image file: the same seeds, statistics,
    /// area estimate and notes, so the same volume meshes to the same mesh either way.
    ///
    /// ```
    /// use rdt_mesher::pipeline::{Input, InputKind};
    /// use oracle::image::{synthetic, ImageOptions, ImageSurface};
    /// use glam::{DAffine3, DVec3};
    /// let vol = synthetic::sample_implicit(|p| p.length() - 5.0, [16, 16, 16],
    ///     DAffine3::from_translation(DVec3::splat(-7.5)));
    /// let opts = ImageOptions { iso: Some(0.0), dark_foreground: true, ..Default::default() };
    /// let input = Input::image(ImageSurface::new(vol, &opts).unwrap(), "ball");
    /// assert_eq!((input.kind, input.components), (InputKind::Image, Some(1)));
    /// ```
    pub fn image(img: ImageSurface, name: impl Into<String>) -> Input<'static> {
        let comps = img.component_count();
        let mut img_notes = img.volume().notes().to_vec();
        img_notes.extend(img.level_note());
        // Room among the control points for a seed tetrahedron on every small component.
        let img = img.with_seed_budget(None);
        let budget = img.seed_budget();
        let vanishing = img.topology().vanishing_components;
        let note = format!(
            "image: {} surface component(s) found by the voxel scan (iso {}{}); {budget} seed points",
            comps,
            img.iso(),
            if vanishing > 0 {
                format!(
                    "; and {vanishing} of zero volume, where voxels equal the iso value inside \
                     the solid: not surfaces, not meshed"
                )
            } else {
                String::new()
            }
        );
        let area = super::forecast::voxel_crossing_area(&img);
        let h = img.volume().spacing();
        let st = img.stats();
        let image_stats = ImageStats {
            dims: img.volume().dims(),
            spacing: h.to_array(),
            iso: img.iso(),
            range: [st.min, st.max],
            components: comps,
            seed_points: budget,
            affine: {
                let a = img.volume().affine();
                let (m, t) = (a.matrix3, a.translation);
                [0, 1, 2].map(|r| [m.x_axis[r], m.y_axis[r], m.z_axis[r], t[r]])
            },
        };
        let mut input = Input::with(
            Held::Owned(Box::new(img)),
            name.into(),
            InputKind::Image,
            DmInf::FromSurface,
        );
        input.components = Some(comps as u32);
        input.max_control_points = budget;
        input.notes.extend(img_notes);
        input.notes.push(note);
        input.stats.image = Some(image_stats);
        input.area = Some(area);
        input.voxel_spacing = Some((h.x * h.y * h.z).cbrt());
        input.voxel_spacing_min = Some(h.x.min(h.y).min(h.z));
        input
    }
}

fn open_point_set(spec: &str, xyz: bool) -> Result<Input<'static>, PipelineError> {
    let path = Path::new(spec);
    let cloud = if xyz {
        oracle::pointset::read_xyz(path).map_err(PipelineError::read)?
    } else {
        let c = meshio::read_point_cloud(path).map_err(PipelineError::read)?;
        oracle::pointset::PointCloud {
            points: c.points,
            normals: c.normals,
        }
    };
    Input::point_cloud(cloud, spec, stem(path))
}

impl Input<'static> {
    /// A point set of the caller's, opened as [`Input::open`] opens a point-set file (`spec`
    /// names it in messages, `name` is the output's default name).
    ///
    /// ```
    /// use rdt_mesher::pipeline::{Input, InputKind};
    /// let pts = (0..400).map(|i| {
    ///     let (t, z) = (i as f64 * 2.4, 1.0 - (2 * i + 1) as f64 / 400.0);
    ///     let r = (1.0 - z * z).sqrt();
    ///     glam::DVec3::new(r * t.cos(), r * t.sin(), z)
    /// }).collect();
    /// let cloud = meshio::PointCloud { points: pts, normals: None };
    /// let input = Input::point_cloud(cloud, "points", "points".into()).unwrap();
    /// assert_eq!(input.kind, InputKind::PointSet);
    /// ```
    pub fn point_cloud(
        cloud: oracle::pointset::PointCloud,
        spec: &str,
        name: String,
    ) -> Result<Input<'static>, PipelineError> {
        let had_normals = cloud.normals.is_some();
        let params = oracle::pointset::PointSetParams::scan();
        let ps = oracle::pointset::PointSetSurface::from_cloud(&cloud, &params)
            .map_err(|e| PipelineError::backend(format!("point set {spec}"), e))?;
        let size = ps.suggested_size();
        let dm = ps.dm_inf_hint();
        let ps_stats = ps.stats().clone();
        let normals = ps.normals().to_vec();
        // The data, as the surface uses it (duplicates merged), beside its normals.
        let support = ps.points().to_vec();
        let mut input = Input::with(
            Held::Owned(Box::new(ps)),
            name,
            InputKind::PointSet,
            DmInf::Known(dm),
        );
        input.default_size = Some(size);
        input.stats.points = Some(PointStats {
            points: cloud.points.len(),
            normals_given: had_normals,
        });
        input.support_data = Some(support);
        input.support_normals = Some(normals);
        let st = ps_stats;
        input.notes.push(format!(
            "point set: {} points{}, normals {}; suggested size {size:.5}; surface trusted within the data's band (median {:.3e} = 2 x spacing {:.3e} + 3 x noise {:.3e}), far-field sign beyond",
            cloud.points.len(),
            match st.duplicates {
                0 => String::new(),
                d => format!(" ({d} equal to an earlier point, merged)"),
            },
            if had_normals {
                "given"
            } else {
                "estimated (PCA + propagation)"
            },
            st.median_band,
            st.median_spacing,
            st.noise,
        ));
        Ok(input)
    }
}

/// Samples of an input mesh's triangles for the `data-support` check (about this many).
const MESH_SUPPORT_SAMPLES: usize = 40_000;

fn open_mesh(spec: &str, smooth: bool) -> Result<Input<'static>, PipelineError> {
    let path = Path::new(spec);
    let mesh = meshio::read(path).map_err(PipelineError::read)?;
    Input::mesh(&mesh, spec, stem(path), smooth)
}

impl Input<'static> {
    /// A triangle mesh of the caller's, opened as [`Input::open`] opens a mesh file (`spec`
    /// names it in messages, `name` is the output's default name; `smooth`: mesh its IMLS
    /// approximation).
    ///
    /// ```
    /// use rdt_mesher::pipeline::{Input, InputKind};
    /// let dir = env!("CARGO_MANIFEST_DIR");
    /// let cube = meshio::read(format!("{dir}/../../fixtures/meshes/cube.off")).unwrap();
    /// let input = Input::mesh(&cube, "cube", "cube".into(), false).unwrap();
    /// assert_eq!((input.kind, input.stats.sharp_edges), (InputKind::Polyhedron, Some(12)));
    /// ```
    pub fn mesh(
        mesh: &meshio::TriMesh,
        spec: &str,
        name: String,
        smooth: bool,
    ) -> Result<Input<'static>, PipelineError> {
        let mut poly = oracle::polyhedron::PolyhedronSurface::new(mesh)
            .map_err(|e| PipelineError::backend(format!("mesh {spec}"), e))?;
        // Self-intersections of the cleaned input, by verify's exact test: a closed mesh that
        // crosses itself is meshed as the solid of its winding number, not by ray parity.
        let welded = poly.welded_mesh();
        let bvh = verify::intersect::triangle_bvh(&welded);
        let pairs = verify::intersect::self_intersections(&welded, &bvh, 0).pairs_total;
        poly.set_self_intersections(pairs);
        let source_topology = (pairs == 0)
            .then(|| super::source_topology::SourceTopology::of(&welded))
            .flatten();
        let size = poly.suggested_size();
        let mut sharp_edges = poly.sharp_edges(SHARP_DEG);
        let sharp_count = sharp_edges.len();
        // The data the output must stay near: samples of the input triangles, on a broken
        // mesh only those on the boundary of the solid {w > 1/2} that is meshed (an interior
        // membrane or the inner sheet of overlapping shells is not part of S: `data-support`
        // FAILed `sphere_membrane.off` at every size, its membrane "not covered").
        let mut support = verify::data_support::mesh_samples(mesh, MESH_SUPPORT_SAMPLES);
        // (A closed mesh crossing itself is not watertight for the oracle either.)
        if !poly.is_watertight() {
            sharp_edges = poly.boundary_parts(&sharp_edges);
            use rayon::prelude::*;
            let kept: Vec<_> = support
                .par_iter()
                .copied()
                .filter(|&p| poly.bounds_solid_at(p))
                .collect();
            if !kept.is_empty() {
                support = kept;
            }
        }
        let pstats = poly.stats().clone();
        let mut notes = vec![format!(
            "polyhedron: {} vertices, {} triangles, {}; {} sharp edges (normals > {SHARP_DEG} deg apart); suggested size {size:.5} (bbox diagonal / 50)",
            mesh.vertices.len(),
            mesh.triangles.len(),
            polyhedron_summary(&pstats),
            sharp_count,
        )];
        let area = AreaEstimate {
            area: super::forecast::triangle_area(mesh),
            source: AreaSource::InputTriangles,
        };
        let surface: Box<dyn Surface> = if !smooth {
            notes.push("polyhedron: meshing the exact triangles (--smooth-polyhedron meshes a smooth approximation)".into());
            Box::new(poly)
        } else {
            let n = oracle::polyhedron::DEFAULT_SAMPLES;
            let s = oracle::polyhedron::SmoothPolyhedron::new(poly, n)
                .map_err(|e| PipelineError::backend(format!("mesh {spec}: smoothing"), e))?;
            notes.push(format!(
            "polyhedron: meshing its IMLS approximation from {n} area-uniform samples (kernel radius {:.2e}); verification measures the distance to the input triangles",
            s.imls().stats().median_radius
        ));
            Box::new(s)
        };
        // A mesh's d_M^inf is not used (0 at its sharp edges): sizes come from its bbox.
        let mut input = Input::with(
            Held::Owned(surface),
            name,
            InputKind::Polyhedron,
            DmInf::Known(None),
        );
        input.default_size = Some(size);
        input.notes = notes;
        input.stats.sharp_edges = Some(sharp_count);
        input.stats.polyhedron = Some(pstats);
        input.sharp_edges = sharp_edges;
        input.area = (area.area > 0.0 && area.area.is_finite()).then_some(area);
        input.support_data = Some(support);
        input.source_topology = source_topology;
        input.exact_polyhedron = !smooth;
        Ok(input)
    }
}

/// `1 component, closed, consistently oriented`, or the defects found, in words.
///
/// ```
/// # use rdt_mesher::pipeline::Input;
/// let dir = env!("CARGO_MANIFEST_DIR");
/// let cube = Input::open(&format!("{dir}/../../fixtures/meshes/cube.off"), &Default::default())
///     .unwrap();
/// assert!(cube.notes[0].contains("12 triangles, 1 component, closed, consistently oriented;"));
/// ```
fn polyhedron_summary(s: &oracle::polyhedron::PolyhedronStats) -> String {
    let mut parts = vec![format!(
        "{} component{}",
        s.components,
        if s.components == 1 { "" } else { "s" }
    )];
    for (n, what) in [
        (s.boundary_edges, "boundary edges (holes)"),
        (s.nonmanifold_edges, "non-manifold edges"),
        (s.nonmanifold_vertices, "non-manifold vertices"),
        (s.misoriented_edges, "misoriented edges"),
        (s.flipped_faces, "faces reoriented"),
        (s.duplicate_faces, "duplicate faces (dropped)"),
        (
            s.self_intersecting_pairs.unwrap_or(0),
            "self-intersecting pairs",
        ),
        (s.duplicate_vertices, "duplicate vertices (welded)"),
        (s.degenerate_triangles, "degenerate triangles (ignored)"),
        (s.unreferenced_vertices, "unreferenced vertices"),
    ] {
        if n > 0 {
            parts.push(format!("{n} {what}"));
        }
    }
    if s.boundary_edges == 0 && s.nonmanifold_edges == 0 {
        parts.push("closed".into());
    }
    if s.misoriented_edges == 0 {
        parts.push("consistently oriented".into());
    }
    if s.inside_out {
        parts.push("inside out (negative signed volume: read with every face reversed)".into());
    }
    if !s.is_clean() {
        parts.push("meshing the solid {winding number > 1/2}".into());
    }
    parts.join(", ")
}

/// The file stem of a path without `.gz` and one extension (`brain.nii.gz` -> `brain`), or
/// `surface`: the default output name of an input.
///
/// ```
/// use std::path::Path;
/// assert_eq!(rdt_mesher::pipeline::stem(Path::new("a/brain.nii.gz")), "brain");
/// assert_eq!(rdt_mesher::pipeline::stem(Path::new("bunny.ply")), "bunny");
/// assert_eq!(rdt_mesher::pipeline::stem(Path::new("cells.ome.zarr")), "cells");
/// ```
pub fn stem(p: &Path) -> String {
    let s = p
        .file_name()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_else(|| "surface".into());
    if let Some(z) = s.strip_suffix(".zarr") {
        return z.trim_end_matches(".ome").to_string();
    }
    s.trim_end_matches(".gz")
        .rsplit_once('.')
        .map(|(a, _)| a.to_string())
        .unwrap_or(s)
}

fn ply_has_no_faces(path: &Path) -> bool {
    // Read the header only.
    let Ok(f) = std::fs::File::open(path) else {
        return false;
    };
    use std::io::{BufRead, BufReader};
    let mut faces = None;
    for line in BufReader::new(f).split(b'\n').take(200) {
        let Ok(line) = line else { break };
        let l = String::from_utf8_lossy(&line);
        let l = l.trim();
        if let Some(rest) = l.strip_prefix("element face") {
            faces = rest.trim().parse::<u64>().ok();
        }
        if l == "end_header" {
            break;
        }
    }
    faces.unwrap_or(0) == 0
}
