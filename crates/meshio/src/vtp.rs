//! VTK XML PolyData, `.vtp` (ours: file format support): `Float64` points and `Int64`
//! `connectivity`/`offsets` as `ascii` data arrays (the shortest exact decimal, so a round
//! trip is exact), and each [`CellData`] as a `Float64` array of `<CellData>`.
//!
//! The reader takes `ascii` and inline `binary` (base64, `header_type` UInt32 or UInt64,
//! no compressor) data arrays of any VTK numeric type; appended data and compressed files
//! (ParaView's defaults) are refused with the way to convert them.

use std::io::Write;
use std::path::Path;

use glam::DVec3;

use crate::xml::{self, Array};
use crate::{CellData, FaceBuilder, Format, MeshIoError, TriMesh, fmt_coord};

/// Write ASCII VTK XML polydata with cell data.
pub(crate) fn write<W: Write>(
    w: &mut W,
    mesh: &TriMesh,
    cells: &[CellData],
) -> std::io::Result<()> {
    let (n, m) = (mesh.vertices.len(), mesh.triangles.len());
    writeln!(w, r#"<?xml version="1.0"?>"#)?;
    writeln!(
        w,
        r#"<VTKFile type="PolyData" version="1.0" byte_order="LittleEndian" header_type="UInt64">"#
    )?;
    writeln!(w, "  <PolyData>")?;
    writeln!(
        w,
        r#"    <Piece NumberOfPoints="{n}" NumberOfVerts="0" NumberOfLines="0" NumberOfStrips="0" NumberOfPolys="{m}">"#
    )?;
    writeln!(w, "      <Points>")?;
    writeln!(
        w,
        r#"        <DataArray type="Float64" Name="Points" NumberOfComponents="3" format="ascii">"#
    )?;
    for &v in &mesh.vertices {
        crate::write_point_line(w, "", v, true)?;
    }
    writeln!(w, "        </DataArray>\n      </Points>\n      <Polys>")?;
    writeln!(
        w,
        r#"        <DataArray type="Int64" Name="connectivity" format="ascii">"#
    )?;
    for t in &mesh.triangles {
        writeln!(w, "{} {} {}", t[0], t[1], t[2])?;
    }
    writeln!(w, "        </DataArray>")?;
    writeln!(
        w,
        r#"        <DataArray type="Int64" Name="offsets" format="ascii">"#
    )?;
    for k in 1..=m {
        writeln!(w, "{}", 3 * k)?;
    }
    writeln!(w, "        </DataArray>\n      </Polys>")?;
    if !cells.is_empty() {
        writeln!(w, r#"      <CellData Scalars="{}">"#, cells[0].name)?;
        for c in cells {
            writeln!(
                w,
                r#"        <DataArray type="Float64" Name="{}" format="ascii">"#,
                c.name
            )?;
            for &v in &c.values {
                writeln!(w, "{}", fmt_coord(v, true))?;
            }
            writeln!(w, "        </DataArray>")?;
        }
        writeln!(w, "      </CellData>")?;
    }
    writeln!(w, "    </Piece>\n  </PolyData>\n</VTKFile>")
}

fn bad(path: &Path, reason: impl Into<String>) -> MeshIoError {
    MeshIoError::not_a_mesh(path, Format::Vtp, reason)
}

/// Read VTK XML polydata (see the module documentation).
pub(crate) fn read(bytes: &[u8], path: &Path) -> Result<TriMesh, MeshIoError> {
    let text = xml::text(bytes, path, Format::Vtp)?;
    let doc = xml::parse(text, path, Format::Vtp)?;
    let root = doc.root_element();
    if root.tag_name().name() != "VTKFile" || root.attribute("type") != Some("PolyData") {
        return Err(bad(
            path,
            "the root element is not <VTKFile type=\"PolyData\"> (a .vtu grid is not read)",
        ));
    }
    if root.attribute("compressor").is_some() {
        return Err(bad(
            path,
            "the data is compressed; write it uncompressed (ParaView: Data Mode ascii, no \
             compressor)",
        ));
    }
    let big = root.attribute("byte_order") == Some("BigEndian");
    let header64 = root.attribute("header_type") == Some("UInt64");
    let pieces: Vec<_> = root
        .descendants()
        .filter(|n| n.has_tag_name("Piece"))
        .collect();
    if pieces.len() != 1 {
        return Err(bad(
            path,
            format!("{} <Piece> elements; exactly one is read", pieces.len()),
        ));
    }
    let piece = pieces[0];
    let count = |attr: &str| -> Result<usize, MeshIoError> {
        match piece.attribute(attr) {
            None => Ok(0),
            Some(s) => s
                .trim()
                .parse()
                .map_err(|_| bad(path, format!("<Piece {attr}=\"{s}\">: not a whole number"))),
        }
    };
    let (n, m) = (count("NumberOfPoints")?, count("NumberOfPolys")?);
    for other in ["NumberOfVerts", "NumberOfLines", "NumberOfStrips"] {
        if count(other)? != 0 {
            return Err(bad(
                path,
                format!("{other} is not 0; only polygons are read"),
            ));
        }
    }
    let array = |parent: &str, name: Option<&str>| -> Result<Array, MeshIoError> {
        let node = piece
            .children()
            .find(|c| c.has_tag_name(parent))
            .and_then(|p| {
                p.children()
                    .filter(|c| c.has_tag_name("DataArray"))
                    .find(|c| name.is_none_or(|nm| c.attribute("Name") == Some(nm)))
            })
            .ok_or_else(|| {
                bad(
                    path,
                    format!(
                        "<{parent}> has no DataArray{}",
                        name.map(|s| format!(" named {s}")).unwrap_or_default()
                    ),
                )
            })?;
        xml::vtk_array(node, path, Format::Vtp, big, header64)
    };
    let pts = array("Points", None)?;
    if pts.values.len() != 3 * n {
        return Err(MeshIoError::Truncated {
            path: path.to_owned(),
            detail: format!(
                "NumberOfPoints is {n} but <Points> holds {} numbers",
                pts.values.len()
            ),
        });
    }
    let vertices = pts
        .values
        .chunks_exact(3)
        .map(|c| DVec3::new(c[0], c[1], c[2]))
        .collect::<Vec<_>>();
    let conn = array("Polys", Some("connectivity"))?.integers(path, Format::Vtp)?;
    let offsets = array("Polys", Some("offsets"))?.integers(path, Format::Vtp)?;
    if offsets.len() != m {
        return Err(bad(
            path,
            format!(
                "NumberOfPolys is {m} but there are {} offsets",
                offsets.len()
            ),
        ));
    }
    let mut faces = FaceBuilder::default();
    let mut start = 0i64;
    for &end in &offsets {
        if end < start || end as u64 > conn.len() as u64 {
            return Err(bad(
                path,
                "the offsets are not increasing within the connectivity",
            ));
        }
        faces
            .push_polygon(&conn[start as usize..end as usize], vertices.len())
            .map_err(|source| MeshIoError::Invalid {
                path: path.to_owned(),
                source,
            })?;
        start = end;
    }
    Ok(TriMesh {
        vertices,
        triangles: faces.triangles,
    })
}
