//! Morton (Z-order) keys (ours): an order of points that keeps near points near, for running
//! many spatial queries in a cache-friendly order. The order changes no result.

use glam::DVec3;

/// Spread the low 21 bits of `v` to every third bit (bit `k` to bit `3k`).
#[inline]
pub fn spread(v: u64) -> u64 {
    let mut x = v & 0x1f_ffff;
    x = (x | (x << 32)) & 0x1f_0000_0000_ffff;
    x = (x | (x << 16)) & 0x1f_0000_ff00_00ff;
    x = (x | (x << 8)) & 0x100f_00f0_0f00_f00f;
    x = (x | (x << 4)) & 0x10c3_0c30_c30c_30c3;
    x = (x | (x << 2)) & 0x1249_2492_4924_9249;
    x
}

/// The Morton key of `p` in the cube of center `center` and half side `half` (21 bits per
/// axis; points outside the cube, and NaN coordinates, are clamped to its faces).
pub fn morton_key(p: DVec3, center: DVec3, half: f64) -> u64 {
    let scale = (1u64 << 21) as f64 / (2.0 * half);
    let q = |x: f64, c: f64| -> u64 {
        let t = ((x - c + half) * scale).clamp(0.0, ((1u64 << 21) - 1) as f64);
        if t.is_nan() { 0 } else { t as u64 }
    };
    spread(q(p.x, center.x)) | (spread(q(p.y, center.y)) << 1) | (spread(q(p.z, center.z)) << 2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spread_moves_bit_k_to_bit_3k() {
        for k in 0..21 {
            assert_eq!(spread(1 << k), 1u64 << (3 * k));
        }
        assert_eq!(spread(0x1f_ffff), 0x1249_2492_4924_9249);
        assert_eq!(spread(1 << 21), 0, "only the low 21 bits");
    }

    #[test]
    fn keys_interleave_the_axes_and_clamp() {
        let c = DVec3::ZERO;
        assert_eq!(morton_key(DVec3::splat(-1.0), c, 1.0), 0);
        // The top corner: every bit set.
        assert_eq!(morton_key(DVec3::splat(1.0), c, 1.0), (1u64 << 63) - 1);
        // Halfway along x only: the top x bit (bit 60).
        assert_eq!(morton_key(DVec3::new(0.0, -1.0, -1.0), c, 1.0), 1u64 << 60);
        assert_eq!(morton_key(DVec3::new(-1.0, 0.0, -1.0), c, 1.0), 1u64 << 61);
        // NaN x and z below: 0; y above: every y bit.
        assert_eq!(
            morton_key(DVec3::new(f64::NAN, 5.0, -9.0), c, 1.0),
            0x1249_2492_4924_9249 << 1
        );
    }
}
