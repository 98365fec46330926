//! Voxel storage in the native type, with a voxel-to-world affine (ours: the image backend's
//! data; section 6.6.2 meshes its level sets).

use super::{ImageError, SharedVoxels};
use glam::{DAffine3, DMat3, DVec3};
use std::collections::BTreeMap;
use std::path::PathBuf;

/// Element type of a [`Volume`]'s voxels.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Dtype {
    U8,
    I8,
    U16,
    I16,
    U32,
    I32,
    F32,
    F64,
    /// 64-bit integers (label volumes): a type of the files only. They are read into the
    /// narrowest storage that holds every value exactly ([`Voxels::decode`]: u32, i32, or f64
    /// up to 9e15), so no [`Voxels`] has this type.
    U64,
    /// See [`Dtype::U64`].
    I64,
}

impl Dtype {
    /// Size of one voxel in bytes.
    pub fn size(self) -> usize {
        match self {
            Dtype::U8 | Dtype::I8 => 1,
            Dtype::U16 | Dtype::I16 => 2,
            Dtype::U32 | Dtype::I32 | Dtype::F32 => 4,
            Dtype::F64 | Dtype::U64 | Dtype::I64 => 8,
        }
    }
    /// Whether the type holds integers (labels are meaningful).
    pub fn is_integer(self) -> bool {
        !matches!(self, Dtype::F32 | Dtype::F64)
    }
}

impl std::str::FromStr for Dtype {
    type Err = String;
    /// Parse `u8, i8, u16, i16, u32, i32, f32, f64` (also `uint8`, `int16`, `float32`, ...).
    fn from_str(s: &str) -> Result<Self, String> {
        Ok(match s.to_ascii_lowercase().as_str() {
            "u8" | "uint8" => Dtype::U8,
            "i8" | "int8" => Dtype::I8,
            "u16" | "uint16" => Dtype::U16,
            "i16" | "int16" => Dtype::I16,
            "u32" | "uint32" => Dtype::U32,
            "i32" | "int32" => Dtype::I32,
            "f32" | "float32" | "float" => Dtype::F32,
            "f64" | "float64" | "double" => Dtype::F64,
            "u64" | "uint64" => Dtype::U64,
            "i64" | "int64" => Dtype::I64,
            _ => {
                return Err(format!(
                    "unknown voxel type '{s}'; use one of u8, i8, u16, i16, u32, i32, f32, f64"
                ));
            }
        })
    }
}

impl std::fmt::Display for Dtype {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let s = match self {
            Dtype::U8 => "u8",
            Dtype::I8 => "i8",
            Dtype::U16 => "u16",
            Dtype::I16 => "i16",
            Dtype::U32 => "u32",
            Dtype::I32 => "i32",
            Dtype::F32 => "f32",
            Dtype::F64 => "f64",
            Dtype::U64 => "u64",
            Dtype::I64 => "i64",
        };
        f.write_str(s)
    }
}

/// A voxel element type: converts to `f64` on the fly (storage stays native).
pub trait Voxel: Copy + Send + Sync + PartialEq + 'static {
    const DTYPE: Dtype;
    fn to_f64(self) -> f64;
    /// Decode one element from its bytes (`b.len() == DTYPE.size()`).
    fn from_bytes(b: &[u8], big_endian: bool) -> Self;
    /// Append the little-endian bytes of `self` (used by the writers).
    fn push_le(self, out: &mut Vec<u8>);
}

macro_rules! impl_voxel {
    ($t:ty, $d:ident) => {
        impl Voxel for $t {
            const DTYPE: Dtype = Dtype::$d;
            #[inline(always)]
            fn to_f64(self) -> f64 {
                self as f64
            }
            #[inline]
            fn from_bytes(b: &[u8], big_endian: bool) -> Self {
                let a: [u8; std::mem::size_of::<$t>()] = b.try_into().expect("voxel size");
                if big_endian {
                    <$t>::from_be_bytes(a)
                } else {
                    <$t>::from_le_bytes(a)
                }
            }
            fn push_le(self, out: &mut Vec<u8>) {
                out.extend_from_slice(&self.to_le_bytes());
            }
        }
    };
}
impl_voxel!(u8, U8);
impl_voxel!(i8, I8);
impl_voxel!(u16, U16);
impl_voxel!(i16, I16);
impl_voxel!(u32, U32);
impl_voxel!(i32, I32);
impl_voxel!(f32, F32);
impl_voxel!(f64, F64);

/// Voxel data in its native type, x fastest: index `x + nx * (y + ny * z)` (NIfTI order).
#[derive(Clone, Debug, PartialEq)]
pub enum Voxels {
    U8(Vec<u8>),
    I8(Vec<i8>),
    U16(Vec<u16>),
    I16(Vec<i16>),
    U32(Vec<u32>),
    I32(Vec<i32>),
    F32(Vec<f32>),
    F64(Vec<f64>),
    /// Voxels borrowed from their owner (see [`SharedVoxels`]), x fastest as well.
    Shared(SharedVoxels),
}

/// `with_voxels!(voxels, d => expr)` evaluates `expr` with `d: &Vec<T>` (or `&[T]` for shared
/// voxels) for the native `T`.
macro_rules! with_voxels {
    ($v:expr, $d:ident => $body:expr) => {
        match $v {
            $crate::image::Voxels::U8($d) => $body,
            $crate::image::Voxels::I8($d) => $body,
            $crate::image::Voxels::U16($d) => $body,
            $crate::image::Voxels::I16($d) => $body,
            $crate::image::Voxels::U32($d) => $body,
            $crate::image::Voxels::I32($d) => $body,
            $crate::image::Voxels::F32($d) => $body,
            $crate::image::Voxels::F64($d) => $body,
            $crate::image::Voxels::Shared(s) => $crate::image::with_view!(s.view(), $d => $body),
        }
    };
}
pub(crate) use with_voxels;

impl Voxels {
    pub fn dtype(&self) -> Dtype {
        match self {
            Voxels::U8(_) => Dtype::U8,
            Voxels::I8(_) => Dtype::I8,
            Voxels::U16(_) => Dtype::U16,
            Voxels::I16(_) => Dtype::I16,
            Voxels::U32(_) => Dtype::U32,
            Voxels::I32(_) => Dtype::I32,
            Voxels::F32(_) => Dtype::F32,
            Voxels::F64(_) => Dtype::F64,
            Voxels::Shared(s) => s.view().dtype(),
        }
    }
    pub fn len(&self) -> usize {
        with_voxels!(self, d => d.len())
    }
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Raw (unscaled) value of voxel `i` as `f64`.
    pub fn get_f64(&self, i: usize) -> f64 {
        with_voxels!(self, d => d[i].to_f64())
    }
    /// [`Voxels::from_bytes`] for every type, the 64-bit integers included: those are held
    /// in the narrowest of u32, i32 and f64 that holds every value exactly, with a note
    /// saying which; a value beyond 9e15 in magnitude (the limit of labels,
    /// [`Volume::labels`]; below 2^53, where f64 holds every integer) is an error
    /// ([`WideValue`]).
    pub fn decode(
        dtype: Dtype,
        bytes: &[u8],
        big_endian: bool,
    ) -> Result<(Voxels, Option<String>), WideValue> {
        let signed = match dtype {
            Dtype::U64 => false,
            Dtype::I64 => true,
            _ => return Ok((Voxels::from_bytes(dtype, bytes, big_endian), None)),
        };
        let values: Vec<i128> = bytes
            .chunks_exact(8)
            .map(|c| {
                let mut b: [u8; 8] = c.try_into().expect("8 bytes");
                if big_endian {
                    b.reverse();
                }
                if signed {
                    i64::from_le_bytes(b) as i128
                } else {
                    u64::from_le_bytes(b) as i128
                }
            })
            .collect();
        let (lo, hi) = values
            .iter()
            .fold((i128::MAX, i128::MIN), |(a, b), &v| (a.min(v), b.max(v)));
        const EXACT: i128 = 9_000_000_000_000_000;
        let (voxels, held) = if values.is_empty() || (lo >= 0 && hi <= u32::MAX as i128) {
            (
                Voxels::U32(values.iter().map(|&v| v as u32).collect()),
                "u32",
            )
        } else if lo >= i32::MIN as i128 && hi <= i32::MAX as i128 {
            (
                Voxels::I32(values.iter().map(|&v| v as i32).collect()),
                "i32",
            )
        } else if lo >= -EXACT && hi <= EXACT {
            (
                Voxels::F64(values.iter().map(|&v| v as f64).collect()),
                "f64",
            )
        } else {
            let v = if hi > EXACT { hi } else { lo };
            return Err(WideValue {
                value: v.to_string(),
                index: values.iter().position(|&x| x == v).unwrap_or(0),
            });
        };
        let note = format!(
            "{dtype} voxels held as {held}, which holds every value exactly (from {lo} to {hi})"
        );
        Ok((voxels, Some(note)))
    }

    /// Decode `bytes` (exactly `n * dtype.size()` long) into native storage.
    ///
    /// # Panics
    /// On a 64-bit integer type whose values are not all within 9e15 (use
    /// [`Voxels::decode`]).
    pub fn from_bytes(dtype: Dtype, bytes: &[u8], big_endian: bool) -> Voxels {
        fn conv<T: Voxel>(bytes: &[u8], be: bool) -> Vec<T> {
            bytes
                .chunks_exact(T::DTYPE.size())
                .map(|c| T::from_bytes(c, be))
                .collect()
        }
        match dtype {
            Dtype::U8 => Voxels::U8(bytes.to_vec()),
            Dtype::I8 => Voxels::I8(conv(bytes, big_endian)),
            Dtype::U16 => Voxels::U16(conv(bytes, big_endian)),
            Dtype::I16 => Voxels::I16(conv(bytes, big_endian)),
            Dtype::U32 => Voxels::U32(conv(bytes, big_endian)),
            Dtype::I32 => Voxels::I32(conv(bytes, big_endian)),
            Dtype::F32 => Voxels::F32(conv(bytes, big_endian)),
            Dtype::F64 => Voxels::F64(conv(bytes, big_endian)),
            Dtype::U64 | Dtype::I64 => {
                Voxels::decode(dtype, bytes, big_endian)
                    .expect("64-bit values within 2^53 (Voxels::decode says which are not)")
                    .0
            }
        }
    }
    /// Little-endian bytes of the data (for the writers).
    pub fn to_le_bytes(&self) -> Vec<u8> {
        with_voxels!(self, d => {
            let mut out = Vec::with_capacity(d.len() * self.dtype().size());
            for &v in d.iter() {
                v.push_le(&mut out);
            }
            out
        })
    }
}

/// [`Voxels::decode`] of a file's voxel data (`path`, a grid of `dims`): the error names the
/// voxel.
pub(crate) fn decode_voxels(
    path: &std::path::Path,
    dims: [usize; 3],
    dtype: Dtype,
    bytes: &[u8],
    big_endian: bool,
) -> Result<(Voxels, Option<String>), ImageError> {
    Voxels::decode(dtype, bytes, big_endian).map_err(|w| ImageError::WideValue {
        path: path.to_path_buf(),
        value: w.value,
        voxel: [
            w.index % dims[0],
            (w.index / dims[0]) % dims[1],
            w.index / (dims[0] * dims[1]),
        ],
    })
}

/// A 64-bit integer voxel value beyond 9e15 in magnitude (no storage type of the mesher
/// holds it as a label): the value and the voxel's linear index.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct WideValue {
    /// The value, in decimal.
    pub value: String,
    /// Its first voxel (linear index, x fastest).
    pub index: usize,
}

/// Value statistics of a volume (in scaled units: `slope * raw + inter`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stats {
    pub min: f64,
    pub max: f64,
    /// `Some((lo, hi))` if the volume holds exactly two distinct values (binary image).
    pub binary: Option<(f64, f64)>,
}

/// A 3D scalar image: native voxels, dims, voxel-to-world affine and intensity scaling.
///
/// Invariants (checked by [`Volume::new`]): `voxels.len() == dims[0] * dims[1] * dims[2]`,
/// every dim is at least 1, the affine is finite, invertible and within the limits of
/// [`check_affine`] (voxel sizes, anisotropy, offset), `slope` is finite and non-zero.
/// The world position of voxel `(i, j, k)` (its centre) is `affine.transform_point3((i, j, k))`.
#[derive(Clone, Debug, PartialEq)]
pub struct Volume {
    dims: [usize; 3],
    voxels: Voxels,
    affine: DAffine3,
    slope: f64,
    inter: f64,
    source: Option<PathBuf>,
    notes: Vec<String>,
}

impl Volume {
    /// A volume with identity scaling. Errors if the length does not match the dims, a dim is
    /// zero, or the affine is singular, not finite or outside the limits of [`check_affine`].
    pub fn new(dims: [usize; 3], voxels: Voxels, affine: DAffine3) -> Result<Volume, ImageError> {
        let n = dims.iter().try_fold(1usize, |a, &d| a.checked_mul(d));
        if dims.contains(&0) {
            return Err(ImageError::Empty { path: None, dims });
        }
        if n != Some(voxels.len()) {
            return Err(ImageError::LengthMismatch {
                dims,
                expected: n.unwrap_or(usize::MAX),
                actual: voxels.len(),
            });
        }
        check_affine(&affine, None, "affine")?;
        Ok(Volume {
            dims,
            voxels,
            affine,
            slope: 1.0,
            inter: 0.0,
            source: None,
            notes: Vec::new(),
        })
    }

    /// Set the intensity scaling `value = slope * raw + inter` (NIfTI `scl_slope`/`scl_inter`).
    /// A slope of 0 or a non-finite value means "no scaling" (the NIfTI rule).
    pub fn with_scaling(mut self, slope: f64, inter: f64) -> Volume {
        if slope != 0.0 && slope.is_finite() && inter.is_finite() {
            self.slope = slope;
            self.inter = inter;
        } else {
            self.slope = 1.0;
            self.inter = 0.0;
        }
        self
    }

    /// Record the file the volume came from (used in error messages).
    pub fn with_source(mut self, path: impl Into<PathBuf>) -> Volume {
        self.source = Some(path.into());
        self
    }

    /// Add a note for the user about how the file was read (e.g. bytes ignored).
    pub fn with_note(mut self, note: String) -> Volume {
        self.notes.push(note);
        self
    }

    /// Notes of the reader (the CLI prints each as `note: ...`).
    /// Give every NaN voxel the value `value` (in scaled units; its raw value is
    /// `(value - inter) / slope`, rounded to the voxel type), with a [`Volume::notes`] entry
    /// saying how many and the value they got. For data where NaN marks "no measurement"
    /// (resampled or masked float images: nibabel's `resampled_anat_moved.nii`, SPM's
    /// statistical maps), which [`Volume::stats`] otherwise refuses. Integer voxels are never
    /// NaN: the volume is returned unchanged. Errors: `value` not finite.
    ///
    /// ```
    /// use oracle::image::{Volume, Voxels};
    /// use glam::DAffine3;
    /// let v = Volume::new([2, 2, 2], Voxels::F32(vec![f32::NAN, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0]),
    ///     DAffine3::IDENTITY)?;
    /// let v = v.replace_nan(0.0)?;
    /// assert_eq!(v.get(0, 0, 0), 0.0);
    /// assert!(v.notes()[0].starts_with("1 NaN voxel(s) set to 0"));
    /// # Ok::<(), oracle::image::ImageError>(())
    /// ```
    pub fn replace_nan(mut self, value: f64) -> Result<Volume, ImageError> {
        if !value.is_finite() {
            return Err(ImageError::NanValue { value });
        }
        let raw = (value - self.inter) / self.slope;
        let n = self.voxels.len();
        let get = |i: usize| self.voxels.get_f64(i);
        let (voxels, count) = match self.voxels.dtype() {
            Dtype::F32 => {
                let r = raw as f32;
                let d: Vec<f32> = (0..n).map(|i| get(i) as f32).collect();
                let count = d.iter().filter(|v| v.is_nan()).count();
                let d = d.into_iter().map(|v| if v.is_nan() { r } else { v });
                (Voxels::F32(d.collect()), count)
            }
            Dtype::F64 => {
                let d: Vec<f64> = (0..n).map(get).collect();
                let count = d.iter().filter(|v| v.is_nan()).count();
                let d = d.into_iter().map(|v| if v.is_nan() { raw } else { v });
                (Voxels::F64(d.collect()), count)
            }
            _ => return Ok(self),
        };
        if count == 0 {
            return Ok(self);
        }
        let stored = match voxels {
            Voxels::F32(_) => raw as f32 as f64,
            _ => raw,
        };
        self.voxels = voxels;
        let got = self.slope * stored + self.inter;
        self.notes.push(format!(
            "{count} NaN voxel(s) set to {got} (--nan-as {value}{})",
            if got == value {
                ""
            } else {
                ", rounded to the voxel type"
            }
        ));
        Ok(self)
    }

    pub fn notes(&self) -> &[String] {
        &self.notes
    }

    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }
    pub fn voxels(&self) -> &Voxels {
        &self.voxels
    }
    pub fn dtype(&self) -> Dtype {
        self.voxels.dtype()
    }
    pub fn affine(&self) -> DAffine3 {
        self.affine
    }
    /// `(slope, inter)`: scaled value = `slope * raw + inter`.
    pub fn scaling(&self) -> (f64, f64) {
        (self.slope, self.inter)
    }
    pub fn source(&self) -> Option<&std::path::Path> {
        self.source.as_deref()
    }
    /// Number of voxels.
    pub fn len(&self) -> usize {
        self.voxels.len()
    }
    pub fn is_empty(&self) -> bool {
        self.voxels.is_empty()
    }
    /// Linear index of voxel `(i, j, k)`.
    #[inline]
    pub fn index(&self, i: usize, j: usize, k: usize) -> usize {
        i + self.dims[0] * (j + self.dims[1] * k)
    }
    /// Scaled value of voxel `(i, j, k)`.
    pub fn get(&self, i: usize, j: usize, k: usize) -> f64 {
        self.slope * self.voxels.get_f64(self.index(i, j, k)) + self.inter
    }
    /// World position of the voxel coordinates `v` (voxel centres at integers).
    pub fn to_world(&self, v: DVec3) -> DVec3 {
        self.affine.transform_point3(v)
    }
    /// World lengths of the three voxel axes (column norms of the affine).
    pub fn spacing(&self) -> DVec3 {
        let m = self.affine.matrix3;
        DVec3::new(m.x_axis.length(), m.y_axis.length(), m.z_axis.length())
    }

    /// Min, max (scaled) and binary detection. Errors on NaN or infinite voxels (naming the
    /// voxel index), so that they are never silently read as a sign.
    pub fn stats(&self) -> Result<Stats, ImageError> {
        type Scan = (f64, f64, Option<(f64, f64)>);
        /// Per chunk: (min, max, up to 3 distinct values) or the index of a non-finite voxel.
        /// Two loops: the distinct values from the start (most images have 3 within a few
        /// voxels), then a branch-free min / max / finiteness pass that the compiler
        /// vectorizes; only a chunk with a non-finite voxel is scanned again for its index.
        fn chunk<T: Voxel>(d: &[T], base: usize) -> Result<(f64, f64, Vec<T>), usize> {
            let mut distinct: Vec<T> = Vec::with_capacity(3);
            for &v in d {
                if distinct.len() == 3 {
                    break;
                }
                if !distinct.contains(&v) {
                    distinct.push(v);
                }
            }
            // Eight independent lanes (no dependency between them, so they vectorize);
            // x * 0 is 0 for a finite x, NaN for NaN and infinities, and a NaN loses every
            // comparison, so only `fin` sees it.
            const L: usize = 8;
            let mut lo = [f64::INFINITY; L];
            let mut hi = [f64::NEG_INFINITY; L];
            let mut fin = [0.0f64; L];
            let mut lanes = d.chunks_exact(L);
            for c in &mut lanes {
                for k in 0..L {
                    let x = c[k].to_f64();
                    lo[k] = if x < lo[k] { x } else { lo[k] };
                    hi[k] = if x > hi[k] { x } else { hi[k] };
                    fin[k] += x * 0.0;
                }
            }
            for &v in lanes.remainder() {
                let x = v.to_f64();
                lo[0] = if x < lo[0] { x } else { lo[0] };
                hi[0] = if x > hi[0] { x } else { hi[0] };
                fin[0] += x * 0.0;
            }
            if fin.iter().any(|&f| f != 0.0) {
                let i = d.iter().position(|v| !v.to_f64().is_finite()).unwrap_or(0);
                return Err(base + i);
            }
            let lo = lo.iter().fold(f64::INFINITY, |a, &b| a.min(b));
            let hi = hi.iter().fold(f64::NEG_INFINITY, |a, &b| a.max(b));
            Ok((lo, hi, distinct))
        }
        /// Parallel over chunks, merged in chunk order (deterministic: the first bad voxel).
        fn scan<T: Voxel>(d: &[T]) -> Result<Scan, usize> {
            use rayon::prelude::*;
            const C: usize = 1 << 18;
            let parts: Vec<_> = d
                .par_chunks(C)
                .enumerate()
                .map(|(c, part)| chunk(part, c * C))
                .collect();
            let (mut lo, mut hi, mut distinct) = (f64::INFINITY, f64::NEG_INFINITY, Vec::new());
            for p in parts {
                let (l, h, dv) = p?;
                lo = lo.min(l);
                hi = hi.max(h);
                for v in dv {
                    if distinct.len() < 3 && !distinct.contains(&v) {
                        distinct.push(v);
                    }
                }
            }
            let bin = (distinct.len() == 2).then(|| (distinct[0].to_f64(), distinct[1].to_f64()));
            Ok((lo, hi, bin))
        }
        let r = with_voxels!(&self.voxels, d => scan(d));
        let (lo, hi, bin) = r.map_err(|i| {
            let nx = self.dims[0];
            let ny = self.dims[1];
            ImageError::NaN {
                path: self.source.clone(),
                index: [i % nx, (i / nx) % ny, i / (nx * ny)],
                nan: self.voxels.get_f64(i).is_nan(),
            }
        })?;
        let s = |x: f64| self.slope * x + self.inter;
        let (a, b) = (s(lo), s(hi));
        let bin = bin.map(|(p, q)| {
            let (p, q) = (s(p), s(q));
            (p.min(q), p.max(q))
        });
        Ok(Stats {
            min: a.min(b),
            max: a.max(b),
            binary: bin,
        })
    }

    /// Labels present in the image with their voxel counts, sorted by label (scaled values,
    /// which must be integers). Errors if a scaled value is not an integer.
    pub fn labels(&self) -> Result<Vec<(i64, usize)>, ImageError> {
        let mut map: BTreeMap<i64, usize> = BTreeMap::new();
        let small = |d: &Voxels| -> Option<Vec<(i64, usize)>> {
            // Histogram fast path for 8/16-bit types.
            let (off, hist) = match d {
                Voxels::U8(d) => (0i64, hist(d.iter().map(|&v| v as usize), 256)),
                Voxels::I8(d) => (
                    -128,
                    hist(d.iter().map(|&v| (v as i64 + 128) as usize), 256),
                ),
                Voxels::U16(d) => (0, hist(d.iter().map(|&v| v as usize), 65536)),
                Voxels::I16(d) => (
                    -32768,
                    hist(d.iter().map(|&v| (v as i64 + 32768) as usize), 65536),
                ),
                _ => return None,
            };
            Some(
                hist.iter()
                    .enumerate()
                    .filter(|(_, c)| **c > 0)
                    .map(|(i, &c)| (i as i64 + off, c))
                    .collect(),
            )
        };
        let raw: Vec<(f64, usize)> = if let Some(h) = small(&self.voxels) {
            h.into_iter().map(|(v, c)| (v as f64, c)).collect()
        } else {
            let mut raw: BTreeMap<u64, (f64, usize)> = BTreeMap::new();
            let r: Result<(), ImageError> = with_voxels!(&self.voxels, d => {
                for (i, &v) in d.iter().enumerate() {
                    let x = v.to_f64();
                    if !x.is_finite() {
                        return Err(ImageError::NaN {
                            path: self.source.clone(),
                            index: self.unindex(i),
                            nan: x.is_nan(),
                        });
                    }
                    raw.entry(x.to_bits()).or_insert((x, 0)).1 += 1;
                }
                Ok(())
            });
            r?;
            raw.into_values().collect()
        };
        for (x, c) in raw {
            let v = self.slope * x + self.inter;
            if v.fract() != 0.0 {
                return Err(ImageError::NotLabels {
                    path: self.source.clone(),
                    value: v,
                });
            }
            if v.abs() > 9.0e15 {
                return Err(ImageError::LabelTooLarge {
                    path: self.source.clone(),
                    value: v,
                });
            }
            *map.entry(v as i64).or_insert(0) += c;
        }
        Ok(map.into_iter().collect())
    }

    /// Voxel `(i, j, k)` of linear index `i`.
    pub fn unindex(&self, i: usize) -> [usize; 3] {
        let nx = self.dims[0];
        let ny = self.dims[1];
        [i % nx, (i / nx) % ny, i / (nx * ny)]
    }
}

fn hist(it: impl Iterator<Item = usize>, n: usize) -> Vec<usize> {
    let mut h = vec![0usize; n];
    for i in it {
        h[i] += 1;
    }
    h
}

/// Smallest and largest voxel size (length of an affine column, in world units).
pub(crate) const MIN_VOXEL_SIZE: f64 = 1e-12;
pub(crate) const MAX_VOXEL_SIZE: f64 = 1e12;
/// Largest anisotropy of a voxel: `‖M‖_F ‖M⁻¹‖_F / 3` of the affine's matrix `M` (1 for a
/// cube, about the ratio of the longest to the shortest voxel axis otherwise).
pub(crate) const MAX_ANISOTROPY: f64 = 1e4;
/// Largest distance of the world origin from the grid, in voxels (`‖t‖_∞ / smallest size`).
pub(crate) const MAX_OFFSET_VOXELS: f64 = 1e12;

/// Check that an affine is usable; `field` names its origin for the message. The limits keep
/// every coordinate the mesher computes far inside what `f64` and the exact predicates
/// represent (world coordinates within about `1e12 * 1e12`, voxel coordinates of the
/// region around the grid below `1e13`, several digits of sub-voxel precision):
/// - every entry finite and the determinant not 0 (nor below `1e-12` of the product of the
///   column lengths, i.e. not numerically singular);
/// - each voxel size (column length) in [[`MIN_VOXEL_SIZE`], [`MAX_VOXEL_SIZE`]];
/// - the anisotropy at most [`MAX_ANISOTROPY`];
/// - the translation at most [`MAX_OFFSET_VOXELS`] voxel sizes from the origin.
pub(crate) fn check_affine(
    a: &DAffine3,
    path: Option<&std::path::Path>,
    field: &str,
) -> Result<(), ImageError> {
    let bad = |detail: String| {
        let fix = if path.is_some() && field != "affine" {
            "fix the header's transform (e.g. with nibabel)"
        } else {
            "check the transform (for a slice stack or raw volume: --spacing)"
        };
        Err(ImageError::BadAffine {
            path: path.map(|p| p.to_path_buf()),
            field: field.to_string(),
            detail: format!("{detail}; {fix}"),
        })
    };
    let m = a.matrix3;
    let finite = a.translation.is_finite() && m.x_axis.is_finite() && m.y_axis.is_finite();
    let finite = finite && m.z_axis.is_finite();
    let sizes = [m.x_axis.length(), m.y_axis.length(), m.z_axis.length()];
    if !finite {
        return bad(format!(
            "an entry is NaN or infinite (voxel axes {:?}, translation {:?})",
            m.to_cols_array(),
            a.translation.to_array()
        ));
    }
    let det = m.determinant();
    let scale = sizes[0] * sizes[1] * sizes[2];
    if !(det.abs() > 1e-12 * scale) || !(scale > 0.0) {
        return bad(format!(
            "the determinant is {det} (voxel sizes {sizes:?}): the voxel axes are \
             (nearly) linearly dependent"
        ));
    }
    if let Some(s) = sizes
        .iter()
        .find(|s| !(**s >= MIN_VOXEL_SIZE && **s <= MAX_VOXEL_SIZE))
    {
        return bad(format!(
            "a voxel size is {s:e} (sizes {sizes:?}); voxel sizes must be within \
             [{MIN_VOXEL_SIZE:e}, {MAX_VOXEL_SIZE:e}] world units"
        ));
    }
    let frob = |m: DMat3| {
        (m.x_axis.length_squared() + m.y_axis.length_squared() + m.z_axis.length_squared()).sqrt()
    };
    let aniso = frob(m) * frob(m.inverse()) / 3.0;
    if !(aniso <= MAX_ANISOTROPY) {
        return bad(format!(
            "the voxels are about {aniso:.3e} times longer in one direction than in another \
             (sizes {sizes:?}); at most {MAX_ANISOTROPY:e} is supported"
        ));
    }
    let smallest = sizes.iter().fold(f64::INFINITY, |x, &y| x.min(y));
    let off = a.translation.abs().max_element() / smallest;
    if !(off <= MAX_OFFSET_VOXELS) {
        return bad(format!(
            "the translation {:?} puts the grid {off:.3e} voxels from the origin; at most \
             {MAX_OFFSET_VOXELS:e} keeps sub-voxel precision",
            a.translation.to_array()
        ));
    }
    Ok(())
}
