//! 4D NRRD and MetaImage series read one 3D volume at a time (`--frame`): every layout of the
//! frames' axis (first, as Slicer's older DWI files; last; in the middle) gives the volume a
//! 3D file of that frame holds, with the same world geometry; the headers that do not say which
//! axis is not spatial, or say it twice differently, are refused, and so is a 2D colour image
//! posing as a volume.

use oracle::image::{
    LoadOptions, Volume, load_volume, read_metaimage, read_metaimage_frame, read_nrrd,
    read_nrrd_frame,
};
use std::path::{Path, PathBuf};

fn tmpdir(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("oracle-4d-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn values(v: &Volume) -> Vec<f64> {
    (0..v.len()).map(|i| v.voxels().get_f64(i)).collect()
}

/// Frames of a 3 x 4 x 2 volume of i16: voxel (i, j, k) of frame t.
const DIMS: [usize; 3] = [3, 4, 2];
const FRAMES: usize = 3;
fn voxel(i: usize, j: usize, k: usize, t: usize) -> i16 {
    (i + 10 * j + 100 * k) as i16 - 1000 * t as i16
}

/// The little-endian bytes of the 4D array with the frames' axis at `axis` (axis 0 fastest).
fn bytes_4d(axis: usize) -> Vec<u8> {
    let mut sizes = vec![DIMS[0], DIMS[1], DIMS[2]];
    sizes.insert(axis, FRAMES);
    let mut out = Vec::new();
    for d in 0..sizes[3] {
        for c in 0..sizes[2] {
            for b in 0..sizes[1] {
                for a in 0..sizes[0] {
                    let mut idx = vec![a, b, c, d];
                    let t = idx.remove(axis);
                    out.extend_from_slice(&voxel(idx[0], idx[1], idx[2], t).to_le_bytes());
                }
            }
        }
    }
    out
}

fn frame_values(t: usize) -> Vec<f64> {
    let mut v = Vec::new();
    for k in 0..DIMS[2] {
        for j in 0..DIMS[1] {
            for i in 0..DIMS[0] {
                v.push(f64::from(voxel(i, j, k, t)));
            }
        }
    }
    v
}

const DIRS: [&str; 3] = ["(0,-2,0)", "(1.5,0,0)", "(0,0,3)"];

/// A 4D NRRD with the frames' axis at `axis`, optional `kinds` and `space directions`.
fn nrrd_4d(dir: &Path, name: &str, axis: usize, kinds: bool, directions: bool) -> PathBuf {
    let mut sizes: Vec<String> = DIMS.iter().map(|d| d.to_string()).collect();
    sizes.insert(axis, FRAMES.to_string());
    let mut k = vec!["domain"; 3];
    k.insert(axis, "list");
    let mut d = DIRS.to_vec();
    d.insert(axis, "none");
    let mut h = format!(
        "NRRD0004\ntype: short\ndimension: 4\nsizes: {}\nendian: little\nencoding: raw\n",
        sizes.join(" ")
    );
    if kinds {
        h += &format!("kinds: {}\n", k.join(" "));
    }
    if directions {
        h += &format!(
            "space: left-posterior-superior\nspace directions: {}\nspace origin: (5,6,7)\n",
            d.join(" ")
        );
    }
    write(dir, name, h, &bytes_4d(axis))
}

fn write(dir: &Path, name: &str, header: String, data: &[u8]) -> PathBuf {
    let p = dir.join(name);
    let mut b = header.into_bytes();
    b.push(b'\n');
    b.extend_from_slice(data);
    std::fs::write(&p, b).unwrap();
    p
}

/// The 3D NRRD of frame `t`, with the same geometry.
fn nrrd_3d(dir: &Path, t: usize) -> PathBuf {
    let h = format!(
        "NRRD0004\ntype: short\ndimension: 3\nsizes: 3 4 2\nendian: little\nencoding: raw\n\
         space: left-posterior-superior\nspace directions: {}\nspace origin: (5,6,7)\n",
        DIRS.join(" ")
    );
    let data: Vec<u8> = frame_values(t)
        .iter()
        .flat_map(|&v| (v as i16).to_le_bytes())
        .collect();
    write(dir, &format!("f{t}.nrrd"), h, &data)
}

#[test]
fn every_layout_of_an_nrrd_series_gives_the_frames_of_a_3d_file() {
    let dir = tmpdir("nrrd");
    for axis in 0..4 {
        for (kinds, directions) in [(true, true), (false, true), (true, false)] {
            let p = nrrd_4d(
                &dir,
                &format!("s{axis}{kinds}{directions}.nrrd"),
                axis,
                kinds,
                directions,
            );
            for t in 0..FRAMES {
                let v = read_nrrd_frame(&p, Some(t)).unwrap();
                assert_eq!(v.dims(), DIMS, "axis {axis}");
                assert_eq!(values(&v), frame_values(t), "axis {axis} frame {t}");
                assert!(
                    v.notes()
                        .iter()
                        .any(|n| n.contains(&format!("frame {t} of 3 along axis {axis}"))),
                    "{:?}",
                    v.notes()
                );
                if directions {
                    let three = read_nrrd(nrrd_3d(&dir, t)).unwrap();
                    assert_eq!(v.affine(), three.affine(), "axis {axis}");
                }
                let opts = LoadOptions {
                    frame: Some(t),
                    ..Default::default()
                };
                assert_eq!(values(&load_volume(&p, &opts).unwrap()), frame_values(t));
            }
            let msg = read_nrrd(&p).unwrap_err().to_string();
            assert!(msg.contains("pass --frame K (0 to 2)"), "{msg}");
            let msg = read_nrrd_frame(&p, Some(3)).unwrap_err().to_string();
            assert!(
                msg.contains("--frame 3") && msg.contains("numbered 0 to 2"),
                "{msg}"
            );
        }
    }
}

#[test]
fn an_nrrd_that_does_not_say_which_axis_holds_the_frames_is_refused() {
    let dir = tmpdir("nrrd_bad");
    let body = bytes_4d(3);
    let base =
        "NRRD0004\ntype: short\ndimension: 4\nsizes: 3 4 2 3\nendian: little\nencoding: raw\n";
    let cases = [
        ("", "must mark exactly one axis"),
        (
            "kinds: domain domain domain domain\n",
            "must mark exactly one axis",
        ),
        (
            "kinds: list domain domain list\n",
            "must mark exactly one axis",
        ),
        (
            "kinds: domain domain domain list\nspace directions: none (1,0,0) (0,1,0) (0,0,1)\n",
            "disagree",
        ),
        ("kinds: domain domain list\n", "expected 4 entries"),
        (
            "space dimension: 4\nspace directions: (1,0,0,0) (0,1,0,0) (0,0,1,0) (0,0,0,9)\n",
            "ITK's 4D NRRD",
        ),
    ];
    for (i, (extra, want)) in cases.iter().enumerate() {
        let p = write(&dir, &format!("b{i}.nrrd"), format!("{base}{extra}"), &body);
        for frame in [None, Some(0)] {
            let msg = read_nrrd_frame(&p, frame).unwrap_err().to_string();
            assert!(msg.contains(want), "case {i} {frame:?}: {msg}");
        }
    }
    // A 2D colour image stored as dimension 3 is not a volume of three slices.
    let rgb = write(
        &dir,
        "rgb.nrrd",
        "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 3 4 5\nkinds: RGB-color domain domain\nencoding: raw\n"
            .into(),
        &[7u8; 60],
    );
    let msg = read_nrrd(&rgb).unwrap_err().to_string();
    assert!(
        msg.contains("not a volume") && msg.contains("RGB-color"),
        "{msg}"
    );
    // A 3D NRRD holds frame 0 only; a series of one frame reads without --frame.
    let three = nrrd_3d(&dir, 1);
    assert_eq!(
        values(&read_nrrd_frame(&three, Some(0)).unwrap()),
        frame_values(1)
    );
    let msg = read_nrrd_frame(&three, Some(1)).unwrap_err().to_string();
    assert!(msg.contains("holds one 3D volume"), "{msg}");
    let one = write(
        &dir,
        "one.nrrd",
        "NRRD0004\ntype: short\ndimension: 4\nsizes: 3 4 2 1\nkinds: domain domain domain list\nendian: little\nencoding: raw\n".into(),
        &bytes_4d(3)[..48],
    );
    let v = read_nrrd(&one).unwrap();
    assert_eq!(values(&v), frame_values(0));
    assert!(v.notes().is_empty(), "{:?}", v.notes());
}

/// A MetaImage series as SimpleITK's `JoinSeries` writes it: `NDims = 4`, 4 spacings and
/// offsets, a 4 x 4 matrix.
fn mha_4d(dir: &Path, name: &str, matrix: &str) -> PathBuf {
    let h = format!(
        "ObjectType = Image\nNDims = 4\nBinaryData = True\nBinaryDataByteOrderMSB = False\n\
         CompressedData = False\nTransformMatrix = {matrix}\nOffset = 5 6 7 0\n\
         ElementSpacing = 2 1.5 3 1\nDimSize = 3 4 2 3\nElementType = MET_SHORT\n\
         ElementDataFile = LOCAL"
    );
    let p = dir.join(name);
    let mut b = h.into_bytes();
    b.push(b'\n');
    b.extend_from_slice(&bytes_4d(3));
    std::fs::write(&p, b).unwrap();
    p
}

#[test]
fn a_metaimage_series_reads_frame_by_frame_with_its_3d_geometry() {
    let dir = tmpdir("mha");
    let m4 = "0 1 0 0 -1 0 0 0 0 0 1 0 0 0 0 1";
    let p = mha_4d(&dir, "s.mha", m4);
    let h3 = "ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = False\n\
              CompressedData = False\nTransformMatrix = 0 1 0 -1 0 0 0 0 1\nOffset = 5 6 7\n\
              ElementSpacing = 2 1.5 3\nDimSize = 3 4 2\nElementType = MET_SHORT\n\
              ElementDataFile = LOCAL\n";
    for t in 0..FRAMES {
        let v = read_metaimage_frame(&p, Some(t)).unwrap();
        assert_eq!(values(&v), frame_values(t), "frame {t}");
        let q = dir.join(format!("f{t}.mha"));
        let mut b = h3.as_bytes().to_vec();
        b.extend(
            frame_values(t)
                .iter()
                .flat_map(|&x| (x as i16).to_le_bytes()),
        );
        std::fs::write(&q, b).unwrap();
        assert_eq!(v.affine(), read_metaimage(&q).unwrap().affine());
        let opts = LoadOptions {
            frame: Some(t),
            ..Default::default()
        };
        assert_eq!(values(&load_volume(&p, &opts).unwrap()), frame_values(t));
    }
    let msg = read_metaimage(&p).unwrap_err().to_string();
    assert!(msg.contains("pass --frame K (0 to 2)"), "{msg}");
    let msg = read_metaimage_frame(&p, Some(5)).unwrap_err().to_string();
    assert!(msg.contains("numbered 0 to 2"), "{msg}");
    // The frames' axis mixed with space: no one geometry for the frames.
    let mixed = mha_4d(&dir, "m.mha", "0 1 0 0 -1 0 0 0 0 0 1 0.5 0 0 0 1");
    let msg = read_metaimage_frame(&mixed, Some(0))
        .unwrap_err()
        .to_string();
    assert!(msg.contains("mixes with space"), "{msg}");
}
