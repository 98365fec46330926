mod common;
use common::*;
use glam::DVec3;
use meshio::{Format, Options, TriMesh};
use proptest::prelude::*;

const ALL: [(Format, &str, bool, bool); 8] = [
    // format, extension, binary, double
    (Format::Ply, "ply", true, true),
    (Format::Ply, "ply", false, true),
    (Format::Ply, "ply", true, false),
    (Format::Ply, "ply", false, false),
    (Format::Off, "off", false, true),
    (Format::Obj, "obj", false, true),
    (Format::Stl, "stl", true, true),
    (Format::Stl, "stl", false, true),
];

fn roundtrip(mesh: &TriMesh, format: Format, binary: bool, double: bool) -> TriMesh {
    let mut bytes = Vec::new();
    meshio::write_to(&mut bytes, mesh, format, Options { binary, double }, "mem").unwrap();
    meshio::read_from(&bytes[..], format, "mem").unwrap()
}

/// Exact formats keep indices and coordinates bit for bit; f32 formats keep them to f32
/// rounding; STL keeps the triangle soup (vertices renumbered by first appearance).
fn check_roundtrip(mesh: &TriMesh, format: Format, binary: bool, double: bool) {
    let back = roundtrip(mesh, format, binary, double);
    let exact = double && !(format == Format::Stl && binary);
    if format == Format::Stl {
        let (a, b) = (soup(mesh), soup(&back));
        assert_eq!(a.len(), b.len());
        for (ta, tb) in a.iter().zip(&b) {
            for k in 0..3 {
                if exact {
                    assert_eq!(ta[k], tb[k], "{format} binary={binary}");
                } else {
                    assert!(close_f32(ta[k], tb[k]), "{:?} vs {:?}", ta[k], tb[k]);
                }
            }
        }
    } else if exact {
        assert_eq!(&back, mesh, "{format} binary={binary}");
    } else {
        assert_eq!(back.triangles, mesh.triangles);
        for (a, b) in mesh.vertices.iter().zip(&back.vertices) {
            assert!(close_f32(*a, *b), "{a:?} vs {b:?}");
            assert_eq!(
                *b,
                a.as_vec3().as_dvec3(),
                "f32 rounding is round-to-nearest"
            );
        }
    }
}

#[test]
fn every_format_roundtrips_the_octahedron() {
    let m = octahedron();
    for (format, _, binary, double) in ALL {
        check_roundtrip(&m, format, binary, double);
    }
}

#[test]
fn files_roundtrip_with_extension_dispatch() {
    let m = octahedron();
    for (format, ext, binary, double) in ALL {
        let p = tmp(&format!("oct-{binary}-{double}.{ext}"));
        meshio::write_with(&p, &m, format, Options { binary, double }).unwrap();
        assert_eq!(Format::from_path(&p).unwrap(), format);
        let back = meshio::read(&p).unwrap();
        assert_eq!(back.triangles.len(), 8);
        if double && format != Format::Stl {
            assert_eq!(back, m);
        }
    }
    let p = tmp("default.PLY");
    meshio::write(&p, &m).unwrap();
    assert_eq!(meshio::read(&p).unwrap(), m, "default options are exact");
}

#[test]
fn binary_ply_is_compact_and_exact() {
    let m = octahedron();
    let mut bytes = Vec::new();
    meshio::write_to(&mut bytes, &m, Format::Ply, Options::default(), "mem").unwrap();
    let header_end = bytes
        .windows(11)
        .position(|w| w == b"end_header\n")
        .unwrap()
        + 11;
    assert_eq!(bytes.len() - header_end, 6 * 24 + 8 * 13);
    assert_eq!(
        meshio::read_from(&bytes[..], Format::Ply, "mem").unwrap(),
        m
    );
}

#[test]
fn big_endian_and_other_index_types_are_read() {
    // Binary big-endian, double coordinates, ushort count + short indices, a quad, an extra
    // per-vertex property and an extra element.
    let mut b = b"ply\nformat binary_big_endian 1.0\nelement vertex 4\nproperty double x\n\
property float y\nproperty double z\nproperty uchar red\nelement face 1\n\
property list ushort short vertex_index\nelement edge 1\nproperty int vertex1\n\
property int vertex2\nend_header\n"
        .to_vec();
    let pts: [[f64; 3]; 4] = [
        [0.0, 0.0, 0.5],
        [1.0, 0.0, 0.5],
        [1.0, 1.0, 0.5],
        [0.0, 1.0, 0.5],
    ];
    for p in pts {
        b.extend_from_slice(&p[0].to_be_bytes());
        b.extend_from_slice(&(p[1] as f32).to_be_bytes());
        b.extend_from_slice(&p[2].to_be_bytes());
        b.push(255);
    }
    b.extend_from_slice(&4u16.to_be_bytes());
    for i in [0i16, 1, 2, 3] {
        b.extend_from_slice(&i.to_be_bytes());
    }
    b.extend_from_slice(&0i32.to_be_bytes());
    b.extend_from_slice(&1i32.to_be_bytes());
    let m = meshio::read_from(&b[..], Format::Ply, "be.ply").unwrap();
    assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3]]);
    assert_eq!(m.vertices[2], DVec3::new(1.0, 1.0, 0.5));
}

#[test]
fn point_cloud_with_normals() {
    let p = tmp("cloud.ply");
    std::fs::write(
        &p,
        "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n\
property float z\nproperty float nx\nproperty float ny\nproperty float nz\nend_header\n\
1 2 3 0 0 1\n4 5 6 1 0 0\n",
    )
    .unwrap();
    let c = meshio::read_point_cloud(&p).unwrap();
    assert_eq!(
        c.points,
        vec![DVec3::new(1.0, 2.0, 3.0), DVec3::new(4.0, 5.0, 6.0)]
    );
    assert_eq!(c.normals, Some(vec![DVec3::Z, DVec3::X]));
    // Reading it as a mesh says what to do instead.
    let e = meshio::read(&p).unwrap_err().to_string();
    assert!(e.contains("--as points"), "{e}");
    // A mesh file is also a point cloud, without normals.
    let c = meshio::read_point_cloud(fixture("tetrahedron.ply")).unwrap();
    assert_eq!(c.points.len(), 4);
    assert_eq!(c.normals, None);
}

#[test]
fn fixtures_read_the_same_in_every_format() {
    let cube_off = meshio::read(fixture("cube.off")).unwrap();
    let cube_obj = meshio::read(fixture("cube_quads.obj")).unwrap();
    assert_eq!(cube_off.vertices, cube_obj.vertices);
    assert_eq!(cube_off.triangles.len(), 12);
    assert_eq!(cube_obj.triangles.len(), 12);
    // Same signed volume (orientation kept by fan triangulation and negative indices).
    let vol = |m: &TriMesh| -> f64 {
        soup(m)
            .iter()
            .map(|[a, b, c]| a.dot(b.cross(*c)))
            .sum::<f64>()
            / 6.0
    };
    assert_eq!(vol(&cube_off), 1.0);
    assert_eq!(vol(&cube_obj), 1.0);
    let tet_ply = meshio::read(fixture("tetrahedron.ply")).unwrap();
    let tet_stl = meshio::read(fixture("tetrahedron.stl")).unwrap();
    assert_eq!(soup(&tet_ply), soup(&tet_stl));
    assert_eq!(
        tet_stl.vertices.len(),
        4,
        "STL corners merged by exact equality"
    );
    assert_eq!(vol(&tet_ply), 1.0 / 6.0);
}

fn arb_mesh() -> impl Strategy<Value = TriMesh> {
    (1usize..40).prop_flat_map(|nv| {
        let v = prop::collection::vec(
            prop::array::uniform3(prop_oneof![
                -1e6f64..1e6,
                -1.0f64..1.0,
                Just(0.0),
                Just(-0.0),
                (-1e-300f64..1e-300)
            ]),
            nv,
        );
        let t = prop::collection::vec(prop::array::uniform3(0u32..nv as u32), 1..60);
        (v, t).prop_map(|(v, t)| TriMesh {
            vertices: v.into_iter().map(DVec3::from_array).collect(),
            triangles: t,
        })
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    #[test]
    fn random_meshes_roundtrip(m in arb_mesh()) {
        for (format, _, binary, double) in ALL {
            if format == Format::Stl || !double {
                continue; // tested on the octahedron; STL merges equal corners
            }
            let back = roundtrip(&m, format, binary, double);
            // -0.0 == 0.0 for DVec3 equality; compare bits to be strict.
            prop_assert_eq!(back.triangles.clone(), m.triangles.clone());
            for (a, b) in m.vertices.iter().zip(&back.vertices) {
                prop_assert_eq!(a.to_array().map(f64::to_bits), b.to_array().map(f64::to_bits));
            }
        }
    }

    #[test]
    fn random_meshes_roundtrip_stl_as_soup(m in arb_mesh()) {
        let back = roundtrip(&m, Format::Stl, false, true);
        prop_assert_eq!(soup(&back), soup(&m));
        let back = roundtrip(&m, Format::Stl, true, true);
        for (ta, tb) in soup(&m).iter().zip(&soup(&back)) {
            for k in 0..3 {
                prop_assert_eq!(tb[k], ta[k].as_vec3().as_dvec3());
            }
        }
    }
}
