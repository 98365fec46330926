//! The image and mesh formats of issue #20 through the command line: one volume saved as
//! NIfTI, NRRD (raw, gzip, detached), MetaImage (.mha, .mhd + .raw) and OME-Zarr (v2, v3)
//! gives a byte-identical mesh from each; the new mesh outputs (.glb, .vtk, .vtp, .gii) are
//! written and read back; bad and truncated files of each new format give one error line.
//! The fixtures are `fixtures/images/formats/` (made by `make_format_fixtures.py`).

use std::path::{Path, PathBuf};

mod common;
use common::{fixture, json, one_error_line, root, xtask};

fn scratch(test: &str) -> PathBuf {
    common::scratch_dir("xtask-cli-formats", test)
}

fn formats(name: &str) -> String {
    fixture(&format!("images/formats/{name}"))
}

/// Mesh `input` at iso 500, size 1 (no verification: the mesh bytes are what is compared);
/// returns the PLY bytes and the report.
fn mesh(dir: &Path, input: &str, out: &str) -> (Vec<u8>, serde_json::Value) {
    let o = xtask(
        dir,
        &[
            "mesh",
            "-q",
            input,
            "--iso",
            "500",
            "--size",
            "1",
            "--no-verify",
            "-o",
            out,
            "--report",
            "r.json",
        ],
    );
    assert!(
        o.status.success(),
        "{input}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    (
        std::fs::read(dir.join(out)).unwrap(),
        json(&dir.join("r.json")),
    )
}

#[test]
fn one_volume_in_every_format_gives_the_same_mesh() {
    let d = scratch("same_mesh");
    for (group, files) in [
        (
            "oblique",
            &[
                "blob_oblique.nii.gz",
                "blob_oblique_pair.hdr",
                "blob_oblique_pair.img",
                "blob_oblique_gz.nrrd",
                "blob_oblique_detached.nhdr",
                "blob_oblique.mha",
                "blob_oblique.mhd",
            ][..],
        ),
        (
            "aligned",
            &[
                "blob_aligned.nii.gz",
                "blob_aligned.nrrd",
                "blob_aligned.mha",
                "blob_aligned_v2.ome.zarr",
                "blob_aligned_v3.ome.zarr",
            ][..],
        ),
    ] {
        let (reference, r0) = mesh(&d, &formats(files[0]), "ref.ply");
        let vertices = r0["stats"]["vertices"].as_u64().unwrap_or(0);
        assert!(vertices > 100, "{group}: a real mesh ({vertices} vertices)");
        for f in &files[1..] {
            let (m, r) = mesh(&d, &formats(f), "m.ply");
            assert_eq!(
                r["input_stats"]["image"]["affine"], r0["input_stats"]["image"]["affine"],
                "{f}: the same world affine as {}",
                files[0]
            );
            assert!(m == reference, "{f}: the mesh differs from {}'s", files[0]);
        }
        eprintln!(
            "{group}: {} formats, {vertices} vertices, byte-identical",
            files.len()
        );
    }
}

/// The world affine of the oblique fixture, as the generator made it (RAS+, NIfTI's frame):
/// the NRRD/MetaImage LPS headers are read into the same numbers.
#[test]
fn lps_headers_are_read_in_the_nifti_world() {
    let d = scratch("lps");
    let (_, r) = mesh(&d, &formats("blob_oblique.mha"), "m.ply");
    let a = &r["input_stats"]["image"]["affine"];
    // Translation row entries: RAS (-12.375, 30.0625, -7.8125); the header says LPS
    // (12.375, -30.0625, -7.8125).
    let t: Vec<f64> = (0..3).map(|i| a[i][3].as_f64().unwrap()).collect();
    assert_eq!(t, [-12.375, 30.0625, -7.8125]);
    // The voxel sizes 0.5, 1, 2 (column lengths), and a positive determinant (the rotation).
    let col = |j: usize| {
        (0..3)
            .map(|i| a[i][j].as_f64().unwrap().powi(2))
            .sum::<f64>()
            .sqrt()
    };
    for (j, s) in [0.5, 1.0, 2.0].iter().enumerate() {
        assert!((col(j) - s).abs() < 1e-6, "axis {j}: {}", col(j));
    }
}

#[test]
fn every_mesh_output_format_is_written_and_read_back() {
    let d = scratch("outputs");
    let (ply, _) = mesh(&d, &formats("blob_aligned.nii.gz"), "m.ply");
    let reference = meshio::read_from(&ply[..], meshio::Format::Ply, "m.ply").unwrap();
    for ext in ["glb", "vtk", "vtp", "gii"] {
        let name = format!("m.{ext}");
        let _ = mesh(&d, &formats("blob_aligned.nii.gz"), &name);
        let back = meshio::read(d.join(&name)).unwrap();
        assert_eq!(back.triangles, reference.triangles, "{ext}");
        for (a, b) in reference.vertices.iter().zip(&back.vertices) {
            let expect = if ext == "glb" || ext == "gii" {
                a.as_vec3().as_dvec3()
            } else {
                *a
            };
            assert_eq!(*b, expect, "{ext}");
        }
        if ext == "vtk" || ext == "vtp" {
            let text = std::fs::read_to_string(d.join(&name)).unwrap();
            assert!(
                text.contains("min_angle_deg") && text.contains("r_over_sigma"),
                "{ext}"
            );
        }
        // A mesh output is also a mesh input.
        let o = xtask(&d, &["verify", &name]);
        assert!(
            o.status.success(),
            "verify {name}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
}

/// Copies the fixture `name` (a file or a folder) into `dir`.
fn copy(name: &str, dir: &Path) -> PathBuf {
    let src = root().join("fixtures/images/formats").join(name);
    let dst = dir.join(name);
    if src.is_dir() {
        for e in walk(&src) {
            let rel = e.strip_prefix(&src).unwrap();
            std::fs::create_dir_all(dst.join(rel).parent().unwrap()).unwrap();
            std::fs::copy(&e, dst.join(rel)).unwrap();
        }
    } else {
        std::fs::copy(&src, &dst).unwrap();
    }
    dst
}

fn walk(d: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(d).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            out.extend(walk(&p));
        } else {
            out.push(p);
        }
    }
    out
}

/// Runs `mesh` on `input` and asserts one error line holding every word of `words`.
fn refused(dir: &Path, input: &Path, words: &[&str]) {
    let o = xtask(
        dir,
        &["mesh", "-q", input.to_str().unwrap(), "--iso", "500"],
    );
    let line = one_error_line(&o, &[]);
    for w in words {
        assert!(
            line.contains(w),
            "{}: expected {w:?} in: {line}",
            input.display()
        );
    }
}

fn edit(p: &Path, from: &str, to: &str) {
    let b = std::fs::read(p).unwrap();
    let at = b
        .windows(from.len())
        .position(|w| w == from.as_bytes())
        .unwrap();
    let mut out = b[..at].to_vec();
    out.extend_from_slice(to.as_bytes());
    out.extend_from_slice(&b[at + from.len()..]);
    std::fs::write(p, out).unwrap();
}

#[test]
fn bad_nrrd_files_give_one_error_line() {
    let d = scratch("bad_nrrd");
    let p = copy("blob_oblique.nrrd", &d);
    let len = std::fs::metadata(&p).unwrap().len();
    let cut = d.join("cut.nrrd");
    std::fs::write(&cut, &std::fs::read(&p).unwrap()[..len as usize - 1000]).unwrap();
    refused(&d, &cut, &["cut.nrrd", "truncated"]);
    edit(&p, "sizes: 24 20 16", "sizes: 24 20");
    refused(&d, &p, &["blob_oblique.nrrd", "sizes", "3 positive"]);
    let p = copy("blob_oblique_gz.nrrd", &d);
    let b = std::fs::read(&p).unwrap();
    std::fs::write(&p, &b[..b.len() - 300]).unwrap();
    refused(&d, &p, &["blob_oblique_gz.nrrd", "truncated"]);
    let p = copy("blob_oblique_detached.nhdr", &d);
    refused(
        &d,
        &p,
        &["data file", "blob_oblique_detached.raw", "does not exist"],
    );
    let p = copy("blob_oblique.nrrd", &d);
    edit(&p, "type: int16", "type: block");
    refused(&d, &p, &["type", "block", "not supported"]);
    // A 64-bit type is read (since session 42): here the data is too short for it.
    edit(&p, "type: block", "type: int64");
    refused(&d, &p, &["truncated", "61440"]);
    edit(&p, "type: int64", "type: int16");
    edit(&p, "left-posterior-superior", "mars-frame");
    refused(&d, &p, &["space", "mars-frame"]);
}

/// Volume formats the mesher does not read are named, with the conversion, in one error
/// line (they said "unknown mesh file extension" and advised renaming the file).
#[test]
fn unsupported_volume_formats_name_the_conversion() {
    let d = scratch("unsupported_volumes");
    for (name, words) in [
        ("scan.PAR", &["Philips", "dcm2niix"][..]),
        ("brain.mnc", &["MINC", "mnc2nii"][..]),
        ("slice.dcm", &["not a DICOM file", "DICM"][..]),
        ("vol.npy", &["numpy", "mesh_image"][..]),
    ] {
        let p = d.join(name);
        std::fs::write(&p, b"not read").unwrap();
        refused(&d, &p, words);
        let line = one_error_line(
            &xtask(&d, &["mesh", "-q", p.to_str().unwrap(), "--iso", "500"]),
            &[],
        );
        assert!(!line.contains("mesh file extension"), "{line}");
    }
}

/// FreeSurfer volumes are read since 2026-12-07 (they were named and refused, with
/// `mri_convert` as the fix): nibabel's `test.mgz` (a series of two) meshes frame by frame,
/// and a damaged one is one error line naming the file.
#[test]
fn freesurfer_volumes_are_read() {
    let d = scratch("mgz");
    let p = fixture("images/nibabel_test.mgz");
    let err = one_error_line(&xtask(&d, &["mesh", "-q", &p, "--iso", "0"]), &[]);
    assert!(
        err.contains("nframes = 2") && err.contains("--frame K (0 to 1)"),
        "{err}"
    );
    let out = xtask(
        &d,
        &[
            "mesh", "-q", &p, "--iso", "0", "--frame", "1", "-o", "m.ply",
        ],
    );
    assert!(out.status.success(), "{}", common::stderr(&out));
    assert!(std::fs::metadata(d.join("m.ply")).unwrap().len() > 1000);
    let bad = d.join("T1.mgz");
    std::fs::write(&bad, b"not read").unwrap();
    refused(&d, &bad, &["T1.mgz", "gzip"]);
}

/// A colour TIFF stored plane by plane decoded as its red plane alone and was meshed
/// without a word (scikit-image's `multipage_rgb.tif`, the real-data sweep of 2026-12-07):
/// it is refused by its colour type.
#[test]
fn a_colour_tiff_is_refused_not_meshed_from_one_channel() {
    let d = scratch("colour_tiff");
    let p = copy("skimage_multipage_rgb.tif", &d);
    refused(&d, &p, &["skimage_multipage_rgb.tif", "RGB", "not grey"]);
}

#[test]
fn bad_metaimage_files_give_one_error_line() {
    let d = scratch("bad_mha");
    let p = copy("blob_oblique.mha", &d);
    let b = std::fs::read(&p).unwrap();
    let cut = d.join("cut.mha");
    std::fs::write(&cut, &b[..b.len() - 10]).unwrap();
    refused(&d, &cut, &["cut.mha", "truncated"]);
    edit(&p, "MET_SHORT", "MET_STRING");
    refused(&d, &p, &["ElementType", "MET_STRING", "not supported"]);
    edit(&p, "MET_STRING", "MET_LONG_LONG");
    refused(&d, &p, &["truncated", "61440"]);
    let p = copy("blob_oblique.mhd", &d);
    refused(
        &d,
        &p,
        &["ElementDataFile", "blob_oblique.raw", "does not exist"],
    );
    copy("blob_oblique.raw", &d);
    edit(&p, "DimSize = 24 20 16", "DimSize = 24 20 x");
    refused(&d, &p, &["DimSize", "3 positive"]);
}

#[test]
fn bad_zarr_stores_give_one_error_line() {
    let d = scratch("bad_zarr");
    let p = copy("blob_aligned_v2.ome.zarr", &d);
    std::fs::remove_file(p.join("0/.zarray")).unwrap();
    refused(&d, &p, &["0/.zarray", "is missing"]);
    // A missing chunk is the fill value (0 here)...
    let p = d.join("v3");
    std::fs::rename(copy("blob_aligned_v3.ome.zarr", &d), &p).unwrap();
    let chunk = walk(&p.join("0/c")).into_iter().next().unwrap();
    std::fs::remove_file(chunk).unwrap();
    let o = xtask(
        &d,
        &[
            "mesh",
            "-q",
            p.to_str().unwrap(),
            "--iso",
            "500",
            "--size",
            "1.5",
            "--no-verify",
            "-o",
            "z.ply",
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("fill value"),
        "a note says so"
    );
    // ... unless the v2 fill value is null: then it is an error naming the chunk.
    let p = d.join("v2");
    std::fs::rename(copy("blob_aligned_v2.ome.zarr", &d), &p).unwrap();
    edit(
        &p.join("0/.zarray"),
        "\"fill_value\": 0",
        "\"fill_value\": null",
    );
    std::fs::remove_file(p.join("0/1.1.1")).unwrap();
    refused(&d, &p, &["1.1.1", "missing", "fill_value is null"]);
    // A damaged chunk, and a store without OME metadata.
    let p = d.join("v2b");
    std::fs::rename(copy("blob_aligned_v2.ome.zarr", &d), &p).unwrap();
    std::fs::write(p.join("0/0.0.0"), b"not blosc").unwrap();
    refused(&d, &p, &["v2b", "cannot be decoded"]);
    std::fs::write(p.join(".zattrs"), b"{}").unwrap();
    refused(&d, &p, &["multiscales", "is missing"]);
}

#[test]
fn bad_mesh_files_of_the_new_formats_give_one_error_line() {
    let d = scratch("bad_meshes");
    let (ply, _) = mesh(&d, &formats("blob_aligned.nii.gz"), "m.glb");
    assert!(!ply.is_empty());
    for ext in ["glb", "vtk", "vtp", "gii"] {
        let _ = mesh(&d, &formats("blob_aligned.nii.gz"), &format!("m.{ext}"));
        let b = std::fs::read(d.join(format!("m.{ext}"))).unwrap();
        let cut = d.join(format!("cut.{ext}"));
        std::fs::write(&cut, &b[..b.len() * 2 / 3]).unwrap();
        let o = xtask(&d, &["verify", cut.to_str().unwrap()]);
        let line = one_error_line(&o, &[]);
        assert!(line.contains(&format!("cut.{ext}")), "{line}");
    }
}
