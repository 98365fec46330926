//! (ours) The HTML viewer: one self-contained page (inline script, inline data, no request to
//! any server) that rotates, zooms and colours the mesh by each measure of the [`Scene`], with
//! toggles for the edges and the highlighted facets, and the summary, the checks and the
//! certificate of the report beside the view. The script is `viewer.js` beside this file.

use crate::camera::views;
use crate::palette;
use crate::scene::Scene;
use glam::DVec3;
use serde_json::{Value, json};

const SCRIPT: &str = include_str!("viewer.js");

const STYLE: &str = "html,body{margin:0;height:100%;font:13px sans-serif;color:#141414}\
#wrap{display:flex;height:100%}#view{flex:1;min-width:0;height:100%;display:block;background:#fff;cursor:grab}\
#panel{width:360px;flex:none;overflow-y:auto;overflow-x:hidden;background:#eef0f3;padding:10px;box-sizing:border-box}\
h1{font-size:15px;margin:0 0 8px;word-break:break-all}h2{font-size:13px;margin:12px 0 4px}\
.bar{height:14px;border:1px solid #888}.barlab{display:flex;justify-content:space-between}\
.sw{display:inline-block;width:12px;height:10px;border:1px solid #666}.small{font-size:11px;color:#444}\
table{border-collapse:collapse;font-size:11px}td{border-top:1px solid #ccd;padding:2px 4px;vertical-align:top}\
tr.FAIL td:first-child{color:#b00;font-weight:bold}tr.PASS td:first-child{color:#070}\
label{display:block;margin:3px 0}select{max-width:250px}";

/// The browser itself forbids every fetch: scripts and styles only inline, images only from
/// `data:`, no connection.
const POLICY: &str =
    "default-src 'none'; script-src 'unsafe-inline'; style-src 'unsafe-inline'; img-src data:";

/// The page for `scene` (deterministic: the same scene gives the same bytes).
pub fn html(scene: &Scene) -> String {
    let data = data(scene).to_string().replace('<', "\\u003c");
    let title = escape(&scene.title);
    format!(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
<meta name=\"viewport\" content=\"width=device-width\">\
<meta http-equiv=\"Content-Security-Policy\" content=\"{POLICY}\">\
<title>{title} - rdt-mesher view</title><style>{STYLE}</style></head><body>\
<div id=\"wrap\"><canvas id=\"view\"></canvas><div id=\"panel\">\
<h1 id=\"title\"></h1>\
<label>colour by <select id=\"color\"></select></label>\
<label><input type=\"checkbox\" id=\"edges\"> edges</label>\
<label><input type=\"checkbox\" id=\"fail\"> highlight the facets behind a FAIL</label>\
<button id=\"reset\">reset view</button> <span class=\"small\">drag: rotate, wheel: zoom; renderer <span id=\"renderer\"></span>; network requests <span id=\"fetched\"></span></span>\
<div id=\"legend\"></div><h2>summary</h2><div id=\"summary\"></div>\
<h2>certificate</h2><div id=\"certificate\"></div><h2>checks</h2><table id=\"checks\"></table>\
</div></div>\
<script type=\"application/json\" id=\"mesh-data\">{data}</script>\
<script>{SCRIPT}</script></body></html>\n"
    )
}

/// The inlined data: positions centred and scaled to the unit ball (float32, base64),
/// triangles (uint32, base64), measures (float32, base64), highlights, palette, front view.
fn data(scene: &Scene) -> Value {
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for p in &scene.vertices {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    let (center, radius) = if lo.is_finite() {
        (
            (lo + hi) / 2.0,
            ((hi - lo).length() / 2.0).max(f64::MIN_POSITIVE),
        )
    } else {
        (DVec3::ZERO, 1.0)
    };
    let mut pos = Vec::with_capacity(12 * scene.vertices.len());
    for p in &scene.vertices {
        for c in ((*p - center) / radius).to_array() {
            pos.extend_from_slice(&(c as f32).to_le_bytes());
        }
    }
    let mut tri = Vec::with_capacity(12 * scene.triangles.len());
    for t in &scene.triangles {
        for v in t {
            tri.extend_from_slice(&v.to_le_bytes());
        }
    }
    let measures: Vec<Value> = scene
        .measures
        .iter()
        .map(|m| {
            let mut b = Vec::with_capacity(4 * m.values.len());
            for v in &m.values {
                b.extend_from_slice(&(*v as f32).to_le_bytes());
            }
            json!({"key": m.key, "label": m.label, "bound": m.bound,
                   "categorical": m.categorical, "values": base64(&b)})
        })
        .collect();
    let highlights: Vec<Value> = scene
        .highlights
        .iter()
        .map(|h| json!({"reason": h.reason, "facets": h.facets}))
        .collect();
    let front = views(scene.up)[0];
    let many = scene.triangles.len() > 20_000;
    json!({
        "title": scene.title,
        "summary": scene.summary,
        "report": scene.report,
        "positions": base64(&pos),
        "triangles": base64(&tri),
        "measures": measures,
        "highlights": highlights,
        "default_measure": scene.default_measure(),
        "edges_default": !many,
        "view": [front.right.to_array(), front.up.to_array(), front.toward.to_array()],
        "palette": {
            "sequential": palette::SEQUENTIAL,
            "categorical": palette::CATEGORICAL,
            "highlight": palette::HIGHLIGHT,
            "unknown": palette::UNKNOWN,
            "background": palette::BACKGROUND,
        },
    })
}

/// Standard base64 with padding.
fn base64(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for c in bytes.chunks(3) {
        let n = (c[0] as u32) << 16
            | (*c.get(1).unwrap_or(&0) as u32) << 8
            | *c.get(2).unwrap_or(&0) as u32;
        for k in 0..4 {
            if k <= c.len() {
                s.push(A[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

/// `s` safe inside HTML text.
fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_known_values() {
        assert_eq!(base64(b""), "");
        assert_eq!(base64(b"f"), "Zg==");
        assert_eq!(base64(b"fo"), "Zm8=");
        assert_eq!(base64(b"foo"), "Zm9v");
        assert_eq!(base64(b"foobar"), "Zm9vYmFy");
    }

    #[test]
    fn page_has_no_remote_reference_and_escapes_the_data() {
        let m = meshio::TriMesh {
            vertices: vec![DVec3::ZERO, DVec3::X, DVec3::Y],
            triangles: vec![[0, 1, 2]],
        };
        let mut s = Scene::new(&m, "a</script><b>").unwrap();
        s.summary.push("</script>".into());
        let page = html(&s);
        assert_eq!(
            page.matches("</script>").count(),
            2,
            "only the two script tags close"
        );
        for bad in ["http://", "https://", "src=", "href=", "@import", "url("] {
            assert!(!page.contains(bad), "{bad}");
        }
    }
}
