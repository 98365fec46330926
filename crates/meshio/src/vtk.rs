//! VTK legacy `.vtk` (ours: file format support): ASCII `UNSTRUCTURED_GRID` of triangles
//! (`CELLS` and `CELL_TYPES` 5; what meshio reads, ParaView and VTK too), double coordinates
//! (the shortest exact decimal, so a round trip is exact), and each [`CellData`] as a
//! `SCALARS NAME double 1` array of `CELL_DATA`.
//!
//! The reader takes ASCII `POLYDATA` (`POLYGONS`, fan-triangulated) and `UNSTRUCTURED_GRID`
//! (`CELLS` with `CELL_TYPES`, triangles only: what meshio writes), in the classic layout
//! (`POLYGONS m size` then `n i1 .. in` per cell) and the 5.x layout (`OFFSETS` and
//! `CONNECTIVITY` arrays). Binary files are refused with the way to convert them.

use std::io::Write;
use std::path::Path;

use glam::DVec3;

use crate::{CellData, FaceBuilder, Format, MeshIoError, TriMesh, fmt_coord};

/// Write an ASCII legacy VTK unstructured grid of triangles with cell data.
pub(crate) fn write<W: Write>(
    w: &mut W,
    mesh: &TriMesh,
    cells: &[CellData],
) -> std::io::Result<()> {
    writeln!(w, "# vtk DataFile Version 4.2")?;
    writeln!(w, "rdt-mesher surface mesh")?;
    writeln!(w, "ASCII")?;
    writeln!(w, "DATASET UNSTRUCTURED_GRID")?;
    writeln!(w, "POINTS {} double", mesh.vertices.len())?;
    for &v in &mesh.vertices {
        crate::write_point_line(w, "", v, true)?;
    }
    let m = mesh.triangles.len();
    writeln!(w, "CELLS {m} {}", 4 * m)?;
    for t in &mesh.triangles {
        writeln!(w, "3 {} {} {}", t[0], t[1], t[2])?;
    }
    writeln!(w, "CELL_TYPES {m}")?;
    for _ in 0..m {
        writeln!(w, "5")?;
    }
    if !cells.is_empty() {
        writeln!(w, "CELL_DATA {m}")?;
        for c in cells {
            writeln!(w, "SCALARS {} double 1", c.name)?;
            writeln!(w, "LOOKUP_TABLE default")?;
            for &v in &c.values {
                writeln!(w, "{}", fmt_coord(v, true))?;
            }
        }
    }
    Ok(())
}

/// Whitespace-separated tokens with the line each is on.
struct Tokens<'a> {
    toks: Vec<(usize, &'a str)>,
    at: usize,
    path: &'a Path,
}

impl<'a> Tokens<'a> {
    fn next(&mut self, what: &str) -> Result<(usize, &'a str), MeshIoError> {
        let t = self
            .toks
            .get(self.at)
            .copied()
            .ok_or_else(|| MeshIoError::Truncated {
                path: self.path.to_owned(),
                detail: format!("the file ends where {what} was expected"),
            })?;
        self.at += 1;
        Ok(t)
    }
    fn num<T: std::str::FromStr>(&mut self, what: &str) -> Result<T, MeshIoError> {
        let (line, t) = self.next(what)?;
        t.parse::<T>().map_err(|_| {
            bad(
                self.path,
                format!("line {line}: {what} {t:?} is not a valid number"),
            )
        })
    }
    fn peek(&self) -> Option<&'a str> {
        self.toks.get(self.at).map(|t| t.1)
    }
}

fn bad(path: &Path, reason: impl Into<String>) -> MeshIoError {
    MeshIoError::not_a_mesh(path, Format::Vtk, reason)
}

/// The text after the three header lines (version, title, ASCII), checked.
fn body<'a>(bytes: &'a [u8], path: &Path) -> Result<&'a str, MeshIoError> {
    let mut lines = bytes.split(|&b| b == b'\n');
    let first = lines.next().unwrap_or_default();
    if !first.starts_with(b"# vtk DataFile Version") {
        return Err(bad(
            path,
            "the first line is not \"# vtk DataFile Version x.y\" (a .vtp or .vtu XML file \
             needs its own extension)",
        ));
    }
    let _title = lines.next();
    let enc = lines.next().map(|l| l.trim_ascii().to_ascii_uppercase());
    match enc.as_deref() {
        Some(b"ASCII") => {}
        Some(b"BINARY") => {
            return Err(bad(
                path,
                "a BINARY legacy VTK file; only ASCII is read: convert it (e.g. meshio: \
                 `meshio.write(OUT, meshio.read(IN), binary=False)`) or use .vtp",
            ));
        }
        None => {
            return Err(MeshIoError::Truncated {
                path: path.to_owned(),
                detail: "the header ends before ASCII/BINARY".into(),
            });
        }
        Some(other) => {
            return Err(bad(
                path,
                format!(
                    "line 3 is {:?}, expected ASCII or BINARY",
                    String::from_utf8_lossy(other)
                ),
            ));
        }
    }
    let header_len: usize = bytes
        .split_inclusive(|&b| b == b'\n')
        .take(3)
        .map(<[u8]>::len)
        .sum();
    std::str::from_utf8(&bytes[header_len..])
        .map_err(|_| bad(path, "the ASCII body is not UTF-8 text"))
}

/// Read ASCII legacy VTK (see the module documentation).
pub(crate) fn read(bytes: &[u8], path: &Path) -> Result<TriMesh, MeshIoError> {
    let text = body(bytes, path)?;
    let toks = text
        .lines()
        .enumerate()
        .flat_map(|(i, l)| l.split_whitespace().map(move |t| (i + 4, t)))
        .collect();
    let mut t = Tokens { toks, at: 0, path };
    let (line, kw) = t.next("DATASET")?;
    let (_, kind) = t.next("the dataset type")?;
    if !kw.eq_ignore_ascii_case("DATASET")
        || !(kind.eq_ignore_ascii_case("POLYDATA")
            || kind.eq_ignore_ascii_case("UNSTRUCTURED_GRID"))
    {
        return Err(bad(
            path,
            format!(
                "line {line}: \"{kw} {kind}\"; expected DATASET POLYDATA or DATASET \
                 UNSTRUCTURED_GRID"
            ),
        ));
    }
    let mut vertices = Vec::new();
    let mut cells: Option<Vec<Vec<i64>>> = None;
    let mut types: Option<Vec<i64>> = None;
    while let Some(kw) = t.peek() {
        let (line, _) = t.next("a section")?;
        match kw.to_ascii_uppercase().as_str() {
            "POINTS" => vertices = points(&mut t)?,
            "POLYGONS" | "CELLS" => cells = Some(cell_lists(&mut t, line)?),
            "CELL_TYPES" => {
                let n: usize = t.num("the CELL_TYPES count")?;
                types = Some(
                    (0..n)
                        .map(|_| t.num("a cell type"))
                        .collect::<Result<_, _>>()?,
                );
            }
            "CELL_DATA" | "POINT_DATA" => {
                t.at -= 1;
                attributes(&mut t)?;
            }
            "VERTICES" | "LINES" | "TRIANGLE_STRIPS" => {
                return Err(bad(
                    path,
                    format!("line {line}: {kw} cells; only polygons and triangles are read"),
                ));
            }
            _ => return Err(bad(path, format!("line {line}: unexpected keyword {kw:?}"))),
        }
    }
    let cells = cells.unwrap_or_default();
    if let Some(types) = &types {
        if types.len() != cells.len() {
            return Err(bad(
                path,
                format!("{} CELL_TYPES for {} CELLS", types.len(), cells.len()),
            ));
        }
        if let Some((i, ty)) = types.iter().enumerate().find(|(_, ty)| **ty != 5) {
            return Err(bad(
                path,
                format!(
                    "cell {i} has VTK cell type {ty}; only triangles (type 5) are read from an \
                     unstructured grid (extract the surface first)"
                ),
            ));
        }
    }
    let mut faces = FaceBuilder::default();
    for c in &cells {
        faces
            .push_polygon(c, vertices.len())
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

/// Skip the `CELL_DATA n` / `POINT_DATA n` sections, checking that each array holds all its
/// values (so a cut file is an error, not a mesh without its data).
fn attributes(t: &mut Tokens) -> Result<(), MeshIoError> {
    let mut n = 0usize;
    while let Some(kw) = t.peek() {
        let (line, _) = t.next("an attribute")?;
        let count = match kw.to_ascii_uppercase().as_str() {
            "CELL_DATA" | "POINT_DATA" => {
                n = t.num("the attribute count")?;
                continue;
            }
            "SCALARS" => {
                let _name = t.next("the array name")?;
                let _ty = t.next("the array type")?;
                let comps = match t.peek() {
                    Some(c) if c.parse::<usize>().is_ok() => t.num("the component count")?,
                    _ => 1usize,
                };
                if t.peek()
                    .is_some_and(|k| k.eq_ignore_ascii_case("LOOKUP_TABLE"))
                {
                    let _ = t.next("LOOKUP_TABLE")?;
                    let _ = t.next("the table name")?;
                }
                n * comps
            }
            "VECTORS" | "NORMALS" => {
                let _ = t.next("the array name")?;
                let _ = t.next("the array type")?;
                3 * n
            }
            "FIELD" => {
                let _ = t.next("the field name")?;
                let arrays: usize = t.num("the field's array count")?;
                for _ in 0..arrays {
                    let _ = t.next("the array name")?;
                    let comps: usize = t.num("the component count")?;
                    let tuples: usize = t.num("the tuple count")?;
                    let _ = t.next("the array type")?;
                    for _ in 0..comps.saturating_mul(tuples) {
                        let _: f64 = t.num("an array value")?;
                    }
                }
                0
            }
            _ => {
                return Err(bad(
                    t.path,
                    format!("line {line}: unexpected keyword {kw:?} in the data attributes"),
                ));
            }
        };
        for _ in 0..count {
            let _: f64 = t.num("an attribute value")?;
        }
    }
    Ok(())
}

fn points(t: &mut Tokens) -> Result<Vec<DVec3>, MeshIoError> {
    let n: usize = t.num("the POINTS count")?;
    let (line, ty) = t.next("the POINTS data type")?;
    if !["float", "double"].contains(&ty.to_ascii_lowercase().as_str()) {
        return Err(bad(
            t.path,
            format!("line {line}: POINTS of type {ty:?}; expected float or double"),
        ));
    }
    let mut v = Vec::with_capacity(n.min(1 << 24));
    for _ in 0..n {
        let x = t.num("a coordinate")?;
        let y = t.num("a coordinate")?;
        let z = t.num("a coordinate")?;
        v.push(DVec3::new(x, y, z));
    }
    Ok(v)
}

/// `m size` then `n i1 .. in` per cell, or (5.x) `m+1 size` then `OFFSETS` and `CONNECTIVITY`.
fn cell_lists(t: &mut Tokens, line: usize) -> Result<Vec<Vec<i64>>, MeshIoError> {
    let m: usize = t.num("the cell count")?;
    let size: usize = t.num("the cell list size")?;
    if t.peek().is_some_and(|k| k.eq_ignore_ascii_case("OFFSETS")) {
        let _ = t.next("OFFSETS")?;
        let _ty = t.next("the OFFSETS type")?;
        let offsets: Vec<usize> = (0..m)
            .map(|_| t.num("an offset"))
            .collect::<Result<_, _>>()?;
        let (l, kw) = t.next("CONNECTIVITY")?;
        if !kw.eq_ignore_ascii_case("CONNECTIVITY") {
            return Err(bad(
                t.path,
                format!("line {l}: expected CONNECTIVITY, found {kw:?}"),
            ));
        }
        let _ty = t.next("the CONNECTIVITY type")?;
        let conn: Vec<i64> = (0..size)
            .map(|_| t.num("an index"))
            .collect::<Result<_, _>>()?;
        let ok = offsets.first() == Some(&0)
            && offsets.windows(2).all(|w| w[0] <= w[1])
            && offsets.last() == Some(&conn.len());
        if !ok {
            return Err(bad(
                t.path,
                format!("line {line}: OFFSETS do not go from 0 up to the CONNECTIVITY length"),
            ));
        }
        return Ok(offsets
            .windows(2)
            .map(|w| conn[w[0]..w[1]].to_vec())
            .collect());
    }
    let mut cells = Vec::with_capacity(m.min(1 << 24));
    let mut used = 0usize;
    for _ in 0..m {
        let n: usize = t.num("a cell size")?;
        used += n + 1;
        if used > size {
            return Err(bad(
                t.path,
                format!("line {line}: the cells hold more than the declared size {size}"),
            ));
        }
        cells.push(
            (0..n)
                .map(|_| t.num("an index"))
                .collect::<Result<_, _>>()?,
        );
    }
    if used != size {
        return Err(bad(
            t.path,
            format!("line {line}: the cells hold {used} numbers but the header says {size}"),
        ));
    }
    Ok(cells)
}
