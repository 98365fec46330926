"""Issue 14 acceptance, the independent Python part: the CLI's image meshes against
scikit-image's marching cubes (MC) at the same iso value, checked with trimesh, numpy and scipy
only (no code of the project but the CLI).

For each case and each size k in (1, 2, 4) voxels (sigma = k * h, h the smallest voxel spacing)
the volume is meshed with `xtask mesh FILE --iso ISO --size SIGMA -o out.ply --report r.json`,
and the test asserts:

- the mesh is closed, oriented and embedded: trimesh's `is_watertight` and
  `is_winding_consistent`, no degenerate face (repeated vertex or zero area), every component
  oriented outward (its signed volume is positive when the winding number of the other
  components at one of its vertices is 0, negative when it is 1: a cavity's wall; no other
  winding number), and `verify`'s closed, manifold, oriented and self-intersections checks
  PASS in the report;
- components (by shared vertices): ours + those the report lists as `dropped` == MC's
  (`marching_cubes(method="lewiner", allow_degenerate=False)` on the volume padded by one
  layer of the background, the data minimum, as the mesher continues the image; duplicate
  vertices merged), or, where they differ, MC's on the same trilinear interpolant sampled
  every 1/8 voxel (`FINE_UP`; 1/4 or 1/2 where that would exceed `FINE_SAMPLES` samples); on
  a difference from both the message lists the report's component decisions (kind, centre,
  size) and where MC differs (an MC component holding several of ours, or none). At the
  voxels, Lewiner's MC is not the trilinear topology everywhere (see `FINE_UP`): its count
  depends on the sampling of one surface and settles as the sampling resolves sub-voxel
  necks, gaps and tunnels;
- two-sided distance within h + sigma: every MC vertex is within it of our mesh (those on voxel
  edges are exact points of the trilinear level set, the voxel-edge crossings of `cargo xtask
  regress`; Lewiner adds a few inside cells, 0.3% on mni-crop, and MC puts one at each node
  equal to the iso value with an inside edge neighbour: the Rust suite and the mesher's
  coverage keep those on the solid's boundary, not the punctures of the inside), and every vertex of ours (on the
  trilinear level set) within it of MC's triangles. The distances compared are upper bounds: exact
  point-to-triangle distances to candidate triangles (those around the k nearest vertices),
  made exact (trimesh.proximity) for the points beyond the bound and the farthest.

MC's vertices are mapped to world coordinates with the NIfTI affine (sform, else qform, else
pixdim, as the mesher reads it); the mapping is checked against the report's affine and by
the bounding boxes of the two meshes agreeing within one voxel plus sigma.

Cases: the fixtures `mni_t1_crop56` (iso 171.2, 190.5), `mni_t1_half` (171.2), the nilearn
motor map (t = 3); volumes nibabel ships in `nibabel/tests/data` (`anatomical.nii`,
`reoriented_anat_moved.nii`, the first volume of `example4d.nii.gz` with its oblique affine) at
the 30% and 60% quantiles of their foreground; and generated hard volumes written to temporary
NIfTI files, the same voxels as `xtask/src/suites/hard_volumes.rs` (blobs, sheet, tube, noise,
checker, integer; the integer one stored as int16), plus smoothed noise.

Every (case, size) passes since 2026-12-05 (session 26: the voxel scan's joins through a
cell's interior, `oracle::image::topology::interior`; before, 12 failed as strict xfails, all
where the scan counted too many components). The measured table is in docs/GUIDE.md
(`cargo xtask regress`). Every size is kept on every case: the whole module took about 3 min
on a shared 2-core machine (the four 1/8-voxel MC runs of the nibabel volumes 84 s, 4.6 GB
peak). Run alone, with `target/release/xtask` built:
`pytest python/tests/test_images_vs_marching_cubes.py`.
"""

import functools
import json
import os
import subprocess

import numpy as np
import pytest

from conftest import FIXTURES

# trimesh, rtree (trimesh.proximity), scikit-image and scipy come from requirements-test.txt: a
# missing one is an error, not a skip. Without nibabel there is neither NIfTI I/O nor its data.
nib = pytest.importorskip("nibabel", reason="nibabel is not installed: no NIfTI writer and no nibabel test volumes")
import skimage.measure as skmeasure  # noqa: E402
import trimesh  # noqa: E402
from scipy.sparse import coo_matrix  # noqa: E402
from scipy.sparse.csgraph import connected_components  # noqa: E402
from scipy.spatial import cKDTree  # noqa: E402

SIZES = (1, 2, 4)

# The component reference: MC at the voxels, or, where its count differs from ours, MC of the
# same trilinear interpolant sampled every 1/FINE_UP voxel (the function restricted to a
# sub-cell is trilinear again, so MC sees the same level set, with fewer ambiguous cells).
# Lewiner's tables at the voxels decide some ambiguous faces and cells otherwise than the
# interpolant; the counts settle as the sampling gets finer (measured 2026-12-05, scikit-image
# 0.26, at 1, 1/2, 1/4, 1/8, 1/16 and 1/32 voxel): checker 43, 34, 35, 35, 35, 35; noise 23,
# 22, 20, 21, 21, 21; nibabel's anatomical at its 60% quantile 268, 279, 283, 284, 284; and at
# 1/8 voxel anatomical at 30% 96, example4d at 30% and 60% 538 and 623: each the voxel scan's
# count (with its joins through cell interiors) and ours.
FINE_UP = 8
# Largest number of samples of a fine MC (float64: 8 bytes each, and about three times that
# while sampling): a finer sampling is tried only below it.
FINE_SAMPLES = 2.5e8

IMAGES = os.path.join(FIXTURES, "images")
NIBABEL_DATA = os.path.join(os.path.dirname(nib.__file__), "tests", "data")


# ---------------------------------------------------------------------------------------------
# Generated hard volumes (the voxels of xtask/src/suites/hard_volumes.rs).


class SplitMix64:
    """geom::SplitMix64: the same stream of numbers as the Rust generator."""

    MASK = (1 << 64) - 1

    def __init__(self, seed):
        self.s = seed & self.MASK

    def next_u64(self):
        self.s = (self.s + 0x9E3779B97F4A7C15) & self.MASK
        z = self.s
        z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & self.MASK
        z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & self.MASK
        return z ^ (z >> 31)

    def next_f64(self):
        return (self.next_u64() >> 11) * (1.0 / (1 << 53))


def grid(n):
    """Voxel index positions (i, j, k) of an n^3 grid, arrays indexed [i, j, k]."""
    return np.meshgrid(*(np.arange(n, dtype=np.float64),) * 3, indexing="ij")


def random_table(n, seed, draw):
    """n^3 values drawn in voxel order (x fastest), as an array indexed [i, j, k]."""
    rng = SplitMix64(seed)
    vals = np.array([draw(rng) for _ in range(n * n * n)], dtype=np.float64)
    return vals.reshape(n, n, n).transpose(2, 1, 0)


def rust_round(x):
    """f64::round: halves away from zero."""
    return np.sign(x) * np.floor(np.abs(x) + 0.5)


def gen_blobs():
    rng = SplitMix64(11)
    n = 36
    blobs = []
    for _ in range(80):
        c = np.array([rng.next_f64(), rng.next_f64(), rng.next_f64()]) * 30.0 + 3.0
        r = 0.3 + 2.7 * rng.next_f64() * rng.next_f64()
        blobs.append((c, r))
    i, j, k = grid(n)
    v = np.zeros((n, n, n))
    for c, r in blobs:
        d2 = (i - c[0]) ** 2 + (j - c[1]) ** 2 + (k - c[2]) ** 2
        v = np.maximum(v, np.exp(-d2 / (r * r)))
    return v.astype(np.float32), 0.5


def gen_sheet():
    n = 28
    nrm = np.array([0.3, 0.5, 1.0])
    nrm /= np.linalg.norm(nrm)
    i, j, k = grid(n)
    q = np.stack([i - 13.5, j - 13.5, k - 13.5], axis=-1)
    qn = q @ nrm
    d = qn - 0.02 * (q * q).sum(-1)
    r = np.linalg.norm(q - qn[..., None] * nrm, axis=-1)
    v = np.where(r > 11.0, 0.0, 1.0 - np.abs(d) / 0.35)
    return v.astype(np.float32), 0.0


def gen_tube():
    n = 28
    t = np.arange(2000) / 2000.0 * np.pi * 2 * 3.0
    pts = np.stack([13.5 + 8.0 * np.cos(t), 13.5 + 8.0 * np.sin(t), 4.0 + 20.0 * t / 18.85], axis=1)
    i, j, k = grid(n)
    d, _ = cKDTree(pts).query(np.stack([i, j, k], axis=-1).reshape(-1, 3))
    return (0.4 - d).reshape(n, n, n).astype(np.float32), 0.0


def gen_noise():
    return random_table(20, 5, lambda r: r.next_f64()).astype(np.float32), 0.5


def gen_checker():
    n = 14
    jitter = random_table(n, 3, lambda r: 0.2 * r.next_f64() - 0.1)
    i, j, k = grid(n)
    sign = np.where((i + j + k).astype(np.int64) % 2 == 0, 1.0, -1.0)
    inside = np.sqrt((i - 6.5) ** 2 + (j - 6.5) ** 2 + (k - 6.5) ** 2) <= 5.5
    return np.where(inside, jitter + sign, -1.0).astype(np.float32), 0.0


def gen_integer():
    n = 24
    i, j, k = grid(n)
    qx, qy, qz = i - 11.5, j - 11.5, k - 11.5
    f = 4.0 * (1.0 - np.sqrt(qx * qx + qy * qy + qz * qz) / 12.0) + 0.8 * np.sin(qx * 0.7) * np.cos(qy * 0.5)
    return np.clip(rust_round(f), 0.0, 4.0).astype(np.int16), 2.0


def gen_smooth_noise():
    from scipy.ndimage import gaussian_filter

    v = gaussian_filter(np.random.default_rng(7).random((24, 24, 24)), 1.2)
    return v.astype(np.float32), float(np.round(np.median(v), 4))


GENERATED = {
    "blobs": gen_blobs,
    "sheet": gen_sheet,
    "tube": gen_tube,
    "noise": gen_noise,
    "checker": gen_checker,
    "integer": gen_integer,
    "smooth-noise": gen_smooth_noise,
}


@functools.lru_cache(maxsize=None)
def generated(name):
    return GENERATED[name]()


# ---------------------------------------------------------------------------------------------
# The cases: name -> (how to get the file, iso or a foreground quantile).


def nibabel_volume(name, tmp_dir):
    """A volume of nibabel's test data: the file itself when 3D, else its first volume
    (written with the same header to a temporary NIfTI)."""
    path = os.path.join(NIBABEL_DATA, name)
    if not os.path.exists(path):
        pytest.skip(f"{path} is not in this nibabel ({nib.__version__})")
    img = nib.load(path)
    if len(img.shape) == 3:
        return path
    data = np.asanyarray(img.dataobj)[..., 0]
    out = os.path.join(tmp_dir, name.split(".")[0] + "_vol0.nii.gz")
    if not os.path.exists(out):
        nib.save(nib.Nifti1Image(data, None, header=img.header), out)
    return out


def foreground_quantile(path, q):
    """The q-quantile of the voxels above the data minimum (+ 0.5 on integer data, so that no
    voxel equals the iso value), rounded to 4 significant digits."""
    d = np.asanyarray(nib.load(path).dataobj)
    fg = d[d > d.min()]
    v = float(np.quantile(fg, q))
    if np.issubdtype(d.dtype, np.integer) and float(nib.load(path).dataobj.slope) == 1.0:
        return float(np.floor(v)) + 0.5
    return float(f"{v:.4g}")


CASES = {
    "mni-crop@171.2": (lambda tmp: os.path.join(IMAGES, "mni_t1_crop56.nii.gz"), 171.2),
    "mni-crop@190.5": (lambda tmp: os.path.join(IMAGES, "mni_t1_crop56.nii.gz"), 190.5),
    "mni-half@171.2": (lambda tmp: os.path.join(IMAGES, "mni_t1_half.nii.gz"), 171.2),
    "motor@3": (lambda tmp: os.path.join(IMAGES, "nilearn_motor_10426.nii.gz"), 3.0),
    "nib-anatomical@q30": (lambda tmp: nibabel_volume("anatomical.nii", tmp), ("q", 0.3)),
    "nib-anatomical@q60": (lambda tmp: nibabel_volume("anatomical.nii", tmp), ("q", 0.6)),
    "nib-reoriented@q30": (lambda tmp: nibabel_volume("reoriented_anat_moved.nii", tmp), ("q", 0.3)),
    "nib-reoriented@q60": (lambda tmp: nibabel_volume("reoriented_anat_moved.nii", tmp), ("q", 0.6)),
    "nib-example4d@q30": (lambda tmp: nibabel_volume("example4d.nii.gz", tmp), ("q", 0.3)),
    "nib-example4d@q60": (lambda tmp: nibabel_volume("example4d.nii.gz", tmp), ("q", 0.6)),
}
for _name, _gen in GENERATED.items():
    CASES[_name] = ("generated", _name)


def params():
    out = []
    for case in CASES:
        for k in SIZES:
            out.append(pytest.param(case, k, id=f"{case}-{k}vox"))
    return out


@pytest.fixture(scope="session")
def volumes_dir(tmp_path_factory):
    return str(tmp_path_factory.mktemp("mc_volumes"))


def case_file(case, tmp_dir):
    """(path of the NIfTI file, iso value) of a case."""
    spec = CASES[case]
    if spec[0] == "generated":
        name = spec[1]
        path = os.path.join(tmp_dir, f"{name}.nii.gz")
        data, iso = generated(name)
        if not os.path.exists(path):
            n = data.shape[0]
            aff = np.eye(4)
            aff[:3, 3] = -0.5 * (n - 1)  # 1 mm voxels, the grid centred on the origin
            img = nib.Nifti1Image(data, aff)
            img.set_sform(aff, code=1)
            img.set_qform(aff, code=1)
            nib.save(img, path)
        return path, iso
    get, iso = spec
    path = get(tmp_dir)
    if isinstance(iso, tuple):
        iso = foreground_quantile(path, iso[1])
    return path, iso


# ---------------------------------------------------------------------------------------------
# Marching cubes and the geometry helpers.


def nifti_volume(path):
    """Scaled voxels (float64, [i, j, k]) and the 4x4 affine the mesher uses (sform if its code
    is set, else qform, else pixdim)."""
    img = nib.load(path)
    hdr = img.header
    if int(hdr["sform_code"]) > 0:
        aff = img.get_sform()
    elif int(hdr["qform_code"]) > 0:
        aff = img.get_qform()
    else:
        aff = np.diag([float(p) if p != 0 else 1.0 for p in hdr["pixdim"][1:4]] + [1.0])
    return np.asanyarray(img.dataobj, dtype=np.float64), aff


def trilinear_samples(vol, s):
    """The trilinear interpolant of `vol` sampled every 1/s voxel (the nodes kept: sample s*i is
    node i), one axis at a time (linear along each axis is trilinear)."""
    out = vol
    for a in range(3):
        n = out.shape[a]
        x = np.arange((n - 1) * s + 1, dtype=np.float64) / s
        i0 = np.minimum(np.floor(x).astype(np.int64), n - 2)
        t = (x - i0).reshape([-1 if b == a else 1 for b in range(3)])
        out = np.take(out, i0, axis=a) * (1.0 - t) + np.take(out, i0 + 1, axis=a) * t
    return out


def mc_mesh(path, iso, up):
    """MC of the volume padded by one layer of the background (the data minimum, as the mesher
    continues a bright foreground), or with `up` > 1 of its trilinear interpolant sampled every
    1/up voxel (the same level set, its ambiguous cells resolved by sampling): vertices in voxel
    coordinates, duplicates merged, faces, and the NIfTI affine."""
    vol, aff = nifti_volume(path)
    assert vol.ndim == 3, vol.shape
    pad = np.pad(vol, 1, constant_values=float(vol.min()))
    if up > 1:
        pad = trilinear_samples(pad, up)
    v, f, _, _ = skmeasure.marching_cubes(pad, level=iso, method="lewiner", allow_degenerate=False)
    del pad
    v = v.astype(np.float64) / up - 1.0  # undo the sampling and the padding
    v, inv = np.unique(v, axis=0, return_inverse=True)
    return v, inv.reshape(-1)[f], aff


@functools.lru_cache(maxsize=None)
def marching_cubes(path, iso):
    """MC's mesh at the voxels in world coordinates, its component count, the voxel h (smallest
    spacing) and the affine."""
    v, f, aff = mc_mesh(path, iso, 1)
    world = v @ aff[:3, :3].T + aff[:3, 3]
    h = float(np.linalg.norm(aff[:3, :3], axis=0).min())
    return world, f, components(f, len(world)), h, aff


@functools.lru_cache(maxsize=None)
def fine_components(path, iso):
    """(sampling, MC's component count) of the trilinear interpolant sampled every 1/FINE_UP
    voxel, or 1/4, 1/2 when that would exceed FINE_SAMPLES samples (the count only is kept)."""
    shape = np.array(nib.load(path).shape[:3]) + 2  # the padded volume
    up = next((u for u in (FINE_UP, 4, 2) if np.prod((shape - 1) * u + 1) <= FINE_SAMPLES), 1)
    v, f, _ = mc_mesh(path, iso, up)
    return up, components(f, len(v))


def components(faces, n):
    """Connected components of a triangle mesh by shared vertices (unused vertices left out)."""
    if len(faces) == 0:
        return 0
    e = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]]])
    g = coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n))
    _, lab = connected_components(g, directed=False)
    return len(np.unique(lab[np.unique(faces)]))


def vertex_labels(faces, n):
    """Component label of every vertex (by shared vertices)."""
    e = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]]])
    return connected_components(coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n)), directed=False)[1]


def joined_by_mc(v, f, mc_v, mc_f, limit=5):
    """Where MC and ours differ: MC components holding several of our components (each of ours
    goes to the MC component of most of its vertices' nearest MC vertices), and MC components
    holding none of ours; as text, with the place of the smaller of ours."""
    lo, lm = vertex_labels(f, len(v)), vertex_labels(mc_f, len(mc_v))
    _, nn = cKDTree(mc_v).query(v)
    used = np.unique(f)
    pairs = np.unique(np.stack([lo[used], lm[nn[used]]], axis=1), axis=0, return_counts=True)
    best = {}
    for (o, m), c in zip(*pairs):
        if c > best.get(o, (None, -1))[1]:
            best[o] = (m, c)
    held = {}
    for o, (m, _) in best.items():
        held.setdefault(m, []).append(o)
    out = []
    for m, os_ in held.items():
        if len(os_) > 1:
            sizes = [(int((lo == o).sum()), o) for o in os_]
            sizes.sort()
            places = ", ".join("({:.1f}, {:.1f}, {:.1f}) {} vertices".format(*v[lo == o].mean(0), n) for n, o in sizes[:-1][:3])
            out.append(f"one MC component holds {len(os_)} of ours: the smaller at {places}")
    none = set(np.unique(lm[mc_f[:, 0]])) - set(held)
    for m in sorted(none)[:limit]:
        out.append("an MC component near none of ours at ({:.1f}, {:.1f}, {:.1f})".format(*mc_v[lm == m].mean(0)))
    return "; ".join(out[:limit]) + (f"; ... ({len(out)} in all)" if len(out) > limit else "")


def vertex_faces(faces, n):
    """CSR of the faces around each vertex: (offsets, face ids)."""
    v = faces.reshape(-1)
    order = np.argsort(v, kind="stable")
    offsets = np.concatenate([[0], np.cumsum(np.bincount(v, minlength=n))])
    return offsets, order // 3


def distance_upper(points, verts, faces, bound, k=4, chunk=20000):
    """Upper bounds of the distances from `points` to the triangle mesh (verts, faces): the
    exact distance to the nearest of the triangles around the k vertices nearest each point;
    then the exact distance to the mesh (trimesh.proximity) for the points beyond `bound` (the
    2000 farthest) and for the farthest until the largest value is exact."""
    from trimesh.triangles import closest_point

    tree = cKDTree(verts)
    off, fid = vertex_faces(faces, len(verts))
    kk = min(k, len(verts))
    out = np.empty(len(points))
    for s in range(0, len(points), chunk):
        p = points[s:s + chunk]
        d0, nv = tree.query(p, k=kk)
        nv = nv.reshape(len(p), kk)
        best = np.asarray(d0).reshape(len(p), kk)[:, 0].copy()  # the nearest vertex
        # Candidate (point, face) pairs: every face around each of the k vertices, once.
        cnt = (off[nv + 1] - off[nv]).reshape(-1)
        rows = np.repeat(np.repeat(np.arange(len(p)), kk), cnt)
        local = np.arange(cnt.sum()) - np.repeat(np.cumsum(cnt) - cnt, cnt)
        cand = fid[np.repeat(off[nv].reshape(-1), cnt) + local]
        pair = np.sort(rows * len(faces) + cand)
        pair = pair[np.r_[True, pair[1:] != pair[:-1]]]
        rows, cand = pair // len(faces), pair % len(faces)
        q = closest_point(verts[faces[cand]], p[rows])
        np.minimum.at(best, rows, np.linalg.norm(q - p[rows], axis=1))
        out[s:s + chunk] = best
    # Exact where the bound fails, then until the largest value is exact.
    exact = np.zeros(len(out), dtype=bool)
    mesh = trimesh.Trimesh(verts, faces, process=False)
    order = np.argsort(out)
    top = order[-2000:][out[order[-2000:]] > bound]
    for _ in range(20):
        top = top[~exact[top]]
        if len(top):
            _, d, _ = trimesh.proximity.closest_point(mesh, points[top])
            out[top] = np.minimum(out[top], d)
            exact[top] = True
        if len(out) == 0 or exact[np.argmax(out)]:
            break
        order = np.argsort(np.where(exact, -np.inf, out))
        top = order[-64:]
    return out


def solid_angle_sum(p, tri):
    """Winding number of the triangles `tri` (m, 3, 3) at the point p (Van Oosterom-Strackee)."""
    a, b, c = tri[:, 0] - p, tri[:, 1] - p, tri[:, 2] - p
    la, lb, lc = (np.linalg.norm(x, axis=1) for x in (a, b, c))
    det = np.einsum("ij,ij->i", a, np.cross(b, c))
    den = la * lb * lc + np.einsum("ij,ij->i", a, b) * lc + np.einsum("ij,ij->i", b, c) * la + np.einsum("ij,ij->i", c, a) * lb
    return float(np.sum(2.0 * np.arctan2(det, den)) / (4.0 * np.pi))


def winding_number(p, tri, lo_yz, hi_yz, maxx, keep):
    """Winding number at p of the closed triangles tri[keep(i)] (tri: (m, 3, 3)): the signed
    crossings of the ray from p along +x (a face crossed counts the sign of its normal's x); by
    solid angles when the ray passes within 1e-12 (barycentric) of an edge."""
    cand = np.flatnonzero((lo_yz[:, 0] <= p[1]) & (p[1] <= hi_yz[:, 0]) & (lo_yz[:, 1] <= p[2]) & (p[2] <= hi_yz[:, 1]) & (maxx > p[0]))
    cand = cand[keep(cand)]
    if len(cand) == 0:
        return 0.0
    t = tri[cand]
    a, b, c = (t[:, i, 1:] - p[1:] for i in range(3))

    def cross(u, v):
        return u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]

    d = cross(b - a, c - a)  # the x of the face's normal (times twice its area)
    with np.errstate(divide="ignore", invalid="ignore"):
        w = np.stack([cross(b, c), cross(c, a), cross(a, b)], axis=1) / d[:, None]
    inside = (d != 0) & (w >= 0).all(axis=1)
    near = (d == 0) | (np.abs(w) < 1e-12).any(axis=1)
    if near.any():
        return solid_angle_sum(p, tri[keep(np.arange(len(tri)))])
    x = (w[inside] * t[inside][:, :, 0]).sum(axis=1)
    return float(np.sign(d[inside][x > p[0]]).sum())


def orientation_errors(v, f):
    """Components whose signed volume does not have the sign their nesting asks for (outward:
    positive, or negative for a cavity's wall, where the other components wind once around
    its vertices)."""
    n = len(v)
    e = np.concatenate([f[:, [0, 1]], f[:, [1, 2]]])
    _, lab = connected_components(coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n)), directed=False)
    flab = lab[f[:, 0]]
    t = v[f]
    vol6 = np.einsum("ij,ij->i", t[:, 0], np.cross(t[:, 1], t[:, 2]))
    order = np.argsort(flab, kind="stable")
    comps, starts = np.unique(flab[order], return_index=True)
    ts = t[order]
    lo = np.minimum.reduceat(ts.min(axis=1), starts)
    hi = np.maximum.reduceat(ts.max(axis=1), starts)
    ends = np.append(starts[1:], len(order))
    vols = np.add.reduceat(vol6[order], starts) / 6.0
    lo_yz, hi_yz, maxx = t[:, :, 1:].min(axis=1), t[:, :, 1:].max(axis=1), t[:, :, 0].max(axis=1)
    errors = []
    for i in range(len(comps)):
        p = ts[starts[i], 0]
        # The winding number of the other components at a vertex of this one.
        w = winding_number(p, t, lo_yz, hi_yz, maxx, lambda f, c=comps[i]: flab[f] != c)
        vol = vols[i]
        wi = int(round(w))
        ok = abs(w - wi) < 1e-3 and ((wi == 0 and vol > 0) or (wi == 1 and vol < 0))
        if not ok:
            errors.append(f"component at ({p[0]:.1f}, {p[1]:.1f}, {p[2]:.1f}): volume {vol:.3g}, winding of the others {w:.3f}")
    return errors


def decisions_text(report):
    ds = report["stats"]["component_decisions"]
    if not ds:
        return "no component decisions in the report"
    return "; ".join(
        "{} comp {} at ({:.1f}, {:.1f}, {:.1f}) size {:.2f}".format(d["kind"], d["component"], *d["center"], d["size"])
        for d in ds
    )


MANIFOLD_CHECKS = ("closed", "edge-manifold", "vertex-manifold", "oriented", "self-intersections")


def verify_status(report):
    """{check name: status} of the report's verify section."""
    checks = report["verify"]["checks"]
    return {c["name"]: c["status"] for c in checks}


# ---------------------------------------------------------------------------------------------
# The test.

MEASURED = []  # rows for the table of docs/GUIDE.md (printed with -s)


@pytest.mark.parametrize("case,k", params())
def test_image_mesh_vs_marching_cubes(xtask, volumes_dir, tmp_path, case, k):
    path, iso = case_file(case, volumes_dir)
    mc_v, mc_f, mc_comps, h, aff = marching_cubes(path, iso)
    sigma = k * h
    bound = h + sigma
    ply, rep = tmp_path / "out.ply", tmp_path / "r.json"
    r = subprocess.run(
        [xtask, "mesh", path, "--iso", repr(iso), "--size", repr(sigma), "-o", str(ply), "--report", str(rep), "--quiet"],
        capture_output=True,
        text=True,
    )
    assert r.returncode == 0, r.stderr
    report = json.loads(rep.read_text())

    # The affine MC's vertices are mapped with is the mesher's.
    assert np.allclose(np.asarray(report["input_stats"]["image"]["affine"]), aff[:3], atol=1e-6 * (1 + np.abs(aff[:3]).max()))

    m = trimesh.load(str(ply), process=False, force="mesh")
    v, f = np.asarray(m.vertices, dtype=np.float64), np.asarray(m.faces, dtype=np.int64)
    assert len(f) > 0
    # Merge coincident vertices, if any (a PLY of ours has none: then nothing changes).
    mv, inv = np.unique(v, axis=0, return_inverse=True)
    assert len(mv) == len(v), f"{len(v) - len(mv)} duplicate vertices in our PLY"
    area = 0.5 * np.linalg.norm(np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]), axis=1)
    degenerate = int(((f[:, 0] == f[:, 1]) | (f[:, 1] == f[:, 2]) | (f[:, 2] == f[:, 0]) | (area <= 0)).sum())
    assert degenerate == 0, f"{degenerate} degenerate faces"
    assert m.is_watertight, "not watertight"
    assert m.is_winding_consistent, "winding not consistent"
    assert m.volume > 0, f"total volume {m.volume} <= 0"
    bad = orientation_errors(v, f)
    assert not bad, "components not oriented outward: " + "; ".join(bad[:5])
    st = verify_status(report)
    failed = {c: st.get(c) for c in MANIFOLD_CHECKS if st.get(c) != "PASS"}
    assert not failed, f"verify: {failed}"

    # The mapping: the bounding boxes agree within one voxel + sigma.
    gap = max(np.abs(v.min(0) - mc_v.min(0)).max(), np.abs(v.max(0) - mc_v.max(0)).max())

    ours = components(f, len(v))
    dropped = sum(1 for d in report["stats"]["component_decisions"] if d["kind"] == "dropped")
    up, mc_fine = (1, mc_comps) if ours + dropped == mc_comps else fine_components(path, iso)
    scan = report["input_stats"]["image"]["components"]

    d_mc_to_ours = distance_upper(mc_v, v, f, bound)
    d_ours_to_mc = distance_upper(v, mc_v, mc_f, bound)
    far1 = int((d_mc_to_ours > bound).sum())
    far2 = int((d_ours_to_mc > bound).sum())
    row = dict(case=case, k=k, iso=iso, ours=ours, dropped=dropped, mc=mc_comps, mc_fine=mc_fine, fine_up=up, scan=scan,
               mc_to_ours=float(d_mc_to_ours.max()), ours_to_mc=float(d_ours_to_mc.max()), bound=bound,
               h=h, vertices=len(v), far1=far1, far2=far2)
    MEASURED.append(row)
    print("MEASURED " + json.dumps(row))

    assert gap <= bound, f"bounding boxes differ by {gap:.3f} > {bound:.3f}: the affine mapping is wrong"
    if ours + dropped not in (mc_comps, mc_fine):
        pytest.fail(
            f"components: ours {ours} + dropped {dropped} != marching cubes {mc_comps} (of the interpolant "
            f"sampled at 1/{up} voxel: {mc_fine}; voxel scan {scan}); "
            f"the report's decisions: {decisions_text(report)}; where MC differs: {joined_by_mc(v, f, mc_v, mc_f)}; "
            f"distances (h + sigma = {bound:.3f}): MC -> ours max {d_mc_to_ours.max():.3f} ({far1} beyond), "
            f"ours -> MC max {d_ours_to_mc.max():.3f} ({far2} beyond)",
            pytrace=False,
        )
    worst1 = mc_v[np.argmax(d_mc_to_ours)]
    worst2 = v[np.argmax(d_ours_to_mc)]
    assert far1 == 0 and far2 == 0, (
        f"two-sided distance over h + sigma = {bound:.3f}: MC -> ours max {d_mc_to_ours.max():.3f} "
        f"({far1} of {len(mc_v)} MC vertices beyond, farthest at ({worst1[0]:.1f}, {worst1[1]:.1f}, {worst1[2]:.1f})); "
        f"ours -> MC max {d_ours_to_mc.max():.3f} ({far2} of {len(v)} of our vertices beyond, farthest at "
        f"({worst2[0]:.1f}, {worst2[1]:.1f}, {worst2[2]:.1f}))"
    )
