//! NIfTI-1 reading (through the `nifti` crate, raw bytes only) and a small writer for tests.
//!
//! The voxel-to-world transform is computed here, not by `nifti` (whose `nalgebra_affine`
//! helpers panic on a negative `pixdim`): the standard NIfTI-1 rule, in this order:
//! 1. `sform_code > 0`: the rows `srow_x`, `srow_y`, `srow_z`;
//! 2. else `qform_code > 0`: the quaternion (`quatern_b/c/d`), offsets (`qoffset_x/y/z`),
//!    voxel sizes `|pixdim[1..4]|` (0 read as 1) and `qfac = pixdim[0]` (0 read as 1);
//! 3. else the diagonal `diag(pixdim[1..4])` (0 read as 1, a negative value flips the axis).

use super::volume::check_affine;
use super::{Dtype, ImageError, Volume, Voxel, Voxels};
use glam::{DAffine3, DMat3, DVec3};
use nifti::{NiftiHeader, NiftiObject, NiftiType, ReaderOptions};
use std::io::Write;
use std::path::Path;

/// Voxel-to-world affine of a NIfTI-1 header (see the module documentation for the rule).
/// Returns the affine and the name of the header field it came from.
pub fn nifti_affine(h: &NiftiHeader) -> (DAffine3, &'static str) {
    let f = |x: f32| x as f64;
    if h.sform_code > 0 {
        let r = [h.srow_x, h.srow_y, h.srow_z];
        let m = DMat3::from_cols(
            DVec3::new(f(r[0][0]), f(r[1][0]), f(r[2][0])),
            DVec3::new(f(r[0][1]), f(r[1][1]), f(r[2][1])),
            DVec3::new(f(r[0][2]), f(r[1][2]), f(r[2][2])),
        );
        let t = DVec3::new(f(r[0][3]), f(r[1][3]), f(r[2][3]));
        return (DAffine3::from_mat3_translation(m, t), "sform (srow_x/y/z)");
    }
    let px = |i: usize| {
        let d = f(h.pixdim[i]);
        if d == 0.0 || !d.is_finite() { 1.0 } else { d }
    };
    if h.qform_code > 0 {
        let q = Qform {
            b: f(h.quatern_b),
            c: f(h.quatern_c),
            d: f(h.quatern_d),
            offset: DVec3::new(f(h.quatern_x), f(h.quatern_y), f(h.quatern_z)),
            qfac: if h.pixdim[0] < 0.0 { -1.0 } else { 1.0 },
            pixdim: DVec3::new(px(1).abs(), px(2).abs(), px(3).abs()),
        };
        return (q.affine(), "qform (quatern_b/c/d, qoffset, pixdim)");
    }
    let d = DVec3::new(px(1), px(2), px(3));
    (DAffine3::from_mat3(DMat3::from_diagonal(d)), "pixdim[1..4]")
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

fn map_nifti_err(path: &Path, e: nifti::NiftiError) -> ImageError {
    use nifti::NiftiError as E;
    match e {
        E::IncompatibleLength(got, expected) => ImageError::Truncated {
            path: path.to_path_buf(),
            detail: format!(
                "the voxel data has {got} bytes, the header's dim and datatype need {expected}"
            ),
        },
        E::Io(io) if io.kind() == std::io::ErrorKind::UnexpectedEof => ImageError::Truncated {
            path: path.to_path_buf(),
            detail: format!("unexpected end of data: {io}"),
        },
        E::Io(io) if io.kind() == std::io::ErrorKind::NotFound => ImageError::Io {
            path: path.to_path_buf(),
            source: io,
        },
        E::Io(io) => ImageError::Truncated {
            path: path.to_path_buf(),
            detail: format!("read error: {io}"),
        },
        E::UnsupportedDataType(t) => ImageError::UnsupportedType {
            path: path.to_path_buf(),
            field: format!("{t:?}"),
        },
        other => ImageError::Nifti {
            path: path.to_path_buf(),
            detail: other.to_string(),
        },
    }
}

/// Read a NIfTI-1 volume (`.nii`, `.nii.gz`, or a `.hdr`/`.img` pair). The voxels keep their
/// on-disk type; `scl_slope`/`scl_inter` are stored as the volume's scaling (applied at sampling
/// time); the affine follows [`nifti_affine`].
///
/// Errors: truncated data, NIfTI-2 or garbage, 2D images (`dim[3] = 1`), 4D series
/// (`dim[4] > 1`), unsupported types (complex, RGB, 64-bit integers), singular transforms.
pub fn read_nifti(path: impl AsRef<Path>) -> Result<Volume, ImageError> {
    let path = path.as_ref();
    if !path.exists() {
        return Err(ImageError::Io {
            path: path.to_path_buf(),
            source: std::io::Error::new(std::io::ErrorKind::NotFound, "no such file"),
        });
    }
    let obj = ReaderOptions::new()
        .read_file(path)
        .map_err(|e| map_nifti_err(path, e))?;
    let h = obj.header().clone();
    let nd = h.dim[0].clamp(1, 7) as usize;
    let dims_all: Vec<u64> = h.dim[1..=nd].iter().map(|&d| d as u64).collect();
    let get = |i: usize| if i <= nd { h.dim[i] as usize } else { 1 };
    let dims = [get(1), get(2), get(3)];
    if dims.contains(&0) {
        return Err(ImageError::Empty {
            path: Some(path.to_path_buf()),
            dims,
        });
    }
    if nd < 3 || dims[2] == 1 {
        return Err(ImageError::NotAVolume {
            path: path.to_path_buf(),
            dims: dims_all,
            nz: dims[2] as u64,
        });
    }
    let frames: u64 = (4..=nd).map(|i| h.dim[i].max(1) as u64).product();
    if frames > 1 {
        return Err(ImageError::FourD {
            path: path.to_path_buf(),
            dims: dims_all,
            frames,
        });
    }
    let dtype = match h.data_type() {
        Ok(NiftiType::Uint8) => Dtype::U8,
        Ok(NiftiType::Int8) => Dtype::I8,
        Ok(NiftiType::Uint16) => Dtype::U16,
        Ok(NiftiType::Int16) => Dtype::I16,
        Ok(NiftiType::Uint32) => Dtype::U32,
        Ok(NiftiType::Int32) => Dtype::I32,
        Ok(NiftiType::Float32) => Dtype::F32,
        Ok(NiftiType::Float64) => Dtype::F64,
        Ok(t) => {
            return Err(ImageError::UnsupportedType {
                path: path.to_path_buf(),
                field: format!("datatype {} ({t:?})", h.datatype),
            });
        }
        Err(_) => {
            return Err(ImageError::UnsupportedType {
                path: path.to_path_buf(),
                field: format!("datatype code {}", h.datatype),
            });
        }
    };
    let big = h.endianness == nifti::Endianness::Big;
    let raw = obj.into_volume().into_raw_data();
    let n = dims[0] * dims[1] * dims[2];
    if raw.len() < n * dtype.size() {
        return Err(ImageError::Truncated {
            path: path.to_path_buf(),
            detail: format!(
                "the voxel data has {} bytes, {n} voxels of {dtype} need {}",
                raw.len(),
                n * dtype.size()
            ),
        });
    }
    let voxels = if dtype == Dtype::U8 && raw.len() == n {
        Voxels::U8(raw)
    } else {
        Voxels::from_bytes(dtype, &raw[..n * dtype.size()], big)
    };
    let (affine, field) = nifti_affine(&h);
    check_affine(&affine, Some(path), field)?;
    let vol = Volume::new(dims, voxels, affine)?
        .with_scaling(h.scl_slope as f64, h.scl_inter as f64)
        .with_source(path);
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
