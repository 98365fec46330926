//! The NIfTI header fields the reader uses, from a NIfTI-1 header (348 bytes, parsed by the
//! `nifti` crate) or a NIfTI-2 one (540 bytes, parsed here; the `nifti` crate reads NIfTI-1
//! only). Ours: file format support. NIfTI-2 is NIfTI-1 with 64-bit `dim` and `vox_offset`
//! and double-precision floats (the layout of `nifti2.h`, as nibabel's `Nifti2Header`):
//! the values are kept at their width, so a NIfTI-2 sform is used to the last bit.

use nifti::NiftiHeader;

/// NIfTI-1 or NIfTI-2 header fields, at the wider types (NIfTI-1 values convert exactly).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Header {
    /// 1 or 2.
    pub version: u8,
    /// `sizeof_hdr` as stored (348 or 540 in a valid file).
    pub sizeof_hdr: i64,
    /// Magic `n+1`/`n+2` (voxels in the header's file) rather than `ni1`/`ni2` (a pair).
    pub single: bool,
    pub dim: [i64; 8],
    pub datatype: i16,
    pub bitpix: i16,
    pub pixdim: [f64; 8],
    pub vox_offset: f64,
    pub scl_slope: f64,
    pub scl_inter: f64,
    pub qform_code: i64,
    pub sform_code: i64,
    pub quatern_b: f64,
    pub quatern_c: f64,
    pub quatern_d: f64,
    pub qoffset: [f64; 3],
    pub srow: [[f64; 4]; 3],
    pub big_endian: bool,
}

impl Header {
    /// The fields of a NIfTI-1 header (`dim` read as signed, as the standard stores it).
    pub fn from_nifti1(h: &NiftiHeader) -> Header {
        let f = |x: f32| x as f64;
        Header {
            version: 1,
            sizeof_hdr: h.sizeof_hdr as i64,
            single: &h.magic == b"n+1\0",
            dim: h.dim.map(|d| d as i16 as i64),
            datatype: h.datatype,
            bitpix: h.bitpix,
            pixdim: h.pixdim.map(f),
            vox_offset: f(h.vox_offset),
            scl_slope: f(h.scl_slope),
            scl_inter: f(h.scl_inter),
            qform_code: h.qform_code as i64,
            sform_code: h.sform_code as i64,
            quatern_b: f(h.quatern_b),
            quatern_c: f(h.quatern_c),
            quatern_d: f(h.quatern_d),
            qoffset: [f(h.quatern_x), f(h.quatern_y), f(h.quatern_z)],
            srow: [h.srow_x.map(f), h.srow_y.map(f), h.srow_z.map(f)],
            big_endian: h.endianness == nifti::Endianness::Big,
        }
    }

    /// The tolerance on `b² + c² + d² <= 1` of a qform: 3 epsilons of the stored float width
    /// (nibabel's `quaternion_threshold`).
    pub fn quaternion_tolerance(&self) -> f64 {
        if self.version == 2 {
            3.0 * f64::EPSILON
        } else {
            3.0 * f32::EPSILON as f64
        }
    }
}

/// Size of a NIfTI-2 header.
pub(crate) const NIFTI2_SIZE: usize = 540;

/// Whether the first four bytes are a NIfTI-2 `sizeof_hdr` (540, either byte order).
pub(crate) fn is_nifti2(b: &[u8]) -> bool {
    b.len() >= 4 && {
        let w: [u8; 4] = b[..4].try_into().expect("4 bytes");
        i32::from_le_bytes(w) == 540 || i32::from_be_bytes(w) == 540
    }
}

/// Parse a NIfTI-2 header (`b` holds at least [`NIFTI2_SIZE`] bytes and starts with
/// `sizeof_hdr` = 540). Errors: the magic (bytes 4 to 11: `n+2\0` or `ni2\0`, then
/// `\r\n\x1a\n`) is not NIfTI-2's, named as in the file.
pub(crate) fn parse_nifti2(b: &[u8]) -> Result<Header, String> {
    let big = i32::from_le_bytes(b[..4].try_into().expect("4 bytes")) != 540;
    let magic = &b[4..8];
    if (magic != b"n+2\0" && magic != b"ni2\0") || &b[8..12] != b"\r\n\x1a\n" {
        let shown: String = String::from_utf8_lossy(&b[4..12]).escape_debug().collect();
        return Err(format!(
            "sizeof_hdr is 540 (NIfTI-2) but the magic (bytes 4-11) is \"{shown}\", expected \
             \"n+2\\0\\r\\n\\x1a\\n\" (a .nii file) or \"ni2\\0...\" (a .hdr/.img pair)"
        ));
    }
    let bytes = |at: usize, n: usize| -> Vec<u8> {
        let mut v = b[at..at + n].to_vec();
        if big {
            v.reverse();
        }
        v
    };
    let i16_at = |at: usize| i16::from_le_bytes(bytes(at, 2).try_into().expect("2"));
    let i32_at = |at: usize| i32::from_le_bytes(bytes(at, 4).try_into().expect("4"));
    let i64_at = |at: usize| i64::from_le_bytes(bytes(at, 8).try_into().expect("8"));
    let f64_at = |at: usize| f64::from_le_bytes(bytes(at, 8).try_into().expect("8"));
    let row = |at: usize| std::array::from_fn(|i| f64_at(at + 8 * i));
    Ok(Header {
        version: 2,
        sizeof_hdr: 540,
        single: magic == b"n+2\0",
        dim: std::array::from_fn(|i| i64_at(16 + 8 * i)),
        datatype: i16_at(12),
        bitpix: i16_at(14),
        pixdim: std::array::from_fn(|i| f64_at(104 + 8 * i)),
        vox_offset: i64_at(168) as f64,
        scl_slope: f64_at(176),
        scl_inter: f64_at(184),
        qform_code: i32_at(344) as i64,
        sform_code: i32_at(348) as i64,
        quatern_b: f64_at(352),
        quatern_c: f64_at(360),
        quatern_d: f64_at(368),
        qoffset: [f64_at(376), f64_at(384), f64_at(392)],
        srow: [row(400), row(432), row(464)],
        big_endian: big,
    })
}
