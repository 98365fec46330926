//! Label images for Python (section 6.6.2's voxel oracle on each label's own crop): an array or
//! a file read once, each label meshed as the CLI's `--labels all` does.

use super::{Params, affine_of, pipeline_err, run, volume_from_array};
use numpy::PyUntypedArray;
use oracle::image::ImageOptions;
use pyo3::exceptions::PyFileNotFoundError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rdt_mesher::pipeline;
use std::path::Path;
use std::sync::Arc;

/// A label image read once, from a numpy array or a file, each label meshed on its own crop
/// (`pipeline::LabelImage`, as the CLI's `--labels all`): `mesh_image` and `mesh_file` with
/// `labels=` give the same meshes as one call per label with `label=`, without reading and
/// scanning the whole volume once per label.
#[pyclass(frozen)]
pub(crate) struct LabelVolume {
    inner: Arc<pipeline::LabelImage>,
    /// The file, or the array's name.
    spec: String,
}

#[pymethods]
impl LabelVolume {
    /// The labels but the background 0, in increasing order.
    pub(crate) fn labels(&self) -> Vec<i64> {
        self.inner.labels()
    }

    /// Mesh one label, named `name` in the report (`None`: as `mesh_spec` names a file).
    #[pyo3(signature = (label, name, params, progress=None))]
    fn mesh<'py>(
        &self,
        py: Python<'py>,
        label: i64,
        name: Option<String>,
        params: Params,
        progress: Option<Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let li = self.inner.clone();
        let opts = ImageOptions {
            label: Some(label),
            ..Default::default()
        };
        let spec = name.clone().unwrap_or_else(|| self.spec.clone());
        let open = Box::new(move || match name {
            Some(n) => li.input_named(&opts, n),
            None => li.input(&opts),
        });
        run(py, &spec, open, &params, progress)
    }
}

/// A 3D numpy array (voxel `[i, j, k]` at `affine @ (i, j, k, 1)`) as a label image.
#[pyfunction]
pub(crate) fn label_volume(
    volume: &Bound<'_, PyUntypedArray>,
    affine: [[f64; 4]; 4],
    name: String,
) -> PyResult<LabelVolume> {
    let vol = volume_from_array(volume, affine_of(affine)?)?;
    let inner = pipeline::LabelImage::from_volume(vol, &name).map_err(pipeline_err)?;
    Ok(LabelVolume {
        inner: Arc::new(inner),
        spec: name,
    })
}

/// An image file (what the CLI reads) as a label image, read once.
#[pyfunction]
#[pyo3(signature = (spec, frame=None, series=None, spacing=None, nan_as=None))]
pub(crate) fn label_file(
    spec: String,
    frame: Option<usize>,
    series: Option<String>,
    spacing: Option<[f64; 3]>,
    nan_as: Option<f64>,
) -> PyResult<LabelVolume> {
    if !Path::new(&spec).exists() {
        return Err(PyFileNotFoundError::new_err(format!(
            "{spec}: no such file or folder"
        )));
    }
    let load = oracle::image::LoadOptions {
        frame,
        series,
        spacing,
        nan_as,
        ..Default::default()
    };
    let inner = pipeline::LabelImage::open(&spec, &load).map_err(pipeline_err)?;
    Ok(LabelVolume {
        inner: Arc::new(inner),
        spec,
    })
}
