//! NRRD volumes (ours: file format support; section 6.6.2 meshes them): `.nrrd` with the
//! data attached after a blank line, or a detached `.nhdr` header naming a `data file`
//! (relative to the header's folder), `raw` or `gzip` encoding, either `endian`.
//!
//! World coordinates: `space directions` (one vector per axis) and `space origin` in the
//! `space` frame, mapped to the RAS+ world of the NIfTI reader (see [`super::orient`]: an
//! LPS header, Slicer's and pynrrd's usual one, has x and y negated); without them,
//! `spacings` (or 1) along the axes, origin 0. 3D scalar volumes (`dimension: 3`) and, one
//! frame at a time (`--frame`, [`super::frame_axis`]), 4D series with one non-spatial axis
//! (`kinds` other than domain or space, or `none` as its space direction: Slicer's DWI
//! volumes, time series) are read; every other case is an error naming the field and the fix.

use super::frame_axis::{self, FrameAxis, frame_bytes};
use super::orient::{self, Frame};
use super::{Dtype, ImageError, Volume};
use glam::DVec3;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

const FMT: &str = "NRRD";

/// The header's fields (lower-case names) and where the attached data starts.
struct Header {
    fields: HashMap<String, String>,
    data_start: usize,
}

fn err(path: &Path, field: &str, detail: impl Into<String>) -> ImageError {
    orient::field(path, FMT, field, detail)
}

/// Parse the header lines of `bytes` (up to the first blank line or the end).
fn parse_header(path: &Path, bytes: &[u8]) -> Result<Header, ImageError> {
    if !bytes.starts_with(b"NRRD000") {
        return Err(err(
            path,
            "magic",
            "(first line) is not NRRD000x: not an NRRD file (check the extension)",
        ));
    }
    let mut fields = HashMap::new();
    let mut at = 0;
    let mut first = true;
    loop {
        let end = bytes[at..].iter().position(|&b| b == b'\n');
        let line_end = end.map_or(bytes.len(), |e| at + e);
        let line = std::str::from_utf8(&bytes[at..line_end])
            .map_err(|_| err(path, "header", "is not text: the header is damaged"))?
            .trim_end_matches('\r');
        at = end.map_or(bytes.len(), |_| line_end + 1);
        if first {
            first = false;
        } else if line.is_empty() {
            break;
        } else if !line.starts_with('#') && !line.contains(":=") {
            let (k, v) = line
                .split_once(": ")
                .ok_or_else(|| err(path, line, "is not a `field: value` line; fix the header"))?;
            fields.insert(k.trim().to_ascii_lowercase(), v.trim().to_string());
        }
        if end.is_none() {
            break;
        }
    }
    Ok(Header {
        fields,
        data_start: at,
    })
}

fn dtype(path: &Path, t: &str) -> Result<Dtype, ImageError> {
    Ok(match t.to_ascii_lowercase().as_str() {
        "signed char" | "int8" | "int8_t" => Dtype::I8,
        "uchar" | "unsigned char" | "uint8" | "uint8_t" => Dtype::U8,
        "short" | "short int" | "signed short" | "signed short int" | "int16" | "int16_t" => {
            Dtype::I16
        }
        "ushort" | "unsigned short" | "unsigned short int" | "uint16" | "uint16_t" => Dtype::U16,
        "int" | "signed int" | "int32" | "int32_t" => Dtype::I32,
        "uint" | "unsigned int" | "uint32" | "uint32_t" => Dtype::U32,
        "longlong"
        | "long long"
        | "long long int"
        | "signed long long"
        | "signed long long int"
        | "int64"
        | "int64_t" => Dtype::I64,
        "ulonglong" | "unsigned long long" | "unsigned long long int" | "uint64" | "uint64_t" => {
            Dtype::U64
        }
        "float" => Dtype::F32,
        "double" => Dtype::F64,
        _ => {
            return Err(err(
                path,
                "type",
                format!(
                    "= {t:?} is not supported; convert the image to int8, uint8, int16, uint16, \
                     int32, uint32, int64, uint64, float or double"
                ),
            ));
        }
    })
}

/// The kinds (lower case) of a spatial axis; `???` and `none` say nothing, so they count as
/// spatial.
const SPATIAL_KINDS: [&str; 4] = ["domain", "space", "???", "none"];

/// The array's axes: every size (3 or 4 of them) and, for a 4D array, its non-spatial axis.
///
/// Invariant: `sizes.len()` is 3 without `frame` and 4 with it.
struct Axes {
    sizes: Vec<usize>,
    frame: Option<FrameAxis>,
}

impl Axes {
    /// The indices of the three spatial axes, in order.
    fn spatial(&self) -> [usize; 3] {
        let skip = self.frame.as_ref().map_or(usize::MAX, |f| f.axis);
        let v: Vec<usize> = (0..self.sizes.len()).filter(|&i| i != skip).collect();
        [v[0], v[1], v[2]]
    }

    /// The sizes of the three spatial axes.
    fn dims(&self) -> [usize; 3] {
        self.spatial().map(|i| self.sizes[i])
    }
}

/// The tokens of a per-axis field (`kinds`, `space directions`, `spacings`), one per axis.
fn per_axis<'a>(
    path: &Path,
    h: &'a Header,
    key: &str,
    n: usize,
) -> Result<Option<Vec<&'a str>>, ImageError> {
    let Some(s) = h.fields.get(key) else {
        return Ok(None);
    };
    let t: Vec<&str> = s.split_whitespace().collect();
    if t.len() != n {
        return Err(err(
            path,
            key,
            format!("= {s:?}: expected {n} entries, one per axis (dimension = {n})"),
        ));
    }
    Ok(Some(t))
}

/// `dimension`, `sizes`, and which axis is not spatial (`kinds` not domain or space, or a
/// `none` space direction): none of a 3D volume, exactly one of a 4D series.
fn axes(path: &Path, h: &Header) -> Result<Axes, ImageError> {
    let f = &h.fields;
    let d = f.get("dimension").map(|s| s.trim().to_string());
    let n = match d.as_deref() {
        Some("3") => 3,
        Some("4") => 4,
        _ => {
            return Err(err(
                path,
                "dimension",
                format!(
                    "= {}: only 3D volumes and 4D series (one non-spatial axis, read with \
                     --frame) are read (extract one 3D volume, e.g. with pynrrd or Slicer)",
                    d.as_deref().unwrap_or("(missing)")
                ),
            ));
        }
    };
    let s = f.get("sizes").ok_or_else(|| {
        err(
            path,
            "sizes",
            format!("is missing; give the {n} axis sizes"),
        )
    })?;
    let sizes: Vec<usize> = s
        .split_whitespace()
        .map(|t| t.parse::<usize>().ok().filter(|&v| v > 0))
        .collect::<Option<_>>()
        .filter(|v: &Vec<usize>| v.len() == n)
        .ok_or_else(|| {
            err(
                path,
                "sizes",
                format!("= {s:?}: expected {n} positive whole numbers (dimension = {n})"),
            )
        })?;
    if f.get("space dimension").is_some_and(|d| d.trim() == "4") {
        return Err(err(
            path,
            "space dimension",
            "= 4 (ITK's 4D NRRD: the frames' axis in a 4D space) is not read; write the series \
             as MetaImage (.mha, read with --frame) or NIfTI",
        ));
    }
    let kinds = per_axis(path, h, "kinds", n)?;
    let dirs = per_axis(path, h, "space directions", n)?;
    let by_kind: Vec<usize> = kinds.as_ref().map_or(vec![], |k| {
        (0..n)
            .filter(|&i| !SPATIAL_KINDS.contains(&k[i].to_ascii_lowercase().as_str()))
            .collect()
    });
    let by_dir: Vec<usize> = dirs
        .as_ref()
        .map_or(vec![], |v| (0..n).filter(|&i| v[i] == "none").collect());
    let kind_of = |i: usize| kinds.as_ref().map(|k| k[i]);
    if n == 3 {
        if let Some(&i) = by_kind.first().or(by_dir.first()) {
            let what =
                kind_of(i).map_or("space direction none".to_string(), |k| format!("kinds {k}"));
            return Err(err(
                path,
                "dimension",
                format!(
                    "= 3 with axis {i} not spatial ({what}): a 2D image of {} values per \
                     pixel, not a volume; give a 3D volume",
                    sizes[i]
                ),
            ));
        }
        return Ok(Axes { sizes, frame: None });
    }
    if dirs.is_some() && kinds.is_some() && !by_kind.is_empty() && by_kind != by_dir {
        return Err(err(
            path,
            "kinds",
            format!(
                "and space directions disagree on the non-spatial axis (kinds: {by_kind:?}, \
                 `none` directions: {by_dir:?}); fix the header"
            ),
        ));
    }
    let found = if dirs.is_some() { &by_dir } else { &by_kind };
    match found.as_slice() {
        [a] => Ok(Axes {
            frame: Some(FrameAxis {
                axis: *a,
                frames: sizes[*a],
                label: kind_of(*a).map_or("space direction none".to_string(), |k| {
                    format!("kinds: {k}")
                }),
            }),
            sizes,
        }),
        _ => Err(err(
            path,
            if dirs.is_some() {
                "space directions"
            } else {
                "kinds"
            },
            format!(
                "of a 4D array must mark exactly one axis as not spatial (found {found:?}): \
                 e.g. kinds: domain domain domain list, or `none` as that axis's space direction"
            ),
        )),
    }
}

/// `(a,b,c)`: one vector of `space directions`.
fn direction(path: &Path, s: &str, v: &str) -> Result<DVec3, ImageError> {
    let bad = || {
        err(
            path,
            "space directions",
            format!(
                "= {s:?}: expected one vector like (1,0,0) per spatial axis (and `none` for the \
                 axis of a 4D series' frames)"
            ),
        )
    };
    let inner = v
        .strip_prefix('(')
        .and_then(|v| v.strip_suffix(')'))
        .ok_or_else(bad)?;
    let n = orient::numbers(inner, 3).ok_or_else(bad)?;
    Ok(DVec3::new(n[0], n[1], n[2]))
}

/// The voxel-to-world axes and origin, and the frame they are in.
fn geometry(path: &Path, h: &Header, ax: &Axes) -> Result<([DVec3; 3], DVec3, Frame), ImageError> {
    let f = &h.fields;
    let frame = match (f.get("space"), f.get("space dimension")) {
        (Some(s), _) => Frame::of_nrrd(s).ok_or_else(|| {
            err(
                path,
                "space",
                format!(
                    "= {s:?} is not a 3D space this reader knows; use left-posterior-superior, \
                     right-anterior-superior, left-anterior-superior or scanner-xyz"
                ),
            )
        })?,
        (None, Some(d)) if d.trim() == "3" => Frame::Plain,
        (None, Some(d)) => {
            return Err(err(
                path,
                "space dimension",
                format!("= {d}: only 3 is supported"),
            ));
        }
        (None, None) => Frame::Plain,
    };
    let n = ax.sizes.len();
    let spatial = ax.spatial();
    if let Some(v) = per_axis(path, h, "space directions", n)? {
        let s = &f["space directions"];
        let mut axes = [DVec3::ZERO; 3];
        for (k, &i) in spatial.iter().enumerate() {
            axes[k] = direction(path, s, v[i])?;
        }
        let origin = match f.get("space origin") {
            Some(o) => {
                let inner = o.trim().strip_prefix('(').and_then(|v| v.strip_suffix(')'));
                let n = inner.and_then(|v| orient::numbers(v, 3)).ok_or_else(|| {
                    err(path, "space origin", format!("= {o:?}: expected (x,y,z)"))
                })?;
                DVec3::new(n[0], n[1], n[2])
            }
            None => DVec3::ZERO,
        };
        return Ok((axes, origin, frame));
    }
    let s = match per_axis(path, h, "spacings", n)? {
        Some(t) => {
            let picked = spatial.map(|i| t[i]).join(" ");
            orient::numbers(&picked, 3).ok_or_else(|| {
                err(
                    path,
                    "spacings",
                    format!(
                        "= {:?}: expected a finite number per spatial axis",
                        f["spacings"]
                    ),
                )
            })?
        }
        None => vec![1.0; 3],
    };
    Ok((
        [DVec3::X * s[0], DVec3::Y * s[1], DVec3::Z * s[2]],
        DVec3::ZERO,
        frame,
    ))
}

/// The voxel bytes: from the attached data or the `data file`, skipped and decoded.
fn data(
    path: &Path,
    h: &Header,
    bytes: Vec<u8>,
    need: usize,
) -> Result<(Vec<u8>, PathBuf), ImageError> {
    let f = &h.fields;
    let (src, mut raw) = match f.get("data file").or_else(|| f.get("datafile")) {
        Some(name) => {
            let p = orient::data_file(path, FMT, "data file", name)?;
            let d = orient::read(&p)?;
            (p, d)
        }
        None => {
            let mut b = bytes;
            b.drain(..h.data_start.min(b.len()));
            (path.to_path_buf(), b)
        }
    };
    let num = |k: &str| -> Result<i64, ImageError> {
        f.get(k).map_or(Ok(0), |v| {
            v.trim()
                .parse::<i64>()
                .map_err(|_| err(path, k, format!("= {v:?}: not a whole number")))
        })
    };
    let line_skip = num("line skip")?;
    let byte_skip = num("byte skip")?;
    if line_skip < 0 || byte_skip < -1 {
        return Err(err(
            path,
            "byte skip",
            "must be 0 or more (or -1 for raw data)",
        ));
    }
    for _ in 0..line_skip {
        let e = raw
            .iter()
            .position(|&b| b == b'\n')
            .map_or(raw.len(), |e| e + 1);
        raw.drain(..e);
    }
    let enc = f.get("encoding").map(|s| s.to_ascii_lowercase());
    let enc = enc.as_deref().unwrap_or("");
    let mut out = match enc {
        "raw" => {
            if byte_skip == -1 {
                let start = raw.len().saturating_sub(need);
                raw.drain(..start);
            }
            raw
        }
        "gzip" | "gz" => super::nifti_io::gunzip(&src, &raw)?,
        _ => {
            return Err(err(
                path,
                "encoding",
                format!("= {enc:?} is not supported; save the volume with encoding raw or gzip"),
            ));
        }
    };
    if enc != "raw" || byte_skip != -1 {
        let skip = (byte_skip.max(0) as usize).min(out.len());
        out.drain(..skip);
    }
    if out.len() < need {
        return Err(ImageError::Truncated {
            path: src,
            detail: format!(
                "the voxel data has {} bytes, sizes and type need {need}",
                out.len()
            ),
        });
    }
    if out.len() > need {
        return Err(err(
            path,
            "sizes",
            format!(
                "and type need {need} bytes but the data has {}; the header does not match the \
                 data (check sizes, type and byte skip)",
                out.len()
            ),
        ));
    }
    Ok((out, src))
}

/// Read an NRRD volume (`.nrrd` or `.nhdr`); see the module documentation. A 4D series
/// is refused: [`read_nrrd_frame`] reads one of its volumes.
pub fn read_nrrd(path: impl AsRef<Path>) -> Result<Volume, ImageError> {
    read_nrrd_frame(path, None)
}

/// [`read_nrrd`] of frame `frame` of a 4D series (`dimension: 4` with one non-spatial axis:
/// `kinds` not domain or space, or `none` in `space directions`; DWI gradients, time
/// points). `None` reads a 3D volume, or a series of one frame, and refuses a longer series.
pub fn read_nrrd_frame(path: impl AsRef<Path>, frame: Option<usize>) -> Result<Volume, ImageError> {
    let path = path.as_ref();
    let bytes = orient::read(path)?;
    let h = parse_header(path, &bytes)?;
    let ax = axes(path, &h)?;
    let k = frame_axis::pick(ax.frame.as_ref(), path, &ax.sizes, frame)?;
    let ty = h.fields.get("type").ok_or_else(|| {
        err(
            path,
            "type",
            "is missing; give the voxel type (e.g. type: short)",
        )
    })?;
    let dtype = dtype(path, ty)?;
    let big = match h.fields.get("endian").map(|s| s.to_ascii_lowercase()) {
        Some(e) if e == "big" => true,
        Some(e) if e == "little" => false,
        None if dtype.size() == 1 => false,
        other => {
            return Err(err(
                path,
                "endian",
                format!(
                    "= {}: multi-byte voxels need endian: little or endian: big",
                    other.as_deref().unwrap_or("(missing)")
                ),
            ));
        }
    };
    let (axes, origin, space) = geometry(path, &h, &ax)?;
    let need = orient::byte_count(path, FMT, "sizes", &ax.sizes, dtype.size())?;
    let (mut raw, _) = data(path, &h, bytes, need)?;
    let mut note = None;
    if let Some(fa) = &ax.frame {
        let s = &ax.sizes;
        raw = frame_bytes(&raw, [s[0], s[1], s[2], s[3]], fa.axis, k, dtype.size());
        note = fa.note(path, k);
    }
    let (voxels, held) = super::volume::decode_voxels(path, ax.dims(), dtype, &raw, big)?;
    let affine = orient::affine(axes, origin, space);
    super::volume::check_affine(&affine, Some(path), "space directions / space origin")?;
    let mut vol = Volume::new(ax.dims(), voxels, affine)?.with_source(path);
    for n in note.into_iter().chain(held) {
        vol = vol.with_note(n);
    }
    Ok(vol)
}
