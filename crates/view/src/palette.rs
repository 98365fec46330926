//! (ours) Colours: a sequential map for quality measures (blue to yellow, after cividis, readable
//! by colour-blind viewers), distinct colours for components, and the highlight colour
//! (magenta), which neither map produces.

/// An RGB colour.
pub type Rgb = [u8; 3];

/// The background of pictures and of the HTML view.
pub const BACKGROUND: Rgb = [255, 255, 255];
/// Facets behind a FAIL or an unmet criterion.
pub const HIGHLIGHT: Rgb = [255, 0, 255];
/// Facets whose measure is not known.
pub const UNKNOWN: Rgb = [190, 190, 190];
/// Text and edges.
pub const INK: Rgb = [20, 20, 20];

/// Control points of the sequential map, from t = 0 to 1.
pub const SEQUENTIAL: [Rgb; 5] = [
    [0, 34, 78],
    [60, 77, 110],
    [124, 123, 120],
    [190, 175, 111],
    [255, 233, 69],
];

/// Component colours (Tableau 10 without its pink and purple, which are near the highlight).
pub const CATEGORICAL: [Rgb; 8] = [
    [31, 119, 180],
    [255, 127, 14],
    [44, 160, 44],
    [214, 39, 40],
    [140, 86, 75],
    [127, 127, 127],
    [188, 189, 34],
    [23, 190, 207],
];

/// The sequential map at `t` in [0, 1] (clamped; NaN gives [`UNKNOWN`]).
pub fn sequential(t: f64) -> Rgb {
    if t.is_nan() {
        return UNKNOWN;
    }
    let x = t.clamp(0.0, 1.0) * (SEQUENTIAL.len() - 1) as f64;
    let i = (x.floor() as usize).min(SEQUENTIAL.len() - 2);
    let f = x - i as f64;
    let (a, b) = (SEQUENTIAL[i], SEQUENTIAL[i + 1]);
    [0, 1, 2].map(|k| (a[k] as f64 + f * (b[k] as f64 - a[k] as f64)).round() as u8)
}

/// The colour of class `i` (cycling).
pub fn categorical(i: usize) -> Rgb {
    CATEGORICAL[i % CATEGORICAL.len()]
}

/// `c` scaled by a shading factor in [0, 1].
pub fn shade(c: Rgb, k: f64) -> Rgb {
    c.map(|v| (v as f64 * k.clamp(0.0, 1.0)).round() as u8)
}

/// Whether a pixel is the highlight colour under any shading factor of at least 0.3 (red and
/// blue equal and bright, no green): what the tests count. No sequential or component colour
/// passes it, shaded or not.
pub fn is_highlight(p: Rgb) -> bool {
    let [r, g, b] = p.map(i32::from);
    r >= 70 && (r - b).abs() <= 8 && g * 5 <= r
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_map_colour_looks_like_the_highlight() {
        for i in 0..=100 {
            for k in 0..=10 {
                let c = shade(sequential(i as f64 / 100.0), k as f64 / 10.0);
                assert!(!is_highlight(c), "{c:?}");
            }
        }
        for i in 0..CATEGORICAL.len() {
            for k in 0..=10 {
                assert!(!is_highlight(shade(categorical(i), k as f64 / 10.0)));
            }
        }
        assert!(!is_highlight(BACKGROUND) && !is_highlight(UNKNOWN) && !is_highlight(INK));
        for k in 3..=10 {
            assert!(is_highlight(shade(HIGHLIGHT, k as f64 / 10.0)));
        }
    }

    #[test]
    fn sequential_ends() {
        assert_eq!(sequential(0.0), SEQUENTIAL[0]);
        assert_eq!(sequential(1.0), SEQUENTIAL[4]);
        assert_eq!(sequential(f64::NAN), UNKNOWN);
    }
}
