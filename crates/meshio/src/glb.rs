//! glTF 2.0 binary, `.glb` (ours: file format support). One mesh, one triangle primitive:
//! `POSITION` as `FLOAT` `VEC3` (glTF has no double-precision positions, so coordinates are
//! rounded to f32) and `UNSIGNED_INT` indices, in one buffer after the JSON chunk.
//! Coordinates are written as they are (glTF's metres and +Y up are a convention of the
//! viewer; no axis is swapped).
//!
//! The reader takes every triangle primitive (`mode` 4, the default) of every mesh, with
//! `FLOAT` `VEC3` positions (any `byteStride`) and `UNSIGNED_BYTE/SHORT/INT` indices or none,
//! and refuses what it would misplace: a node with a transform (`matrix`, `translation`,
//! `rotation`, `scale`), sparse accessors, external buffers, and data outside the BIN chunk.

use std::io::Write;
use std::path::Path;

use glam::DVec3;
use serde_json::Value;

use crate::{Format, MeshIoError, TriMesh};

const MAGIC: &[u8; 4] = b"glTF";
const CHUNK_JSON: u32 = 0x4E4F_534A;
const CHUNK_BIN: u32 = 0x004E_4942;
const FLOAT: u64 = 5126;

/// Write `mesh` as glTF binary (coordinates must be finite as f32: checked by the caller).
pub(crate) fn write<W: Write>(w: &mut W, mesh: &TriMesh) -> std::io::Result<()> {
    let n = mesh.vertices.len();
    let m = mesh.triangles.len();
    let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
    let mut bin = Vec::with_capacity(12 * (n + m));
    for v in &mesh.vertices {
        for (k, c) in v.to_array().into_iter().enumerate() {
            let c = c as f32;
            lo[k] = lo[k].min(c);
            hi[k] = hi[k].max(c);
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    for t in &mesh.triangles {
        for i in t {
            bin.extend_from_slice(&i.to_le_bytes());
        }
    }
    if n == 0 {
        (lo, hi) = ([0.0; 3], [0.0; 3]);
    }
    let arr = |a: [f32; 3]| format!("[{},{},{}]", a[0], a[1], a[2]);
    let json = format!(
        concat!(
            r#"{{"asset":{{"version":"2.0","generator":"rdt-mesher meshio"}},"scene":0,"#,
            r#""scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],"#,
            r#""meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1,"mode":4}}]}}],"#,
            r#""accessors":[{{"bufferView":0,"componentType":5126,"count":{n},"type":"VEC3","min":{lo},"max":{hi}}},"#,
            r#"{{"bufferView":1,"componentType":5125,"count":{i},"type":"SCALAR"}}],"#,
            r#""bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":{pv},"target":34962}},"#,
            r#"{{"buffer":0,"byteOffset":{pv},"byteLength":{pi},"target":34963}}],"#,
            r#""buffers":[{{"byteLength":{b}}}]}}"#
        ),
        n = n,
        lo = arr(lo),
        hi = arr(hi),
        i = 3 * m,
        pv = 12 * n,
        pi = 12 * m,
        b = bin.len()
    );
    let mut json = json.into_bytes();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    // `bin` is a multiple of 4 bytes (f32 and u32 entries).
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let total = u32::try_from(total).map_err(|_| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "the mesh is over 4 GiB, more than a .glb holds: write .ply instead",
        )
    })?;
    w.write_all(MAGIC)?;
    w.write_all(&2u32.to_le_bytes())?;
    w.write_all(&total.to_le_bytes())?;
    w.write_all(&(json.len() as u32).to_le_bytes())?;
    w.write_all(&CHUNK_JSON.to_le_bytes())?;
    w.write_all(&json)?;
    w.write_all(&(bin.len() as u32).to_le_bytes())?;
    w.write_all(&CHUNK_BIN.to_le_bytes())?;
    w.write_all(&bin)
}

/// A reading context: the file name, the JSON and the BIN chunk.
struct Glb<'a> {
    path: &'a Path,
    json: Value,
    bin: &'a [u8],
}

fn bad(path: &Path, reason: impl Into<String>) -> MeshIoError {
    MeshIoError::not_a_mesh(path, Format::Glb, reason)
}

fn truncated(path: &Path, detail: impl Into<String>) -> MeshIoError {
    MeshIoError::Truncated {
        path: path.to_owned(),
        detail: detail.into(),
    }
}

fn u32_at(b: &[u8], i: usize) -> u32 {
    u32::from_le_bytes(b[i..i + 4].try_into().expect("4 bytes"))
}

/// Split the file into its JSON value and BIN chunk, checking the header and chunk lengths.
fn chunks<'a>(bytes: &'a [u8], path: &'a Path) -> Result<Glb<'a>, MeshIoError> {
    if bytes.len() < 12 || &bytes[..4] != MAGIC {
        if bytes.len() >= 4 && &bytes[..4] == MAGIC {
            return Err(truncated(path, "the 12-byte glb header is cut"));
        }
        return Err(bad(
            path,
            "the file does not start with the magic \"glTF\" (a .gltf JSON file with separate \
             buffers is not read: convert it to .glb)",
        ));
    }
    let version = u32_at(bytes, 4);
    if version != 2 {
        return Err(bad(
            path,
            format!("glb version {version}; only glTF 2.0 is read"),
        ));
    }
    let total = u32_at(bytes, 8) as usize;
    if bytes.len() < total {
        return Err(truncated(
            path,
            format!(
                "the header says {total} bytes, the file has {}",
                bytes.len()
            ),
        ));
    }
    let body = &bytes[..total];
    let (mut json, mut bin) = (None, None);
    let mut at = 12;
    while at < body.len() {
        if at + 8 > body.len() {
            return Err(truncated(
                path,
                format!("a chunk header at byte {at} is cut"),
            ));
        }
        let (len, kind) = (u32_at(body, at) as usize, u32_at(body, at + 4));
        let data = body.get(at + 8..at + 8 + len).ok_or_else(|| {
            truncated(path, format!("the chunk at byte {at} ({len} bytes) is cut"))
        })?;
        match kind {
            CHUNK_JSON if json.is_none() => json = Some(data),
            CHUNK_BIN if bin.is_none() => bin = Some(data),
            _ => {}
        }
        at += 8 + len;
    }
    let json = json.ok_or_else(|| bad(path, "there is no JSON chunk"))?;
    let json: Value = serde_json::from_slice(json)
        .map_err(|e| bad(path, format!("the JSON chunk is not valid JSON ({e})")))?;
    Ok(Glb {
        path,
        json,
        bin: bin.unwrap_or(&[]),
    })
}

impl Glb<'_> {
    fn get(&self, list: &str, i: u64) -> Result<&Value, MeshIoError> {
        self.json
            .get(list)
            .and_then(|l| l.get(i as usize))
            .ok_or_else(|| bad(self.path, format!("{list}[{i}] is referenced but missing")))
    }

    fn uint(&self, v: &Value, field: &str, what: &str) -> Result<u64, MeshIoError> {
        v.get(field).and_then(Value::as_u64).ok_or_else(|| {
            bad(
                self.path,
                format!("{what}: {field} is missing or not a whole number"),
            )
        })
    }

    /// The bytes of accessor `a`: (data from its first element, stride, count).
    fn accessor(&self, a: u64, elem: usize) -> Result<(&[u8], usize, usize), MeshIoError> {
        let what = format!("accessors[{a}]");
        let acc = self.get("accessors", a)?;
        if acc.get("sparse").is_some() {
            return Err(bad(
                self.path,
                format!("{what} is sparse; sparse accessors are not read"),
            ));
        }
        let count = self.uint(acc, "count", &what)? as usize;
        let view_i = self.uint(acc, "bufferView", &what)?;
        let view = self.get("bufferViews", view_i)?;
        let vwhat = format!("bufferViews[{view_i}]");
        let buffer = self.uint(view, "buffer", &vwhat)?;
        if buffer != 0 || self.get("buffers", 0)?.get("uri").is_some() {
            return Err(bad(
                self.path,
                format!("{vwhat} uses an external buffer; only the glb's own BIN chunk is read"),
            ));
        }
        let off = view.get("byteOffset").and_then(Value::as_u64).unwrap_or(0) as usize
            + acc.get("byteOffset").and_then(Value::as_u64).unwrap_or(0) as usize;
        let len = self.uint(view, "byteLength", &vwhat)? as usize;
        let stride = view
            .get("byteStride")
            .and_then(Value::as_u64)
            .map_or(elem, |s| s as usize);
        let need = if count == 0 {
            0
        } else {
            (count - 1).saturating_mul(stride).saturating_add(elem)
        };
        let view_start = view.get("byteOffset").and_then(Value::as_u64).unwrap_or(0) as usize;
        let end = off.saturating_add(need);
        if end > view_start.saturating_add(len) || end > self.bin.len() {
            return Err(truncated(
                self.path,
                format!(
                    "{what} needs bytes up to {end} but the BIN chunk has {}",
                    self.bin.len()
                ),
            ));
        }
        Ok((&self.bin[off..end], stride, count))
    }

    fn positions(&self, a: u64) -> Result<Vec<DVec3>, MeshIoError> {
        let acc = self.get("accessors", a)?;
        let kind = acc.get("type").and_then(Value::as_str).unwrap_or("");
        let ct = acc
            .get("componentType")
            .and_then(Value::as_u64)
            .unwrap_or(0);
        if kind != "VEC3" || ct != FLOAT {
            return Err(bad(
                self.path,
                format!(
                    "accessors[{a}] (POSITION) is {kind} of componentType {ct}; positions must \
                     be VEC3 of FLOAT (5126)"
                ),
            ));
        }
        let (data, stride, count) = self.accessor(a, 12)?;
        let f = |i: usize| f32::from_le_bytes(data[i..i + 4].try_into().expect("4 bytes")) as f64;
        Ok((0..count)
            .map(|k| DVec3::new(f(k * stride), f(k * stride + 4), f(k * stride + 8)))
            .collect())
    }

    fn indices(&self, a: u64) -> Result<Vec<u64>, MeshIoError> {
        let acc = self.get("accessors", a)?;
        let ct = acc
            .get("componentType")
            .and_then(Value::as_u64)
            .unwrap_or(0);
        let size = match ct {
            5121 => 1,
            5123 => 2,
            5125 => 4,
            _ => {
                return Err(bad(
                    self.path,
                    format!(
                        "accessors[{a}] (indices) has componentType {ct}; indices must be \
                         UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT"
                    ),
                ));
            }
        };
        let (data, stride, count) = self.accessor(a, size)?;
        Ok((0..count)
            .map(|k| {
                let b = &data[k * stride..k * stride + size];
                b.iter().rev().fold(0u64, |acc, &x| (acc << 8) | x as u64)
            })
            .collect())
    }
}

/// Read a `.glb` (see the module documentation for what is accepted).
pub(crate) fn read(bytes: &[u8], path: &Path) -> Result<TriMesh, MeshIoError> {
    let g = chunks(bytes, path)?;
    for (i, node) in g
        .json
        .get("nodes")
        .and_then(Value::as_array)
        .into_iter()
        .flatten()
        .enumerate()
    {
        if ["matrix", "translation", "rotation", "scale"]
            .iter()
            .any(|k| node.get(k).is_some())
        {
            return Err(bad(
                path,
                format!(
                    "nodes[{i}] has a transform; apply it to the vertices first (e.g. trimesh's \
                     `scene.to_geometry()`), so the coordinates are the world's"
                ),
            ));
        }
    }
    let mut mesh = TriMesh::default();
    let meshes = g.json.get("meshes").and_then(Value::as_array);
    for (mi, m) in meshes.into_iter().flatten().enumerate() {
        let prims = m.get("primitives").and_then(Value::as_array);
        for (pi, p) in prims.into_iter().flatten().enumerate() {
            let what = format!("meshes[{mi}].primitives[{pi}]");
            let mode = p.get("mode").and_then(Value::as_u64).unwrap_or(4);
            if mode != 4 {
                return Err(bad(
                    path,
                    format!("{what} has mode {mode}; only triangles (mode 4) are read"),
                ));
            }
            let pos = p
                .get("attributes")
                .and_then(|a| a.get("POSITION"))
                .and_then(Value::as_u64)
                .ok_or_else(|| bad(path, format!("{what} has no POSITION attribute")))?;
            let verts = g.positions(pos)?;
            let idx = match p.get("indices").and_then(Value::as_u64) {
                Some(a) => g.indices(a)?,
                None => (0..verts.len() as u64).collect(),
            };
            if !idx.len().is_multiple_of(3) {
                return Err(bad(
                    path,
                    format!("{what} has {} indices, not a multiple of 3", idx.len()),
                ));
            }
            let base = mesh.vertices.len() as u64;
            for (f, t) in idx.chunks_exact(3).enumerate() {
                if let Some(&i) = t.iter().find(|&&i| i >= verts.len() as u64) {
                    return Err(bad(
                        path,
                        format!(
                            "{what} triangle {f} uses vertex {i} but POSITION has {} vertices",
                            verts.len()
                        ),
                    ));
                }
                let tri = [t[0] + base, t[1] + base, t[2] + base];
                let tri = tri.map(|i| u32::try_from(i).unwrap_or(u32::MAX));
                mesh.triangles.push(tri);
            }
            mesh.vertices.extend(verts);
        }
    }
    crate::check_vertex_coords(path, &mesh.vertices)?;
    Ok(mesh)
}
