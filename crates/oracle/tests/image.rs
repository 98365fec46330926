//! Tests of the voxel-image oracle (`oracle::image`).

mod common;

use glam::{DAffine3, DMat3, DQuat, DVec3};
use oracle::Surface;
use oracle::image::{
    Dtype, ImageError, ImageOptions, ImageSurface, LoadOptions, NiftiWriteOptions, Qform,
    RawOptions, Volume, Voxels, load_volume, read_nifti, read_raw, read_slice_folder,
    read_tiff_stack, synthetic, write_nifti,
};
use std::path::PathBuf;

fn tmpdir(name: &str) -> PathBuf {
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("oracle-image-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn fixtures() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/images")
}

/// The nilearn motor-task map fixture at iso 3 (9 blobs, one with a cavity).
fn nilearn_motor_at_iso_3() -> ImageSurface {
    let path = fixtures().join("nilearn_motor_10426.nii.gz");
    ImageSurface::open(path, &Default::default(), &at_iso(3.0)).unwrap()
}

/// Options with the iso value `iso` (bright foreground).
fn at_iso(iso: f64) -> ImageOptions {
    ImageOptions {
        iso: Some(iso),
        ..Default::default()
    }
}

fn dark(iso: f64) -> ImageOptions {
    ImageOptions {
        iso: Some(iso),
        dark_foreground: true,
        ..Default::default()
    }
}

/// Signed-distance ball of radius `r` centred at the origin, voxel size 1, on n^3 voxels.
fn sdf_ball(n: usize, r: f64) -> ImageSurface {
    let aff = DAffine3::from_translation(DVec3::splat(-(n as f64 - 1.0) / 2.0));
    let vol = synthetic::sample_implicit(|p| p.length() - r, [n; 3], aff);
    ImageSurface::new(vol, &dark(0.0)).unwrap()
}

#[test]
fn ball_sign_seeds_and_components() {
    let s = sdf_ball(32, 10.0);
    assert!(s.value(DVec3::ZERO) < 0.0);
    assert!(s.value(DVec3::new(12.0, 0.0, 0.0)) > 0.0);
    assert_eq!(s.component_count(), 1);
    let t = s.topology();
    assert_eq!((t.inside_components, t.outside_components), (1, 1));
    let seeds = s.seed_points(7);
    assert!(!seeds.is_empty());
    for p in &seeds {
        // Trilinear interpolation of a distance function: within ~0.05 voxel of the sphere.
        assert!(
            (p.length() - 10.0).abs() < 0.05,
            "seed {p} at radius {}",
            p.length()
        );
        assert!(s.value(*p).abs() < 1e-9);
    }
    // Deterministic, seed-dependent extras.
    assert_eq!(seeds, s.seed_points(7));
    // Bounding sphere: value positive on it.
    let bs = s.bounding_sphere();
    for d in [
        DVec3::X,
        DVec3::Y,
        DVec3::Z,
        DVec3::ONE.normalize(),
        -DVec3::ONE.normalize(),
    ] {
        assert!(s.value(bs.center + d * bs.radius) > 0.0);
        assert!(bs.contains(d * 10.0));
    }
}

#[test]
fn crossing_matches_bisection_and_lands_on_surface() {
    let s = sdf_ball(32, 10.0);
    let tol = s.tolerance();
    let mut rng = oracle::roots::SplitMix64(3);
    for _ in 0..200 {
        let a = rng.unit_vector() * 3.0 * rng.next_f64();
        let b = rng.unit_vector() * (11.0 + 3.0 * rng.next_f64());
        let (fa, fb) = (s.value(a), s.value(b));
        assert!(fa < 0.0 && fb > 0.0);
        let p = s.crossing(a, fa, b, fb);
        let q = oracle::roots::bisect(|x| s.value(x), oracle::roots::Ends::new(a, fa, b, fb), tol);
        assert!((p - q).length() < 2.0 * tol, "{p} vs {q}");
        // Reverse orientation too.
        let p2 = s.crossing(b, fb, a, fa);
        assert!((p2 - q).length() < 2.0 * tol);
        assert!(((p - a).cross(b - a)).length() / (b - a).length() < 1e-9);
    }
}

#[test]
fn gradient_points_outward() {
    let s = sdf_ball(32, 10.0);
    for d in [DVec3::X, DVec3::new(0.3, -0.5, 0.8).normalize()] {
        let g = s.gradient(d * 10.0);
        assert!(g.normalize().dot(d) > 0.98, "{g}");
        assert!((g.length() - 1.0).abs() < 0.1);
    }
}

#[test]
fn binary_ball_default_iso_and_dm_inf() {
    let n = 40;
    let aff = DAffine3::from_translation(DVec3::splat(-(n as f64 - 1.0) / 2.0));
    let r = 12.0;
    let vol = synthetic::sample_binary(|p| p.length() - r, [n; 3], aff);
    let s = ImageSurface::new(vol, &ImageOptions::default()).unwrap();
    assert_eq!(s.iso(), 0.5);
    assert!(s.value(DVec3::ZERO) < 0.0);
    assert_eq!(s.component_count(), 1);
    let dm = s.dm_inf_hint().unwrap();
    assert!(
        dm > 0.75 * r && dm <= r + 1.0,
        "binary ball dm_inf estimate {dm} for R = {r}"
    );
    // Each seed within a voxel of the sphere.
    for p in s.seed_points(1) {
        assert!((p.length() - r).abs() < 1.0, "{}", p.length());
    }
}

#[test]
fn dm_inf_of_sampled_ball_and_torus() {
    let s = sdf_ball(40, 12.0);
    let dm = s.dm_inf_hint().unwrap();
    assert!(dm > 12.0 - 1.5 && dm <= 12.0 + 0.5, "ball: {dm}");
    // Torus R = 10, r = 3: d_M^inf = 3 (the tube radius).
    let n = 40;
    let aff = DAffine3::from_translation(DVec3::splat(-(n as f64 - 1.0) / 2.0));
    let torus = |p: DVec3| (DVec3::new(p.x, p.y, 0.0).length() - 10.0).hypot(p.z) - 3.0;
    let vol = synthetic::sample_implicit(torus, [n; 3], aff);
    let s = ImageSurface::new(vol, &dark(0.0)).unwrap();
    assert_eq!(s.component_count(), 1);
    let dm = s.dm_inf_hint().unwrap();
    assert!(dm > 1.2 && dm <= 3.5, "torus: {dm}");
}

#[test]
fn two_blobs_nested_shells_and_border() {
    let n = 48;
    let aff = DAffine3::from_translation(DVec3::splat(-(n as f64 - 1.0) / 2.0));
    let c1 = DVec3::new(-10.0, 0.0, 0.0);
    let c2 = DVec3::new(11.0, 2.0, -3.0);
    let f = |p: DVec3| ((p - c1).length() - 7.0).min((p - c2).length() - 5.0);
    let s = ImageSurface::new(synthetic::sample_implicit(f, [n; 3], aff), &dark(0.0)).unwrap();
    assert_eq!(s.component_count(), 2);
    let seeds = s.topology().component_seeds.clone();
    assert!(seeds.iter().any(|p| (p - c1).length() < 8.0));
    assert!(seeds.iter().any(|p| (p - c2).length() < 6.0));

    // Shell 14 < |p| < 20 with a ball |p| < 6 inside: 3 surfaces; 2 inside, 2 outside regions.
    let f = |p: DVec3| {
        let r = p.length();
        (r - 6.0).min((r - 20.0).max(14.0 - r))
    };
    let s = ImageSurface::new(synthetic::sample_implicit(f, [n; 3], aff), &dark(0.0)).unwrap();
    let t = s.topology();
    assert_eq!((t.inside_components, t.outside_components), (2, 2));
    assert_eq!(s.component_count(), 3);
    let radii: Vec<f64> = t.component_seeds.iter().map(|p| p.length()).collect();
    for r in [6.0, 14.0, 20.0] {
        assert!(
            radii.iter().any(|x| (x - r).abs() < 0.1),
            "no seed at radius {r}: {radii:?}"
        );
    }

    // A ball cut by the grid box: closed by the background, one component; the value just
    // outside the box is positive.
    let f = |p: DVec3| (p - DVec3::new(20.0, 0.0, 0.0)).length() - 10.0;
    let s = ImageSurface::new(synthetic::sample_implicit(f, [n; 3], aff), &dark(0.0)).unwrap();
    assert_eq!(s.component_count(), 1);
    let edge = (n as f64 - 1.0) / 2.0;
    assert!(s.value(DVec3::new(edge - 0.5, 0.0, 0.0)) < 0.0);
    assert!(s.value(DVec3::new(edge + 1.0, 0.0, 0.0)) > 0.0);
    assert!(s.seed_points(0).iter().any(|p| p.x > edge));
}

#[test]
fn diagonal_face_connections_use_the_asymptotic_decider() {
    // Two voxels touching along an edge diagonal (xy face): joined or not by the face saddle.
    for (hi, expect) in [(1.0f32, 2usize), (3.0, 1)] {
        let mut v = vec![0f32; 4 * 4 * 3];
        let idx = |i: usize, j: usize, k: usize| i + 4 * (j + 4 * k);
        v[idx(1, 1, 1)] = hi;
        v[idx(2, 2, 1)] = hi;
        // iso 0.6: saddle of face (1,1)-(2,2) is (hi*hi - 0)/(2hi) - iso = hi/2 - 0.6.
        let vol = Volume::new([4, 4, 3], Voxels::F32(v), DAffine3::IDENTITY).unwrap();
        let s = ImageSurface::new(vol, &at_iso(0.6)).unwrap();
        assert_eq!(s.topology().inside_components, expect, "hi = {hi}");
        // Cross-check against the interpolant at the face centre.
        let inside_centre = s.value(DVec3::new(1.5, 1.5, 1.0)) < 0.0;
        assert_eq!(inside_centre, expect == 1);
    }
}

fn world_ellipsoid(p: DVec3) -> f64 {
    // Ellipsoid with semi-axes 9, 6, 5 (mm) centred at (3, -2, 1), in world coordinates.
    let q = (p - DVec3::new(3.0, -2.0, 1.0)) / DVec3::new(9.0, 6.0, 5.0);
    q.length() - 1.0
}

fn oblique_affine() -> DAffine3 {
    let rot = DQuat::from_axis_angle(DVec3::new(1.0, 2.0, 0.5).normalize(), 0.6);
    let m = DMat3::from_quat(rot) * DMat3::from_diagonal(DVec3::new(0.7, 0.9, 1.6));
    // Centre the grid (40 x 36 x 24 voxels) on the ellipsoid's centre.
    let c = DVec3::new(19.5, 17.5, 11.5);
    DAffine3::from_mat3_translation(m, DVec3::new(3.0, -2.0, 1.0) - m * c)
}

/// issue 17: a .nii with bytes after its (non-u8) voxel data reads the same voxels as
/// without them (nibabel ignores them), with a note naming the file and the count.
#[test]
fn trailing_bytes_after_float_voxels_are_ignored_with_a_note() {
    let dir = tmpdir("trailing-f32");
    let vol = synthetic::sample_implicit(world_ellipsoid, [10, 9, 6], oblique_affine());
    let path = dir.join("e.nii");
    write_nifti(&path, &vol, &NiftiWriteOptions::new()).unwrap();
    let clean = read_nifti(&path).unwrap();
    assert!(clean.notes().is_empty());
    let mut b = std::fs::read(&path).unwrap();
    b.extend_from_slice(&[0xff; 5]);
    std::fs::write(&path, &b).unwrap();
    let long = read_nifti(&path).unwrap();
    assert_eq!(long.voxels(), clean.voxels());
    assert_eq!(long.affine(), clean.affine());
    let n = long.notes();
    assert!(
        n.len() == 1 && n[0].contains("e.nii: 5 byte(s) after the voxel data"),
        "{n:?}"
    );
    // One byte short of the header's size is still an error.
    b.truncate(b.len() - 6);
    std::fs::write(&path, &b).unwrap();
    let e = read_nifti(&path).unwrap_err();
    assert!(matches!(e, ImageError::Truncated { .. }), "{e}");
}

#[test]
fn oblique_anisotropic_sform_matches_analytic_surface_in_world_space() {
    let dir = tmpdir("oblique");
    let aff = oblique_affine();
    let vol = synthetic::sample_implicit(world_ellipsoid, [40, 36, 24], aff);
    let path = dir.join("ellipsoid.nii.gz");
    write_nifti(&path, &vol, &NiftiWriteOptions::new()).unwrap();
    let back = read_nifti(&path).unwrap();
    assert_eq!(back.dims(), [40, 36, 24]);
    assert!((back.affine().matrix3 - aff.matrix3).abs_diff_eq(DMat3::ZERO, 1e-5));
    let s = ImageSurface::new(back, &dark(0.0)).unwrap();
    assert_eq!(s.component_count(), 1);
    // Zero crossings on rays from the centre match the analytic surface within a voxel.
    let c = DVec3::new(3.0, -2.0, 1.0);
    let mut rng = oracle::roots::SplitMix64(11);
    for _ in 0..100 {
        let d = rng.unit_vector();
        let b = c + d * 12.0;
        let p = s.crossing(c, s.value(c), b, s.value(b));
        // Analytic crossing along the ray: |(d * t) / axes| = 1.
        let t = 1.0 / (d / DVec3::new(9.0, 6.0, 5.0)).length();
        assert!(
            ((p - c).length() - t).abs() < 0.3,
            "ray {d}: {} vs {t}",
            (p - c).length()
        );
    }
    for p in s.seed_points(0) {
        assert!(world_ellipsoid(p).abs() < 0.05, "{p}");
    }
}

#[test]
fn negative_determinant_affines_keep_the_inside_inside() {
    let dir = tmpdir("negdet");
    let n = 24;
    let centre = DVec3::new(5.0, -7.0, 2.0);
    let ball = |p: DVec3| (p - centre).length() - 6.0;
    // x flipped (radiological LAS-like) sform, and a pixdim diagonal with a negative entry.
    let m = DMat3::from_diagonal(DVec3::new(-1.0, 1.0, 1.2));
    let aff = DAffine3::from_mat3_translation(m, centre - m * DVec3::splat(11.5));
    assert!(aff.matrix3.determinant() < 0.0);
    let vol = synthetic::sample_implicit(ball, [n; 3], aff);
    let check = |s: &ImageSurface| {
        assert!(s.value(centre) < 0.0);
        assert!(s.value(centre + DVec3::new(7.0, 0.0, 0.0)) > 0.0);
        assert!(s.value(centre + DVec3::new(0.0, 0.0, 8.0)) > 0.0);
        let g = s.gradient(centre + DVec3::X * 6.0);
        assert!(g.x > 0.0, "outward gradient {g}");
        for p in s.seed_points(0) {
            assert!(ball(p).abs() < 0.05);
        }
    };
    check(&ImageSurface::new(vol.clone(), &dark(0.0)).unwrap());
    // Through NIfTI: sform.
    let p1 = dir.join("negdet_sform.nii");
    write_nifti(&p1, &vol, &NiftiWriteOptions::new()).unwrap();
    check(&ImageSurface::new(read_nifti(&p1).unwrap(), &dark(0.0)).unwrap());
    // qform with qfac = -1 (z flipped) and the identity rotation.
    let q = Qform {
        b: 0.0,
        c: 0.0,
        d: 0.0,
        offset: centre + DVec3::new(-11.5, -11.5, 11.5),
        qfac: -1.0,
        pixdim: DVec3::ONE,
    };
    let qa = q.affine();
    assert!(qa.matrix3.determinant() < 0.0);
    let volq = synthetic::sample_implicit(ball, [n; 3], qa);
    let p2 = dir.join("negdet_qform.nii.gz");
    let opts = NiftiWriteOptions {
        sform: false,
        qform: Some(q),
        ..Default::default()
    };
    write_nifti(&p2, &volq, &opts).unwrap();
    let back = read_nifti(&p2).unwrap();
    assert!((back.affine().matrix3 - qa.matrix3).abs_diff_eq(DMat3::ZERO, 1e-6));
    check(&ImageSurface::new(back, &dark(0.0)).unwrap());
    // No sform, no qform: diagonal pixdim with pixdim[1] < 0. As nibabel, the absolute value
    // is used (issue 17: a negative pixdim must not mirror the mesh silently).
    let pd = DAffine3::from_mat3(DMat3::from_diagonal(DVec3::new(-1.0, 1.0, 1.0)));
    let c0 = DVec3::new(-11.5, 11.5, 11.5);
    let ball0 = |p: DVec3| (p - c0).length() - 6.0;
    let vold = synthetic::sample_implicit(ball0, [n; 3], pd);
    let p3 = dir.join("negdet_pixdim.nii");
    let opts = NiftiWriteOptions {
        sform: false,
        pixdim: Some([-1.0, 1.0, 1.0]),
        ..Default::default()
    };
    write_nifti(&p3, &vold, &opts).unwrap();
    let back = read_nifti(&p3).unwrap();
    assert_eq!(back.affine(), DAffine3::IDENTITY);
    let s = ImageSurface::new(back, &dark(0.0)).unwrap();
    let c1 = DVec3::splat(11.5); // the ball's centre voxel, at |pixdim| = 1
    assert!(s.value(c1) < 0.0 && s.value(c1 + DVec3::X * 7.0) > 0.0);
    assert!(s.value(c0) > 0.0, "not mirrored to x < 0");
}

#[test]
fn qform_rotation_matches_sform() {
    // A rotation quaternion (b, c, d) with a > 0, pixdim (0.8, 1.1, 1.3), qfac = +1.
    let rot = DQuat::from_axis_angle(DVec3::new(0.2, -1.0, 0.4).normalize(), 0.9);
    let q = Qform {
        b: rot.x,
        c: rot.y,
        d: rot.z,
        offset: DVec3::new(-3.0, 4.0, 5.0),
        qfac: 1.0,
        pixdim: DVec3::new(0.8, 1.1, 1.3),
    };
    let expect = DMat3::from_quat(rot) * DMat3::from_diagonal(q.pixdim);
    assert!((q.affine().matrix3 - expect).abs_diff_eq(DMat3::ZERO, 1e-12));
    assert_eq!(q.affine().translation, q.offset);
}

fn all_dtype_volumes() -> Vec<Volume> {
    let dims = [5, 4, 3];
    let n = 60;
    let aff = DAffine3::from_scale(DVec3::new(0.5, 0.75, 2.0));
    let mk = |v: Voxels| Volume::new(dims, v, aff).unwrap();
    vec![
        mk(Voxels::U8((0..n).map(|i| (i * 4) as u8).collect())),
        mk(Voxels::I8((0..n).map(|i| i as i8 - 30).collect())),
        mk(Voxels::U16((0..n).map(|i| (i * 1000) as u16).collect())),
        mk(Voxels::I16(
            (0..n).map(|i| (i * 500 - 15000) as i16).collect(),
        )),
        mk(Voxels::U32((0..n).map(|i| i as u32 * 70_000_000).collect())),
        mk(Voxels::I32(
            (0..n).map(|i| i * 30_000_000 - 900_000_000).collect(),
        )),
        mk(Voxels::F32((0..n).map(|i| i as f32 * 0.25 - 3.0).collect())),
        mk(Voxels::F64(
            (0..n).map(|i| i as f64 * 1e-3 - 0.01).collect(),
        )),
    ]
}

#[test]
fn nifti_round_trips_every_type_both_endians_and_scaling() {
    let dir = tmpdir("roundtrip");
    for (t, vol) in all_dtype_volumes().into_iter().enumerate() {
        let vol = vol.with_scaling(0.5, -10.0);
        for be in [false, true] {
            for ext in ["nii", "nii.gz"] {
                let p = dir.join(format!("v{t}_{be}.{ext}"));
                let opts = NiftiWriteOptions {
                    big_endian: be,
                    ..NiftiWriteOptions::new()
                };
                write_nifti(&p, &vol, &opts).unwrap();
                let back = read_nifti(&p).unwrap();
                assert_eq!(back.voxels(), vol.voxels(), "{} be={be}", vol.dtype());
                assert_eq!(back.dims(), vol.dims());
                assert_eq!(back.scaling(), (0.5, -10.0));
                assert_eq!(back.affine(), vol.affine());
                // Scaling applied at sampling time: value = -(0.5 raw - 10 - iso).
                let iso = back.get(2, 1, 1) - 0.01 * (back.get(2, 1, 1) - back.get(1, 1, 1));
                let s = ImageSurface::new(back.clone(), &at_iso(iso)).unwrap();
                let v = s.value(back.to_world(DVec3::new(2.0, 1.0, 1.0)));
                assert!((v + (back.get(2, 1, 1) - iso)).abs() < 1e-9 * (1.0 + v.abs()));
            }
        }
    }
}

#[test]
fn load_volume_dispatches_and_reads_stacks() {
    let dir = tmpdir("stacks");
    // 16-bit PNG slices named s1..s11: natural order puts s2 before s10.
    let slices = dir.join("png16");
    std::fs::create_dir_all(&slices).unwrap();
    let (w, h) = (7u32, 5u32);
    for k in 1..=11u16 {
        let img = image::ImageBuffer::<image::Luma<u16>, _>::from_fn(w, h, |x, y| {
            image::Luma([k * 1000 + (x + 10 * y) as u16])
        });
        img.save(slices.join(format!("s{k}.png"))).unwrap();
    }
    std::fs::write(slices.join("notes.txt"), "ignored").unwrap();
    let opts = LoadOptions {
        spacing: Some([0.5, 0.5, 2.0]),
        ..Default::default()
    };
    let v = load_volume(&slices, &opts).unwrap();
    assert_eq!(v.dims(), [7, 5, 11]);
    assert_eq!(v.dtype(), Dtype::U16);
    for k in 0..11 {
        assert_eq!(v.get(3, 2, k), ((k + 1) * 1000 + 23) as f64);
    }
    assert_eq!(
        v.to_world(DVec3::new(1.0, 1.0, 1.0)),
        DVec3::new(0.5, 0.5, 2.0)
    );

    // 8-bit TIFF slices with one of a different size: error naming that file.
    let bad = dir.join("tif8");
    std::fs::create_dir_all(&bad).unwrap();
    for k in 0..4u32 {
        let ww = if k == 2 { 8 } else { 6 };
        let img = image::GrayImage::from_fn(ww, 4, |x, _| image::Luma([(x * 10 + k) as u8]));
        img.save(bad.join(format!("slice_{k:03}.tif"))).unwrap();
    }
    let e = read_slice_folder(&bad, None).unwrap_err();
    assert!(matches!(e, ImageError::SliceSize { .. }));
    let msg = e.to_string();
    assert!(
        msg.contains("slice_002.tif") && msg.contains("8x4") && msg.contains("6x4"),
        "{msg}"
    );

    // Multi-page TIFF (16 bit) through the tiff crate.
    let mp = dir.join("stack.tif");
    {
        let f = std::fs::File::create(&mp).unwrap();
        let mut enc = tiff::encoder::TiffEncoder::new(f).unwrap();
        for k in 0..5u16 {
            let data: Vec<u16> = (0..12u16).map(|i| i + 100 * k).collect();
            enc.write_image::<tiff::encoder::colortype::Gray16>(4, 3, &data)
                .unwrap();
        }
    }
    let v = load_volume(&mp, &LoadOptions::default()).unwrap();
    assert_eq!(v.dims(), [4, 3, 5]);
    assert_eq!(v.get(1, 2, 4), (9 + 400) as f64);
    let v2 = read_tiff_stack(&mp, Some([1.0, 2.0, 3.0])).unwrap();
    assert_eq!(v2.spacing(), DVec3::new(1.0, 2.0, 3.0));

    // Raw: round trip, big endian, with a header offset; size mismatch is an error.
    let raw = dir.join("vol.raw");
    let vals: Vec<i16> = (0..60).map(|i| i * 7 - 200).collect();
    let mut bytes = vec![0xAAu8; 16];
    for v in &vals {
        bytes.extend_from_slice(&v.to_be_bytes());
    }
    std::fs::write(&raw, &bytes).unwrap();
    let ro = RawOptions {
        dims: [5, 4, 3],
        dtype: "int16".parse().unwrap(),
        big_endian: true,
        offset: 16,
    };
    let v = read_raw(&raw, &ro, Some([1.0, 1.0, 2.5])).unwrap();
    assert_eq!(v.voxels(), &Voxels::I16(vals));
    let e = read_raw(&raw, &RawOptions { offset: 0, ..ro }, None).unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.contains("needs 120 bytes") && msg.contains("has 136"),
        "{msg}"
    );
    let e = read_raw(&raw, &ro, Some([1.0, 0.0, 1.0])).unwrap_err();
    assert!(matches!(e, ImageError::BadSpacing { .. }));
    assert!(matches!(
        load_volume(&raw, &LoadOptions::default()),
        Err(ImageError::RawNeedsDims { .. })
    ));
}

#[test]
fn labels_are_listed_and_meshed_one_at_a_time() {
    let n = 24;
    let aff = DAffine3::from_translation(DVec3::splat(-11.5));
    let c1 = DVec3::new(-5.0, 0.0, 0.0);
    let c2 = DVec3::new(5.0, 0.0, 0.0);
    let mut v = vec![0u8; n * n * n];
    for (i, x) in v.iter_mut().enumerate() {
        let p = aff.transform_point3(DVec3::new(
            (i % n) as f64,
            ((i / n) % n) as f64,
            (i / (n * n)) as f64,
        ));
        if (p - c1).length() < 4.0 {
            *x = 3;
        } else if (p - c2).length() < 4.0 || (p - c2 - DVec3::Z * 9.0).length() < 2.5 {
            *x = 7;
        }
    }
    let vol = Volume::new([n; 3], Voxels::U8(v), aff).unwrap();
    let labels = vol.labels().unwrap();
    assert_eq!(
        labels.iter().map(|l| l.0).collect::<Vec<_>>(),
        vec![0, 3, 7]
    );
    assert_eq!(labels.iter().map(|l| l.1).sum::<usize>(), n * n * n);
    let opt = |l| ImageOptions {
        label: Some(l),
        ..Default::default()
    };
    let s3 = ImageSurface::new(vol.clone(), &opt(3)).unwrap();
    assert_eq!(s3.component_count(), 1);
    assert!(s3.value(c1) < 0.0 && s3.value(c2) > 0.0);
    let s7 = ImageSurface::new(vol.clone(), &opt(7)).unwrap();
    assert_eq!(s7.component_count(), 2);
    assert!(s7.value(c2) < 0.0 && s7.value(c1) > 0.0);
    // Without a label the 3-valued image needs an iso value.
    let e = ImageSurface::new(vol.clone(), &ImageOptions::default()).unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.starts_with(
            "iso value required for a non-binary image; the data range is [0, 7] (pass --iso \
             VALUE, e.g. --iso "
        ) && msg.ends_with("(Otsu's threshold of the histogram), or --label L for a segmentation)"),
        "{msg}"
    );
    let e = ImageSurface::new(vol, &opt(5)).unwrap_err();
    assert!(e.to_string().contains("labels present: 0, 3, 7"), "{e}");
}

#[test]
fn bad_input_gives_clear_errors() {
    let dir = tmpdir("errors");
    let aff = DAffine3::IDENTITY;
    // Constant image.
    let vol = Volume::new([3, 3, 3], Voxels::U8(vec![4; 27]), aff).unwrap();
    let e = ImageSurface::new(vol, &ImageOptions::default()).unwrap_err();
    assert!(e.to_string().contains("all voxels equal 4"), "{e}");
    // NaN voxel, with its index.
    let mut v = vec![0f32; 27];
    v[1 + 3 * 2] = 1.0;
    v[2 + 3 * (1 + 3 * 2)] = f32::NAN;
    let vol = Volume::new([3, 3, 3], Voxels::F32(v), aff).unwrap();
    let e = ImageSurface::new(vol, &at_iso(0.5)).unwrap_err();
    assert!(e.to_string().contains("voxel [2, 1, 2] is NaN"), "{e}");
    // Iso outside the data range.
    let vol = synthetic::sample_implicit(|p| p.x, [4, 4, 4], aff);
    let e = ImageSurface::new(vol.clone(), &at_iso(9.0)).unwrap_err();
    assert_eq!(
        e.to_string(),
        "iso value 9 is outside the data range [0, 3] (or equal to an end): there is no surface; pick a value strictly inside the range"
    );
    // Background on the wrong side.
    let e = ImageSurface::new(
        vol,
        &ImageOptions {
            iso: Some(1.5),
            background: Some(2.0),
            ..Default::default()
        },
    )
    .unwrap_err();
    assert!(matches!(e, ImageError::BadBackground { .. }));
    // Length mismatch, empty, singular affine.
    assert!(matches!(
        Volume::new([3, 3, 3], Voxels::U8(vec![0; 26]), aff),
        Err(ImageError::LengthMismatch {
            expected: 27,
            actual: 26,
            ..
        })
    ));
    assert!(matches!(
        Volume::new([3, 0, 3], Voxels::U8(vec![]), aff),
        Err(ImageError::Empty { .. })
    ));
    assert!(matches!(
        Volume::new(
            [1, 1, 1],
            Voxels::U8(vec![0]),
            DAffine3::from_scale(DVec3::new(1.0, 0.0, 1.0))
        ),
        Err(ImageError::BadAffine { .. })
    ));
    // A 2D NIfTI (dim[3] = 1) and a 4D one.
    let vol2d = Volume::new([4, 4, 1], Voxels::U8((0..16).collect()), aff).unwrap();
    let p = dir.join("flat.nii");
    let o = NiftiWriteOptions {
        dim_override: Some([2, 4, 4, 1, 1, 1, 1, 1]),
        ..NiftiWriteOptions::new()
    };
    write_nifti(&p, &vol2d, &o).unwrap();
    let e = read_nifti(&p).unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.contains("flat.nii") && msg.contains("2D image (dim[3] = 1)"),
        "{msg}"
    );
    let vol4 = Volume::new([2, 2, 8], Voxels::U8(vec![0; 32]), aff).unwrap();
    let p = dir.join("series.nii");
    let o = NiftiWriteOptions {
        dim_override: Some([4, 2, 2, 2, 4, 1, 1, 1]),
        ..NiftiWriteOptions::new()
    };
    write_nifti(&p, &vol4, &o).unwrap();
    assert!(matches!(
        read_nifti(&p),
        Err(ImageError::FourD { frames: 4, .. })
    ));
    // Not a NIfTI file at all; missing file.
    let p = dir.join("garbage.nii");
    std::fs::write(&p, vec![7u8; 400]).unwrap();
    let e = read_nifti(&p).unwrap_err();
    assert!(e.to_string().contains("garbage.nii"), "{e}");
    assert!(matches!(
        read_nifti(dir.join("missing.nii")),
        Err(ImageError::Io { .. })
    ));
    // Unknown extension; empty slice folder.
    let p = dir.join("vol.xyz");
    std::fs::write(&p, b"x").unwrap();
    assert!(matches!(
        load_volume(&p, &LoadOptions::default()),
        Err(ImageError::UnknownFormat { .. })
    ));
    let empty = dir.join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    assert!(matches!(
        read_slice_folder(&empty, None),
        Err(ImageError::NoSlices { .. })
    ));
    // Non-integer values are not labels.
    let vol = synthetic::sample_implicit(|p| p.x * 0.3, [4, 4, 4], aff);
    assert!(matches!(vol.labels(), Err(ImageError::NotLabels { .. })));
}

#[test]
fn real_looking_fixture_and_its_truncated_copy() {
    let f = fixtures().join("phantom_i16_32.nii.gz");
    let vol = read_nifti(&f).unwrap();
    assert_eq!(vol.dims(), [32, 32, 32]);
    assert_eq!(vol.dtype(), Dtype::I16);
    let (slope, inter) = vol.scaling();
    assert_eq!((slope, inter), (0.5, -100.0));
    assert!(vol.affine().matrix3.determinant() < 0.0);
    // "Skull" iso: bright shell above 250, closed; "brain" between 80 and 200.
    let s = ImageSurface::new(vol.clone(), &at_iso(250.0)).unwrap();
    assert_eq!(s.component_count(), 2, "outer and inner skull surfaces");
    let e = ImageSurface::new(vol, &ImageOptions::default()).unwrap_err();
    assert!(matches!(e, ImageError::IsoRequired { .. }));

    let t = fixtures().join("phantom_i16_32_truncated.nii.gz");
    let e = read_nifti(&t).unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, ImageError::Truncated { .. }), "{e:?}");
    assert!(
        msg.contains("phantom_i16_32_truncated.nii.gz") && msg.contains("truncated"),
        "{msg}"
    );
}

/// The phantom: an ellipsoidal head with a bright skull shell, grey brain, dark ventricles,
/// deterministic noise; i16 with scl_slope 0.5, scl_inter -100; LAS-like sform (x flipped).
fn phantom() -> Volume {
    let n = 32;
    let m = DMat3::from_diagonal(DVec3::new(-6.0, 6.5, 6.0));
    let aff = DAffine3::from_mat3_translation(m, -(m * DVec3::splat(15.5)));
    let mut rng = oracle::roots::SplitMix64(2024);
    let mut v = Vec::with_capacity(n * n * n);
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let p = aff.transform_point3(DVec3::new(i as f64, j as f64, k as f64));
                let r = (p / DVec3::new(80.0, 95.0, 85.0)).length();
                let vent =
                    ((p - DVec3::new(12.0, 5.0, 10.0)) / DVec3::new(10.0, 25.0, 12.0)).length();
                let mut val: f64 = if r > 1.0 {
                    0.0
                } else if r > 0.82 {
                    600.0
                } else {
                    140.0
                };
                if vent < 1.0 {
                    val = 30.0;
                }
                val += 10.0 * (rng.next_f64() - 0.5);
                v.push(((val + 100.0) / 0.5).round() as i16);
            }
        }
    }
    Volume::new([n; 3], Voxels::I16(v), aff)
        .unwrap()
        .with_scaling(0.5, -100.0)
}

#[test]
#[ignore = "regenerates fixtures/images (run by hand)"]
fn regenerate_fixtures() {
    let f = fixtures().join("phantom_i16_32.nii.gz");
    write_nifti(&f, &phantom(), &NiftiWriteOptions::new()).unwrap();
    let bytes = std::fs::read(&f).unwrap();
    let t = fixtures().join("phantom_i16_32_truncated.nii.gz");
    std::fs::write(&t, &bytes[..bytes.len() * 2 / 3]).unwrap();
}

#[test]
fn fixture_is_the_phantom() {
    let vol = read_nifti(fixtures().join("phantom_i16_32.nii.gz")).unwrap();
    let p = phantom();
    assert_eq!(vol.voxels(), p.voxels());
    assert!((vol.affine().matrix3 - p.affine().matrix3).abs_diff_eq(DMat3::ZERO, 1e-6));
}

#[test]
fn tanglecube_64_topology_and_seeds() {
    let vol = synthetic::tanglecube_volume(64);
    let s = ImageSurface::new(vol, &dark(0.0)).unwrap();
    assert_eq!(s.component_count(), 1);
    let t = s.topology();
    assert_eq!((t.inside_components, t.outside_components), (1, 1));
    let h = 5.2 / 63.0;
    for p in s.seed_points(5) {
        // Within a fraction of a voxel of the analytic surface (|grad f| ≈ 10..30 there).
        let g = {
            let e = 1e-6;
            oracle::roots::central_difference(synthetic::tanglecube, p, e)
        };
        let dist = synthetic::tanglecube(p).abs() / g.length();
        assert!(dist < 0.25 * h, "seed {p} is {dist} from the surface");
    }
    let dm = s.dm_inf_hint().unwrap();
    assert!(dm >= h && dm < 1.0, "tanglecube dm_inf estimate {dm}");
}

#[test]
fn results_do_not_depend_on_thread_count() {
    let vol = synthetic::tanglecube_volume(40);
    let run = |threads| {
        common::with_threads(threads, || {
            let s = ImageSurface::new(vol.clone(), &dark(0.0)).unwrap();
            (s.topology().clone(), s.seed_points(3), s.dm_inf_hint())
        })
    };
    assert_eq!(run(1), run(3));
}

/// Memory check: a 512^3 u16 volume (256 MiB of voxels). Run with
/// `/usr/bin/time -v cargo test -p oracle --release --test image -- --ignored large_512`
/// and read "Maximum resident set size".
#[test]
#[ignore = "large: 512^3 volume, run by hand for the memory figure"]
fn large_512_u16_volume() {
    use rayon::prelude::*;
    let n = 512;
    let c = (n as f64 - 1.0) / 2.0;
    let v: Vec<u16> = (0..n * n * n)
        .into_par_iter()
        .map(|p| {
            let q = DVec3::new((p % n) as f64, ((p / n) % n) as f64, (p / (n * n)) as f64);
            let r = (q - DVec3::splat(c)).length();
            (1000.0 + 2000.0 * (1.0 - r / 200.0).clamp(0.0, 1.0) + 0.5) as u16
        })
        .collect();
    let vol = Volume::new(
        [n; 3],
        Voxels::U16(v),
        DAffine3::from_scale(DVec3::splat(0.5)),
    )
    .unwrap();
    let s = ImageSurface::new(vol, &at_iso(2000.0)).unwrap();
    let t0 = std::time::Instant::now();
    assert_eq!(s.component_count(), 1);
    eprintln!("topology: {:?}", t0.elapsed());
    let t0 = std::time::Instant::now();
    let dm = s.dm_inf_hint().unwrap();
    eprintln!(
        "dm_inf_hint = {dm} (ball radius 50 world units): {:?}",
        t0.elapsed()
    );
    assert!(dm > 45.0 && dm < 51.0);
}

/// Inspect a real NIfTI file: `ORACLE_NIFTI=path [ORACLE_ISO=v] cargo test -p oracle --release
/// --test image -- --ignored real_nifti --nocapture`. Prints dims, type, transform, range,
/// components, the d_M^inf estimate and timings. Not run by default (needs a file outside the repo).
#[test]
#[ignore = "needs ORACLE_NIFTI=path"]
fn real_nifti_from_env() {
    let Ok(path) = std::env::var("ORACLE_NIFTI") else {
        return;
    };
    let t0 = std::time::Instant::now();
    let vol = read_nifti(&path).unwrap();
    eprintln!(
        "{path}: dims {:?} {} scaling {:?} read in {:?}",
        vol.dims(),
        vol.dtype(),
        vol.scaling(),
        t0.elapsed()
    );
    eprintln!(
        "affine {:?} det {}",
        vol.affine(),
        vol.affine().matrix3.determinant()
    );
    let st = vol.stats().unwrap();
    eprintln!("range [{}, {}], binary {:?}", st.min, st.max, st.binary);
    let iso = std::env::var("ORACLE_ISO")
        .ok()
        .map(|v| v.parse().unwrap())
        .unwrap_or(0.5 * (st.min + st.max));
    let s = ImageSurface::new(vol, &at_iso(iso)).unwrap();
    let t0 = std::time::Instant::now();
    let t = s.topology();
    eprintln!(
        "iso {iso}: {} surface components ({} inside, {} outside), {} crossing edges, {:?}",
        t.surface_components,
        t.inside_components,
        t.outside_components,
        t.crossing_edges,
        t0.elapsed()
    );
    let t0 = std::time::Instant::now();
    eprintln!("dm_inf_hint {:?} in {:?}", s.dm_inf_hint(), t0.elapsed());
    for p in s.seed_points(0).iter().take(2000) {
        assert!(s.value(*p).abs() < 1e-6 * (st.max - st.min));
    }
}

#[test]
fn real_statistical_map_from_nilearn() {
    let vol = read_nifti(fixtures().join("nilearn_motor_10426.nii.gz")).unwrap();
    assert_eq!(vol.dims(), [53, 63, 46]);
    assert_eq!(vol.dtype(), Dtype::F32);
    assert_eq!(vol.affine().matrix3.determinant(), -27.0);
    // The voxel of the largest t value is inside the iso-3 surface, in world space.
    let Voxels::F32(d) = vol.voxels() else {
        panic!()
    };
    let (imax, _) = d
        .iter()
        .enumerate()
        .fold((0, f32::MIN), |b, (i, &v)| if v > b.1 { (i, v) } else { b });
    let ijk = vol.unindex(imax);
    let world_max = vol.to_world(DVec3::new(ijk[0] as f64, ijk[1] as f64, ijk[2] as f64));
    let s = ImageSurface::new(vol, &at_iso(3.0)).unwrap();
    assert!(s.value(world_max) < 0.0);
    assert!(s.value(s.bounding_sphere().center + DVec3::X * s.bounding_sphere().radius) > 0.0);
    let n = s.component_count();
    assert!(n >= 2, "several activation blobs, found {n}");
    let seeds = s.seed_points(0);
    assert!(seeds.len() >= n);
    for p in &seeds {
        assert!(s.value(*p).abs() < 1e-6, "{p}");
    }
    // The gradient at a seed points outward (towards lower t values).
    let p = s.topology().component_seeds[0];
    let g = s.gradient(p);
    assert!(s.value(p + g.normalize() * 0.5) > s.value(p - g.normalize() * 0.5));
}

mod props {
    use super::*;
    use proptest::prelude::*;

    fn affine_strategy() -> impl Strategy<Value = DAffine3> {
        (
            prop::array::uniform3(-1.0f64..1.0),
            0.0f64..3.0,
            prop::array::uniform3(0.3f64..2.0),
            prop::bool::ANY,
            prop::array::uniform3(-20.0f64..20.0),
        )
            .prop_map(|(axis, angle, sc, flip, t)| {
                let axis = DVec3::from(axis);
                let axis = if axis.length() > 1e-3 {
                    axis.normalize()
                } else {
                    DVec3::Z
                };
                let mut s = DVec3::from(sc);
                if flip {
                    s.y = -s.y;
                }
                DAffine3::from_mat3_translation(
                    DMat3::from_quat(DQuat::from_axis_angle(axis, angle)) * DMat3::from_diagonal(s),
                    DVec3::from(t),
                )
            })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        /// At voxel centres the value is exactly -(intensity - iso); between them it is bounded
        /// by the cell's corner values; far outside it is the background. Any affine.
        #[test]
        fn value_interpolates_in_world_space(
            aff in affine_strategy(),
            data in prop::collection::vec(0u16..1000, 4 * 5 * 3),
            q in prop::array::uniform3(-1.5f64..5.5),
        ) {
            prop_assume!(data.iter().min() != data.iter().max());
            let vol = Volume::new([4, 5, 3], Voxels::U16(data.clone()), aff).unwrap();
            let s = ImageSurface::new(vol.clone(), &at_iso(500.5));
            prop_assume!(s.is_ok());
            let s = s.unwrap();
            for k in 0..3 { for j in 0..5 { for i in 0..4 {
                let p = aff.transform_point3(DVec3::new(i as f64, j as f64, k as f64));
                let v = s.value(p);
                let expect = -(vol.get(i, j, k) - 500.5);
                prop_assert!((v - expect).abs() < 1e-6, "{v} vs {expect}");
            }}}
            let q = DVec3::from(q);
            let v = s.value(aff.transform_point3(q));
            let (lo, hi) = (-(999.0 - 500.5), 500.5);
            prop_assert!(v >= lo - 1e-9 && v <= hi + 1e-9);
            let bs = s.bounding_sphere();
            prop_assert!(s.value(bs.center + DVec3::new(0.6, -0.3, 0.74).normalize() * bs.radius) > 0.0);
        }

        /// The crossing lies on the segment, within tolerance of a sign change.
        #[test]
        fn crossing_brackets_a_sign_change(
            aff in affine_strategy(),
            a in prop::array::uniform3(-1.0f64..16.0),
            b in prop::array::uniform3(-1.0f64..16.0),
        ) {
            let vol = synthetic::sample_implicit(
                |p| (aff.inverse().transform_point3(p) - DVec3::splat(7.0)).length() - 5.0,
                [15, 15, 15],
                aff,
            );
            let s = ImageSurface::new(vol, &dark(0.0)).unwrap();
            let (a, b) = (aff.transform_point3(DVec3::from(a)), aff.transform_point3(DVec3::from(b)));
            let (fa, fb) = (s.value(a), s.value(b));
            prop_assume!((fa < 0.0) != (fb < 0.0));
            let p = s.crossing(a, fa, b, fb);
            let d = (b - a).normalize();
            let tol = s.tolerance();
            let t = (p - a).dot(d);
            prop_assert!(t >= -tol && t <= (b - a).length() + tol);
            prop_assert!((a + d * t - p).length() < 1e-9 * (1.0 + p.length()));
            let (u, w) = (a + d * (t - tol).max(0.0), a + d * (t + tol).min((b - a).length()));
            let (fu, fw) = (s.value(u), s.value(w));
            prop_assert!((fu < 0.0) != (fw < 0.0) || fu.abs() < 1e-9 || fw.abs() < 1e-9,
                "no sign change around the crossing: {fu} {fw}");
        }

        /// Long segments through many blocks of the crossing's sign summary and several
        /// sheets (a tanglecube on 40^3 voxels, oblique affine), starting and ending inside,
        /// outside or beyond the grid: the crossing is within tolerance of a sign change.
        #[test]
        fn long_crossings_through_many_blocks(
            aff in affine_strategy(),
            a in prop::array::uniform3(-12.0f64..52.0),
            b in prop::array::uniform3(-12.0f64..52.0),
        ) {
            let inv = aff.inverse();
            let vol = synthetic::sample_implicit(
                |p| synthetic::tanglecube((inv.transform_point3(p) - DVec3::splat(19.5)) * 0.2),
                [40, 40, 40],
                aff,
            );
            let s = ImageSurface::new(vol, &dark(0.0)).unwrap();
            let (a, mut b) = (aff.transform_point3(DVec3::from(a)), aff.transform_point3(DVec3::from(b)));
            let fa = s.value(a);
            if (s.value(b) < 0.0) == (fa < 0.0) {
                // Replace b by a point of the other side: the centre is outside, a point of a
                // tube of the tanglecube inside.
                let v = if fa < 0.0 { DVec3::splat(19.5) } else { DVec3::new(27.4, 27.4, 19.5) };
                b = aff.transform_point3(v);
            }
            let fb = s.value(b);
            prop_assert!((fa < 0.0) != (fb < 0.0));
            for (a, fa, b, fb) in [(a, fa, b, fb), (b, fb, a, fa)] {
                let p = s.crossing(a, fa, b, fb);
                let d = (b - a).normalize();
                let tol = s.tolerance();
                let t = (p - a).dot(d);
                prop_assert!(t >= -tol && t <= (b - a).length() + tol);
                let (u, w) = (a + d * (t - tol).max(0.0), a + d * (t + tol).min((b - a).length()));
                let (fu, fw) = (s.value(u), s.value(w));
                prop_assert!((fu < 0.0) != (fw < 0.0) || fu.abs() < 1e-9 || fw.abs() < 1e-9,
                    "no sign change around the crossing: {fu} {fw}");
            }
        }
    }
}

/// CPU-time measurement helper (the machine may be loaded, so wall-clock benches mislead):
/// `/usr/bin/time -f %U target/release/deps/image-* --ignored cpu_loop` with ORACLE_LOOP=value
/// or crossing; divide the user time by the printed number of calls.
#[test]
#[ignore = "manual CPU-time measurement"]
fn cpu_loop() {
    let what = std::env::var("ORACLE_LOOP").unwrap_or_default();
    let s = ImageSurface::new(synthetic::tanglecube_volume(128), &dark(0.0)).unwrap();
    let mut rng = oracle::roots::SplitMix64(1);
    let t0 = std::time::Instant::now();
    let seeds = s.seed_points(0);
    let mut segs = Vec::new();
    for p in seeds.iter().cycle().take(100_000) {
        let d = rng.unit_vector() * (2.0 * 5.2 / 127.0);
        let (a, b) = (*p - d * rng.next_f64(), *p + d);
        let (fa, fb) = (s.value(a), s.value(b));
        if (fa < 0.0) != (fb < 0.0) {
            segs.push((a, fa, b, fb));
        }
        if segs.len() == 1000 {
            break;
        }
    }
    let pts: Vec<DVec3> = (0..4096)
        .map(|_| (DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) - 0.5) * 5.0)
        .collect();
    eprintln!("setup {:?}", t0.elapsed());
    let mut acc = 0.0;
    let n = 20_000_000usize;
    match what.as_str() {
        "value" => {
            for i in 0..n {
                acc += s.value(std::hint::black_box(pts[i & 4095]));
            }
        }
        "crossing" | "bisection" => {
            for i in 0..n / 10 {
                let (a, fa, b, fb) = segs[i % segs.len()];
                let p = if what == "crossing" {
                    s.crossing(a, fa, b, fb)
                } else {
                    oracle::roots::bisect(
                        |x| s.value(x),
                        oracle::roots::Ends::new(a, fa, b, fb),
                        s.tolerance(),
                    )
                };
                acc += p.x;
            }
        }
        _ => return,
    }
    eprintln!(
        "{what}: {} calls, acc {acc}",
        if what == "value" { n } else { n / 10 }
    );
}

#[test]
fn crossings_finds_both_sides_of_a_shell() {
    // Shell 6 < |p| < 9: a diameter crosses it 4 times.
    let n = 24;
    let aff = DAffine3::from_translation(DVec3::splat(-(n as f64 - 1.0) / 2.0));
    let f = |p: DVec3| (p.length() - 9.0).max(6.0 - p.length());
    let s = ImageSurface::new(synthetic::sample_implicit(f, [n; 3], aff), &dark(0.0)).unwrap();
    let mut out = Vec::new();
    let (a, b) = (DVec3::new(-15.0, 0.3, 0.2), DVec3::new(15.0, 0.3, 0.2));
    s.crossings(a, b, &mut out);
    assert_eq!(out.len(), 4, "{out:?}");
    let xs: Vec<f64> = out.iter().map(|p| p.x).collect();
    assert!(xs.windows(2).all(|w| w[0] < w[1]));
    for (x, e) in xs.iter().zip([-9.0f64, -6.0, 6.0, 9.0]) {
        assert!((x.abs() - e.abs()).abs() < 0.1, "{xs:?}");
    }
}

#[test]
fn dm_inf_of_an_ellipsoid_is_bounded_by_curvature() {
    // Semi-axes 9, 6, 5: the smallest radius of curvature is 5²/9 ≈ 2.78 (ends of the long
    // axis), smaller than the thickness part of the medial axis.
    let n = 28;
    let aff = DAffine3::from_translation(DVec3::splat(-(n as f64 - 1.0) / 2.0));
    let f = |p: DVec3| {
        let q = p / DVec3::new(9.0, 6.0, 5.0);
        // A signed distance-like function (exact on the axes).
        (q.length() - 1.0) * 5.0
    };
    let s = ImageSurface::new(synthetic::sample_implicit(f, [n; 3], aff), &dark(0.0)).unwrap();
    let dm = s.dm_inf_hint().unwrap();
    assert!(
        dm > 2.0 && dm < 3.2,
        "ellipsoid dm_inf estimate {dm}, true 2.78"
    );
}

#[test]
fn stats_over_many_chunks() {
    // 80^3 = 512 000 voxels (two parallel chunks): binary detection and the first NaN index.
    let n = 80;
    let mut v = vec![3.0f32; n * n * n];
    v[400_000] = 7.0;
    let vol = Volume::new([n; 3], Voxels::F32(v.clone()), DAffine3::IDENTITY).unwrap();
    let st = vol.stats().unwrap();
    assert_eq!((st.min, st.max, st.binary), (3.0, 7.0, Some((3.0, 7.0))));
    v[10] = 5.0;
    let vol = Volume::new([n; 3], Voxels::F32(v.clone()), DAffine3::IDENTITY).unwrap();
    assert_eq!(vol.stats().unwrap().binary, None);
    v[300_001] = f32::NAN;
    v[500_000] = f32::INFINITY;
    let vol = Volume::new([n; 3], Voxels::F32(v), DAffine3::IDENTITY).unwrap();
    let e = vol.stats().unwrap_err();
    assert!(matches!(e, ImageError::NaN { index, .. } if index == vol.unindex(300_001)));
    // An infinity alone, near the start or at the very end, is caught the same way.
    for at in [7, 511_999] {
        let mut v = vec![3.0f32; n * n * n];
        v[at] = f32::NEG_INFINITY;
        let vol = Volume::new([n; 3], Voxels::F32(v), DAffine3::IDENTITY).unwrap();
        let e = vol.stats().unwrap_err();
        assert!(
            matches!(e, ImageError::NaN { index, .. } if index == vol.unindex(at)),
            "{at}"
        );
    }
}

/// Component seeds always come first and are never diluted: seed_points has at most
/// `Topology::SEED_BUDGET` points when there are fewer components, so the mesher's
/// farthest-point thinning of control points (64 by default) keeps every component seed.
#[test]
fn seed_points_keep_every_component_seed_within_the_budget() {
    let s = nilearn_motor_at_iso_3();
    let t = s.topology();
    assert!(t.component_seeds.len() >= 2 && t.extra_seeds.len() > 64);
    for seed in [0, 1, 99] {
        let p = s.seed_points(seed);
        assert_eq!(p.len(), oracle::image::Topology::SEED_BUDGET);
        assert_eq!(p[..t.component_seeds.len()], t.component_seeds[..]);
    }
}

fn circumcentre(q: [DVec3; 4]) -> DVec3 {
    let (a, b, c) = (q[1] - q[0], q[2] - q[0], q[3] - q[0]);
    let det = a.dot(b.cross(c));
    q[0] + (b.cross(c) * a.length_squared()
        + c.cross(a) * b.length_squared()
        + a.cross(b) * c.length_squared())
        / (2.0 * det)
}

/// Checks the seed tetrahedra of `s`: four points on S whose circumcentre is near them (the
/// circumradius is at most 10 voxels: the tetrahedron is built within a small component or 3
/// voxels of a seed) and strictly on one side; returns (tetrahedra, circumcentres inside).
fn check_tets(s: &ImageSurface) -> (usize, usize) {
    let t = s.topology();
    assert_eq!(t.component_tets.len(), t.component_seeds.len());
    assert_eq!(t.component_edges.len(), t.component_seeds.len());
    let (mut n, mut inside) = (0, 0);
    for (seed, tet) in t.component_seeds.iter().zip(&t.component_tets) {
        if tet.is_empty() {
            continue;
        }
        assert_eq!(tet.len(), 3);
        let q = [*seed, tet[0], tet[1], tet[2]];
        let scale = s.volume().spacing().max_element();
        for p in q {
            assert!(s.value(p).abs() < 1e-9 * scale, "{p} not on S");
        }
        let cc = circumcentre(q);
        assert!(cc.distance(*seed) < 10.0 * scale, "{cc} far from {seed}");
        let v = s.value(cc);
        assert!(v != 0.0);
        n += 1;
        inside += (v < 0.0) as usize;
    }
    (n, inside)
}

/// Small components are seeded with a tetrahedron around them (the fix for blobs of one or
/// two voxels that the mesher's control-point rays used to miss): isolated bright voxels of
/// various intensities (so the blobs have various sizes and shapes) each get one, with the
/// circumcentre inside the blob, within a voxel of the bright voxel.
#[test]
fn single_voxel_blobs_get_seed_tetrahedra_around_them() {
    let n = 24;
    let mut v = vec![0f32; n * n * n];
    let mut centres = Vec::new();
    let mut rng = oracle::roots::SplitMix64(5);
    for k in 0..8 {
        let c = [3 + 5 * (k % 4), 4 + 8 * (k / 4), 5 + (k % 3) * 6];
        v[c[0] + n * (c[1] + n * c[2])] = 1.1 + rng.next_f64() as f32 * 3.0;
        // A dimmer neighbour on some blobs (elongated shapes).
        if k % 2 == 1 {
            v[c[0] + 1 + n * (c[1] + n * c[2])] = 0.6 + rng.next_f64() as f32 * 0.8;
        }
        centres.push(DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64));
    }
    let vol = Volume::new([n; 3], Voxels::F32(v), DAffine3::IDENTITY).unwrap();
    let s = ImageSurface::new(vol, &at_iso(1.0)).unwrap();
    assert_eq!(s.component_count(), 8);
    let (tets, inside) = check_tets(&s);
    assert_eq!((tets, inside), (8, 8));
    let t = s.topology();
    for (seed, tet) in t.component_seeds.iter().zip(&t.component_tets) {
        let cc = circumcentre([*seed, tet[0], tet[1], tet[2]]);
        let d = centres
            .iter()
            .map(|c| c.distance(cc))
            .fold(f64::INFINITY, f64::min);
        assert!(
            d < 1.0,
            "circumcentre {cc} is {d} voxels from its bright voxel"
        );
    }
    // The seed points put the four points of every tetrahedron first.
    let p = s.seed_points(0);
    assert_eq!(p.len(), oracle::image::Topology::SEED_BUDGET);
    for tet in &t.component_tets {
        for q in tet {
            assert!(p[..8 + 3 * 8].contains(q));
        }
    }
}

/// On the nilearn fixture at iso 3 (10 components: 9 blobs, 7 of them 1 to 13 voxels, and a
/// cavity), every component gets a seed tetrahedron; the circumcentres lie in the blobs
/// (value < 0) except for the cavity's (value > 0).
#[test]
fn nilearn_components_get_seed_tetrahedra() {
    let s = nilearn_motor_at_iso_3();
    let t = s.topology();
    assert_eq!((t.inside_components, t.outside_components), (9, 2));
    assert_eq!(check_tets(&s), (10, 9));
}

/// Integer voxels round the true values: the gradient's direction is known only to
/// asin(sqrt(3) q / (h |grad|)); float voxels are taken as exact.
#[test]
fn normal_uncertainty_from_integer_rounding() {
    let n = 16;
    // A ramp of 10 units per voxel along x, voxel size 0.5: |grad| = 20 per world unit.
    let ramp = |i: usize| 10.0 * i as f64;
    let idx = |p: usize| p % n;
    let affine = DAffine3::from_scale(DVec3::splat(0.5));
    let opts = at_iso(75.0);
    let u16v: Vec<u16> = (0..n * n * n).map(|p| ramp(idx(p)) as u16).collect();
    let f32v: Vec<f32> = (0..n * n * n).map(|p| ramp(idx(p)) as f32).collect();
    let s16 = ImageSurface::new(
        Volume::new([n; 3], Voxels::U16(u16v), affine).unwrap(),
        &opts,
    )
    .unwrap();
    let s32 = ImageSurface::new(
        Volume::new([n; 3], Voxels::F32(f32v), affine).unwrap(),
        &opts,
    )
    .unwrap();
    let p = DVec3::new(3.75, 4.1, 3.9); // on the level set x = 7.5 voxels
    let expect = (3f64.sqrt() * 1.0 / (0.5 * 20.0)).asin().to_degrees();
    let got = s16.normal_uncertainty_deg(p);
    assert!((got - expect).abs() < 1e-6, "{got} vs {expect}");
    assert_eq!(s32.normal_uncertainty_deg(p), 0.0);
}

// ---------------------------------------------------------------------------------------------
// Issue 17: strict NIfTI-1 reading. Each case is a file built as bytes here (a valid 8^3 u8 ball
// written by `write_nifti`, then patched); each was accepted (or misread) before.

mod strict_nifti {
    use super::*;
    use std::io::Write;

    /// A binary ball on 8^3 u8 voxels, identity sform centred on the grid (nibabel reads one
    /// centred ball).
    fn ball() -> Volume {
        let aff = DAffine3::from_translation(DVec3::splat(-3.5));
        let v: Vec<u8> = (0..512)
            .map(|i| {
                let p = DVec3::new((i % 8) as f64, (i / 8 % 8) as f64, (i / 64) as f64);
                u8::from((p - DVec3::splat(3.5)).length() <= 3.2)
            })
            .collect();
        Volume::new([8; 3], Voxels::U8(v), aff).unwrap()
    }

    /// The bytes of `ball()` as a single-file NIfTI-1 (little endian, vox_offset 352).
    fn ball_bytes() -> Vec<u8> {
        // One folder per call: tests run in parallel and `tmpdir` empties its folder.
        static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
        let k = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let p = tmpdir(&format!("strict-src{k}")).join("ball.nii");
        write_nifti(&p, &ball(), &NiftiWriteOptions::new()).unwrap();
        std::fs::read(p).unwrap()
    }

    fn put_f32(b: &mut [u8], off: usize, v: f32) {
        b[off..off + 4].copy_from_slice(&v.to_le_bytes());
    }
    fn put_i16(b: &mut [u8], off: usize, v: i16) {
        b[off..off + 2].copy_from_slice(&v.to_le_bytes());
    }

    fn gz(data: &[u8], level: flate2::Compression) -> Vec<u8> {
        let mut e = flate2::write::GzEncoder::new(Vec::new(), level);
        e.write_all(data).unwrap();
        e.finish().unwrap()
    }

    /// Read `bytes` saved as `name`.
    fn read(name: &str, bytes: &[u8]) -> Result<Volume, ImageError> {
        let p = tmpdir(&format!("strict-{name}")).join(name);
        std::fs::write(&p, bytes).unwrap();
        read_nifti(&p)
    }

    fn err(name: &str, bytes: &[u8]) -> (ImageError, String) {
        let e = read(name, bytes).expect_err(name);
        let s = e.to_string();
        assert!(s.contains(name), "names the file: {s}");
        assert!(
            !s.contains("NIfTI-2"),
            "a NIfTI-1 error does not mention NIfTI-2: {s}"
        );
        (e, s)
    }

    fn bad_field(name: &str, bytes: &[u8], field: &str) -> String {
        let (e, s) = err(name, bytes);
        match &e {
            ImageError::BadHeader { field: f, .. } => assert_eq!(f, field, "{s}"),
            _ => panic!("{name}: expected a BadHeader error on {field}, got {s}"),
        }
        assert!(s.contains(&format!("header field {field} ")), "{s}");
        s
    }

    #[test]
    fn the_valid_ball_reads_back() {
        let v = read("ok.nii", &ball_bytes()).unwrap();
        assert_eq!(v.voxels(), ball().voxels());
        assert_eq!(v.affine(), ball().affine());
    }

    #[test]
    fn vox_offset_1024_is_honoured() {
        let b = ball_bytes();
        let mut c = b[..352].to_vec();
        put_f32(&mut c, 108, 1024.0);
        c.resize(1024, 0);
        c.extend_from_slice(&b[352..]);
        let v = read("off1024.nii", &c).unwrap();
        assert_eq!(
            v.voxels(),
            ball().voxels(),
            "the voxels start at vox_offset"
        );
        let s = ImageSurface::new(v, &ImageOptions::default()).unwrap();
        assert_eq!(s.component_count(), 1, "one centred ball");
        assert!(s.value(DVec3::ZERO) < 0.0);
        // Gzipped too.
        let v = read("off1024.nii.gz", &gz(&c, flate2::Compression::default())).unwrap();
        assert_eq!(v.voxels(), ball().voxels());
    }

    #[test]
    fn bad_vox_offsets_are_rejected() {
        for (v, name) in [
            (1e9f32, "off1e9.nii"),
            (-100.0, "offneg.nii"),
            (f32::NAN, "offnan.nii"),
            (352.5, "offhalf.nii"),
            (0.0, "off0.nii"),
            (348.0, "off348.nii"),
        ] {
            let mut b = ball_bytes();
            put_f32(&mut b, 108, v);
            if v == 1e9 {
                let (e, s) = err(name, &b);
                assert!(matches!(e, ImageError::Truncated { .. }), "{s}");
                assert!(s.contains("after vox_offset 1000000000 has 0 bytes"), "{s}");
            } else {
                let s = bad_field(name, &b, "vox_offset");
                assert!(s.contains("at least 352"), "{s}");
            }
        }
    }

    #[test]
    fn data_length_must_match_dims_and_datatype() {
        let mut b = ball_bytes();
        // Bytes after the voxel data: read as nibabel reads them (ignored), with a note.
        b.extend_from_slice(&[1, 2, 3]);
        let v = read("long.nii", &b).unwrap();
        assert_eq!(v.voxels(), ball().voxels());
        assert_eq!(v.notes().len(), 1);
        let note = &v.notes()[0];
        assert!(
            note.contains("long.nii: 3 byte(s) after the voxel data"),
            "{note}"
        );
        assert!(note.contains("ignored"), "{note}");
        assert!(ball().notes().is_empty());
        b.truncate(352 + 511);
        let (e, s) = err("short.nii", &b);
        assert!(matches!(e, ImageError::Truncated { .. }), "{s}");
        assert!(
            s.contains("has 511 bytes, 512 voxels of u8 need 512"),
            "{s}"
        );
    }

    #[test]
    fn gzip_checksum_and_length_errors_are_detected() {
        let b = ball_bytes();
        // Stored (uncompressed) blocks: zero voxel bytes inside the block; the CRC-32 differs.
        let mut z = gz(&b, flate2::Compression::none());
        // One stored block: 10 bytes of gzip header, 5 of block header, then the file.
        let first_one = 352 + b[352..].iter().position(|&x| x == 1).unwrap();
        let at = 15 + first_one;
        assert_eq!(z[at..at + 8], b[first_one..first_one + 8]);
        assert!(z[at..at + 8].iter().any(|&x| x != 0));
        z[at..at + 8].fill(0);
        let (e, s) = err("zeroed.nii.gz", &z);
        assert!(matches!(e, ImageError::CorruptGzip { .. }), "{s}");
        // A wrong ISIZE (length modulo 2^32) in the trailer.
        let mut z = gz(&b, flate2::Compression::default());
        let n = z.len();
        z[n - 4] ^= 1;
        let (e, s) = err("isize.nii.gz", &z);
        assert!(matches!(e, ImageError::CorruptGzip { .. }), "{s}");
        // A corrupt deflate stream is corrupt, not truncated.
        let mut z = gz(&b, flate2::Compression::default());
        z[10] = 0xff; // the first block header: an invalid block type
        let (e, s) = err("deflate.nii.gz", &z);
        assert!(matches!(e, ImageError::CorruptGzip { .. }), "{s}");
        assert!(!s.contains("truncated"), "{s}");
        // Trailing garbage after the stream.
        let mut z = gz(&b, flate2::Compression::default());
        z.extend_from_slice(b"garbage");
        let (e, s) = err("trailing.nii.gz", &z);
        assert!(matches!(e, ImageError::CorruptGzip { .. }), "{s}");
        assert!(s.contains("7 bytes of trailing garbage"), "{s}");
        // A stream cut short is truncated.
        let z = gz(&b, flate2::Compression::default());
        let (e, s) = err("cut.nii.gz", &z[..z.len() - 5]);
        assert!(matches!(e, ImageError::Truncated { .. }), "{s}");
        // Valid: zero padding after the stream, and two concatenated members.
        let mut z = gz(&b, flate2::Compression::default());
        z.extend_from_slice(&[0; 16]);
        assert_eq!(read("pad.nii.gz", &z).unwrap().voxels(), ball().voxels());
        let mut z = gz(&b[..400], flate2::Compression::default());
        z.extend_from_slice(&gz(&b[400..], flate2::Compression::best()));
        assert_eq!(read("two.nii.gz", &z).unwrap().voxels(), ball().voxels());
    }

    /// The ball without an sform (`sform_code = 0`), with the given pixdim and qform code.
    fn no_sform(pixdim: [f32; 3], qform: bool) -> Vec<u8> {
        let mut b = ball_bytes();
        put_i16(&mut b, 254, 0);
        put_i16(&mut b, 252, i16::from(qform));
        for (i, p) in pixdim.iter().enumerate() {
            put_f32(&mut b, 80 + 4 * i, *p);
        }
        b
    }

    #[test]
    fn pixdim_zero_nan_or_inf_is_rejected_when_the_transform_uses_it() {
        for qform in [false, true] {
            for (k, d) in [0.0, f32::NAN, f32::INFINITY, f32::NEG_INFINITY]
                .iter()
                .enumerate()
            {
                let mut px = [1.0f32; 3];
                px[k % 3] = *d;
                let s = bad_field(
                    &format!("pix{k}{qform}.nii"),
                    &no_sform(px, qform),
                    &format!("pixdim[{}]", k % 3 + 1),
                );
                assert!(s.contains("finite non-zero"), "{s}");
            }
        }
        // With an sform, pixdim is not used (nibabel reads such a file with its sform).
        let mut b = ball_bytes();
        put_f32(&mut b, 80, 0.0);
        assert_eq!(read("pix_sform.nii", &b).unwrap().affine(), ball().affine());
    }

    #[test]
    fn negative_pixdim_does_not_mirror_with_a_qform() {
        // nibabel: pixdim[1..4] -> |pixdim|, so (-2, 1, 1) and (2, 1, 1) give the same qform.
        let neg = read("qneg.nii", &no_sform([-2.0, 1.0, 1.0], true)).unwrap();
        let pos = read("qpos.nii", &no_sform([2.0, 1.0, 1.0], true)).unwrap();
        assert_eq!(neg.affine(), pos.affine());
        assert!(neg.affine().matrix3.determinant() > 0.0);
        // qfac = pixdim[0] flips z only when it is -1 (nibabel resets other values to 1).
        let mut b = no_sform([1.0; 3], true);
        put_f32(&mut b, 76, -0.5);
        assert_eq!(read("qfac.nii", &b).unwrap().affine(), DAffine3::IDENTITY);
        put_f32(&mut b, 76, -1.0);
        let flipped = read("qfac1.nii", &b).unwrap().affine();
        assert_eq!(flipped.matrix3.z_axis, DVec3::new(0.0, 0.0, -1.0));
    }

    #[test]
    fn a_non_unit_quaternion_is_rejected() {
        let mut b = no_sform([1.0; 3], true);
        put_f32(&mut b, 256, 0.9);
        put_f32(&mut b, 260, 0.9);
        let s = bad_field("quat.nii", &b, "quatern_b/c/d");
        assert!(s.contains("exceeds 1"), "{s}");
    }

    #[test]
    fn wrong_sizeof_hdr_is_rejected_and_a_nifti2_size_needs_its_magic() {
        for v in [349i32, 0, 348 * 256] {
            let mut b = ball_bytes();
            b[..4].copy_from_slice(&v.to_le_bytes());
            let s = bad_field("sizeof.nii", &b, "sizeof_hdr");
            assert!(s.contains("a NIfTI-1 header has 348"), "{s}");
        }
        // 540 is NIfTI-2's size: read as such, the NIfTI-1 magic is named.
        let mut b = ball_bytes();
        b[..4].copy_from_slice(&540i32.to_le_bytes());
        let e = read("nifti2.nii", &b).unwrap_err();
        assert!(matches!(e, ImageError::Nifti { .. }), "{e}");
        assert!(e.to_string().contains("but the magic (bytes 4-11)"), "{e}");
    }

    /// scripts/mutate.py found these (exit 0 before): bitpix (bytes 72-73) not matching the
    /// datatype, e.g. a u8 file with bitpix 0 or 512, an f32 file with bitpix 16 or -32768.
    #[test]
    fn bitpix_must_match_the_datatype() {
        for v in [0i16, 16, 512, -32768] {
            let mut b = ball_bytes();
            b[72..74].copy_from_slice(&v.to_le_bytes());
            let s = bad_field(&format!("bitpix{v}.nii"), &b, "bitpix");
            assert!(s.contains(&format!("= {v} but datatype")), "{s}");
        }
    }

    #[test]
    fn infinite_scaling_is_rejected_and_slope_0_or_nan_means_none() {
        let mut b = ball_bytes();
        put_f32(&mut b, 112, f32::INFINITY);
        bad_field("slope.nii", &b, "scl_slope");
        put_f32(&mut b, 112, f32::NEG_INFINITY);
        bad_field("slope2.nii", &b, "scl_slope");
        put_f32(&mut b, 112, 2.0);
        put_f32(&mut b, 116, f32::INFINITY);
        bad_field("inter.nii", &b, "scl_inter");
        put_f32(&mut b, 116, f32::NAN);
        bad_field("inter2.nii", &b, "scl_inter");
        for slope in [0.0, f32::NAN] {
            put_f32(&mut b, 112, slope);
            put_f32(&mut b, 116, 5.0);
            assert_eq!(read("none.nii", &b).unwrap().scaling(), (1.0, 0.0));
        }
        put_f32(&mut b, 112, 2.0);
        put_f32(&mut b, 116, -1.0);
        assert_eq!(read("scaled.nii", &b).unwrap().scaling(), (2.0, -1.0));
    }

    #[test]
    fn dim_errors_name_the_right_field() {
        let mut b = ball_bytes();
        put_i16(&mut b, 42, 0); // dim[1] = 0
        let s = bad_field("dim1.nii", &b, "dim[1]");
        assert!(
            s.contains("dim[1] = 0: every dimension must be at least 1"),
            "{s}"
        );
        assert!(!s.contains("dim[0]"), "{s}");
        let mut b = ball_bytes();
        put_i16(&mut b, 44, -3); // dim[2] = -3
        bad_field("dim2.nii", &b, "dim[2]");
        let mut b = ball_bytes();
        put_i16(&mut b, 40, 0); // dim[0] = 0
        bad_field("dim0.nii", &b, "dim[0]");
        // A 1x1x1 volume is a single voxel, not "a 2D image".
        let one = Volume::new([1; 3], Voxels::U8(vec![1]), DAffine3::IDENTITY).unwrap();
        let p = tmpdir("strict-one").join("one.nii");
        write_nifti(&p, &one, &NiftiWriteOptions::new()).unwrap();
        let s = read_nifti(&p).unwrap_err().to_string();
        assert!(s.contains("is a single voxel, not a volume"), "{s}");
        assert!(!s.contains("2D image"), "{s}");
    }

    #[test]
    fn garbage_is_named_without_nifti2() {
        let (e, s) = err("garbage.nii", &[7u8; 400]);
        assert!(matches!(e, ImageError::Nifti { .. }), "{s}");
        assert!(s.contains("the magic (bytes 344-347)"), "{s}");
        let (e, s) = err("short_header.nii", &[0u8; 20]);
        assert!(matches!(e, ImageError::Truncated { .. }), "{s}");
    }

    /// The ball with these sform rows.
    fn with_sform(rows: [[f32; 4]; 3]) -> Vec<u8> {
        let mut b = ball_bytes();
        for (r, row) in rows.iter().enumerate() {
            for (c, v) in row.iter().enumerate() {
                put_f32(&mut b, 280 + 16 * r + 4 * c, *v);
            }
        }
        b
    }

    #[test]
    fn huge_or_degenerate_sforms_are_rejected_at_load() {
        let id = |sx: f32, t: f32| {
            [
                [sx, 0.0, 0.0, t],
                [0.0, 1.0, 0.0, 0.0],
                [0.0, 0.0, 1.0, 0.0],
            ]
        };
        for (name, rows, want) in [
            ("x1e20.nii", id(1e20, 0.0), "a voxel size is 1.00000002"),
            ("srow38.nii", id(3.4e38, 0.0), "a voxel size is 3.39"),
            ("srow30.nii", id(1e30, 0.0), "a voxel size is 1"),
            ("aniso.nii", id(1e7, 0.0), "times longer in one direction"),
            ("aniso6.nii", id(1e6, 0.0), "times longer in one direction"),
            ("tiny.nii", id(1e-13, 0.0), "a voxel size is 9.99"),
            ("far.nii", id(1.0, 1e15), "voxels from the origin"),
            ("inf.nii", id(f32::INFINITY, 0.0), "NaN or infinite"),
            ("det0.nii", id(0.0, 0.0), "the determinant is 0"),
        ] {
            let (e, s) = err(name, &with_sform(rows));
            assert!(matches!(e, ImageError::BadAffine { .. }), "{s}");
            assert!(
                s.contains("sform (srow_x/y/z)") && s.contains(want),
                "{name}: {s}"
            );
            assert!(s.contains("fix the header's transform"), "{s}");
        }
        // Within the limits: read (the mesher's budget, not the reader, bounds the work).
        for sx in [1e4f32, 1e-2] {
            read("okaniso.nii", &with_sform(id(sx, 0.0))).unwrap();
        }
        // The same limits apply to every loader (here a raw volume's spacing).
        let e = Volume::new(
            [2; 3],
            Voxels::U8(vec![0; 8]),
            DAffine3::from_scale(DVec3::new(1e20, 1.0, 1.0)),
        )
        .unwrap_err();
        assert!(e.to_string().contains("--spacing"), "{e}");
    }
}
