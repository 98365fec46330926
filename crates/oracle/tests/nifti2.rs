//! NIfTI-2 files (540-byte header, 64-bit `dim` and `vox_offset`, double-precision fields):
//! headers built byte by byte here after `nifti2.h`, in both byte orders and as a `.hdr`/`.img`
//! pair, read to the last bit of their f64 sform; nibabel's `example_nifti2.nii.gz` (a 4D
//! int16 series) read frame by frame; a NIfTI-2 size with another magic is an error.

use glam::{DAffine3, DMat3, DVec3};
use oracle::image::{ImageError, read_nifti, read_nifti_frame};
use std::path::{Path, PathBuf};

fn tmpdir(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("oracle-nifti2-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The sform of the hand-built files: not representable in f32 (0.1, 1/3).
const SROW: [[f64; 4]; 3] = [
    [0.1, 0.0, 0.0, -12.345678901234],
    [0.0, 1.0 / 3.0, 0.0, 7.25],
    [0.0, 0.0, 2.0, 0.000001],
];

/// A NIfTI-2 header for `dims` int16 voxels (little or big endian), magic `n+2` (single file,
/// `vox_offset` 544) or `ni2` (pair, offset 0).
fn header(dims: &[i64], big: bool, single: bool) -> Vec<u8> {
    let mut h = vec![0u8; 540];
    let mut put = |at: usize, b: &[u8]| {
        let mut b = b.to_vec();
        if big {
            b.reverse();
        }
        h[at..at + b.len()].copy_from_slice(&b);
    };
    put(0, &540i32.to_le_bytes());
    put(12, &4i16.to_le_bytes()); // datatype int16
    put(14, &16i16.to_le_bytes()); // bitpix
    put(16, &(dims.len() as i64).to_le_bytes());
    for (i, d) in dims.iter().enumerate() {
        put(24 + 8 * i, &d.to_le_bytes());
    }
    for i in 0..8 {
        put(104 + 8 * i, &1.0f64.to_le_bytes()); // pixdim
    }
    put(168, &(if single { 544i64 } else { 0 }).to_le_bytes());
    put(348, &1i32.to_le_bytes()); // sform_code
    for (r, row) in SROW.iter().enumerate() {
        for (c, v) in row.iter().enumerate() {
            put(400 + 32 * r + 8 * c, &v.to_le_bytes());
        }
    }
    let magic: &[u8] = if single { b"n+2\0" } else { b"ni2\0" };
    h[4..8].copy_from_slice(magic);
    h[8..12].copy_from_slice(b"\r\n\x1a\n");
    h
}

fn voxels(n: usize, big: bool) -> (Vec<u8>, Vec<f64>) {
    let v: Vec<i16> = (0..n).map(|i| (i as i16 * 37) % 101 - 50).collect();
    let bytes = v
        .iter()
        .flat_map(|x| {
            if big {
                x.to_be_bytes()
            } else {
                x.to_le_bytes()
            }
        })
        .collect();
    (bytes, v.iter().map(|&x| x as f64).collect())
}

fn values(v: &oracle::image::Volume) -> Vec<f64> {
    (0..v.len()).map(|i| v.voxels().get_f64(i)).collect()
}

fn expected_affine() -> DAffine3 {
    let c = |j: usize| DVec3::new(SROW[0][j], SROW[1][j], SROW[2][j]);
    DAffine3::from_mat3_translation(DMat3::from_cols(c(0), c(1), c(2)), c(3))
}

#[test]
fn a_nifti2_file_is_read_with_its_f64_sform_in_both_byte_orders() {
    let dir = tmpdir("orders");
    for big in [false, true] {
        let mut b = header(&[4, 3, 5], big, true);
        b.extend_from_slice(&[0; 4]);
        let (data, vals) = voxels(60, big);
        b.extend_from_slice(&data);
        let p = dir.join(format!("v{big}.nii"));
        std::fs::write(&p, &b).unwrap();
        let v = read_nifti(&p).unwrap();
        assert_eq!(v.dims(), [4, 3, 5]);
        assert_eq!(values(&v), vals, "big endian {big}");
        assert_eq!(v.affine(), expected_affine(), "bit for bit");
    }
    // A .hdr/.img pair, opened by either name.
    let (data, vals) = voxels(60, false);
    std::fs::write(dir.join("p.hdr"), header(&[4, 3, 5], false, false)).unwrap();
    std::fs::write(dir.join("p.img"), &data).unwrap();
    for name in ["p.hdr", "p.img"] {
        assert_eq!(values(&read_nifti(dir.join(name)).unwrap()), vals);
    }
}

#[test]
fn a_nifti2_series_reads_frame_by_frame_and_bad_headers_are_named() {
    let dir = tmpdir("series");
    let mut b = header(&[2, 3, 2, 3], false, true);
    b.extend_from_slice(&[0; 4]);
    let (data, vals) = voxels(36, false);
    b.extend_from_slice(&data);
    let p = dir.join("s.nii");
    std::fs::write(&p, &b).unwrap();
    for k in 0..3 {
        let v = read_nifti_frame(&p, Some(k)).unwrap();
        assert_eq!(values(&v), vals[12 * k..12 * (k + 1)]);
    }
    assert!(matches!(
        read_nifti(&p),
        Err(ImageError::FourD { frames: 3, .. })
    ));
    // The voxels may not start inside the header.
    let mut bad = b.clone();
    bad[168..176].copy_from_slice(&540i64.to_le_bytes());
    std::fs::write(&p, &bad).unwrap();
    let msg = read_nifti_frame(&p, Some(0)).unwrap_err().to_string();
    assert!(
        msg.contains("vox_offset") && msg.contains("at least 544"),
        "{msg}"
    );
    // sizeof_hdr 540 with a NIfTI-1 magic; a header cut short.
    let mut bad = b.clone();
    bad[4..8].copy_from_slice(b"n+1\0");
    std::fs::write(&p, &bad).unwrap();
    let msg = read_nifti(&p).unwrap_err().to_string();
    assert!(
        msg.contains("sizeof_hdr is 540 (NIfTI-2) but the magic"),
        "{msg}"
    );
    std::fs::write(&p, &b[..400]).unwrap();
    let e = read_nifti(&p).unwrap_err();
    assert!(matches!(e, ImageError::Truncated { .. }), "{e}");
}

#[test]
fn nibabel_example_nifti2_reads_as_a_series_of_two() {
    // nibabel's example_nifti2.nii.gz: 32 x 20 x 12 x 2 int16, sform and qform codes 1.
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/images/nibabel_example_nifti2.nii.gz");
    assert!(matches!(
        read_nifti(&p),
        Err(ImageError::FourD { frames: 2, .. })
    ));
    let a = read_nifti_frame(&p, Some(0)).unwrap();
    let b = read_nifti_frame(&p, Some(1)).unwrap();
    assert_eq!(a.dims(), [32, 20, 12]);
    assert_eq!(a.affine(), b.affine());
    // The affine nibabel reports (`img.affine`), to its printed digits.
    let m = a.affine();
    assert!((m.matrix3.x_axis.x + 2.0).abs() < 1e-6, "{m:?}");
    assert!((m.translation.x - 117.8551).abs() < 1e-3, "{m:?}");
    assert!((m.matrix3.y_axis.z - 0.3232).abs() < 1e-3, "{m:?}");
    assert_ne!(values(&a), values(&b));
}
