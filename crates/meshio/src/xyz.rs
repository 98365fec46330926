//! `.xyz` point files (ours), the one strict reader of the workspace: one point per line,
//! `x y z` or `x y z nx ny nz`, separated by spaces, tabs or commas. Blank lines and lines
//! starting with `#` or `//` are skipped. Every data line must have the same number of
//! columns (3 or 6), every value must be a finite number, and there must be at least one
//! point; each error names the file and the line (1-based).

use glam::DVec3;
use std::io::BufRead;
use std::path::{Path, PathBuf};

use crate::PointCloud;

/// Errors reading an `.xyz` file. Every variant names the file (`path`) and, for a bad
/// line, its 1-based number (`line`) and 1-based `column`.
#[derive(Debug, thiserror::Error)]
#[allow(missing_docs)] // the fields are named by the messages
pub enum XyzError {
    /// The file could not be opened or read.
    #[error("{path}: cannot read: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// A line has neither 3 nor 6 values.
    #[error(
        "{path}:{line}: expected 3 (x y z) or 6 (x y z nx ny nz) numbers, found {found}; fix \
         that line"
    )]
    Columns {
        path: PathBuf,
        line: usize,
        found: usize,
    },
    /// A line's column count differs from the first data line's.
    #[error(
        "{path}:{line}: {found} columns, but the first data line had {expected}; every line must \
         have the same columns"
    )]
    Inconsistent {
        path: PathBuf,
        line: usize,
        found: usize,
        expected: usize,
    },
    /// A value is not a number.
    #[error("{path}:{line}: column {column} is `{text}`, not a number; fix that value")]
    Number {
        path: PathBuf,
        line: usize,
        column: usize,
        text: String,
    },
    /// A value is infinite or NaN.
    #[error("{path}:{line}: column {column} is {value}, not finite; fix that value")]
    NonFinite {
        path: PathBuf,
        line: usize,
        column: usize,
        value: f64,
    },
    /// No data line.
    #[error("{path}: no points (the file is empty or only has comments); give x y z lines")]
    Empty { path: PathBuf },
}

/// Read an `.xyz` file (see the module docs for the format).
pub fn read_xyz(path: impl AsRef<Path>) -> Result<PointCloud, XyzError> {
    let path = path.as_ref();
    let f = std::fs::File::open(path).map_err(|source| XyzError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    read_xyz_from(std::io::BufReader::new(f), path)
}

/// Read `.xyz` text from any reader; `path` is only used in error messages.
///
/// ```
/// use meshio::xyz::read_xyz_from;
/// let c = read_xyz_from("# x y z nx ny nz\n0 0 1 0 0 1\n1 0 0 1 0 0\n".as_bytes(), "a.xyz")
///     .unwrap();
/// assert_eq!(c.points.len(), 2);
/// assert_eq!(c.normals.unwrap()[1].x, 1.0);
/// let e = read_xyz_from("0 0 0\n1 2\n".as_bytes(), "b.xyz").unwrap_err();
/// assert_eq!(e.to_string(), "b.xyz:2: expected 3 (x y z) or 6 (x y z nx ny nz) numbers, found 2; fix that line");
/// ```
pub fn read_xyz_from(reader: impl BufRead, path: impl AsRef<Path>) -> Result<PointCloud, XyzError> {
    let path = path.as_ref();
    let mut points = Vec::new();
    let mut normals = Vec::new();
    let mut cols = 0usize;
    let mut vals = Vec::with_capacity(6);
    for (ln, line) in reader.lines().enumerate() {
        let line_no = ln + 1;
        let line = line.map_err(|source| XyzError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let t = line.trim();
        if t.is_empty() || t.starts_with('#') || t.starts_with("//") {
            continue;
        }
        vals.clear();
        for (c, tok) in t
            .split(|ch: char| ch.is_whitespace() || ch == ',')
            .filter(|s| !s.is_empty())
            .enumerate()
        {
            let v: f64 = tok.parse().map_err(|_| XyzError::Number {
                path: path.to_path_buf(),
                line: line_no,
                column: c + 1,
                text: tok.to_string(),
            })?;
            if !v.is_finite() {
                return Err(XyzError::NonFinite {
                    path: path.to_path_buf(),
                    line: line_no,
                    column: c + 1,
                    value: v,
                });
            }
            vals.push(v);
        }
        if vals.len() != 3 && vals.len() != 6 {
            return Err(XyzError::Columns {
                path: path.to_path_buf(),
                line: line_no,
                found: vals.len(),
            });
        }
        if cols == 0 {
            cols = vals.len();
        } else if vals.len() != cols {
            return Err(XyzError::Inconsistent {
                path: path.to_path_buf(),
                line: line_no,
                found: vals.len(),
                expected: cols,
            });
        }
        points.push(DVec3::new(vals[0], vals[1], vals[2]));
        if cols == 6 {
            normals.push(DVec3::new(vals[3], vals[4], vals[5]));
        }
    }
    if points.is_empty() {
        return Err(XyzError::Empty {
            path: path.to_path_buf(),
        });
    }
    Ok(PointCloud {
        points,
        normals: (cols == 6).then_some(normals),
    })
}
