//! Seeing the mesh: `--picture` PNGs (the mesh in frame in each view, the highlight on a
//! mesh with a planted defect and not on a clean one) and the HTML viewer in headless
//! chromium (drawn, the colour mode changes it, no network request in chromium's net log).

mod common;
use common::*;
use std::path::{Path, PathBuf};
use std::process::Command;
use view::palette::{BACKGROUND, is_highlight};
use view::picture::HEADER;

/// The tile side of the default picture.
const TILE: u32 = 360;

fn png(path: &Path) -> image::RgbImage {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert!(
        bytes.starts_with(b"\x89PNG\r\n\x1a\n"),
        "{} is not a PNG",
        path.display()
    );
    image::load_from_memory(&bytes).unwrap().to_rgb8()
}

/// Per view: (mesh pixels, highlight pixels, bounding box of the mesh pixels), over the tile
/// without its bottom label line.
fn tiles(img: &image::RgbImage) -> Vec<(u32, u32, [u32; 4])> {
    assert_eq!(img.height(), HEADER + TILE + 8);
    (0..3)
        .map(|i| {
            let (mut mesh, mut high, mut bb) = (0, 0, [u32::MAX, u32::MAX, 0, 0]);
            for y in HEADER..HEADER + TILE - 14 {
                for x in i * TILE..(i + 1) * TILE {
                    let p = img.get_pixel(x, y).0;
                    if p != BACKGROUND {
                        mesh += 1;
                        let (lx, ly) = (x - i * TILE, y - HEADER);
                        bb = [bb[0].min(lx), bb[1].min(ly), bb[2].max(lx), bb[3].max(ly)];
                    }
                    high += u32::from(is_highlight(p));
                }
            }
            (mesh, high, bb)
        })
        .collect()
}

/// A small sphere mesh, meshed by the command (`dir/sphere.ply`).
fn sphere(dir: &Path) -> PathBuf {
    let o = xtask_line(dir, "mesh implicit:sphere --size 0.25 -q -o sphere.ply");
    assert!(o.status.success(), "{}", stderr(&o));
    dir.join("sphere.ply")
}

#[test]
fn mesh_picture_shows_the_mesh_in_frame_in_every_view() {
    let d = scratch_dir("view", "mesh_picture");
    let o = xtask_line(
        &d,
        "mesh implicit:torus --size 0.1 -q -o t.ply --picture t.png --html",
    );
    assert!(o.status.success(), "{}", stderr(&o));
    has(&stdout(&o), &["wrote t.png", "wrote t.html"]);
    let img = png(&d.join("t.png"));
    let t = tiles(&img);
    for (i, (mesh, high, bb)) in t.iter().enumerate() {
        let area = TILE * (TILE - 14);
        // The torus (radii 1, 0.3) seen edge-on covers about a quarter of its box, from
        // above about 60 %: in between here, never empty, never the whole tile.
        assert!(
            *mesh > area / 20 && *mesh < area * 9 / 10,
            "view {i}: {mesh} of {area}"
        );
        assert_eq!(*high, 0, "view {i}: a PASS mesh has nothing highlighted");
        // In frame: the mesh fills most of the tile's width and touches no border.
        assert!(
            bb[0] >= 4 && bb[2] <= TILE - 5 && bb[1] >= 4,
            "view {i}: {bb:?}"
        );
        assert!(bb[2] - bb[0] > TILE * 3 / 4, "view {i}: {bb:?}");
    }
    // The front and side views see the ring edge-on (flat), the top view sees the hole.
    let h = |i: usize| t[i].2[3] - t[i].2[1];
    assert!(h(0) * 2 < h(2) && h(1) * 2 < h(2), "{t:?}");
    let top = &t[2].2;
    let c = [(top[0] + top[2]) / 2, (top[1] + top[3]) / 2 + HEADER];
    assert_eq!(
        img.get_pixel(2 * TILE + c[0], c[1]).0,
        BACKGROUND,
        "the hole of the torus"
    );
}

/// Writes `m` as OFF.
fn write_off(path: &Path, m: &meshio::TriMesh) {
    let mut s = format!("OFF\n{} {} 0\n", m.vertices.len(), m.triangles.len());
    for p in &m.vertices {
        s += &format!("{} {} {}\n", p.x, p.y, p.z);
    }
    for t in &m.triangles {
        s += &format!("3 {} {} {}\n", t[0], t[1], t[2]);
    }
    std::fs::write(path, s).unwrap();
}

#[test]
fn verify_picture_highlights_a_hole_and_a_nonmanifold_edge() {
    let d = scratch_dir("view", "verify_defects");
    let good = sphere(&d);
    let m = meshio::read(&good).unwrap();
    // Control: the clean mesh passes, and its picture has no highlight.
    let o = xtask(
        &d,
        &["verify", good.to_str().unwrap(), "--picture", "good.png"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let clean: u32 = tiles(&png(&d.join("good.png"))).iter().map(|t| t.1).sum();
    assert_eq!(clean, 0);

    // A hole: drop one facet (three facets around it meet a boundary edge).
    let mut holed = m.clone();
    holed.triangles.remove(0);
    write_off(&d.join("holed.off"), &holed);
    // A non-manifold edge: a fin on the first facet's edge, to a new vertex outside.
    let mut fin = m.clone();
    let [a, b, _] = fin.triangles[0];
    let mid = (fin.vertices[a as usize] + fin.vertices[b as usize]) * 0.75;
    fin.vertices.push(mid);
    fin.triangles.push([a, b, fin.vertices.len() as u32 - 1]);
    write_off(&d.join("fin.off"), &fin);
    for (mesh, failing) in [("holed.off", "closed"), ("fin.off", "edge-manifold")] {
        let pic = format!("{mesh}.png");
        let o = xtask(&d, &["verify", mesh, "--picture", &pic]);
        assert!(!o.status.success(), "{mesh} must FAIL");
        has(&stdout(&o), &[&format!("FAIL {failing}")]);
        let t = tiles(&png(&d.join(&pic)));
        let high: u32 = t.iter().map(|t| t.1).sum();
        // Three facets (holed) or three facets at one edge (fin), each ringed in every
        // view where it is seen: far more than stray pixels.
        assert!(high >= 40, "{mesh}: {high} highlight pixels: {t:?}");
    }
}

/// Headless chromium, or None (with the reason printed) when it is not installed.
fn chromium() -> Option<PathBuf> {
    let p = PathBuf::from("/usr/bin/chromium");
    if p.exists() {
        Some(p)
    } else {
        eprintln!("skipped: /usr/bin/chromium is not installed (CI installs it: .ci/run)");
        None
    }
}

/// Runs chromium headless on `url` with `extra` flags (a fresh profile each time).
fn browse(dir: &Path, name: &str, url: &str, extra: &[String]) -> std::process::Output {
    let profile = dir.join(format!("profile-{name}"));
    let _ = std::fs::remove_dir_all(&profile);
    let mut args: Vec<String> = [
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--use-angle=swiftshader",
        "--enable-unsafe-swiftshader",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--no-first-run",
        "--window-size=1000,700",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    args.push(format!("--user-data-dir={}", profile.display()));
    args.extend(extra.iter().cloned());
    args.push(url.to_string());
    let o = Command::new("/usr/bin/chromium")
        .args(&args)
        .output()
        .expect("cannot run chromium");
    assert!(o.status.success(), "chromium failed: {}", stderr(&o));
    o
}

/// The network requests a page started, from chromium's net log: the URL_REQUEST_START_JOB
/// events whose initiator is an origin (the page's, `null` for a file) and not the browser's
/// own background requests (initiator `not an origin`).
fn page_requests(netlog: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(netlog).unwrap();
    let log: serde_json::Value = serde_json::from_str(&text)
        .unwrap_or_else(|e| panic!("{}: not a complete net log: {e}", netlog.display()));
    let start = &log["constants"]["logEventTypes"]["URL_REQUEST_START_JOB"];
    assert!(
        start.is_u64(),
        "the net log names no URL_REQUEST_START_JOB event type"
    );
    let events = log["events"].as_array().expect("net log events");
    events
        .iter()
        .filter(|e| &e["type"] == start && e["params"]["initiator"] != "not an origin")
        .filter_map(|e| e["params"]["url"].as_str())
        .filter(|u| !u.starts_with("file:") && !u.starts_with("data:"))
        .map(str::to_string)
        .collect()
}

/// Pixels of the view (left of the 360-pixel panel): (drawn, blue-dominant).
fn drawn(img: &image::RgbImage) -> (u32, u32, Vec<[u8; 3]>) {
    let (mut n, mut blue, mut px) = (0, 0, Vec::new());
    for y in 0..img.height() {
        for x in 0..600.min(img.width()) {
            let p = img.get_pixel(x, y).0;
            if p != BACKGROUND {
                n += 1;
                let [r, g, b] = p.map(i32::from);
                blue += u32::from(b > r + 40 && b > g);
            }
            px.push(p);
        }
    }
    (n, blue, px)
}

#[test]
fn html_viewer_draws_in_chromium_and_the_colour_mode_changes_it() {
    let Some(_) = chromium() else { return };
    let d = scratch_dir("view", "html_chromium");
    let o = xtask_line(
        &d,
        "mesh implicit:torus --size 0.1 -q -o t.ply --report t.json --html t.html",
    );
    assert!(o.status.success(), "{}", stderr(&o));
    // `view` gives the same page from the mesh and its report.
    let o = xtask_line(&d, "view t.ply --report t.json -o v.html");
    assert!(o.status.success(), "{}", stderr(&o));
    let page = std::fs::read_to_string(d.join("v.html")).unwrap();
    // Without the surface the page has no per-facet ball measures; with it, r/sigma (the
    // report's sigma) and the distance, as `mesh --html` has.
    lacks(&page, &["\"key\":\"r_sigma\"", "\"key\":\"distance\""]);
    let o = xtask_line(
        &d,
        "view t.ply --report t.json --against implicit:torus -o w.html",
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let with = std::fs::read_to_string(d.join("w.html")).unwrap();
    has(&with, &["\"key\":\"r_sigma\"", "\"key\":\"distance\""]);
    let from_mesh = std::fs::read_to_string(d.join("t.html")).unwrap();
    has(&from_mesh, &["\"key\":\"r_sigma\"", "\"key\":\"distance\""]);
    lacks(&page, &["http://", "https://", " src=", " href="]);
    has(&page, &["Content-Security-Policy", "default-src 'none'"]);
    let url = |hash: &str| format!("file://{}#{hash}", d.join("v.html").display());

    // The net log of the first screenshot: no request started by the page.
    let netlog = d.join("net.json");
    let mut shots = Vec::new();
    for (name, hash) in [
        ("component", "color=component&edges=0"),
        ("angle", "color=min_angle&edges=0"),
        ("canvas2d", "color=component&edges=0&renderer=2d"),
    ] {
        let shot = d.join(format!("{name}.png"));
        let mut flags = vec![format!("--screenshot={}", shot.display())];
        if name == "component" {
            flags.push(format!("--log-net-log={}", netlog.display()));
        }
        browse(&d, name, &url(hash), &flags);
        shots.push(drawn(&png(&shot)));
    }
    let area = 600 * 700;
    for (i, (n, _, _)) in shots.iter().enumerate() {
        // The torus at the default three-quarter view covers a sizeable part of the view.
        assert!(
            *n > area / 20 && *n < area * 9 / 10,
            "shot {i}: {n} of {area} pixels drawn"
        );
    }
    // One component: all blue (the first component colour); by angle: mostly not.
    let (comp, angle, flat) = (&shots[0], &shots[1], &shots[2]);
    assert!(
        comp.1 * 10 > comp.0 * 9,
        "component mode: {} of {} blue",
        comp.1,
        comp.0
    );
    assert!(
        angle.1 * 2 < angle.0,
        "angle mode: {} of {} blue",
        angle.1,
        angle.0
    );
    let changed = comp.2.iter().zip(&angle.2).filter(|(a, b)| a != b).count() as u32;
    assert!(
        changed * 2 > comp.0,
        "switching the colour mode changed {changed} pixels"
    );
    // The 2D-canvas fallback draws the same mesh in the same place, within a few percent.
    assert!(
        flat.1 * 10 > flat.0 * 9,
        "2d canvas: {} of {} blue",
        flat.1,
        flat.0
    );
    assert!(
        flat.0.abs_diff(comp.0) * 10 < comp.0,
        "{} vs {}",
        flat.0,
        comp.0
    );

    let asked = page_requests(&netlog);
    assert!(
        asked.is_empty(),
        "the viewer asked the network for {asked:?}"
    );
    // Control: the same check sees a page that asks (a local port that refuses).
    let leak = d.join("leak.html");
    std::fs::write(&leak, "<img src=\"http://127.0.0.1:9/x.png\">").unwrap();
    let leak_log = d.join("leak.json");
    browse(
        &d,
        "leak",
        &format!("file://{}", leak.display()),
        &[
            format!("--log-net-log={}", leak_log.display()),
            "--dump-dom".into(),
        ],
    );
    let leaked = page_requests(&leak_log);
    assert!(
        leaked.iter().any(|u| u == "http://127.0.0.1:9/x.png"),
        "{leaked:?}"
    );

    // The page chose WebGL and fetched nothing (its resource timing list is empty).
    let dom = stdout(&browse(&d, "dom", &url(""), &["--dump-dom".into()]));
    has(
        &dom,
        &[
            "<span id=\"renderer\">webgl</span>",
            "<span id=\"fetched\">0</span>",
            "verify: PASS",
        ],
    );
}

#[test]
fn bad_view_flags_and_files_give_one_error_line() {
    let d = scratch_dir("view", "errors");
    let s = sphere(&d);
    let s = s.to_str().unwrap();
    let o = xtask_line(&d, "mesh implicit:sphere --size 0.3 -q --picture p.jpg");
    let e = one_error_line(&o, &["note:", "forecast:"]);
    has(&e, &["--picture p.jpg", ".png"]);
    assert!(!d.join("out").exists(), "refused before meshing");
    let e = one_error_line(&xtask(&d, &["verify", s, "--up", "w"]), &[]);
    has(&e, &["--up w", "x, y or z"]);
    let e = one_error_line(&xtask(&d, &["view", s, "-o", "v.png"]), &[]);
    has(&e, &["v.png", ".html"]);
    let e = one_error_line(&xtask(&d, &["view", "missing.ply", "-o", "v.html"]), &[]);
    has(&e, &["missing.ply"]);
    std::fs::write(d.join("bad.json"), "{ not json").unwrap();
    let e = one_error_line(
        &xtask(&d, &["view", s, "--report", "bad.json", "-o", "v.html"]),
        &[],
    );
    has(&e, &["--report bad.json", "not JSON"]);
    // The report of another mesh is refused.
    let o = xtask_line(
        &d,
        "mesh implicit:torus --size 0.3 -q -o t.ply --report t.json",
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let e = one_error_line(
        &xtask(&d, &["view", s, "--report", "t.json", "-o", "v.html"]),
        &[],
    );
    has(&e, &["t.json", "triangles", "give the report of this mesh"]);
    assert!(!d.join("v.html").exists());
}
