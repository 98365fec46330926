//! End to end: 3D images through the voxel-image oracle (`oracle::image::ImageSurface`) and the
//! mesher (issue 5). Volumes are generated here (sampled analytic surfaces) except the real
//! NIfTI fixture; the meshes are checked with `verify` against the analytic surfaces.

use glam::{DAffine3, DMat3, DQuat, DVec3};
use oracle::Surface;
use oracle::image::{ImageOptions, ImageSurface, Volume, synthetic};
use rdt_mesher::{Criteria, MeshOptions, MeshResult, Sizing, mesh};
use std::path::PathBuf;
use std::time::Instant;

fn dark(iso: f64) -> ImageOptions {
    ImageOptions {
        iso: Some(iso),
        dark_foreground: true,
        ..Default::default()
    }
}

fn opts(size: f64) -> MeshOptions {
    MeshOptions {
        criteria: Criteria {
            size: Some(Sizing::Constant(size)),
            min_angle_deg: 30.0,
            max_distance: None,
        },
        ..Default::default()
    }
}

/// Mesh `s`, assert a complete run, and return the mesh with its verification report against
/// `reference` (the analytic surface, or the image itself).
fn mesh_and_verify(
    s: &ImageSurface,
    o: &MeshOptions,
    reference: &dyn Surface,
) -> (MeshResult, verify::Report) {
    let t = Instant::now();
    let out = mesh(s, o).expect("meshing succeeds");
    let secs = t.elapsed().as_secs_f64();
    assert!(out.stats.stopped_by.is_none(), "{:?}", out.stats.stopped_by);
    let vo = verify::Options {
        samples_per_edge: 2,
        self_intersections: false,
        component_seeds: Some(s.topology().component_seeds.clone()),
        ..Default::default()
    };
    let r = verify::check_against(&out.mesh, reference, &vo);
    eprintln!(
        "{} vertices, {} facets in {secs:.3} s; scan components {}",
        out.stats.vertices,
        out.stats.facets,
        s.component_count()
    );
    (out, r)
}

fn topo(r: &verify::Report) -> &verify::Topology {
    r.topology.as_ref().expect("topology section")
}

fn geometry(r: &verify::Report) -> &verify::Geometry {
    r.geometry.as_ref().expect("geometry section")
}

/// Closed, oriented 2-manifold with exactly the components the voxel scan found.
fn assert_closed_with_all_components(s: &ImageSurface, r: &verify::Report) {
    let t = topo(r);
    assert!(t.is_closed_oriented_manifold(), "{}", r.summary());
    assert_eq!(
        t.components.len(),
        s.component_count(),
        "mesh components vs voxel scan\n{}",
        r.summary()
    );
}

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/images")
        .join(name)
}

/// The tanglecube sampled on 64^3 voxels (h = 0.083 over [-2.6, 2.6]^3), meshed at sigma 0.12:
/// one closed genus-5 surface within half a voxel of the analytic tanglecube.
#[test]
fn tanglecube_64_genus_5_close_to_the_analytic_surface() {
    let n = 64;
    let s = ImageSurface::new(synthetic::tanglecube_volume(n), &dark(0.0)).unwrap();
    let h = 5.2 / (n as f64 - 1.0);
    assert_eq!(s.component_count(), 1);
    let analytic = oracle::catalog::surface("tanglecube").unwrap();
    let (out, r) = mesh_and_verify(&s, &opts(0.12), &analytic);
    assert!(out.stats.criteria_met, "{:?}", out.stats.unmet);
    assert_closed_with_all_components(&s, &r);
    assert_eq!(topo(&r).genera(), vec![Some(5)], "{}", r.summary());
    let g = geometry(&r);
    eprintln!(
        "tanglecube 64^3: Hausdorff {:.4} = {:.3} voxel",
        g.hausdorff,
        g.hausdorff / h
    );
    assert!(
        g.hausdorff < 0.5 * h,
        "Hausdorff {} vs voxel {h}\n{}",
        g.hausdorff,
        r.summary()
    );
    assert_eq!(g.normals.inverted_facets, 0, "{}", r.summary());
    assert!(r.quality.as_ref().unwrap().volume > 0.0);
}

/// A binary ball (u8, default iso 0.5): one sphere, enclosed volume close to the ball's.
#[test]
fn binary_ball_is_one_sphere_of_the_right_volume() {
    let n = 40;
    let radius = 14.0;
    let aff = DAffine3::from_translation(DVec3::splat(-19.5));
    let vol = synthetic::sample_binary(|p| p.length() - radius, [n; 3], aff);
    let s = ImageSurface::new(vol, &ImageOptions::default()).unwrap();
    assert_eq!(s.iso(), 0.5);
    assert_eq!(s.component_count(), 1);
    let (out, r) = mesh_and_verify(&s, &opts(2.0), &s);
    assert_closed_with_all_components(&s, &r);
    assert_eq!(topo(&r).genera(), vec![Some(0)]);
    // Every vertex lies within one voxel of the ideal sphere (staircase of the binary image).
    let worst = out
        .mesh
        .vertices
        .iter()
        .map(|v| (v.length() - radius).abs())
        .fold(0.0, f64::max);
    assert!(worst < 1.0, "vertex {worst} voxel from the sphere");
    let v = r.quality.as_ref().unwrap().volume;
    let exact = 4.0 / 3.0 * std::f64::consts::PI * radius.powi(3);
    eprintln!("binary ball: volume {v:.1} vs {exact:.1}");
    assert!((v / exact - 1.0).abs() < 0.08, "volume {v} vs {exact}");
}

/// Two disjoint blobs: the scan finds both and the mesh has both.
#[test]
fn two_disjoint_blobs_are_both_meshed() {
    let c1 = DVec3::new(-6.0, 0.0, 0.0);
    let c2 = DVec3::new(7.0, 1.0, -1.0);
    let f = move |p: DVec3| ((p - c1).length() - 4.0).min((p - c2).length() - 3.0);
    let aff = DAffine3::from_translation(DVec3::new(-13.0, -7.0, -7.0));
    let vol = synthetic::sample_implicit(f, [28, 16, 16], aff);
    let s = ImageSurface::new(vol, &dark(0.0)).unwrap();
    assert_eq!(s.component_count(), 2);
    let (_, r) = mesh_and_verify(&s, &opts(1.0), &s);
    assert_closed_with_all_components(&s, &r);
    assert_eq!(topo(&r).genera(), vec![Some(0), Some(0)]);
}

/// The catalog torus (R = 1, r = 0.3) sampled on an anisotropic grid (0.03 x 0.045 x 0.06)
/// with an oblique sform: the world-space mesh matches the analytic torus.
#[test]
fn anisotropic_oblique_sform_matches_the_analytic_torus() {
    let torus = oracle::catalog::surface("torus").unwrap();
    let spacing = DVec3::new(0.03, 0.045, 0.06);
    let rot = DQuat::from_axis_angle(DVec3::new(1.0, 2.0, 0.5).normalize(), 0.6);
    let m = DMat3::from_quat(rot) * DMat3::from_diagonal(spacing);
    let dims = [100usize, 67, 50];
    let centre = DVec3::new(
        dims[0] as f64 - 1.0,
        dims[1] as f64 - 1.0,
        dims[2] as f64 - 1.0,
    ) * 0.5;
    let aff = DAffine3::from_mat3_translation(m, -(m * centre));
    let vol = synthetic::sample_implicit(|p| torus.value(p), dims, aff);
    let s = ImageSurface::new(vol, &dark(0.0)).unwrap();
    assert_eq!(s.component_count(), 1);
    let (out, r) = mesh_and_verify(&s, &opts(0.08), &torus);
    assert!(out.stats.criteria_met, "{:?}", out.stats.unmet);
    assert_closed_with_all_components(&s, &r);
    assert_eq!(topo(&r).genera(), vec![Some(1)]);
    let g = geometry(&r);
    eprintln!(
        "oblique torus: Hausdorff {:.4} (largest spacing 0.06)",
        g.hausdorff
    );
    assert!(g.hausdorff < 0.25 * 0.06, "{}", r.summary());
    assert_eq!(g.normals.inverted_facets, 0, "{}", r.summary());
}

/// An affine with a negative determinant (x flipped) does not turn the mesh inside out:
/// positive enclosed volume, close to the ball's, outward normals.
#[test]
fn negative_determinant_affine_keeps_the_mesh_outward() {
    let centre = DVec3::new(5.0, -7.0, 2.0);
    let ball = move |p: DVec3| (p - centre).length() - 6.0;
    let m = DMat3::from_diagonal(DVec3::new(-0.5, 0.5, 0.6));
    let aff = DAffine3::from_mat3_translation(m, centre - m * DVec3::splat(15.5));
    assert!(aff.matrix3.determinant() < 0.0);
    let vol: Volume = synthetic::sample_implicit(ball, [32; 3], aff);
    let s = ImageSurface::new(vol, &dark(0.0)).unwrap();
    let (_, r) = mesh_and_verify(&s, &opts(0.8), &s);
    assert_closed_with_all_components(&s, &r);
    let v = r.quality.as_ref().unwrap().volume;
    let exact = 4.0 / 3.0 * std::f64::consts::PI * 216.0;
    assert!(v > 0.0, "inside out: volume {v}");
    assert!((v / exact - 1.0).abs() < 0.03, "volume {v} vs {exact}");
    assert_eq!(geometry(&r).normals.inverted_facets, 0, "{}", r.summary());
}

/// Number of inside grid nodes (value < 0) 6-connected to the inside end of the grid edge
/// that carries component seed `p` (capped at `cap`): the size of the blob it seeds.
fn blob_nodes(s: &ImageSurface, p: DVec3, cap: usize) -> usize {
    let d = s.volume().dims().map(|x| x as i64);
    let v = s.world_to_voxel().transform_point3(p);
    let f = v.floor();
    let inside = |q: [i64; 3]| {
        q.iter().zip(&d).all(|(&a, &n)| a >= 0 && a < n)
            && s.value_voxel(DVec3::new(q[0] as f64, q[1] as f64, q[2] as f64)) < 0.0
    };
    let Some(start) = (0..8)
        .map(|c| {
            [
                f.x as i64 + (c & 1),
                f.y as i64 + ((c >> 1) & 1),
                f.z as i64 + ((c >> 2) & 1),
            ]
        })
        .find(|&q| inside(q))
    else {
        return 0;
    };
    let mut seen = std::collections::HashSet::from([start]);
    let mut stack = vec![start];
    while let Some(q) = stack.pop() {
        if seen.len() >= cap {
            break;
        }
        for (ax, dir) in [(0, -1), (0, 1), (1, -1), (1, 1), (2, -1), (2, 1)] {
            let mut r = q;
            r[ax] += dir;
            if inside(r) && seen.insert(r) {
                stack.push(r);
            }
        }
    }
    seen.len()
}

/// The real NIfTI fixture (nilearn motor map, 53x63x46 f32, 3 mm voxels, det < 0) at iso 5
/// and 3: closed oriented manifold output, and every component of the voxel scan is meshed
/// (the mesh passes within one voxel of its seed), the small blobs (1 to 13 grid nodes, one or
/// two voxels across) included: the oracle seeds them with a tetrahedron whose circumcentre is
/// inside the blob (`Topology::component_tets`).
#[test]
fn real_nifti_fixture_closed_manifold() {
    let path = fixture("nilearn_motor_10426.nii.gz");
    let t = Instant::now();
    let vol = oracle::image::read_nifti(&path).unwrap();
    let load = t.elapsed().as_secs_f64();
    let voxel = vol.spacing().max_element();
    let vol = std::sync::Arc::new(vol);
    for iso in [5.0, 3.0] {
        let o = ImageOptions {
            iso: Some(iso),
            ..Default::default()
        };
        let s = ImageSurface::new_shared(vol.clone(), &o).unwrap();
        let t = Instant::now();
        let comps = s.component_count();
        let scan = t.elapsed().as_secs_f64();
        let (out, r) = mesh_and_verify(&s, &opts(2.0), &s);
        let bvh = verify::intersect::triangle_bvh(&out.mesh);
        let dist = verify::distance::MeshDistance::new(&out.mesh, &bvh);
        let mut big = 0;
        for p in &s.topology().component_seeds {
            let n = blob_nodes(&s, *p, 27);
            let near = dist.nearest(*p).map_or(f64::INFINITY, |x| x.1);
            big += (n >= 27) as usize;
            assert!(
                near < voxel,
                "iso {iso}: the component of {n} nodes at {p} is not meshed ({near})"
            );
        }
        eprintln!(
            "nilearn motor iso {iso}: load {load:.3} s, scan {scan:.3} s, {} vertices in {:.3} s; mesh has {} of {comps} components ({big} of >= 27 nodes), every one meshed",
            out.stats.vertices,
            out.stats.time_total_s,
            topo(&r).components.len()
        );
        assert!(big >= 2);
        assert!(topo(&r).is_closed_oriented_manifold(), "{}", r.summary());
        // No two components merged into one piece (a neck thinner than sigma can split one).
        assert!(topo(&r).components.len() >= comps);
        assert!(r.quality.as_ref().unwrap().volume > 0.0);
    }
}

/// The noisy phantom at iso 4.5 (414 components), `--size 18` (3 voxels): the scaffold
/// points inserted far outside the seeds' hull make stars of more than 128 boundary
/// vertices, and the next insertion linked its star wrong (`delaunay3::star`'s local ids):
/// a corrupt triangulation and a "neighbor symmetry" panic at the first full scan. Found by
/// a sweep of the fixtures at 0.5, 0.75, 1.5 and 3 voxels. Sizes 17 to 18.5 panicked.
#[test]
fn phantom_at_three_voxels_does_not_corrupt_the_triangulation() {
    use rdt_mesher::pipeline::{Input, InputOptions, Request, SizeRequest, run};
    let opts = InputOptions {
        image: ImageOptions {
            iso: Some(4.5),
            ..Default::default()
        },
        ..Default::default()
    };
    let file = fixture("phantom_i16_32.nii.gz");
    let input = Input::open(file.to_str().unwrap(), &opts).unwrap();
    for size in [17.0, 18.0] {
        let req = Request {
            size: SizeRequest::Size(size),
            ..Default::default()
        };
        let out = run(&input, &req).unwrap();
        let rep = out.report.as_ref().unwrap();
        for c in [
            "closed",
            "edge-manifold",
            "vertex-manifold",
            "oriented",
            "scan-topology",
        ] {
            assert_eq!(
                rep.status(c),
                Some(verify::Status::Pass),
                "size {size}, {c}: {}",
                rep.summary()
            );
        }
    }
}

/// Theorem 4.7's check on a figure known only within its precision: a ball whose values fall
/// linearly with the distance (24^3 voxels of 1 x 2 x 1, iso 500, the default size) has a
/// mesh -> S maximum measured as 0.05, the branch and bound's own tolerance (the sample is
/// on S), against a bound of 0.036; the exact S -> mesh side is 0.013. The check said FAIL
/// (the real-data sweep of 2026-12-07); the true figure may be on either side of the bound,
/// so it is not decided (INFO), and a figure over the bound by more than its precision still
/// FAILs.
#[test]
fn a_hausdorff_figure_within_its_precision_of_the_bound_is_not_a_failure() {
    let affine = DAffine3::from_scale(DVec3::new(1.0, 2.0, 1.0));
    let vol = synthetic::sample_implicit(
        |p| {
            let d = (DVec3::new(p.x, p.y / 2.0, p.z) - DVec3::splat(11.5)).length();
            ((7.0 - d) * 200.0 + 500.0).clamp(0.0, 1000.0).round()
        },
        [24, 24, 24],
        affine,
    );
    let opts = ImageOptions {
        iso: Some(500.0),
        ..Default::default()
    };
    let input = rdt_mesher::pipeline::Input::image(ImageSurface::new(vol, &opts).unwrap(), "ball");
    let out = rdt_mesher::pipeline::run(&input, &Default::default()).unwrap();
    let rep = out.report.as_ref().unwrap();
    let (g, hb) = (
        rep.geometry.as_ref().unwrap(),
        rep.hausdorff_bound.clone().unwrap(),
    );
    let check = rep.check("theorem-4.7").unwrap();
    eprintln!("{:?} {}", check.status, check.detail);
    let least = g
        .surface_to_mesh
        .max
        .max(g.mesh_to_surface.max - g.mesh_to_surface_precision);
    if hb.hausdorff > hb.bound && least <= hb.bound {
        assert!(hb.undecided && check.status == verify::Status::Info);
        assert!(check.detail.contains("not decided"), "{}", check.detail);
    } else {
        assert!(!hb.undecided);
    }
    assert_ne!(check.status, verify::Status::Fail, "{}", check.detail);
}

/// One label of a connectomics-style Voronoi partition (`voronoi_label_border.nii.gz`: a
/// 44 x 84 x 20 crop of a generated 192^3 partition, 8 x 8 x 40 nm voxels, the label as 1,
/// the rest 0; it touches the volume's x = 0 face). At the default size, two seeds of one point
/// of S, (4, 344, 600) nm, found 9e-16 apart by the voxel scan and by a random line, both
/// became vertices; every restricted facet on their edge was a sliver, and the refinement ran
/// away there: 14,785 vertices, 1,638 of them within 1 nm of that point, minimum angle 0.4
/// degrees, `verify: FAIL: short-edges, angles`. Control points closer than the oracle's
/// precision are now one point (`init::control::merge_coincident`).
#[test]
fn seeds_found_twice_at_one_point_do_not_start_a_cluster() {
    use rdt_mesher::pipeline::{Input, InputOptions, Request, run};
    let file = fixture("voronoi_label_border.nii.gz");
    let input = Input::open(file.to_str().unwrap(), &InputOptions::default()).unwrap();
    let out = run(&input, &Request::default()).unwrap();
    let rep = out.report.as_ref().unwrap();
    for c in ["short-edges", "angles", "closed", "scan-topology"] {
        assert_eq!(
            rep.status(c),
            Some(verify::Status::Pass),
            "{c}: {}",
            rep.summary()
        );
    }
    let at = DVec3::new(4.0, 344.0, 600.0);
    let near = out
        .mesh
        .vertices
        .iter()
        .filter(|v| v.distance(at) < 1.0)
        .count();
    assert!(near <= 1, "{near} vertices within 1 nm of {at}");
    // A given initial sample E_0 is inserted as given: the same pair given there still starts
    // a cluster, and the unsound-centre test (`schedule/batch.rs`: a refinement point closer
    // to a sample point than half its ball's radius is not inserted) keeps it finite.
    let req = Request {
        initial_points: vec![at, DVec3::new(3.999999999999999, 344.0, 600.0)],
        ..Default::default()
    };
    let out = run(&input, &req).unwrap();
    assert!(out.stats.stopped_by.is_none(), "{:?}", out.stats.stopped_by);
    assert!(out.stats.unsound_centers > 0);
    assert!(
        out.mesh.vertices.len() < 20_000,
        "{}",
        out.mesh.vertices.len()
    );
}
