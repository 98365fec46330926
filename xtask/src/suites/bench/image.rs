//! Image group of `cargo xtask bench`: the voxel-image oracle through the mesher on float32
//! tanglecube volumes, beside CGAL's grey-level image mesher (`cgal_image_mesher`) with
//! `--vs-cgal`.
//!
//! Cases (both grids span [-4, 4]^3 with nodes at -4 + i h, h = 8 / (N - 1), the grid of
//! `cgal_image_mesher --tanglecube-grid N`; criteria angle 30, radius = distance = r):
//! - 128^3, r = 0.06 (about one voxel): the CGAL comparison (19.5k vertices);
//! - 256^3, r = 0.052: about 25k vertices (the paper's figure 8 setting).
//!
//! Row `rdt` times the topology scan (seeds) plus `rdt_mesher::mesh` on an already loaded
//! volume (CGAL's `seconds` also excludes its INR read). The NIfTI read of the same volume
//! (`.nii`, uncompressed, from a temporary file), the scan alone and the d_M^inf estimate (not
//! needed with a given size) are reported separately in `extra` and on stderr.
//!
//! Measured 2026-11-22 06:36-06:55 UTC on the 2-vCPU machine (`cargo xtask bench image
//! --vs-cgal --runs 9`, CGAL alternating with us run by run): 128^3, 18 538 vertices in
//! 0.095-0.105 s vs CGAL 19 493 in 0.77-0.86 s (7.6-8.2x; 5.55-6.8x in the VM's lost-core
//! phases, where the tuner runs sequential batches; one thread 5.3-6.0x); 256^3, 24 764
//! vertices in 0.166-0.186 s vs CGAL 25 869 in 1.12-1.21 s (6.5-6.8x). Separately: .nii read
//! 0.004 / 0.037 s, scan 0.003 / 0.016 s, d_M^inf 0.06 / 0.38 s (not needed with a size;
//! `mesh` computes it on first use only).

use super::cgal::{CgalBaseline, cgal_criteria_args};
use super::common::{BenchArgs, Row, cgal_mesh_options, median};
use anyhow::{Context, Result};
use oracle::image::{ImageOptions, ImageSurface, NiftiWriteOptions, synthetic};
use std::time::Instant;

pub fn bench_image(a: &BenchArgs, rows: &mut Vec<Row>) -> Result<()> {
    let mut cases: Vec<(usize, f64)> = vec![(128, 0.06)];
    if !a.quick {
        cases.push((256, 0.052));
    }
    let dir = std::env::temp_dir().join(format!("rdt_bench_image_{}", std::process::id()));
    std::fs::create_dir_all(&dir).with_context(|| format!("cannot create {}", dir.display()))?;
    for (n, r) in cases {
        let case = format!("tanglecube {n}^3 r={r}");
        let vol = synthetic::sample_implicit(
            synthetic::tanglecube,
            [n; 3],
            synthetic::cube_affine(n, 4.0),
        );
        let path = dir.join(format!("tanglecube_{n}.nii"));
        oracle::image::write_nifti(&path, &vol, &NiftiWriteOptions::new())?;
        drop(vol);
        let iso = ImageOptions {
            iso: Some(0.0),
            dark_foreground: true,
            ..Default::default()
        };
        let opts = cgal_mesh_options(r);
        let mut cgal = CgalBaseline::new(
            a.vs_cgal,
            "cgal_image_mesher",
            [
                vec![
                    "--tanglecube-grid".into(),
                    n.to_string(),
                    "--iso".into(),
                    "0".into(),
                ],
                cgal_criteria_args(r),
                vec![
                    "--write-inr".into(),
                    dir.join(format!("cgal_tanglecube_{n}.inr"))
                        .display()
                        .to_string(),
                ],
            ]
            .concat(),
        );
        let (mut load, mut scan, mut dm, mut times) = (vec![], vec![], vec![], vec![]);
        let mut last = None;
        for _ in 0..a.runs {
            let t = Instant::now();
            let vol = std::sync::Arc::new(oracle::image::read_nifti(&path)?);
            load.push(t.elapsed().as_secs_f64());
            // Scan alone (on its own surface), then d_M^inf alone.
            let s = ImageSurface::new_shared(vol.clone(), &iso)?;
            let t = Instant::now();
            let comps = s.component_count();
            scan.push(t.elapsed().as_secs_f64());
            let t = Instant::now();
            let dm_inf = s.dm_inf_estimate();
            dm.push(t.elapsed().as_secs_f64());
            // Timed: scan + mesh on a fresh surface.
            let s = ImageSurface::new_shared(vol, &iso)?;
            let t = Instant::now();
            let out = rdt_mesher::mesh(&s, &opts)?;
            times.push(t.elapsed().as_secs_f64());
            last = Some((out, comps, dm_inf));
            if let Some(c) = cgal.as_mut() {
                c.run_once()?;
            }
        }
        let (out, comps, dm_inf) = last.expect("at least one run");
        let st = &out.stats;
        let topo = verify::topology::analyze(&out.mesh, 4);
        let chi: Vec<i64> = topo
            .components
            .iter()
            .map(|c| c.euler_characteristic)
            .collect();
        let med = median(&mut times.clone());
        eprintln!(
            "image {case}: load (.nii read) {:.3} s, scan {:.3} s ({comps} component), d_M^inf {:.3} s ({:.4}); scan+mesh {med:.3} s: {} vertices (Delaunay {:.3} s, oracle {:.3} s), chi {chi:?}, closed manifold {}",
            median(&mut load.clone()),
            median(&mut scan.clone()),
            median(&mut dm.clone()),
            dm_inf.unwrap_or(f64::NAN),
            st.vertices,
            st.time_delaunay_s,
            st.time_oracle_s,
            topo.is_closed_oriented_manifold(),
        );
        rows.push(Row {
            group: "image".into(),
            case: case.clone(),
            tool: "rdt".into(),
            median_s: med,
            runs: times,
            size: st.vertices,
            size_unit: "vertices".into(),
            extra: serde_json::json!({
                "grid": n, "radius": r, "distance": r, "angle": 30,
                "load_s": median(&mut load.clone()), "scan_s": median(&mut scan.clone()),
                "dm_inf_s": median(&mut dm.clone()), "dm_inf": dm_inf,
                "mesh_time_total_s": st.time_total_s, "time_delaunay_s": st.time_delaunay_s,
                "time_oracle_s": st.time_oracle_s, "facets": st.facets,
                "scan_components": comps, "mesh_components": topo.components.len(),
                "euler": chi, "closed_manifold": topo.is_closed_oriented_manifold(),
                "criteria_met": st.criteria_met,
            }),
        });
        let _ = std::fs::remove_file(&path);
        if let Some(c) = cgal {
            rows.push(c.row("image", &case, "vertices", "vertices"));
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    Ok(())
}
