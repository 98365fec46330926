//! Triangle meshes and their file formats (PLY ASCII/binary, OFF, OBJ, STL ASCII/binary,
//! glTF binary `.glb`, VTK legacy `.vtk`, VTK XML `.vtp`, GIFTI `.gii`).
//!
//! The format is chosen from the file extension ([`Format::from_path`]). Every reader checks
//! what it returns ([`TriMesh::validate`]): indices in range, finite coordinates. Polygons are
//! fan-triangulated. Errors name the file, what is wrong and how to fix it. The VTK formats
//! also carry per-facet values ([`CellData`], see [`write_with_cell_data`]); glTF and GIFTI
//! store f32 coordinates.
//!
//! ```
//! use glam::DVec3;
//! use meshio::{Format, Options, TriMesh};
//! let mesh = TriMesh {
//!     vertices: vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z],
//!     triangles: vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
//! };
//! let path = std::env::temp_dir().join(format!("meshio-doc-{}.ply", std::process::id()));
//! meshio::write(&path, &mesh).unwrap(); // binary little-endian, double coordinates
//! assert_eq!(meshio::read(&path).unwrap(), mesh);
//! meshio::write_with(&path, &mesh, Format::Ply, Options { binary: false, ..Options::default() })
//!     .unwrap();
//! assert_eq!(meshio::read(&path).unwrap(), mesh);
//! std::fs::remove_file(&path).unwrap();
//! ```

#![forbid(unsafe_code)]

use std::fmt;
use std::io::{BufRead, BufReader, BufWriter, Write};
use std::path::{Path, PathBuf};

use glam::DVec3;

mod gii;
mod glb;
mod obj;
mod off;
mod ply;
mod stl;
mod vtk;
mod vtp;
mod xml;
pub mod xyz;

pub use xyz::{XyzError, read_xyz, read_xyz_from};

/// An indexed triangle mesh. Invariant (when produced by the mesher): every index is
/// `< vertices.len()`; triangles are counter-clockwise seen from outside.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriMesh {
    pub vertices: Vec<DVec3>,
    pub triangles: Vec<[u32; 3]>,
}

/// A point set, with normals if the file has `nx ny nz` for every point: the one point-cloud
/// type of the workspace (read by [`read_point_cloud`] and [`read_xyz`], consumed by
/// `oracle::pointset`, which re-exports it). It lives here, next to [`TriMesh`], as the data
/// the readers return; the kernel crate `geom` stays free of I/O types.
/// Invariant: `normals`, when present, has one entry per point.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PointCloud {
    /// The points.
    pub points: Vec<DVec3>,
    /// One normal per point, if the input had them (not necessarily unit length).
    pub normals: Option<Vec<DVec3>>,
}

/// What is wrong with an in-memory mesh (see [`TriMesh::validate`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum InvalidMesh {
    #[error(
        "face {face} uses vertex index {index} but there are only {num_vertices} vertices; \
         fix the face list or add the missing vertices"
    )]
    IndexOutOfRange {
        face: usize,
        index: i64,
        num_vertices: usize,
    },
    #[error(
        "vertex {vertex} has a non-finite coordinate ({x}, {y}, {z}); \
         remove or repair NaN/inf coordinates"
    )]
    NonFinite {
        vertex: usize,
        x: f64,
        y: f64,
        z: f64,
    },
    #[error("face {face} has only {len} vertices; every face needs at least 3")]
    ShortFace { face: usize, len: usize },
    #[error("there are {0} vertices, more than u32 indices can address; split the mesh")]
    TooManyVertices(usize),
    #[error(
        "vertex {vertex} has coordinate {value}, beyond the f32 range of this format; \
         write .ply (double precision) instead"
    )]
    BeyondF32 { vertex: usize, value: f64 },
    #[error(
        "there are {0} vertices, more than the format's signed 32-bit indices address; write \
         .ply instead"
    )]
    TooManyForI32(usize),
    #[error(
        "cell data {name:?} has {len} values for {facets} facets, or its name is not one word \
         of letters, digits and '_'; give one value per facet"
    )]
    BadCellData {
        name: String,
        len: usize,
        facets: usize,
    },
}

/// Errors of the readers and writers. Every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum MeshIoError {
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error(
        "{path}: {}; the mesh formats are .ply, .off, .obj, .stl, .glb, .vtk, .vtp and .gii \
         (any case): rename the file, or from Rust call meshio::read_with / meshio::write_with with an explicit \
         meshio::Format",
        if ext.is_empty() { "no file extension".to_string() } else { format!("unknown mesh file extension {ext:?}") }
    )]
    UnknownExtension { path: PathBuf, ext: String },
    #[error("{path}: the file is empty; expected a {format} mesh: re-export or re-download it")]
    Empty { path: PathBuf, format: Format },
    #[error(
        "{path}: not {} {format} mesh: {reason}; check that the file really is {format} \
         (the format is chosen from the extension)",
        article(&format.to_string())
    )]
    NotAMesh {
        path: PathBuf,
        format: Format,
        reason: String,
    },
    #[error(
        "{path}: the file is truncated ({detail}); the header promises more data than the file \
         holds: re-export or re-download it"
    )]
    Truncated { path: PathBuf, detail: String },
    #[error("{path}: the file has vertices but no faces; mesh it as a point set (--as points)")]
    NoFaces { path: PathBuf },
    #[error("{path}: {source}")]
    Invalid { path: PathBuf, source: InvalidMesh },
}

impl MeshIoError {
    fn io(path: &Path, source: std::io::Error) -> Self {
        if source.kind() == std::io::ErrorKind::UnexpectedEof {
            MeshIoError::Truncated {
                path: path.to_owned(),
                detail: source.to_string(),
            }
        } else {
            MeshIoError::Io {
                path: path.to_owned(),
                source,
            }
        }
    }
    fn not_a_mesh(path: &Path, format: Format, reason: impl Into<String>) -> Self {
        MeshIoError::NotAMesh {
            path: path.to_owned(),
            format,
            reason: reason.into(),
        }
    }
}

/// A mesh file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Format {
    Ply,
    Off,
    Obj,
    Stl,
    /// glTF 2.0 binary.
    Glb,
    /// VTK legacy (ASCII polydata).
    Vtk,
    /// VTK XML polydata.
    Vtp,
    /// GIFTI surface.
    Gii,
}

impl fmt::Display for Format {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Format::Ply => "PLY",
            Format::Off => "OFF",
            Format::Obj => "OBJ",
            Format::Stl => "STL",
            Format::Glb => "glTF binary (.glb)",
            Format::Vtk => "VTK legacy",
            Format::Vtp => "VTK XML PolyData",
            Format::Gii => "GIFTI",
        })
    }
}

impl Format {
    /// The format named by the file extension (case-insensitive).
    pub fn from_path(path: impl AsRef<Path>) -> Result<Format, MeshIoError> {
        let path = path.as_ref();
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .unwrap_or("")
            .to_ascii_lowercase();
        match ext.as_str() {
            "ply" => Ok(Format::Ply),
            "off" => Ok(Format::Off),
            "obj" => Ok(Format::Obj),
            "stl" => Ok(Format::Stl),
            "glb" => Ok(Format::Glb),
            "vtk" => Ok(Format::Vtk),
            "vtp" => Ok(Format::Vtp),
            "gii" => Ok(Format::Gii),
            _ => Err(MeshIoError::UnknownExtension {
                path: path.to_owned(),
                ext,
            }),
        }
    }
}

/// Writer options.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Options {
    /// Binary encoding (PLY little-endian, STL binary). Ignored by OFF and OBJ (text only).
    pub binary: bool,
    /// Write coordinates as f64 (`double`) rather than f32 (`float`). PLY only; binary STL is
    /// always f32 and text formats always print the shortest exact decimal of the f64
    /// (or of the f32 value when `double` is false).
    pub double: bool,
}

impl Default for Options {
    /// Binary, double precision: exact round trips for PLY.
    fn default() -> Self {
        Options {
            binary: true,
            double: true,
        }
    }
}

impl TriMesh {
    /// Check the invariants every reader guarantees: indices `< vertices.len()`, finite
    /// coordinates, at most `u32::MAX` vertices.
    pub fn validate(&self) -> Result<(), InvalidMesh> {
        if self.vertices.len() > u32::MAX as usize {
            return Err(InvalidMesh::TooManyVertices(self.vertices.len()));
        }
        for (i, v) in self.vertices.iter().enumerate() {
            if !v.is_finite() {
                return Err(InvalidMesh::NonFinite {
                    vertex: i,
                    x: v.x,
                    y: v.y,
                    z: v.z,
                });
            }
        }
        let n = self.vertices.len();
        for (f, t) in self.triangles.iter().enumerate() {
            for &i in t {
                if i as usize >= n {
                    return Err(InvalidMesh::IndexOutOfRange {
                        face: f,
                        index: i as i64,
                        num_vertices: n,
                    });
                }
            }
        }
        Ok(())
    }
}

/// Polygon faces collected by the readers before triangulation.
#[derive(Default)]
pub(crate) struct FaceBuilder {
    pub triangles: Vec<[u32; 3]>,
    pub num_faces: usize,
}

impl FaceBuilder {
    /// Fan-triangulate one polygon after checking its indices against `num_vertices`.
    pub fn push_polygon(&mut self, idx: &[i64], num_vertices: usize) -> Result<(), InvalidMesh> {
        let face = self.num_faces;
        self.num_faces += 1;
        if idx.len() < 3 {
            return Err(InvalidMesh::ShortFace {
                face,
                len: idx.len(),
            });
        }
        for &i in idx {
            if i < 0 || i as u64 >= num_vertices as u64 {
                return Err(InvalidMesh::IndexOutOfRange {
                    face,
                    index: i,
                    num_vertices,
                });
            }
        }
        for k in 1..idx.len() - 1 {
            self.triangles
                .push([idx[0] as u32, idx[k] as u32, idx[k + 1] as u32]);
        }
        Ok(())
    }
}

fn check_vertices(path: &Path, vertices: &[DVec3]) -> Result<(), MeshIoError> {
    if vertices.len() > u32::MAX as usize {
        return Err(MeshIoError::Invalid {
            path: path.to_owned(),
            source: InvalidMesh::TooManyVertices(vertices.len()),
        });
    }
    for (i, v) in vertices.iter().enumerate() {
        if !v.is_finite() {
            return Err(MeshIoError::Invalid {
                path: path.to_owned(),
                source: InvalidMesh::NonFinite {
                    vertex: i,
                    x: v.x,
                    y: v.y,
                    z: v.z,
                },
            });
        }
    }
    Ok(())
}

fn open(path: &Path, format: Format) -> Result<BufReader<std::fs::File>, MeshIoError> {
    let file = std::fs::File::open(path).map_err(|e| MeshIoError::io(path, e))?;
    let len = file.metadata().map_err(|e| MeshIoError::io(path, e))?.len();
    if len == 0 {
        return Err(MeshIoError::Empty {
            path: path.to_owned(),
            format,
        });
    }
    Ok(BufReader::with_capacity(1 << 16, file))
}

/// Read a triangle mesh; the format comes from the extension.
pub fn read(path: impl AsRef<Path>) -> Result<TriMesh, MeshIoError> {
    let path = path.as_ref();
    read_with(path, Format::from_path(path)?)
}

/// Read a triangle mesh in the given format.
pub fn read_with(path: impl AsRef<Path>, format: Format) -> Result<TriMesh, MeshIoError> {
    let path = path.as_ref();
    let reader = open(path, format)?;
    read_from(reader, format, path)
}

/// Read a triangle mesh from any buffered reader; `name` is used in error messages.
pub fn read_from<R: BufRead>(
    mut reader: R,
    format: Format,
    name: impl AsRef<Path>,
) -> Result<TriMesh, MeshIoError> {
    let path = name.as_ref();
    let mesh = match format {
        Format::Ply => ply::read(&mut reader, path)?,
        Format::Off => off::read(&mut reader, path)?,
        Format::Obj => obj::read(&mut reader, path)?,
        _ => {
            let mut bytes = Vec::new();
            reader
                .read_to_end(&mut bytes)
                .map_err(|e| MeshIoError::io(path, e))?;
            match format {
                Format::Stl => stl::read(&bytes, path)?,
                Format::Glb => glb::read(&bytes, path)?,
                Format::Vtk => vtk::read(&bytes, path)?,
                Format::Vtp => vtp::read(&bytes, path)?,
                _ => gii::read(&bytes, path)?,
            }
        }
    };
    if mesh.vertices.is_empty() && mesh.triangles.is_empty() {
        return Err(MeshIoError::Empty {
            path: path.to_owned(),
            format,
        });
    }
    if mesh.triangles.is_empty() {
        return Err(MeshIoError::NoFaces {
            path: path.to_owned(),
        });
    }
    validate_for(&mesh, path)?;
    Ok(mesh)
}

/// Read the vertices (and `nx ny nz` normals if present) of a PLY file, with or without faces.
pub fn read_point_cloud(path: impl AsRef<Path>) -> Result<PointCloud, MeshIoError> {
    let path = path.as_ref();
    let mut reader = open(path, Format::Ply)?;
    let (cloud, _) = ply::read_points_and_faces(&mut reader, path, false)?;
    if cloud.points.is_empty() {
        return Err(MeshIoError::Empty {
            path: path.to_owned(),
            format: Format::Ply,
        });
    }
    Ok(cloud)
}

/// Write a mesh; the format comes from the extension, with [`Options::default`]
/// (binary and double precision where the format allows it).
pub fn write(path: impl AsRef<Path>, mesh: &TriMesh) -> Result<(), MeshIoError> {
    let path = path.as_ref();
    write_with(path, mesh, Format::from_path(path)?, Options::default())
}

/// Write a mesh in the given format. The mesh is validated first.
pub fn write_with(
    path: impl AsRef<Path>,
    mesh: &TriMesh,
    format: Format,
    options: Options,
) -> Result<(), MeshIoError> {
    write_full(path.as_ref(), mesh, format, options, &[])
}

/// Write a mesh with per-facet values (the format from the extension, default options).
/// `.vtk` and `.vtp` store them as cell data; the other formats have no place for them and
/// write the mesh alone. Each [`CellData`] needs one value per triangle and a name of letters,
/// digits and `_`.
///
/// ```
/// use meshio::{CellData, TriMesh};
/// use glam::DVec3;
/// let mesh = TriMesh {
///     vertices: vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z],
///     triangles: vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
/// };
/// let q = CellData { name: "min_angle_deg".into(), values: vec![45.0, 45.0, 60.0, 45.0] };
/// let path = std::env::temp_dir().join(format!("meshio-doc-{}.vtk", std::process::id()));
/// meshio::write_with_cell_data(&path, &mesh, &[q]).unwrap();
/// assert!(std::fs::read_to_string(&path).unwrap().contains("SCALARS min_angle_deg double 1"));
/// assert_eq!(meshio::read(&path).unwrap(), mesh);
/// std::fs::remove_file(&path).unwrap();
/// ```
pub fn write_with_cell_data(
    path: impl AsRef<Path>,
    mesh: &TriMesh,
    cells: &[CellData],
) -> Result<(), MeshIoError> {
    let path = path.as_ref();
    write_full(
        path,
        mesh,
        Format::from_path(path)?,
        Options::default(),
        cells,
    )
}

fn write_full(
    path: &Path,
    mesh: &TriMesh,
    format: Format,
    options: Options,
    cells: &[CellData],
) -> Result<(), MeshIoError> {
    validate_for(mesh, path)?;
    let file = std::fs::File::create(path).map_err(|e| MeshIoError::io(path, e))?;
    let mut w = BufWriter::with_capacity(1 << 16, file);
    write_to_with(&mut w, mesh, format, options, cells, path)?;
    w.flush().map_err(|e| MeshIoError::io(path, e))
}

/// Per-facet values written as VTK cell data (e.g. the minimum angle, r/sigma).
#[derive(Clone, Debug, PartialEq)]
pub struct CellData {
    /// The array name: letters, digits and `_`.
    pub name: String,
    /// One value per triangle, in triangle order.
    pub values: Vec<f64>,
}

/// The checks of the f32 formats (glTF, GIFTI) and of the cell data.
fn check_for_format(mesh: &TriMesh, format: Format, cells: &[CellData]) -> Result<(), InvalidMesh> {
    if matches!(format, Format::Glb | Format::Gii) {
        for (i, v) in mesh.vertices.iter().enumerate() {
            if let Some(&value) = v.to_array().iter().find(|c| !(**c as f32).is_finite()) {
                return Err(InvalidMesh::BeyondF32 { vertex: i, value });
            }
        }
    }
    if format == Format::Gii && mesh.vertices.len() > i32::MAX as usize {
        return Err(InvalidMesh::TooManyForI32(mesh.vertices.len()));
    }
    for c in cells {
        let ok_name = !c.name.is_empty()
            && c.name
                .chars()
                .all(|ch| ch.is_ascii_alphanumeric() || ch == '_');
        if !ok_name || c.values.len() != mesh.triangles.len() {
            return Err(InvalidMesh::BadCellData {
                name: c.name.clone(),
                len: c.values.len(),
                facets: mesh.triangles.len(),
            });
        }
    }
    Ok(())
}

/// [`TriMesh::validate`], the error naming `path`.
fn validate_for(mesh: &TriMesh, path: &Path) -> Result<(), MeshIoError> {
    mesh.validate().map_err(|source| MeshIoError::Invalid {
        path: path.to_owned(),
        source,
    })
}

/// Write a mesh to any writer; `name` is used in error messages.
pub fn write_to<W: Write>(
    w: &mut W,
    mesh: &TriMesh,
    format: Format,
    options: Options,
    name: impl AsRef<Path>,
) -> Result<(), MeshIoError> {
    write_to_with(w, mesh, format, options, &[], name.as_ref())
}

/// [`write_to`] with cell data (see [`write_with_cell_data`]).
pub fn write_to_with<W: Write>(
    w: &mut W,
    mesh: &TriMesh,
    format: Format,
    options: Options,
    cells: &[CellData],
    name: impl AsRef<Path>,
) -> Result<(), MeshIoError> {
    let path = name.as_ref();
    validate_for(mesh, path)?;
    check_for_format(mesh, format, cells).map_err(|source| MeshIoError::Invalid {
        path: path.to_owned(),
        source,
    })?;
    let r = match format {
        Format::Ply => ply::write(w, mesh, options),
        Format::Off => off::write(w, mesh, options),
        Format::Obj => obj::write(w, mesh, options),
        Format::Stl => stl::write(w, mesh, options),
        Format::Glb => glb::write(w, mesh),
        Format::Vtk => vtk::write(w, mesh, cells),
        Format::Vtp => vtp::write(w, mesh, cells),
        Format::Gii => gii::write(w, mesh),
    };
    r.map_err(|e| MeshIoError::io(path, e))
}

/// Writes one text line `{prefix}x y z` of the point `v` (coordinates by [`fmt_coord`]).
pub(crate) fn write_point_line<W: std::io::Write>(
    w: &mut W,
    prefix: &str,
    v: DVec3,
    double: bool,
) -> std::io::Result<()> {
    let [x, y, z] = v.to_array().map(|c| fmt_coord(c, double));
    writeln!(w, "{prefix}{x} {y} {z}")
}

/// Writes the text vertex lines (`{vertex_prefix}x y z`) then the triangle lines
/// (`{face_prefix}i j k`, indices plus `base`) of `mesh`: the body of ASCII OFF, PLY and OBJ.
pub(crate) fn write_text_body<W: std::io::Write>(
    w: &mut W,
    mesh: &TriMesh,
    double: bool,
    (vertex_prefix, face_prefix, base): (&str, &str, u32),
) -> std::io::Result<()> {
    for &v in &mesh.vertices {
        write_point_line(w, vertex_prefix, v, double)?;
    }
    for t in &mesh.triangles {
        let [i, j, k] = t.map(|i| i + base);
        writeln!(w, "{face_prefix}{i} {j} {k}")?;
    }
    Ok(())
}

/// Shortest exact decimal of `x`, or of `x as f32` when `double` is false.
pub(crate) fn fmt_coord(x: f64, double: bool) -> String {
    if double {
        format!("{x}")
    } else {
        format!("{}", x as f32)
    }
}

/// `line` without its comment: a `#` at the start of the line or after white space starts
/// one. A `#` inside a token (`0.707#65`) does not, so the token is reported as bad instead of
/// being silently cut to `0.707`.
pub(crate) fn strip_comment(line: &str) -> &str {
    let mut prev_ws = true;
    for (i, c) in line.char_indices() {
        if c == '#' && prev_ws {
            return &line[..i];
        }
        prev_ws = c.is_whitespace();
    }
    line
}

/// Parse a decimal coordinate token.
pub(crate) fn parse_f64(tok: &str) -> Option<f64> {
    tok.parse::<f64>().ok()
}

pub(crate) use check_vertices as check_vertex_coords;

/// "an" before a format's initialism read letter by letter when its first letter's name
/// starts with a vowel sound (an OBJ, an STL, an OFF), else "a" (a PLY, a GLB).
fn article(name: &str) -> &'static str {
    match name.chars().next().map(|c| c.to_ascii_uppercase()) {
        Some('A' | 'E' | 'F' | 'H' | 'I' | 'L' | 'M' | 'N' | 'O' | 'R' | 'S' | 'X') => "an",
        _ => "a",
    }
}
