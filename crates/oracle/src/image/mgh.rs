//! FreeSurfer MGH volumes (ours: file format support; section 6.6.2 meshes them): `.mgh`, or
//! `.mgz` (the same gzipped), as nibabel's `MGHImage` reads them.
//!
//! Layout (big-endian, 284 header bytes, then the voxels x fastest, frame after frame, then
//! optional tags, ignored): `version` (1), `width`, `height`, `depth`, `nframes`, `type`
//! (0 u8, 1 i32, 3 f32, 4 i16), `dof`, `goodRASFlag` (i16), `delta` (3 f32, the voxel sizes),
//! `Mdc` (9 f32: the x, y, z axis directions, one after the other), `Pxyz_c` (3 f32, the
//! world position of the volume's centre). World coordinates: FreeSurfer's scanner RAS, the
//! NIfTI reader's frame. With `goodRASFlag` set, the affine is nibabel's: `M = Mdc^T diag(delta)`
//! (a float32 product, as nibabel rounds it) and translation `Pxyz_c - M (width, height,
//! depth) / 2` (rounded to float32, as nibabel's affine array is); without it, nibabel's default
//! (unit voxels, axes (-1, 0, 0), (0, 0, 1), (0, -1, 0): coronal, centre at 0).

use super::orient::{self, Frame};
use super::{Dtype, ImageError, Volume, Voxels};
use glam::{DAffine3, DMat3, DVec3};
use std::path::Path;

const FMT: &str = "MGH";
/// Bytes before the voxels.
const HEADER: usize = 284;

fn err(path: &Path, field: &str, detail: impl Into<String>) -> ImageError {
    orient::field(path, FMT, field, detail)
}

/// Read frame `frame` (`None`: a single-frame file) of a `.mgh` or `.mgz` volume. Strict: a
/// gzip stream is read to its end, the version must be 1, the type one of the four, the
/// dimensions positive, the voxel sizes (with `goodRASFlag`) finite and non-zero, and the file
/// must hold every frame's voxels (a shorter one is truncated).
pub fn read_mgh(path: impl AsRef<Path>, frame: Option<usize>) -> Result<Volume, ImageError> {
    let path = path.as_ref();
    let raw = orient::read(path)?;
    let gz = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("mgz") || e.eq_ignore_ascii_case("gz"));
    let b = if gz {
        super::nifti_io::gunzip(path, &raw)?
    } else {
        raw
    };
    if b.len() < HEADER {
        return Err(ImageError::Truncated {
            path: path.to_path_buf(),
            detail: format!("an MGH header has {HEADER} bytes, the file has {}", b.len()),
        });
    }
    let i32_at = |at: usize| i32::from_be_bytes(b[at..at + 4].try_into().expect("4 bytes"));
    if i32_at(0) != 1 {
        return Err(err(
            path,
            "version",
            format!(
                "= {} (bytes 0-3): an MGH file has version 1; the file is damaged or not MGH",
                i32_at(0)
            ),
        ));
    }
    let d = [i32_at(4), i32_at(8), i32_at(12), i32_at(16)];
    if let Some(i) = d.iter().position(|&v| v < 1) {
        let name = ["width", "height", "depth", "nframes"][i];
        return Err(err(
            path,
            name,
            format!("= {}: every dimension must be at least 1", d[i]),
        ));
    }
    let dims = [d[0] as usize, d[1] as usize, d[2] as usize];
    let frames = d[3] as usize;
    let series = |detail: String| ImageError::Frame {
        path: path.to_path_buf(),
        dims: d.iter().map(|&v| v as u64).collect(),
        detail,
    };
    match frame {
        None if frames > 1 => {
            return Err(series(format!(
                "a series of {frames} 3D volumes (nframes = {frames}); pass --frame K (0 to {}) \
                 to mesh one of them",
                frames - 1
            )));
        }
        Some(k) if k >= frames => {
            return Err(series(format!(
                "--frame {k}: the file has {frames} frame(s) (nframes = {frames}), numbered 0 \
                 to {}",
                frames - 1
            )));
        }
        _ => {}
    }
    let dtype = match i32_at(20) {
        0 => Dtype::U8,
        1 => Dtype::I32,
        3 => Dtype::F32,
        4 => Dtype::I16,
        t => {
            return Err(err(
                path,
                "type",
                format!("= {t}: the voxel type must be 0 (u8), 1 (i32), 3 (f32) or 4 (i16)"),
            ));
        }
    };
    let one = orient::byte_count(path, FMT, "width/height/depth", &dims, dtype.size())?;
    let need = one.saturating_mul(frames);
    if b.len() - HEADER < need {
        return Err(ImageError::Truncated {
            path: path.to_path_buf(),
            detail: format!(
                "the voxel data after byte {HEADER} has {} bytes, {frames} frame(s) of {} {dtype} \
                 voxels need {need}",
                b.len() - HEADER,
                dims[0] * dims[1] * dims[2]
            ),
        });
    }
    let affine = geometry(path, &b, dims)?;
    super::volume::check_affine(&affine, Some(path), "delta / Mdc / Pxyz_c")?;
    let k = frame.unwrap_or(0);
    let start = HEADER + k * one;
    let voxels = Voxels::from_bytes(dtype, &b[start..start + one], true);
    let mut vol = Volume::new(dims, voxels, affine)?.with_source(path);
    if frames > 1 {
        vol = vol.with_note(format!(
            "{}: frame {k} of {frames} (nframes = {frames}; --frame)",
            path.display()
        ));
    }
    Ok(vol)
}

/// The voxel-to-world affine of the header `b` (see the module docs), `delta` checked.
fn geometry(path: &Path, b: &[u8], dims: [usize; 3]) -> Result<DAffine3, ImageError> {
    let f32_at = |at: usize| f32::from_be_bytes(b[at..at + 4].try_into().expect("4 bytes")) as f64;
    let (m, centre) = if i16::from_be_bytes([b[28], b[29]]) != 0 {
        let delta = DVec3::new(f32_at(30), f32_at(34), f32_at(38));
        if let Some(i) = (0..3).find(|&i| !(delta[i].is_finite() && delta[i] != 0.0)) {
            return Err(err(
                path,
                "delta",
                format!(
                    "[{i}] = {}: the voxel size must be a finite non-zero number",
                    delta[i]
                ),
            ));
        }
        // nibabel's `Mdc.T * delta` is a float32 product: rounded the same here.
        let axis = |i: usize| {
            let d = delta[i] as f32;
            let at = |o: usize| (f32_at(42 + 12 * i + o) as f32 * d) as f64;
            DVec3::new(at(0), at(4), at(8))
        };
        let m = DMat3::from_cols(axis(0), axis(1), axis(2));
        (m, DVec3::new(f32_at(78), f32_at(82), f32_at(86)))
    } else {
        let m = DMat3::from_cols(DVec3::new(-1.0, 0.0, 0.0), DVec3::Z, DVec3::Y * -1.0);
        (m, DVec3::ZERO)
    };
    // nibabel's affine array takes the float32 type of `MdcD`: the translation, computed in
    // float64, is stored rounded to float32.
    let half = DVec3::new(dims[0] as f64, dims[1] as f64, dims[2] as f64) / 2.0;
    let t = (centre - m * half).as_vec3().as_dvec3();
    Ok(orient::affine(
        [m.x_axis, m.y_axis, m.z_axis],
        t,
        Frame::Ras,
    ))
}
