//! OFF (ours: file format support), text only. Accepts `OFF`, `COFF`, `NOFF` and `CNOFF`
//! headers, `#` comments, blank lines, and the counts `nv nf [ne]` on the header line or the
//! next line.
//!
//! Strict: a vertex line has exactly `x y z` (NOFF: plus `nx ny nz`; COFF: plus an `r g b` or
//! `r g b a` colour, ignored), a face line `n i1 ... in` and an optional colour (1, 3 or 4
//! numbers, ignored), and nothing but comments may follow the last face.

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
            let s = crate::strip_comment(&self.buf).trim();
            if !s.is_empty() {
                return Ok(Some((self.line_no, s.to_owned())));
            }
        }
    }
}

/// The per-vertex values an OFF variant has: `(with_normals, with_colours)`.
fn variant(tok: &str) -> Result<(bool, bool), String> {
    let Some(prefix) = tok.strip_suffix("OFF") else {
        return Err(format!("expected an OFF header, found {tok:?}"));
    };
    if prefix.contains(['S', 'T', '4', 'n']) {
        return Err(format!("unsupported OFF variant {tok:?}; use plain OFF"));
    }
    match prefix {
        "" => Ok((false, false)),
        "C" => Ok((false, true)),
        "N" => Ok((true, false)),
        "CN" => Ok((true, true)),
        _ => Err(format!(
            "expected an OFF header (OFF, COFF, NOFF or CNOFF), found {tok:?}"
        )),
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
    let (normals, colours) = variant(&toks[0]).map_err(|w| bad(l0, w))?;
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
    let counts: Vec<usize> = toks.iter().filter_map(|t| t.parse().ok()).collect();
    if counts.len() != toks.len() || !(2..=3).contains(&counts.len()) {
        return Err(bad(
            lines.line_no,
            format!("expected the counts 'nv nf ne' (non-negative integers), found {toks:?}"),
        ));
    }
    let (nv, nf) = (counts[0], counts[1]);
    let per_vertex = 3 + if normals { 3 } else { 0 };
    let mut vertices = Vec::with_capacity(nv.min(1 << 16));
    for i in 0..nv {
        let Some((ln, l)) = lines.next_line()? else {
            return Err(truncated(path, nv, "vertices", i));
        };
        let toks: Vec<&str> = l.split_whitespace().collect();
        let c: Vec<f64> = toks.iter().filter_map(|t| crate::parse_f64(t)).collect();
        let extra = toks.len().wrapping_sub(per_vertex);
        let ok = c.len() == toks.len() && (extra == 0 || (colours && (extra == 3 || extra == 4)));
        if !ok {
            let want = match (normals, colours) {
                (false, false) => "x y z",
                (false, true) => "x y z r g b [a]",
                (true, false) => "x y z nx ny nz",
                (true, true) => "x y z nx ny nz r g b [a]",
            };
            return Err(bad(
                ln,
                format!("vertex {i}: expected '{want}' (numbers), found {l:?}"),
            ));
        }
        vertices.push(DVec3::new(c[0], c[1], c[2]));
    }
    crate::check_vertex_coords(path, &vertices)?;
    let mut fb = FaceBuilder::default();
    let mut idx = Vec::new();
    for i in 0..nf {
        let Some((ln, l)) = lines.next_line()? else {
            return Err(truncated(path, nf, "faces", i));
        };
        let toks: Vec<&str> = l.split_whitespace().collect();
        let n: usize = toks[0].parse().map_err(|_| {
            bad(
                ln,
                format!("face {i}: expected a vertex count, found {l:?}"),
            )
        })?;
        let rest = &toks[1..];
        let colour = rest.len().checked_sub(n);
        let ok_colour = matches!(colour, Some(0 | 1 | 3 | 4))
            && rest[n..]
                .iter()
                .all(|t| crate::parse_f64(t).is_some_and(f64::is_finite));
        idx.clear();
        idx.extend(rest.iter().take(n).map_while(|t| t.parse::<i64>().ok()));
        if idx.len() != n || !ok_colour {
            return Err(bad(
                ln,
                format!(
                    "face {i}: expected {n} integer indices and an optional colour (1, 3 or 4 \
                     numbers), found {l:?}"
                ),
            ));
        }
        fb.push_polygon(&idx, nv)
            .map_err(|source| MeshIoError::Invalid {
                path: path.to_owned(),
                source,
            })?;
    }
    if let Some((ln, l)) = lines.next_line()? {
        return Err(bad(
            ln,
            format!(
                "data after the last face ({l:?}); the header announces {nv} vertices and {nf} \
                 faces"
            ),
        ));
    }
    Ok(TriMesh {
        vertices,
        triangles: fb.triangles,
    })
}

/// The file ends after `found` of the `announced` elements the header promised.
fn truncated(path: &Path, announced: usize, what: &str, found: usize) -> MeshIoError {
    MeshIoError::Truncated {
        path: path.to_owned(),
        detail: format!("the header announces {announced} {what}, the file has {found}"),
    }
}

pub(crate) fn write<W: Write>(w: &mut W, mesh: &TriMesh, o: Options) -> std::io::Result<()> {
    writeln!(w, "OFF\n{} {} 0", mesh.vertices.len(), mesh.triangles.len())?;
    crate::write_text_body(w, mesh, o.double, ("", "3 ", 0))
}
