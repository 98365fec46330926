//! NIfTI-1 and NIfTI-2 reading (ours: file format support; a NIfTI-1 header is parsed by the
//! `nifti` crate, a NIfTI-2 one by [`super::nifti_header`], the rest here), one frame of a
//! series, and a small NIfTI-1 writer for tests.
//!
//! The voxel-to-world transform is computed here, not by `nifti` (whose `nalgebra_affine`
//! helpers panic on a negative `pixdim`), by nibabel's rules (`get_best_affine`, after the
//! header fixes nibabel applies on load), in this order:
//! 1. `sform_code` 1 to 4: the rows `srow_x`, `srow_y`, `srow_z`;
//! 2. else `qform_code` 1 to 4: the quaternion (`quatern_b/c/d`), offsets (`qoffset_x/y/z`),
//!    voxel sizes `|pixdim[1..4]|` and `qfac` = -1 if `pixdim[0]` is -1, else 1;
//! 3. else the diagonal `diag(|pixdim[1..4]|)` (the NIfTI-1 standard's method 1; nibabel's
//!    fallback also flips x and centres the grid, an Analyze convention not followed here).
//!
//! A negative `pixdim` never mirrors the mesh: as nibabel, its absolute value is used. Codes
//! outside 0 to 4 count as 0 (nibabel resets them). [`read_nifti`] rejects what nibabel would
//! silently repair into something else: a `pixdim[1..4]` that is 0, NaN or infinite when the
//! transform uses it (methods 2 and 3), and a quaternion with `b² + c² + d² > 1`.

use super::nifti_header::{Header, NIFTI2_SIZE, is_nifti2, parse_nifti2};
use super::volume::check_affine;
use super::{Dtype, ImageError, Volume, Voxel, Voxels};
use glam::{DAffine3, DMat3, DVec3};
use nifti::NiftiHeader;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Whether a `qform_code` / `sform_code` selects its transform (valid codes are 1 to 4).
fn code_set(code: i64) -> bool {
    (1..=4).contains(&code)
}

/// Voxel-to-world affine of a NIfTI-1 header (see the module documentation for the rule).
/// Returns the affine and the name of the header field it came from.
pub fn nifti_affine(h: &NiftiHeader) -> (DAffine3, &'static str) {
    header_affine(&Header::from_nifti1(h))
}

/// [`nifti_affine`] of NIfTI-1 and NIfTI-2 headers.
fn header_affine(h: &Header) -> (DAffine3, &'static str) {
    if code_set(h.sform_code) {
        let r = h.srow;
        let m = DMat3::from_cols(
            DVec3::new(r[0][0], r[1][0], r[2][0]),
            DVec3::new(r[0][1], r[1][1], r[2][1]),
            DVec3::new(r[0][2], r[1][2], r[2][2]),
        );
        let t = DVec3::new(r[0][3], r[1][3], r[2][3]);
        return (DAffine3::from_mat3_translation(m, t), "sform (srow_x/y/z)");
    }
    // nibabel's header fixes: 0 becomes 1, a negative value its absolute value.
    let px = |i: usize| {
        let d = h.pixdim[i].abs();
        if d == 0.0 || !d.is_finite() { 1.0 } else { d }
    };
    if code_set(h.qform_code) {
        let q = Qform {
            b: h.quatern_b,
            c: h.quatern_c,
            d: h.quatern_d,
            offset: DVec3::from_array(h.qoffset),
            qfac: if h.pixdim[0] == -1.0 { -1.0 } else { 1.0 },
            pixdim: DVec3::new(px(1), px(2), px(3)),
        };
        return (q.affine(), "qform (quatern_b/c/d, qoffset, pixdim)");
    }
    let d = DVec3::new(px(1), px(2), px(3));
    (DAffine3::from_mat3(DMat3::from_diagonal(d)), "pixdim[1..4]")
}

/// [`nifti_affine`] after checking the fields it uses: `pixdim[1..4]` finite and non-zero
/// (qform and pixdim methods), the quaternion's `b² + c² + d² <= 1` (qform, with nibabel's
/// tolerance of 3 f32 epsilons).
fn checked_affine(path: &Path, h: &Header) -> Result<(DAffine3, &'static str), ImageError> {
    if !code_set(h.sform_code) {
        for i in 1..=3 {
            let d = h.pixdim[i];
            if d == 0.0 || !d.is_finite() {
                return Err(bad_header(
                    path,
                    &format!("pixdim[{i}]"),
                    format!(
                        "= {d}: the voxel size must be a finite non-zero number (there is no \
                         sform, so the transform uses it); fix the header, e.g. with nibabel"
                    ),
                ));
            }
        }
    }
    if !code_set(h.sform_code) && code_set(h.qform_code) {
        let (b, c, d) = (h.quatern_b, h.quatern_c, h.quatern_d);
        let n2 = b * b + c * c + d * d;
        if !(n2 <= 1.0 + h.quaternion_tolerance()) {
            return Err(bad_header(
                path,
                "quatern_b/c/d",
                format!(
                    "= ({b}, {c}, {d}): b² + c² + d² = {n2} exceeds 1, so this is not a rotation \
                     quaternion; fix the qform (or set an sform)"
                ),
            ));
        }
    }
    Ok(header_affine(h))
}

/// A NIfTI-1 quaternion transform (the `qform_code > 0` method).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Qform {
    pub b: f64,
    pub c: f64,
    pub d: f64,
    pub offset: DVec3,
    /// `pixdim[0]`: +1 or -1 (flips the third axis).
    pub qfac: f64,
    /// Voxel sizes (positive).
    pub pixdim: DVec3,
}

impl Qform {
    /// The affine `x = R * diag(pixdim) * diag(1, 1, qfac) * ijk + offset`.
    pub fn affine(&self) -> DAffine3 {
        let (b, c, d) = (self.b, self.c, self.d);
        let a2 = 1.0 - (b * b + c * c + d * d);
        // nifti1_io: if a2 is (slightly) negative, renormalise (b, c, d) and take a = 0.
        let (a, b, c, d) = if a2 < 1e-7 {
            let n = (b * b + c * c + d * d).sqrt().max(f64::MIN_POSITIVE);
            (0.0, b / n, c / n, d / n)
        } else {
            (a2.sqrt(), b, c, d)
        };
        let r = DMat3::from_cols(
            DVec3::new(
                a * a + b * b - c * c - d * d,
                2.0 * (b * c + a * d),
                2.0 * (b * d - a * c),
            ),
            DVec3::new(
                2.0 * (b * c - a * d),
                a * a + c * c - b * b - d * d,
                2.0 * (c * d + a * b),
            ),
            DVec3::new(
                2.0 * (b * d + a * c),
                2.0 * (c * d - a * b),
                a * a + d * d - c * c - b * b,
            ),
        );
        let qfac = if self.qfac < 0.0 { -1.0 } else { 1.0 };
        let s = DVec3::new(self.pixdim.x, self.pixdim.y, self.pixdim.z * qfac);
        DAffine3::from_mat3_translation(r * DMat3::from_diagonal(s), self.offset)
    }
}

/// Read a file, decompressing it (see [`gunzip`]) if its name ends with `.gz`.
fn read_bytes(path: &Path) -> Result<Vec<u8>, ImageError> {
    let raw = std::fs::read(path).map_err(|source| ImageError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let gz = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("gz"));
    if gz { gunzip(path, &raw) } else { Ok(raw) }
}

/// Decompress every gzip member of `raw` to its end, so that each member's CRC-32 and length
/// (ISIZE) are checked (flate2 checks them only when a member is read to its end). Zero bytes
/// after the last member are allowed (gzip and Python's gzip module skip them); anything else
/// after it is an error, and so is a corrupt deflate stream (called corrupt, not truncated).
pub(crate) fn gunzip(path: &Path, raw: &[u8]) -> Result<Vec<u8>, ImageError> {
    use std::io::Read;
    let corrupt = |detail: String| ImageError::CorruptGzip {
        path: path.to_path_buf(),
        detail,
    };
    if !raw.starts_with(&[0x1f, 0x8b]) {
        return Err(corrupt(
            "the file does not start with the gzip magic bytes 1f 8b, although its name ends \
             with .gz"
                .into(),
        ));
    }
    // ISIZE of the last member: a hint only (it is checked below, modulo 2^32).
    let hint = raw.len().checked_sub(4).map_or(0, |i| {
        u32::from_le_bytes(raw[i..].try_into().expect("4 bytes")) as usize
    });
    let mut out = Vec::with_capacity(hint.min(raw.len().saturating_mul(1032)));
    let mut rest = raw;
    loop {
        let mut dec = flate2::bufread::GzDecoder::new(rest);
        dec.read_to_end(&mut out).map_err(|e| {
            if e.kind() == std::io::ErrorKind::UnexpectedEof {
                ImageError::Truncated {
                    path: path.to_path_buf(),
                    detail: "the gzip stream ends before its end marker and checksum".into(),
                }
            } else {
                corrupt(e.to_string())
            }
        })?;
        rest = dec.into_inner();
        if rest.iter().all(|&b| b == 0) {
            return Ok(out);
        }
        if !rest.starts_with(&[0x1f, 0x8b]) {
            return Err(corrupt(format!(
                "{} bytes of trailing garbage after the gzip stream",
                rest.len()
            )));
        }
    }
}

/// Parse the NIfTI-1 (348 bytes) or NIfTI-2 (540 bytes) header at the start of `b`.
fn parse_header(path: &Path, b: &[u8]) -> Result<Header, ImageError> {
    if is_nifti2(b) {
        if b.len() < NIFTI2_SIZE {
            return Err(ImageError::Truncated {
                path: path.to_path_buf(),
                detail: format!(
                    "a NIfTI-2 header has {NIFTI2_SIZE} bytes, the file has {}",
                    b.len()
                ),
            });
        }
        return parse_nifti2(b).map_err(|detail| ImageError::Nifti {
            path: path.to_path_buf(),
            detail,
        });
    }
    if b.len() < HEADER_SIZE {
        return Err(ImageError::Truncated {
            path: path.to_path_buf(),
            detail: format!(
                "a NIfTI-1 header has {HEADER_SIZE} bytes, the file has {}",
                b.len()
            ),
        });
    }
    let magic = &b[344..348];
    if magic != b"n+1\0" && magic != b"ni1\0" {
        let shown: String = String::from_utf8_lossy(magic).escape_debug().collect();
        return Err(ImageError::Nifti {
            path: path.to_path_buf(),
            detail: format!(
                "the magic (bytes 344-347) is \"{shown}\", expected \"n+1\" (a .nii file) or \
                 \"ni1\" (a .hdr/.img pair); Analyze 7.5 headers are not read"
            ),
        });
    }
    let h = NiftiHeader::from_reader(b).map_err(|e| ImageError::Nifti {
        path: path.to_path_buf(),
        detail: e.to_string(),
    })?;
    if h.sizeof_hdr != HEADER_SIZE as i32 {
        return Err(bad_header(
            path,
            "sizeof_hdr",
            format!(
                "= {} (bytes 0-3), but a NIfTI-1 header has {HEADER_SIZE}: the file is damaged \
                 or not NIfTI-1",
                h.sizeof_hdr
            ),
        ));
    }
    Ok(Header::from_nifti1(&h))
}

/// Size of a NIfTI-1 header; a single file's voxels start at `vox_offset >= 352` (NIfTI-2:
/// 540 and 544).
const HEADER_SIZE: usize = 348;

fn bad_header(path: &Path, field: &str, detail: String) -> ImageError {
    ImageError::BadHeader {
        path: path.to_path_buf(),
        field: field.to_string(),
        detail,
    }
}

/// What the header says about the voxel data.
struct Layout {
    dims: [usize; 3],
    dtype: Dtype,
    /// Byte offset of the voxels in the data file (`vox_offset`).
    offset: usize,
    /// The 3D volumes stored one after the other (`dim[4]`, 1 for a 3D file).
    frames: usize,
    /// The one to read (`--frame`; 0 for a 3D file).
    frame: usize,
}

/// Check `dim`, `datatype` and `vox_offset` (`single`: data in the header's file) and the
/// requested `frame` of a series.
fn layout(
    path: &Path,
    h: &Header,
    single: bool,
    frame: Option<usize>,
) -> Result<Layout, ImageError> {
    let dim: Vec<i64> = h.dim.to_vec();
    if !(1..=7).contains(&dim[0]) {
        return Err(bad_header(
            path,
            "dim[0]",
            format!("= {}: the number of dimensions must be 1 to 7", dim[0]),
        ));
    }
    let nd = dim[0] as usize;
    if let Some(i) = (1..=nd).find(|&i| dim[i] < 1) {
        return Err(bad_header(
            path,
            &format!("dim[{i}]"),
            format!("= {}: every dimension must be at least 1", dim[i]),
        ));
    }
    let dims_all: Vec<u64> = dim[1..=nd].iter().map(|&d| d as u64).collect();
    let get = |i: usize| if i <= nd { dim[i] as usize } else { 1 };
    let dims = [get(1), get(2), get(3)];
    if nd < 3 || dims[2] == 1 {
        return Err(ImageError::NotAVolume {
            path: path.to_path_buf(),
            dims: dims_all,
            nz: dims[2] as u64,
        });
    }
    let frames = series_frames(path, &dims_all, frame)?;
    let dtype = dtype_of(path, h)?;
    if h.bitpix as i64 != 8 * dtype.size() as i64 {
        return Err(bad_header(
            path,
            "bitpix",
            format!(
                "= {} but datatype {} ({dtype}) has {} bits a voxel: the header is damaged \
                 (rewrite it with bitpix = {})",
                h.bitpix,
                h.datatype,
                8 * dtype.size(),
                8 * dtype.size()
            ),
        ));
    }
    let off = h.vox_offset;
    let header = if h.version == 2 {
        NIFTI2_SIZE
    } else {
        HEADER_SIZE
    };
    let min = if single { (header + 4) as f64 } else { 0.0 };
    if !(off.is_finite() && off.fract() == 0.0 && off >= min && off <= 1e15) {
        return Err(bad_header(
            path,
            "vox_offset",
            format!(
                "= {off}: the voxel data offset must be a whole number of bytes, at least {min} \
                 {}",
                if single {
                    "in a .nii file (the header and 4 extension bytes come first)"
                } else {
                    "in the .img file"
                }
            ),
        ));
    }
    Ok(Layout {
        dims,
        dtype,
        offset: off as usize,
        frames: frames as usize,
        frame: frame.unwrap_or(0),
    })
}

/// The number of 3D volumes of a file of dimensions `dims_all` (`dim[1..=dim[0]]`), checked
/// against the requested `frame`: a series (`dim[4] > 1`) needs one, a 3D file takes only 0,
/// and dimensions past the fourth (vector or tensor voxels) are not frames.
fn series_frames(path: &Path, dims_all: &[u64], frame: Option<usize>) -> Result<u64, ImageError> {
    let frames = dims_all.get(3).copied().unwrap_or(1);
    let beyond: u64 = dims_all.iter().skip(4).product();
    let err = |detail: String| ImageError::Frame {
        path: path.to_path_buf(),
        dims: dims_all.to_vec(),
        detail,
    };
    if beyond > 1 {
        return Err(err(format!(
            "dim[5..] = {:?}: each voxel holds {beyond} values (a vector or tensor image), not one intensity; extract one component first (e.g. with nibabel)",
            &dims_all[4..]
        )));
    }
    match frame {
        None if frames > 1 => Err(ImageError::FourD {
            path: path.to_path_buf(),
            dims: dims_all.to_vec(),
            frames,
        }),
        Some(k) if k as u64 >= frames => Err(err(format!(
            "--frame {k}: the file has {frames} frame(s) (dim[4] = {frames}), numbered 0 to {}",
            frames - 1
        ))),
        _ => Ok(frames),
    }
}

fn dtype_of(path: &Path, h: &Header) -> Result<Dtype, ImageError> {
    let other = |name: &str| ImageError::UnsupportedType {
        path: path.to_path_buf(),
        field: format!("datatype {} ({name})", h.datatype),
    };
    Ok(match h.datatype {
        2 => Dtype::U8,
        256 => Dtype::I8,
        512 => Dtype::U16,
        4 => Dtype::I16,
        768 => Dtype::U32,
        8 => Dtype::I32,
        16 => Dtype::F32,
        64 => Dtype::F64,
        // The other codes of the standard (nifti1.h), named as the `nifti` crate names them.
        1 => return Err(other("Binary")),
        32 => return Err(other("Complex64")),
        128 => return Err(other("Rgb24")),
        1024 => Dtype::I64,
        1280 => Dtype::U64,
        1536 => return Err(other("Float128")),
        1792 => return Err(other("Complex128")),
        2048 => return Err(other("Complex256")),
        2304 => return Err(other("Rgba32")),
        _ => {
            return Err(ImageError::UnsupportedType {
                path: path.to_path_buf(),
                field: format!("datatype code {}", h.datatype),
            });
        }
    })
}

/// `scl_slope`/`scl_inter` as nibabel reads them: a slope of 0 or NaN means no scaling (the
/// intercept is then ignored); an infinite slope, or a non-finite intercept with a valid slope,
/// is an error.
fn scaling(path: &Path, h: &Header) -> Result<(f64, f64), ImageError> {
    let (slope, inter) = (h.scl_slope, h.scl_inter);
    if slope == 0.0 || slope.is_nan() {
        return Ok((1.0, 0.0));
    }
    if slope.is_infinite() {
        return Err(bad_header(
            path,
            "scl_slope",
            format!("= {slope}: the intensity scale must be finite (0 or NaN for no scaling)"),
        ));
    }
    if !inter.is_finite() {
        return Err(bad_header(
            path,
            "scl_inter",
            format!("= {inter} with scl_slope = {slope}: the intensity offset must be finite"),
        ));
    }
    Ok((slope, inter))
}

/// The header file and the data file of `path` (the same file for `.nii`/`.nii.gz`; for a
/// `.hdr`/`.img` pair, given either name, the other one next to it, plain or gzipped).
fn pair_paths(path: &Path) -> (PathBuf, PathBuf) {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let lower = name.to_ascii_lowercase();
    let sibling = |from: &str, to: &str| -> Option<PathBuf> {
        let stem_len = if lower.ends_with(&format!("{from}.gz")) {
            name.len() - from.len() - 3
        } else if lower.ends_with(from) {
            name.len() - from.len()
        } else {
            return None;
        };
        let stem = &name[..stem_len];
        let plain = path.with_file_name(format!("{stem}{to}"));
        let gz = path.with_file_name(format!("{stem}{to}.gz"));
        Some(if !plain.exists() && gz.exists() {
            gz
        } else {
            plain
        })
    };
    if let Some(hdr) = sibling(".img", ".hdr") {
        (hdr, path.to_path_buf())
    } else if let Some(img) = sibling(".hdr", ".img") {
        (path.to_path_buf(), img)
    } else {
        (path.to_path_buf(), path.to_path_buf())
    }
}

/// Read a NIfTI-1 or NIfTI-2 volume (`.nii`, `.nii.gz`, or a `.hdr`/`.img` pair, each possibly
/// gzipped). The voxels keep their on-disk type and are read from `vox_offset`;
/// `scl_slope`/`scl_inter` are stored as the volume's scaling (applied at sampling time, see
/// [`scaling`]); the affine follows [`nifti_affine`] and must pass the volume's transform checks.
///
/// Strict: a gzip stream is read to its end (checksums and lengths checked), `sizeof_hdr` must
/// be 348 (NIfTI-2: 540, with its magic), `vox_offset` a whole number (at least 352 in a `.nii`,
/// NIfTI-2 544), and the data after it at least `dim` x datatype bytes (bytes after those are
/// ignored, as nibabel does, with a [`Volume::notes`] entry). Errors name the field: truncated
/// or corrupt data, garbage, 2D images (`dim[3] = 1`), 4D series (`dim[4] > 1`: see
/// [`read_nifti_frame`]), unsupported types (complex, RGB, 64-bit integers), bad `pixdim` or
/// scaling, unusable transforms.
pub fn read_nifti(path: impl AsRef<Path>) -> Result<Volume, ImageError> {
    read_nifti_frame(path, None)
}

/// [`read_nifti`] of frame `frame` of a series (`dim[4] > 1`, the volumes stored one after the
/// other: frame `k` starts `k` volumes after `vox_offset`). `None` reads a 3D file and refuses a
/// series; `Some(0)` also reads a 3D file. The whole series must be in the file (a shorter
/// file is truncated, as for a 3D one). A volume read from a series has a [`Volume::notes`]
/// entry naming the frame.
///
/// ```no_run
/// // The second volume of nibabel's `example4d.nii.gz` (128 x 96 x 24 x 2).
/// let vol = oracle::image::read_nifti_frame("example4d.nii.gz", Some(1))?;
/// assert_eq!(vol.dims(), [128, 96, 24]);
/// # Ok::<(), oracle::image::ImageError>(())
/// ```
pub fn read_nifti_frame(
    path: impl AsRef<Path>,
    frame: Option<usize>,
) -> Result<Volume, ImageError> {
    let path = path.as_ref();
    if !path.exists() {
        return Err(ImageError::Io {
            path: path.to_path_buf(),
            source: std::io::Error::new(std::io::ErrorKind::NotFound, "no such file"),
        });
    }
    let (hdr_path, img_path) = pair_paths(path);
    let hbytes = read_bytes(&hdr_path)?;
    let h = parse_header(&hdr_path, &hbytes)?;
    let single = h.single;
    if single != (hdr_path == img_path) {
        return Err(ImageError::Nifti {
            path: hdr_path,
            detail: if single {
                "the magic \"n+1\" says a single .nii file, but the name is a .hdr/.img pair's"
                    .into()
            } else {
                "the magic \"ni1\" says a .hdr/.img pair, but the name ends with .nii: rename \
                 it .hdr and put the voxels in a .img next to it"
                    .into()
            },
        });
    }
    let lay = layout(&hdr_path, &h, single, frame)?;
    let dbytes = if single {
        hbytes
    } else {
        read_bytes(&img_path)?
    };
    let n = lay.dims.iter().try_fold(1usize, |a, &d| a.checked_mul(d));
    let one = n.and_then(|n| n.checked_mul(lay.dtype.size()));
    let need = one.and_then(|b| b.checked_mul(lay.frames));
    let avail = dbytes.len().saturating_sub(lay.offset);
    let (Some(n), Some(one), Some(need)) = (n, one, need) else {
        return Err(ImageError::TooLarge {
            n: usize::MAX,
            max: usize::MAX / 8,
        });
    };
    if lay.offset > dbytes.len() || avail < need {
        return Err(ImageError::Truncated {
            path: img_path,
            detail: format!(
                "the voxel data after vox_offset {} has {avail} bytes, {n} voxels of {}{} need \
                 {need}",
                lay.offset,
                lay.dtype,
                if lay.frames > 1 {
                    format!(" in each of {} frames", lay.frames)
                } else {
                    String::new()
                }
            ),
        });
    }
    // nibabel reads the voxels it needs and ignores what follows; so do we, with a note.
    let extra = (avail > need).then(|| {
        format!(
            "{}: {} byte(s) after the voxel data (vox_offset {} + {need} bytes for dim and \
             datatype) ignored, as nibabel does",
            img_path.display(),
            avail - need,
            lay.offset
        )
    });
    let (slope, inter) = scaling(&hdr_path, &h)?;
    let (affine, field) = checked_affine(&hdr_path, &h)?;
    let big = h.big_endian;
    let start = lay.offset + lay.frame * one;
    let (voxels, held) = if lay.dtype == Dtype::U8 {
        let mut d = dbytes;
        d.truncate(start + one);
        d.drain(..start);
        (Voxels::U8(d), None)
    } else {
        let b = &dbytes[start..start + one];
        super::volume::decode_voxels(&img_path, lay.dims, lay.dtype, b, big)?
    };
    check_affine(&affine, Some(&hdr_path), field)?;
    let mut vol = Volume::new(lay.dims, voxels, affine)?
        .with_scaling(slope, inter)
        .with_source(path);
    for note in extra.into_iter().chain(held) {
        vol = vol.with_note(note);
    }
    if lay.frames > 1 {
        vol = vol.with_note(format!(
            "{}: frame {} of {} (dim[4] = {}; --frame)",
            path.display(),
            lay.frame,
            lay.frames,
            lay.frames
        ));
    }
    Ok(vol)
}

/// Options of [`write_nifti`] (a minimal NIfTI-1 writer, for tests and fixtures).
#[derive(Clone, Debug, Default)]
pub struct NiftiWriteOptions {
    /// Write the volume's affine as the sform (`sform_code = 1`). Default true via [`Self::new`].
    pub sform: bool,
    /// Write this quaternion transform (`qform_code = 1`, and `pixdim[0] = qfac`).
    pub qform: Option<Qform>,
    /// `pixdim[1..4]` (default: the affine's column norms).
    pub pixdim: Option<[f64; 3]>,
    /// Big-endian byte order (default little-endian).
    pub big_endian: bool,
    /// Gzip the output (`.nii.gz`). Default: from the file name.
    pub gzip: Option<bool>,
    /// Override `dim` (e.g. to write a deliberately 2D header in tests).
    pub dim_override: Option<[u16; 8]>,
}

impl NiftiWriteOptions {
    /// sform from the volume's affine, little endian, gzip by extension.
    pub fn new() -> Self {
        NiftiWriteOptions {
            sform: true,
            ..Default::default()
        }
    }
}

fn datatype_code(d: Dtype) -> (i16, i16) {
    match d {
        Dtype::U8 => (2, 8),
        Dtype::I16 => (4, 16),
        Dtype::I32 => (8, 32),
        Dtype::F32 => (16, 32),
        Dtype::F64 => (64, 64),
        Dtype::I8 => (256, 8),
        Dtype::U16 => (512, 16),
        Dtype::U32 => (768, 32),
        Dtype::I64 => (1024, 64),
        Dtype::U64 => (1280, 64),
    }
}

struct Hdr {
    buf: Vec<u8>,
    be: bool,
}
impl Hdr {
    fn put(&mut self, off: usize, bytes_le: &[u8]) {
        let mut b = bytes_le.to_vec();
        if self.be {
            b.reverse();
        }
        self.buf[off..off + b.len()].copy_from_slice(&b);
    }
    fn i16(&mut self, off: usize, v: i16) {
        self.put(off, &v.to_le_bytes());
    }
    fn i32(&mut self, off: usize, v: i32) {
        self.put(off, &v.to_le_bytes());
    }
    fn f32(&mut self, off: usize, v: f64) {
        self.put(off, &(v as f32).to_le_bytes());
    }
}

/// Write `vol` as a single-file NIfTI-1 (`.nii`, or `.nii.gz` when gzipped), with the raw voxels,
/// the volume's scaling as `scl_slope`/`scl_inter`, and the transforms chosen in `opts`.
pub fn write_nifti(
    path: impl AsRef<Path>,
    vol: &Volume,
    opts: &NiftiWriteOptions,
) -> Result<(), ImageError> {
    let path = path.as_ref();
    let io = |source| ImageError::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut h = Hdr {
        buf: vec![0u8; 352],
        be: opts.big_endian,
    };
    h.i32(0, 348);
    h.buf[38] = b'r';
    let d = vol.dims();
    let dim = opts
        .dim_override
        .unwrap_or([3, d[0] as u16, d[1] as u16, d[2] as u16, 1, 1, 1, 1]);
    for (i, &v) in dim.iter().enumerate() {
        h.i16(40 + 2 * i, v as i16);
    }
    let (code, bitpix) = datatype_code(vol.dtype());
    h.i16(70, code);
    h.i16(72, bitpix);
    let sp = vol.spacing();
    let pix = opts.pixdim.unwrap_or([sp.x, sp.y, sp.z]);
    let qfac = opts
        .qform
        .map_or(1.0, |q| if q.qfac < 0.0 { -1.0 } else { 1.0 });
    h.f32(76, qfac);
    for (i, &p) in pix.iter().enumerate() {
        h.f32(80 + 4 * i, p);
    }
    h.f32(108, 352.0);
    let (slope, inter) = vol.scaling();
    h.f32(112, slope);
    h.f32(116, inter);
    h.buf[123] = 2; // xyzt_units: millimetres
    if let Some(q) = opts.qform {
        h.i16(252, 1);
        h.f32(256, q.b);
        h.f32(260, q.c);
        h.f32(264, q.d);
        h.f32(268, q.offset.x);
        h.f32(272, q.offset.y);
        h.f32(276, q.offset.z);
    }
    if opts.sform {
        h.i16(254, 1);
        let a = vol.affine();
        let m = a.matrix3;
        for r in 0..3 {
            let row = [m.x_axis[r], m.y_axis[r], m.z_axis[r], a.translation[r]];
            for (c, v) in row.iter().enumerate() {
                h.f32(280 + 16 * r + 4 * c, *v);
            }
        }
    }
    h.buf[344..348].copy_from_slice(b"n+1\0");
    let mut data = h.buf;
    with_voxels_be(vol.voxels(), opts.big_endian, &mut data);
    let gz = opts.gzip.unwrap_or_else(|| {
        path.extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("gz"))
    });
    let mut f = std::fs::File::create(path).map_err(io)?;
    if gz {
        let mut enc = flate2::write::GzEncoder::new(f, flate2::Compression::default());
        enc.write_all(&data).map_err(io)?;
        enc.finish().map_err(io)?;
    } else {
        f.write_all(&data).map_err(io)?;
    }
    Ok(())
}

fn with_voxels_be(v: &Voxels, be: bool, out: &mut Vec<u8>) {
    fn push<T: Voxel>(d: &[T], be: bool, out: &mut Vec<u8>) {
        let s = T::DTYPE.size();
        for &x in d {
            let start = out.len();
            x.push_le(out);
            if be {
                out[start..start + s].reverse();
            }
        }
    }
    super::with_voxels!(v, d => push(d, be, out))
}
