//! PLY: read with `ply-rs-bw` (ASCII, binary little- and big-endian, any scalar type),
//! write by hand (header + little-endian bytes).

use std::io::{BufRead, Write};
use std::path::Path;

use glam::DVec3;
use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{Header, Property, PropertyAccess, PropertyAccessResult, PropertyType};

use crate::{FaceBuilder, Format, MeshIoError, Options, PointCloud, TriMesh};

#[derive(Default)]
struct Vertex {
    p: [f64; 6],
}

impl Vertex {
    fn set(&mut self, name: &str, v: f64) -> PropertyAccessResult {
        let k = match name {
            "x" => 0,
            "y" => 1,
            "z" => 2,
            "nx" => 3,
            "ny" => 4,
            "nz" => 5,
            _ => return PropertyAccessResult::Ignored,
        };
        self.p[k] = v;
        PropertyAccessResult::Set
    }
}

impl PropertyAccess for Vertex {
    fn new() -> Self {
        Self::default()
    }
    fn set_char(&mut self, n: &str, v: i8) -> PropertyAccessResult {
        self.set(n, v.into())
    }
    fn set_uchar(&mut self, n: &str, v: u8) -> PropertyAccessResult {
        self.set(n, v.into())
    }
    fn set_short(&mut self, n: &str, v: i16) -> PropertyAccessResult {
        self.set(n, v.into())
    }
    fn set_ushort(&mut self, n: &str, v: u16) -> PropertyAccessResult {
        self.set(n, v.into())
    }
    fn set_int(&mut self, n: &str, v: i32) -> PropertyAccessResult {
        self.set(n, v.into())
    }
    fn set_uint(&mut self, n: &str, v: u32) -> PropertyAccessResult {
        self.set(n, v.into())
    }
    fn set_float(&mut self, n: &str, v: f32) -> PropertyAccessResult {
        self.set(n, v.into())
    }
    fn set_double(&mut self, n: &str, v: f64) -> PropertyAccessResult {
        self.set(n, v)
    }
}

fn is_index_list(name: &str) -> bool {
    name == "vertex_indices" || name == "vertex_index"
}

#[derive(Default)]
struct Face {
    idx: Vec<i64>,
}

impl Face {
    fn set<T: Into<i64>>(&mut self, name: &str, v: Vec<T>) -> PropertyAccessResult {
        if !is_index_list(name) {
            return PropertyAccessResult::Ignored;
        }
        self.idx = v.into_iter().map(Into::into).collect();
        PropertyAccessResult::Set
    }
}

impl PropertyAccess for Face {
    fn new() -> Self {
        Self::default()
    }
    fn set_list_char(&mut self, n: &str, v: Vec<i8>) -> PropertyAccessResult {
        self.set(n, v)
    }
    fn set_list_uchar(&mut self, n: &str, v: Vec<u8>) -> PropertyAccessResult {
        self.set(n, v)
    }
    fn set_list_short(&mut self, n: &str, v: Vec<i16>) -> PropertyAccessResult {
        self.set(n, v)
    }
    fn set_list_ushort(&mut self, n: &str, v: Vec<u16>) -> PropertyAccessResult {
        self.set(n, v)
    }
    fn set_list_int(&mut self, n: &str, v: Vec<i32>) -> PropertyAccessResult {
        self.set(n, v)
    }
    fn set_list_uint(&mut self, n: &str, v: Vec<u32>) -> PropertyAccessResult {
        self.set(n, v)
    }
    fn set_list_float(&mut self, n: &str, _v: Vec<f32>) -> PropertyAccessResult {
        if is_index_list(n) {
            PropertyAccessResult::UnsupportedType
        } else {
            PropertyAccessResult::Ignored
        }
    }
    fn set_list_double(&mut self, n: &str, _v: Vec<f64>) -> PropertyAccessResult {
        self.set_list_float(n, Vec::new())
    }
}

/// An element we skip (its values are parsed and dropped).
struct Skip;

impl PropertyAccess for Skip {
    fn new() -> Self {
        Skip
    }
    fn set_property(&mut self, _: &str, _: Property) -> PropertyAccessResult {
        PropertyAccessResult::Ignored
    }
}

fn map_parse_error(path: &Path, e: ply_rs_bw::parser::ParseError) -> MeshIoError {
    // ply-rs's messages span several lines; keep one line.
    let one_line = |s: String| s.split_whitespace().collect::<Vec<_>>().join(" ");
    if e.kind() == std::io::ErrorKind::UnexpectedEof {
        MeshIoError::Truncated {
            path: path.to_owned(),
            detail: "the file ends before all vertices and faces announced in its header"
                .to_string(),
        }
    } else {
        MeshIoError::not_a_mesh(path, Format::Ply, one_line(e.to_string()))
    }
}

fn has_scalar(header: &Header, element: &str, prop: &str) -> bool {
    header.elements.get(element).is_some_and(|e| {
        e.properties
            .get(prop)
            .is_some_and(|p| matches!(p.data_type, PropertyType::Scalar(_)))
    })
}

/// Read the `vertex` element (and the `face` element when `want_faces`).
pub(crate) fn read_points_and_faces<R: BufRead>(
    reader: &mut R,
    path: &Path,
    want_faces: bool,
) -> Result<(PointCloud, Option<FaceBuilder>), MeshIoError> {
    // Cheap magic check, so that a non-PLY file gets a clear message.
    let head = reader.fill_buf().map_err(|e| MeshIoError::io(path, e))?;
    if !head.starts_with(b"ply") {
        let shown: String = String::from_utf8_lossy(&head[..head.len().min(16)])
            .escape_debug()
            .collect();
        return Err(MeshIoError::not_a_mesh(
            path,
            Format::Ply,
            format!("the file does not start with \"ply\" (starts with \"{shown}\")"),
        ));
    }
    let mut reader = Reader::new(reader);
    let header = Parser::<Skip>::new()
        .read_header(&mut reader)
        .map_err(|e| map_parse_error(path, e))?;
    if !header.elements.contains_key("vertex") {
        return Err(MeshIoError::not_a_mesh(
            path,
            Format::Ply,
            "the header has no vertex element",
        ));
    }
    for c in ["x", "y", "z"] {
        if !has_scalar(&header, "vertex", c) {
            return Err(MeshIoError::not_a_mesh(
                path,
                Format::Ply,
                format!("the vertex element has no scalar property {c}"),
            ));
        }
    }
    let with_normals = ["nx", "ny", "nz"]
        .iter()
        .all(|c| has_scalar(&header, "vertex", c));
    if want_faces && let Some(face) = header.elements.get("face") {
        {
            let ok = face.properties.iter().any(|(name, p)| {
                is_index_list(name) && matches!(p.data_type, PropertyType::List(_, _))
            });
            if !ok {
                return Err(MeshIoError::not_a_mesh(
                    path,
                    Format::Ply,
                    "the face element has no list property vertex_indices or vertex_index",
                ));
            }
        }
    }
    let mut cloud = PointCloud::default();
    let mut faces: Option<FaceBuilder> = None;
    let mut vertices_read = false;
    for (name, def) in &header.elements {
        if name == "vertex" {
            let vs = Parser::<Vertex>::new()
                .read_payload_for_element(&mut reader, def, &header)
                .map_err(|e| map_parse_error(path, e))?;
            cloud.points = vs
                .iter()
                .map(|v| DVec3::new(v.p[0], v.p[1], v.p[2]))
                .collect();
            if with_normals {
                cloud.normals = Some(
                    vs.iter()
                        .map(|v| DVec3::new(v.p[3], v.p[4], v.p[5]))
                        .collect(),
                );
            }
            vertices_read = true;
        } else if name == "face" && want_faces {
            let fs = Parser::<Face>::new()
                .read_payload_for_element(&mut reader, def, &header)
                .map_err(|e| map_parse_error(path, e))?;
            if !vertices_read {
                return Err(MeshIoError::not_a_mesh(
                    path,
                    Format::Ply,
                    "the face element comes before the vertex element; write vertices first",
                ));
            }
            let mut fb = FaceBuilder::default();
            for f in &fs {
                fb.push_polygon(&f.idx, cloud.points.len())
                    .map_err(|source| MeshIoError::Invalid {
                        path: path.to_owned(),
                        source,
                    })?;
            }
            faces = Some(fb);
        } else if want_faces || !vertices_read {
            Parser::<Skip>::new()
                .read_payload_for_element(&mut reader, def, &header)
                .map_err(|e| map_parse_error(path, e))?;
        } else {
            break; // point cloud: nothing after the vertices is needed
        }
    }
    crate::check_vertex_coords(path, &cloud.points)?;
    Ok((cloud, faces))
}

pub(crate) fn read<R: BufRead>(reader: &mut R, path: &Path) -> Result<TriMesh, MeshIoError> {
    let (cloud, faces) = read_points_and_faces(reader, path, true)?;
    Ok(TriMesh {
        vertices: cloud.points,
        triangles: faces.map(|f| f.triangles).unwrap_or_default(),
    })
}

pub(crate) fn write<W: Write>(w: &mut W, mesh: &TriMesh, o: Options) -> std::io::Result<()> {
    let ty = if o.double { "double" } else { "float" };
    let enc = if o.binary {
        "binary_little_endian"
    } else {
        "ascii"
    };
    write!(
        w,
        "ply\nformat {enc} 1.0\ncomment written by meshio\nelement vertex {}\n\
         property {ty} x\nproperty {ty} y\nproperty {ty} z\nelement face {}\n\
         property list uchar uint vertex_indices\nend_header\n",
        mesh.vertices.len(),
        mesh.triangles.len()
    )?;
    if o.binary {
        let mut buf = Vec::with_capacity(mesh.vertices.len() * 24);
        for v in &mesh.vertices {
            for c in v.to_array() {
                if o.double {
                    buf.extend_from_slice(&c.to_le_bytes());
                } else {
                    buf.extend_from_slice(&(c as f32).to_le_bytes());
                }
            }
        }
        w.write_all(&buf)?;
        buf.clear();
        buf.reserve(mesh.triangles.len() * 13);
        for t in &mesh.triangles {
            buf.push(3);
            for i in t {
                buf.extend_from_slice(&i.to_le_bytes());
            }
        }
        w.write_all(&buf)?;
    } else {
        for v in &mesh.vertices {
            writeln!(
                w,
                "{} {} {}",
                crate::fmt_coord(v.x, o.double),
                crate::fmt_coord(v.y, o.double),
                crate::fmt_coord(v.z, o.double)
            )?;
        }
        for t in &mesh.triangles {
            writeln!(w, "3 {} {} {}", t[0], t[1], t[2])?;
        }
    }
    Ok(())
}
