//! A DICOM series' planes stacked into one volume (ours: the voxel grid of section 6.6.2's
//! images; DICOM PS3.3 C.7.6.2.1.1, the patient frame of `ImagePositionPatient`).
//!
//! Invariants kept: the planes of the volume share one series, one size, one orientation and
//! one pixel spacing; sorted along the normal `row_dir x col_dir`, they are evenly spaced on a
//! line (within 1% of the step), so the voxel-to-world affine places every voxel where its
//! file says, to that tolerance. Nothing is resampled: a sheared stack (gantry tilt) keeps its
//! shear in the affine.

use super::super::orient::{Frame, affine, field};
use super::super::{ImageError, Volume, Voxels};
use super::object::Plane;
use glam::DVec3;
use std::path::Path;

const FORMAT: &str = "DICOM";

/// Relative tolerance on the slice step, orientation and pixel spacing (DICOM's decimal
/// strings carry at most 16 characters, so equal geometry can differ in the last digits).
const TOLERANCE: f64 = 0.01;

/// Stack `planes` (read from `source`, a folder or a multi-frame file) into a volume, in
/// RAS+ world coordinates (LPS with x and y negated, as nibabel and dcm2niix do).
/// `frame` picks one of several volumes at the same positions ([`super::volumes::select`]).
pub(crate) fn stack(
    source: &Path,
    planes: Vec<Plane>,
    skipped: usize,
    frame: Option<usize>,
) -> Result<Volume, ImageError> {
    let err = |detail: String| ImageError::Dicom {
        path: source.to_path_buf(),
        detail,
    };
    for p in &planes[1..] {
        same_grid(&planes[0], p)?;
    }
    let (mut planes, which) = super::volumes::select(source, planes, frame)?;
    let first = &planes[0];
    if planes.len() == 1 {
        let folder = first.file.parent().unwrap_or(Path::new("."));
        return Err(err(format!(
            "one slice ({} x {} pixels): a 2D image, not a volume; pass the folder that holds \
             all the files of the series (`mesh {}`)",
            first.cols,
            first.rows,
            folder.display()
        )));
    }
    let normal = first.row_dir.cross(first.col_dir);
    let depth = |p: &Plane| normal.dot(p.position);
    planes.sort_by(|a, b| depth(a).total_cmp(&depth(b)));
    let n = planes.len();
    let step = even_step(source, &planes, normal)?;
    let origin = planes[0].position;
    let voxels = concat(&planes);
    let scaled = voxels.is_none();
    let voxels = match voxels {
        Some(v) => v,
        None => scaled_f32(&planes),
    };
    let p0 = &planes[0];
    let axes = [p0.row_dir * p0.spacing[1], p0.col_dir * p0.spacing[0], step];
    let dims = [p0.cols, p0.rows, n];
    let mut vol = Volume::new(dims, voxels, affine(axes, origin, Frame::Lps))
        .map_err(|e| err(format!("the series' geometry is unusable: {e}")))?;
    if !scaled {
        vol = vol.with_scaling(p0.slope, p0.inter);
    }
    vol = vol.with_source(source).with_note(format!(
        "DICOM: {n} slices of {} x {} pixels, series {}, {:.4} x {:.4} x {:.4} mm{}",
        p0.cols,
        p0.rows,
        if p0.series_label.is_empty() {
            "(unnamed)"
        } else {
            &p0.series_label
        },
        p0.spacing[1],
        p0.spacing[0],
        step.length(),
        if skipped > 0 {
            format!("; {skipped} other file(s) in the folder skipped (not DICOM images)")
        } else {
            String::new()
        }
    ));
    let tilt = step
        .normalize()
        .dot(normal)
        .abs()
        .clamp(0.0, 1.0)
        .acos()
        .to_degrees();
    if tilt > 0.05 {
        vol = vol.with_note(format!(
            "DICOM: the slices are sheared ({tilt:.2} degrees between the slice step and the \
             slice normal: a gantry tilt); the voxels are placed where the files say, not \
             resampled"
        ));
    }
    if let Some(which) = which {
        vol = vol.with_note(which);
    }
    if planes.iter().any(|p| p.lossy) {
        vol = vol.with_note(
            "DICOM: the pixel data is lossy-compressed (JPEG baseline or extended, JPEG 2000): \
             the values are the decoder's approximation of the scanner's"
                .to_string(),
        );
    }
    if scaled {
        vol = vol.with_note(
            "DICOM: the slices have different voxel types or rescale slopes/intercepts; their \
             values were scaled to float32"
                .to_string(),
        );
    }
    Ok(vol)
}

/// The step between `planes` (sorted along `normal`): their positions evenly spaced on a line
/// (within [`TOLERANCE`] of the step), else an error naming the gap (missing slices) or the
/// slice off the line.
fn even_step(source: &Path, planes: &[Plane], normal: DVec3) -> Result<DVec3, ImageError> {
    let err = |detail: String| ImageError::Dicom {
        path: source.to_path_buf(),
        detail,
    };
    let n = planes.len();
    let depth = |p: &Plane| normal.dot(p.position);
    let d: Vec<f64> = planes.iter().map(depth).collect();
    let mut steps: Vec<f64> = d.windows(2).map(|w| w[1] - w[0]).collect();
    let span = d[n - 1] - d[0];
    let mean = span / (n - 1) as f64;
    // `volumes::select` left one plane per position: every step is positive.
    debug_assert!(steps.iter().all(|&s| s > 0.0));
    let (k, worst) = steps
        .iter()
        .enumerate()
        .map(|(k, &s)| (k, s))
        .max_by(|a, b| (a.1 - mean).abs().total_cmp(&(b.1 - mean).abs()))
        .unwrap_or((0, mean));
    steps.sort_by(f64::total_cmp);
    let median = steps[steps.len() / 2];
    if (worst - mean).abs() > TOLERANCE * mean {
        let why = if worst > 1.5 * median {
            format!(
                "about {:.0} missing slice(s) there",
                (worst / median).round() - 1.0
            )
        } else {
            "uneven slice spacing".to_string()
        };
        return Err(err(format!(
            "the slices are not evenly spaced: {} and {} are {worst:.4} mm apart, the median \
             step is {median:.4} mm ({why}); re-export the complete series, or convert it with \
             dcm2niix (which can resample uneven stacks)",
            planes[k].name(),
            planes[k + 1].name()
        )));
    }
    let step = (planes[n - 1].position - planes[0].position) / (n - 1) as f64;
    let origin = planes[0].position;
    let off_line = planes
        .iter()
        .enumerate()
        .map(|(k, p)| (p.position - (origin + step * k as f64)).length())
        .fold(0.0, f64::max);
    if off_line > TOLERANCE * step.length() {
        return Err(err(format!(
            "the slice positions (ImagePositionPatient) do not lie on one line: one is {off_line:.4} \
             mm off it, for a step of {:.4} mm; convert the series with dcm2niix",
            step.length()
        )));
    }
    Ok(step)
}

/// The planes of the series `wanted` (a `SeriesNumber` or a `SeriesInstanceUID`), or all of
/// them when they are one series; otherwise an error listing the series with `--series`.
pub(crate) fn pick(
    source: &Path,
    planes: Vec<Plane>,
    wanted: Option<&str>,
) -> Result<Vec<Plane>, ImageError> {
    let mut series: Vec<(&Plane, usize)> = Vec::new();
    for p in &planes {
        match series.iter_mut().find(|s| s.0.series == p.series) {
            Some(s) => s.1 += 1,
            None => series.push((p, 1)),
        }
    }
    // A series is named by its number when no other series here has that number.
    let key = |p: &Plane| match &p.series_number {
        Some(n)
            if series
                .iter()
                .filter(|s| s.0.series_number.as_ref() == Some(n))
                .count()
                == 1 =>
        {
            n.clone()
        }
        _ => p.series.clone(),
    };
    let list = || {
        series
            .iter()
            .map(|(p, count)| {
                let label = if p.series_label.is_empty() {
                    &p.series
                } else {
                    &p.series_label
                };
                format!("--series {}: {label}, {count} image(s)", key(p))
            })
            .collect::<Vec<_>>()
            .join("; ")
    };
    let err = |detail: String| ImageError::Dicom {
        path: source.to_path_buf(),
        detail,
    };
    match wanted {
        None if series.len() < 2 => Ok(planes),
        None => Err(err(format!(
            "{} series in one folder ({}); pick one with --series",
            series.len(),
            list()
        ))),
        Some(w) => {
            let w = w.trim();
            let hits: Vec<&str> = series
                .iter()
                .filter(|(p, _)| p.series == w || p.series_number.as_deref() == Some(w))
                .map(|(p, _)| p.series.as_str())
                .collect();
            match hits.as_slice() {
                [uid] => {
                    let uid = uid.to_string();
                    Ok(planes.into_iter().filter(|p| p.series == uid).collect())
                }
                [] => Err(err(format!(
                    "--series {w}: no series of that number or UID here ({})",
                    list()
                ))),
                _ => Err(err(format!(
                    "--series {w}: {} series have that number ({}); give the SeriesInstanceUID",
                    hits.len(),
                    list()
                ))),
            }
        }
    }
}

/// Errors unless `p` has the size, orientation and spacing of `first`.
fn same_grid(first: &Plane, p: &Plane) -> Result<(), ImageError> {
    let fail = |what: &str, a: String, b: String| {
        Err(field(
            &p.file,
            FORMAT,
            what,
            format!(
                "= {b}, but {} has {a}: the slices of one volume must share it (a localizer \
                 or a reformat in the series?); keep only the slices of one volume in the folder",
                first.name()
            ),
        ))
    };
    if (p.rows, p.cols) != (first.rows, first.cols) {
        return fail(
            "Rows/Columns",
            format!("{} x {}", first.rows, first.cols),
            format!("{} x {}", p.rows, p.cols),
        );
    }
    let close = |a: DVec3, b: DVec3| (a - b).abs().max_element() <= 1e-4;
    if !(close(p.row_dir, first.row_dir) && close(p.col_dir, first.col_dir)) {
        return fail(
            "ImageOrientationPatient (0020,0037)",
            format!("{:?} {:?}", first.row_dir, first.col_dir),
            format!("{:?} {:?}", p.row_dir, p.col_dir),
        );
    }
    let rel = |a: f64, b: f64| (a - b).abs() <= 1e-4 * a.abs().max(b.abs());
    if !(rel(p.spacing[0], first.spacing[0]) && rel(p.spacing[1], first.spacing[1])) {
        return fail(
            "PixelSpacing (0028,0030)",
            format!("{:?}", first.spacing),
            format!("{:?}", p.spacing),
        );
    }
    Ok(())
}

/// The planes' pixels one after the other in their native type, when every plane has the same
/// type and scaling; `None` otherwise.
fn concat(planes: &[Plane]) -> Option<Voxels> {
    let p0 = &planes[0];
    let same = planes.iter().all(|p| {
        p.pixels.dtype() == p0.pixels.dtype() && p.slope == p0.slope && p.inter == p0.inter
    });
    if !same {
        return None;
    }
    macro_rules! join {
        ($variant:ident) => {{
            let mut out = Vec::with_capacity(p0.pixels.len() * planes.len());
            for p in planes {
                if let Voxels::$variant(d) = &p.pixels {
                    out.extend_from_slice(d);
                }
            }
            Voxels::$variant(out)
        }};
    }
    let v = match p0.pixels {
        Voxels::U8(_) => join!(U8),
        Voxels::I8(_) => join!(I8),
        Voxels::U16(_) => join!(U16),
        Voxels::I16(_) => join!(I16),
        Voxels::U32(_) => join!(U32),
        Voxels::I32(_) => join!(I32),
        Voxels::F32(_) => join!(F32),
        Voxels::F64(_) => join!(F64),
        Voxels::Shared(_) => return None,
    };
    (v.len() == p0.pixels.len() * planes.len()).then_some(v)
}

/// Every plane's values scaled by its own slope and intercept, as float32.
fn scaled_f32(planes: &[Plane]) -> Voxels {
    let mut out = Vec::with_capacity(planes[0].pixels.len() * planes.len());
    for p in planes {
        out.extend((0..p.pixels.len()).map(|i| (p.slope * p.pixels.get_f64(i) + p.inter) as f32));
    }
    Voxels::F32(out)
}
