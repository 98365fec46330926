//! 64-bit integer volumes (connectomics segmentations are uint64): raw, NRRD and MetaImage
//! files hold them in the narrowest exact storage (u32, i32, f64 up to 9e15) with a note; a
//! value beyond 9e15 (the limit of labels) is refused naming the voxel. NIfTI and OME-Zarr are checked against
//! nibabel and zarr in `python/tests/test_formats.py`.

use oracle::image::{Dtype, ImageError, LoadOptions, RawOptions, Voxels, load_volume};
use std::path::PathBuf;

fn dir() -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("wide-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A 6 x 5 x 4 volume of label 0 with a block of `a` and a block of `b` (x fastest).
fn grid(a: u64, b: u64) -> Vec<u64> {
    let mut v = vec![0u64; 6 * 5 * 4];
    for k in 1..3 {
        for j in 1..3 {
            v[1 + 6 * (j + 5 * k)] = a;
            v[4 + 6 * (j + 5 * k)] = b;
        }
    }
    v
}

fn bytes(v: &[u64], big: bool) -> Vec<u8> {
    v.iter()
        .flat_map(|x| {
            if big {
                x.to_be_bytes()
            } else {
                x.to_le_bytes()
            }
        })
        .collect()
}

fn raw(
    v: &[u64],
    dtype: Dtype,
    big: bool,
    name: &str,
) -> Result<oracle::image::Volume, ImageError> {
    let p = dir().join(name);
    std::fs::write(&p, bytes(v, big)).unwrap();
    let opts = LoadOptions {
        raw: Some(RawOptions {
            dims: [6, 5, 4],
            dtype,
            big_endian: big,
            offset: 0,
        }),
        ..Default::default()
    };
    load_volume(&p, &opts)
}

/// Ids that fit 32 bits are u32; larger ids up to 9e15 are f64, exactly; each says so.
#[test]
fn wide_ids_are_held_exactly() {
    let small = raw(&grid(7, u32::MAX as u64), Dtype::U64, false, "small.raw").unwrap();
    assert!(matches!(small.voxels(), Voxels::U32(_)));
    let labels: Vec<i64> = small.labels().unwrap().iter().map(|l| l.0).collect();
    assert_eq!(labels, vec![0, 7, u32::MAX as i64]);
    assert!(
        small
            .notes()
            .iter()
            .any(|n| n.contains("u64 voxels held as u32"))
    );
    let (a, b) = ((1u64 << 40) + 7, 9_000_000_000_000_000);
    for big in [false, true] {
        let wide = raw(&grid(a, b), Dtype::U64, big, "wide.raw").unwrap();
        assert!(matches!(wide.voxels(), Voxels::F64(_)));
        let labels: Vec<i64> = wide.labels().unwrap().iter().map(|l| l.0).collect();
        assert_eq!(labels, vec![0, a as i64, b as i64]);
        assert_eq!(wide.get(1, 1, 1), a as f64);
    }
    // Signed: negative ids fit i32.
    let neg: Vec<u64> = grid(5, 9).iter().map(|&x| (-(x as i64)) as u64).collect();
    let v = raw(&neg, Dtype::I64, false, "neg.raw").unwrap();
    assert!(matches!(v.voxels(), Voxels::I32(_)));
    assert_eq!(v.get(4, 1, 1), -9.0);
}

/// 9e15 + 1 is beyond the labels' limit: refused, naming the voxel and the fix.
#[test]
fn ids_beyond_9e15_are_refused_at_their_voxel() {
    let e = raw(
        &grid(3, 9_000_000_000_000_001),
        Dtype::U64,
        false,
        "huge.raw",
    )
    .unwrap_err();
    let m = e.to_string();
    assert!(
        matches!(
            e,
            ImageError::WideValue {
                voxel: [4, 1, 1],
                ..
            }
        ),
        "{m}"
    );
    assert!(
        m.contains("9000000000000001") && m.contains("renumber"),
        "{m}"
    );
}

/// NRRD `uint64` / `int64` and MetaImage `MET_ULONG_LONG` / `MET_LONG_LONG` read the same
/// voxels as the raw file.
#[test]
fn nrrd_and_metaimage_read_64_bit_ids() {
    let (a, b) = ((1u64 << 40) + 7, 12);
    let data = bytes(&grid(a, b), false);
    let d = dir();
    for (name, header) in [
        (
            "w.nrrd",
            "NRRD0004\ntype: uint64\ndimension: 3\nsizes: 6 5 4\nencoding: raw\nendian: little\n\n",
        ),
        (
            "s.nrrd",
            "NRRD0004\ntype: long long\ndimension: 3\nsizes: 6 5 4\nencoding: raw\nendian: little\n\n",
        ),
        (
            "w.mha",
            "ObjectType = Image\nNDims = 3\nDimSize = 6 5 4\nElementType = MET_ULONG_LONG\nElementDataFile = LOCAL\n",
        ),
        (
            "s.mha",
            "ObjectType = Image\nNDims = 3\nDimSize = 6 5 4\nElementType = MET_LONG_LONG\nElementDataFile = LOCAL\n",
        ),
    ] {
        let p = d.join(name);
        let mut f = header.as_bytes().to_vec();
        f.extend_from_slice(&data);
        std::fs::write(&p, f).unwrap();
        let v = load_volume(&p, &LoadOptions::default()).unwrap_or_else(|e| panic!("{name}: {e}"));
        let labels: Vec<i64> = v.labels().unwrap().iter().map(|l| l.0).collect();
        assert_eq!(labels, vec![0, b as i64, a as i64], "{name}");
        assert_eq!(
            (v.get(1, 1, 1), v.get(4, 2, 2)),
            (a as f64, b as f64),
            "{name}"
        );
    }
}
