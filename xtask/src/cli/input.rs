//! The input flags of `mesh` and `verify` (ours): parsed into `rdt_mesher::pipeline`'s
//! `InputOptions`, and the library's errors said with the flags' names.

use anyhow::{Context, Result, bail};
use clap::ValueEnum;
use glam::DVec3;
use oracle::BoundingSphere;
use oracle::image::{Dtype, ImageOptions, LoadOptions, RawOptions};
use rdt_mesher::pipeline::{self, Input, InputOptions, PipelineError, ReadAs};
use std::path::Path;

#[derive(Clone, Copy, Debug, ValueEnum, PartialEq, Eq)]
pub enum AsKind {
    Mesh,
    Points,
}

/// Options for image, mesh and point-set inputs.
#[derive(clap::Args, Debug, Default, Clone)]
pub struct SurfaceOptions {
    /// Image iso value (default for binary images: halfway, or 19/36 of the way to the
    /// foreground where halfway pinches the level set; required otherwise).
    #[arg(long, allow_negative_numbers = true)]
    pub iso: Option<f64>,
    /// Image: mesh the boundary of this label (its indicator's level set: no --iso).
    #[arg(long, allow_hyphen_values = true, conflicts_with = "iso")]
    pub label: Option<i64>,
    /// Image: the inside is where the intensity is below the iso value (default: above).
    #[arg(long)]
    pub dark_foreground: bool,
    /// Image stacks and raw volumes: voxel spacing `sx,sy,sz` in world units.
    #[arg(long, allow_hyphen_values = true, value_parser = parse_spacing)]
    pub spacing: Option<[f64; 3]>,
    /// Image: the 3D volume of a series (fMRI, diffusion, echoes) to mesh, from 0: NIfTI and
    /// MGH series, DICOM series with several volumes at the same slice positions.
    #[arg(long)]
    pub frame: Option<usize>,
    /// Image: mesh NaN voxels (no value: resampled or masked float images) as this value,
    /// e.g. 0 (default: a NaN voxel is an error).
    #[arg(long, allow_negative_numbers = true, value_parser = parse_nan_as)]
    pub nan_as: Option<f64>,
    /// DICOM folder holding several series: the one to mesh, by its SeriesNumber or
    /// SeriesInstanceUID (the error of such a folder lists them).
    #[arg(long)]
    pub series: Option<String>,
    /// Raw volume: dimensions `nx,ny,nz`.
    #[arg(long, allow_hyphen_values = true, value_parser = parse_dims)]
    pub dims: Option<[usize; 3]>,
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

/// Comma-separated numbers (`--bounding-sphere`).
pub fn parse_vec3(s: &str, what: &str) -> Result<Vec<f64>> {
    s.split(',')
        .map(|t| {
            t.trim().parse::<f64>().with_context(|| {
                format!("{what}: '{t}' is not a number (expected comma-separated numbers)")
            })
        })
        .collect()
}

/// Three comma-separated values of `T` each accepted by `ok`, or None.
fn triple<T: std::str::FromStr>(s: &str, ok: impl Fn(&T) -> bool) -> Option<[T; 3]> {
    let v: Vec<T> = s
        .split(',')
        .map(|t| t.trim().parse::<T>().ok().filter(&ok))
        .collect::<Option<_>>()?;
    v.try_into().ok()
}

/// `--spacing sx,sy,sz`: three positive finite voxel sizes within the image reader's limits
/// (so the affine built from them is usable).
pub fn parse_spacing(s: &str) -> Result<[f64; 3], String> {
    let (lo, hi) = (1e-12, 1e12);
    triple::<f64>(s, |v| (lo..=hi).contains(v)).ok_or_else(|| {
        format!(
            "--spacing {s}: spacing must be three positive finite numbers (each in \
             [{lo:e}, {hi:e}]), e.g. --spacing 1,1,1"
        )
    })
}

/// `--nan-as VALUE`: a finite number.
pub fn parse_nan_as(s: &str) -> Result<f64, String> {
    s.trim()
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| {
            format!(
                "--nan-as {s}: the value for NaN voxels must be a finite number, e.g. --nan-as 0"
            )
        })
}

/// `--dims nx,ny,nz`: three positive whole numbers.
pub fn parse_dims(s: &str) -> Result<[usize; 3], String> {
    triple::<usize>(s, |v| *v > 0).ok_or_else(|| {
        format!("--dims {s}: dims must be three positive whole numbers, e.g. --dims 64,64,32")
    })
}

/// Voxel spacing and raw-volume options of an image input.
pub fn image_load_options(o: &SurfaceOptions) -> Result<LoadOptions> {
    let spacing = o.spacing;
    let raw = match (&o.dims, &o.dtype) {
        (Some(d), Some(t)) => Some(RawOptions {
            dims: *d,
            dtype: t
                .parse::<Dtype>()
                .map_err(|e| anyhow::anyhow!("--dtype {t}: {e}"))?,
            big_endian: o.big_endian,
            offset: 0,
        }),
        (None, None) => None,
        _ => bail!("a raw volume needs both --dims nx,ny,nz and --dtype TYPE"),
    };
    Ok(LoadOptions {
        spacing,
        raw,
        frame: o.frame,
        nan_as: o.nan_as,
        series: o.series.clone(),
    })
}

fn bounding_sphere(s: Option<&str>) -> Result<Option<BoundingSphere>> {
    let Some(s) = s else { return Ok(None) };
    let v = parse_vec3(s, "--bounding-sphere")?;
    if v.len() != 4 {
        bail!(
            "--bounding-sphere expects cx,cy,cz,r (4 numbers), got {}",
            v.len()
        );
    }
    Ok(Some(BoundingSphere {
        center: DVec3::new(v[0], v[1], v[2]),
        radius: v[3],
    }))
}

/// The library's input options from the flags. The image flags are read (and their errors
/// reported) only for an input that is an image, as before.
fn input_options(spec: &str, bs: Option<&str>, o: &SurfaceOptions) -> Result<InputOptions> {
    let bounding_sphere = bounding_sphere(bs)?;
    let image_input = !spec.starts_with("implicit:")
        && Path::new(spec).exists()
        && pipeline::is_image_spec(spec, o.dims.is_some());
    let load = if image_input {
        image_load_options(o)?
    } else {
        LoadOptions::default()
    };
    Ok(InputOptions {
        bounding_sphere,
        image: ImageOptions {
            iso: o.iso,
            label: o.label,
            dark_foreground: o.dark_foreground,
            background: None,
        },
        load,
        read_as: o.as_kind.map(|k| match k {
            AsKind::Mesh => ReadAs::Mesh,
            AsKind::Points => ReadAs::Points,
        }),
        smooth_polyhedron: o.smooth_polyhedron,
    })
}

/// Open `spec` with the library's defaults; errors name the flags.
pub fn open(spec: &str, bs: Option<&str>, o: &SurfaceOptions) -> Result<Input<'static>> {
    let opts = input_options(spec, bs, o)?;
    Input::open(spec, &opts).map_err(|e| cli_error(e, spec))
}

/// Labels present in an image (`--labels all`), without the background label 0.
pub fn label_image(spec: &str, o: &SurfaceOptions) -> Result<pipeline::LabelImage> {
    pipeline::LabelImage::open(spec, &image_load_options(o)?).map_err(|e| cli_error(e, spec))
}

/// The input of label `o.label` of `li` (read from `spec`), as [`open`] gives it.
pub fn label_input(
    li: &pipeline::LabelImage,
    spec: &str,
    bs: Option<&str>,
    o: &SurfaceOptions,
) -> Result<Input<'static>> {
    let opts = input_options(spec, bs, o)?;
    li.input(&opts.image).map_err(|e| cli_error(e, spec))
}

/// A pipeline error in the CLI's words (flag names instead of library names); `spec` is the
/// input as given on the command line.
pub fn cli_error(e: PipelineError, spec: &str) -> anyhow::Error {
    match e {
        PipelineError::Mesh {
            source: rdt_mesher::MeshError::NoSeeds { center, radius },
            ..
        } => anyhow::anyhow!(
            "{spec}: the mesh is empty (no point of the surface inside the bounding sphere, \
             center ({:.4}, {:.4}, {:.4}), radius {radius:.4}); nothing written. An open or \
             flat input mesh may bound no solid (winding number > 1/2 nowhere): close it, or \
             mesh its vertices with --as points; for other inputs check --iso / --label or \
             --bounding-sphere",
            center.x,
            center.y,
            center.z
        ),
        PipelineError::UnknownName { name, names } => anyhow::anyhow!(
            "implicit:\"{name}\" is not a catalog name ({}); an expression needs --bounding-sphere cx,cy,cz,r",
            names.join(", ")
        ),
        PipelineError::NotALabelImage { spec, source } => {
            anyhow::Error::new(source).context(format!("--labels all: {spec} is not a label image"))
        }
        PipelineError::InvalidSize(s) => anyhow::anyhow!(
            "--size {s}: the size bound must be a positive number, e.g. --size 0.05"
        ),
        PipelineError::InvalidEpsilon(e) => {
            anyhow::anyhow!("--epsilon {e}: epsilon must be in (0, 1), e.g. --epsilon 0.09")
        }
        PipelineError::InvalidDmInf(d) => {
            anyhow::anyhow!("--dm-inf {d}: must be a positive number")
        }
        PipelineError::NoDmInf { .. } => anyhow::anyhow!(
            "--epsilon needs d_M^inf, which {spec} does not provide: pass --dm-inf VALUE \
             (`cargo xtask paper-table` prints estimates) or use --size"
        ),
        PipelineError::EpsilonOnTriangles { sharp_edges, .. } => anyhow::anyhow!(
            "{spec}: --epsilon without --dm-inf on the exact triangles of a mesh: d_M = 0 at \
             every edge that is not flat ({sharp_edges} edges with normals more than 30 deg \
             apart), so no eps-sample of them exists; add --smooth-polyhedron to mesh its \
             smooth approximation to --epsilon, or give --size"
        ),
        PipelineError::OverBudget {
            forecast,
            budget,
            fits,
            dm_inf,
            ..
        } => over_budget(&forecast, budget, fits, dm_inf),
        PipelineError::Mesh {
            two_pass, source, ..
        } => anyhow::Error::new(source).context(format!(
            "meshing {spec}{}",
            if two_pass { " (two passes)" } else { "" }
        )),
        e => anyhow::Error::new(e),
    }
}

/// A size refused before meshing, in flags: the forecast, the size that fits, and the budgets
/// that would let the size run.
fn over_budget(
    f: &pipeline::Forecast,
    budget: pipeline::Budget,
    fits: f64,
    dm_inf: Option<f64>,
) -> anyhow::Error {
    let raise_v = round_up_2(f.vertices as f64 * 1.25) as u64;
    let raise_m = (f.memory_bytes as f64 * 1.25 / (1u64 << 30) as f64)
        .ceil()
        .max(1.0);
    let (asked, fitting) = match dm_inf {
        None => (format!("--size {}", f.sigma), format!("--size {fits}")),
        Some(dm) => (
            format!(
                "--epsilon {} (first pass at sigma_0 = epsilon * d_M^inf {dm})",
                f.sigma / dm
            ),
            format!("--epsilon {}", pipeline::round_up_3(fits / dm)),
        ),
    };
    anyhow::anyhow!(
        "{asked}: refused before meshing: the forecast is {f}, over {budget}; {fitting} fits. \
         To mesh at this size anyway, raise the budgets: --max-vertices {raise_v} \
         --max-memory {raise_m}G"
    )
}

/// `x` rounded up to two significant digits.
fn round_up_2(x: f64) -> f64 {
    if !(x > 0.0 && x.is_finite()) {
        return x;
    }
    let e = 10f64.powi(x.log10().floor() as i32 - 1);
    (x / e).ceil() * e
}
