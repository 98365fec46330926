//! STL, ASCII and binary. Vertices are merged by exact coordinate equality on read
//! (`-0.0` and `0.0` are the same vertex), in order of first appearance.

use std::collections::HashMap;
use std::io::Write;
use std::path::Path;

use glam::DVec3;

use crate::{Format, MeshIoError, Options, TriMesh};

#[derive(Default)]
struct Merger {
    map: HashMap<[u64; 3], u32>,
    mesh: TriMesh,
}

impl Merger {
    fn vertex(&mut self, p: DVec3) -> u32 {
        let p = p + DVec3::ZERO; // -0.0 + 0.0 == +0.0
        let key = [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
        let next = self.mesh.vertices.len() as u32;
        *self.map.entry(key).or_insert_with(|| {
            self.mesh.vertices.push(p);
            next
        })
    }
    fn triangle(&mut self, t: [DVec3; 3]) {
        let tri = [self.vertex(t[0]), self.vertex(t[1]), self.vertex(t[2])];
        self.mesh.triangles.push(tri);
    }
}

fn check_finite(path: &Path, t: &[DVec3; 3], facet: usize) -> Result<(), MeshIoError> {
    for p in t {
        if !p.is_finite() {
            return Err(MeshIoError::not_a_mesh(
                path,
                Format::Stl,
                format!(
                    "facet {facet} has a non-finite coordinate ({}, {}, {}); remove or repair \
                     NaN/inf coordinates",
                    p.x, p.y, p.z
                ),
            ));
        }
    }
    Ok(())
}

pub(crate) fn read(bytes: &[u8], path: &Path) -> Result<TriMesh, MeshIoError> {
    if bytes.is_empty() {
        return Err(MeshIoError::Empty {
            path: path.to_owned(),
            format: Format::Stl,
        });
    }
    let binary_size_ok = bytes.len() >= 84 && {
        let n = u32::from_le_bytes(bytes[80..84].try_into().unwrap()) as u64;
        bytes.len() as u64 == 84 + 50 * n
    };
    let looks_ascii = bytes.trim_ascii_start().starts_with(b"solid");
    if looks_ascii && !binary_size_ok {
        return read_ascii(bytes, path);
    }
    if bytes.len() < 84 {
        return Err(MeshIoError::not_a_mesh(
            path,
            Format::Stl,
            format!(
                "{} bytes: too short for a binary STL (84-byte header) and not ASCII STL \
                 (which starts with \"solid\")",
                bytes.len()
            ),
        ));
    }
    let n = u32::from_le_bytes(bytes[80..84].try_into().unwrap()) as u64;
    let need = 84 + 50 * n;
    if (bytes.len() as u64) < need {
        return Err(MeshIoError::Truncated {
            path: path.to_owned(),
            detail: format!(
                "binary STL header announces {n} facets ({need} bytes), the file has {} bytes",
                bytes.len()
            ),
        });
    }
    let mut m = Merger::default();
    let f = |b: &[u8]| f32::from_le_bytes(b.try_into().unwrap()) as f64;
    for k in 0..n as usize {
        let rec = &bytes[84 + 50 * k..84 + 50 * (k + 1)];
        let p = |j: usize| {
            let o = 12 + 12 * j;
            DVec3::new(
                f(&rec[o..o + 4]),
                f(&rec[o + 4..o + 8]),
                f(&rec[o + 8..o + 12]),
            )
        };
        let t = [p(0), p(1), p(2)];
        check_finite(path, &t, k)?;
        m.triangle(t);
    }
    Ok(m.mesh)
}

fn read_ascii(bytes: &[u8], path: &Path) -> Result<TriMesh, MeshIoError> {
    let text = std::str::from_utf8(bytes).map_err(|_| {
        MeshIoError::not_a_mesh(
            path,
            Format::Stl,
            "starts with \"solid\" but is not ASCII text",
        )
    })?;
    let mut m = Merger::default();
    let mut corners: Vec<DVec3> = Vec::with_capacity(3);
    let mut facet = 0;
    let mut in_facet = false;
    for (ln, line) in text.lines().enumerate() {
        let mut it = line.split_whitespace();
        match it.next() {
            Some("facet") => {
                corners.clear();
                in_facet = true;
            }
            Some("vertex") => {
                let c: Vec<f64> = it.take(3).filter_map(crate::parse_f64).collect();
                if c.len() < 3 || !in_facet {
                    return Err(MeshIoError::not_a_mesh(
                        path,
                        Format::Stl,
                        format!("line {}: bad vertex line {line:?}", ln + 1),
                    ));
                }
                corners.push(DVec3::new(c[0], c[1], c[2]));
            }
            Some("endfacet") => {
                if corners.len() < 3 {
                    return Err(MeshIoError::not_a_mesh(
                        path,
                        Format::Stl,
                        format!(
                            "line {}: facet {facet} has {} vertices",
                            ln + 1,
                            corners.len()
                        ),
                    ));
                }
                for k in 1..corners.len() - 1 {
                    let t = [corners[0], corners[k], corners[k + 1]];
                    check_finite(path, &t, facet)?;
                    m.triangle(t);
                }
                facet += 1;
                in_facet = false;
            }
            _ => {}
        }
    }
    if in_facet {
        return Err(MeshIoError::Truncated {
            path: path.to_owned(),
            detail: format!("ASCII STL ends inside facet {facet} (no endfacet)"),
        });
    }
    Ok(m.mesh)
}

fn normal(mesh: &TriMesh, t: &[u32; 3]) -> DVec3 {
    let [a, b, c] = t.map(|i| mesh.vertices[i as usize]);
    (b - a).cross(c - a).normalize_or_zero()
}

pub(crate) fn write<W: Write>(w: &mut W, mesh: &TriMesh, o: Options) -> std::io::Result<()> {
    if o.binary {
        let mut header = [0u8; 80];
        let msg = b"binary STL written by meshio";
        header[..msg.len()].copy_from_slice(msg);
        w.write_all(&header)?;
        let n = u32::try_from(mesh.triangles.len())
            .map_err(|_| std::io::Error::other("more than 2^32 triangles do not fit in STL"))?;
        w.write_all(&n.to_le_bytes())?;
        let mut buf = Vec::with_capacity(mesh.triangles.len() * 50);
        for t in &mesh.triangles {
            let nrm = normal(mesh, t);
            for c in nrm.to_array() {
                buf.extend_from_slice(&(c as f32).to_le_bytes());
            }
            for &i in t {
                for c in mesh.vertices[i as usize].to_array() {
                    buf.extend_from_slice(&(c as f32).to_le_bytes());
                }
            }
            buf.extend_from_slice(&0u16.to_le_bytes());
        }
        w.write_all(&buf)
    } else {
        writeln!(w, "solid meshio")?;
        for t in &mesh.triangles {
            let n = normal(mesh, t);
            writeln!(
                w,
                "facet normal {} {} {}\nouter loop",
                n.x as f32, n.y as f32, n.z as f32
            )?;
            for &i in t {
                let v = mesh.vertices[i as usize];
                writeln!(
                    w,
                    "vertex {} {} {}",
                    crate::fmt_coord(v.x, o.double),
                    crate::fmt_coord(v.y, o.double),
                    crate::fmt_coord(v.z, o.double)
                )?;
            }
            writeln!(w, "endloop\nendfacet")?;
        }
        writeln!(w, "endsolid meshio")
    }
}
