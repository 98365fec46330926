//! GIFTI surfaces, `.gii` (ours: file format support): two data arrays,
//! `NIFTI_INTENT_POINTSET` (`NIFTI_TYPE_FLOAT32`, n x 3) and `NIFTI_INTENT_TRIANGLE`
//! (`NIFTI_TYPE_INT32`, m x 3), row-major, little-endian `Base64Binary`. The coordinates
//! are the mesh's world coordinates, which for an image input are the image's world
//! millimetres (the NIfTI convention, RAS+), so the point set's `DataSpace` and
//! `TransformedSpace` are `NIFTI_XFORM_SCANNER_ANAT` with the identity matrix. GIFTI stores
//! f32, so coordinates are rounded to f32.
//!
//! The reader takes `ASCII`, `Base64Binary` and `GZipBase64Binary` (zlib) data of any
//! NIfTI numeric type, either byte order and either indexing order; the coordinates are
//! returned as stored (in the array's `DataSpace`, as nibabel's `darrays[i].data`). Data in
//! an external file is refused.

use std::io::{Read, Write};
use std::path::Path;

use glam::DVec3;

use crate::xml::{self, Num};
use crate::{FaceBuilder, Format, MeshIoError, TriMesh};

/// Write `mesh` as GIFTI (coordinates finite as f32: checked by the caller).
pub(crate) fn write<W: Write>(w: &mut W, mesh: &TriMesh) -> std::io::Result<()> {
    let mut pts = Vec::with_capacity(12 * mesh.vertices.len());
    for v in &mesh.vertices {
        for c in v.to_array() {
            pts.extend_from_slice(&(c as f32).to_le_bytes());
        }
    }
    let mut tris = Vec::with_capacity(12 * mesh.triangles.len());
    for t in &mesh.triangles {
        for &i in t {
            // Indices are < vertices.len() <= i32::MAX (checked by the caller).
            tris.extend_from_slice(&(i as i32).to_le_bytes());
        }
    }
    writeln!(w, r#"<?xml version="1.0" encoding="UTF-8"?>"#)?;
    writeln!(w, r#"<GIFTI Version="1.0" NumberOfDataArrays="2">"#)?;
    writeln!(w, "<MetaData/>\n<LabelTable/>")?;
    let array = |w: &mut W, intent: &str, ty: &str, n: usize, data: &[u8], xform: bool| {
        writeln!(
            w,
            r#"<DataArray Intent="{intent}" DataType="{ty}" ArrayIndexingOrder="RowMajorOrder" Dimensionality="2" Dim0="{n}" Dim1="3" Encoding="Base64Binary" Endian="LittleEndian" ExternalFileName="" ExternalFileOffset="">"#
        )?;
        writeln!(w, "<MetaData/>")?;
        if xform {
            writeln!(w, "<CoordinateSystemTransformMatrix>")?;
            writeln!(w, "<DataSpace>NIFTI_XFORM_SCANNER_ANAT</DataSpace>")?;
            writeln!(
                w,
                "<TransformedSpace>NIFTI_XFORM_SCANNER_ANAT</TransformedSpace>"
            )?;
            writeln!(
                w,
                "<MatrixData>\n1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n</MatrixData>"
            )?;
            writeln!(w, "</CoordinateSystemTransformMatrix>")?;
        }
        writeln!(w, "<Data>{}</Data>", xml::base64_encode(data))?;
        writeln!(w, "</DataArray>")
    };
    let n = mesh.vertices.len();
    array(
        w,
        "NIFTI_INTENT_POINTSET",
        "NIFTI_TYPE_FLOAT32",
        n,
        &pts,
        true,
    )?;
    let m = mesh.triangles.len();
    array(
        w,
        "NIFTI_INTENT_TRIANGLE",
        "NIFTI_TYPE_INT32",
        m,
        &tris,
        false,
    )?;
    writeln!(w, "</GIFTI>")
}

fn bad(path: &Path, reason: impl Into<String>) -> MeshIoError {
    MeshIoError::not_a_mesh(path, Format::Gii, reason)
}

fn nifti_type(s: &str) -> Option<Num> {
    Some(match s {
        "NIFTI_TYPE_FLOAT32" => Num::F32,
        "NIFTI_TYPE_FLOAT64" => Num::F64,
        "NIFTI_TYPE_INT8" => Num::I8,
        "NIFTI_TYPE_UINT8" => Num::U8,
        "NIFTI_TYPE_INT16" => Num::I16,
        "NIFTI_TYPE_UINT16" => Num::U16,
        "NIFTI_TYPE_INT32" => Num::I32,
        "NIFTI_TYPE_UINT32" => Num::U32,
        "NIFTI_TYPE_INT64" => Num::I64,
        "NIFTI_TYPE_UINT64" => Num::U64,
        _ => return None,
    })
}

/// The `n x 3` values of one `<DataArray>`, row-major.
fn data_array(node: roxmltree::Node, path: &Path, what: &str) -> Result<Vec<f64>, MeshIoError> {
    let attr = |a: &str| node.attribute(a).unwrap_or("");
    let dim = |a: &str| attr(a).trim().parse::<usize>().ok();
    let (Some(n), Some(3)) = (dim("Dim0"), dim("Dim1")) else {
        return Err(bad(
            path,
            format!(
                "the {what} array has Dim0=\"{}\" Dim1=\"{}\"; a surface array is n x 3",
                attr("Dim0"),
                attr("Dim1")
            ),
        ));
    };
    if !attr("ExternalFileName").is_empty() {
        return Err(bad(
            path,
            format!("the {what} array is in an external file; save the GIFTI with inline data"),
        ));
    }
    let num = nifti_type(attr("DataType")).ok_or_else(|| {
        bad(
            path,
            format!("the {what} array has DataType {:?}", attr("DataType")),
        )
    })?;
    let body = node
        .children()
        .find(|c| c.has_tag_name("Data"))
        .and_then(|d| d.text())
        .unwrap_or("");
    let big = attr("Endian") == "BigEndian";
    let values = match attr("Encoding") {
        "ASCII" => xml::ascii_numbers(body, path, Format::Gii, what)?,
        enc @ ("Base64Binary" | "GZipBase64Binary") => {
            let mut b = xml::base64(body)
                .ok_or_else(|| bad(path, format!("the {what} array is not valid base64")))?;
            if enc == "GZipBase64Binary" {
                let mut out = Vec::new();
                flate2::read::ZlibDecoder::new(&b[..])
                    .read_to_end(&mut out)
                    .map_err(|e| {
                        bad(
                            path,
                            format!("the {what} array's zlib data is corrupt ({e})"),
                        )
                    })?;
                b = out;
            }
            if b.len() != 3 * n * num.size() {
                return Err(MeshIoError::Truncated {
                    path: path.to_owned(),
                    detail: format!(
                        "the {what} array has {} bytes, Dim0 = {n} needs {}",
                        b.len(),
                        3 * n * num.size()
                    ),
                });
            }
            num.decode(&b, big)
        }
        other => {
            return Err(bad(
                path,
                format!("the {what} array has Encoding {other:?}"),
            ));
        }
    };
    if values.len() != 3 * n {
        return Err(MeshIoError::Truncated {
            path: path.to_owned(),
            detail: format!(
                "the {what} array has {} values, Dim0 = {n} needs {}",
                values.len(),
                3 * n
            ),
        });
    }
    if attr("ArrayIndexingOrder") == "ColumnMajorOrder" {
        return Ok((0..3 * n).map(|k| values[(k % 3) * n + k / 3]).collect());
    }
    Ok(values)
}

/// Read a GIFTI surface (see the module documentation).
pub(crate) fn read(bytes: &[u8], path: &Path) -> Result<TriMesh, MeshIoError> {
    let text = xml::text(bytes, path, Format::Gii)?;
    let doc = xml::parse(text, path, Format::Gii)?;
    if !doc.root_element().has_tag_name("GIFTI") {
        return Err(bad(path, "the root element is not <GIFTI>"));
    }
    let find = |intent: &str| {
        doc.root_element()
            .children()
            .find(|c| c.has_tag_name("DataArray") && c.attribute("Intent") == Some(intent))
    };
    let pts = find("NIFTI_INTENT_POINTSET").ok_or_else(|| {
        bad(
            path,
            "no NIFTI_INTENT_POINTSET data array (not a surface file)",
        )
    })?;
    let vertices: Vec<DVec3> = data_array(pts, path, "NIFTI_INTENT_POINTSET")?
        .chunks_exact(3)
        .map(|c| DVec3::new(c[0], c[1], c[2]))
        .collect();
    let tri = find("NIFTI_INTENT_TRIANGLE").ok_or(MeshIoError::NoFaces {
        path: path.to_owned(),
    })?;
    let idx = xml::Array {
        values: data_array(tri, path, "NIFTI_INTENT_TRIANGLE")?,
    }
    .integers(path, Format::Gii)?;
    let mut faces = FaceBuilder::default();
    for t in idx.chunks_exact(3) {
        faces
            .push_polygon(t, vertices.len())
            .map_err(|source| MeshIoError::Invalid {
                path: path.to_owned(),
                source,
            })?;
    }
    Ok(TriMesh {
        vertices,
        triangles: faces.triangles,
    })
}
