"""rdt_mesher: restricted Delaunay surface meshing (Boissonnat & Oudot) with a certificate.

numpy arrays, NIfTI images, files the CLI reads, implicit functions, triangle meshes and
point sets in; a :class:`Mesh` out: ``vertices`` (V, 3) float64, ``faces`` (F, 3) int64,
per-facet quality, the CLI's ``--report`` dict and its certificate. See docs/PYTHON.md.

Axis order: a volume's element ``volume[i, j, k]`` is the voxel whose centre lies at
``affine @ (i, j, k, 1)``, the convention of nibabel (``img.get_fdata()``, ``img.dataobj``
and ``img.affine``). C- and Fortran-ordered arrays are both read in place (no copy); do not
write to an array while a call that uses it runs.
"""

from __future__ import annotations

import json
import os
from typing import Any, Callable, Dict, Optional, Sequence, Union

import numpy as np

from . import _rdt_mesher as _core

__all__ = [
    "Mesh",
    "mesh_image",
    "mesh_nifti",
    "mesh_file",
    "mesh_implicit",
    "remesh",
    "mesh_points",
    "verify",
    "__version__",
]

__version__ = _core.__version__

_ALIASES = {
    "max_radius_surface_delaunay_ball": "size",
    "min_facet_angle": "min_angle",
    "max_facet_distance": "max_distance",
}


class Mesh:
    """A mesh and what the mesher says about it.

    Attributes: ``vertices`` (V, 3) float64; ``faces`` (F, 3) int64 (outward orientation);
    ``min_angle`` (F,) smallest angle of each facet in degrees; ``ball_radius`` (F,) radius of
    each facet's surface Delaunay ball; ``r_over_sigma`` (F,) that radius over the size bound
    (NaN in two-pass mode, where the bound varies); ``sigma`` the size bound (None in two-pass
    mode); ``report`` the dict the CLI writes with ``--report`` (its ``output`` is "");
    ``certificate`` the loose-epsilon certificate (``report["verify"]["certificate"]``) or None.
    """

    def __init__(self, d: Dict[str, Any]):
        self.vertices: np.ndarray = d["vertices"]
        self.faces: np.ndarray = d["faces"]
        self.min_angle: np.ndarray = d["min_angle"]
        self.ball_radius: np.ndarray = d["ball_radius"]
        self.r_over_sigma: np.ndarray = d["r_over_sigma"]
        self.sigma: Optional[float] = d["sigma"]
        self.report: Dict[str, Any] = json.loads(d["report"])

    @property
    def certificate(self) -> Optional[Dict[str, Any]]:
        v = self.report.get("verify") or {}
        return v.get("certificate")

    @property
    def passed(self) -> Optional[bool]:
        """Whether every verification check passed (None when not verified)."""
        v = self.report.get("verify")
        if not v:
            return None
        return all(c.get("status") != "FAIL" for c in v.get("checks", []))

    def __repr__(self) -> str:
        return f"Mesh({len(self.vertices)} vertices, {len(self.faces)} faces, sigma={self.sigma})"

    def save(self, path: Union[str, os.PathLike]) -> None:
        """Write the mesh (format from the extension: .ply binary double, .off, .obj, .stl),
        atomically (a temporary file beside it, renamed)."""
        _core.save(self.vertices, self.faces, os.fspath(path))

    def to_trimesh(self):
        """A ``trimesh.Trimesh`` (needs the trimesh package)."""
        import trimesh

        return trimesh.Trimesh(self.vertices, self.faces, process=False)

    def to_meshio(self):
        """A ``meshio.Mesh`` with the per-facet arrays as cell data (needs meshio)."""
        import meshio

        return meshio.Mesh(
            self.vertices,
            [("triangle", self.faces)],
            cell_data={
                "min_angle": [self.min_angle],
                "ball_radius": [self.ball_radius],
            },
        )


def _params(
    *,
    size: Optional[float] = None,
    epsilon: Optional[float] = None,
    dm_inf: Optional[float] = None,
    min_angle: float = 30.0,
    max_distance: Optional[float] = None,
    oracle: str = "bipolar",
    manifold: bool = True,
    scaffold: bool = True,
    initialization: str = "control-points",
    seed: int = 0,
    max_vertices: Optional[int] = None,
    max_memory: Optional[int] = None,
    time_limit: Optional[float] = None,
    verify: bool = True,
    certify_epsilon: Optional[float] = None,
    min_component: Optional[float] = None,
    keep_unsupported: bool = False,
    threads: Optional[int] = None,
    **aliased: Any,
) -> Dict[str, Any]:
    p = dict(
        size=size,
        epsilon=epsilon,
        dm_inf=dm_inf,
        min_angle=min_angle,
        max_distance=max_distance,
        oracle=oracle,
        manifold=manifold,
        scaffold=scaffold,
        initialization=initialization,
        seed=seed,
        max_vertices=max_vertices,
        max_memory=max_memory,
        time_limit=time_limit,
        verify=verify,
        certify_epsilon=certify_epsilon,
        min_component=min_component,
        keep_unsupported=bool(keep_unsupported),
        threads=threads,
    )
    for k, v in aliased.items():
        if k not in _ALIASES:
            raise TypeError(f"unexpected keyword argument '{k}'")
        name = _ALIASES[k]
        default = 30.0 if name == "min_angle" else None
        if p[name] != default and p[name] != v:
            raise ValueError(f"{k} and {name}: give one of them (they are the same criterion)")
        p[name] = v
    for k in ("size", "epsilon", "dm_inf", "max_distance", "time_limit", "certify_epsilon",
              "min_component", "min_angle"):
        if p[k] is not None:
            if isinstance(p[k], bool) or not isinstance(p[k], (int, float, np.floating, np.integer)):
                raise TypeError(f"{k}: a number is needed, got {type(p[k]).__name__}")
            p[k] = float(p[k])
    for k in ("seed", "max_vertices", "max_memory", "threads"):
        if p[k] is not None:
            if isinstance(p[k], bool) or not isinstance(p[k], (int, np.integer)):
                raise TypeError(f"{k}: a whole number is needed, got {type(p[k]).__name__}")
            if p[k] < 0:
                raise ValueError(f"{k} {p[k]}: must not be negative")
            p[k] = int(p[k])
    if p["max_vertices"] == 0:
        raise ValueError("max_vertices 0: give at least 1")
    for k in ("oracle", "initialization"):
        if not isinstance(p[k], str):
            raise TypeError(f"{k}: a name is needed, got {type(p[k]).__name__}")
    return p


def _affine(affine, spacing, origin) -> np.ndarray:
    if affine is not None and (spacing is not None or origin is not None):
        raise ValueError("affine and spacing/origin: give the affine alone (it holds both)")
    if affine is not None:
        a = np.asarray(affine, dtype=np.float64)
        if a.shape != (4, 4):
            raise ValueError(f"affine: a 4x4 matrix is needed (nibabel's img.affine), got shape {a.shape}")
        return a
    a = np.eye(4)
    if spacing is not None:
        s = np.asarray(spacing, dtype=np.float64).reshape(-1)
        if s.shape == (1,):
            s = np.repeat(s, 3)
        if s.shape != (3,) or not np.all(np.isfinite(s)) or np.any(s <= 0):
            raise ValueError(f"spacing: three positive voxel sizes are needed, got {spacing!r}")
        a[[0, 1, 2], [0, 1, 2]] = s
    if origin is not None:
        o = np.asarray(origin, dtype=np.float64).reshape(-1)
        if o.shape != (3,):
            raise ValueError(f"origin: three coordinates are needed, got {origin!r}")
        a[:3, 3] = o
    return a


def _volume(volume) -> np.ndarray:
    if not isinstance(volume, np.ndarray):
        raise TypeError(
            f"volume: a numpy array is needed, got {type(volume).__name__} (numpy.asarray(volume))"
        )
    if volume.ndim != 3:
        raise ValueError(f"volume: a 3D array is needed, got shape {volume.shape}")
    if volume.dtype.kind not in "biuf":
        raise TypeError(f"volume: dtype {volume.dtype} is not supported; use bool, integers or floats")
    if volume.dtype.kind in "iu" and volume.dtype.itemsize == 8:
        # 64-bit integers (connectomics label ids): held exactly by the narrowest type that
        # can, int32, uint32, else float64 up to 2^53; beyond, consecutive ids would merge.
        lo, hi = (int(volume.min()), int(volume.max())) if volume.size else (0, 0)
        if -(2**31) <= lo and hi < 2**31:
            volume = volume.astype(np.int32, order="K")
        elif 0 <= lo and hi < 2**32:
            volume = volume.astype(np.uint32, order="K")
        elif max(-lo, hi) <= 9 * 10**15:
            volume = volume.astype(np.float64, order="K")
        else:
            raise ValueError(
                f"volume: 64-bit integers up to {max(-lo, hi)}: beyond 9e15 float64 cannot tell "
                "consecutive ids apart; relabel with smaller ids (numpy.unique(ids, return_inverse=True))"
            )
    if not volume.dtype.isnative:
        volume = volume.astype(volume.dtype.newbyteorder("="), order="K")
    if volume.dtype == np.float16:
        volume = volume.astype(np.float32, order="K")
    if not (volume.flags.c_contiguous or volume.flags.f_contiguous) or not volume.flags.aligned:
        volume = np.asfortranarray(volume).copy(order="F")
    return volume


def _labels_arg(labels, label):
    if labels is not None and label is not None:
        raise ValueError("label and labels: give one of them")
    if labels is None:
        return None
    if isinstance(labels, str):
        if labels != "all":
            raise ValueError(f"labels {labels!r}: use labels='all' or a list of labels")
        return "all"
    try:
        return [int(x) for x in labels]
    except TypeError:
        raise TypeError("labels: 'all' or a list of whole numbers is needed") from None


def _check_number(name, v):
    if v is not None and (isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating))):
        raise TypeError(f"{name}: a number is needed, got {type(v).__name__}")
    return None if v is None else float(v)


def mesh_image(
    volume: np.ndarray,
    *,
    affine=None,
    spacing=None,
    origin=None,
    iso: Optional[float] = None,
    label: Optional[int] = None,
    labels=None,
    dark_foreground: bool = False,
    background: Optional[float] = None,
    name: str = "volume",
    progress: Optional[Callable[[dict], Any]] = None,
    **criteria,
) -> Union[Mesh, Dict[int, Mesh]]:
    """Mesh the level set ``iso`` (or the boundary of ``label``) of a 3D array.

    ``volume[i, j, k]`` lies at ``affine @ (i, j, k, 1)`` (nibabel's convention); without an
    affine, at ``(i, j, k) * spacing + origin``. The inside is where the value is above ``iso``
    (below with ``dark_foreground``). ``labels="all"`` (or a list) returns ``{label: Mesh}``.
    Criteria: see :func:`_params` (size, epsilon, min_angle=30, max_distance, oracle,
    max_vertices, max_memory, time_limit, seed, threads, ...).
    """
    vol = _volume(volume)
    a = _affine(affine, spacing, origin)
    iso = _check_number("iso", iso)
    background = _check_number("background", background)
    p = _params(**criteria)
    which = _labels_arg(labels, label)
    if which is not None:
        # Read once: each label is meshed on its own crop (as the CLI's --labels all).
        lv = _core.label_volume(vol, a.tolist(), name)
        todo = lv.labels() if which == "all" else which
        if not todo:
            raise ValueError(f"labels: {name} has no label other than the background 0: nothing to mesh")
        return {l: Mesh(lv.mesh(l, f"{name} (label {l})", p, progress)) for l in todo}
    if label is not None and (isinstance(label, bool) or not isinstance(label, (int, np.integer))):
        raise TypeError(f"label: a whole number is needed, got {type(label).__name__}")
    lab = None if label is None else int(label)
    return Mesh(_core.mesh_volume(vol, a.tolist(), iso, lab, bool(dark_foreground), background, name, p, progress))


def mesh_nifti(image, **kwargs) -> Union[Mesh, Dict[int, Mesh]]:
    """Mesh a NIfTI image: a path (read by the library's reader, as the CLI does) or a
    nibabel image (its ``dataobj`` in place and its ``affine``)."""
    if isinstance(image, (str, os.PathLike)):
        return mesh_file(image, **kwargs)
    if not hasattr(image, "dataobj") or not hasattr(image, "affine"):
        raise TypeError(f"mesh_nifti: a path or a nibabel image is needed, got {type(image).__name__}")
    data = np.asanyarray(image.dataobj)
    if data.ndim == 4 and data.shape[3] == 1:
        data = data[..., 0]
    kwargs.setdefault("name", os.path.basename(getattr(image, "get_filename", lambda: None)() or "nifti"))
    return mesh_image(data, affine=image.affine, **kwargs)


def mesh_file(
    path: Union[str, os.PathLike],
    *,
    iso: Optional[float] = None,
    label: Optional[int] = None,
    labels=None,
    dark_foreground: bool = False,
    background: Optional[float] = None,
    spacing: Optional[Sequence[float]] = None,
    read_as: Optional[str] = None,
    smooth_polyhedron: bool = False,
    bounding_sphere=None,
    progress: Optional[Callable[[dict], Any]] = None,
    frame: Optional[int] = None,
    nan_as: Optional[float] = None,
    series: Optional[Union[int, str]] = None,
    **criteria,
) -> Union[Mesh, Dict[int, Mesh]]:
    """Mesh what ``cargo xtask mesh`` reads: an image (.nii, .nii.gz, .mgz, .nrrd, .mha,
    .tif, .tiff, .raw, a DICOM folder or multi-frame file, a folder of slices), a mesh (.ply .off .obj .stl), a point set (.xyz, a .ply without faces),
    or ``implicit:NAME`` / ``implicit:EXPR`` (with ``bounding_sphere=(center, radius)``).
    The same defaults as the CLI, hence the same mesh. ``frame`` picks one 3D volume of a
    NIfTI or MGH series, or of a DICOM series holding several volumes (``--frame``); ``nan_as`` gives NaN voxels a value (``--nan-as``);
    ``series`` picks one series of a DICOM folder by its SeriesNumber or SeriesInstanceUID
    (``--series``)."""
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"mesh_file: a path is needed, got {type(path).__name__}")
    spec = os.fspath(path)
    if not spec.startswith("implicit:") and not os.path.exists(spec):
        raise FileNotFoundError(f"{spec}: no such file or folder")
    iso = _check_number("iso", iso)
    background = _check_number("background", background)
    bs = _sphere(bounding_sphere) if bounding_sphere is not None else None
    sp = None
    if spacing is not None:
        sp = [float(x) for x in np.broadcast_to(np.asarray(spacing, dtype=np.float64), (3,))]
    nan_as = _check_number("nan_as", nan_as)
    if frame is not None:
        if isinstance(frame, bool) or not isinstance(frame, (int, np.integer)) or frame < 0:
            raise ValueError(f"frame {frame!r}: the frame of a series is a whole number from 0")
        frame = int(frame)
    if series is not None:
        if isinstance(series, bool) or not isinstance(series, (int, np.integer, str)):
            raise TypeError(f"series {series!r}: a SeriesNumber (int) or SeriesInstanceUID (str)")
        series = str(series)
    p = _params(**criteria)
    which = _labels_arg(labels, label)
    if which is not None and bs is None and read_as is None and not smooth_polyhedron:
        # Read once: each label is meshed on its own crop (as the CLI's --labels all).
        lv = _core.label_file(spec, frame, series, sp, nan_as)
        todo = lv.labels() if which == "all" else which
        if not todo:
            raise ValueError(f"labels: {spec} has no label other than the background 0: nothing to mesh")
        return {l: Mesh(lv.mesh(l, None, p, progress)) for l in todo}
    if which is not None:
        todo = _core.file_labels(spec, frame, series) if which == "all" else which
        if not todo:
            raise ValueError(f"labels: {spec} has no label other than the background 0: nothing to mesh")
        return {
            l: Mesh(_core.mesh_spec(spec, bs, None, l, False, None, sp, read_as, smooth_polyhedron, p, progress,
                                    frame=frame, nan_as=nan_as, series=series))
            for l in todo
        }
    lab = None if label is None else int(label)
    return Mesh(_core.mesh_spec(spec, bs, iso, lab, bool(dark_foreground), background, sp, read_as,
                                bool(smooth_polyhedron), p, progress, frame=frame, nan_as=nan_as,
                                series=series))


def _sphere(bs):
    try:
        c, r = bs
        c = [float(x) for x in c]
        r = float(r)
    except (TypeError, ValueError):
        raise TypeError("bounding_sphere: (center, radius) is needed, e.g. ((0, 0, 0), 2.0)") from None
    if len(c) != 3 or not all(np.isfinite(c)) or not (r > 0 and np.isfinite(r)):
        raise ValueError(f"bounding_sphere {bs!r}: a finite centre of 3 coordinates and a positive radius are needed")
    return (c, r)


def mesh_implicit(
    f: Union[str, Callable[[np.ndarray], np.ndarray]],
    *,
    bounding_sphere,
    grid: int = 128,
    batch: int = 1 << 16,
    progress: Optional[Callable[[dict], Any]] = None,
    **criteria,
) -> Mesh:
    """Mesh the zero set of ``f`` (negative inside) within ``bounding_sphere=(center, radius)``.

    ``f`` is an expression string in x, y, z (the library's parser, meshed exactly) or a
    vectorized callable taking an (N, 3) float64 array and returning (N,) values. A callable is
    called in batches of ``batch`` points, never point by point: it is sampled on a
    ``grid``^3 lattice over the sphere's bounding cube and the mesher meshes the trilinear
    interpolant of the samples (the certificate is about that interpolant).
    """
    c, r = _sphere(bounding_sphere)
    p = _params(**criteria)
    if isinstance(f, str):
        spec = f if f.startswith("implicit:") else "implicit:" + f
        return Mesh(_core.mesh_spec(spec, (c, r), None, None, False, None, None, None, False, p, progress))
    if not callable(f):
        raise TypeError(f"mesh_implicit: an expression string or a callable is needed, got {type(f).__name__}")
    if isinstance(grid, bool) or not isinstance(grid, (int, np.integer)) or grid < 4:
        raise ValueError(f"grid {grid!r}: at least 4 samples per axis are needed")
    n = int(grid)
    h = 2.0 * r / (n - 1)
    ax = [c[k] - r + h * np.arange(n) for k in range(3)]
    vals = np.empty(n * n * n, dtype=np.float64)
    # x fastest: the Fortran order of an (n, n, n) array.
    idx = np.arange(n * n * n)
    for s in range(0, n * n * n, int(batch)):
        i = idx[s : s + int(batch)]
        pts = np.stack([ax[0][i % n], ax[1][(i // n) % n], ax[2][i // (n * n)]], axis=1)
        v = np.asarray(f(pts), dtype=np.float64).reshape(-1)
        if v.shape != (len(i),):
            raise ValueError(f"mesh_implicit: f returned {v.size} values for {len(i)} points; return one per row")
        if not np.all(np.isfinite(v)):
            raise ValueError("mesh_implicit: f returned non-finite values")
        vals[s : s + len(i)] = v
    # The contract of an implicit surface (as the CLI's): f > 0 on and outside the bounding
    # sphere. A sample there at or below 0 means S crosses the sphere, and the mesh of the
    # lattice would close it along the cube's faces: a surface f does not have.
    g = np.stack(np.meshgrid(*ax, indexing="ij"), axis=-1).reshape(-1, 3, order="F")
    bad = np.nonzero((np.linalg.norm(g - np.asarray(c), axis=1) >= r) & (vals <= 0.0))[0]
    if bad.size:
        q, fq = g[bad[0]], vals[bad[0]]
        raise ValueError(
            f"mesh_implicit: the surface crosses or touches the bounding sphere (center "
            f"({c[0]}, {c[1]}, {c[2]}), radius {r}): f({q[0]}, {q[1]}, {q[2]}) = {fq}, but f must "
            f"be > 0 on and outside the sphere ({bad.size} of the lattice's samples there are "
            f"not); enlarge the radius or move the center"
        )
    vol = vals.reshape((n, n, n), order="F")
    a = np.eye(4)
    a[[0, 1, 2], [0, 1, 2]] = h
    a[:3, 3] = [c[k] - r for k in range(3)]
    return Mesh(_core.mesh_volume(vol, a.tolist(), 0.0, None, True, None, "implicit", p, progress))


def _mesh_arrays(vertices, faces):
    v = np.ascontiguousarray(vertices, dtype=np.float64)
    fa = np.asarray(faces)
    if fa.dtype.kind not in "iu":
        raise TypeError(f"faces: an integer array is needed, got dtype {fa.dtype}")
    fa = np.ascontiguousarray(fa, dtype=np.int64)
    if v.ndim != 2 or v.shape[1] != 3:
        raise ValueError(f"vertices: a (V, 3) array is needed, got shape {v.shape}")
    if fa.ndim != 2 or fa.shape[1] != 3:
        raise ValueError(f"faces: an (F, 3) array of vertex indices is needed, got shape {fa.shape}")
    return v, fa


def remesh(vertices, faces, *, smooth_polyhedron: bool = False,
           progress: Optional[Callable[[dict], Any]] = None, **criteria) -> Mesh:
    """Remesh a closed triangle mesh (its exact triangles, or with ``smooth_polyhedron`` an
    IMLS approximation), as the CLI remeshes a mesh file. ``epsilon`` without ``dm_inf``
    meshes the IMLS approximation: the triangles have d_M = 0 at their edges, so no
    eps-sample of them exists."""
    v, fa = _mesh_arrays(vertices, faces)
    return Mesh(_core.remesh(v, fa, bool(smooth_polyhedron), _params(**criteria), progress))


def mesh_points(points, normals=None, *, progress: Optional[Callable[[dict], Any]] = None,
                **criteria) -> Mesh:
    """Mesh the surface sampled by an (N, 3) point set (normals estimated when not given)."""
    pts = np.ascontiguousarray(points, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise ValueError(f"points: an (N, 3) array is needed, got shape {pts.shape}")
    nrm = None if normals is None else np.ascontiguousarray(normals, dtype=np.float64)
    if nrm is not None and (nrm.ndim != 2 or nrm.shape[1] != 3):
        raise ValueError(f"normals: an (N, 3) array is needed, got shape {nrm.shape}")
    return Mesh(_core.mesh_points(pts, nrm, _params(**criteria), progress))


def verify(vertices, faces, *, against: Optional[str] = None, bounding_sphere=None,
           epsilon: Optional[float] = None, max_hausdorff: Optional[float] = None,
           min_angle: Optional[float] = None, samples_per_edge: int = 4) -> Dict[str, Any]:
    """Verify a triangle mesh as ``cargo xtask verify`` does (against a surface spec when
    given: a file or ``implicit:...``); the report as a dict (``report["checks"]``)."""
    v, fa = _mesh_arrays(vertices, faces)
    bs = _sphere(bounding_sphere) if bounding_sphere is not None else None
    if against is not None:
        against = os.fspath(against)
        if not against.startswith("implicit:") and not os.path.exists(against):
            raise FileNotFoundError(f"{against}: no such file or folder")
    return json.loads(_core.verify_mesh(
        v, fa, against, bs, _check_number("epsilon", epsilon),
        _check_number("max_hausdorff", max_hausdorff), _check_number("min_angle", min_angle),
        int(samples_per_edge)))
