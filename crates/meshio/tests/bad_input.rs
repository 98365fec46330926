mod common;
use common::*;
use glam::DVec3;
use meshio::{Format, InvalidMesh, MeshIoError, Options, TriMesh};

fn err_of(path: &std::path::Path) -> (MeshIoError, String) {
    let e = meshio::read(path).unwrap_err();
    let s = e.to_string();
    assert!(
        s.contains(&path.display().to_string()),
        "error names the file: {s}"
    );
    (e, s)
}

#[test]
fn unknown_extension() {
    let p = tmp("mesh.xyz");
    std::fs::write(&p, "1 2 3\n").unwrap();
    let (e, s) = err_of(&p);
    assert!(matches!(e, MeshIoError::UnknownExtension { .. }), "{s}");
    assert!(
        s.contains(".ply"),
        "the message lists the known extensions: {s}"
    );
    for ext in [
        ".ply",
        ".off",
        ".obj",
        ".stl",
        "read_with",
        "write_with",
        "meshio::Format",
    ] {
        assert!(s.contains(ext), "the message names {ext}: {s}");
    }
    assert!(Format::from_path("a/b.Stl").is_ok());
    let e = Format::from_path("dir/noext").unwrap_err().to_string();
    assert!(
        e.starts_with("dir/noext: no file extension;") && e.contains(".stl"),
        "{e}"
    );
}

#[test]
fn not_a_mesh() {
    for (name, content) in [
        ("text.ply", "hello world\n".as_bytes()),
        ("text.off", b"hello world\n"),
        ("text.obj", b"hello world\n"),
        ("bin.stl", &[1u8, 2, 3, 4, 5]),
        ("bin.obj", &[0xff, 0xfe, 0x00, 0x10]),
    ] {
        let p = tmp(name);
        std::fs::write(&p, content).unwrap();
        let (e, s) = err_of(&p);
        assert!(matches!(e, MeshIoError::NotAMesh { .. }), "{name}: {s}");
    }
}

#[test]
fn empty_files() {
    for name in ["empty.ply", "empty.off", "empty.obj", "empty.stl"] {
        let p = tmp(name);
        std::fs::write(&p, "").unwrap();
        let (e, s) = err_of(&p);
        assert!(matches!(e, MeshIoError::Empty { .. }), "{name}: {s}");
    }
    let p = tmp("comments.obj");
    std::fs::write(&p, "# nothing here\n").unwrap();
    assert!(matches!(err_of(&p).0, MeshIoError::Empty { .. }));
}

#[test]
fn truncated_binary_ply_and_stl() {
    let m = octahedron();
    for (ext, format) in [("ply", Format::Ply), ("stl", Format::Stl)] {
        let mut bytes = Vec::new();
        meshio::write_to(&mut bytes, &m, format, Options::default(), "mem").unwrap();
        for cut in [bytes.len() - 1, bytes.len() - 20, bytes.len() / 2 + 3] {
            let p = tmp(&format!("cut{cut}.{ext}"));
            std::fs::write(&p, &bytes[..cut]).unwrap();
            let (e, s) = err_of(&p);
            assert!(
                matches!(e, MeshIoError::Truncated { .. }),
                "{ext} cut at {cut}: {s}"
            );
        }
    }
    let p = tmp("cut.off");
    std::fs::write(&p, "OFF\n4 4 0\n0 0 0\n1 0 0\n").unwrap();
    assert!(matches!(err_of(&p).0, MeshIoError::Truncated { .. }));
}

#[test]
fn face_index_out_of_range_names_face_and_index() {
    let cases = [
        (
            "oor.off",
            "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 2 7\n",
            1,
            7,
        ),
        (
            "oor.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 3\nf 1 2 9\n",
            2,
            9,
        ),
        ("neg.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n", 0, -0),
        (
            "oor.ply",
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n",
            0,
            3,
        ),
    ];
    for (name, text, face, index) in cases {
        let p = tmp(name);
        std::fs::write(&p, text).unwrap();
        let (e, s) = err_of(&p);
        match e {
            MeshIoError::Invalid {
                source:
                    InvalidMesh::IndexOutOfRange {
                        face: f, index: i, ..
                    },
                ..
            } => {
                assert_eq!(f, face, "{s}");
                if name != "neg.obj" {
                    assert_eq!(i, index, "{s}");
                }
                assert!(s.contains(&format!("face {face}")), "{s}");
            }
            _ => panic!("{name}: {s}"),
        }
    }
    // Binary PLY with an index out of range.
    let mut m = octahedron();
    let mut bytes = Vec::new();
    meshio::write_to(&mut bytes, &m, Format::Ply, Options::default(), "mem").unwrap();
    let n = bytes.len();
    bytes[n - 4..].copy_from_slice(&99u32.to_le_bytes());
    let e = meshio::read_from(&bytes[..], Format::Ply, "x.ply").unwrap_err();
    assert!(e.to_string().contains("face 7 uses vertex index 99"), "{e}");
    // Writers refuse it too.
    m.triangles[3][1] = 6;
    let e = meshio::write_with(tmp("w.ply"), &m, Format::Ply, Options::default()).unwrap_err();
    assert!(e.to_string().contains("face 3 uses vertex index 6"), "{e}");
}

#[test]
fn non_finite_coordinates() {
    for (name, text) in [
        ("nan.off", "OFF\n3 1 0\n0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n"),
        ("inf.obj", "v 0 0 0\nv 1 0 0\nv 0 inf 0\nf 1 2 3\n"),
        (
            "nan.stl",
            "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 NaN 0\nendloop\nendfacet\nendsolid\n",
        ),
    ] {
        let p = tmp(name);
        std::fs::write(&p, text).unwrap();
        let (_, s) = err_of(&p);
        assert!(s.contains("non-finite"), "{name}: {s}");
    }
    let m = TriMesh {
        vertices: vec![DVec3::ZERO, DVec3::X, DVec3::NAN],
        triangles: vec![[0, 1, 2]],
    };
    assert!(matches!(
        m.validate(),
        Err(InvalidMesh::NonFinite { vertex: 2, .. })
    ));
    // Binary PLY.
    let mut bytes = Vec::new();
    let ok = TriMesh {
        vertices: vec![DVec3::ZERO, DVec3::X, DVec3::Y],
        triangles: vec![[0, 1, 2]],
    };
    meshio::write_to(&mut bytes, &ok, Format::Ply, Options::default(), "mem").unwrap();
    let n = bytes.len();
    let at = n - 13 - 8; // z of the last vertex
    bytes[at..at + 8].copy_from_slice(&f64::INFINITY.to_le_bytes());
    let p = tmp("inf.ply");
    std::fs::write(&p, &bytes).unwrap();
    let (_, s) = err_of(&p);
    assert!(
        s.contains("vertex 2, property z: inf is not a finite coordinate"),
        "{s}"
    );
}

#[test]
fn short_faces_and_missing_properties() {
    let p = tmp("short.off");
    std::fs::write(&p, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n").unwrap();
    assert!(err_of(&p).1.contains("only 2 vertices"));
    let p = tmp("noz.ply");
    std::fs::write(
        &p,
        "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n0 0\n",
    )
    .unwrap();
    assert!(err_of(&p).1.contains("no scalar property z"));
}
