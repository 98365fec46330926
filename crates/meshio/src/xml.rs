//! The XML side of `.vtp` and `.gii` (ours: file format support): parsing with `roxmltree`,
//! base64, and typed numeric arrays, with errors naming the file and the element.

use std::path::Path;

use crate::{Format, MeshIoError};

/// Numbers of one data array, as f64 (exact for every f32, every f64 and integers up to 2^53).
pub(crate) struct Array {
    pub values: Vec<f64>,
}

impl Array {
    /// The values as integers; an error if one is not a whole number.
    pub fn integers(&self, path: &Path, format: Format) -> Result<Vec<i64>, MeshIoError> {
        self.values
            .iter()
            .map(|&v| {
                if v.fract() == 0.0 && v.abs() < 9.0e15 {
                    Ok(v as i64)
                } else {
                    Err(MeshIoError::not_a_mesh(
                        path,
                        format,
                        format!("index {v} is not a whole number"),
                    ))
                }
            })
            .collect()
    }
}

pub(crate) fn text<'a>(
    bytes: &'a [u8],
    path: &Path,
    format: Format,
) -> Result<&'a str, MeshIoError> {
    std::str::from_utf8(bytes)
        .map_err(|_| MeshIoError::not_a_mesh(path, format, "the file is not UTF-8 XML text"))
}

pub(crate) fn parse<'a>(
    text: &'a str,
    path: &Path,
    format: Format,
) -> Result<roxmltree::Document<'a>, MeshIoError> {
    let opts = roxmltree::ParsingOptions {
        allow_dtd: true,
        ..Default::default()
    };
    roxmltree::Document::parse_with_options(text, opts).map_err(|e| {
        let s = e.to_string();
        if s.contains("unexpected end of stream") {
            MeshIoError::Truncated {
                path: path.to_owned(),
                detail: format!("the XML ends early ({s})"),
            }
        } else {
            MeshIoError::not_a_mesh(path, format, format!("not well-formed XML ({s})"))
        }
    })
}

/// Decode standard base64 (white space ignored, `=` padding optional).
pub(crate) fn base64(s: &str) -> Option<Vec<u8>> {
    let mut out = Vec::with_capacity(s.len() / 4 * 3);
    let (mut acc, mut bits) = (0u32, 0u32);
    for c in s.bytes() {
        let v = match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            b'=' | b' ' | b'\n' | b'\r' | b'\t' => continue,
            _ => return None,
        };
        acc = (acc << 6) | v as u32;
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
            acc &= (1 << bits) - 1;
        }
    }
    Some(out)
}

/// Encode standard base64 with padding.
pub(crate) fn base64_encode(b: &[u8]) -> String {
    const T: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::with_capacity(b.len().div_ceil(3) * 4);
    for c in b.chunks(3) {
        let n = (c[0] as u32) << 16
            | (*c.get(1).unwrap_or(&0) as u32) << 8
            | *c.get(2).unwrap_or(&0) as u32;
        for k in 0..4 {
            if k <= c.len() {
                s.push(T[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

/// A numeric type: byte size, and whether it is a float / signed integer.
#[derive(Clone, Copy)]
pub(crate) enum Num {
    F32,
    F64,
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    I64,
    U64,
}

impl Num {
    pub fn vtk(name: &str) -> Option<Num> {
        Some(match name {
            "Float32" => Num::F32,
            "Float64" => Num::F64,
            "Int8" => Num::I8,
            "UInt8" => Num::U8,
            "Int16" => Num::I16,
            "UInt16" => Num::U16,
            "Int32" => Num::I32,
            "UInt32" => Num::U32,
            "Int64" => Num::I64,
            "UInt64" => Num::U64,
            _ => return None,
        })
    }
    pub fn size(self) -> usize {
        match self {
            Num::I8 | Num::U8 => 1,
            Num::I16 | Num::U16 => 2,
            Num::F32 | Num::I32 | Num::U32 => 4,
            Num::F64 | Num::I64 | Num::U64 => 8,
        }
    }
    /// Decode packed values (`big`: big-endian); `b.len()` must be a multiple of the size.
    pub fn decode(self, b: &[u8], big: bool) -> Vec<f64> {
        b.chunks_exact(self.size())
            .map(|c| {
                let mut a = [0u8; 8];
                a[..c.len()].copy_from_slice(c);
                if big {
                    a[..c.len()].reverse();
                }
                match self {
                    Num::F32 => f32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
                    Num::F64 => f64::from_le_bytes(a),
                    Num::I8 => a[0] as i8 as f64,
                    Num::U8 => a[0] as f64,
                    Num::I16 => i16::from_le_bytes([a[0], a[1]]) as f64,
                    Num::U16 => u16::from_le_bytes([a[0], a[1]]) as f64,
                    Num::I32 => i32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
                    Num::U32 => u32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
                    Num::I64 => i64::from_le_bytes(a) as f64,
                    Num::U64 => u64::from_le_bytes(a) as f64,
                }
            })
            .collect()
    }
}

/// Whitespace-separated decimal numbers of an element's text.
pub(crate) fn ascii_numbers(
    s: &str,
    path: &Path,
    format: Format,
    what: &str,
) -> Result<Vec<f64>, MeshIoError> {
    s.split_ascii_whitespace()
        .map(|t| {
            t.parse::<f64>().map_err(|_| {
                MeshIoError::not_a_mesh(path, format, format!("{what}: {t:?} is not a number"))
            })
        })
        .collect()
}

/// A VTK `<DataArray>`: `ascii`, or inline base64 `binary` (a byte-count header then the data).
pub(crate) fn vtk_array(
    node: roxmltree::Node,
    path: &Path,
    format: Format,
    big: bool,
    header64: bool,
) -> Result<Array, MeshIoError> {
    let name = node.attribute("Name").unwrap_or("(unnamed)");
    let what = format!("DataArray {name}");
    let ty = node.attribute("type").unwrap_or("");
    let num = Num::vtk(ty).ok_or_else(|| {
        MeshIoError::not_a_mesh(path, format, format!("{what} has unknown type {ty:?}"))
    })?;
    let body = node.text().unwrap_or("");
    match node.attribute("format").unwrap_or("ascii") {
        "ascii" => Ok(Array {
            values: ascii_numbers(body, path, format, &what)?,
        }),
        "binary" => {
            let b = base64(body).ok_or_else(|| {
                MeshIoError::not_a_mesh(path, format, format!("{what}: invalid base64 data"))
            })?;
            let h = if header64 { 8 } else { 4 };
            if b.len() < h {
                return Err(MeshIoError::Truncated {
                    path: path.to_owned(),
                    detail: format!("{what}: the binary block has no length header"),
                });
            }
            let len = Num::U64.decode(&pad(&b[..h], big), big)[0] as usize;
            let data = &b[h..];
            if data.len() < len || !len.is_multiple_of(num.size()) {
                return Err(MeshIoError::Truncated {
                    path: path.to_owned(),
                    detail: format!("{what}: the header says {len} bytes, {} follow", data.len()),
                });
            }
            Ok(Array {
                values: num.decode(&data[..len], big),
            })
        }
        other => Err(MeshIoError::not_a_mesh(
            path,
            format,
            format!(
                "{what} has format=\"{other}\"; only ascii and inline binary are read (ParaView: \
                 save with Data Mode ascii)"
            ),
        )),
    }
}

/// A 4- or 8-byte header widened to 8 bytes in its byte order.
fn pad(h: &[u8], big: bool) -> Vec<u8> {
    let mut v = vec![0u8; 8 - h.len()];
    if big {
        v.extend_from_slice(h);
        v
    } else {
        let mut w = h.to_vec();
        w.extend(v);
        w
    }
}
