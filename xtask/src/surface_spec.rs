//! Turning a command-line surface spec into an oracle: `implicit:NAME`, `implicit:EXPR`,
//! images (.nii, .nii.gz, .tif/.tiff stacks, folders of slices, raw volumes), meshes
//! (.ply .off .obj .stl) and point sets (.xyz, .ply without faces).

use anyhow::{Context, Result, bail};
use clap::ValueEnum;
use glam::DVec3;
use oracle::image::{Dtype, ImageOptions, ImageSurface, LoadOptions, RawOptions};
use oracle::{BoundingSphere, Surface};
use std::path::Path;

#[derive(Clone, Copy, Debug, ValueEnum, PartialEq, Eq)]
pub enum AsKind {
    Mesh,
    Points,
}

/// Options for image, mesh and point-set inputs.
#[derive(clap::Args, Debug, Default, Clone)]
pub struct SurfaceOptions {
    /// Image iso value (default: halfway for binary images; required otherwise).
    #[arg(long, allow_negative_numbers = true)]
    pub iso: Option<f64>,
    /// Image: mesh the boundary of this label.
    #[arg(long)]
    pub label: Option<i64>,
    /// Image: the inside is where the intensity is below the iso value (default: above).
    #[arg(long)]
    pub dark_foreground: bool,
    /// Image stacks and raw volumes: voxel spacing `sx,sy,sz` in world units.
    #[arg(long)]
    pub spacing: Option<String>,
    /// Raw volume: dimensions `nx,ny,nz`.
    #[arg(long)]
    pub dims: Option<String>,
    /// Raw volume: voxel type (u8, i8, u16, i16, u32, i32, f32, f64).
    #[arg(long)]
    pub dtype: Option<String>,
    /// Raw volume: big-endian voxels.
    #[arg(long)]
    pub big_endian: bool,
    /// Read a .ply as a triangle mesh or as a point set (default: by its faces).
    #[arg(long = "as", value_enum)]
    pub as_kind: Option<AsKind>,
    /// Mesh input: mesh a smooth IMLS approximation of the polyhedron (rounds sharp edges by
    /// about one kernel radius) instead of the exact triangles (the default).
    #[arg(long)]
    pub smooth_polyhedron: bool,
}

/// An opened surface with what the command needs to know about it.
#[allow(dead_code)] // genus and components are read by the regression suite
pub struct Opened {
    pub surface: Box<dyn Surface>,
    /// Short name for default output paths.
    pub name: String,
    /// Known or estimated d_M^inf (read it with [`Opened::dm_inf`]).
    pub dm_inf: Option<f64>,
    /// d_M^inf is the surface's `dm_inf_hint()`, computed on first use only (images: the
    /// distance-transform estimate costs about 1 s at 256^3 and `--size` does not need it).
    pub lazy_dm_inf: bool,
    /// A default size when neither --size nor --epsilon is given (otherwise 0.09 d_M^inf).
    pub default_size: Option<f64>,
    /// Catalog genus and component count, if known.
    pub genus: Option<u32>,
    pub components: Option<u32>,
    pub control_points: Option<Vec<DVec3>>,
    /// The mesher's `max_control_points` (64 by default; images: room for a seed tetrahedron
    /// on every small component).
    pub max_control_points: usize,
    pub notes: Vec<String>,
    /// Mesh input: its sharp edges (normals deviating by more than [`SHARP_DEG`]).
    pub sharp_edges: Vec<(DVec3, DVec3)>,
}

impl Opened {
    /// The mesher's default options for this input (images: `max_control_points` with room
    /// for a seed tetrahedron on every small component).
    pub fn mesh_defaults(&self) -> rdt_mesher::MeshOptions {
        rdt_mesher::MeshOptions {
            max_control_points: self.max_control_points,
            ..Default::default()
        }
    }

    /// Known or estimated d_M^inf (computed now if it is lazy).
    pub fn dm_inf(&self) -> Option<f64> {
        if self.lazy_dm_inf {
            self.surface.dm_inf_hint()
        } else {
            self.dm_inf
        }
    }
}

/// Sharp-edge threshold: the two face normals differ by more than this (degrees), i.e. the
/// dihedral angle is below 180° minus it.
pub const SHARP_DEG: f64 = 30.0;

fn triple<T: std::str::FromStr>(s: &str, what: &str) -> Result<[T; 3]> {
    let v: Vec<T> = s
        .split(',')
        .map(|t| {
            t.trim().parse::<T>().map_err(|_| {
                anyhow::anyhow!(
                    "{what}: '{t}' is not valid (expected three comma-separated values, e.g. 1,1,2)"
                )
            })
        })
        .collect::<Result<_>>()?;
    let n = v.len();
    v.try_into()
        .map_err(|_| anyhow::anyhow!("{what}: expected three comma-separated values, got {n}"))
}

/// A catalog surface by name (for benches and suites).
pub fn catalog_surface(name: &str) -> Result<Box<dyn Surface>> {
    Ok(Box::new(oracle::catalog::surface(name)?))
}

pub fn stem(p: &Path) -> String {
    let s = p
        .file_name()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_else(|| "surface".into());
    s.trim_end_matches(".gz")
        .rsplit_once('.')
        .map(|(a, _)| a.to_string())
        .unwrap_or(s)
}

/// Voxel spacing and raw-volume options of an image input.
fn image_load_options(o: &SurfaceOptions) -> Result<LoadOptions> {
    let spacing = o
        .spacing
        .as_deref()
        .map(|s| triple::<f64>(s, "--spacing"))
        .transpose()?;
    let raw = match (&o.dims, &o.dtype) {
        (Some(d), Some(t)) => Some(RawOptions {
            dims: triple::<usize>(d, "--dims")?,
            dtype: t
                .parse::<Dtype>()
                .map_err(|e| anyhow::anyhow!("--dtype {t}: {e}"))?,
            big_endian: o.big_endian,
            offset: 0,
        }),
        (None, None) => None,
        _ => bail!("a raw volume needs both --dims nx,ny,nz and --dtype TYPE"),
    };
    Ok(LoadOptions { spacing, raw })
}

/// Labels present in an image (`--labels all`), without the background label 0.
pub fn image_labels(spec: &str, o: &SurfaceOptions) -> Result<Vec<i64>> {
    let vol = oracle::image::load_volume(Path::new(spec), &image_load_options(o)?)
        .with_context(|| format!("opening image {spec}"))?;
    let labels = vol
        .labels()
        .with_context(|| format!("--labels all: {spec} is not a label image"))?;
    Ok(labels
        .into_iter()
        .map(|(l, _)| l)
        .filter(|&l| l != 0)
        .collect())
}

pub fn open(spec: &str, bounding_sphere: Option<&str>, o: &SurfaceOptions) -> Result<Opened> {
    let bs = match bounding_sphere {
        Some(s) => {
            let v = crate::mesh_cmd::parse_vec3(s, "--bounding-sphere")?;
            if v.len() != 4 {
                bail!(
                    "--bounding-sphere expects cx,cy,cz,r (4 numbers), got {}",
                    v.len()
                );
            }
            Some(BoundingSphere {
                center: DVec3::new(v[0], v[1], v[2]),
                radius: v[3],
            })
        }
        None => None,
    };
    if let Some(rest) = spec.strip_prefix("implicit:") {
        let entry = oracle::catalog::entry(rest.trim());
        if entry.is_none() && bs.is_none() {
            bail!(
                "implicit:\"{rest}\" is not a catalog name ({}); an expression needs --bounding-sphere cx,cy,cz,r",
                oracle::catalog::names().join(", ")
            );
        }
        let s = oracle::catalog::resolve(rest, bs)?;
        let name = entry
            .as_ref()
            .map(|e| e.name.to_string())
            .unwrap_or_else(|| "implicit".into());
        return Ok(Opened {
            dm_inf: s.dm_inf_hint(),
            lazy_dm_inf: false,
            surface: Box::new(s),
            name,
            default_size: None,
            genus: entry.as_ref().and_then(|e| e.genus),
            components: entry.as_ref().and_then(|e| e.components),
            control_points: None,
            max_control_points: rdt_mesher::MeshOptions::default().max_control_points,
            notes: vec![],
            sharp_edges: vec![],
        });
    }
    let path = Path::new(spec);
    if !path.exists() {
        bail!(
            "input '{spec}' is neither implicit:NAME/EXPR nor an existing file (catalog names: {})",
            oracle::catalog::names().join(", ")
        );
    }
    let lower = spec.to_lowercase();
    let is_image = path.is_dir()
        || lower.ends_with(".nii")
        || lower.ends_with(".nii.gz")
        || lower.ends_with(".tif")
        || lower.ends_with(".tiff")
        || lower.ends_with(".raw")
        || o.dims.is_some();
    if is_image {
        let load = image_load_options(o)?;
        let img = ImageSurface::open(
            path,
            &load,
            &ImageOptions {
                iso: o.iso,
                label: o.label,
                dark_foreground: o.dark_foreground,
                background: None,
            },
        )
        .with_context(|| format!("opening image {spec}"))?;
        let comps = img.component_count();
        // Room among the control points for a seed tetrahedron on every small component.
        let img = img.with_seed_budget(None);
        let budget = img.seed_budget();
        let notes = vec![format!(
            "image: {} surface component(s) found by the voxel scan (iso {}); {budget} seed points",
            comps,
            img.iso()
        )];
        return Ok(Opened {
            surface: Box::new(img),
            name: stem(path),
            dm_inf: None,
            lazy_dm_inf: true,
            default_size: None,
            genus: None,
            components: Some(comps as u32),
            control_points: None,
            max_control_points: budget,
            notes,
            sharp_edges: vec![],
        });
    }
    let as_points = match o.as_kind {
        Some(AsKind::Points) => true,
        Some(AsKind::Mesh) => false,
        None => lower.ends_with(".xyz") || (lower.ends_with(".ply") && ply_has_no_faces(path)),
    };
    if as_points {
        let cloud = if lower.ends_with(".xyz") {
            oracle::pointset::read_xyz(path)?
        } else {
            let c = meshio::read_point_cloud(path)?;
            oracle::pointset::PointCloud {
                points: c.points,
                normals: c.normals,
            }
        };
        let had_normals = cloud.normals.is_some();
        let ps = oracle::pointset::PointSetSurface::from_cloud(&cloud, &Default::default())
            .with_context(|| format!("point set {spec}"))?;
        let size = ps.suggested_size();
        return Ok(Opened {
            dm_inf: ps.dm_inf_hint(),
            lazy_dm_inf: false,
            name: stem(path),
            default_size: Some(size),
            genus: None,
            components: None,
            control_points: None,
            max_control_points: rdt_mesher::MeshOptions::default().max_control_points,
            notes: vec![format!(
                "point set: {} points, normals {}; suggested size {size:.5}",
                cloud.points.len(),
                if had_normals {
                    "given"
                } else {
                    "estimated (PCA + propagation)"
                }
            )],
            sharp_edges: vec![],
            surface: Box::new(ps),
        });
    }
    let mesh = meshio::read(path)?;
    let poly = oracle::polyhedron::PolyhedronSurface::new(&mesh)
        .with_context(|| format!("mesh {spec}"))?;
    let size = poly.suggested_size();
    let sharp_edges = poly.sharp_edges(SHARP_DEG);
    let mut notes = vec![format!(
        "polyhedron: {} vertices, {} triangles ({:?}); {} sharp edges (normals > {SHARP_DEG} deg apart); suggested size {size:.5} (bbox diagonal / 50)",
        mesh.vertices.len(),
        mesh.triangles.len(),
        poly.stats(),
        sharp_edges.len(),
    )];
    let surface: Box<dyn Surface> = if !o.smooth_polyhedron {
        notes.push("polyhedron: meshing the exact triangles (--smooth-polyhedron meshes a smooth approximation)".into());
        Box::new(poly)
    } else {
        let n = oracle::polyhedron::DEFAULT_SAMPLES;
        let s = oracle::polyhedron::SmoothPolyhedron::new(poly, n)
            .with_context(|| format!("mesh {spec}: smoothing"))?;
        notes.push(format!(
            "polyhedron: meshing its IMLS approximation from {n} area-uniform samples (kernel radius {:.2e}); verification measures the distance to the input triangles",
            s.imls().stats().median_radius
        ));
        Box::new(s)
    };
    Ok(Opened {
        dm_inf: None,
        lazy_dm_inf: false,
        name: stem(path),
        default_size: Some(size),
        genus: None,
        components: None,
        control_points: None,
        max_control_points: rdt_mesher::MeshOptions::default().max_control_points,
        notes,
        sharp_edges,
        surface,
    })
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
