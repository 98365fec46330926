//! MetaImage volumes (ours: file format support; section 6.6.2 meshes them): `.mha` with the
//! data after `ElementDataFile = LOCAL`, or a `.mhd` header naming a data file (relative to
//! the header's folder, e.g. a `.raw`), uncompressed or zlib (`CompressedData = True`).
//!
//! Fields read: `NDims` (3, or 4 for a series read one frame at a time with `--frame`,
//! [`super::frame_axis`]), `DimSize`, `ElementType` (`MET_CHAR` .. `MET_DOUBLE`),
//! `ElementSpacing`, `Offset` (or `Origin`/`Position`), `TransformMatrix` (or
//! `Rotation`/`Orientation`; as ITK reads it, the numbers are the direction of axis 0, then
//! of axis 1, then of axis 2), `BinaryDataByteOrderMSB` (or `ElementByteOrderMSB`),
//! `CompressedData`, `ElementNumberOfChannels` (1), `HeaderSize` (`.mhd`; -1: the data is
//! at the end of the file). World coordinates: MetaImage is ITK's format, and ITK's physical
//! space is LPS+ whatever `AnatomicalOrientation` says, so the axes and offset are mapped to
//! the RAS+ world of the NIfTI reader by negating x and y (see [`super::orient`]).

use super::frame_axis::{self, FrameAxis, frame_bytes};
use super::orient::{self, Frame};
use super::{Dtype, ImageError, Volume};
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
        "MET_LONG_LONG" => Dtype::I64,
        "MET_ULONG_LONG" => Dtype::U64,
        _ => {
            return Err(err(
                path,
                "ElementType",
                format!(
                    "= {t} is not supported; convert the image to MET_CHAR, MET_UCHAR, \
                     MET_SHORT, MET_USHORT, MET_INT, MET_UINT, MET_LONG_LONG, MET_ULONG_LONG, MET_FLOAT \
                     or MET_DOUBLE"
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

/// Read a MetaImage volume (`.mha` or `.mhd`); see the module documentation. A 4D series
/// is refused: [`read_metaimage_frame`] reads one of its volumes.
pub fn read_metaimage(path: impl AsRef<Path>) -> Result<Volume, ImageError> {
    read_metaimage_frame(path, None)
}

/// [`read_metaimage`] of frame `frame` of a 4D series (`NDims = 4`: ITK's 3D + time or
/// series images, the fourth axis the frames, as SimpleITK's `JoinSeries` writes them).
/// `None` reads a 3D volume, or a series of one frame, and refuses a longer series.
pub fn read_metaimage_frame(
    path: impl AsRef<Path>,
    frame: Option<usize>,
) -> Result<Volume, ImageError> {
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
    let (sizes, series, k) = layout(path, &f, frame)?;
    let nd = sizes.len();
    let dims = [sizes[0], sizes[1], sizes[2]];
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
        nd,
        vec![1.0; nd],
    )?;
    let offset = vector(
        path,
        &f,
        &["Offset", "Origin", "Position"],
        nd,
        vec![0.0; nd],
    )?;
    let eye: Vec<f64> = (0..nd * nd)
        .map(|i| if i / nd == i % nd { 1.0 } else { 0.0 })
        .collect();
    let tm = vector(
        path,
        &f,
        &["TransformMatrix", "Rotation", "Orientation"],
        nd * nd,
        eye,
    )?;
    let tm = spatial_block(path, &f, &tm, nd)?;
    let need = orient::byte_count(path, FMT, "DimSize", &sizes, dtype.size())?;
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
    let affine = orient::affine(axes, DVec3::from_slice(&offset[..3]), Frame::Lps);
    super::volume::check_affine(
        &affine,
        Some(path),
        "TransformMatrix / ElementSpacing / Offset",
    )?;
    let (data, note) = match &series {
        Some(fa) => {
            let s = [sizes[0], sizes[1], sizes[2], sizes[3]];
            (frame_bytes(&data, s, 3, k, dtype.size()), fa.note(path, k))
        }
        None => (data, None),
    };
    let (voxels, held) = super::volume::decode_voxels(path, dims, dtype, &data, big)?;
    let mut vol = Volume::new(dims, voxels, affine)?.with_source(path);
    for n in note.into_iter().chain(held) {
        vol = vol.with_note(n);
    }
    Ok(vol)
}

/// `NDims` and `DimSize`, the frames' axis of a 4D series, and the frame to read (see
/// [`read_metaimage_frame`]).
fn layout(
    path: &Path,
    f: &HashMap<String, String>,
    frame: Option<usize>,
) -> Result<(Vec<usize>, Option<FrameAxis>, usize), ImageError> {
    let nd = match f.get("NDims").map(String::as_str) {
        Some("3") => 3,
        Some("4") => 4,
        nd => {
            return Err(err(
                path,
                "NDims",
                format!(
                    "= {}: only 3D volumes and 4D series (read with --frame) are read (extract \
                     one 3D volume, e.g. with SimpleITK)",
                    nd.unwrap_or("(missing)")
                ),
            ));
        }
    };
    let ds = f
        .get("DimSize")
        .ok_or_else(|| err(path, "DimSize", format!("is missing; give the {nd} sizes")))?;
    let sizes: Vec<usize> = ds
        .split_whitespace()
        .map(|t| t.parse::<usize>().ok().filter(|&v| v > 0))
        .collect::<Option<_>>()
        .filter(|v: &Vec<usize>| v.len() == nd)
        .ok_or_else(|| {
            err(
                path,
                "DimSize",
                format!("= {ds:?}: expected {nd} positive whole numbers (NDims = {nd})"),
            )
        })?;
    let series = (nd == 4).then(|| FrameAxis {
        axis: 3,
        frames: sizes[3],
        label: "the fourth of NDims = 4".into(),
    });
    let k = frame_axis::pick(series.as_ref(), path, &sizes, frame)?;
    Ok((sizes, series, k))
}

/// The 3 x 3 direction block (axis 0's direction, then axis 1's, then axis 2's) of an
/// `nd x nd` `TransformMatrix`; for `nd = 4`, the frame axis must not mix with space (its
/// row and column zero but the diagonal), else the frames would not share one geometry.
fn spatial_block(
    path: &Path,
    f: &HashMap<String, String>,
    tm: &[f64],
    nd: usize,
) -> Result<Vec<f64>, ImageError> {
    if nd == 3 {
        return Ok(tm.to_vec());
    }
    if (0..3).any(|i| tm[4 * i + 3] != 0.0 || tm[12 + i] != 0.0) {
        let key = ["TransformMatrix", "Rotation", "Orientation"]
            .into_iter()
            .find(|k| f.contains_key(*k))
            .unwrap_or("TransformMatrix");
        return Err(err(
            path,
            key,
            format!(
                "= {tm:?}: the fourth axis (the frames) mixes with space; its row and column \
                 must be 0 but the diagonal"
            ),
        ));
    }
    Ok((0..3)
        .flat_map(|i| (0..3).map(move |j| tm[4 * i + j]))
        .collect())
}
