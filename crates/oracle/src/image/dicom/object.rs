//! One DICOM object's image planes: geometry and pixel values of each frame (ours: the voxel
//! reader of section 6.6.2's images; DICOM PS3.3 C.7.6.2 Image Plane, C.7.6.3 Image Pixel,
//! C.7.6.16 the enhanced multi-frame functional groups).
//!
//! Invariant kept: a [`Plane`]'s `pixels` hold exactly `rows * cols` values, row by row
//! (column index fastest), masked to `BitsStored` and sign-extended as the header says.

use super::super::orient::field;
use super::super::{ImageError, Voxels};
use super::order::VolumeOrder;
use dicom_core::Tag;
use dicom_core::header::HasLength;
use dicom_core::value::{PrimitiveValue, Value};
use dicom_dictionary_std::tags;
use dicom_object::file::ReadPreamble;
use dicom_object::{FileDicomObject, InMemDicomObject, OpenFileOptions};
use glam::DVec3;
use std::path::{Path, PathBuf};

const FORMAT: &str = "DICOM";

/// One 2D frame: where it lies (patient LPS, millimetres) and its values.
#[derive(Clone, Debug)]
pub(crate) struct Plane {
    /// The file it came from and its frame number there.
    pub file: PathBuf,
    pub frame: usize,
    /// `SeriesInstanceUID`, its `SeriesNumber`, and `#SeriesNumber 'SeriesDescription'
    /// (Modality)` for messages.
    pub series: String,
    pub series_number: Option<String>,
    pub series_label: String,
    pub rows: usize,
    pub cols: usize,
    /// `ImagePositionPatient`: the centre of the first pixel.
    pub position: DVec3,
    /// `ImageOrientationPatient`: the direction of increasing column index (along a row), then
    /// of increasing row index.
    pub row_dir: DVec3,
    pub col_dir: DVec3,
    /// `PixelSpacing`: between rows, then between columns.
    pub spacing: [f64; 2],
    /// `RescaleSlope`, `RescaleIntercept` (RT Dose: `DoseGridScaling`, 0).
    pub slope: f64,
    pub inter: f64,
    pub pixels: Voxels,
    /// Whether the values come from a lossy compression (JPEG baseline, JPEG 2000 lossy).
    pub lossy: bool,
    /// Its place among the volumes of a series at one slice position.
    pub order: VolumeOrder,
    /// `SOPInstanceUID` (empty when absent): the same image under two file names.
    pub instance_uid: String,
}

impl Plane {
    /// Its file (and frame, in a multi-frame file) for messages.
    pub fn name(&self) -> String {
        let file = self.file.display();
        if self.frame > 0 {
            format!("{file} (frame {})", self.frame + 1)
        } else {
            file.to_string()
        }
    }
}

/// Whether the file starts with the DICOM preamble (`DICM` at byte 128).
pub(crate) fn has_preamble(path: &Path) -> bool {
    use std::io::Read;
    let mut head = [0u8; 132];
    std::fs::File::open(path)
        .and_then(|mut f| f.read_exact(&mut head))
        .is_ok()
        && &head[128..] == b"DICM"
}

/// The file at `path` parsed, its declared lengths checked first (`lengths`). The object owns
/// its values: the file's bytes go when this returns (a multi-frame file was held four times
/// while read, twice since).
fn parse(path: &Path) -> Result<FileDicomObject<InMemDicomObject>, ImageError> {
    let bytes = super::super::orient::read(path)?;
    if bytes.len() < 132 || &bytes[128..132] != b"DICM" {
        return Err(ImageError::Dicom {
            path: path.to_path_buf(),
            detail: "not a DICOM file: no 'DICM' preamble at byte 128 (a file without the \
                     DICOM file header is not read; re-export the series as DICOM files)"
                .into(),
        });
    }
    super::lengths::check(&bytes[132..]).map_err(|why| ImageError::Dicom {
        path: path.to_path_buf(),
        detail: format!(
            "cannot parse the DICOM data set ({why}); the file is damaged or truncated: \
             re-export it"
        ),
    })?;
    let obj = OpenFileOptions::new()
        .read_preamble(ReadPreamble::Never)
        .from_reader(&bytes[128..])
        .map_err(|e| ImageError::Dicom {
            path: path.to_path_buf(),
            detail: format!(
                "cannot parse the DICOM data set ({e}); the file is damaged or truncated: \
                 re-export it"
            ),
        })?;
    Ok(obj)
}

/// The planes of the DICOM file at `path`; `Ok(None)` when it holds no image (a structured
/// report, a DICOMDIR, a presentation state).
pub(crate) fn read_planes(path: &Path) -> Result<Option<Vec<Plane>>, ImageError> {
    let mut obj = parse(path)?;
    let ts = obj
        .meta()
        .transfer_syntax()
        .trim_end_matches('\0')
        .to_string();
    let Some((pixel_tag, declared, encapsulated)) = pixel_element(&obj) else {
        return Ok(None);
    };
    let header = Header::of(path, &obj)?;
    if let Some(kind) = mosaic(&obj) {
        return Err(ImageError::Dicom {
            path: path.to_path_buf(),
            detail: format!(
                "a Siemens mosaic ({kind}): each image tiles the slices of a whole volume, \
                 whose positions are in Siemens' private CSA header, which is not read; convert \
                 the series with dcm2niix"
            ),
        });
    }
    let frames = header.frames;
    let (values, lossy) = match encapsulated {
        true => {
            let Some(lossy) = super::compressed::decodable(&ts) else {
                return Err(ImageError::Dicom {
                    path: path.to_path_buf(),
                    detail: format!(
                        "the pixel data is compressed ({}, transfer syntax {ts}), which is not \
                         read; decompress the series first (`gdcmconv --raw IN OUT`, dcmtk's \
                         `dcmdjpeg`) or convert it with dcm2niix",
                        syntax_name(&ts)
                    ),
                });
            };
            let need = header.samples(path)? * (header.bits_allocated as usize / 8);
            let bytes = super::compressed::decode(path, &ts, &obj, need)?;
            (integers(&bytes, &header), lossy)
        }
        false => {
            // Owned, so that its copy goes once converted (at most two copies at a time).
            let value = obj
                .take_element(pixel_tag)
                .map_err(|e| field(path, FORMAT, "PixelData (7FE0,0010)", format!("{e}")))?
                .into_value();
            (decode_pixels(path, &ts, value, declared, &header)?, false)
        }
    };
    // Decoded: the compressed element's copy goes too (the geometry is read from `obj` below;
    // the native one was taken above).
    obj.remove_element(pixel_tag);
    // Each frame's values in the file's type: the whole buffer for one frame, else cut from
    // its little-endian bytes (`Voxels`' own conversions).
    let frame_pixels: Vec<Voxels> = if frames == 1 {
        vec![values]
    } else {
        let (dtype, le) = (values.dtype(), values.to_le_bytes());
        drop(values); // at most two copies of the frames at a time
        le.chunks_exact(le.len() / frames)
            .map(|b| Voxels::from_bytes(dtype, b, false))
            .collect()
    };
    let uid = text(&obj, tags::SOP_INSTANCE_UID).unwrap_or_default();
    let mut planes = Vec::with_capacity(frames);
    for (f, pixels) in frame_pixels.into_iter().enumerate() {
        let geo = frame_geometry(path, &obj, f, frames)?;
        planes.push(Plane {
            file: path.to_path_buf(),
            frame: f,
            series: header.series.clone(),
            series_number: header.series_number.clone(),
            series_label: header.series_label.clone(),
            rows: header.rows,
            cols: header.cols,
            position: geo.position,
            row_dir: geo.row_dir,
            col_dir: geo.col_dir,
            spacing: geo.spacing,
            slope: geo.slope,
            inter: geo.inter,
            pixels,
            lossy,
            instance_uid: uid.clone(),
            order: VolumeOrder::of(
                &obj,
                item(&obj, tags::PER_FRAME_FUNCTIONAL_GROUPS_SEQUENCE, f),
                f,
            ),
        });
    }
    Ok(Some(planes))
}

/// The pixel data element: integer (`PixelData`) or float (`FloatPixelData`,
/// `DoubleFloatPixelData`), with its length as the file declares it (the parser reads 16-bit
/// words, so a declared odd length loses its last byte in the value).
fn pixel_element(obj: &InMemDicomObject) -> Option<(Tag, Option<usize>, bool)> {
    [
        tags::PIXEL_DATA,
        tags::FLOAT_PIXEL_DATA,
        tags::DOUBLE_FLOAT_PIXEL_DATA,
    ]
    .iter()
    .find_map(|&t| obj.element_opt(t).ok().flatten())
    .map(|e| {
        let encapsulated = matches!(e.value(), Value::PixelSequence(_));
        let tag = dicom_core::header::Header::tag(e);
        (tag, e.length().get().map(|l| l as usize), encapsulated)
    })
}

/// The image pixel module and the series, read once per file.
struct Header {
    rows: usize,
    cols: usize,
    frames: usize,
    bits_allocated: u32,
    bits_stored: u32,
    signed: bool,
    series: String,
    series_number: Option<String>,
    series_label: String,
}

impl Header {
    /// `Rows x Columns x NumberOfFrames`, or an error when it cannot be held in memory (the
    /// bytes, up to 8 a sample, must fit an allocation).
    fn samples(&self, path: &Path) -> Result<usize, ImageError> {
        self.rows
            .checked_mul(self.cols)
            .and_then(|v| v.checked_mul(self.frames))
            .filter(|&v| v <= isize::MAX as usize / 8)
            .ok_or_else(|| {
                field(
                    path,
                    FORMAT,
                    "Rows/Columns/NumberOfFrames",
                    "hold more voxels than can be held in memory; the header is damaged",
                )
            })
    }

    /// The image pixel module (PS3.3 C.7.6.3): every field it needs present and consistent.
    fn of(path: &Path, obj: &InMemDicomObject) -> Result<Header, ImageError> {
        let bad = |name: &str, detail: String| field(path, FORMAT, name, detail);
        let int = |tag: Tag, name: &str| -> Result<u32, ImageError> {
            uint(obj, tag).ok_or_else(|| {
                bad(
                    name,
                    "is missing or not a number; the file is not a complete image".into(),
                )
            })
        };
        let samples = int(tags::SAMPLES_PER_PIXEL, "SamplesPerPixel (0028,0002)")?;
        let photometric = text(obj, tags::PHOTOMETRIC_INTERPRETATION).unwrap_or_default();
        if samples != 1 || !matches!(photometric.as_str(), "MONOCHROME1" | "MONOCHROME2") {
            return Err(bad(
                "SamplesPerPixel (0028,0002) / PhotometricInterpretation (0028,0004)",
                format!(
                    "= {samples} / {photometric:?}: not a greyscale image (colour, or palette \
                     indices that are not intensities); convert it to one greyscale channel first"
                ),
            ));
        }
        let rows = int(tags::ROWS, "Rows (0028,0010)")? as usize;
        let cols = int(tags::COLUMNS, "Columns (0028,0011)")? as usize;
        if rows == 0 || cols == 0 {
            return Err(bad(
                "Rows/Columns",
                format!("= {rows} x {cols}: an empty image"),
            ));
        }
        let frames = match text(obj, tags::NUMBER_OF_FRAMES) {
            None => 1,
            Some(s) => s
                .trim()
                .parse::<usize>()
                .ok()
                .filter(|&n| n >= 1)
                .ok_or_else(|| {
                    bad(
                        "NumberOfFrames (0028,0008)",
                        format!("= {s:?} is not a positive whole number; the header is damaged"),
                    )
                })?,
        };
        let float = obj.element_opt(tags::PIXEL_DATA).ok().flatten().is_none();
        let bits_allocated = int(tags::BITS_ALLOCATED, "BitsAllocated (0028,0100)")?;
        let allowed: &[u32] = if float { &[32, 64] } else { &[8, 16, 32] };
        if !allowed.contains(&bits_allocated) {
            return Err(bad(
                "BitsAllocated (0028,0100)",
                format!(
                    "= {bits_allocated} is not read (8, 16 or 32 bits; 32 or 64 for float pixel \
                     data); convert the series with dcm2niix"
                ),
            ));
        }
        let (bits_stored, high, representation) = if float {
            (bits_allocated, bits_allocated - 1, 0)
        } else {
            (
                int(tags::BITS_STORED, "BitsStored (0028,0101)")?,
                int(tags::HIGH_BIT, "HighBit (0028,0102)")?,
                int(
                    tags::PIXEL_REPRESENTATION,
                    "PixelRepresentation (0028,0103)",
                )?,
            )
        };
        if bits_stored == 0 || bits_stored > bits_allocated || high + 1 != bits_stored {
            return Err(bad(
                "BitsStored (0028,0101) / HighBit (0028,0102)",
                format!(
                    "= {bits_stored} / {high} with BitsAllocated {bits_allocated}: the stored bits \
                     must fit the allocated ones and HighBit be BitsStored - 1; the header is \
                     damaged"
                ),
            ));
        }
        if representation > 1 {
            return Err(bad(
                "PixelRepresentation (0028,0103)",
                format!(
                    "= {representation}: must be 0 (unsigned) or 1 (signed); the header is damaged"
                ),
            ));
        }
        let series = text(obj, tags::SERIES_INSTANCE_UID).unwrap_or_default();
        let series_number = text(obj, tags::SERIES_NUMBER);
        let label = [
            series_number.as_ref().map(|s| format!("#{s}")),
            text(obj, tags::SERIES_DESCRIPTION).map(|s| format!("'{s}'")),
            text(obj, tags::MODALITY).map(|s| format!("({s})")),
        ]
        .into_iter()
        .flatten()
        .collect::<Vec<_>>()
        .join(" ");
        Ok(Header {
            rows,
            cols,
            frames,
            bits_allocated,
            bits_stored,
            signed: representation == 1,
            series,
            series_number,
            series_label: label,
        })
    }
}

/// Where frame `f` lies and how its values scale: the per-frame functional group, else the
/// shared one, else the top-level attributes (classic images); RT Dose frames step along the
/// normal by `GridFrameOffsetVector`.
struct Geometry {
    position: DVec3,
    row_dir: DVec3,
    col_dir: DVec3,
    spacing: [f64; 2],
    slope: f64,
    inter: f64,
}

fn frame_geometry(
    path: &Path,
    obj: &InMemDicomObject,
    f: usize,
    frames: usize,
) -> Result<Geometry, ImageError> {
    let per_frame = item(obj, tags::PER_FRAME_FUNCTIONAL_GROUPS_SEQUENCE, f);
    let shared = item(obj, tags::SHARED_FUNCTIONAL_GROUPS_SEQUENCE, 0);
    // The first of: per-frame macro, shared macro, top level; a present but malformed value
    // is an error naming the field, never a default.
    let look = |seq: Tag, tag: Tag, n: usize, name: &str| -> Result<Option<Vec<f64>>, ImageError> {
        let bad = |detail: String| field(path, FORMAT, name, detail);
        for g in [per_frame, shared].into_iter().flatten() {
            if let Some(m) = item(g, seq, 0)
                && let Some(v) = floats(m, tag, n).map_err(bad)?
            {
                return Ok(Some(v));
            }
        }
        floats(obj, tag, n).map_err(bad)
    };
    let missing = |name: &str| {
        field(
            path,
            FORMAT,
            name,
            "is missing: the frames' place in space is unknown, so this is not a volume \
             (a secondary capture or a stripped file); convert the series with dcm2niix, or \
             export the slices as PNG/TIFF and give --spacing",
        )
    };
    const IOP: &str = "ImageOrientationPatient (0020,0037)";
    let iop = look(
        tags::PLANE_ORIENTATION_SEQUENCE,
        tags::IMAGE_ORIENTATION_PATIENT,
        6,
        IOP,
    )?
    .ok_or_else(|| missing(IOP))?;
    let row_dir = DVec3::new(iop[0], iop[1], iop[2]);
    let col_dir = DVec3::new(iop[3], iop[4], iop[5]);
    let unit = |v: DVec3| (v.length() - 1.0).abs() < 1e-3;
    if !(unit(row_dir) && unit(col_dir) && row_dir.dot(col_dir).abs() < 1e-3) {
        return Err(field(
            path,
            FORMAT,
            IOP,
            format!(
                "= {iop:?}: the row and column directions must be orthogonal unit vectors; \
                 the header is damaged"
            ),
        ));
    }
    const IPP: &str = "ImagePositionPatient (0020,0032)";
    let mut position = look(
        tags::PLANE_POSITION_SEQUENCE,
        tags::IMAGE_POSITION_PATIENT,
        3,
        IPP,
    )?
    .map(|p| DVec3::new(p[0], p[1], p[2]))
    .ok_or_else(|| missing(IPP))?;
    let mut scale = 1.0;
    if frames > 1 && per_frame.is_none() {
        // A classic multi-frame object: frames are placed by the RT Dose grid offsets.
        const OFFSETS: &str = "GridFrameOffsetVector (3004,000C)";
        let offsets = floats(obj, tags::GRID_FRAME_OFFSET_VECTOR, frames)
            .map_err(|d| field(path, FORMAT, OFFSETS, d))?
            .ok_or_else(|| missing(OFFSETS))?;
        position += row_dir.cross(col_dir) * (offsets[f] - offsets[0]);
        const SCALING: &str = "DoseGridScaling (3004,000E)";
        if let Some(s) =
            floats(obj, tags::DOSE_GRID_SCALING, 1).map_err(|d| field(path, FORMAT, SCALING, d))?
        {
            scale = s[0];
        }
    }
    const PS: &str = "PixelSpacing (0028,0030)";
    let ps = look(tags::PIXEL_MEASURES_SEQUENCE, tags::PIXEL_SPACING, 2, PS)?
        .ok_or_else(|| missing(PS))?;
    if !(ps[0] > 0.0 && ps[1] > 0.0) {
        return Err(field(
            path,
            FORMAT,
            PS,
            format!("= {ps:?}: spacings must be positive; the header is damaged"),
        ));
    }
    let rescale =
        |tag: Tag, name: &str| look(tags::PIXEL_VALUE_TRANSFORMATION_SEQUENCE, tag, 1, name);
    let slope =
        rescale(tags::RESCALE_SLOPE, "RescaleSlope (0028,1053)")?.map_or(1.0, |s| s[0]) * scale;
    let inter =
        rescale(tags::RESCALE_INTERCEPT, "RescaleIntercept (0028,1052)")?.map_or(0.0, |s| s[0]);
    if slope == 0.0 || !slope.is_finite() {
        return Err(field(
            path,
            FORMAT,
            "RescaleSlope (0028,1053) or DoseGridScaling (3004,000E)",
            format!("= {slope}: the values cannot be scaled by it; the header is damaged"),
        ));
    }
    Ok(Geometry {
        position,
        row_dir,
        col_dir,
        spacing: [ps[0], ps[1]],
        slope,
        inter,
    })
}

/// How `obj` says it is a Siemens mosaic (`ImageType` holding `MOSAIC`, or the private
/// `NumberOfImagesInMosaic` (0019,100A) above 1), else `None`.
fn mosaic(obj: &InMemDicomObject) -> Option<String> {
    let image_type = obj
        .element_opt(tags::IMAGE_TYPE)
        .ok()
        .flatten()
        .and_then(|e| e.to_multi_str().ok().map(|v| v.to_vec()))
        .unwrap_or_default();
    if image_type.iter().any(|v| v.trim() == "MOSAIC") {
        return Some(format!("ImageType {}", image_type.join("\\")));
    }
    uint(obj, Tag(0x0019, 0x100A))
        .filter(|&n| n > 1)
        .map(|n| format!("NumberOfImagesInMosaic (0019,100A) = {n}"))
}

/// Item `i` of the sequence `tag`.
fn item(obj: &InMemDicomObject, tag: Tag, i: usize) -> Option<&InMemDicomObject> {
    obj.element_opt(tag).ok().flatten()?.items()?.get(i)
}

/// Exactly `n` finite numbers (decimal strings or binary floats): `Ok(None)` when the element
/// is absent, an error (the detail) when it holds anything else, empty included (every field
/// read here is required when present).
fn floats(obj: &InMemDicomObject, tag: Tag, n: usize) -> Result<Option<Vec<f64>>, String> {
    let Some(e) = obj.element_opt(tag).ok().flatten() else {
        return Ok(None);
    };
    let shown = || e.to_str().map(|s| s.into_owned()).unwrap_or_default();
    match e.to_multi_float64() {
        Ok(v) if v.len() == n && v.iter().all(|x| x.is_finite()) => Ok(Some(v)),
        _ => Err(format!(
            "= {:?}: expected {n} finite number(s); the header is damaged",
            shown()
        )),
    }
}

/// One whole number; `None` when absent, malformed, or of an odd declared length (a binary
/// value cut: the parser would read its whole words and drop the odd byte).
fn uint(obj: &InMemDicomObject, tag: Tag) -> Option<u32> {
    let e = obj.element_opt(tag).ok().flatten()?;
    if e.length().get().is_some_and(|l| l % 2 == 1) {
        return None;
    }
    e.to_int::<u32>().ok()
}

fn text(obj: &InMemDicomObject, tag: Tag) -> Option<String> {
    let s = obj.element_opt(tag).ok().flatten()?.to_str().ok()?;
    let s = s.trim_matches(|c: char| c == '\0' || c.is_whitespace());
    (!s.is_empty()).then(|| s.to_string())
}

/// The name of a compressed transfer syntax, for the error.
fn syntax_name(uid: &str) -> &'static str {
    match uid {
        "1.2.840.10008.1.2.5" => "RLE Lossless",
        "1.2.840.10008.1.2.4.50" => "JPEG Baseline",
        "1.2.840.10008.1.2.4.51" => "JPEG Extended",
        "1.2.840.10008.1.2.4.57" | "1.2.840.10008.1.2.4.70" => "JPEG Lossless",
        "1.2.840.10008.1.2.4.80" | "1.2.840.10008.1.2.4.81" => "JPEG-LS",
        "1.2.840.10008.1.2.4.90" | "1.2.840.10008.1.2.4.91" => "JPEG 2000",
        "1.2.840.10008.1.2.4.201" | "1.2.840.10008.1.2.4.202" | "1.2.840.10008.1.2.4.203" => {
            "High-Throughput JPEG 2000"
        }
        _ => "compressed",
    }
}

/// All frames' values, masked to `BitsStored` and sign-extended, in the native type.
fn decode_pixels(
    path: &Path,
    ts: &str,
    value: Value<InMemDicomObject>,
    declared: Option<usize>,
    h: &Header,
) -> Result<Voxels, ImageError> {
    let prim = match value {
        Value::Primitive(p) => p,
        Value::PixelSequence(_) | Value::Sequence(_) => {
            return Err(field(
                path,
                FORMAT,
                "PixelData (7FE0,0010)",
                "is a sequence, not pixel values; the file is damaged",
            ));
        }
    };
    let n = h.samples(path)?;
    let big_endian = ts == "1.2.840.10008.1.2.2";
    // The values as little-endian bytes of `BitsAllocated` each.
    let float = matches!(prim, PrimitiveValue::F32(_) | PrimitiveValue::F64(_));
    // Each arm consumes the value: one copy of the pixels at a time beside the bytes.
    let bytes: Vec<u8> = match prim {
        PrimitiveValue::U8(v) if !big_endian || h.bits_allocated == 8 => v.into_vec(),
        PrimitiveValue::U16(v) if !big_endian || h.bits_allocated == 16 => {
            v.iter().flat_map(|w| w.to_le_bytes()).collect()
        }
        PrimitiveValue::F32(v) => v.iter().flat_map(|w| w.to_le_bytes()).collect(),
        PrimitiveValue::F64(v) => v.iter().flat_map(|w| w.to_le_bytes()).collect(),
        _ => {
            return Err(field(
                path,
                FORMAT,
                "PixelData (7FE0,0010)",
                format!(
                    "holds {}-bit values in a form this reader does not take (big-endian \
                     transfer syntax {ts}); convert the series with dcm2niix",
                    h.bits_allocated
                ),
            ));
        }
    };
    let size = h.bits_allocated as usize / 8;
    let need = n * size;
    let have = declared.unwrap_or(bytes.len());
    if have.min(bytes.len()) < need {
        return Err(ImageError::Truncated {
            path: path.to_path_buf(),
            detail: format!(
                "PixelData has {have} bytes, Rows x Columns x NumberOfFrames = {} x {} x {} at {} \
                 bits needs {need}",
                h.rows, h.cols, h.frames, h.bits_allocated
            ),
        });
    }
    // One padding byte only when the data is of odd length (DICOM values are even).
    if have > need + (need % 2) || have % 2 == 1 {
        return Err(field(
            path,
            FORMAT,
            "PixelData (7FE0,0010)",
            format!(
                "has {have} bytes, but Rows x Columns x NumberOfFrames = {} x {} x {} at {} bits \
                 needs exactly {need}: the header does not match the data (check Rows, \
                 Columns, NumberOfFrames and BitsAllocated)",
                h.rows, h.cols, h.frames, h.bits_allocated
            ),
        ));
    }
    let bytes = &bytes[..need];
    Ok(if float {
        let t = if size == 4 {
            super::super::Dtype::F32
        } else {
            super::super::Dtype::F64
        };
        Voxels::from_bytes(t, bytes, false)
    } else {
        integers(bytes, h)
    })
}

/// Integer pixels: the low `BitsStored` bits of each value, sign-extended when signed.
fn integers(bytes: &[u8], h: &Header) -> Voxels {
    let bits = h.bits_stored;
    let word = |c: &[u8]| -> u32 {
        c.iter()
            .rev()
            .fold(0u32, |acc, &b| (acc << 8) | u32::from(b))
    };
    let mask = if bits >= 32 {
        u32::MAX
    } else {
        (1u32 << bits) - 1
    };
    let signed = |v: u32| -> i32 {
        let v = v & mask;
        if bits < 32 && v >> (bits - 1) & 1 == 1 {
            (v | !mask) as i32
        } else {
            v as i32
        }
    };
    let size = h.bits_allocated as usize / 8;
    let it = bytes.chunks_exact(size).map(word);
    match (h.bits_allocated, h.signed) {
        (8, false) => Voxels::U8(it.map(|v| (v & mask) as u8).collect()),
        (8, true) => Voxels::I8(it.map(|v| signed(v) as i8).collect()),
        (16, false) => Voxels::U16(it.map(|v| (v & mask) as u16).collect()),
        (16, true) => Voxels::I16(it.map(|v| signed(v) as i16).collect()),
        (_, false) => Voxels::U32(it.map(|v| v & mask).collect()),
        (_, true) => Voxels::I32(it.map(signed).collect()),
    }
}
