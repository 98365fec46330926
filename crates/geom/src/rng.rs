//! SplitMix64 (ours; Steele, Lea & Flood 2014, the generator of Java's `SplittableRandom`):
//! the one seeded generator of the workspace. Every seeded choice (oracle seeds, random lines,
//! tests, the CGAL benchmark's point sets) draws from it, so the sequences are fixed by the
//! seed alone: changing the arithmetic here changes every mesh.

use glam::DVec3;

/// The SplitMix64 generator; the field is the state (the seed before the first draw).
///
/// ```
/// use geom::SplitMix64;
/// let mut r = SplitMix64(1);
/// assert_eq!(r.next_u64(), 0x910a_2dec_8902_5cc1);
/// let x = r.next_f64();
/// assert!((0.0..1.0).contains(&x));
/// ```
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SplitMix64(pub u64);

impl SplitMix64 {
    /// A generator with state `seed`.
    pub fn new(seed: u64) -> Self {
        SplitMix64(seed)
    }

    /// The next 64 random bits.
    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1): the top 53 bits of [`Self::next_u64`] times 2⁻⁵³ (the same value as
    /// dividing by 2⁵³, which the copies of this generator elsewhere do).
    #[inline]
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform in [lo, hi): `lo + (hi - lo) * next_f64()`.
    #[inline]
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next_f64()
    }

    /// Uniform on the unit sphere (rejection from the cube [-1, 1)³, three draws per try).
    pub fn unit_vector(&mut self) -> DVec3 {
        loop {
            let v = DVec3::new(
                2.0 * self.next_f64() - 1.0,
                2.0 * self.next_f64() - 1.0,
                2.0 * self.next_f64() - 1.0,
            );
            let l2 = v.length_squared();
            if l2 > 1e-6 && l2 <= 1.0 {
                return v / l2.sqrt();
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reference_sequence() {
        // Reference values of SplitMix64 from seed 0 (Vigna's splitmix64.c).
        let mut r = SplitMix64(0);
        assert_eq!(r.next_u64(), 0xe220_a839_7b1d_cdaf);
        assert_eq!(r.next_u64(), 0x6e78_9e6a_a1b9_65f4);
        assert_eq!(r.next_u64(), 0x06c4_5d18_8009_454f);
    }

    #[test]
    fn unit_draws_equal_the_division_form() {
        let (mut a, mut b) = (SplitMix64(42), SplitMix64(42));
        for _ in 0..10_000 {
            let x = a.next_f64();
            let y = (b.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
            assert_eq!(x.to_bits(), y.to_bits());
            assert!((0.0..1.0).contains(&x));
        }
        let v = SplitMix64(3).unit_vector();
        assert!((v.length() - 1.0).abs() < 1e-15);
    }
}
