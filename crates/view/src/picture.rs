//! (ours) The `--picture` PNG: the scene from the front, side and top views of [`crate::camera`],
//! Lambert-shaded, coloured by one measure with a colour bar, the highlighted facets in magenta
//! with a ring around each (when there are few, so that one bad facet is seen at any size).

use crate::camera::{Frame, views};
use crate::palette::{self, BACKGROUND, HIGHLIGHT, INK, Rgb};
use crate::raster::Canvas;
use crate::scene::{Measure, Scene, SceneError};
use glam::DVec3;

/// How to draw a picture.
#[derive(Debug, Clone, PartialEq)]
pub struct PictureOptions {
    /// The measure shown (a key of [`Scene::measures`]); default [`Scene::default_measure`].
    pub measure: Option<String>,
    /// Side of each view's square tile, in pixels (at least 64).
    pub tile: u32,
    /// Draw facet edges: `None` draws them when facets are at least 10 pixels across.
    pub edges: Option<bool>,
}

impl Default for PictureOptions {
    fn default() -> Self {
        PictureOptions {
            measure: None,
            tile: 360,
            edges: None,
        }
    }
}

/// Height of the title lines above the views.
pub const HEADER: u32 = 36;
/// Width of the legend right of the views.
pub const LEGEND: u32 = 250;
/// Highlighted facets get rings when there are at most this many.
const MAX_RINGS: usize = 500;

/// The picture of `scene`: `3 * tile + LEGEND` by `HEADER + tile + 8` pixels.
pub fn picture(scene: &Scene, opts: &PictureOptions) -> Result<image::RgbImage, SceneError> {
    let key = opts
        .measure
        .clone()
        .unwrap_or_else(|| scene.default_measure().to_string());
    let Some(measure) = scene.measure(&key) else {
        let have: Vec<&str> = scene.measures.iter().map(|m| m.key.as_str()).collect();
        return Err(SceneError(format!(
            "no measure '{key}' for this mesh (known here: {})",
            have.join(", ")
        )));
    };
    let tile = opts.tile.max(64);
    let mut c = Canvas::new(3 * tile + LEGEND, HEADER + tile + 8, BACKGROUND);
    let colors = facet_colors(scene, measure);
    let highlighted = scene.highlighted();
    for (i, view) in views(scene.up).into_iter().enumerate() {
        let frame = Frame::fit(
            view,
            &scene.vertices,
            [i as u32 * tile, HEADER],
            [tile, tile],
            12.0,
        );
        draw_view(
            &mut c,
            scene,
            &frame,
            &colors,
            &highlighted,
            opts.edges,
            tile,
        );
        c.text(i as u32 * tile + 6, HEADER + tile - 10, view.name, INK, 1);
    }
    let title: String = scene
        .title
        .chars()
        .take(((3 * tile) / 8) as usize - 2)
        .collect();
    c.text(6, 6, &title, INK, 1);
    let n_high = highlighted.iter().filter(|&&h| h).count();
    let line = if n_high == 0 {
        format!(
            "{} facets; coloured by {}; nothing highlighted",
            scene.triangles.len(),
            measure.label
        )
    } else {
        format!(
            "{} facets; coloured by {}; {n_high} highlighted (magenta)",
            scene.triangles.len(),
            measure.label
        )
    };
    c.text(6, 20, &line, INK, 1);
    legend(&mut c, scene, measure, 3 * tile, tile);
    Ok(c.into_image())
}

/// The PNG bytes of an image.
pub fn encode_png(img: &image::RgbImage) -> Result<Vec<u8>, SceneError> {
    let mut out = Vec::new();
    img.write_with_encoder(image::codecs::png::PngEncoder::new(&mut out))
        .map_err(|e| SceneError(format!("cannot encode the PNG: {e}")))?;
    Ok(out)
}

/// Each facet's colour under `measure` (before shading and highlighting).
pub fn facet_colors(scene: &Scene, m: &Measure) -> Vec<Rgb> {
    let (lo, hi) = m.range().unwrap_or((0.0, 1.0));
    m.values
        .iter()
        .map(|&v| {
            if !v.is_finite() {
                palette::UNKNOWN
            } else if m.categorical {
                palette::categorical(v.max(0.0) as usize)
            } else if hi > lo {
                palette::sequential((v - lo) / (hi - lo))
            } else {
                palette::sequential(0.5)
            }
        })
        .take(scene.triangles.len())
        .collect()
}

fn draw_view(
    c: &mut Canvas,
    scene: &Scene,
    f: &Frame,
    colors: &[Rgb],
    highlighted: &[bool],
    edges: Option<bool>,
    tile: u32,
) {
    let clip = [
        f.origin[0] as u32,
        f.origin[1] as u32,
        f.origin[0] as u32 + tile,
        f.origin[1] as u32 + tile,
    ];
    let v = &f.view;
    let light = (v.toward + 0.5 * v.up - 0.3 * v.right).normalize();
    let corners = |t: &[u32; 3]| t.map(|i| scene.vertices[i as usize]);
    let draw_edges = edges.unwrap_or_else(|| {
        let n = scene.triangles.len().max(1) as f64;
        let mean: f64 = scene
            .triangles
            .iter()
            .map(|t| {
                let [a, b, c] = corners(t);
                (b - a).cross(c - a).length().sqrt()
            })
            .sum::<f64>()
            / n;
        mean * f.scale >= 10.0
    });
    for (i, t) in scene.triangles.iter().enumerate() {
        let p = corners(t);
        let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
        let k = 0.3 + 0.7 * n.dot(light).abs();
        let base = if highlighted[i] { HIGHLIGHT } else { colors[i] };
        let col = palette::shade(base, if highlighted[i] { k.max(0.6) } else { k });
        let edge = draw_edges.then(|| palette::shade(col, 0.6));
        c.triangle(p.map(|q| f.pixel(q)), col, edge, clip);
    }
    let marked: Vec<usize> = (0..highlighted.len()).filter(|&i| highlighted[i]).collect();
    if marked.len() <= MAX_RINGS {
        for i in marked {
            let p = corners(&scene.triangles[i]);
            let centroid: DVec3 = (p[0] + p[1] + p[2]) / 3.0;
            let [x, y, z] = f.pixel(centroid);
            if x < clip[0] as f64
                || y < clip[1] as f64
                || x >= clip[2] as f64
                || y >= clip[3] as f64
            {
                continue;
            }
            // Visible: nothing drawn there is nearer than the facet by more than 2 pixels.
            if c.depth_at(x as u32, y as u32) <= z + 2.0 / f.scale {
                c.ring(x, y, 7.0, HIGHLIGHT, clip);
            }
        }
    }
}

/// The colour bar (or the component swatches) and the list of highlights.
fn legend(c: &mut Canvas, scene: &Scene, m: &Measure, x0: u32, tile: u32) {
    let mut y = HEADER + 4;
    for line in wrap(&m.label, 28) {
        c.text(x0 + 8, y, &line, INK, 1);
        y += 12;
    }
    y += 6;
    if m.categorical {
        let count = m.range().map_or(0, |(_, hi)| hi as usize + 1);
        for i in 0..count.min(8) {
            c.rect(x0 + 8, y, 14, 10, palette::categorical(i));
            c.text(x0 + 28, y + 1, &format!("{i}"), INK, 1);
            y += 14;
        }
        if count > 8 {
            c.text(
                x0 + 8,
                y,
                &format!("{count} in all (colours repeat)"),
                INK,
                1,
            );
            y += 14;
        }
    } else if let Some((lo, hi)) = m.range() {
        let h = (tile / 2).max(40);
        for j in 0..h {
            // Top is the largest value.
            let t = 1.0 - j as f64 / (h - 1) as f64;
            c.rect(x0 + 8, y + j, 22, 1, palette::sequential(t));
        }
        c.text(x0 + 36, y, &fmt_value(hi), INK, 1);
        c.text(x0 + 36, y + h - 8, &fmt_value(lo), INK, 1);
        if let Some(b) = m.bound.filter(|b| *b >= lo && *b <= hi && hi > lo) {
            let yb = y + ((hi - b) / (hi - lo) * (h - 1) as f64).round() as u32;
            c.rect(x0 + 4, yb, 30, 2, INK);
            c.text(
                x0 + 36,
                yb.saturating_sub(3).max(y + 10).min(y + h - 18),
                &format!("bound {}", fmt_value(b)),
                INK,
                1,
            );
        }
        y += h + 8;
    } else {
        c.text(x0 + 8, y, "(not known for any facet)", INK, 1);
        y += 14;
    }
    y += 8;
    for h in &scene.highlights {
        if y + 24 > c.height {
            break;
        }
        c.rect(x0 + 8, y, 14, 10, HIGHLIGHT);
        let mut first = true;
        for line in wrap(&format!("{}: {}", h.facets.len(), h.reason), 26) {
            c.text(x0 + 28, y + 1, &line, INK, 1);
            y += 12;
            if !first && y + 12 > c.height {
                break;
            }
            first = false;
        }
        y += 4;
    }
}

/// A value for the colour bar: 4 significant digits, plain or scientific.
fn fmt_value(v: f64) -> String {
    if v != 0.0 && (v.abs() >= 1e5 || v.abs() < 1e-3) {
        format!("{v:.3e}")
    } else {
        format!("{:.4}", v)
            .trim_end_matches('0')
            .trim_end_matches('.')
            .to_string()
    }
}

/// `s` cut into lines of at most `w` characters at spaces.
fn wrap(s: &str, w: usize) -> Vec<String> {
    let mut lines = Vec::new();
    let mut cur = String::new();
    for word in s.split_whitespace() {
        if !cur.is_empty() && cur.chars().count() + 1 + word.chars().count() > w {
            lines.push(std::mem::take(&mut cur));
        }
        if !cur.is_empty() {
            cur.push(' ');
        }
        cur.push_str(word);
    }
    if !cur.is_empty() {
        lines.push(cur);
    }
    lines
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A grid of `n x n` squares in the plane z = 0, two triangles each.
    fn grid(n: u32) -> meshio::TriMesh {
        let mut m = meshio::TriMesh {
            vertices: Vec::new(),
            triangles: Vec::new(),
        };
        for j in 0..=n {
            for i in 0..=n {
                m.vertices.push(DVec3::new(i as f64, j as f64, 0.0));
            }
        }
        for j in 0..n {
            for i in 0..n {
                let v = j * (n + 1) + i;
                m.triangles.push([v, v + 1, v + n + 2]);
                m.triangles.push([v, v + n + 2, v + n + 1]);
            }
        }
        m
    }

    fn highlight_pixels(img: &image::RgbImage) -> usize {
        img.pixels().filter(|p| palette::is_highlight(p.0)).count()
    }

    #[test]
    fn one_tiny_highlighted_facet_is_ringed_and_pictures_are_deterministic() {
        let mut s = Scene::new(&grid(200), "grid").unwrap();
        // An open grid: its border facets are highlighted (closed: boundary edge); keep only
        // one interior facet instead.
        s.highlights.clear();
        let img = picture(&s, &PictureOptions::default()).unwrap();
        assert_eq!(highlight_pixels(&img), 0);
        s.add_highlight("test: one facet", [40_401]);
        let img = picture(&s, &PictureOptions::default()).unwrap();
        // The facet is under a pixel across in the top view; its ring is not.
        assert!(highlight_pixels(&img) >= 30, "{}", highlight_pixels(&img));
        let again = picture(&s, &PictureOptions::default()).unwrap();
        assert_eq!(encode_png(&img).unwrap(), encode_png(&again).unwrap());
        let e = picture(
            &s,
            &PictureOptions {
                measure: Some("nope".into()),
                ..Default::default()
            },
        );
        assert!(e.unwrap_err().0.contains("min_angle, component"));
    }

    #[test]
    fn values_and_wrapping() {
        assert_eq!(fmt_value(30.0), "30");
        assert_eq!(fmt_value(0.12345), "0.1235");
        assert_eq!(fmt_value(1e-5), "1.000e-5");
        assert_eq!(wrap("a bb ccc dddd", 6), vec!["a bb", "ccc", "dddd"]);
    }
}
