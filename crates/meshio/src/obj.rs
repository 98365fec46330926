//! Wavefront OBJ (ours: file format support): `v` and `f` lines; polygons are
//! fan-triangulated; the specification's other statements are ignored, unknown ones (a
//! garbled keyword) are errors.
//!
//! - `v x y z`, `v x y z w` (the weight `w` of rational curves, read and ignored: polygon
//!   vertices are not divided by it), and the common colour extension `v x y z r g b` (and
//!   `... r g b a`, as trimesh reads them), colours ignored. Every value must be a number;
//!   5 or more than 7 numbers are errors.
//! - `f` corners `i`, `i/t`, `i//n` or `i/t/n`: every present index an integer other than 0,
//!   negative ones relative to the elements read so far; texture and normal indices must
//!   refer to existing `vt` / `vn` lines.
//! - `vt u [v [w]]` and `vn x y z`: finite numbers (checked, then ignored).

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
    // Counts of `vt` and `vn` lines so far, and the texture / normal references to check.
    let mut counts = [0usize; 2];
    // (line, index as written, 0-based index)
    let mut refs: [Vec<(usize, i64, i64)>; 2] = [Vec::new(), Vec::new()];
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
        let s = crate::strip_comment(&buf).trim();
        let mut it = s.split_whitespace();
        match it.next() {
            Some("v") => {
                vertices.push(parse_v(it, s).map_err(|w| bad(line_no, w))?);
                saw_statement = true;
            }
            Some(kw @ ("vt" | "vn")) => {
                check_vt_vn(kw == "vn", it, s).map_err(|w| bad(line_no, w))?;
                counts[usize::from(kw == "vn")] += 1;
                saw_statement = true;
            }
            Some("f") => {
                let mut poly = Vec::new();
                for tok in it {
                    let (i, t, n) = parse_corner(tok).ok_or_else(|| {
                        bad(
                            line_no,
                            format!(
                                "bad face corner {tok:?} (expected i, i/t, i//n or i/t/n with \
                                 integer indices other than 0)"
                            ),
                        )
                    })?;
                    for (k, r) in [t, n].into_iter().enumerate() {
                        if let Some(r) = r {
                            refs[k].push((line_no, r, resolve(r, counts[k])));
                        }
                    }
                    poly.push(resolve(i, vertices.len()));
                }
                polygons.push(poly);
                saw_statement = true;
            }
            Some(kw) if !OTHER_STATEMENTS.contains(&kw) => {
                let what = if saw_statement {
                    "; a garbled line would silently drop its data: fix or remove it"
                } else {
                    ""
                };
                return Err(bad(line_no, format!("unknown OBJ statement {kw:?}{what}")));
            }
            Some(_) | None => {}
        }
    }
    crate::check_vertex_coords(path, &vertices)?;
    check_refs(&refs, counts).map_err(|(line, what)| bad(line, what))?;
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

/// Check that every texture / normal reference `(line, index as written, 0-based index)`
/// names an existing `vt` / `vn` line; on failure, the line and the message.
/// The statements of the OBJ specification other than `v`, `vt`, `vn` and `f` (free-form
/// geometry, grouping, display attributes): read and ignored. Anything else is an error, so
/// that a garbled `f` or `v` line cannot silently drop its data.
const OTHER_STATEMENTS: [&str; 35] = [
    "vp",
    "g",
    "o",
    "s",
    "mg",
    "usemtl",
    "mtllib",
    "usemap",
    "maplib",
    "l",
    "p",
    "cstype",
    "deg",
    "bmat",
    "step",
    "curv",
    "curv2",
    "surf",
    "parm",
    "trim",
    "hole",
    "scrv",
    "sp",
    "end",
    "con",
    "bevel",
    "c_interp",
    "d_interp",
    "lod",
    "shadow_obj",
    "trace_obj",
    "ctech",
    "stech",
    "call",
    "csh",
];

fn check_refs(
    refs: &[Vec<(usize, i64, i64)>; 2],
    counts: [usize; 2],
) -> Result<(), (usize, String)> {
    for (k, what) in ["texture (vt)", "normal (vn)"].into_iter().enumerate() {
        if let Some((line, i, _)) = refs[k]
            .iter()
            .find(|(_, _, r)| *r < 0 || *r as usize >= counts[k])
        {
            return Err((
                *line,
                format!(
                    "a face corner refers to {what} index {i}, which does not exist ({} such \
                     lines in the file)",
                    counts[k]
                ),
            ));
        }
    }
    Ok(())
}

/// The position of a `v` line (`s` is the whole line, for the message): 3, 4 (weight) or
/// 6 / 7 (colour) numbers, the extra ones finite.
fn parse_v<'a>(toks: impl Iterator<Item = &'a str>, s: &str) -> Result<DVec3, String> {
    let toks: Vec<&str> = toks.collect();
    let c: Vec<f64> = toks.iter().filter_map(|t| crate::parse_f64(t)).collect();
    if c.len() != toks.len() || !matches!(c.len(), 3 | 4 | 6 | 7) {
        return Err(format!(
            "expected 'v x y z', 'v x y z w' or 'v x y z r g b' (numbers), found {s:?}"
        ));
    }
    if c[3..].iter().any(|x| !x.is_finite()) {
        return Err(format!("non-finite weight or colour in {s:?}"));
    }
    Ok(DVec3::new(c[0], c[1], c[2]))
}

/// A `vn x y z` (`normal`) or `vt u [v [w]]` line: finite numbers, checked then ignored.
fn check_vt_vn<'a>(
    normal: bool,
    toks: impl Iterator<Item = &'a str>,
    s: &str,
) -> Result<(), String> {
    let toks: Vec<&str> = toks.collect();
    let finite = toks
        .iter()
        .all(|t| crate::parse_f64(t).is_some_and(f64::is_finite));
    let (n_ok, want) = if normal {
        (toks.len() == 3, "'vn x y z'")
    } else {
        ((1..=3).contains(&toks.len()), "'vt u [v [w]]'")
    };
    if finite && n_ok {
        Ok(())
    } else {
        Err(format!("expected {want} (finite numbers), found {s:?}"))
    }
}

/// `i`, `i/t`, `i//n` or `i/t/n` as (i, t, n), every index a non-zero integer.
fn parse_corner(tok: &str) -> Option<(i64, Option<i64>, Option<i64>)> {
    let idx = |s: &str| s.parse::<i64>().ok().filter(|&i| i != 0);
    let parts: Vec<&str> = tok.split('/').collect();
    match parts.as_slice() {
        [i] => Some((idx(i)?, None, None)),
        [i, t] => Some((idx(i)?, Some(idx(t)?), None)),
        [i, "", n] => Some((idx(i)?, None, Some(idx(n)?))),
        [i, t, n] => Some((idx(i)?, Some(idx(t)?), Some(idx(n)?))),
        _ => None,
    }
}

/// A 1-based OBJ index (negative: relative to the `so_far` elements read) as a 0-based one.
fn resolve(i: i64, so_far: usize) -> i64 {
    if i > 0 { i - 1 } else { so_far as i64 + i }
}

pub(crate) fn write<W: Write>(w: &mut W, mesh: &TriMesh, o: Options) -> std::io::Result<()> {
    writeln!(
        w,
        "# written by meshio: {} vertices, {} triangles",
        mesh.vertices.len(),
        mesh.triangles.len()
    )?;
    crate::write_text_body(w, mesh, o.double, ("v ", "f ", 1))
}
