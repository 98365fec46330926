//! OFF (Object File Format), text only. Accepts `OFF`, `COFF`, `NOFF`, ... headers, `#`
//! comments, counts on the header line or the next line, and extra per-vertex/face values
//! (colours), which are ignored.

use std::io::{BufRead, Write};
use std::path::Path;

use glam::DVec3;

use crate::{FaceBuilder, Format, MeshIoError, Options, TriMesh};

/// Non-empty, comment-stripped lines with their 1-based line numbers.
struct Lines<'a, R: BufRead> {
    reader: &'a mut R,
    line_no: usize,
    buf: String,
    path: &'a Path,
}

impl<R: BufRead> Lines<'_, R> {
    fn next_line(&mut self) -> Result<Option<(usize, String)>, MeshIoError> {
        loop {
            self.buf.clear();
            let n = self.reader.read_line(&mut self.buf).map_err(|e| {
                if e.kind() == std::io::ErrorKind::InvalidData {
                    MeshIoError::not_a_mesh(self.path, Format::Off, "the file is not UTF-8 text")
                } else {
                    MeshIoError::io(self.path, e)
                }
            })?;
            if n == 0 {
                return Ok(None);
            }
            self.line_no += 1;
            let s = self.buf.split('#').next().unwrap_or("").trim();
            if !s.is_empty() {
                return Ok(Some((self.line_no, s.to_owned())));
            }
        }
    }
}

pub(crate) fn read<R: BufRead>(reader: &mut R, path: &Path) -> Result<TriMesh, MeshIoError> {
    let bad = |line: usize, what: String| {
        MeshIoError::not_a_mesh(path, Format::Off, format!("line {line}: {what}"))
    };
    let mut lines = Lines {
        reader,
        line_no: 0,
        buf: String::new(),
        path,
    };
    let Some((l0, first)) = lines.next_line()? else {
        return Err(MeshIoError::Empty {
            path: path.to_owned(),
            format: Format::Off,
        });
    };
    let mut toks: Vec<String> = first.split_whitespace().map(str::to_owned).collect();
    if !toks[0].ends_with("OFF") {
        return Err(bad(
            l0,
            format!("expected an OFF header, found {:?}", toks[0]),
        ));
    }
    if toks[0].starts_with("ST") || toks[0].contains('4') || toks[0].starts_with('n') {
        return Err(bad(
            l0,
            format!("unsupported OFF variant {:?}; use plain OFF", toks[0]),
        ));
    }
    toks.remove(0);
    if toks.is_empty() {
        let Some((_, l)) = lines.next_line()? else {
            return Err(MeshIoError::Truncated {
                path: path.to_owned(),
                detail: "no vertex/face counts after the OFF header".into(),
            });
        };
        toks = l.split_whitespace().map(str::to_owned).collect();
    }
    let counts: Vec<usize> = toks.iter().take(2).filter_map(|t| t.parse().ok()).collect();
    if counts.len() < 2 {
        return Err(bad(
            lines.line_no,
            format!("expected 'nv nf ne' counts, found {toks:?}"),
        ));
    }
    let (nv, nf) = (counts[0], counts[1]);
    let mut vertices = Vec::with_capacity(nv.min(1 << 16));
    for i in 0..nv {
        let Some((ln, l)) = lines.next_line()? else {
            return Err(MeshIoError::Truncated {
                path: path.to_owned(),
                detail: format!("the header announces {nv} vertices, the file has {i}"),
            });
        };
        let c: Vec<f64> = l
            .split_whitespace()
            .take(3)
            .filter_map(crate::parse_f64)
            .collect();
        if c.len() < 3 {
            return Err(bad(
                ln,
                format!("vertex {i}: expected 3 coordinates, found {l:?}"),
            ));
        }
        vertices.push(DVec3::new(c[0], c[1], c[2]));
    }
    crate::check_vertex_coords(path, &vertices)?;
    let mut fb = FaceBuilder::default();
    let mut idx = Vec::new();
    for i in 0..nf {
        let Some((ln, l)) = lines.next_line()? else {
            return Err(MeshIoError::Truncated {
                path: path.to_owned(),
                detail: format!("the header announces {nf} faces, the file has {i}"),
            });
        };
        let mut it = l.split_whitespace();
        let n: usize = it.next().and_then(|t| t.parse().ok()).ok_or_else(|| {
            bad(
                ln,
                format!("face {i}: expected a vertex count, found {l:?}"),
            )
        })?;
        idx.clear();
        for _ in 0..n {
            let v: i64 = it.next().and_then(|t| t.parse().ok()).ok_or_else(|| {
                bad(
                    ln,
                    format!("face {i}: expected {n} integer indices, found {l:?}"),
                )
            })?;
            idx.push(v);
        }
        fb.push_polygon(&idx, nv)
            .map_err(|source| MeshIoError::Invalid {
                path: path.to_owned(),
                source,
            })?;
    }
    Ok(TriMesh {
        vertices,
        triangles: fb.triangles,
    })
}

pub(crate) fn write<W: Write>(w: &mut W, mesh: &TriMesh, o: Options) -> std::io::Result<()> {
    writeln!(w, "OFF\n{} {} 0", mesh.vertices.len(), mesh.triangles.len())?;
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
    Ok(())
}
