//! Python bindings of the pipeline (ours): numpy arrays and files in, the mesh, the per-facet
//! quality, the CLI's report and the certificate out. The Python package `rdt_mesher`
//! (python/rdt_mesher) wraps this module (`rdt_mesher._rdt_mesher`) with keyword arguments.
//!
//! Every run happens on a worker thread with the GIL released; the calling thread waits for it,
//! calls the progress callback and checks for signals (Ctrl-C cancels the run through
//! [`rdt_mesher::Cancel`] and raises `KeyboardInterrupt`). A panic of the worker is caught and
//! becomes a `RuntimeError` naming the input.

use glam::{DAffine3, DMat3, DVec3};
use numpy::ndarray::Array2;
use numpy::{
    IntoPyArray, PyArray1, PyArray3, PyArrayMethods, PyReadonlyArray2, PyUntypedArray,
    PyUntypedArrayMethods,
};
use oracle::image::{
    Dtype, ImageOptions, ImageSurface, SharedVoxels, Volume, VoxelSource, VoxelView, Voxels,
};
use pyo3::exceptions::{PyFileNotFoundError, PyKeyboardInterrupt, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rdt_mesher::pipeline::{self, Event, Input, InputOptions, PipelineError, Request, SizeRequest};
use rdt_mesher::{Cancel, Initialization, OracleKind};
use std::path::Path;
use std::sync::Arc;
use std::sync::mpsc;
use std::time::Duration;

mod labels;

/// A numpy array lent to a volume: its voxels, x fastest (a Fortran-ordered `(nx, ny, nz)`
/// array, or a C-ordered one read with its axes reversed).
struct NumpyVoxels {
    /// Keeps the array (and so its data) alive while a volume uses it.
    _array: Py<PyAny>,
    ptr: usize,
    len: usize,
    dtype: Dtype,
}

impl VoxelSource for NumpyVoxels {
    fn view(&self) -> VoxelView<'_> {
        /// The array's data as a typed slice.
        ///
        /// SAFETY: `ptr` is the data pointer of a contiguous, aligned numpy array of `len`
        /// elements of the type `T` that `dtype` names (checked by `volume_from_array`, bool
        /// read as u8: numpy stores booleans as bytes 0 and 1, valid u8 values); the array is
        /// kept alive by `_array` for as long as `self` is, and numpy never moves the data of a
        /// live array that has other references (`resize` refuses). The caller documents that
        /// the array must not be written while a call runs (the GIL is released then).
        unsafe fn slice<'a, T>(ptr: usize, len: usize) -> &'a [T] {
            unsafe { std::slice::from_raw_parts(ptr as *const T, len) }
        }
        // SAFETY: see `slice`.
        unsafe {
            match self.dtype {
                Dtype::U8 => VoxelView::U8(slice(self.ptr, self.len)),
                Dtype::I8 => VoxelView::I8(slice(self.ptr, self.len)),
                Dtype::U16 => VoxelView::U16(slice(self.ptr, self.len)),
                Dtype::I16 => VoxelView::I16(slice(self.ptr, self.len)),
                Dtype::U32 => VoxelView::U32(slice(self.ptr, self.len)),
                Dtype::I32 => VoxelView::I32(slice(self.ptr, self.len)),
                Dtype::F32 => VoxelView::F32(slice(self.ptr, self.len)),
                Dtype::F64 => VoxelView::F64(slice(self.ptr, self.len)),
                // `array_dtype` gives none of these (the package narrows 64-bit arrays first).
                Dtype::U64 | Dtype::I64 => unreachable!("a 64-bit array view"),
            }
        }
    }
}

/// The dtype of a numpy array among those a volume holds (bool as u8), and its data pointer.
fn array_dtype(a: &Bound<'_, PyUntypedArray>) -> PyResult<(Dtype, usize)> {
    macro_rules! try_as {
        ($t:ty, $d:expr) => {
            if let Ok(x) = a.cast::<PyArray3<$t>>() {
                return Ok(($d, x.data() as usize));
            }
        };
    }
    try_as!(bool, Dtype::U8);
    try_as!(u8, Dtype::U8);
    try_as!(i8, Dtype::I8);
    try_as!(u16, Dtype::U16);
    try_as!(i16, Dtype::I16);
    try_as!(u32, Dtype::U32);
    try_as!(i32, Dtype::I32);
    try_as!(f32, Dtype::F32);
    try_as!(f64, Dtype::F64);
    Err(pyo3::exceptions::PyTypeError::new_err(format!(
        "volume: dtype {} is not supported; use bool, uint8, int8, uint16, int16, uint32, int32, float32 or float64 (e.g. volume.astype(numpy.float32))",
        a.dtype()
    )))
}

/// A volume over the array's memory (no copy) whose voxel `[i, j, k]` lies at
/// `affine * (i, j, k, 1)`.
fn volume_from_array(a: &Bound<'_, PyUntypedArray>, affine: DAffine3) -> PyResult<Volume> {
    if a.ndim() != 3 {
        return Err(PyValueError::new_err(format!(
            "volume: a 3D array is needed, got {} dimensions (shape {:?})",
            a.ndim(),
            a.shape()
        )));
    }
    let (dtype, ptr) = array_dtype(a)?;
    let s = a.shape();
    let (fortran, c) = (a.is_fortran_contiguous(), a.is_c_contiguous());
    if !fortran && !c {
        return Err(PyValueError::new_err(
            "volume: the array must be C- or Fortran-contiguous (numpy.asfortranarray(volume))",
        ));
    }
    if !ptr.is_multiple_of(dtype.size()) {
        return Err(PyValueError::new_err(
            "volume: the array's data is not aligned (numpy.require(volume, requirements='A'))",
        ));
    }
    let (dims, affine) = if fortran {
        ([s[0], s[1], s[2]], affine)
    } else {
        // C order: k fastest. Read as the volume (k, j, i): swap the first and last columns.
        let m = affine.matrix3;
        let swapped = DMat3::from_cols(m.z_axis, m.y_axis, m.x_axis);
        (
            [s[2], s[1], s[0]],
            DAffine3::from_mat3_translation(swapped, affine.translation),
        )
    };
    let owner = NumpyVoxels {
        _array: a.clone().into_any().unbind(),
        ptr,
        len: s.iter().product(),
        dtype,
    };
    let voxels = Voxels::Shared(SharedVoxels::new(Arc::new(owner)));
    Volume::new(dims, voxels, affine).map_err(|e| PyValueError::new_err(format!("volume: {e}")))
}

/// One line: the error and its sources.
fn one_line(e: &(dyn std::error::Error + 'static)) -> String {
    let mut s = e.to_string();
    let mut src = e.source();
    while let Some(x) = src {
        let m = x.to_string();
        if !s.contains(&m) {
            s.push_str(": ");
            s.push_str(&m);
        }
        src = x.source();
    }
    s
}

fn pipeline_err(e: PipelineError) -> PyErr {
    let msg = one_line(&e);
    match e {
        PipelineError::NoSuchInput { .. } => PyFileNotFoundError::new_err(msg),
        _ => PyValueError::new_err(msg),
    }
}

/// What a run asks for, from the Python keyword arguments.
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
struct Params {
    size: Option<f64>,
    epsilon: Option<f64>,
    dm_inf: Option<f64>,
    min_angle: f64,
    max_distance: Option<f64>,
    oracle: String,
    manifold: bool,
    scaffold: bool,
    initialization: String,
    seed: u64,
    max_vertices: Option<usize>,
    max_memory: Option<u64>,
    time_limit: Option<f64>,
    verify: bool,
    certify_epsilon: Option<f64>,
    min_component: Option<f64>,
    keep_unsupported: bool,
    threads: Option<usize>,
}

impl Params {
    /// An epsilon that estimates d_M (`SizeRequest::estimates_dm`): a mesh is then opened as
    /// its smooth approximation, as the CLI does (its triangles have d_M = 0 at their edges).
    fn estimates_dm(&self) -> bool {
        self.request().is_ok_and(|r| r.size.estimates_dm())
    }

    fn request(&self) -> PyResult<Request> {
        let bad = |m: String| PyValueError::new_err(m);
        let size = match (self.size, self.epsilon) {
            (Some(s), None) => SizeRequest::Size(s),
            (None, Some(e)) => SizeRequest::Epsilon {
                epsilon: e,
                dm_inf: self.dm_inf,
            },
            (None, None) => SizeRequest::Auto,
            (Some(_), Some(_)) => {
                return Err(bad(
                    "size and epsilon: give one of them (size: a constant bound; epsilon: two passes)"
                        .into(),
                ));
            }
        };
        if !(0.0..=60.0).contains(&self.min_angle) {
            return Err(bad(format!(
                "min_angle {}: the facet angle bound must be in [0, 60] degrees, e.g. min_angle=30",
                self.min_angle
            )));
        }
        if let Some(t) = self.time_limit
            && !(t > 0.0 && t.is_finite())
        {
            return Err(bad(format!(
                "time_limit {t}: give a positive number of seconds"
            )));
        }
        if self.threads == Some(0) {
            return Err(bad(
                "threads 0: give at least 1 (or None for all cores)".into()
            ));
        }
        Ok(Request {
            size,
            min_angle_deg: self.min_angle,
            max_distance: self.max_distance,
            oracle: self.oracle.parse::<OracleKind>().map_err(bad)?,
            manifold: self.manifold,
            scaffold: self.scaffold,
            initialization: self.initialization.parse::<Initialization>().map_err(bad)?,
            seed: self.seed,
            max_vertices: self.max_vertices,
            max_memory: self.max_memory,
            time_limit: self.time_limit.map(Duration::from_secs_f64),
            initial_points: Vec::new(),
            verify: self.verify,
            certify_epsilon: self.certify_epsilon,
            min_component: self.min_component,
            keep_unsupported: self.keep_unsupported,
            cancel: None,
        })
    }
}

/// What the worker sends the calling thread.
enum Msg {
    Progress(Event),
    Done(Box<Result<Done, String>>),
}

/// A finished run.
struct Done {
    result: Result<Finished, PipelineError>,
}

struct Finished {
    vertices: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
    radius: Vec<f64>,
    sigma: Option<f64>,
    report: serde_json::Value,
    cancelled: bool,
}

fn panic_text(p: &(dyn std::any::Any + Send)) -> String {
    p.downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| p.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "a panic".into())
}

/// Open the input with `open` and mesh it as `params` asks, on a worker thread, the GIL
/// released; progress, signals and panics handled as the module doc says.
fn run<'py>(
    py: Python<'py>,
    spec: &str,
    open: Box<dyn FnOnce() -> Result<Input<'static>, PipelineError> + Send>,
    params: &Params,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let mut request = params.request()?;
    let cancel = Cancel::default();
    request.cancel = Some(cancel.clone());
    let pool = match params.threads {
        Some(n) => Some(
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .map_err(|e| PyRuntimeError::new_err(format!("threads {n}: {e}")))?,
        ),
        None => None,
    };
    let (tx, rx) = mpsc::channel::<Msg>();
    let spec_owned = spec.to_string();
    let work = move || {
        let tx2 = tx.clone();
        let body = std::panic::AssertUnwindSafe(move || -> Done {
            let job = || -> Result<Finished, PipelineError> {
                let input = open()?;
                let plan = pipeline::plan(&input, &request)?;
                let forecast = plan.forecast().copied();
                let budgets = *plan.budgets();
                let out = plan.execute(&mut |e| {
                    let _ = tx2.send(Msg::Progress(e));
                })?;
                let report = pipeline::report::mesh_report(
                    &spec_owned,
                    Path::new(""),
                    &input,
                    forecast.as_ref(),
                    &budgets,
                    &request,
                    &out,
                );
                let cancelled = matches!(
                    out.stats.stopped_by,
                    Some(rdt_mesher::StopReason::Cancelled)
                ) || out.two_pass.as_ref().is_some_and(|t| {
                    matches!(
                        t.first.stats.stopped_by,
                        Some(rdt_mesher::StopReason::Cancelled)
                    )
                });
                Ok(Finished {
                    radius: out.balls.iter().map(|b| b.radius).collect(),
                    vertices: out.mesh.vertices,
                    triangles: out.mesh.triangles,
                    sigma: out.sigma,
                    report,
                    cancelled,
                })
            };
            Done {
                result: match &pool {
                    Some(p) => p.install(job),
                    None => job(),
                },
            }
        });
        let r = std::panic::catch_unwind(body).map_err(|p| panic_text(p.as_ref()));
        let _ = tx.send(Msg::Done(Box::new(r)));
    };
    let handle = std::thread::Builder::new()
        .name("rdt-mesher".into())
        .spawn(work)
        .map_err(|e| PyRuntimeError::new_err(format!("{spec}: cannot start a thread: {e}")))?;
    let mut interrupted: Option<PyErr> = None;
    let mut rx = Some(rx);
    let done = loop {
        let r = rx.take().expect("the receiver is put back every turn");
        let (msg, r) = py.detach(move || (r.recv_timeout(Duration::from_millis(50)), r));
        rx = Some(r);
        match msg {
            Ok(Msg::Done(d)) => break Some(*d),
            Ok(Msg::Progress(e)) => {
                if let (Some(cb), None) = (&progress, &interrupted) {
                    let d = PyDict::new(py);
                    match e {
                        Event::Meshing(p) => {
                            d.set_item("stage", "meshing")?;
                            d.set_item("sample_points", p.sample_points)?;
                            d.set_item("restricted_facets", p.restricted_facets)?;
                            d.set_item("queue", p.queue)?;
                        }
                        Event::Verifying => d.set_item("stage", "verifying")?,
                        Event::Round(r) => {
                            d.set_item("stage", "round")?;
                            d.set_item("round", r.round)?;
                            d.set_item("sample_points", r.vertices)?;
                            d.set_item("dm_inf_estimate", r.dm_inf_estimate)?;
                        }
                    }
                    if let Err(err) = cb.call1((d,)) {
                        cancel.cancel();
                        interrupted = Some(err);
                    }
                }
            }
            Err(mpsc::RecvTimeoutError::Timeout) => {}
            Err(mpsc::RecvTimeoutError::Disconnected) => break None,
        }
        if interrupted.is_none()
            && let Err(err) = py.check_signals()
        {
            cancel.cancel();
            interrupted = Some(err);
        }
    };
    let _ = py.detach(|| handle.join());
    if let Some(err) = interrupted {
        return Err(err);
    }
    let done = match done {
        Some(Ok(d)) => d,
        Some(Err(panic)) => {
            return Err(PyRuntimeError::new_err(format!(
                "{spec}: internal error of rdt-mesher ({panic}); please report it with this input"
            )));
        }
        None => {
            return Err(PyRuntimeError::new_err(format!(
                "{spec}: internal error of rdt-mesher (the worker stopped without a result)"
            )));
        }
    };
    let f = done.result.map_err(pipeline_err)?;
    if f.cancelled {
        return Err(PyKeyboardInterrupt::new_err(format!(
            "{spec}: meshing cancelled"
        )));
    }
    if f.triangles.is_empty() {
        return Err(PyValueError::new_err(format!(
            "{spec}: the mesh is empty (no facet on the surface). An open or flat input mesh bounds no solid: close it, or mesh its vertices with mesh_points; for other inputs check iso / label or try a smaller size"
        )));
    }
    finished_dict(py, f)
}

/// Per-facet smallest angle (degrees).
fn min_angles(v: &[DVec3], t: &[[u32; 3]]) -> Vec<f64> {
    t.iter()
        .map(|f| {
            let p = f.map(|i| v[i as usize]);
            (0..3)
                .map(|i| {
                    let (a, b) = (p[(i + 1) % 3] - p[i], p[(i + 2) % 3] - p[i]);
                    a.angle_between(b).to_degrees()
                })
                .fold(f64::INFINITY, f64::min)
        })
        .collect()
}

fn finished_dict(py: Python<'_>, f: Finished) -> PyResult<Bound<'_, PyDict>> {
    let d = PyDict::new(py);
    let nv = f.vertices.len();
    let flat: Vec<f64> = f.vertices.iter().flat_map(|p| p.to_array()).collect();
    let verts = Array2::from_shape_vec((nv, 3), flat).expect("3 coordinates per vertex");
    let nf = f.triangles.len();
    let tri: Vec<i64> = f
        .triangles
        .iter()
        .flat_map(|t| t.map(|i| i as i64))
        .collect();
    let faces = Array2::from_shape_vec((nf, 3), tri).expect("3 indices per facet");
    d.set_item(
        "min_angle",
        PyArray1::from_vec(py, min_angles(&f.vertices, &f.triangles)),
    )?;
    let r_over_sigma: Vec<f64> = match f.sigma {
        Some(s) => f.radius.iter().map(|r| r / s).collect(),
        None => vec![f64::NAN; f.radius.len()],
    };
    d.set_item("ball_radius", PyArray1::from_vec(py, f.radius))?;
    d.set_item("r_over_sigma", PyArray1::from_vec(py, r_over_sigma))?;
    d.set_item("vertices", verts.into_pyarray(py))?;
    d.set_item("faces", faces.into_pyarray(py))?;
    d.set_item("sigma", f.sigma)?;
    d.set_item("report", f.report.to_string())?;
    Ok(d)
}

fn affine_of(m: [[f64; 4]; 4]) -> PyResult<DAffine3> {
    let finite = m.iter().flatten().all(|x| x.is_finite());
    if !finite || m[3] != [0.0, 0.0, 0.0, 1.0] {
        return Err(PyValueError::new_err(
            "affine: a finite 4x4 matrix with last row [0, 0, 0, 1] is needed (nibabel's img.affine)",
        ));
    }
    let col = |j: usize| DVec3::new(m[0][j], m[1][j], m[2][j]);
    Ok(DAffine3::from_mat3_translation(
        DMat3::from_cols(col(0), col(1), col(2)),
        col(3),
    ))
}

/// Mesh a level set (or a label) of a 3D numpy array whose voxel `[i, j, k]` lies at
/// `affine @ (i, j, k, 1)`.
#[pyfunction]
#[pyo3(signature = (volume, affine, iso, label, dark_foreground, background, name, params, progress=None))]
#[allow(clippy::too_many_arguments)]
fn mesh_volume<'py>(
    py: Python<'py>,
    volume: &Bound<'py, PyUntypedArray>,
    affine: [[f64; 4]; 4],
    iso: Option<f64>,
    label: Option<i64>,
    dark_foreground: bool,
    background: Option<f64>,
    name: String,
    params: Params,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let vol = volume_from_array(volume, affine_of(affine)?)?;
    let opts = ImageOptions {
        iso,
        label,
        dark_foreground,
        background,
    };
    let spec = name.clone();
    let open = Box::new(move || -> Result<Input<'static>, PipelineError> {
        let img = ImageSurface::new(vol, &opts).map_err(|e| PipelineError::Backend {
            context: format!("opening image {spec}"),
            source: Box::new(e),
        })?;
        Ok(Input::image(img, spec))
    });
    run(py, &name, open, &params, progress)
}

/// Mesh what the CLI reads: a file, a folder of slices or `implicit:NAME|EXPR`.
#[pyfunction]
#[pyo3(signature = (spec, bounding_sphere, iso, label, dark_foreground, background, spacing, read_as, smooth_polyhedron, params, progress=None, frame=None, nan_as=None, series=None))]
#[allow(clippy::too_many_arguments)]
fn mesh_spec<'py>(
    py: Python<'py>,
    spec: String,
    bounding_sphere: Option<([f64; 3], f64)>,
    iso: Option<f64>,
    label: Option<i64>,
    dark_foreground: bool,
    background: Option<f64>,
    spacing: Option<[f64; 3]>,
    read_as: Option<String>,
    smooth_polyhedron: bool,
    params: Params,
    progress: Option<Bound<'py, PyAny>>,
    frame: Option<usize>,
    nan_as: Option<f64>,
    series: Option<String>,
) -> PyResult<Bound<'py, PyDict>> {
    let mut opts = InputOptions {
        bounding_sphere: bounding_sphere.map(|(c, r)| oracle::BoundingSphere {
            center: DVec3::from_array(c),
            radius: r,
        }),
        image: ImageOptions {
            iso,
            label,
            dark_foreground,
            background,
        },
        smooth_polyhedron: smooth_polyhedron || params.estimates_dm(),
        ..Default::default()
    };
    if let Some(h) = spacing {
        opts.load.spacing = Some(h);
    }
    opts.load.frame = frame;
    opts.load.nan_as = nan_as;
    opts.load.series = series;
    opts.read_as = match read_as.as_deref() {
        None => None,
        Some("mesh") => Some(pipeline::ReadAs::Mesh),
        Some("points") => Some(pipeline::ReadAs::Points),
        Some(o) => {
            return Err(PyValueError::new_err(format!(
                "read_as {o:?}: use 'mesh' or 'points'"
            )));
        }
    };
    let s = spec.clone();
    let open = Box::new(move || Input::open(&s, &opts));
    run(py, &spec, open, &params, progress)
}

/// The labels of an image file, without 0.
#[pyfunction]
#[pyo3(signature = (spec, frame=None, series=None))]
fn file_labels(spec: String, frame: Option<usize>, series: Option<String>) -> PyResult<Vec<i64>> {
    Ok(labels::label_file(spec, frame, series, None, None)?.labels())
}

fn points_of(a: &PyReadonlyArray2<'_, f64>, what: &str) -> PyResult<Vec<DVec3>> {
    let v = a.as_array();
    if v.ncols() != 3 {
        return Err(PyValueError::new_err(format!(
            "{what}: an (N, 3) array is needed, got shape {:?}",
            v.shape()
        )));
    }
    let pts: Vec<DVec3> = v
        .rows()
        .into_iter()
        .map(|r| DVec3::new(r[0], r[1], r[2]))
        .collect();
    if let Some(i) = pts.iter().position(|p| !p.is_finite()) {
        return Err(PyValueError::new_err(format!(
            "{what}: row {i} is not finite ({:?})",
            pts[i].to_array()
        )));
    }
    Ok(pts)
}

fn trimesh_of(
    vertices: &PyReadonlyArray2<'_, f64>,
    faces: &PyReadonlyArray2<'_, i64>,
) -> PyResult<meshio::TriMesh> {
    let v = points_of(vertices, "vertices")?;
    let f = faces.as_array();
    if f.ncols() != 3 {
        return Err(PyValueError::new_err(format!(
            "faces: an (F, 3) array of vertex indices is needed, got shape {:?}",
            f.shape()
        )));
    }
    let mut tri = Vec::with_capacity(f.nrows());
    for (i, r) in f.rows().into_iter().enumerate() {
        let mut t = [0u32; 3];
        for k in 0..3 {
            let x = r[k];
            if x < 0 || x as usize >= v.len() {
                return Err(PyValueError::new_err(format!(
                    "faces: row {i} has index {x}, outside 0..{} (the vertex count)",
                    v.len()
                )));
            }
            t[k] = x as u32;
        }
        tri.push(t);
    }
    Ok(meshio::TriMesh {
        vertices: v,
        triangles: tri,
    })
}

/// Remesh a triangle mesh (the polyhedron oracle, or its IMLS approximation).
#[pyfunction]
#[pyo3(signature = (vertices, faces, smooth_polyhedron, params, progress=None))]
fn remesh<'py>(
    py: Python<'py>,
    vertices: PyReadonlyArray2<'py, f64>,
    faces: PyReadonlyArray2<'py, i64>,
    smooth_polyhedron: bool,
    params: Params,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let mesh = trimesh_of(&vertices, &faces)?;
    let smooth = smooth_polyhedron || params.estimates_dm();
    let open = Box::new(move || Input::mesh(&mesh, "mesh", "mesh".into(), smooth));
    run(py, "mesh", open, &params, progress)
}

/// Mesh the surface of a point set (normals estimated when not given).
#[pyfunction]
#[pyo3(signature = (points, normals, params, progress=None))]
fn mesh_points<'py>(
    py: Python<'py>,
    points: PyReadonlyArray2<'py, f64>,
    normals: Option<PyReadonlyArray2<'py, f64>>,
    params: Params,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let pts = points_of(&points, "points")?;
    let normals = match &normals {
        Some(n) => {
            let n = points_of(n, "normals")?;
            if n.len() != pts.len() {
                return Err(PyValueError::new_err(format!(
                    "normals: {} rows for {} points; give one normal per point",
                    n.len(),
                    pts.len()
                )));
            }
            Some(n)
        }
        None => None,
    };
    let cloud = meshio::PointCloud {
        points: pts,
        normals,
    };
    let open = Box::new(move || Input::point_cloud(cloud, "points", "points".into()));
    run(py, "points", open, &params, progress)
}

/// Verify a triangle mesh (optionally against a surface spec); the report as JSON text.
#[pyfunction]
#[pyo3(signature = (vertices, faces, against, bounding_sphere, epsilon, max_hausdorff, min_angle, samples_per_edge))]
#[allow(clippy::too_many_arguments)]
fn verify_mesh(
    py: Python<'_>,
    vertices: PyReadonlyArray2<'_, f64>,
    faces: PyReadonlyArray2<'_, i64>,
    against: Option<String>,
    bounding_sphere: Option<([f64; 3], f64)>,
    epsilon: Option<f64>,
    max_hausdorff: Option<f64>,
    min_angle: Option<f64>,
    samples_per_edge: usize,
) -> PyResult<String> {
    let mesh = trimesh_of(&vertices, &faces)?;
    if samples_per_edge == 0 {
        return Err(PyValueError::new_err(
            "samples_per_edge 0: must be a positive whole number, e.g. 4",
        ));
    }
    let opts = verify::Options {
        epsilon,
        max_hausdorff,
        min_angle_deg: min_angle,
        samples_per_edge,
        ..Default::default()
    };
    let result = py.detach(|| {
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(
            || -> Result<verify::Report, PipelineError> {
                Ok(match &against {
                    Some(spec) => {
                        let io = InputOptions {
                            bounding_sphere: bounding_sphere.map(|(c, r)| oracle::BoundingSphere {
                                center: DVec3::from_array(c),
                                radius: r,
                            }),
                            ..Default::default()
                        };
                        let input = Input::open(spec, &io)?;
                        verify::check_against(&mesh, input.surface(), &opts)
                    }
                    None => verify::check(&mesh, &opts),
                })
            },
        ))
    });
    let report = result
        .map_err(|p| {
            PyRuntimeError::new_err(format!(
                "verify: internal error of rdt-mesher ({})",
                panic_text(p.as_ref())
            ))
        })?
        .map_err(pipeline_err)?;
    let mut v: serde_json::Value = serde_json::from_str(&report.to_json())
        .map_err(|e| PyRuntimeError::new_err(format!("verify: report: {e}")))?;
    pipeline::report::bound_lists(&mut v, pipeline::report::LIST_LIMIT);
    Ok(v.to_string())
}

/// Write a mesh in the format of `path`'s extension (PLY binary double, OFF, OBJ, STL),
/// atomically: a temporary file beside it, renamed.
#[pyfunction]
fn save(
    vertices: PyReadonlyArray2<'_, f64>,
    faces: PyReadonlyArray2<'_, i64>,
    path: std::path::PathBuf,
) -> PyResult<()> {
    let mesh = trimesh_of(&vertices, &faces)?;
    let err = |e: String| PyValueError::new_err(format!("{}: {e}", path.display()));
    let format = meshio::Format::from_path(&path).map_err(|e| err(one_line(&e)))?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => std::path::PathBuf::from("."),
    };
    if !dir.is_dir() {
        return Err(PyFileNotFoundError::new_err(format!(
            "{}: the folder {} does not exist",
            path.display(),
            dir.display()
        )));
    }
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_string())
        .unwrap_or_else(|| "mesh".into());
    let tmp = dir.join(format!(".{name}.{}.tmp", std::process::id()));
    let written = meshio::write_with(&tmp, &mesh, format, meshio::Options::default())
        .map_err(|e| err(one_line(&e)))
        .and_then(|()| std::fs::rename(&tmp, &path).map_err(|e| err(e.to_string())));
    if written.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    written
}

/// The extension module; see the Python package `rdt_mesher`.
#[pymodule]
fn _rdt_mesher(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(mesh_volume, m)?)?;
    m.add_function(wrap_pyfunction!(labels::label_volume, m)?)?;
    m.add_function(wrap_pyfunction!(labels::label_file, m)?)?;
    m.add_class::<labels::LabelVolume>()?;
    m.add_function(wrap_pyfunction!(mesh_spec, m)?)?;
    m.add_function(wrap_pyfunction!(file_labels, m)?)?;
    m.add_function(wrap_pyfunction!(remesh, m)?)?;
    m.add_function(wrap_pyfunction!(mesh_points, m)?)?;
    m.add_function(wrap_pyfunction!(verify_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(save, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
