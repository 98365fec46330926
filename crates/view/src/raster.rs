//! (ours) A small z-buffer rasterizer: flat-coloured triangles with a depth test, facet edges,
//! rectangles and bitmap text. Written here because the maintained 2D rasterizers (tiny-skia)
//! have no depth buffer, and three orthographic views of a closed surface need one. Pixel
//! centres are sampled at (x + 0.5, y + 0.5); depth ties keep the first facet drawn, so the
//! picture depends only on the order of the triangles.

use crate::font;
use crate::palette::Rgb;

/// An RGB image with a depth buffer (larger depth is nearer the viewer).
pub struct Canvas {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<Rgb>,
    depth: Vec<f64>,
}

/// A pixel rectangle `[x0, y0, x1, y1)` that drawing is clipped to.
pub type Clip = [u32; 4];

impl Canvas {
    /// A `width x height` canvas filled with `background`, depth at minus infinity.
    pub fn new(width: u32, height: u32, background: Rgb) -> Canvas {
        let n = width as usize * height as usize;
        Canvas {
            width,
            height,
            pixels: vec![background; n],
            depth: vec![f64::NEG_INFINITY; n],
        }
    }

    /// The pixel at `(x, y)`.
    pub fn get(&self, x: u32, y: u32) -> Rgb {
        self.pixels[y as usize * self.width as usize + x as usize]
    }

    /// The depth at `(x, y)` (minus infinity where nothing was drawn).
    pub fn depth_at(&self, x: u32, y: u32) -> f64 {
        self.depth[y as usize * self.width as usize + x as usize]
    }

    fn clip(&self, c: Clip) -> Clip {
        [
            c[0].min(self.width),
            c[1].min(self.height),
            c[2].min(self.width),
            c[3].min(self.height),
        ]
    }

    /// Fills the triangle `p` (pixel x, y, depth) where it is nearer than what is drawn.
    /// Pixels within half a pixel of an edge take `edge` when given. Either orientation.
    pub fn triangle(&mut self, p: [[f64; 3]; 3], color: Rgb, edge: Option<Rgb>, clip: Clip) {
        let area =
            (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[1][1] - p[0][1]) * (p[2][0] - p[0][0]);
        if area == 0.0 || !area.is_finite() {
            return;
        }
        let c = self.clip(clip);
        let xs = [p[0][0], p[1][0], p[2][0]];
        let ys = [p[0][1], p[1][1], p[2][1]];
        let lo_x = xs
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min)
            .floor()
            .max(c[0] as f64) as u32;
        let hi_x = xs
            .iter()
            .copied()
            .fold(f64::NEG_INFINITY, f64::max)
            .ceil()
            .min(c[2] as f64) as u32;
        let lo_y = ys
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min)
            .floor()
            .max(c[1] as f64) as u32;
        let hi_y = ys
            .iter()
            .copied()
            .fold(f64::NEG_INFINITY, f64::max)
            .ceil()
            .min(c[3] as f64) as u32;
        // Edge k runs from vertex k+1 to k+2, opposite vertex k.
        let len: [f64; 3] = std::array::from_fn(|k| {
            let (a, b) = (p[(k + 1) % 3], p[(k + 2) % 3]);
            (b[0] - a[0]).hypot(b[1] - a[1])
        });
        for y in lo_y..hi_y {
            for x in lo_x..hi_x {
                let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
                let w: [f64; 3] = std::array::from_fn(|k| {
                    let (a, b) = (p[(k + 1) % 3], p[(k + 2) % 3]);
                    ((b[0] - a[0]) * (py - a[1]) - (b[1] - a[1]) * (px - a[0])) / area
                });
                if w.iter().any(|&v| v < 0.0) {
                    continue;
                }
                let z = w[0] * p[0][2] + w[1] * p[1][2] + w[2] * p[2][2];
                let i = y as usize * self.width as usize + x as usize;
                if z <= self.depth[i] {
                    continue;
                }
                self.depth[i] = z;
                // Distance to edge k in pixels: w_k times the height over that edge.
                let near_edge = (0..3).any(|k| w[k] * area.abs() / len[k] < 0.5);
                self.pixels[i] = match edge {
                    Some(e) if near_edge => e,
                    _ => color,
                };
            }
        }
    }

    /// Fills a rectangle (no depth test).
    pub fn rect(&mut self, x: u32, y: u32, w: u32, h: u32, color: Rgb) {
        for yy in y..(y + h).min(self.height) {
            for xx in x..(x + w).min(self.width) {
                self.pixels[yy as usize * self.width as usize + xx as usize] = color;
            }
        }
    }

    /// Draws a ring of radius `r` and width 2 around `(cx, cy)` (no depth test).
    pub fn ring(&mut self, cx: f64, cy: f64, r: f64, color: Rgb, clip: Clip) {
        let c = self.clip(clip);
        let (x0, x1) = (
            (cx - r - 2.0).floor().max(c[0] as f64) as u32,
            (cx + r + 2.0).ceil().min(c[2] as f64) as u32,
        );
        let (y0, y1) = (
            (cy - r - 2.0).floor().max(c[1] as f64) as u32,
            (cy + r + 2.0).ceil().min(c[3] as f64) as u32,
        );
        for y in y0..y1 {
            for x in x0..x1 {
                let d = (x as f64 + 0.5 - cx).hypot(y as f64 + 0.5 - cy);
                if (d - r).abs() <= 1.0 {
                    self.pixels[y as usize * self.width as usize + x as usize] = color;
                }
            }
        }
    }

    /// Writes `s` with its top-left corner at `(x, y)`, 8 pixels per character times `scale`.
    pub fn text(&mut self, x: u32, y: u32, s: &str, color: Rgb, scale: u32) {
        for (n, ch) in s.chars().enumerate() {
            let g = font::glyph(ch);
            for (row, bits) in g.iter().enumerate() {
                for col in 0..8u32 {
                    if bits >> col & 1 == 1 {
                        let px = x + (n as u32 * 8 + col) * scale;
                        let py = y + row as u32 * scale;
                        self.rect(px, py, scale, scale, color);
                    }
                }
            }
        }
    }

    /// The canvas as an `image` buffer.
    pub fn into_image(self) -> image::RgbImage {
        let raw: Vec<u8> = self.pixels.iter().flatten().copied().collect();
        image::RgbImage::from_raw(self.width, self.height, raw)
            .unwrap_or_else(|| unreachable!("width * height pixels of 3 bytes"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearer_triangle_wins_in_either_order() {
        let far = [[0.0, 0.0, 0.0], [10.0, 0.0, 0.0], [0.0, 10.0, 0.0]];
        let near = [[0.0, 0.0, 1.0], [0.0, 10.0, 1.0], [10.0, 0.0, 1.0]];
        for order in [[far, near], [near, far]] {
            let mut c = Canvas::new(10, 10, [255; 3]);
            let colors = if order[0] == far {
                [[1, 1, 1], [2, 2, 2]]
            } else {
                [[2, 2, 2], [1, 1, 1]]
            };
            c.triangle(order[0], colors[0], None, [0, 0, 10, 10]);
            c.triangle(order[1], colors[1], None, [0, 0, 10, 10]);
            assert_eq!(c.get(2, 2), [2, 2, 2]);
            assert_eq!(c.get(9, 9), [255; 3]);
        }
    }

    #[test]
    fn clip_and_text_stay_in_bounds() {
        let mut c = Canvas::new(20, 10, [255; 3]);
        c.triangle(
            [[-50.0, -50.0, 0.0], [80.0, 0.0, 0.0], [0.0, 80.0, 0.0]],
            [0; 3],
            None,
            [5, 0, 10, 10],
        );
        assert_eq!(c.get(4, 4), [255; 3]);
        assert_eq!(c.get(6, 4), [0; 3]);
        c.text(15, 5, "W8", [0; 3], 1);
        c.ring(19.0, 9.0, 5.0, [0; 3], [0, 0, 99, 99]);
    }
}
