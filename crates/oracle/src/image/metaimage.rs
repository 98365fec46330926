//! MetaImage volumes (ours: file format support; section 6.6.2 meshes them): `.mha` with the
//! data after `ElementDataFile = LOCAL`, or a `.mhd` header naming a data file (relative to
//! the header's folder, e.g. a `.raw`), uncompressed or zlib (`CompressedData = True`).
//!
//! Fields read: `NDims` (3), `DimSize`, `ElementType` (`MET_CHAR` .. `MET_DOUBLE`),
//! `ElementSpacing`, `Offset` (or `Origin`/`Position`), `TransformMatrix` (or
//! `Rotation`/`Orientation`; as ITK reads it, the numbers are the direction of axis 0, then
//! of axis 1, then of axis 2), `BinaryDataByteOrderMSB` (or `ElementByteOrderMSB`),
//! `CompressedData`, `ElementNumberOfChannels` (1), `HeaderSize` (`.mhd`; -1: the data is
//! at the end of the file). World coordinates: MetaImage is ITK's format, and ITK's physical
//! space is LPS+ whatever `AnatomicalOrientation` says, so the axes and offset are mapped to
//! the RAS+ world of the NIfTI reader by negating x and y (see [`super::orient`]).

use super::orient::{self, Frame};
use super::{Dtype, ImageError, Volume, Voxels};
use glam::DVec3;
use std::collections::HashMap;
use std::path::Path;

const FMT: &str = "MetaImage";

fn err(path: &Path, field: &str, detail: impl Into<String>) -> ImageError {
    orient::field(path, FMT, field, detail)
}

/// The `Key = Value` fields (keys as written) and where the local data starts.
fn parse_header(path: &Path, bytes: &[u8]) -> Result<(HashMap<String, String>, usize), ImageError> {
    let mut fields = HashMap::new();
    let mut at = 0;
    while at < bytes.len() {
        let end = bytes[at..].iter().position(|&b| b == b'\n');
        let line_end = end.map_or(bytes.len(), |e| at + e);
        let line = std::str::from_utf8(&bytes[at..line_end]).map_err(|_| {
            err(
                path,
                "header",
                "is not text before ElementDataFile: not a MetaImage header",
            )
        })?;
        let line = line.trim_end_matches('\r');
        at = end.map_or(bytes.len(), |_| line_end + 1);
        if line.trim().is_empty() {
            continue;
        }
        let (k, v) = line.split_once('=').ok_or_else(|| {
            err(
                path,
                line.trim(),
                "is not a `Key = Value` line; not a MetaImage header (or it is damaged)",
            )
        })?;
        let (k, v) = (k.trim().to_string(), v.trim().to_string());
        let last = k == "ElementDataFile";
        fields.insert(k, v);
        if last {
            return Ok((fields, at));
        }
    }
    if fields.is_empty() {
        return Err(err(path, "header", "is empty: not a MetaImage file"));
    }
    Err(err(
        path,
        "ElementDataFile",
        "is missing (it must be the last header line: LOCAL or the data file's name); the \
         header is incomplete",
    ))
}

fn dtype(path: &Path, t: &str) -> Result<Dtype, ImageError> {
    Ok(match t {
        "MET_CHAR" => Dtype::I8,
        "MET_UCHAR" => Dtype::U8,
        "MET_SHORT" => Dtype::I16,
        "MET_USHORT" => Dtype::U16,
        "MET_INT" | "MET_LONG" => Dtype::I32,
        "MET_UINT" | "MET_ULONG" => Dtype::U32,
        "MET_FLOAT" => Dtype::F32,
        "MET_DOUBLE" => Dtype::F64,
        _ => {
            return Err(err(
                path,
                "ElementType",
                format!(
                    "= {t} is not supported; convert the image to MET_CHAR, MET_UCHAR, \
                     MET_SHORT, MET_USHORT, MET_INT, MET_UINT, MET_FLOAT or MET_DOUBLE"
                ),
            ));
        }
    })
}

fn flag(path: &Path, f: &HashMap<String, String>, keys: &[&str]) -> Result<bool, ImageError> {
    match keys.iter().find_map(|k| f.get(*k).map(|v| (k, v))) {
        None => Ok(false),
        Some((k, v)) => match v.to_ascii_lowercase().as_str() {
            "true" | "1" => Ok(true),
            "false" | "0" => Ok(false),
            _ => Err(err(path, k, format!("= {v}: expected True or False"))),
        },
    }
}

fn vector(
    path: &Path,
    f: &HashMap<String, String>,
    keys: &[&str],
    n: usize,
    default: Vec<f64>,
) -> Result<Vec<f64>, ImageError> {
    match keys.iter().find_map(|k| f.get(*k).map(|v| (k, v))) {
        None => Ok(default),
        Some((k, v)) => orient::numbers(v, n)
            .ok_or_else(|| err(path, k, format!("= {v:?}: expected {n} finite numbers"))),
    }
}

/// The voxel bytes as stored: after the header (`LOCAL`) or in the named data file (after
/// `HeaderSize` bytes; -1: the last bytes), with the file they come from.
fn load_data(
    path: &Path,
    f: &HashMap<String, String>,
    bytes: Vec<u8>,
    data_start: usize,
    need: usize,
    compressed: bool,
) -> Result<(std::path::PathBuf, Vec<u8>), ImageError> {
    let file = &f["ElementDataFile"];
    Ok(if file == "LOCAL" {
        let mut b = bytes;
        b.drain(..data_start);
        (path.to_path_buf(), b)
    } else {
        let p = orient::data_file(path, FMT, "ElementDataFile", file)?;
        let mut d = orient::read(&p)?;
        let hs = f.get("HeaderSize").map_or(Ok(0i64), |v| {
            v.parse::<i64>()
                .map_err(|_| err(path, "HeaderSize", format!("= {v}: not a whole number")))
        })?;
        if hs == -1 && !compressed {
            let start = d.len().saturating_sub(need);
            d.drain(..start);
        } else if hs > 0 {
            d.drain(..(hs as usize).min(d.len()));
        }
        (p, d)
    })
}

/// Read a MetaImage volume (`.mha` or `.mhd`); see the module documentation.
pub fn read_metaimage(path: impl AsRef<Path>) -> Result<Volume, ImageError> {
    let path = path.as_ref();
    let bytes = orient::read(path)?;
    let (f, data_start) = parse_header(path, &bytes)?;
    if let Some(t) = f.get("ObjectType").filter(|t| *t != "Image") {
        return Err(err(
            path,
            "ObjectType",
            format!("= {t}: only Image is read"),
        ));
    }
    let nd = f.get("NDims").map(String::as_str);
    if nd != Some("3") {
        return Err(err(
            path,
            "NDims",
            format!(
                "= {}: only 3D volumes are read (extract one 3D volume, e.g. with SimpleITK)",
                nd.unwrap_or("(missing)")
            ),
        ));
    }
    let ds = f
        .get("DimSize")
        .ok_or_else(|| err(path, "DimSize", "is missing; give the three sizes"))?;
    let dims: Vec<usize> = ds
        .split_whitespace()
        .map(|t| t.parse::<usize>().ok().filter(|&v| v > 0))
        .collect::<Option<_>>()
        .filter(|v: &Vec<usize>| v.len() == 3)
        .ok_or_else(|| {
            err(
                path,
                "DimSize",
                format!("= {ds:?}: expected three positive whole numbers"),
            )
        })?;
    let dims = [dims[0], dims[1], dims[2]];
    let channels = f.get("ElementNumberOfChannels").map_or("1", String::as_str);
    if channels != "1" {
        return Err(err(
            path,
            "ElementNumberOfChannels",
            format!("= {channels}: only scalar images (1 channel) are read"),
        ));
    }
    let ty = f.get("ElementType").ok_or_else(|| {
        err(
            path,
            "ElementType",
            "is missing; give the voxel type (e.g. MET_SHORT)",
        )
    })?;
    let dtype = dtype(path, ty)?;
    let big = flag(path, &f, &["BinaryDataByteOrderMSB", "ElementByteOrderMSB"])?;
    let compressed = flag(path, &f, &["CompressedData"])?;
    let spacing = vector(
        path,
        &f,
        &["ElementSpacing", "ElementSize"],
        3,
        vec![1.0; 3],
    )?;
    let offset = vector(path, &f, &["Offset", "Origin", "Position"], 3, vec![0.0; 3])?;
    let eye = vec![1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
    let tm = vector(
        path,
        &f,
        &["TransformMatrix", "Rotation", "Orientation"],
        9,
        eye,
    )?;
    let need = orient::byte_count(path, FMT, "DimSize", dims, dtype.size())?;
    let (src, raw) = load_data(path, &f, bytes, data_start, need, compressed)?;
    let data = if compressed {
        orient::inflate_zlib(&src, &raw, need)?
    } else {
        raw
    };
    if data.len() != need {
        if data.len() < need {
            return Err(ImageError::Truncated {
                path: src,
                detail: format!(
                    "the voxel data has {} bytes, DimSize and ElementType need {need}",
                    data.len()
                ),
            });
        }
        return Err(err(
            path,
            "DimSize",
            format!(
                "and ElementType need {need} bytes but the data has {}; the header does not \
                 match the data",
                data.len()
            ),
        ));
    }
    let axes = [0, 1, 2].map(|i| DVec3::new(tm[3 * i], tm[3 * i + 1], tm[3 * i + 2]) * spacing[i]);
    let affine = orient::affine(axes, DVec3::from_slice(&offset), Frame::Lps);
    super::volume::check_affine(
        &affine,
        Some(path),
        "TransformMatrix / ElementSpacing / Offset",
    )?;
    let voxels = Voxels::from_bytes(dtype, &data, big);
    Ok(Volume::new(dims, voxels, affine)?.with_source(path))
}
