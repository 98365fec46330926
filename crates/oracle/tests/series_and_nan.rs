//! One 3D volume out of a NIfTI series (`--frame`) and NaN voxels given a value (`--nan-as`):
//! the frames against the bytes they were written from, the errors of a series read without a
//! frame or with one out of range, and nibabel's real files (`functional.nii`, an fMRI series of
//! 20 volumes; `resampled_anat_moved.nii`, a resampled anatomy whose voxels outside the
//! original field of view are NaN).

use glam::DAffine3;
use oracle::image::{
    Dtype, ImageError, ImageOptions, ImageSurface, LoadOptions, NiftiWriteOptions, RawOptions,
    Volume, Voxels, load_volume, read_nifti, read_nifti_frame, write_nifti,
};
use std::path::{Path, PathBuf};

fn tmpdir(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("oracle-series-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/images")
        .join(name)
}

fn values(v: &Volume) -> Vec<f64> {
    (0..v.len()).map(|i| v.voxels().get_f64(i)).collect()
}

/// A 3 x 2 x 8 volume written with the header of a series of four 3 x 2 x 2 volumes: the
/// bytes of frame `k` are the original's slices `2k` and `2k + 1`.
fn series(dir: &Path, name: &str, dim: [u16; 8]) -> (PathBuf, Vec<f64>) {
    let data: Vec<i16> = (0..48).map(|i| (i * 7 % 31) as i16 - 9).collect();
    let vol = Volume::new([3, 2, 8], Voxels::I16(data), DAffine3::IDENTITY).unwrap();
    let p = dir.join(name);
    let o = NiftiWriteOptions {
        dim_override: Some(dim),
        ..NiftiWriteOptions::new()
    };
    write_nifti(&p, &vol, &o).unwrap();
    (p, values(&vol))
}

#[test]
fn each_frame_of_a_series_is_the_volume_stored_at_its_place() {
    let dir = tmpdir("frames");
    for name in ["s.nii", "s.nii.gz"] {
        let (p, all) = series(&dir, name, [4, 3, 2, 2, 4, 1, 1, 1]);
        for k in 0..4 {
            let v = read_nifti_frame(&p, Some(k)).unwrap();
            assert_eq!(v.dims(), [3, 2, 2]);
            assert_eq!(values(&v), all[12 * k..12 * (k + 1)], "{name} frame {k}");
            assert!(
                v.notes()
                    .iter()
                    .any(|n| n.contains(&format!("frame {k} of 4"))),
                "{:?}",
                v.notes()
            );
            // load_volume gives the same volume.
            let opts = LoadOptions {
                frame: Some(k),
                ..Default::default()
            };
            assert_eq!(values(&load_volume(&p, &opts).unwrap()), values(&v));
        }
        // Without a frame: the error names the flag and the range.
        let e = read_nifti(&p).unwrap_err();
        assert!(matches!(e, ImageError::FourD { frames: 4, .. }), "{e}");
        let msg = e.to_string();
        assert!(msg.contains("--frame K (0 to 3)"), "{msg}");
        // Out of range.
        let msg = read_nifti_frame(&p, Some(4)).unwrap_err().to_string();
        assert!(
            msg.contains("--frame 4") && msg.contains("numbered 0 to 3"),
            "{msg}"
        );
    }
}

#[test]
fn frames_are_refused_where_there_is_no_series() {
    let dir = tmpdir("no_series");
    // Five dimensions with two values a voxel: not frames.
    let (p, _) = series(&dir, "vec.nii", [5, 3, 2, 2, 2, 2, 1, 1]);
    for frame in [None, Some(0), Some(1)] {
        let msg = read_nifti_frame(&p, frame).unwrap_err().to_string();
        assert!(msg.contains("vector or tensor"), "{frame:?}: {msg}");
    }
    // A 3D file is frame 0 and only that.
    let (p, all) = series(&dir, "three.nii", [3, 3, 2, 8, 1, 1, 1, 1]);
    assert_eq!(values(&read_nifti_frame(&p, Some(0)).unwrap()), all);
    let msg = read_nifti_frame(&p, Some(1)).unwrap_err().to_string();
    assert!(msg.contains("--frame 1") && msg.contains("0 to 0"), "{msg}");
    // Other formats hold one volume.
    let raw = dir.join("v.raw");
    std::fs::write(&raw, [0u8; 8]).unwrap();
    let opts = LoadOptions {
        raw: Some(RawOptions {
            dims: [2, 2, 2],
            dtype: Dtype::U8,
            big_endian: false,
            offset: 0,
        }),
        frame: Some(1),
        ..Default::default()
    };
    let msg = load_volume(&raw, &opts).unwrap_err().to_string();
    assert!(
        msg.contains("series are read from NIfTI, MGH, NRRD, MetaImage and DICOM"),
        "{msg}"
    );
    // A raw layout given for a file named like a NIfTI one: raw, one volume.
    let named = dir.join("v.nii");
    std::fs::write(&named, [0u8; 8]).unwrap();
    let msg = load_volume(&named, &opts).unwrap_err().to_string();
    assert!(msg.contains("holds one 3D volume"), "{msg}");
}

#[test]
fn a_series_short_of_its_last_frame_is_truncated() {
    let dir = tmpdir("short");
    // Four frames in the header, three in the data: no frame is read, not even the first.
    let (p, _) = series(&dir, "short.nii", [4, 3, 2, 2, 5, 1, 1, 1]);
    let e = read_nifti_frame(&p, Some(0)).unwrap_err();
    assert!(matches!(e, ImageError::Truncated { .. }), "{e}");
    assert!(e.to_string().contains("in each of 5 frames"), "{e}");
}

#[test]
fn a_real_fmri_series_reads_frame_by_frame() {
    // nibabel's functional.nii: 17 x 21 x 3 x 20, int16 with scl_slope.
    let p = fixture("nibabel_functional.nii.gz");
    assert!(matches!(
        read_nifti(&p),
        Err(ImageError::FourD { frames: 20, .. })
    ));
    let first = read_nifti_frame(&p, Some(0)).unwrap();
    let last = read_nifti_frame(&p, Some(19)).unwrap();
    assert_eq!(first.dims(), [17, 21, 3]);
    assert_eq!(first.affine(), last.affine());
    assert_ne!(values(&first), values(&last), "the frames differ");
    assert!(read_nifti_frame(&p, Some(20)).is_err());
}

#[test]
fn nan_voxels_take_the_value_asked_for() {
    let aff = DAffine3::IDENTITY;
    let mut d: Vec<f32> = (0..27).map(|i| i as f32).collect();
    d[4] = f32::NAN;
    d[20] = f32::NAN;
    // Scaled: value = 2 raw + 10, so the value 0 is the raw -5.
    let v = Volume::new([3, 3, 3], Voxels::F32(d.clone()), aff)
        .unwrap()
        .with_scaling(2.0, 10.0);
    let e = v.stats().unwrap_err();
    assert!(
        matches!(
            e,
            ImageError::NaN {
                index: [1, 1, 0],
                nan: true,
                ..
            }
        ),
        "{e}"
    );
    assert!(e.to_string().contains("--nan-as VALUE"), "{e}");
    let r = v.clone().replace_nan(0.0).unwrap();
    assert_eq!((r.get(1, 1, 0), r.get(2, 0, 2)), (0.0, 0.0));
    assert_eq!(r.get(0, 0, 0), 10.0, "other voxels unchanged");
    assert_eq!(r.notes(), ["2 NaN voxel(s) set to 0 (--nan-as 0)"]);
    assert!(r.stats().is_ok());
    // A value the voxel type rounds is said so.
    let r = v.replace_nan(0.1).unwrap();
    assert!(
        r.notes()[0].contains("rounded to the voxel type"),
        "{:?}",
        r.notes()
    );
    // f64 voxels; integer voxels are never NaN.
    let f: Vec<f64> = d.iter().map(|&x| x as f64).collect();
    let r = Volume::new([3, 3, 3], Voxels::F64(f), aff)
        .unwrap()
        .replace_nan(-1.5)
        .unwrap();
    assert_eq!(r.get(1, 1, 0), -1.5);
    let i = Volume::new([3, 3, 3], Voxels::U8(vec![1; 27]), aff).unwrap();
    assert_eq!(i.clone().replace_nan(0.0).unwrap(), i);
    assert!(matches!(
        i.replace_nan(f64::NAN),
        Err(ImageError::NanValue { .. })
    ));
    // An infinite voxel is not NaN: --nan-as does not cover it, and the error says so.
    let mut d = vec![0.0f32; 27];
    d[3] = f32::INFINITY;
    let v = Volume::new([3, 3, 3], Voxels::F32(d), aff).unwrap();
    let v = v.replace_nan(0.0).unwrap();
    let msg = v.stats().unwrap_err().to_string();
    assert!(
        msg.contains("infinite") && msg.contains("replaces NaN only"),
        "{msg}"
    );
}

#[test]
fn a_real_resampled_volume_with_nan_meshes_with_nan_as() {
    // nibabel's resampled_anat_moved.nii: 17 x 21 x 3 big-endian float32 from byte 352; the
    // NaN voxels counted from the bytes themselves.
    let p = fixture("nibabel_resampled_anat_moved.nii");
    let bytes = std::fs::read(&p).unwrap();
    let nan = bytes[352..352 + 4 * 17 * 21 * 3]
        .chunks_exact(4)
        .filter(|c| f32::from_be_bytes([c[0], c[1], c[2], c[3]]).is_nan())
        .count();
    assert_eq!(nan, 153);
    let iso = ImageOptions {
        iso: Some(5000.0),
        ..Default::default()
    };
    let e = ImageSurface::open(&p, &LoadOptions::default(), &iso).unwrap_err();
    assert!(
        e.to_string().contains("is NaN (no value): pass --nan-as"),
        "{e}"
    );
    let opts = LoadOptions {
        nan_as: Some(0.0),
        ..Default::default()
    };
    let vol = load_volume(&p, &opts).unwrap();
    assert_eq!(
        vol.notes(),
        [format!("{nan} NaN voxel(s) set to 0 (--nan-as 0)")]
    );
    let s = ImageSurface::open(&p, &opts, &iso).unwrap();
    assert_eq!(s.topology().surface_components, 3);
}

#[test]
fn otsu_threshold_splits_two_populations_and_is_suggested_when_iso_is_missing() {
    use oracle::image::otsu_threshold;
    // 3/4 of the voxels at 0..3, 1/4 at 100..103: the threshold lies between the two, at a
    // bin centre (256 bins over [0, 103]).
    let v: Vec<f32> = (0..512)
        .map(|i| {
            if i % 4 == 0 {
                100.0 + (i % 3) as f32
            } else {
                (i % 3) as f32
            }
        })
        .collect();
    let vol = Volume::new([8, 8, 8], Voxels::F32(v), DAffine3::IDENTITY).unwrap();
    let t = otsu_threshold(&vol).unwrap();
    let w = 102.0 / 256.0;
    assert!(t > 2.0 && t < 100.0, "{t}");
    assert!(
        (((t / w) - 0.5).round() - ((t / w) - 0.5)).abs() < 1e-9,
        "a bin centre: {t}"
    );
    // Scaled values: the threshold is in scaled units.
    let s = vol.clone().with_scaling(2.0, -50.0);
    assert!((otsu_threshold(&s).unwrap() - (2.0 * t - 50.0)).abs() < 1e-9);
    // Constant: none.
    let c = Volume::new([2, 2, 2], Voxels::U8(vec![3; 8]), DAffine3::IDENTITY).unwrap();
    assert_eq!(otsu_threshold(&c), None);
    // The error that asks for an iso value suggests it.
    let e = ImageSurface::new(vol, &ImageOptions::default()).unwrap_err();
    let shown = e.to_string();
    assert!(
        shown.contains("e.g. --iso ") && shown.contains("Otsu's threshold"),
        "{shown}"
    );
}
