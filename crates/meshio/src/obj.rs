//! Wavefront OBJ: `v x y z [w]` and `f` lines (`i`, `i/t`, `i//n`, `i/t/n`, negative indices
//! relative to the vertices read so far). Everything else is ignored. Polygons are
//! fan-triangulated.

use std::io::{BufRead, Write};
use std::path::Path;

use glam::DVec3;

use crate::{FaceBuilder, Format, InvalidMesh, MeshIoError, Options, TriMesh};

pub(crate) fn read<R: BufRead>(reader: &mut R, path: &Path) -> Result<TriMesh, MeshIoError> {
    let bad = |line: usize, what: String| {
        MeshIoError::not_a_mesh(path, Format::Obj, format!("line {line}: {what}"))
    };
    let mut vertices = Vec::new();
    // Faces are checked at the end: OBJ allows faces to refer to vertices defined later.
    let mut polygons: Vec<Vec<i64>> = Vec::new();
    let mut buf = String::new();
    let mut line_no = 0;
    let mut saw_statement = false;
    loop {
        buf.clear();
        let n = reader.read_line(&mut buf).map_err(|e| {
            if e.kind() == std::io::ErrorKind::InvalidData {
                MeshIoError::not_a_mesh(path, Format::Obj, "the file is not UTF-8 text")
            } else {
                MeshIoError::io(path, e)
            }
        })?;
        if n == 0 {
            break;
        }
        line_no += 1;
        let s = buf.split('#').next().unwrap_or("").trim();
        let mut it = s.split_whitespace();
        match it.next() {
            Some("v") => {
                let c: Vec<f64> = it.take(3).filter_map(crate::parse_f64).collect();
                if c.len() < 3 {
                    return Err(bad(line_no, format!("expected 'v x y z', found {s:?}")));
                }
                vertices.push(DVec3::new(c[0], c[1], c[2]));
                saw_statement = true;
            }
            Some("f") => {
                let mut poly = Vec::new();
                for tok in it {
                    let first = tok.split('/').next().unwrap_or("");
                    let i: i64 = first.parse().map_err(|_| {
                        bad(
                            line_no,
                            format!("bad face vertex {tok:?} (expected i, i/t, i//n or i/t/n)"),
                        )
                    })?;
                    let idx = match i {
                        0 => {
                            return Err(bad(
                                line_no,
                                "face index 0 (OBJ indices start at 1)".into(),
                            ));
                        }
                        i if i > 0 => i - 1,
                        i => vertices.len() as i64 + i,
                    };
                    poly.push(idx);
                }
                polygons.push(poly);
                saw_statement = true;
            }
            Some(kw) => {
                const KNOWN: [&str; 14] = [
                    "vt", "vn", "vp", "g", "o", "s", "usemtl", "mtllib", "l", "p", "mg", "cstype",
                    "deg", "curv",
                ];
                if !KNOWN.contains(&kw) && !saw_statement {
                    return Err(bad(line_no, format!("unknown OBJ statement {kw:?}")));
                }
            }
            None => {}
        }
    }
    crate::check_vertex_coords(path, &vertices)?;
    let mut fb = FaceBuilder::default();
    for p in &polygons {
        fb.push_polygon(p, vertices.len()).map_err(|source| {
            // Report OBJ's own 1-based index in the message.
            let source = match source {
                InvalidMesh::IndexOutOfRange {
                    face,
                    index,
                    num_vertices,
                } => InvalidMesh::IndexOutOfRange {
                    face,
                    index: index + 1,
                    num_vertices,
                },
                s => s,
            };
            MeshIoError::Invalid {
                path: path.to_owned(),
                source,
            }
        })?;
    }
    Ok(TriMesh {
        vertices,
        triangles: fb.triangles,
    })
}

pub(crate) fn write<W: Write>(w: &mut W, mesh: &TriMesh, o: Options) -> std::io::Result<()> {
    writeln!(
        w,
        "# written by meshio: {} vertices, {} triangles",
        mesh.vertices.len(),
        mesh.triangles.len()
    )?;
    for v in &mesh.vertices {
        writeln!(
            w,
            "v {} {} {}",
            crate::fmt_coord(v.x, o.double),
            crate::fmt_coord(v.y, o.double),
            crate::fmt_coord(v.z, o.double)
        )?;
    }
    for t in &mesh.triangles {
        writeln!(w, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1)?;
    }
    Ok(())
}
