//! World coordinates of the text-header image formats (ours: NRRD, MetaImage, OME-Zarr give
//! voxel axes and an origin; section 6.6.2 meshes the image in world space).
//!
//! The world frame of every image reader is the NIfTI one, **RAS+** millimetres (x towards
//! the subject's right, y towards anterior, z towards superior),
//! because [`read_nifti`](super::read_nifti) returns the sform/qform unchanged, as nibabel
//! does. NRRD and MetaImage describe the same anatomy in **LPS+** (DICOM, ITK, 3D Slicer):
//! a point `(x, y, z)` in LPS is `(-x, -y, z)` in RAS. So an LPS header's voxel axes and
//! origin are mapped by `diag(-1, -1, 1)`, exactly (a sign change), and a volume saved as
//! NIfTI by nibabel and as NRRD or MetaImage by pynrrd or SimpleITK (which convert RAS to
//! LPS the same way) gives the same affine bit for bit, so the same mesh.
//!
//! A frame without anatomy (NRRD `scanner-xyz`, `3D-right-handed`, a bare `space
//! dimension`; OME-Zarr, whose axes are physical but not anatomical) is taken as is.

use super::ImageError;
use glam::{DAffine3, DMat3, DVec3};
use std::path::Path;

/// The anatomical frame a header's coordinates are in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Frame {
    /// Right, anterior, superior: the NIfTI world, kept.
    Ras,
    /// Left, posterior, superior (ITK, DICOM, Slicer): x and y negated.
    Lps,
    /// Left, anterior, superior: x negated.
    Las,
    /// No anatomical meaning: kept.
    Plain,
}

impl Frame {
    /// The frame of an NRRD `space` value (case-insensitive; `None` if unknown).
    pub fn of_nrrd(space: &str) -> Option<Frame> {
        Some(match space.trim().to_ascii_lowercase().as_str() {
            "right-anterior-superior" | "ras" => Frame::Ras,
            "left-posterior-superior" | "lps" => Frame::Lps,
            "left-anterior-superior" | "las" => Frame::Las,
            "scanner-xyz" | "3d-right-handed" | "3d-left-handed" => Frame::Plain,
            _ => return None,
        })
    }

    /// The matrix taking this frame's coordinates to RAS.
    fn to_ras(self) -> DVec3 {
        match self {
            Frame::Lps => DVec3::new(-1.0, -1.0, 1.0),
            Frame::Las => DVec3::new(-1.0, 1.0, 1.0),
            Frame::Ras | Frame::Plain => DVec3::ONE,
        }
    }
}

/// The voxel-to-world (RAS) affine: `x = F (sum_i ijk_i axes[i] + origin)` with `F` the
/// frame's sign flips; `axes[i]` is the world step of one voxel along index axis `i`.
pub(crate) fn affine(axes: [DVec3; 3], origin: DVec3, frame: Frame) -> DAffine3 {
    let f = frame.to_ras();
    DAffine3::from_mat3_translation(
        DMat3::from_cols(axes[0] * f, axes[1] * f, axes[2] * f),
        origin * f,
    )
}

/// A header error naming the file, the format, the field and the fix.
pub(crate) fn field(
    path: &Path,
    format: &'static str,
    field: &str,
    detail: impl Into<String>,
) -> ImageError {
    ImageError::Field {
        path: path.to_path_buf(),
        format,
        field: field.to_string(),
        detail: detail.into(),
    }
}

/// The data file a header names (NRRD `data file`, MetaImage `ElementDataFile`), beside the
/// header: one file that exists, else an error naming the header, the field and the fix.
pub(crate) fn data_file(
    header: &Path,
    format: &'static str,
    key: &str,
    name: &str,
) -> Result<std::path::PathBuf, ImageError> {
    if name.starts_with("LIST") || name.split_whitespace().count() > 1 {
        return Err(field(
            header,
            format,
            key,
            format!("= {name}: multi-file data is not read; save one data file"),
        ));
    }
    let p = header.parent().unwrap_or(Path::new(".")).join(name);
    if !p.is_file() {
        return Err(field(
            header,
            format,
            key,
            format!(
                "= {name}: {} does not exist; put the data file next to the header or fix the \
                 name",
                p.display()
            ),
        ));
    }
    Ok(p)
}

/// Read a file, the error naming it.
pub(crate) fn read(path: &Path) -> Result<Vec<u8>, ImageError> {
    std::fs::read(path).map_err(|source| ImageError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// Inflate a zlib stream (MetaImage `CompressedData`) to exactly `need` bytes.
pub(crate) fn inflate_zlib(path: &Path, raw: &[u8], need: usize) -> Result<Vec<u8>, ImageError> {
    use std::io::Read;
    let mut out = Vec::with_capacity(need);
    flate2::read::ZlibDecoder::new(raw)
        .take(need as u64 + 1)
        .read_to_end(&mut out)
        .map_err(|e| {
            if e.kind() == std::io::ErrorKind::UnexpectedEof {
                ImageError::Truncated {
                    path: path.to_path_buf(),
                    detail: "the zlib stream ends before its end marker".into(),
                }
            } else {
                ImageError::CorruptGzip {
                    path: path.to_path_buf(),
                    detail: format!("zlib: {e}"),
                }
            }
        })?;
    Ok(out)
}

/// Parse `n` whitespace- or comma-separated finite numbers.
pub(crate) fn numbers(s: &str, n: usize) -> Option<Vec<f64>> {
    let v: Vec<f64> = s
        .split(|c: char| c.is_whitespace() || c == ',')
        .filter(|t| !t.is_empty())
        .map(|t| t.parse::<f64>().ok().filter(|x| x.is_finite()))
        .collect::<Option<_>>()?;
    (v.len() == n).then_some(v)
}

/// `dims` multiplied out with the byte size, or an error naming `field`.
pub(crate) fn byte_count(
    path: &Path,
    format: &'static str,
    fieldname: &str,
    dims: &[usize],
    size: usize,
) -> Result<usize, ImageError> {
    dims.iter()
        .try_fold(size, |a, &d| a.checked_mul(d))
        .filter(|&n| n <= isize::MAX as usize / 2)
        .ok_or_else(|| {
            field(
                path,
                format,
                fieldname,
                format!("= {dims:?}: more voxels than can be held in memory; crop the image"),
            )
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lps_and_ras_describe_the_same_point() {
        let axes = [
            DVec3::new(0.5, 0.25, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::Z * 2.0,
        ];
        let o = DVec3::new(10.0, -20.0, 5.0);
        let a = affine(axes, o, Frame::Lps);
        // Voxel (1, 2, 3) in LPS is sum + origin; RAS negates x and y.
        let lps = axes[0] + axes[1] * 2.0 + axes[2] * 3.0 + o;
        let ras = a.transform_point3(DVec3::new(1.0, 2.0, 3.0));
        assert_eq!(ras, DVec3::new(-lps.x, -lps.y, lps.z));
        assert_eq!(affine(axes, o, Frame::Ras).translation, o);
        assert_eq!(Frame::of_nrrd("Left-Posterior-Superior"), Some(Frame::Lps));
        assert_eq!(Frame::of_nrrd("mars"), None);
    }

    #[test]
    fn numbers_need_the_exact_count() {
        assert_eq!(numbers("1, 2 3", 3), Some(vec![1.0, 2.0, 3.0]));
        assert_eq!(numbers("1 2", 3), None);
        assert_eq!(numbers("1 nan 2", 3), None);
    }
}
