//! DICOM volumes on real files that packages ship (`fixtures/images/dicom`, see its README):
//! pydicom's RT Dose grid (a multi-frame volume placed by `GridFrameOffsetVector`) against the
//! values and positions pydicom gives, nibabel's Philips enhanced MR header against the affine
//! of nibabel's `dicomwrappers`, and the refusals (one slice, compressed pixel data, no
//! geometry, two series, several volumes at one position, a damaged file), each one error
//! naming the file and the fix. Series written from real volumes are compared with SimpleITK
//! and dcm2niix in `python/tests/test_dicom.py`.

use glam::DVec3;
use oracle::image::{LoadOptions, is_dicom_file, load_volume, read_dicom};
use std::path::{Path, PathBuf};

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/images/dicom")
        .join(name)
}

fn tmpdir(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("oracle-dicom-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn close(a: DVec3, b: DVec3, tol: f64) -> bool {
    (a - b).abs().max_element() <= tol
}

/// The error of reading `p`, which must fail.
fn refused(p: &Path) -> String {
    let e = read_dicom(p, None)
        .expect_err("must be refused")
        .to_string();
    assert!(!e.contains('\n'), "one line: {e}");
    e
}

#[test]
fn an_rt_dose_grid_reads_as_pydicom_reads_it() {
    let p = fixture("rtdose.dcm");
    assert!(is_dicom_file(&p));
    let v = load_volume(&p, &LoadOptions::default()).unwrap();
    assert_eq!(v.dims(), [10, 10, 15]);
    // pydicom: ImagePositionPatient (189.43125, 199.43125, -761.87) LPS, PixelSpacing 10 x 10,
    // an axial orientation, GridFrameOffsetVector 0, 5, ..., 70; RAS negates x and y.
    let a = v.affine();
    assert_eq!(a.translation, DVec3::new(-189.43125, -199.43125, -761.87));
    assert_eq!(a.matrix3.x_axis, DVec3::new(-10.0, 0.0, 0.0));
    assert_eq!(a.matrix3.y_axis, DVec3::new(0.0, -10.0, 0.0));
    assert!(close(a.matrix3.z_axis, DVec3::new(0.0, 0.0, 5.0), 1e-12));
    // pydicom's pixel_array[3, 2, 5] (frame, row, column) = 1131000, max 1254000; scaled by
    // DoseGridScaling 1e-6 (Gy).
    assert!((v.get(5, 2, 3) - 1.131).abs() < 1e-12, "{}", v.get(5, 2, 3));
    let max = (0..v.len())
        .map(|i| v.voxels().get_f64(i))
        .fold(0.0, f64::max);
    assert_eq!(max, 1_254_000.0);
    assert!(
        v.notes()[0].contains("15 slices of 10 x 10 pixels"),
        "{:?}",
        v.notes()
    );
}

#[test]
#[allow(clippy::excessive_precision)] // nibabel's reprs, as printed
fn an_enhanced_mr_is_placed_as_nibabel_places_it() {
    use std::io::Read;
    let d = tmpdir("philips");
    let mut bytes = Vec::new();
    flate2::read::GzDecoder::new(std::fs::File::open(fixture("philips_mprage.dcm.gz")).unwrap())
        .read_to_end(&mut bytes)
        .unwrap();
    let p = d.join("philips_mprage.dcm");
    std::fs::write(&p, bytes).unwrap();
    let v = read_dicom(&p, None).unwrap();
    assert_eq!(v.dims(), [256, 256, 176]);
    // nibabel.nicom.dicomwrappers.wrapper_from_file(...).affine (LPS; its voxel axes are
    // (row, column, slice), ours (column, row, slice)), x and y negated for RAS.
    let ras = |x: f64, y: f64, z: f64| DVec3::new(-x, -y, z);
    let row = ras(
        -3.3793509006500001e-02,
        -6.4996287226600002e-02,
        -9.9731314182279995e-01,
    );
    let col = ras(
        -2.2011068649000001e-03,
        9.9788552522659002e-01,
        -6.4959004521300004e-02,
    );
    let slice = ras(
        9.9943546970631159e-01,
        9.8578216815829951e-11,
        -3.3865423142437616e-02,
    );
    let origin = ras(
        -8.2190830214181005e+01,
        -1.2512766968458000e+02,
        1.4242164846509601e+02,
    );
    // nibabel runs the slices the other way (from frame 176; ours, as ITK's, go along the
    // normal row x column): our voxel (i, j, k) is nibabel's (j, i, 175 - k). nibabel steps
    // along the orientation's normal, we along the frames' positions (first to last over 175):
    // the file's two differ by 8e-6 rad, 1.3e-3 mm at the far end, so 2e-3 mm here.
    let nib = |i: f64, j: f64, k: f64| origin + row * i + col * j + slice * k;
    let a = v.affine();
    for (i, j, k) in [
        (0, 0, 0),
        (255, 0, 0),
        (0, 255, 0),
        (0, 0, 175),
        (17, 200, 99),
    ] {
        let ours = a.transform_point3(DVec3::new(i as f64, j as f64, k as f64));
        let theirs = nib(j as f64, i as f64, (175 - k) as f64);
        assert!(
            close(ours, theirs, 2e-3),
            "voxel {:?}: {ours:?} vs {theirs:?}",
            (i, j, k)
        );
    }
    assert!(
        close(a.matrix3.x_axis, col, 1e-12),
        "{:?}",
        a.matrix3.x_axis
    );
    assert!(
        close(a.matrix3.y_axis, row, 1e-12),
        "{:?}",
        a.matrix3.y_axis
    );
    // The per-frame PixelValueTransformation's slope (2.1079...) is kept as the scaling.
    assert!(
        (v.scaling().0 - 2.107_936_507_936_5).abs() < 1e-12,
        "{:?}",
        v.scaling()
    );
}

#[test]
fn what_is_not_a_volume_is_refused_with_the_fix() {
    let e = refused(&fixture("MR_small.dcm"));
    assert!(
        e.contains("one slice") && e.contains("pass the folder"),
        "{e}"
    );
    let e = refused(&fixture("MR_small_jpeg_ls_lossless.dcm"));
    assert!(
        e.contains("compressed (JPEG-LS") && e.contains("dcm2niix"),
        "{e}"
    );
    let e = refused(&fixture("emri_small.dcm"));
    assert!(
        e.contains("(0020,0037) is missing") && e.contains("not a volume"),
        "{e}"
    );

    let d = tmpdir("refusals");
    let not = d.join("notes.dcm");
    std::fs::write(&not, b"not a DICOM file").unwrap();
    assert!(refused(&not).contains("no 'DICM' preamble"));
    // A damaged copy: the file cut in the middle of its pixel data.
    let bytes = std::fs::read(fixture("MR_small.dcm")).unwrap();
    let cut = d.join("cut.dcm");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let e = refused(&cut);
    assert!(
        e.contains("cut.dcm") && (e.contains("truncated") || e.contains("damaged")),
        "{e}"
    );
}

/// Two slices of one series from one file: the file itself and a copy whose position is 1 mm
/// further along z (the decimal string `6.6406` of `ImagePositionPatient` made `7.6406`, the
/// same length, in the raw bytes: the compressed pixel data is untouched).
fn two_slices(name: &str) -> PathBuf {
    let d = tmpdir(&format!("two-{name}"));
    let bytes = std::fs::read(fixture(name)).unwrap();
    let at = bytes.windows(6).position(|w| w == b"6.6406").unwrap();
    let mut moved = bytes.clone();
    moved[at] = b'7';
    std::fs::write(d.join("a"), &bytes).unwrap();
    std::fs::write(d.join("b"), &moved).unwrap();
    d
}

#[test]
fn a_siemens_mosaic_is_refused_not_read_as_a_slice() {
    use std::io::Read;
    // nibabel's Siemens DWI mosaic (a volume tiled in one image): before, two such files of a
    // series made a 2-slice volume of tiles, meshed and verified; now each is refused.
    let d = tmpdir("mosaic");
    let mut bytes = Vec::new();
    flate2::read::GzDecoder::new(std::fs::File::open(fixture("siemens_dwi_0.dcm.gz")).unwrap())
        .read_to_end(&mut bytes)
        .unwrap();
    std::fs::write(d.join("b0.dcm"), &bytes).unwrap();
    // A second file of the series one slice step away, as the nibabel pair `0.dcm`, `1.dcm`.
    let at = bytes.windows(10).position(|w| w == b"-75.097641").unwrap();
    bytes[at + 1..at + 3].copy_from_slice(b"72");
    std::fs::write(d.join("b1.dcm"), &bytes).unwrap();
    for p in [d.join("b0.dcm"), d.clone()] {
        let e = refused(&p);
        assert!(
            e.contains("b0.dcm: a Siemens mosaic") && e.contains("dcm2niix"),
            "{e}"
        );
    }
}

#[test]
fn a_blown_up_length_is_refused_before_it_is_allocated() {
    // MR_small's PixelData (7FE0,0010) declaring 4 GB: dicom-object zero-fills a declared
    // length before reading it (4.2 GB of memory and 5.6 s for this 9 KB file); the lengths
    // are now checked against the file first.
    let mut bytes = std::fs::read(fixture("MR_small.dcm")).unwrap();
    let at = bytes
        .windows(6)
        .position(|w| w == [0xE0, 0x7F, 0x10, 0x00, b'O', b'W'])
        .unwrap();
    bytes[at + 8..at + 12].copy_from_slice(&0xFFFF_FFE0u32.to_le_bytes());
    let d = tmpdir("blown");
    std::fs::write(d.join("a.dcm"), &bytes).unwrap();
    let e = refused(&d.join("a.dcm"));
    assert!(
        e.contains("(7FE0,0010) declares 4294967264 bytes where 8330 remain"),
        "{e}"
    );
}

#[test]
fn compressed_slices_read_as_the_uncompressed_ones() {
    // pydicom's MR slice uncompressed, RLE Lossless and JPEG 2000 lossless (dicom-pixeldata's
    // decoders): the same voxels and affine.
    let plain = read_dicom(&two_slices("MR_small.dcm"), None).unwrap();
    assert_eq!(plain.dims(), [64, 64, 2]);
    assert!((plain.affine().matrix3.z_axis - DVec3::new(0.0, 0.0, 1.0)).length() < 1e-12);
    for name in ["MR_small_RLE.dcm", "MR_small_jp2klossless.dcm"] {
        let v = read_dicom(&two_slices(name), None).unwrap();
        assert_eq!(v.voxels(), plain.voxels(), "{name}");
        assert_eq!(v.affine(), plain.affine(), "{name}");
        assert!(
            !v.notes().iter().any(|n| n.contains("lossy")),
            "{:?}",
            v.notes()
        );
    }
}

#[test]
fn a_folder_is_one_volume_of_one_series() {
    // Two series: the MR slice and the dose grid.
    let d = tmpdir("two_series");
    std::fs::copy(fixture("MR_small.dcm"), d.join("a")).unwrap();
    std::fs::copy(fixture("rtdose.dcm"), d.join("b")).unwrap();
    let e = refused(&d);
    assert!(
        e.contains("2 series in one folder") && e.contains("(MR)") && e.contains("--series 1"),
        "{e}"
    );
    // --series picks one, by SeriesNumber (both are #1 here: ambiguous) or by UID.
    let e = read_dicom(&d, Some("1")).unwrap_err().to_string();
    assert!(e.contains("2 series have that number"), "{e}");
    let e = read_dicom(&d, Some("7")).unwrap_err().to_string();
    assert!(e.contains("--series 7: no series"), "{e}");
    let v = read_dicom(&d, Some("1.2.777.777.77.7.7777.7777")).unwrap();
    assert_eq!(v.dims(), [10, 10, 15]);
    let opts = LoadOptions {
        series: Some("1.3.6.1.4.1.5962.1.3.4.1.20040826185059.5457".into()),
        ..LoadOptions::default()
    };
    assert!(
        load_volume(&d, &opts)
            .unwrap_err()
            .to_string()
            .contains("one slice")
    );
    // --series on a file that is not DICOM: refused, not ignored.
    let nifti = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/images/phantom_i16_32.nii.gz");
    let e = load_volume(&nifti, &opts).unwrap_err().to_string();
    assert!(e.contains("series are picked from DICOM folders"), "{e}");
    // The same slice twice (one SOPInstanceUID): a copied file, not a second volume.
    let d = tmpdir("repeated");
    std::fs::copy(fixture("MR_small.dcm"), d.join("1.dcm")).unwrap();
    std::fs::copy(fixture("MR_small.dcm"), d.join("2.dcm")).unwrap();
    let e = refused(&d);
    assert!(
        e.contains("1.dcm and ") && e.contains("2.dcm are the same image"),
        "{e}"
    );
    // Two images at one position (another SOPInstanceUID, its last digit changed everywhere)
    // and nothing else to tell them apart: refused, with or without --frame (only the file
    // names would order them).
    let uid = b"1.3.6.1.4.1.5962.1.1.4.1.1.20040826185059.5457";
    let mut bytes = std::fs::read(fixture("MR_small.dcm")).unwrap();
    let mut changed = 0;
    while let Some(at) = bytes.windows(uid.len()).position(|w| w == uid) {
        bytes[at + uid.len() - 1] = b'8';
        changed += 1;
    }
    assert!(changed >= 1);
    std::fs::write(d.join("2.dcm"), &bytes).unwrap();
    for frame in [None, Some(0), Some(1)] {
        let opts = LoadOptions {
            frame,
            ..LoadOptions::default()
        };
        let e = load_volume(&d, &opts).unwrap_err().to_string();
        assert!(e.contains("nothing tells their volumes apart"), "{e}");
    }
    // A multi-frame file in a folder, beside a text file: read, the other file noted.
    let d = tmpdir("with_readme");
    std::fs::copy(fixture("rtdose.dcm"), d.join("dose")).unwrap();
    std::fs::write(d.join("README.txt"), "exported").unwrap();
    let v = load_volume(&d, &LoadOptions::default()).unwrap();
    assert_eq!(v.dims(), [10, 10, 15]);
    assert!(v.notes()[0].contains("1 other file(s)"), "{:?}", v.notes());
    // An export keeps its series in subfolders: the error names them.
    let d = tmpdir("export");
    for (sub, f) in [
        ("DICOM/ST0/SE0", "MR_small.dcm"),
        ("DICOM/ST0/SE1", "rtdose.dcm"),
    ] {
        std::fs::create_dir_all(d.join(sub)).unwrap();
        std::fs::copy(fixture(f), d.join(sub).join("IM0")).unwrap();
    }
    let e = load_volume(&d, &LoadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("in 2 subfolder(s)") && e.contains("SE0 (1 files)") && e.contains("SE1"),
        "{e}"
    );
    // No DICOM image at all: the slice-folder reader's error, not a DICOM one.
    let d = tmpdir("empty");
    std::fs::write(d.join("README.txt"), "nothing").unwrap();
    let e = load_volume(&d, &LoadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("no PNG or TIFF slices"), "{e}");
}

mod damaged {
    //! Damaged files (bytes changed, cut, length fields blown up, chunks repeated) are read or
    //! refused, never a panic or an abort: the parser is `dicom-object`'s, the pixel decoding
    //! and the geometry are ours. A length field blown up to 2-4 GiB costs about 0.5 s (the
    //! parser allocates before it finds the file short), hence 80 cases.
    use super::*;
    use proptest::prelude::*;

    fn mutate(src: &[u8], kind: u8, at: usize, byte: u8, len: usize) -> Vec<u8> {
        let mut b = src.to_vec();
        let at = 132 + at % (b.len() - 136);
        match kind % 4 {
            0 => b[at] = byte,
            1 => b.truncate(at),
            2 => {
                let at = at & !1;
                let big =
                    [0xFFFF_FFF0u32, 0x7FFF_FFFF, 0x1000_0000, 0xFFFF_FFFF][byte as usize % 4];
                b[at..at + 4].copy_from_slice(&big.to_le_bytes());
            }
            _ => {
                let end = (at + len % 200).min(b.len());
                let chunk = b[at..end].to_vec();
                b.splice(at..at, chunk);
            }
        }
        b
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 80, .. ProptestConfig::default() })]
        #[test]
        fn a_damaged_file_is_read_or_refused(
            which in 0usize..4, kind in 0u8..4, at in 0usize..1 << 20, byte in 0u8..=255,
            len in 0usize..1000,
        ) {
            let src = std::fs::read(fixture(
                ["rtdose.dcm", "MR_small.dcm", "MR_small_RLE.dcm", "MR_small_jp2klossless.dcm"][which],
            ))
            .unwrap();
            let d = tmpdir(&format!("damaged-{which}-{kind}-{at}-{byte}-{len}"));
            let p = d.join("m.dcm");
            std::fs::write(&p, mutate(&src, kind, at, byte, len)).unwrap();
            if let Err(e) = read_dicom(&p, None) {
                let e = e.to_string();
                prop_assert!(e.contains("m.dcm") && !e.contains('\n'), "{}", e);
            }
            let _ = std::fs::remove_dir_all(&d);
        }
    }
}
