//! FreeSurfer MGH/MGZ volumes: nibabel's `test.mgz` (3 x 4 x 5 x 2 float32) against the values
//! and the affine nibabel gives, and files built byte by byte (the 284-byte big-endian header
//! of `mghformat.py`): every voxel type, the default affine without `goodRASFlag`, gzip or not,
//! and the errors (version, type, dimensions, voxel sizes, truncation, frames).

use glam::{DAffine3, DMat3, DVec3};
use oracle::image::{LoadOptions, load_volume, read_mgh};
use std::path::{Path, PathBuf};

fn tmpdir(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("oracle-mgh-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn values(v: &oracle::image::Volume) -> Vec<f64> {
    (0..v.len()).map(|i| v.voxels().get_f64(i)).collect()
}

#[test]
fn nibabel_test_mgz_reads_as_nibabel_reads_it() {
    let p =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/images/nibabel_test.mgz");
    let msg = load_volume(&p, &LoadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains("nframes = 2") && msg.contains("--frame K (0 to 1)"),
        "{msg}"
    );
    // nibabel: img.affine and, per frame, min, max and the voxel [1, 2, 3].
    let affine = DAffine3::from_mat3_translation(
        DMat3::from_cols(
            DVec3::new(1.0, 2.0, 3.0),
            DVec3::new(2.0, 3.0, 1.0),
            DVec3::new(3.0, 1.0, 2.0),
        ),
        DVec3::new(-13.0, -11.5, -11.5),
    );
    let expect = [
        (-1.7049814462661743, 2.472317695617676, -0.30470070242881775),
        (
            -2.4256153106689453,
            1.8168381452560425,
            0.0017987990286201239,
        ),
    ];
    for (k, (lo, hi, at)) in expect.into_iter().enumerate() {
        let opts = LoadOptions {
            frame: Some(k),
            ..Default::default()
        };
        let v = load_volume(&p, &opts).unwrap();
        assert_eq!(v.dims(), [3, 4, 5]);
        assert_eq!(v.affine(), affine);
        let s = v.stats().unwrap();
        assert_eq!((s.min, s.max, v.get(1, 2, 3)), (lo, hi, at), "frame {k}");
    }
}

/// An MGH file: `dims` of type `ty` (0 u8, 1 i32, 3 f32, 4 i16), `frames` frames of the voxel
/// values 0, 1, 2, ..., and the geometry (`None`: goodRASFlag 0).
fn mgh(
    dims: [i32; 3],
    frames: i32,
    ty: i32,
    geometry: Option<([f32; 3], [f32; 9], [f32; 3])>,
) -> Vec<u8> {
    let mut b = Vec::new();
    for v in [1, dims[0], dims[1], dims[2], frames, ty, 0] {
        b.extend_from_slice(&v.to_be_bytes());
    }
    b.extend_from_slice(&(geometry.is_some() as i16).to_be_bytes());
    let (delta, mdc, c) = geometry.unwrap_or(([0.0; 3], [0.0; 9], [0.0; 3]));
    for v in delta.iter().chain(&mdc).chain(&c) {
        b.extend_from_slice(&v.to_be_bytes());
    }
    b.resize(284, 0);
    let n = dims.iter().product::<i32>() * frames;
    for i in 0..n {
        match ty {
            0 => b.push(i as u8),
            1 => b.extend_from_slice(&i.to_be_bytes()),
            3 => b.extend_from_slice(&(i as f32).to_be_bytes()),
            _ => b.extend_from_slice(&(i as i16).to_be_bytes()),
        }
    }
    b.extend_from_slice(b"tags after the voxels are ignored");
    b
}

#[test]
fn every_voxel_type_and_both_geometries_read() {
    let dir = tmpdir("types");
    // An oblique geometry with voxel sizes that are not powers of two.
    let (s, c) = (0.6f32, 0.8f32);
    let geo = (
        [0.7, 1.3, 2.1],
        [c, s, 0.0, -s, c, 0.0, 0.0, 0.0, 1.0],
        [10.0, -20.0, 5.5],
    );
    for ty in [0, 1, 3, 4] {
        let bytes = mgh([2, 3, 4], 2, ty, Some(geo));
        let plain = dir.join(format!("v{ty}.mgh"));
        std::fs::write(&plain, &bytes).unwrap();
        let gz = dir.join(format!("v{ty}.mgz"));
        let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
        std::io::Write::write_all(&mut e, &bytes).unwrap();
        std::fs::write(&gz, e.finish().unwrap()).unwrap();
        for p in [&plain, &gz] {
            let v = read_mgh(p, Some(1)).unwrap();
            let want: Vec<f64> = (24..48).map(|i| i as f64).collect();
            assert_eq!(values(&v), want, "{p:?}");
            // nibabel's affine: columns Mdc_i * delta_i (a float32 product), and the centre
            // at (2, 3, 4) / 2 in voxels.
            let col = |i: usize| {
                let d = geo.0[i];
                DVec3::new(
                    (geo.1[3 * i] * d) as f64,
                    (geo.1[3 * i + 1] * d) as f64,
                    (geo.1[3 * i + 2] * d) as f64,
                )
            };
            let m = DMat3::from_cols(col(0), col(1), col(2));
            let t = (DVec3::new(10.0, -20.0, 5.5) - m * DVec3::new(1.0, 1.5, 2.0))
                .as_vec3()
                .as_dvec3();
            assert_eq!(v.affine(), DAffine3::from_mat3_translation(m, t), "{p:?}");
        }
    }
    // The same bytes read by nibabel 5.4.2 (`nib.load(f).affine`, its reprs): bit for bit.
    let a = read_mgh(dir.join("v3.mgh"), Some(0)).unwrap().affine();
    let nibabel = [
        [
            0.5600000023841858,
            -0.7800000309944153,
            0.0,
            10.609999656677246,
        ],
        [
            0.42000001668930054,
            1.0399999618530273,
            0.0,
            -21.979999542236328,
        ],
        [0.0, 0.0, 2.0999999046325684, 1.3000001907348633],
    ];
    let cols = [
        a.matrix3.x_axis,
        a.matrix3.y_axis,
        a.matrix3.z_axis,
        a.translation,
    ];
    for (r, row) in nibabel.iter().enumerate() {
        for (c, &v) in row.iter().enumerate() {
            assert_eq!(cols[c][r], v, "affine[{r}][{c}]");
        }
    }
    // goodRASFlag 0: nibabel's default (coronal, unit voxels, centred at 0).
    let p = dir.join("default.mgh");
    std::fs::write(&p, mgh([2, 2, 2], 1, 0, None)).unwrap();
    let v = read_mgh(&p, None).unwrap();
    let a = v.affine();
    assert_eq!(a.matrix3.x_axis, DVec3::new(-1.0, 0.0, 0.0));
    assert_eq!(a.matrix3.y_axis, DVec3::new(0.0, 0.0, 1.0));
    assert_eq!(a.matrix3.z_axis, DVec3::new(0.0, -1.0, 0.0));
    assert_eq!(
        a.translation,
        DVec3::new(1.0, 1.0, -1.0),
        "nibabel's affine of this file"
    );
}

#[test]
fn bad_mgh_files_are_errors_naming_the_field() {
    let dir = tmpdir("bad");
    let geo = Some((
        [1.0; 3],
        [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
        [0.0; 3],
    ));
    let good = mgh([3, 3, 3], 2, 3, geo);
    let read = |name: &str, b: &[u8], frame: Option<usize>| {
        let p = dir.join(name);
        std::fs::write(&p, b).unwrap();
        read_mgh(&p, frame).unwrap_err().to_string()
    };
    let mut b = good.clone();
    b[3] = 2;
    assert!(read("version.mgh", &b, Some(0)).contains("version"));
    let mut b = good.clone();
    b[23] = 2;
    let msg = read("type.mgh", &b, Some(0));
    assert!(msg.contains("type") && msg.contains("= 2"), "{msg}");
    let mut b = good.clone();
    b[8..12].copy_from_slice(&0i32.to_be_bytes());
    assert!(read("height.mgh", &b, Some(0)).contains("height"));
    let mut b = good.clone();
    b[34..38].copy_from_slice(&0f32.to_be_bytes());
    assert!(read("delta.mgh", &b, Some(0)).contains("delta"));
    // Short of the second frame: truncated, whichever frame is asked.
    let msg = read("short.mgh", &good[..284 + 4 * 27 + 8], Some(0));
    assert!(
        msg.contains("truncated") && msg.contains("2 frame(s)"),
        "{msg}"
    );
    assert!(read("head.mgh", &good[..100], None).contains("truncated"));
    let msg = read("frame.mgh", &good, Some(2));
    assert!(msg.contains("--frame 2") && msg.contains("0 to 1"), "{msg}");
    assert!(read("gz.mgz", &good, Some(0)).contains("gzip"));
}
