//! OME-Zarr volumes (ours: file format support; section 6.6.2 meshes them), read with the
//! `zarrs` crate from a local store, Zarr v2 (OME-NGFF 0.4 and earlier, `.zattrs`) or v3
//! (OME-NGFF 0.5, `zarr.json` `attributes.ome`).
//!
//! What is read: the first multiscale's level 0 (`datasets[0].path`), with its
//! `coordinateTransformations` (`scale`, then an optional `translation`) followed by the
//! multiscale's own, if any. Axes: the three `space` axes (named `x`, `y`, `z`, any order;
//! without names, the last three in `z, y, x` order); any other axis (`t`, `c`) must have
//! size 1. World coordinates are `index * scale + translation` along each axis, in the
//! axes' unit, taken as is (OME-Zarr has no anatomical frame and no rotation).
//!
//! A missing chunk is the array's fill value when the metadata defines one (Zarr v3 always
//! does; v2 unless `fill_value` is null), with a [`Volume::notes`] entry; with a null fill
//! value it is an error naming the chunk.

use super::orient::{self};
use super::{Dtype, ImageError, Volume};
use glam::{DAffine3, DMat3, DVec3};
use serde_json::Value;
use std::path::Path;
use std::sync::Arc;
use zarrs::array::{Array, DataType};
use zarrs::filesystem::FilesystemStore;
use zarrs::storage::ReadableStorageTraits;

const FMT: &str = "OME-Zarr";

fn err(path: &Path, field: &str, detail: impl Into<String>) -> ImageError {
    orient::field(path, FMT, field, detail)
}

/// Whether the folder is a Zarr group or array (v2 or v3 metadata present).
pub(crate) fn is_zarr(p: &Path) -> bool {
    ["zarr.json", ".zattrs", ".zgroup", ".zarray"]
        .iter()
        .any(|f| p.join(f).is_file())
}

fn json(path: &Path, file: &Path) -> Result<Value, ImageError> {
    let b = orient::read(file)?;
    serde_json::from_slice(&b).map_err(|e| {
        err(
            path,
            &file
                .file_name()
                .map(|f| f.to_string_lossy().into_owned())
                .unwrap_or_default(),
            format!("is not valid JSON ({e}); the store is damaged"),
        )
    })
}

/// The group's `multiscales` list and the Zarr version (2 or 3).
fn multiscales(path: &Path) -> Result<(Value, u8), ImageError> {
    let v3 = path.join("zarr.json");
    let (attrs, version) = if v3.is_file() {
        let j = json(path, &v3)?;
        let a = j.get("attributes").cloned().unwrap_or(Value::Null);
        (a.get("ome").cloned().unwrap_or(a), 3)
    } else if path.join(".zattrs").is_file() {
        (json(path, &path.join(".zattrs"))?, 2)
    } else {
        return Err(err(
            path,
            ".zattrs / zarr.json",
            "is missing: not an OME-Zarr image group (give the folder that holds the multiscales \
             metadata, e.g. image.ome.zarr)",
        ));
    };
    let ms = attrs
        .get("multiscales")
        .and_then(|m| m.get(0))
        .cloned()
        .ok_or_else(|| {
            err(
                path,
                "multiscales",
                "is missing from the group attributes: not an OME-Zarr image (a plain Zarr \
                 array has no voxel size; write it with ome-zarr-py)",
            )
        })?;
    Ok((ms, version))
}

/// Per-axis `x -> a x + b` from a list of coordinate transformations.
fn transforms(
    path: &Path,
    list: Option<&Value>,
    n: usize,
    field: &str,
) -> Result<Vec<(f64, f64)>, ImageError> {
    let mut ab = vec![(1.0, 0.0); n];
    for t in list.and_then(Value::as_array).into_iter().flatten() {
        let kind = t.get("type").and_then(Value::as_str).unwrap_or("");
        let vals = |key: &str| -> Result<Vec<f64>, ImageError> {
            let v: Option<Vec<f64>> = t
                .get(key)
                .and_then(Value::as_array)
                .map(|a| {
                    a.iter()
                        .map(|x| x.as_f64().filter(|f| f.is_finite()))
                        .collect()
                })
                .unwrap_or(None);
            v.filter(|v| v.len() == n).ok_or_else(|| {
                err(
                    path,
                    field,
                    format!("has a {kind} without {n} finite numbers in \"{key}\" (one per axis)"),
                )
            })
        };
        match kind {
            "scale" => {
                for (x, s) in ab.iter_mut().zip(vals("scale")?) {
                    *x = (x.0 * s, x.1 * s);
                }
            }
            "translation" => {
                for (x, t) in ab.iter_mut().zip(vals("translation")?) {
                    x.1 += t;
                }
            }
            "identity" => {}
            other => {
                return Err(err(
                    path,
                    field,
                    format!(
                        "has a transformation of type {other:?}; only scale and translation are read"
                    ),
                ));
            }
        }
    }
    Ok(ab)
}

/// For each array axis: `Some(0|1|2)` for the x, y, z voxel index, `None` for another axis.
fn axis_roles(path: &Path, ms: &Value, n: usize) -> Result<Vec<Option<usize>>, ImageError> {
    let axes = ms.get("axes").and_then(Value::as_array);
    let names: Vec<(String, bool)> = match axes {
        Some(a) => a
            .iter()
            .map(|x| match x {
                Value::String(s) => (
                    s.to_ascii_lowercase(),
                    ["x", "y", "z"].contains(&s.as_str()),
                ),
                _ => (
                    x.get("name")
                        .and_then(Value::as_str)
                        .unwrap_or("")
                        .to_ascii_lowercase(),
                    x.get("type").and_then(Value::as_str) == Some("space"),
                ),
            })
            .collect(),
        None => (0..n).map(|i| (String::new(), i + 3 >= n)).collect(),
    };
    if names.len() != n {
        return Err(err(
            path,
            "multiscales[0].axes",
            format!(
                "lists {} axes but the level-0 array has {n} dimensions",
                names.len()
            ),
        ));
    }
    let space: Vec<usize> = (0..n).filter(|&i| names[i].1).collect();
    if space.len() != 3 {
        return Err(err(
            path,
            "multiscales[0].axes",
            format!("has {} space axes; a volume needs exactly 3", space.len()),
        ));
    }
    let mut roles = vec![None; n];
    let named = ["x", "y", "z"].map(|c| space.iter().find(|&&i| names[i].0 == c).copied());
    if let [Some(x), Some(y), Some(z)] = named {
        roles[x] = Some(0);
        roles[y] = Some(1);
        roles[z] = Some(2);
    } else {
        roles[space[0]] = Some(2);
        roles[space[1]] = Some(1);
        roles[space[2]] = Some(0);
    }
    Ok(roles)
}

/// The voxels of `bytes` (elements of `size` bytes, voxel (i, j, k) at element
/// `i * strides[0] + j * strides[1] + k * strides[2]`) in x-fastest order.
fn x_fastest(bytes: &[u8], dims: [usize; 3], strides: [usize; 3], size: usize) -> Vec<u8> {
    let mut out = Vec::with_capacity(dims.iter().product::<usize>() * size);
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                let s = (i * strides[0] + j * strides[1] + k * strides[2]) * size;
                out.extend_from_slice(&bytes[s..s + size]);
            }
        }
    }
    out
}

fn dtype(path: &Path, t: &DataType) -> Result<Dtype, ImageError> {
    Ok(match t {
        DataType::UInt8 => Dtype::U8,
        DataType::Int8 => Dtype::I8,
        DataType::UInt16 => Dtype::U16,
        DataType::Int16 => Dtype::I16,
        DataType::UInt32 => Dtype::U32,
        DataType::Int32 => Dtype::I32,
        DataType::Float32 => Dtype::F32,
        DataType::Float64 => Dtype::F64,
        DataType::UInt64 => Dtype::U64,
        DataType::Int64 => Dtype::I64,
        other => {
            return Err(err(
                path,
                "dtype / data_type",
                format!(
                    "{other} is not supported; convert the array to uint8, int8, uint16, int16, \
                     uint32, int32, uint64, int64, float32 or float64"
                ),
            ));
        }
    })
}

/// The chunks of `array` that are not in the store: an error if the fill value is null (v2).
fn missing_chunks(
    path: &Path,
    array: &Array<FilesystemStore>,
    store: &FilesystemStore,
    level: &Path,
    version: u8,
) -> Result<usize, ImageError> {
    let grid = array.chunk_grid_shape().clone();
    let total: u64 = grid.iter().product();
    let null_fill = version == 2
        && json(path, &level.join(".zarray"))?
            .get("fill_value")
            .is_some_and(Value::is_null);
    let mut missing = 0;
    let mut idx = vec![0u64; grid.len()];
    for _ in 0..total {
        let key = array.chunk_key(&idx);
        let present = store
            .size_key(&key)
            .map_err(|e| err(path, key.as_str(), format!("cannot be read ({e})")))?
            .is_some();
        if !present {
            if null_fill {
                return Err(err(
                    path,
                    key.as_str(),
                    "(a chunk) is missing and the array's fill_value is null, so its voxels are \
                     undefined; re-write the array (or set a fill_value)",
                ));
            }
            missing += 1;
        }
        for d in (0..idx.len()).rev() {
            idx[d] += 1;
            if idx[d] < grid[d] {
                break;
            }
            idx[d] = 0;
        }
    }
    Ok(missing)
}

/// Read the level-0 image of an OME-Zarr group; see the module documentation.
pub fn read_ome_zarr(path: impl AsRef<Path>) -> Result<Volume, ImageError> {
    let path = path.as_ref();
    let (ms, version) = multiscales(path)?;
    let ds = ms.get("datasets").and_then(|d| d.get(0));
    let sub = ds
        .and_then(|d| d.get("path"))
        .and_then(Value::as_str)
        .ok_or_else(|| err(path, "multiscales[0].datasets[0].path", "is missing"))?;
    let level = path.join(sub);
    let meta = if version == 3 { "zarr.json" } else { ".zarray" };
    if !level.join(meta).is_file() {
        return Err(err(
            path,
            &format!("{sub}/{meta}"),
            format!(
                "is missing: multiscales[0].datasets[0].path names {sub:?} but there is no Zarr \
                 v{version} array there; the store is incomplete"
            ),
        ));
    }
    let store = FilesystemStore::new(path)
        .map_err(|e| err(path, "store", format!("cannot be opened ({e})")))?;
    let store = Arc::new(store);
    let array = Array::open(store.clone(), &format!("/{sub}")).map_err(|e| {
        err(
            path,
            &format!("{sub}/{meta}"),
            format!("is not a readable Zarr array ({e})"),
        )
    })?;
    let shape = array.shape().to_vec();
    let n = shape.len();
    let roles = axis_roles(path, &ms, n)?;
    if let Some(i) = (0..n).find(|&i| roles[i].is_none() && shape[i] != 1) {
        return Err(err(
            path,
            "multiscales[0].axes",
            format!(
                "axis {i} is not a space axis and has size {}; extract one 3D volume (one time \
                 point, one channel)",
                shape[i]
            ),
        ));
    }
    let own = transforms(
        path,
        ds.and_then(|d| d.get("coordinateTransformations")),
        n,
        "multiscales[0].datasets[0].coordinateTransformations",
    )?;
    let outer = transforms(
        path,
        ms.get("coordinateTransformations"),
        n,
        "multiscales[0].coordinateTransformations",
    )?;
    let dtype = dtype(path, array.data_type())?;
    let mut dims = [1usize; 3];
    let mut strides = [0usize; 3];
    let (mut scale, mut origin) = (DVec3::ONE, DVec3::ZERO);
    let mut stride = 1usize;
    for a in (0..n).rev() {
        if let Some(r) = roles[a] {
            dims[r] = shape[a] as usize;
            strides[r] = stride;
            let (s, t) = (own[a].0 * outer[a].0, own[a].1 * outer[a].0 + outer[a].1);
            scale[r] = s;
            origin[r] = t;
        }
        stride = stride.saturating_mul(shape[a] as usize);
    }
    let need = orient::byte_count(path, FMT, "shape", &dims, dtype.size())?;
    let missing = missing_chunks(path, &array, &store, &level, version)?;
    let bytes = array
        .retrieve_array_subset(&array.subset_all())
        .and_then(|b| Ok(b.into_fixed()?.into_owned()))
        .map_err(|e| {
            err(
                path,
                sub,
                format!(
                    "cannot be decoded ({e}); the chunks are damaged or use an unsupported codec"
                ),
            )
        })?;
    let size = dtype.size();
    if bytes.len() != need {
        return Err(err(
            path,
            sub,
            format!("decoded to {} bytes, the shape needs {need}", bytes.len()),
        ));
    }
    let out = x_fastest(&bytes, dims, strides, size);
    let big = cfg!(target_endian = "big");
    let (voxels, held) = super::volume::decode_voxels(path, dims, dtype, &out, big)?;
    let affine = DAffine3::from_mat3_translation(DMat3::from_diagonal(scale), origin);
    super::volume::check_affine(
        &affine,
        Some(path),
        "coordinateTransformations (scale, translation)",
    )?;
    let mut vol = Volume::new(dims, voxels, affine)?.with_source(path);
    let fill = (missing > 0).then(|| {
        format!(
            "{}: {missing} chunk(s) of level {sub:?} are not stored; their voxels are the fill value, as the Zarr format says",
            path.display()
        )
    });
    for n in held.into_iter().chain(fill) {
        vol = vol.with_note(n);
    }
    Ok(vol)
}
