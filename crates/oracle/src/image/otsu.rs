//! Otsu's threshold of an image's values (ours: a suggested iso value for the error that asks
//! for one; Otsu 1979, as scikit-image's `threshold_otsu` computes it on a float image): a
//! histogram of [`BINS`] equal bins over [min, max], and the bin centre that maximises the
//! between-class variance `w1 w2 (m1 - m2)^2` of the values at or below it against those
//! above. Nothing is meshed at it unless the user passes it as `--iso`.

use super::volume::with_voxels;
use super::{Volume, Voxel};

/// Histogram bins (scikit-image's default `nbins`).
pub const BINS: usize = 256;

/// Otsu's threshold of `vol`'s scaled values, `None` for a constant or non-finite image.
/// Deterministic (one pass, integer counts).
///
/// ```
/// use oracle::image::{otsu_threshold, Volume, Voxels};
/// use glam::DAffine3;
/// // Two populations around 10 and 200: the threshold falls between them.
/// let v: Vec<f32> = (0..64).map(|i| if i % 2 == 0 { 10.0 + (i % 5) as f32 } else { 200.0 - (i % 7) as f32 }).collect();
/// let vol = Volume::new([4, 4, 4], Voxels::F32(v), DAffine3::IDENTITY)?;
/// let t = otsu_threshold(&vol).unwrap();
/// assert!(t > 14.0 && t < 194.0, "{t}");
/// # Ok::<(), oracle::image::ImageError>(())
/// ```
pub fn otsu_threshold(vol: &Volume) -> Option<f64> {
    let stats = vol.stats().ok()?;
    let (lo, hi) = (stats.min, stats.max);
    if !(hi > lo) {
        return None;
    }
    let (slope, inter) = vol.scaling();
    let width = (hi - lo) / BINS as f64;
    let mut hist = [0u64; BINS];
    fn fill<T: Voxel>(d: &[T], f: impl Fn(f64) -> f64, lo: f64, w: f64, h: &mut [u64; BINS]) {
        for &v in d {
            let b = ((f(v.to_f64()) - lo) / w) as usize;
            h[b.min(BINS - 1)] += 1;
        }
    }
    let scale = |x: f64| slope * x + inter;
    with_voxels!(vol.voxels(), d => fill(d, scale, lo, width, &mut hist));
    let centre = |i: usize| lo + (i as f64 + 0.5) * width;
    let total: u64 = hist.iter().sum();
    let sum: f64 = hist
        .iter()
        .enumerate()
        .map(|(i, &h)| h as f64 * centre(i))
        .sum();
    let (mut w1, mut s1) = (0u64, 0.0f64);
    let mut best = (f64::NEG_INFINITY, centre(0));
    for (i, &h) in hist.iter().enumerate().take(BINS - 1) {
        w1 += h;
        s1 += h as f64 * centre(i);
        let w2 = total - w1;
        if w1 == 0 || w2 == 0 {
            continue;
        }
        let (m1, m2) = (s1 / w1 as f64, (sum - s1) / w2 as f64);
        let var = w1 as f64 * w2 as f64 * (m1 - m2) * (m1 - m2);
        if var > best.0 {
            best = (var, centre(i));
        }
    }
    Some(best.1)
}
