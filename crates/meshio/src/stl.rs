//! STL (ours: file format support), ASCII and binary. Vertices are merged by exact coordinate
//! equality on read (`-0.0` and `0.0` are the same vertex), in order of first appearance.
//!
//! Strict: a binary STL has exactly `84 + 50 n` bytes (`n` from its header); an ASCII STL is
//! checked statement by statement (`solid`, `facet normal`, `outer loop`, three `vertex`,
//! `endloop`, `endfacet`, `endsolid`), so garbled keywords and facets with other than three
//! vertices are errors naming the line.

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
    if bytes.len() as u64 != need {
        return Err(MeshIoError::not_a_mesh(
            path,
            Format::Stl,
            format!(
                "the binary STL header announces {n} facets, i.e. 84 + 50 * {n} = {need} bytes, \
                 but the file has {} bytes",
                bytes.len()
            ),
        ));
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

/// Where the ASCII STL parser is: the statement it expects next.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Expect {
    /// `solid [name]` (at the start, or after `endsolid`: files may hold several solids).
    Solid,
    /// `facet normal ni nj nk` or `endsolid [name]`.
    FacetOrEnd,
    OuterLoop,
    /// `vertex x y z` number `0, 1, 2`, then `endloop`.
    Vertex(usize),
    EndLoop,
    EndFacet,
}

impl Expect {
    fn describe(self) -> &'static str {
        match self {
            Expect::Solid => "'solid [name]'",
            Expect::FacetOrEnd => "'facet normal ni nj nk' or 'endsolid [name]'",
            Expect::OuterLoop => "'outer loop'",
            Expect::Vertex(_) => "'vertex x y z' (a facet has exactly 3 vertices)",
            Expect::EndLoop => "'endloop' (a facet has exactly 3 vertices)",
            Expect::EndFacet => "'endfacet'",
        }
    }
}

/// Three numbers after a keyword, or `None`.
fn three_numbers<'a>(it: impl Iterator<Item = &'a str>) -> Option<[f64; 3]> {
    let v: Vec<&str> = it.collect();
    match v.as_slice() {
        [a, b, c] => Some([
            crate::parse_f64(a)?,
            crate::parse_f64(b)?,
            crate::parse_f64(c)?,
        ]),
        _ => None,
    }
}

/// ASCII STL, checked statement by statement (keywords case-insensitive, as most readers do):
/// `solid`, then per facet `facet normal n n n`, `outer loop`, three `vertex x y z`,
/// `endloop`, `endfacet`, and `endsolid`. The normal is read and ignored.
fn read_ascii(bytes: &[u8], path: &Path) -> Result<TriMesh, MeshIoError> {
    let text = std::str::from_utf8(bytes).map_err(|_| {
        MeshIoError::not_a_mesh(
            path,
            Format::Stl,
            "starts with \"solid\" but is not ASCII text",
        )
    })?;
    let bad = |ln: usize, what: String| {
        MeshIoError::not_a_mesh(path, Format::Stl, format!("line {}: {what}", ln + 1))
    };
    let mut m = Merger::default();
    let mut corners = [DVec3::ZERO; 3];
    let mut facet = 0;
    let mut state = Expect::Solid;
    for (ln, line) in text.lines().enumerate() {
        let lower = line.to_ascii_lowercase();
        let mut it = lower.split_ascii_whitespace();
        let Some(kw) = it.next() else { continue };
        let next = match (state, kw) {
            (Expect::Solid, "solid") => Some(Expect::FacetOrEnd),
            (Expect::FacetOrEnd, "endsolid") => Some(Expect::Solid),
            (Expect::FacetOrEnd, "facet") => {
                let ok = it.next() == Some("normal") && three_numbers(it).is_some();
                ok.then_some(Expect::OuterLoop)
            }
            (Expect::OuterLoop, "outer") => {
                (it.next() == Some("loop") && it.next().is_none()).then_some(Expect::Vertex(0))
            }
            (Expect::Vertex(k), "vertex") => three_numbers(it).map(|[x, y, z]| {
                corners[k] = DVec3::new(x, y, z);
                if k == 2 {
                    Expect::EndLoop
                } else {
                    Expect::Vertex(k + 1)
                }
            }),
            (Expect::EndLoop, "endloop") => it.next().is_none().then_some(Expect::EndFacet),
            (Expect::EndFacet, "endfacet") => {
                if it.next().is_some() {
                    None
                } else {
                    check_finite(path, &corners, facet)?;
                    m.triangle(corners);
                    facet += 1;
                    Some(Expect::FacetOrEnd)
                }
            }
            _ => None,
        };
        state = next.ok_or_else(|| {
            bad(
                ln,
                format!(
                    "facet {facet}: expected {}, found {:?}",
                    state.describe(),
                    line.trim()
                ),
            )
        })?;
    }
    if state != Expect::Solid {
        return Err(MeshIoError::Truncated {
            path: path.to_owned(),
            detail: format!(
                "ASCII STL ends at facet {facet} while expecting {}",
                state.describe()
            ),
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
                crate::write_point_line(w, "vertex ", mesh.vertices[i as usize], o.double)?;
            }
            writeln!(w, "endloop\nendfacet")?;
        }
        writeln!(w, "endsolid meshio")
    }
}
