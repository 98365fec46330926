//! (ours) Text in pictures: the public-domain 8x8 bitmap font of the `font8x8` crate.

use font8x8::{BASIC_FONTS, UnicodeFonts};

/// The 8 rows of `c` (bit 0 is the leftmost pixel); `?` for characters outside basic Latin.
pub fn glyph(c: char) -> [u8; 8] {
    BASIC_FONTS
        .get(c)
        .or_else(|| BASIC_FONTS.get('?'))
        .unwrap_or([0; 8])
}
