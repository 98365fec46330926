//! The voxel-image surface (section 6.6.2): trilinear interpolation of (intensity - iso), in
//! world space.

use super::blocks::Blocks;
use super::topology::Topology;
use super::{ImageError, Stats, Volume, Voxel, with_voxels};
use crate::BoundingSphere;
#[cfg(doc)]
use crate::Surface;
use glam::{DAffine3, DMat3, DVec3};
use std::sync::OnceLock;

/// How an [`ImageSurface`] picks its level set.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ImageOptions {
    /// Iso value (in scaled intensity units). Default for a binary image: halfway between its
    /// two values, or [`BINARY_LEVEL`](super::BINARY_LEVEL) of the way from the background
    /// value to the foreground value when the midpoint pinches the level set (voxels touching
    /// only along an edge; see [`ImageSurface::contacts`]); required otherwise.
    pub iso: Option<f64>,
    /// Mesh the boundary of the voxels equal to this label (indicator function, trilinear, at
    /// the level 0.5, or [`BINARY_LEVEL`](super::BINARY_LEVEL) when 0.5 pinches it, as for a
    /// binary image). Overrides `iso`; `dark_foreground` and `background` are ignored.
    pub label: Option<i64>,
    /// The inside is where the intensity is **below** the iso value (default: above).
    pub dark_foreground: bool,
    /// Value of the image outside the voxel grid (scaled units). Default: the data minimum
    /// (maximum with `dark_foreground`). Must lie on the outside side of the iso value.
    pub background: Option<f64>,
}

#[derive(Clone, Copy, Debug)]
pub(super) enum Mode {
    /// value = a * raw + b.
    Intensity { a: f64, b: f64 },
    /// value = level - interp(indicator(slope * raw + inter == label)).
    Label {
        label: f64,
        slope: f64,
        inter: f64,
        level: f64,
    },
}

/// A level set of a [`Volume`] as a [`Surface`], in world coordinates.
///
/// `value(p)` = `s * (I(affine⁻¹ p) - iso)` where `I` is the trilinear interpolant of the scaled
/// intensities (background outside the grid) and `s = -1` (bright foreground inside) or `+1`
/// (`dark_foreground`). With a label, `value = level - I_L` for the label's indicator `I_L`
/// (the level 0.5, or [`BINARY_LEVEL`](super::BINARY_LEVEL): [`ImageSurface::contacts`]).
/// The value is thus negative inside, positive outside, and positive on and outside the
/// bounding sphere (the grid box enlarged by 2 voxels, where the image is background).
pub struct ImageSurface {
    pub(super) vol: std::sync::Arc<Volume>,
    pub(super) inv: DAffine3,
    pub(super) inv_t: DMat3,
    pub(super) n: [isize; 3],
    pub(super) nf: [f64; 3],
    pub(super) mode: Mode,
    /// Background in raw units (intensity mode) or 0 (label indicator).
    pub(super) bg_raw: f64,
    pub(super) iso: f64,
    pub(super) stats: Stats,
    pub(super) sphere: BoundingSphere,
    pub(super) topo: OnceLock<Topology>,
    pub(super) dm: OnceLock<Option<f64>>,
    /// Sign summary by blocks for [`Surface::crossing`] (built on the first crossing).
    pub(super) blocks: OnceLock<Blocks>,
    /// The level set's total genus from the grid ([`ImageSurface::scan_genus`]).
    pub(super) genus: OnceLock<Option<usize>>,
    /// Budget of [`Surface::seed_points`] (see [`ImageSurface::with_seed_budget`]).
    pub(super) seed_budget: Option<usize>,
    /// Two-valued images (binary, or a label's indicator): the grid faces where the midpoint
    /// pinches the level set, and whether the level was moved off it ([`ImageSurface::contacts`]).
    pub(super) contacts: Option<(usize, bool)>,
}

impl std::fmt::Debug for ImageSurface {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ImageSurface")
            .field("dims", &self.vol.dims())
            .field("dtype", &self.vol.dtype())
            .field("iso", &self.iso)
            .field("mode", &self.mode)
            .finish()
    }
}

impl ImageSurface {
    /// Build the oracle. Errors: NaN voxels, a constant image, a missing iso for a non-binary
    /// image, an iso outside the data range (no surface), an absent label, a background on the
    /// foreground side.
    pub fn new(vol: Volume, opts: &ImageOptions) -> Result<ImageSurface, ImageError> {
        ImageSurface::new_shared(std::sync::Arc::new(vol), opts)
    }

    /// [`ImageSurface::new`] with the default options and the level set at `iso`.
    ///
    /// ```
    /// use oracle::image::{ImageSurface, Volume, Voxels};
    /// use glam::DAffine3;
    /// let v: Vec<f32> = (0..64).map(|i| (i % 4) as f32).collect();
    /// let vol = Volume::new([4, 4, 4], Voxels::F32(v), DAffine3::IDENTITY).unwrap();
    /// assert_eq!(ImageSurface::at_iso(vol, 1.5).unwrap().iso(), 1.5);
    /// ```
    pub fn at_iso(vol: Volume, iso: f64) -> Result<ImageSurface, ImageError> {
        let opts = ImageOptions {
            iso: Some(iso),
            ..Default::default()
        };
        ImageSurface::new(vol, &opts)
    }

    /// Same as [`ImageSurface::new`] on a shared volume: mesh several labels or iso values of
    /// one image without copying the voxels.
    ///
    /// ```
    /// use oracle::image::{ImageOptions, ImageSurface, Volume, Voxels};
    /// use glam::DAffine3;
    /// use std::sync::Arc;
    /// let mut v = vec![0u8; 6 * 6 * 6];
    /// v[2 + 6 * (2 + 6 * 2)] = 1;
    /// v[3 + 6 * (3 + 6 * 3)] = 2;
    /// let vol = Arc::new(Volume::new([6, 6, 6], Voxels::U8(v), DAffine3::IDENTITY).unwrap());
    /// for (label, _count) in vol.labels().unwrap().into_iter().filter(|l| l.0 != 0) {
    ///     let opts = ImageOptions { label: Some(label), ..Default::default() };
    ///     let s = ImageSurface::new_shared(vol.clone(), &opts).unwrap();
    ///     assert_eq!(s.component_count(), 1);
    /// }
    /// ```
    pub fn new_shared(
        vol: std::sync::Arc<Volume>,
        opts: &ImageOptions,
    ) -> Result<ImageSurface, ImageError> {
        let stats = vol.stats()?;
        if stats.min == stats.max {
            return Err(ImageError::Constant {
                path: vol.source().map(|p| p.to_path_buf()),
                value: stats.min,
            });
        }
        let (slope, inter) = vol.scaling();
        let (mode, bg_raw, iso) = if let Some(label) = opts.label {
            let labels = vol.label_boxes()?;
            let Some(b) = labels.iter().find(|b| b.label == label) else {
                let mut present: Vec<String> = labels
                    .iter()
                    .take(32)
                    .map(|b| b.label.to_string())
                    .collect();
                if labels.len() > 32 {
                    present.push(format!("... ({} labels)", labels.len()));
                }
                return Err(ImageError::LabelAbsent {
                    label,
                    present: present.join(", "),
                });
            };
            if b.count == vol.len() {
                return Err(ImageError::LabelEverywhere {
                    path: vol.source().map(|p| p.to_path_buf()),
                    label,
                });
            }
            // The label's own region (see `label_box`): the same surface, scanned and meshed
            // without the rest of the grid.
            if let Some(crop) = vol.label_crop(b) {
                return ImageSurface::new_shared(std::sync::Arc::new(crop), opts);
            }
            let mode = Mode::Label {
                label: label as f64,
                slope,
                inter,
                level: 0.5,
            };
            (mode, 0.0, 0.5)
        } else {
            let iso = match (opts.iso, stats.binary) {
                (Some(iso), _) => iso,
                (None, Some((lo, hi))) => 0.5 * (lo + hi),
                (None, None) => {
                    return Err(ImageError::IsoRequired {
                        min: stats.min,
                        max: stats.max,
                        otsu: super::otsu_threshold(&vol),
                    });
                }
            };
            if !(iso > stats.min && iso < stats.max) {
                return Err(ImageError::IsoOutOfRange {
                    iso,
                    min: stats.min,
                    max: stats.max,
                });
            }
            let s = if opts.dark_foreground { 1.0 } else { -1.0 };
            let bg = opts.background.unwrap_or(if opts.dark_foreground {
                stats.max
            } else {
                stats.min
            });
            if !(s * (bg - iso) > 0.0) {
                return Err(ImageError::BadBackground {
                    background: bg,
                    iso,
                    side: if opts.dark_foreground {
                        "above"
                    } else {
                        "below"
                    },
                });
            }
            let mode = Mode::Intensity {
                a: s * slope,
                b: s * (inter - iso),
            };
            (mode, (bg - inter) / slope, iso)
        };
        let d = vol.dims();
        if d[0].saturating_mul(d[1]).saturating_mul(d[2]) >= u32::MAX as usize {
            return Err(ImageError::TooLarge {
                n: vol.len(),
                max: u32::MAX as usize - 1,
            });
        }
        let inv = vol.affine().inverse();
        let mut s = ImageSurface {
            inv,
            inv_t: inv.matrix3.transpose(),
            n: [d[0] as isize, d[1] as isize, d[2] as isize],
            nf: [d[0] as f64, d[1] as f64, d[2] as f64],
            mode,
            bg_raw,
            iso,
            stats,
            sphere: grid_sphere(vol.affine(), d),
            vol,
            topo: OnceLock::new(),
            dm: OnceLock::new(),
            blocks: OnceLock::new(),
            genus: OnceLock::new(),
            seed_budget: Some(Topology::SEED_BUDGET),
            contacts: None,
        };
        s.leave_the_pinched_midpoint(opts);
        Ok(s)
    }
}

/// The bounding sphere of a grid of `d` nodes under `aff`, enlarged by 2 voxels (where the
/// image is background) on every side.
fn grid_sphere(aff: DAffine3, d: [usize; 3]) -> BoundingSphere {
    let lo = DVec3::splat(-2.0);
    let hi = DVec3::new(d[0] as f64 + 1.0, d[1] as f64 + 1.0, d[2] as f64 + 1.0);
    let center = aff.transform_point3(0.5 * (lo + hi));
    let mut radius: f64 = 0.0;
    for c in 0..8 {
        let v = DVec3::new(
            if c & 1 == 0 { lo.x } else { hi.x },
            if c & 2 == 0 { lo.y } else { hi.y },
            if c & 4 == 0 { lo.z } else { hi.z },
        );
        radius = radius.max((aff.transform_point3(v) - center).length());
    }
    BoundingSphere {
        center,
        radius: radius * (1.0 + 1e-9),
    }
}

impl ImageSurface {
    /// Load `path` with [`load_volume`](super::load_volume) (NIfTI, slice folder, multi-page
    /// TIFF, raw) and build the oracle: the one-call entry point for the CLI.
    ///
    /// ```no_run
    /// use oracle::image::{ImageOptions, ImageSurface, LoadOptions};
    /// // A segmentation: mesh label 3.
    /// let seg = ImageSurface::open(
    ///     "labels.nii.gz",
    ///     &LoadOptions::default(),
    ///     &ImageOptions { label: Some(3), ..Default::default() },
    /// )?;
    /// // A stack of 16-bit PNG slices, 0.5 x 0.5 x 2 mm, iso 1200.
    /// let stack = ImageSurface::open(
    ///     "slices/",
    ///     &LoadOptions { spacing: Some([0.5, 0.5, 2.0]), ..Default::default() },
    ///     &ImageOptions { iso: Some(1200.0), ..Default::default() },
    /// )?;
    /// println!("{} components", stack.component_count());
    /// # Ok::<(), oracle::image::ImageError>(())
    /// ```
    pub fn open(
        path: impl AsRef<std::path::Path>,
        load: &super::LoadOptions,
        opts: &ImageOptions,
    ) -> Result<ImageSurface, ImageError> {
        ImageSurface::new(super::load_volume(path.as_ref(), load)?, opts)
    }

    /// Set the number of points [`Surface::seed_points`] aims at: `Some(b)`, or `None` for
    /// [`Topology::full_seed_budget`] (a seed tetrahedron for every small component; the
    /// default is [`Topology::SEED_BUDGET`], 64). The mesher must keep as many control points
    /// (`MeshOptions::max_control_points`, see [`ImageSurface::seed_budget`]), else its
    /// farthest-point thinning drops the close points of the tetrahedra first.
    ///
    /// ```
    /// use oracle::image::{ImageOptions, ImageSurface, Volume, Voxels};
    /// use oracle::Surface;
    /// use glam::DAffine3;
    /// // 40 isolated bright voxels: 40 components, too many for tetrahedra within 64 points.
    /// let mut v = vec![0u8; 24 * 24 * 24];
    /// for k in 0..40 {
    ///     v[2 + 5 * (k % 4) + 24 * (2 + 5 * ((k / 4) % 4) + 24 * (2 + 8 * (k / 16)))] = 1;
    /// }
    /// let vol = Volume::new([24; 3], Voxels::U8(v), DAffine3::IDENTITY).unwrap();
    /// let s = ImageSurface::new(vol, &ImageOptions::default()).unwrap();
    /// assert_eq!(s.component_count(), 40);
    /// assert_eq!(s.seed_points(0).len(), 64);
    /// let s = s.with_seed_budget(None);
    /// assert_eq!(s.seed_points(0).len(), s.seed_budget());
    /// assert!(s.seed_budget() >= 40 * 4);
    /// ```
    pub fn with_seed_budget(mut self, budget: Option<usize>) -> ImageSurface {
        self.seed_budget = budget;
        self
    }

    /// The number of points [`Surface::seed_points`] aims at (runs the voxel scan when the
    /// budget is [`Topology::full_seed_budget`]).
    pub fn seed_budget(&self) -> usize {
        self.seed_budget
            .unwrap_or_else(|| self.topology().full_seed_budget())
    }

    /// The image.
    pub fn volume(&self) -> &Volume {
        &self.vol
    }
    /// The iso value in scaled units (for a label, the indicator's level: 0.5, or
    /// [`BINARY_LEVEL`](super::BINARY_LEVEL) when 0.5 pinches it).
    pub fn iso(&self) -> f64 {
        self.iso
    }
    /// Data range and binary detection.
    pub fn stats(&self) -> Stats {
        self.stats
    }
    /// World-to-voxel transform.
    pub fn world_to_voxel(&self) -> DAffine3 {
        self.inv
    }

    /// The signed value at voxel coordinates `v` (voxel centres at integers).
    #[inline]
    pub fn value_voxel(&self, v: DVec3) -> f64 {
        match self.mode {
            Mode::Intensity { a, b } => {
                let r = with_voxels!(self.vol.voxels(), d => self.interp(d, v, |x| x.to_f64(), self.bg_raw));
                a * r + b
            }
            Mode::Label {
                label,
                slope,
                inter,
                level,
            } => {
                let ind = |x: f64| ((slope * x + inter) == label) as u8 as f64;
                let r = with_voxels!(self.vol.voxels(), d => self.interp(d, v, |x| ind(x.to_f64()), 0.0));
                level - r
            }
        }
    }

    /// Signed value of grid node `(i, j, k)`, the background's outside the grid: the value
    /// of [`ImageSurface::value_voxel`] at that integer point (the trilinear weights of the
    /// other corners are 0), read directly.
    pub fn grid_value(&self, [i, j, k]: [i64; 3]) -> f64 {
        let [nx, ny, nz] = self.n.map(|x| x as i64);
        if i >= 0 && j >= 0 && k >= 0 && i < nx && j < ny && k < nz {
            self.node_value((i + nx * (j + ny * k)) as usize)
        } else {
            self.background_value()
        }
    }

    /// Signed value of grid node `i` (linear index).
    #[inline]
    pub(crate) fn node_value(&self, i: usize) -> f64 {
        self.map_raw(self.vol.voxels().get_f64(i))
    }

    /// Signed value of a raw voxel value (also of the background: `map_raw(bg_raw)`).
    #[inline]
    pub(crate) fn map_raw(&self, raw: f64) -> f64 {
        match self.mode {
            Mode::Intensity { a, b } => a * raw + b,
            Mode::Label {
                label,
                slope,
                inter,
                level,
            } => level - ((slope * raw + inter) == label) as u8 as f64,
        }
    }

    /// Signed value of the background (positive).
    pub(crate) fn background_value(&self) -> f64 {
        self.map_raw(self.bg_raw)
    }

    /// Inside bits of every grid node (`value < 0`), 64 nodes per word, x fastest.
    pub(crate) fn inside_bits(&self) -> Vec<u64> {
        use rayon::prelude::*;
        let n = self.vol.len();
        let mut bits = vec![0u64; n.div_ceil(64)];
        fn fill<T: Voxel>(d: &[T], bits: &mut [u64], f: &(impl Fn(f64) -> f64 + Sync)) {
            bits.par_chunks_mut(1024)
                .enumerate()
                .for_each(|(c, words)| {
                    for (w, word) in words.iter_mut().enumerate() {
                        let start = (c * 1024 + w) * 64;
                        let end = (start + 64).min(d.len());
                        let mut acc = 0u64;
                        for (b, &x) in d[start..end].iter().enumerate() {
                            acc |= ((f(x.to_f64()) < 0.0) as u64) << b;
                        }
                        *word = acc;
                    }
                });
        }
        let f = |x: f64| self.map_raw(x);
        with_voxels!(self.vol.voxels(), d => fill(d, &mut bits, &f));
        bits
    }

    /// Inside bits row by row: row `r = j + ny * k` occupies words `r * W .. (r + 1) * W` with
    /// `W = ceil(nx / 64)`, bit `x % 64` of word `x / 64` (unused high bits are 0).
    pub(crate) fn inside_bits_rows(&self) -> Vec<u64> {
        use rayon::prelude::*;
        let nx = self.n[0] as usize;
        let w = nx.div_ceil(64);
        let rows = self.vol.len() / nx;
        let mut bits = vec![0u64; rows * w];
        fn fill<T: Voxel>(
            d: &[T],
            nx: usize,
            w: usize,
            bits: &mut [u64],
            f: &(impl Fn(f64) -> f64 + Sync),
        ) {
            bits.par_chunks_mut(w * 64)
                .enumerate()
                .for_each(|(c, chunk)| {
                    for (rr, row) in chunk.chunks_mut(w).enumerate() {
                        let r = c * 64 + rr;
                        let vals = &d[r * nx..(r + 1) * nx];
                        for (wi, word) in row.iter_mut().enumerate() {
                            let mut acc = 0u64;
                            for (b, &x) in vals[wi * 64..((wi + 1) * 64).min(nx)].iter().enumerate()
                            {
                                acc |= ((f(x.to_f64()) < 0.0) as u64) << b;
                            }
                            *word = acc;
                        }
                    }
                });
        }
        let f = |x: f64| self.map_raw(x);
        with_voxels!(self.vol.voxels(), d => fill(d, nx, w, &mut bits, &f));
        bits
    }

    #[inline(always)]
    fn interp<T: Voxel>(&self, d: &[T], v: DVec3, fetch: impl Fn(T) -> f64, bg: f64) -> f64 {
        let (x, y, z) = (v.x, v.y, v.z);
        if !(x > -1.0 && y > -1.0 && z > -1.0 && x < self.nf[0] && y < self.nf[1] && z < self.nf[2])
        {
            return if v.is_nan() { f64::NAN } else { bg };
        }
        // floor by truncation (x > -1 here): avoids a libm call on baseline x86-64.
        let i = (x + 1.0) as isize - 1;
        let j = (y + 1.0) as isize - 1;
        let k = (z + 1.0) as isize - 1;
        let c = self.corners(d, [i, j, k], fetch, bg);
        trilinear(&c, v - DVec3::new(i as f64, j as f64, k as f64))
    }

    /// Raw (or indicator) values at the corners of `cell`, `bg` outside the grid.
    #[inline(always)]
    fn corners<T: Voxel>(
        &self,
        d: &[T],
        [i, j, k]: [isize; 3],
        fetch: impl Fn(T) -> f64,
        bg: f64,
    ) -> [f64; 8] {
        let [nx, ny, nz] = self.n;
        // `i < nx - 1`, not `i + 1 < nx`: no overflow for any `i` (every `n` is >= 1).
        if i >= 0 && j >= 0 && k >= 0 && i < nx - 1 && j < ny - 1 && k < nz - 1 {
            let sx = 1usize;
            let sy = nx as usize;
            let sz = (nx * ny) as usize;
            let b = i as usize + sy * (j as usize + ny as usize * k as usize);
            // One bounds check for the whole cell, then plain fetches.
            let cell = &d[b..=b + sx + sy + sz];
            [
                fetch(cell[0]),
                fetch(cell[sx]),
                fetch(cell[sy]),
                fetch(cell[sx + sy]),
                fetch(cell[sz]),
                fetch(cell[sx + sz]),
                fetch(cell[sy + sz]),
                fetch(cell[sx + sy + sz]),
            ]
        } else {
            let at = |a: isize, b: isize, c: isize| {
                if a < 0 || b < 0 || c < 0 || a >= nx || b >= ny || c >= nz {
                    bg
                } else {
                    fetch(d[(a + nx * (b + ny * c)) as usize])
                }
            };
            [
                at(i, j, k),
                at(i + 1, j, k),
                at(i, j + 1, k),
                at(i + 1, j + 1, k),
                at(i, j, k + 1),
                at(i + 1, j, k + 1),
                at(i, j + 1, k + 1),
                at(i + 1, j + 1, k + 1),
            ]
        }
    }

    /// Signed values at the 8 corners of the cell whose lowest corner is `cell` (integer voxel
    /// coordinates, background outside the grid), x fastest.
    #[inline]
    pub(super) fn cell_corners(&self, cell: DVec3) -> [f64; 8] {
        if cell.is_nan() {
            return [f64::NAN; 8];
        }
        // A cell whose lowest corner is outside [-1, n - 1] on some axis touches no voxel:
        // map it to -2 (all background) before the cast, so that no huge coordinate (a huge
        // sform scale puts world points at 1e30 voxels) reaches the index arithmetic.
        let axis = |x: f64, n: isize| {
            if x >= -1.0 && x <= (n - 1) as f64 {
                x as isize
            } else {
                -2
            }
        };
        let cell = [
            axis(cell.x, self.n[0]),
            axis(cell.y, self.n[1]),
            axis(cell.z, self.n[2]),
        ];
        match self.mode {
            Mode::Intensity { a, b } => {
                let r = with_voxels!(self.vol.voxels(), d => self.corners(d, cell, |x| x.to_f64(), self.bg_raw));
                r.map(|x| a * x + b)
            }
            Mode::Label {
                label,
                slope,
                inter,
                level,
            } => {
                let ind = |x: f64| ((slope * x + inter) == label) as u8 as f64;
                let r = with_voxels!(self.vol.voxels(), d => self.corners(d, cell, |x| ind(x.to_f64()), 0.0));
                r.map(|x| level - x)
            }
        }
    }

    /// Whether the oracle meshes one label (indicator function).
    pub fn is_label(&self) -> bool {
        matches!(self.mode, Mode::Label { .. })
    }

    pub(crate) fn dims_isize(&self) -> [isize; 3] {
        self.n
    }
}

/// `v.floor()` without the libm call of baseline x86-64 (no SSE4.1 `roundsd`): exact for
/// |x| < 2^53 (the `as i64` cast truncates toward zero, then a step down for negatives);
/// NaN and huge values fall back to `f64::floor`.
#[inline(always)]
pub(super) fn floor3(v: DVec3) -> DVec3 {
    #[inline(always)]
    fn f(x: f64) -> f64 {
        if x.abs() < 4.0e15 {
            let t = x as i64 as f64;
            if t > x { t - 1.0 } else { t }
        } else {
            x.floor()
        }
    }
    DVec3::new(f(v.x), f(v.y), f(v.z))
}

/// Trilinear interpolation of the 8 corner values `c` (x fastest) at local coordinates `t`
/// (the interpolant whose level set [`ImageSurface`] is).
///
/// ```
/// use glam::DVec3;
/// let c = [0.0, 1.0, 0.0, 1.0, 0.0, 1.0, 0.0, 1.0]; // the value is x
/// assert_eq!(oracle::image::trilinear(&c, DVec3::new(0.25, 0.5, 0.75)), 0.25);
/// ```
#[inline(always)]
pub fn trilinear(c: &[f64; 8], t: DVec3) -> f64 {
    let x00 = c[0] + t.x * (c[1] - c[0]);
    let x10 = c[2] + t.x * (c[3] - c[2]);
    let x01 = c[4] + t.x * (c[5] - c[4]);
    let x11 = c[6] + t.x * (c[7] - c[6]);
    let y0 = x00 + t.y * (x10 - x00);
    let y1 = x01 + t.y * (x11 - x01);
    y0 + t.z * (y1 - y0)
}

#[cfg(test)]
mod tests {
    use super::floor3;
    use crate::image::{ImageOptions, ImageSurface, Volume, Voxels};
    use glam::{DAffine3, DVec3};

    /// A volume of the given dimensions whose voxel `(i, j, k)` holds `1 + i + 2j + 4k`,
    /// meshed at iso 1.5 with background 0.
    fn ramp(dims: [usize; 3]) -> ImageSurface {
        let n = dims[0] * dims[1] * dims[2];
        let v = (0..n)
            .map(|t| {
                let (i, j, k) = (t % dims[0], t / dims[0] % dims[1], t / (dims[0] * dims[1]));
                (1 + i + 2 * j + 4 * k) as u8
            })
            .collect();
        let vol = Volume::new(dims, Voxels::U8(v), DAffine3::IDENTITY).unwrap();
        let opts = ImageOptions {
            iso: Some(1.5),
            background: Some(0.0),
            ..Default::default()
        };
        ImageSurface::new(vol, &opts).unwrap()
    }

    /// The raw values at the corners of `cell` in `ramp(dims)`, 0 (the background) outside
    /// the grid; x fastest.
    fn expected(dims: [usize; 3], cell: [i64; 3]) -> [f64; 8] {
        let mut out = [0.0; 8];
        for (c, o) in out.iter_mut().enumerate() {
            let p = [
                cell[0] + (c & 1) as i64,
                cell[1] + (c >> 1 & 1) as i64,
                cell[2] + (c >> 2) as i64,
            ];
            let inside = (0..3).all(|a| p[a] >= 0 && p[a] < dims[a] as i64);
            *o = if inside {
                (1 + p[0] + 2 * p[1] + 4 * p[2]) as f64
            } else {
                0.0
            };
        }
        out
    }

    #[test]
    fn cell_corners_on_thin_and_tiny_volumes() {
        for dims in [[1, 3, 4], [2, 2, 2], [3, 1, 2]] {
            let s = ramp(dims);
            for i in -3i64..=3 {
                for j in -3i64..=4 {
                    for k in -3i64..=5 {
                        let got = s.cell_corners(DVec3::new(i as f64, j as f64, k as f64));
                        let want = expected(dims, [i, j, k]).map(|raw| s.map_raw(raw));
                        assert_eq!(got, want, "{dims:?} cell ({i},{j},{k})");
                    }
                }
            }
        }
    }

    #[test]
    fn grid_value_is_the_interpolated_value_at_nodes() {
        for dims in [[1, 3, 4], [2, 2, 2], [5, 3, 2]] {
            let s = ramp(dims);
            for i in -2i64..=6 {
                for j in -2i64..=4 {
                    for k in -2i64..=5 {
                        let p = DVec3::new(i as f64, j as f64, k as f64);
                        assert_eq!(s.grid_value([i, j, k]), s.value_voxel(p), "{dims:?} {p}");
                    }
                }
            }
        }
    }

    #[test]
    fn cell_corners_far_outside_are_background() {
        let s = ramp([2, 2, 2]);
        let bg = s.cell_corners(DVec3::splat(-5.0));
        assert_eq!(bg, [s.map_raw(0.0); 8]);
        assert!(bg[0] > 0.0, "the background is outside (positive): {bg:?}");
        for x in [
            1e30,
            -1e30,
            3.4e38,
            f64::MAX,
            f64::INFINITY,
            f64::NEG_INFINITY,
            9.3e18,
            -9.3e18,
        ] {
            for cell in [
                DVec3::new(x, 0.0, 0.0),
                DVec3::new(0.0, x, 0.0),
                DVec3::new(0.0, 0.0, x),
                DVec3::splat(x),
            ] {
                assert_eq!(s.cell_corners(cell), bg, "{cell}");
            }
        }
        assert!(
            s.cell_corners(DVec3::new(0.0, f64::NAN, 0.0))
                .iter()
                .all(|v| v.is_nan())
        );
    }

    #[test]
    fn floor3_matches_floor() {
        let mut rng = crate::roots::SplitMix64(7);
        let specials = [
            0.0,
            -0.0,
            1.0,
            -1.0,
            0.5,
            -0.5,
            -1e-300,
            2.0f64.powi(52) + 0.5,
            -4.1e15,
            1e300,
        ];
        for &x in &specials {
            let v = DVec3::splat(x);
            assert_eq!(floor3(v), v.floor(), "{x}");
        }
        assert!(floor3(DVec3::NAN).is_nan());
        for _ in 0..100_000 {
            let x = (rng.next_f64() - 0.5) * 1e3;
            let y = (rng.next_f64() - 0.5) * 4.0;
            let z = x.round() + [-1e-12, 0.0, 1e-12][(rng.next_u64() % 3) as usize];
            let v = DVec3::new(x, y, z);
            assert_eq!(floor3(v), v.floor(), "{v}");
        }
    }
}
