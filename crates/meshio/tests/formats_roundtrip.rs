//! glTF binary, VTK legacy, VTK XML and GIFTI: round trips, cell data, other writers'
//! variants, and every truncation of a written file giving an error (never a panic).
mod common;
use common::*;
use meshio::{CellData, Format, MeshIoError, Options, TriMesh};
use std::io::Write;

const NEW: [(Format, &str, bool); 4] = [
    // format, extension, exact (f64) coordinates
    (Format::Glb, "glb", false),
    (Format::Vtk, "vtk", true),
    (Format::Vtp, "vtp", true),
    (Format::Gii, "gii", false),
];

fn bytes_of(mesh: &TriMesh, format: Format, cells: &[CellData]) -> Vec<u8> {
    let mut b = Vec::new();
    meshio::write_to_with(&mut b, mesh, format, Options::default(), cells, "mem").unwrap();
    b
}

#[test]
fn new_formats_roundtrip_through_files() {
    let m = octahedron();
    for (format, ext, exact) in NEW {
        let p = tmp(&format!("octa.{ext}"));
        meshio::write(&p, &m).unwrap();
        assert_eq!(Format::from_path(&p).unwrap(), format);
        let back = meshio::read(&p).unwrap();
        assert_eq!(back.triangles, m.triangles, "{format}");
        for (a, b) in m.vertices.iter().zip(&back.vertices) {
            if exact {
                assert_eq!(a, b, "{format}");
            } else {
                assert_eq!(*b, a.as_vec3().as_dvec3(), "{format}: f32 rounding");
            }
        }
        assert_eq!(back.vertices.len(), m.vertices.len());
    }
}

#[test]
fn cell_data_is_written_for_vtk_and_checked() {
    let m = octahedron();
    let q: Vec<f64> = (0..m.triangles.len())
        .map(|i| 30.0 + i as f64 / 3.0)
        .collect();
    let cells = [CellData {
        name: "min_angle_deg".into(),
        values: q.clone(),
    }];
    for format in [Format::Vtk, Format::Vtp] {
        let text = String::from_utf8(bytes_of(&m, format, &cells)).unwrap();
        let key = if format == Format::Vtk {
            "SCALARS min_angle_deg"
        } else {
            "Name=\"min_angle_deg\""
        };
        let at = text.find(key).expect("the array is named");
        let after = &text[at..];
        let body = after.split_once('\n').unwrap().1;
        let body = if format == Format::Vtk {
            body.split_once('\n').unwrap().1 // LOOKUP_TABLE default
        } else {
            body
        };
        let got: Vec<f64> = body
            .split_whitespace()
            .take(q.len())
            .map(|t| t.parse().unwrap())
            .collect();
        assert_eq!(got, q, "{format}: the values in order, exactly");
        assert_eq!(
            meshio::read_from(text.as_bytes(), format, "mem").unwrap(),
            m
        );
    }
    // One value per facet and a one-word name, or an error naming the array.
    for bad in [
        CellData {
            name: "min angle".into(),
            values: q.clone(),
        },
        CellData {
            name: "r_over_sigma".into(),
            values: q[1..].to_vec(),
        },
    ] {
        let mut b = Vec::new();
        let e = meshio::write_to_with(&mut b, &m, Format::Vtk, Options::default(), &[bad], "x.vtk")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("x.vtk: cell data"), "{e}");
    }
}

#[test]
fn f32_formats_refuse_coordinates_beyond_f32() {
    let mut m = octahedron();
    m.vertices[2].y = 1e300;
    for format in [Format::Glb, Format::Gii] {
        let mut b = Vec::new();
        let e = meshio::write_to(&mut b, &m, format, Options::default(), "big.glb")
            .unwrap_err()
            .to_string();
        assert!(e.contains("vertex 2") && e.contains(".ply"), "{e}");
    }
    // The double formats keep it.
    let back = meshio::read_from(&bytes_of(&m, Format::Vtp, &[])[..], Format::Vtp, "m").unwrap();
    assert_eq!(back, m);
}

#[test]
fn every_truncation_is_an_error_not_a_panic() {
    let m = octahedron();
    for (format, _, _) in NEW {
        let full = bytes_of(&m, format, &[]);
        for cut in (0..full.len()).step_by(7) {
            let r = meshio::read_from(&full[..cut], format, "cut");
            match r {
                Err(e) => {
                    let s = e.to_string();
                    assert!(s.starts_with("cut: "), "{format} at {cut}: {s}");
                    assert!(!s.contains('\n'), "one line: {s}");
                }
                // A text format cut after the last face but before its closing lines still
                // parses only if nothing was lost.
                Ok(back) => assert_eq!(back.triangles, m.triangles, "{format} at {cut}"),
            }
        }
    }
}

#[test]
fn truncated_glb_says_truncated() {
    let full = bytes_of(&octahedron(), Format::Glb, &[]);
    let e = meshio::read_from(&full[..full.len() - 10], Format::Glb, "t.glb").unwrap_err();
    assert!(matches!(e, MeshIoError::Truncated { .. }), "{e}");
    let e = meshio::read_from(&b"glTF\x01\0\0\0"[..], Format::Glb, "t.glb").unwrap_err();
    assert!(e.to_string().contains("t.glb"), "{e}");
}

/// meshio (the Python package) writes unstructured grids; the 5.x layout has offsets.
#[test]
fn vtk_unstructured_grids_and_the_5x_layout() {
    let classic = "# vtk DataFile Version 4.2\nmeshio\nASCII\nDATASET UNSTRUCTURED_GRID\n\
                   POINTS 4 double\n0 0 0 1 0 0 0 1 0 0 0 1\nCELLS 2 8\n3 0 2 1\n3 0 1 3\n\
                   CELL_TYPES 2\n5\n5\n";
    let new = "# vtk DataFile Version 5.1\nmeshio\nASCII\nDATASET UNSTRUCTURED_GRID\n\
               POINTS 4 double\n0 0 0 1 0 0 0 1 0 0 0 1\nCELLS 3 6\nOFFSETS vtktypeint64\n\
               0 3 6\nCONNECTIVITY vtktypeint64\n0 2 1 0 1 3\nCELL_TYPES 2\n5\n5\n";
    for text in [classic, new] {
        let m = meshio::read_from(text.as_bytes(), Format::Vtk, "u.vtk").unwrap();
        assert_eq!(m.triangles, vec![[0, 2, 1], [0, 1, 3]]);
        assert_eq!(m.vertices.len(), 4);
    }
    let tets = classic.replace(
        "CELLS 2 8\n3 0 2 1\n3 0 1 3\nCELL_TYPES 2\n5\n5",
        "CELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n10",
    );
    let e = meshio::read_from(tets.as_bytes(), Format::Vtk, "u.vtk")
        .unwrap_err()
        .to_string();
    assert!(e.contains("cell type 10") && e.contains("triangles"), "{e}");
    let bin = classic.replace("ASCII", "BINARY");
    let e = meshio::read_from(bin.as_bytes(), Format::Vtk, "b.vtk")
        .unwrap_err()
        .to_string();
    assert!(e.contains("binary=False"), "{e}");
}

/// nibabel writes GZipBase64Binary (zlib) by default, and column-major arrays exist.
#[test]
fn gifti_compressed_and_column_major() {
    let pts: [f32; 12] = [0., 0., 0., 1., 0., 0., 0., 1., 0., 0., 0., 1.];
    let raw: Vec<u8> = pts.iter().flat_map(|v| v.to_le_bytes()).collect();
    let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
    z.write_all(&raw).unwrap();
    let zb = z.finish().unwrap();
    let b64 = |b: &[u8]| {
        // A tiny encoder, independent of the crate's.
        const T: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
        let mut s = String::new();
        for c in b.chunks(3) {
            let n = c
                .iter()
                .enumerate()
                .fold(0u32, |a, (i, &x)| a | (x as u32) << (16 - 8 * i));
            for k in 0..4 {
                s.push(if k <= c.len() {
                    T[(n >> (18 - 6 * k) & 63) as usize] as char
                } else {
                    '='
                });
            }
        }
        s
    };
    let doc = format!(
        r#"<?xml version="1.0" encoding="UTF-8"?>
<!DOCTYPE GIFTI SYSTEM "gifti.dtd">
<GIFTI Version="1.0" NumberOfDataArrays="2">
<DataArray Intent="NIFTI_INTENT_POINTSET" DataType="NIFTI_TYPE_FLOAT32" ArrayIndexingOrder="RowMajorOrder" Dimensionality="2" Dim0="4" Dim1="3" Encoding="GZipBase64Binary" Endian="LittleEndian" ExternalFileName="" ExternalFileOffset="">
<Data>{}</Data></DataArray>
<DataArray Intent="NIFTI_INTENT_TRIANGLE" DataType="NIFTI_TYPE_INT32" ArrayIndexingOrder="ColumnMajorOrder" Dimensionality="2" Dim0="2" Dim1="3" Encoding="ASCII" Endian="LittleEndian" ExternalFileName="" ExternalFileOffset="">
<Data>0 0 2 1 1 3</Data></DataArray>
</GIFTI>"#,
        b64(&zb)
    );
    let m = meshio::read_from(doc.as_bytes(), Format::Gii, "n.gii").unwrap();
    assert_eq!(m.triangles, vec![[0, 2, 1], [0, 1, 3]]);
    assert_eq!(m.vertices[3], glam::DVec3::Z);
    let e = meshio::read_from(
        doc.replace("Dim0=\"4\"", "Dim0=\"5\"").as_bytes(),
        Format::Gii,
        "n.gii",
    )
    .unwrap_err();
    assert!(matches!(e, MeshIoError::Truncated { .. }), "{e}");
}
