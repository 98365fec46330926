//! Errors of the image backend: each names the file (if any), the field and the fix.

use std::path::PathBuf;

/// What a flat image is, for [`ImageError::NotAVolume`].
fn flat_kind(dims: &[u64], nz: u64) -> String {
    if dims.iter().all(|&d| d == 1) {
        "a single voxel".to_string()
    } else {
        format!("a 2D image (dim[3] = {nz})")
    }
}

fn show(p: &Option<PathBuf>) -> String {
    match p {
        Some(p) => format!("{}: ", p.display()),
        None => String::new(),
    }
}

/// Errors raised while loading a volume or building an [`ImageSurface`](super::ImageSurface).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ImageError {
    #[error("{}: cannot read: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error(
        "{}: the file is truncated ({detail}); re-export or re-download it",
        path.display()
    )]
    Truncated { path: PathBuf, detail: String },
    #[error("{}: not a valid NIfTI file ({detail})", path.display())]
    Nifti { path: PathBuf, detail: String },
    #[error("{}: {format} header field {field} {detail}", path.display())]
    Field {
        path: PathBuf,
        format: &'static str,
        field: String,
        detail: String,
    },
    #[error("{}: NIfTI header field {field} {detail}", path.display())]
    BadHeader {
        path: PathBuf,
        field: String,
        detail: String,
    },
    #[error(
        "{}: the gzip data is corrupt ({detail}); the file is damaged (`gzip -t` checks it): \
         re-download or re-export it",
        path.display()
    )]
    CorruptGzip { path: PathBuf, detail: String },
    #[error(
        "{}: the voxel data after vox_offset {offset} has {actual} bytes, but dim and datatype \
         need exactly {expected}; the header does not match the data (check dim, datatype and \
         vox_offset)",
        path.display()
    )]
    DataLength {
        path: PathBuf,
        offset: u64,
        expected: u64,
        actual: u64,
    },
    #[error(
        "{}: {field} is not supported; convert the image to u8, i8, u16, i16, u32, i32, u64, i64, f32 or f64",
        path.display()
    )]
    UnsupportedType { path: PathBuf, field: String },
    #[error(
        "{}: voxel ({}, {}, {}) holds the 64-bit value {value}, beyond 9e15, where float64 values \
         cannot tell consecutive integers apart (the limit of labels); renumber the labels to consecutive ids \
         (e.g. fastremap.renumber in Python) and save the volume again",
        path.display(),
        voxel[0],
        voxel[1],
        voxel[2]
    )]
    WideValue {
        path: PathBuf,
        value: String,
        voxel: [usize; 3],
    },
    #[error(
        "{}: dim = {dims:?} is {}, not a volume; give a 3D image, or a folder of 2D slices (with --spacing)",
        path.display(),
        flat_kind(dims, *nz)
    )]
    NotAVolume {
        path: PathBuf,
        dims: Vec<u64>,
        nz: u64,
    },
    #[error(
        "{}: dim = {dims:?} is a series of {frames} 3D volumes (dim[4] = {frames}); pass --frame K (0 to {}) to mesh one of them",
        path.display(),
        frames - 1
    )]
    FourD {
        path: PathBuf,
        dims: Vec<u64>,
        frames: u64,
    },
    #[error("{}: dim = {dims:?}: {detail}", path.display())]
    Frame {
        path: PathBuf,
        dims: Vec<u64>,
        detail: String,
    },
    #[error(
        "{}the image is empty (dims {dims:?}); every dimension must be at least 1",
        show(path)
    )]
    Empty {
        path: Option<PathBuf>,
        dims: [usize; 3],
    },
    #[error("{dims:?} voxels need {expected} values but {actual} were given")]
    LengthMismatch {
        dims: [usize; 3],
        expected: usize,
        actual: usize,
    },
    #[error(
        "{}{field} gives an unusable voxel-to-world transform: {detail}",
        show(path)
    )]
    BadAffine {
        path: Option<PathBuf>,
        field: String,
        detail: String,
    },
    #[error("spacing {spacing:?} is invalid; give three positive finite numbers (sx, sy, sz)")]
    BadSpacing { spacing: [f64; 3] },
    #[error(
        "{}all voxels equal {value}: the image is constant, so there is no surface",
        show(path)
    )]
    Constant { path: Option<PathBuf>, value: f64 },
    #[error(
        "{}voxel {index:?} is {}",
        show(path),
        if *nan {
            "NaN (no value): pass --nan-as VALUE to mesh NaN voxels as VALUE (e.g. --nan-as 0 where NaN marks the background), or replace them before meshing"
        } else {
            "infinite: fix the data before meshing (--nan-as replaces NaN only)"
        }
    )]
    NaN {
        path: Option<PathBuf>,
        index: [usize; 3],
        /// NaN (else infinite).
        nan: bool,
    },
    #[error("--nan-as {value}: the value for NaN voxels must be a finite number")]
    NanValue { value: f64 },
    #[error(
        "iso value required for a non-binary image; the data range is [{min}, {max}] (pass --iso VALUE{}, or --label L for a segmentation)",
        otsu.map_or(String::new(), |t| format!(", e.g. --iso {} (Otsu's threshold of the histogram)", four_digits(t)))
    )]
    IsoRequired {
        min: f64,
        max: f64,
        /// Otsu's threshold of the values ([`super::otsu_threshold`]), a value to try.
        otsu: Option<f64>,
    },
    #[error(
        "iso value {iso} is outside the data range [{min}, {max}] (or equal to an end): there is no surface; pick a value strictly inside the range"
    )]
    IsoOutOfRange { iso: f64, min: f64, max: f64 },
    #[error(
        "background {background} is on the foreground side of iso {iso}; choose a background {side} the iso value, or flip the foreground"
    )]
    BadBackground {
        background: f64,
        iso: f64,
        side: &'static str,
    },
    #[error("label {label} is not present in the image; labels present: {present}")]
    LabelAbsent { label: i64, present: String },
    #[error(
        "{}label {label} fills the whole image: there is no surface",
        show(path)
    )]
    LabelEverywhere { path: Option<PathBuf>, label: i64 },
    #[error(
        "{}value {value} is not an integer, so the image is not a label image; mesh it with an iso value instead",
        show(path)
    )]
    NotLabels { path: Option<PathBuf>, value: f64 },
    #[error(
        "{}label {value} is beyond 9e15, where float64 values cannot tell consecutive integers apart; relabel the image with smaller ids (e.g. numpy.unique(ids, return_inverse=True))",
        show(path)
    )]
    LabelTooLarge { path: Option<PathBuf>, value: f64 },
    #[error("{}: {detail}", path.display())]
    Dicom { path: PathBuf, detail: String },
    #[error("{}: no PNG or TIFF slices found in the folder; put the 2D slices (*.png, *.tif, *.tiff) there", dir.display())]
    NoSlices { dir: PathBuf },
    #[error("{}: slice is {found_w}x{found_h} but the first slice {} is {w}x{h}; all slices must have the same size", path.display(), first.display())]
    SliceSize {
        path: PathBuf,
        first: PathBuf,
        w: u32,
        h: u32,
        found_w: u32,
        found_h: u32,
    },
    #[error("{}: slice has voxel type {found} but the first slice {} has {expected}; convert the stack to one bit depth", path.display(), first.display())]
    SliceType {
        path: PathBuf,
        first: PathBuf,
        expected: String,
        found: String,
    },
    #[error("{}: cannot decode the image ({detail})", path.display())]
    Decode { path: PathBuf, detail: String },
    #[error("{}: raw volume of dims {dims:?} and type {dtype} needs {expected} bytes (after an offset of {offset}) but the file has {actual}; check --dims, --dtype and the header offset", path.display())]
    RawSize {
        path: PathBuf,
        dims: [usize; 3],
        dtype: String,
        offset: u64,
        expected: u64,
        actual: u64,
    },
    #[error("{}: the raw format needs dims and a dtype (e.g. --dims 256,256,128 --dtype u16)", path.display())]
    RawNeedsDims { path: PathBuf },
    #[error("{}: unknown image format (extension '{ext}'); use .nii, .nii.gz, .hdr, .nrrd, .nhdr, .mha, .mhd, .zarr (OME-Zarr), .tif/.tiff (multi-page), .raw with dims, or a folder of slices", path.display())]
    UnknownFormat { path: PathBuf, ext: String },
    #[error(
        "the volume has {n} voxels, more than this backend indexes ({max}); crop or downsample it"
    )]
    TooLarge { n: usize, max: usize },
}

/// `x` to four significant digits, printed without trailing zeros (412.3, 0.1235, 1235).
fn four_digits(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let e = x.abs().log10().floor() as i32;
    let p = 10f64.powi(3 - e);
    let r = (x * p).round() / p;
    let s = format!("{:.*}", (3 - e).max(0) as usize, r);
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}
