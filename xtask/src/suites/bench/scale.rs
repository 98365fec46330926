//! Scale group of `cargo xtask bench` (not in the paper: issue 21's table): the catalog
//! torus at ~10^4, 10^5, 10^6 output vertices and a 256^3 tanglecube image at two sizes,
//! with time, vertices/s and peak memory, beside CGAL's Surface_mesher (`--vs-cgal`) at the
//! sizes it finishes in minutes (here: up to ~10^5 vertices).
//!
//! Peak memory: before each run the process's peak RSS is reset (`5` written to
//! `/proc/self/clear_refs`, Linux >= 4.0) and `VmHWM` is read after it; `peak_mib` is that
//! whole-process peak (it includes the resident set at the reset, `base_mib`, a few MiB).
//! Bytes per vertex are `(peak - base) / vertices`.

use super::cgal::{CgalBaseline, cgal_criteria_args};
use super::common::{BenchArgs, Row, cgal_mesh_options, median};
use anyhow::Result;
use oracle::image::{ImageOptions, ImageSurface, synthetic};
use std::time::Instant;

/// `VmHWM` and `VmRSS` of this process in bytes (0 where /proc is not readable).
fn vm_kib(key: &str) -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with(key))
                .and_then(|l| l.split_whitespace().nth(1)?.parse::<u64>().ok())
        })
        .unwrap_or(0)
        * 1024
}

/// Resets the peak RSS; returns the resident set at the reset.
fn reset_peak() -> u64 {
    let _ = std::fs::write("/proc/self/clear_refs", "5");
    vm_kib("VmRSS:")
}

/// The torus radii (angle 30, radius = distance = r) for ~10^4, 10^5, 10^6 vertices
/// (vertices ~ 8.0e3 / r^2 on the catalog torus, from r = 0.0097: 83 453 and r = 0.003:
/// 870 745), and whether CGAL runs beside us.
const TORUS: [(f64, bool); 3] = [(0.028, true), (0.0089, true), (0.0028, false)];
/// The 256^3 tanglecube radii: 25k vertices (figure 8's setting), and ~10x that.
const IMAGE: [(f64, bool); 2] = [(0.052, true), (0.0164, false)];

struct Case {
    label: String,
    size_note: &'static str,
    r: f64,
    cgal: Option<CgalBaseline>,
}

/// The cases of the scale table: the torus sizes, then (without `--quick`) the image sizes,
/// each with its CGAL baseline where `--vs-cgal` asks for one and CGAL finishes in minutes.
fn scale_cases(a: &BenchArgs) -> Vec<Case> {
    let mut cases = Vec::new();
    let torus_cases: &[(f64, bool)] = if a.quick { &TORUS[..1] } else { &TORUS };
    for &(r, with_cgal) in torus_cases {
        cases.push(Case {
            label: format!("torus r={r}"),
            size_note: "torus",
            r,
            cgal: CgalBaseline::new(
                a.vs_cgal && with_cgal,
                "cgal_surface_mesher",
                [
                    vec!["--surface".into(), "torus".into()],
                    cgal_criteria_args(r),
                    vec!["--manifold".into()],
                ]
                .concat(),
            ),
        });
    }
    if !a.quick {
        for &(r, with_cgal) in &IMAGE {
            cases.push(Case {
                label: format!("tanglecube 256^3 r={r}"),
                size_note: "image",
                r,
                cgal: CgalBaseline::new(
                    a.vs_cgal && with_cgal,
                    "cgal_image_mesher",
                    [
                        vec![
                            "--tanglecube-grid".into(),
                            "256".into(),
                            "--iso".into(),
                            "0".into(),
                        ],
                        cgal_criteria_args(r),
                    ]
                    .concat(),
                ),
            });
        }
    }
    cases
}

pub fn bench_scale(a: &BenchArgs, rows: &mut Vec<Row>) -> Result<()> {
    let torus = oracle::catalog::surface("torus")?;
    let cases = scale_cases(a);
    let vol = (!a.quick).then(|| {
        std::sync::Arc::new(synthetic::sample_implicit(
            synthetic::tanglecube,
            [256; 3],
            synthetic::cube_affine(256, 4.0),
        ))
    });
    let iso = ImageOptions {
        iso: Some(0.0),
        dark_foreground: true,
        ..Default::default()
    };
    for mut c in cases {
        let opts = cgal_mesh_options(c.r);
        let (mut times, mut peaks) = (Vec::new(), Vec::new());
        let (mut base, mut last) = (0, None);
        for _ in 0..a.runs {
            let image = match (c.size_note, &vol) {
                ("image", Some(v)) => Some(ImageSurface::new_shared(v.clone(), &iso)?),
                _ => None,
            };
            base = reset_peak();
            let t = Instant::now();
            let out = match &image {
                Some(s) => rdt_mesher::mesh(s, &opts)?,
                None => rdt_mesher::mesh(&torus, &opts)?,
            };
            times.push(t.elapsed().as_secs_f64());
            peaks.push(vm_kib("VmHWM:"));
            last = Some(out.stats.clone());
            drop(out);
            drop(image);
            if let Some(cg) = c.cgal.as_mut() {
                cg.run_once()?;
            }
        }
        let st = last.expect("at least one run");
        let med = median(&mut times.clone());
        let peak = *peaks.iter().max().unwrap_or(&0);
        let mib = |b: u64| b as f64 / (1u64 << 20) as f64;
        eprintln!(
            "scale {}: {} vertices, median {med:.3} s ({:.0} v/s; Delaunay {:.3} s, oracle {:.3} s), peak {:.0} MiB (base {:.0} MiB), {:.0} B/vertex",
            c.label,
            st.vertices,
            st.vertices as f64 / med,
            st.time_delaunay_s,
            st.time_oracle_s,
            mib(peak),
            mib(base),
            (peak.saturating_sub(base)) as f64 / st.vertices.max(1) as f64,
        );
        rows.push(Row {
            group: "scale".into(),
            case: c.label.clone(),
            tool: "rdt".into(),
            median_s: med,
            runs: times,
            size: st.vertices,
            size_unit: "vertices".into(),
            extra: serde_json::json!({
                "radius": c.r, "distance": c.r, "angle": 30,
                "peak_mib": mib(peak), "base_mib": mib(base),
                "bytes_per_vertex": (peak.saturating_sub(base)) as f64 / st.vertices.max(1) as f64,
                "time_delaunay_s": st.time_delaunay_s, "time_oracle_s": st.time_oracle_s,
                "facets": st.facets, "criteria_met": st.criteria_met,
            }),
        });
        if let Some(cg) = c.cgal {
            let row = cg.row("scale", &c.label, "vertices", "vertices");
            eprintln!(
                "scale {} (cgal): {} vertices, median {:.3} s, peak {:.0} MiB (getrusage of the child: a forked child starts with the parent's high-water mark, so this is at least ours)",
                c.label,
                row.size,
                row.median_s,
                row.extra["peak_rss_bytes"].as_f64().unwrap_or(0.0) / (1u64 << 20) as f64
            );
            rows.push(row);
        }
    }
    Ok(())
}
