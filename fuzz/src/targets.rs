//! (ours) The bodies of the fuzz targets. Each takes arbitrary bytes; a panic, a hang or an
//! allocation beyond the fuzzer's limit is a bug. Where a property holds for every accepted
//! input (a read mesh round-trips, a triangulation validates), the target asserts it.
//!
//! Shared by the cargo-fuzz binaries (`fuzz/fuzz_targets/*.rs`) and by the corpus replay
//! test of the workspace (`xtask/tests/fuzz_corpus.rs`), which runs every file of
//! `fuzz/corpus/TARGET/` through the same function.

use glam::{DAffine3, DVec3};
use std::io::Cursor;
use std::path::PathBuf;
use std::time::Duration;

/// A fuzz target's body.
pub type Target = fn(&[u8]);

/// Every target by name, for the corpus replay.
pub const TARGETS: &[(&str, Target)] = &[
    ("mesh_formats", mesh_formats),
    ("xyz", xyz),
    ("nifti", nifti),
    ("tiff", tiff),
    ("raw", raw),
    ("expr", expr),
    ("delaunay", delaunay),
    ("mesh_expr", mesh_expr),
    ("mesh_image", mesh_image),
];

/// A scratch file for the readers that take a path, one per process and thread.
fn scratch(ext: &str, data: &[u8]) -> PathBuf {
    let tid = format!("{:?}", std::thread::current().id());
    let tid: String = tid.chars().filter(|c| c.is_ascii_digit()).collect();
    let p = std::env::temp_dir().join(format!("rdt-fuzz-{}-{tid}.{ext}", std::process::id()));
    std::fs::write(&p, data).expect("scratch file");
    p
}

/// PLY, OFF, OBJ and STL (first byte picks the format). An accepted mesh must survive a
/// binary PLY round trip unchanged.
pub fn mesh_formats(data: &[u8]) {
    use meshio::Format;
    let Some((&sel, rest)) = data.split_first() else {
        return;
    };
    let format = [Format::Ply, Format::Off, Format::Obj, Format::Stl][sel as usize % 4];
    let Ok(mesh) = meshio::read_from(Cursor::new(rest), format, "fuzz-input") else {
        return;
    };
    let mut buf = Vec::new();
    meshio::write_to(
        &mut buf,
        &mesh,
        Format::Ply,
        meshio::Options::default(),
        "fuzz-out",
    )
    .expect("writing an accepted mesh");
    let back = meshio::read_from(Cursor::new(&buf), Format::Ply, "fuzz-out").expect("re-read");
    assert_eq!(back.triangles, mesh.triangles);
    assert_eq!(back.vertices.len(), mesh.vertices.len());
    for (a, b) in back.vertices.iter().zip(&mesh.vertices) {
        assert_eq!(
            a.to_array().map(f64::to_bits),
            b.to_array().map(f64::to_bits)
        );
    }
}

/// `.xyz` point sets: every accepted point is finite.
pub fn xyz(data: &[u8]) {
    let p = scratch("xyz", data);
    let r = oracle::pointset::read_xyz(&p);
    let _ = std::fs::remove_file(&p);
    if let Ok(cloud) = r {
        assert!(cloud.points.iter().all(|p| p.is_finite()));
    }
}

/// NIfTI-1/2, plain or gzip (first byte): an accepted volume has finite statistics work and
/// a finite, invertible affine.
pub fn nifti(data: &[u8]) {
    let Some((&sel, rest)) = data.split_first() else {
        return;
    };
    let ext = if sel & 1 == 0 { "nii" } else { "nii.gz" };
    let p = scratch(ext, rest);
    let r = oracle::image::load_volume(&p, &Default::default());
    let _ = std::fs::remove_file(&p);
    if let Ok(vol) = r {
        let a = vol.affine();
        assert!(a.matrix3.determinant().is_finite() && a.matrix3.determinant() != 0.0);
        let _ = vol.stats();
    }
}

/// Multi-page TIFF stacks.
pub fn tiff(data: &[u8]) {
    let p = scratch("tif", data);
    let r = oracle::image::load_volume(&p, &Default::default());
    let _ = std::fs::remove_file(&p);
    if let Ok(vol) = r {
        let _ = vol.stats();
    }
}

/// Raw volumes: the first four bytes give dims (1-16 each), dtype and endianness.
pub fn raw(data: &[u8]) {
    use oracle::image::{Dtype, RawOptions};
    if data.len() < 4 {
        return;
    }
    let dims = [0, 1, 2].map(|i| data[i] as usize % 16 + 1);
    let dtypes = [
        Dtype::U8,
        Dtype::I8,
        Dtype::U16,
        Dtype::I16,
        Dtype::U32,
        Dtype::I32,
        Dtype::F32,
        Dtype::F64,
    ];
    let raw = RawOptions {
        dims,
        dtype: dtypes[data[3] as usize % 8],
        big_endian: data[3] & 8 != 0,
        offset: 0,
    };
    let p = scratch("raw", &data[4..]);
    let r = oracle::image::read_raw(&p, &raw, None);
    let _ = std::fs::remove_file(&p);
    if let Ok(vol) = r {
        assert_eq!(vol.len(), dims.iter().product::<usize>());
        let _ = vol.stats();
    }
}

/// The expression parser and evaluator: any accepted expression evaluates without a panic.
pub fn expr(data: &[u8]) {
    let src = String::from_utf8_lossy(data);
    if let Ok(e) = oracle::expr::Expr::parse(&src) {
        for p in [DVec3::ZERO, DVec3::new(0.3, -1.7, 2.5), DVec3::splat(1e300)] {
            let _ = e.eval(p);
            let _ = e.eval_grad(p);
        }
    }
}

/// Delaunay insertion of adversarial points: small integer coordinates (duplicates,
/// coplanar and cospherical sets) at a scale the first byte picks; the triangulation must
/// validate after every accepted input.
pub fn delaunay(data: &[u8]) {
    let Some((&sel, rest)) = data.split_first() else {
        return;
    };
    let scale = [1.0, 0.5, 1e-3, 1e3, 1e-150, 1e150, 3.0e-308, 1.7e308][sel as usize % 8];
    let mut t = delaunay3::Triangulation::new();
    for c in rest.chunks_exact(3).take(400) {
        let p = DVec3::new(
            c[0] as i8 as f64,
            c[1] as i8 as f64,
            c[2] as i8 as f64 / 4.0,
        ) * scale;
        let _ = t.insert(p);
    }
    assert!(t.is_valid().is_ok(), "{:?}", t.is_valid());
}

/// Options for the mesher targets: a small budget so that every input ends quickly.
fn budget(sigma: f64) -> rdt_mesher::MeshOptions {
    rdt_mesher::MeshOptions {
        criteria: rdt_mesher::Criteria::uniform(sigma),
        max_vertices: Some(3000),
        time_limit: Some(Duration::from_secs(2)),
        ..Default::default()
    }
}

/// A random expression through the whole mesher.
pub fn mesh_expr(data: &[u8]) {
    let Some((&sel, rest)) = data.split_first() else {
        return;
    };
    let src = String::from_utf8_lossy(rest);
    let bs = oracle::BoundingSphere {
        center: DVec3::ZERO,
        radius: 2.0,
    };
    let Ok(s) = oracle::implicit::ImplicitSurface::from_expr(&src, bs) else {
        return;
    };
    let sigma = [0.2, 0.5, 1.0, 0.05][sel as usize % 4];
    let _ = rdt_mesher::mesh(&s, &budget(sigma));
}

/// A tiny u8 image (2-8 voxels a side) through the whole mesher at iso 127.5.
pub fn mesh_image(data: &[u8]) {
    use oracle::image::{ImageOptions, ImageSurface, Volume, Voxels};
    if data.len() < 3 {
        return;
    }
    let dims = [0, 1, 2].map(|i| data[i] as usize % 7 + 2);
    let n: usize = dims.iter().product();
    let mut vox: Vec<u8> = data[3..].iter().copied().take(n).collect();
    vox.resize(n, 0);
    let Ok(vol) = Volume::new(dims, Voxels::U8(vox), DAffine3::IDENTITY) else {
        return;
    };
    let opts = ImageOptions {
        iso: Some(127.5),
        ..Default::default()
    };
    let Ok(s) = ImageSurface::new(vol, &opts) else {
        return;
    };
    let _ = rdt_mesher::mesh(&s, &budget(0.7));
}
