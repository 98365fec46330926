//! Image stacks (ours: a folder of 2D slices, a multi-page TIFF) and raw volumes.

use super::{
    Dtype, ImageError, Volume, Voxels, read_metaimage_frame, read_nifti_frame, read_nrrd_frame,
};
use glam::{DAffine3, DMat3, DVec3};
use std::cmp::Ordering;
use std::path::{Path, PathBuf};

/// Layout of a headerless raw volume (x fastest, then y, then z).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RawOptions {
    /// Voxels along x, y, z.
    pub dims: [usize; 3],
    /// Voxel type.
    pub dtype: Dtype,
    /// Whether multi-byte voxels are big-endian.
    pub big_endian: bool,
    /// Bytes to skip at the start of the file (a header).
    pub offset: u64,
}

/// How [`load_volume`] reads a path. `spacing` applies to stacks and raw volumes (NIfTI files
/// carry their own transform and ignore it).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LoadOptions {
    /// Voxel size `(sx, sy, sz)` in world units; default `(1, 1, 1)`.
    pub spacing: Option<[f64; 3]>,
    /// Read the file as raw voxels with this layout (whatever its extension).
    pub raw: Option<RawOptions>,
    /// The 3D volume of a NIfTI, MGH, NRRD or MetaImage series (`dim[4] > 1`, `nframes > 1`,
    /// a 4D array with one non-spatial axis, `NDims = 4`) or of a DICOM
    /// series holding several volumes at the same slice positions to read, from 0 (`--frame`);
    /// a series without it is refused. Other files (and raw volumes) hold one volume: only 0
    /// is accepted.
    pub frame: Option<usize>,
    /// Give NaN voxels this value (`--nan-as`; see [`Volume::replace_nan`]); without it a NaN
    /// voxel is an error when the surface is built.
    pub nan_as: Option<f64>,
    /// The series of a DICOM folder that holds several: its `SeriesNumber` or
    /// `SeriesInstanceUID` (`--series`); other inputs refuse it.
    pub series: Option<String>,
}

fn spacing_affine(spacing: Option<[f64; 3]>) -> Result<DAffine3, ImageError> {
    let s = spacing.unwrap_or([1.0; 3]);
    if s.iter().any(|v| !(v.is_finite() && *v > 0.0)) {
        return Err(ImageError::BadSpacing { spacing: s });
    }
    Ok(DAffine3::from_mat3(DMat3::from_diagonal(DVec3::from(s))))
}

/// The file name endings [`load_volume`] reads as images (lower case; `.gz` variants of the
/// NIfTI and MGH ones included).
pub const IMAGE_EXTENSIONS: [&str; 18] = [
    ".nii", ".nii.gz", ".hdr", ".hdr.gz", ".img", ".img.gz", ".nrrd", ".nhdr", ".mha", ".mhd",
    ".tif", ".tiff", ".raw", ".mgh", ".mgz", ".mgh.gz", ".dcm", ".ima",
];

/// Whether the file name (any case) ends with one of [`IMAGE_EXTENSIONS`].
///
/// ```
/// use oracle::image::is_image_file_name;
/// assert!(is_image_file_name("Brain.NII.GZ") && is_image_file_name("anat.hdr"));
/// assert!(!is_image_file_name("bunny.ply"));
/// ```
pub fn is_image_file_name(name: &str) -> bool {
    let lower = name.to_ascii_lowercase();
    IMAGE_EXTENSIONS.iter().any(|e| lower.ends_with(e))
}

/// For a volume format this crate does not read (Philips, MINC, AFNI, ECAT, numpy),
/// its name and how to convert it to one it reads; `None` for any other name.
///
/// ```
/// use oracle::image::unsupported_volume_format;
/// assert!(unsupported_volume_format("T1.mnc").unwrap().0.contains("MINC"));
/// assert!(unsupported_volume_format("T1.mgz").is_none(), "FreeSurfer volumes are read");
/// assert!(unsupported_volume_format("bunny.ply").is_none());
/// ```
pub fn unsupported_volume_format(name: &str) -> Option<(&'static str, &'static str)> {
    let lower = name.to_ascii_lowercase();
    const FORMATS: [(&[&str], &str, &str); 5] = [
        (
            &[".par", ".rec"],
            "a Philips PAR/REC volume",
            "convert it with `dcm2niix` or nibabel's `parrec2nii`",
        ),
        (
            &[".mnc", ".mnc.gz"],
            "a MINC volume",
            "convert it with `mnc2nii` or nibabel (`nibabel.save(nibabel.load(IN), 'OUT.nii.gz')`)",
        ),
        (
            &[".head", ".brik", ".brik.gz"],
            "an AFNI volume",
            "convert it with `3dAFNItoNIFTI` or nibabel",
        ),
        (
            &[".v"],
            "an ECAT volume",
            "convert it with nibabel (`nibabel.save(nibabel.load(IN), 'OUT.nii.gz')`)",
        ),
        (
            &[".npy", ".npz"],
            "a numpy array",
            "mesh it from Python with `rdt_mesher.mesh_image(array, spacing=...)`, or save it as NIfTI with nibabel",
        ),
    ];
    FORMATS
        .iter()
        .find(|(ends, _, _)| ends.iter().any(|e| lower.ends_with(e)))
        .map(|&(_, what, how)| (what, how))
}

/// Read a volume from `path`: a folder of slices, an OME-Zarr folder (with `.zattrs`,
/// `.zgroup` or `zarr.json`), `.nii`/`.nii.gz`/`.hdr`/`.img`, `.nrrd`/`.nhdr`, `.mha`/`.mhd`,
/// a `.tif`/`.tiff` (multi-page) or, with `opts.raw`, a raw file.
///
/// ```no_run
/// use oracle::image::{load_volume, ImageOptions, ImageSurface, LoadOptions};
/// let vol = load_volume("brain.nii.gz".as_ref(), &LoadOptions::default())?;
/// let surface = ImageSurface::new(vol, &ImageOptions { iso: Some(300.0), ..Default::default() })?;
/// # Ok::<(), oracle::image::ImageError>(())
/// ```
pub fn load_volume(path: &Path, opts: &LoadOptions) -> Result<Volume, ImageError> {
    let vol = read_volume(path, opts)?;
    let dicom = || {
        opts.raw.is_none()
            && (named(path, &[".dcm", ".ima"])
                || super::is_dicom_file(path)
                || (path.is_dir() && super::is_dicom_folder(path)))
    };
    // Asked only for a frame above 0: `dicom()` may read the folder's files again.
    let series = || {
        opts.raw.is_none()
            && ([&NIFTI[..], &MGH, &NRRD, &METAIMAGE]
                .iter()
                .any(|e| named(path, e))
                || dicom())
    };
    if let Some(k) = opts.frame.filter(|&k| k > 0 && !series()) {
        return Err(ImageError::Frame {
            path: path.to_path_buf(),
            dims: vol.dims().iter().map(|&d| d as u64).collect(),
            detail: format!(
                "--frame {k}: this file holds one 3D volume (frame 0); series are read from \
                 NIfTI, MGH, NRRD, MetaImage and DICOM"
            ),
        });
    }
    if let Some(s) = opts.series.as_deref().filter(|_| !dicom()) {
        return Err(ImageError::Frame {
            path: path.to_path_buf(),
            dims: vol.dims().iter().map(|&d| d as u64).collect(),
            detail: format!("--series {s}: series are picked from DICOM folders; this is not one"),
        });
    }
    match opts.nan_as {
        Some(value) => vol.replace_nan(value),
        None => Ok(vol),
    }
}

/// For a folder without slices whose subfolders hold DICOM series: the error naming them.
fn dicom_below(path: &Path) -> Option<ImageError> {
    let found = super::dicom_subfolders(path);
    let list = found
        .iter()
        .take(8)
        .map(|(d, n)| format!("{} ({n} files)", d.display()))
        .collect::<Vec<_>>()
        .join(", ");
    (!found.is_empty()).then(|| ImageError::Dicom {
        path: path.to_path_buf(),
        detail: format!(
            "the DICOM files are in {} subfolder(s): pass the folder of one series: {list}{}",
            found.len(),
            if found.len() > 8 { ", ..." } else { "" }
        ),
    })
}

/// Whether the file name (any case) ends with one of `ends` (lower case).
fn named(path: &Path, ends: &[&str]) -> bool {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    ends.iter().any(|e| name.ends_with(e))
}

/// A NIfTI file's endings (`.nii`, `.hdr`, `.img`, gzipped or not).
const NIFTI: [&str; 6] = [".nii", ".nii.gz", ".hdr", ".hdr.gz", ".img", ".img.gz"];
/// A FreeSurfer volume's endings.
const MGH: [&str; 3] = [".mgh", ".mgz", ".mgh.gz"];
/// An NRRD file's endings.
const NRRD: [&str; 2] = [".nrrd", ".nhdr"];
/// A MetaImage file's endings.
const METAIMAGE: [&str; 2] = [".mha", ".mhd"];

/// [`load_volume`] before the frame check and the NaN replacement.
fn read_volume(path: &Path, opts: &LoadOptions) -> Result<Volume, ImageError> {
    if let Some(raw) = opts.raw {
        return read_raw(path, &raw, opts.spacing);
    }
    if path.is_dir() {
        if super::zarr::is_zarr(path) {
            return super::read_ome_zarr(path);
        }
        if super::is_dicom_folder(path) {
            return super::read_dicom_frame(path, opts.series.as_deref(), opts.frame);
        }
        return read_slice_folder(path, opts.spacing).map_err(|e| match e {
            ImageError::NoSlices { .. } => dicom_below(path).unwrap_or(e),
            e => e,
        });
    }
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let ends = |s: &str| name.ends_with(s);
    if named(path, &NIFTI) {
        read_nifti_frame(path, opts.frame)
    } else if named(path, &MGH) {
        super::read_mgh(path, opts.frame)
    } else if named(path, &NRRD) {
        read_nrrd_frame(path, opts.frame)
    } else if named(path, &METAIMAGE) {
        read_metaimage_frame(path, opts.frame)
    } else if ends(".tif") || ends(".tiff") {
        read_tiff_stack(path, opts.spacing)
    } else if ends(".dcm") || ends(".ima") || super::is_dicom_file(path) {
        super::read_dicom_frame(path, opts.series.as_deref(), opts.frame)
    } else if ends(".raw") {
        Err(ImageError::RawNeedsDims {
            path: path.to_path_buf(),
        })
    } else {
        Err(ImageError::UnknownFormat {
            path: path.to_path_buf(),
            ext: path
                .extension()
                .map(|e| e.to_string_lossy().into_owned())
                .unwrap_or_default(),
        })
    }
}

/// Read a headerless raw volume. Errors (giving expected vs actual bytes) unless the file
/// holds exactly `offset + nx*ny*nz*size` bytes.
pub fn read_raw(
    path: &Path,
    raw: &RawOptions,
    spacing: Option<[f64; 3]>,
) -> Result<Volume, ImageError> {
    let affine = spacing_affine(spacing)?;
    let bytes = std::fs::read(path).map_err(|source| ImageError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let n = raw
        .dims
        .iter()
        .try_fold(1u64, |a, &d| a.checked_mul(d as u64));
    let expected = n
        .and_then(|n| n.checked_mul(raw.dtype.size() as u64))
        .unwrap_or(u64::MAX);
    if raw.dims.contains(&0) {
        return Err(ImageError::Empty {
            path: Some(path.to_path_buf()),
            dims: raw.dims,
        });
    }
    let actual = bytes.len() as u64;
    if raw.offset.checked_add(expected) != Some(actual) {
        return Err(ImageError::RawSize {
            path: path.to_path_buf(),
            dims: raw.dims,
            dtype: raw.dtype.to_string(),
            offset: raw.offset,
            expected,
            actual,
        });
    }
    let data = &bytes[raw.offset as usize..];
    let (voxels, held) =
        super::volume::decode_voxels(path, raw.dims, raw.dtype, data, raw.big_endian)?;
    drop(bytes);
    let vol = Volume::new(raw.dims, voxels, affine)?.with_source(path);
    Ok(match held {
        Some(n) => vol.with_note(n),
        None => vol,
    })
}

/// Natural order: digit runs compare as numbers (`slice2 < slice10`), the rest bytewise.
pub(crate) fn natural_cmp(a: &str, b: &str) -> Ordering {
    let (a, b) = (a.as_bytes(), b.as_bytes());
    let (mut i, mut j) = (0, 0);
    while i < a.len() && j < b.len() {
        if a[i].is_ascii_digit() && b[j].is_ascii_digit() {
            let si = i;
            while i < a.len() && a[i].is_ascii_digit() {
                i += 1;
            }
            let sj = j;
            while j < b.len() && b[j].is_ascii_digit() {
                j += 1;
            }
            let (na, nb) = (trim0(&a[si..i]), trim0(&b[sj..j]));
            let c = na.len().cmp(&nb.len()).then(na.cmp(nb));
            if c != Ordering::Equal {
                return c;
            }
        } else {
            if a[i] != b[j] {
                return a[i].cmp(&b[j]);
            }
            i += 1;
            j += 1;
        }
    }
    (a.len() - i).cmp(&(b.len() - j)).then(a.cmp(b))
}

fn trim0(s: &[u8]) -> &[u8] {
    let k = s.iter().position(|&c| c != b'0').unwrap_or(s.len());
    &s[k..]
}

enum Slice {
    U8(Vec<u8>),
    U16(Vec<u16>),
}

fn decode_slice(path: &Path) -> Result<(u32, u32, Slice), ImageError> {
    use image::DynamicImage as D;
    let img = image::open(path).map_err(|e| ImageError::Decode {
        path: path.to_path_buf(),
        detail: e.to_string(),
    })?;
    let (w, h) = (img.width(), img.height());
    let s = match img {
        D::ImageLuma8(b) => Slice::U8(b.into_raw()),
        D::ImageLuma16(b) => Slice::U16(b.into_raw()),
        // Colour or alpha: converted to luma (documented); 16-bit stays 16-bit.
        D::ImageLumaA16(_) | D::ImageRgb16(_) | D::ImageRgba16(_) => {
            Slice::U16(img.to_luma16().into_raw())
        }
        D::ImageLumaA8(_) | D::ImageRgb8(_) | D::ImageRgba8(_) => {
            Slice::U8(img.to_luma8().into_raw())
        }
        // Float (or future) pixel types: never quantise silently.
        other => {
            return Err(ImageError::UnsupportedType {
                path: path.to_path_buf(),
                field: format!(
                    "slice pixel type {:?} (float or unknown; use a multi-page TIFF, which keeps f32)",
                    other.color()
                ),
            });
        }
    };
    Ok((w, h, s))
}

/// Read a folder of 2D slices (`*.png`, `*.tif`, `*.tiff`; 8 or 16 bit grey, colour converted
/// to luma) in natural name order (`s2` before `s10`). Slice `k` is `z = k`; pixel `(col, row)`
/// is voxel `(x, y)`. The affine is `diag(spacing)` (default 1). Errors name the first slice
/// whose size or bit depth differs from the first one.
pub fn read_slice_folder(dir: &Path, spacing: Option<[f64; 3]>) -> Result<Volume, ImageError> {
    let affine = spacing_affine(spacing)?;
    let io = |source| ImageError::Io {
        path: dir.to_path_buf(),
        source,
    };
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(io)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.is_file()
                && p.extension().is_some_and(|e| {
                    let e = e.to_string_lossy().to_ascii_lowercase();
                    e == "png" || e == "tif" || e == "tiff"
                })
        })
        .collect();
    if files.is_empty() {
        return Err(ImageError::NoSlices {
            dir: dir.to_path_buf(),
        });
    }
    files.sort_by(|a, b| {
        let na = a.file_name().unwrap_or_default().to_string_lossy();
        let nb = b.file_name().unwrap_or_default().to_string_lossy();
        natural_cmp(&na, &nb)
    });
    let (w, h, first) = decode_slice(&files[0])?;
    let nz = files.len();
    let mut out = match first {
        Slice::U8(v) => {
            let mut o = Vec::with_capacity(v.len() * nz);
            o.extend_from_slice(&v);
            Voxels::U8(o)
        }
        Slice::U16(v) => {
            let mut o = Vec::with_capacity(v.len() * nz);
            o.extend_from_slice(&v);
            Voxels::U16(o)
        }
    };
    for f in &files[1..] {
        let (fw, fh, s) = decode_slice(f)?;
        if (fw, fh) != (w, h) {
            return Err(ImageError::SliceSize {
                path: f.clone(),
                first: files[0].clone(),
                w,
                h,
                found_w: fw,
                found_h: fh,
            });
        }
        match (&mut out, s) {
            (Voxels::U8(o), Slice::U8(v)) => o.extend_from_slice(&v),
            (Voxels::U16(o), Slice::U16(v)) => o.extend_from_slice(&v),
            (o, s) => {
                return Err(ImageError::SliceType {
                    path: f.clone(),
                    first: files[0].clone(),
                    expected: o.dtype().to_string(),
                    found: match s {
                        Slice::U8(_) => "u8".into(),
                        Slice::U16(_) => "u16".into(),
                    },
                });
            }
        }
    }
    let dims = [w as usize, h as usize, nz];
    Ok(Volume::new(dims, out, affine)?.with_source(dir))
}

/// Read a multi-page TIFF (one page per slice; 8/16/32-bit integer or 32/64-bit float grey)
/// through the `tiff` crate. The affine is `diag(spacing)` (default 1).
pub fn read_tiff_stack(path: &Path, spacing: Option<[f64; 3]>) -> Result<Volume, ImageError> {
    use tiff::decoder::{Decoder, DecodingResult as R};
    let affine = spacing_affine(spacing)?;
    let dec_err = |e: tiff::TiffError| ImageError::Decode {
        path: path.to_path_buf(),
        detail: e.to_string(),
    };
    let file = std::fs::File::open(path).map_err(|source| ImageError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let mut dec = Decoder::new(std::io::BufReader::new(file)).map_err(dec_err)?;
    let (w, h) = dec.dimensions().map_err(dec_err)?;
    let unread = if spacing.is_none() {
        declared_spacing(&mut dec)
    } else {
        None
    };
    let mut out: Option<Voxels> = None;
    let mut nz = 0usize;
    loop {
        let (pw, ph) = dec.dimensions().map_err(dec_err)?;
        let page = PathBuf::from(format!("{} (page {nz})", path.display()));
        if (pw, ph) != (w, h) {
            return Err(ImageError::SliceSize {
                path: page,
                first: PathBuf::from(format!("{} (page 0)", path.display())),
                w,
                h,
                found_w: pw,
                found_h: ph,
            });
        }
        // A colour page stored plane by plane decodes as its first plane alone: refuse it
        // by its colour type, not by the sample count.
        let colour = dec.colortype().map_err(dec_err)?;
        if !matches!(colour, tiff::ColorType::Gray(_)) {
            return Err(ImageError::Decode {
                path: path.to_path_buf(),
                detail: format!(
                    "page {nz} is {colour:?}, not grey: only single-channel stacks are read; \
                     convert it to grey first (e.g. tifffile and numpy, or ImageJ's 8-bit \
                     conversion)"
                ),
            });
        }
        let img = dec.read_image().map_err(dec_err)?;
        let n = (w as usize) * (h as usize);
        let bad = |found: &str, expected: &str| ImageError::SliceType {
            path: PathBuf::from(format!("{} (page {nz})", path.display())),
            first: PathBuf::from(format!("{} (page 0)", path.display())),
            expected: expected.to_string(),
            found: found.to_string(),
        };
        macro_rules! push {
            ($v:ident, $variant:ident) => {{
                if $v.len() != n {
                    return Err(ImageError::Decode {
                        path: path.to_path_buf(),
                        detail: format!(
                            "page {nz} has {} samples for {w}x{h} pixels; only single-channel (grey) stacks are supported",
                            $v.len()
                        ),
                    });
                }
                match &mut out {
                    None => out = Some(Voxels::$variant($v)),
                    Some(Voxels::$variant(o)) => o.extend_from_slice(&$v),
                    Some(o) => return Err(bad(stringify!($variant), &o.dtype().to_string())),
                }
            }};
        }
        match img {
            R::U8(v) => push!(v, U8),
            R::I8(v) => push!(v, I8),
            R::U16(v) => push!(v, U16),
            R::I16(v) => push!(v, I16),
            R::U32(v) => push!(v, U32),
            R::I32(v) => push!(v, I32),
            R::F32(v) => push!(v, F32),
            R::F64(v) => push!(v, F64),
            _ => {
                return Err(ImageError::UnsupportedType {
                    path: path.to_path_buf(),
                    field: "TIFF sample format (64-bit integer or 16-bit float)".into(),
                });
            }
        }
        nz += 1;
        if !dec.more_images() {
            break;
        }
        dec.next_image().map_err(dec_err)?;
    }
    let voxels = out.expect("at least one page");
    if nz == 1 {
        return Err(ImageError::NotAVolume {
            path: path.to_path_buf(),
            dims: vec![w as u64, h as u64, 1],
            nz: 1,
        });
    }
    let vol = Volume::new([w as usize, h as usize, nz], voxels, affine)?.with_source(path);
    Ok(match unread {
        Some(what) => vol.with_note(format!(
            "{}: voxel spacing 1 x 1 x 1 (no --spacing): the file declares {what}, which this \
             reader does not apply (its units are not certain); pass --spacing sx,sy,sz",
            path.display()
        )),
        None => vol,
    })
}

/// What page 0 of a TIFF says about its pixel size, for the note of a stack read without
/// `--spacing` (before 2026-12-07 such a stack was meshed in voxel units without a word): the
/// resolution tags and a `spacing` in the description (ImageJ's and tifffile's metadata).
fn declared_spacing<R: std::io::Read + std::io::Seek>(
    dec: &mut tiff::decoder::Decoder<R>,
) -> Option<String> {
    use tiff::decoder::ifd::Value;
    use tiff::tags::Tag;
    let mut found = Vec::new();
    for (tag, name) in [
        (Tag::XResolution, "XResolution"),
        (Tag::YResolution, "YResolution"),
    ] {
        if let Ok(Some(Value::Rational(n, d))) = dec.find_tag(tag) {
            found.push(format!("{name} {n}/{d}"));
        }
    }
    if let Ok(text) = dec.get_tag_ascii_string(Tag::ImageDescription)
        && let Some(at) = text.find("spacing")
    {
        let v: String = text[at..]
            .chars()
            .take_while(|&c| c != '\n' && c != ',')
            .filter(|&c| c != '"')
            .take(40)
            .collect();
        found.push(format!("`{}` in its description", v.trim()));
    }
    (!found.is_empty()).then(|| found.join(", "))
}
