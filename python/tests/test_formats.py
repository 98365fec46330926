"""Independent readers of the formats of issue #20 (ours: cross-checks with the Python tools).

The built command line (target/release/xtask) writes each new mesh format, and trimesh (.glb),
meshio (.vtk), nibabel (.gii) and the standard library's XML parser (.vtp: meshio reads .vtu,
not .vtp) read it back: the same vertices, the same faces and the same world coordinates as
the PLY of the same run. Each image fixture of fixtures/images/formats/ is read with nibabel,
pynrrd, SimpleITK or zarr: the voxels must be the generator's, and the world affine (in
NIfTI's RAS+ frame; NRRD and MetaImage are LPS+) must be the one the CLI reports.
Missing packages skip their tests; a missing binary skips everything (build it with
`cargo build --release -p xtask`).
"""
import json
import os
import subprocess
import xml.etree.ElementTree as ET

import pytest

np = pytest.importorskip("numpy")

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
XTASK = os.path.join(ROOT, "target", "release", "xtask")
FIX = os.path.join(ROOT, "fixtures", "images", "formats")
LPS = np.diag([-1.0, -1.0, 1.0])


def run_mesh(tmp, image, out):
    if not os.path.exists(XTASK):
        pytest.skip("target/release/xtask is not built")
    report = os.path.join(tmp, out + ".json")
    cmd = [XTASK, "mesh", "-q", image, "--iso", "500", "--size", "1", "--no-verify",
           "-o", os.path.join(tmp, out), "--report", report]
    r = subprocess.run(cmd, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    with open(report) as f:
        return json.load(f)


def read_ply(path):
    trimesh = pytest.importorskip("trimesh")
    m = trimesh.load(path, process=False)
    return np.asarray(m.vertices, dtype=np.float64), np.asarray(m.faces, dtype=np.int64)


@pytest.fixture(scope="module")
def meshes(tmp_path_factory):
    tmp = str(tmp_path_factory.mktemp("formats"))
    image = os.path.join(FIX, "blob_oblique.nii.gz")
    for ext in ["ply", "glb", "vtk", "vtp", "gii"]:
        run_mesh(tmp, image, "m." + ext)
    v, f = read_ply(os.path.join(tmp, "m.ply"))
    assert len(v) > 100 and len(f) > 100
    return tmp, v, f


def test_glb_with_trimesh(meshes):
    tmp, v, f = meshes
    trimesh = pytest.importorskip("trimesh")
    m = trimesh.load(os.path.join(tmp, "m.glb"), force="mesh", process=False)
    assert np.array_equal(np.asarray(m.faces), f)
    assert np.array_equal(np.asarray(m.vertices, dtype=np.float32), v.astype(np.float32))


def test_vtk_with_meshio(meshes):
    tmp, v, f = meshes
    meshio = pytest.importorskip("meshio")
    m = meshio.read(os.path.join(tmp, "m.vtk"))
    assert np.array_equal(m.points, v)  # double precision, exact
    assert np.array_equal(m.cells_dict["triangle"], f)
    angle = np.ravel(m.cell_data["min_angle_deg"][0])
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]

    def ang(p, q, r):
        u, w = q - p, r - p
        return np.degrees(np.arctan2(np.linalg.norm(np.cross(u, w), axis=1), (u * w).sum(1)))

    expect = np.minimum(np.minimum(ang(a, b, c), ang(b, c, a)), ang(c, a, b))
    assert np.allclose(angle, expect, atol=1e-9)
    assert angle.min() > 20.0
    rs = np.ravel(m.cell_data["r_over_sigma"][0])
    assert rs.max() <= 1.0 + 1e-12 and rs.min() > 0.0


def test_vtp_with_xml(meshes):
    tmp, v, f = meshes
    root = ET.parse(os.path.join(tmp, "m.vtp")).getroot()
    assert root.get("type") == "PolyData"

    def array(parent, name=None):
        for p in root.iter(parent):
            for d in p.iter("DataArray"):
                if name is None or d.get("Name") == name:
                    return np.array(d.text.split(), dtype=np.float64)
        raise AssertionError(f"no {parent}/{name}")

    assert np.array_equal(array("Points").reshape(-1, 3), v)
    conn = array("Polys", "connectivity").astype(np.int64)
    offsets = array("Polys", "offsets").astype(np.int64)
    assert np.array_equal(offsets, 3 * np.arange(1, len(f) + 1))
    assert np.array_equal(conn.reshape(-1, 3), f)
    assert len(array("CellData", "min_angle_deg")) == len(f)


def test_gii_with_nibabel(meshes):
    tmp, v, f = meshes
    nib = pytest.importorskip("nibabel")
    g = nib.load(os.path.join(tmp, "m.gii"))
    coords, tris = g.agg_data(("pointset", "triangle"))
    assert np.array_equal(tris, f)
    assert np.array_equal(coords, v.astype(np.float32))  # world millimetres, as stored
    cs = g.darrays[0].coordsys
    assert cs.dataspace == cs.xformspace == nib.nifti1.xform_codes["scanner"]
    assert np.array_equal(np.asarray(cs.xform), np.eye(4))


def cli_affine(tmp, image):
    r = run_mesh(tmp, image, "a.ply")
    a = np.array(r["input_stats"]["image"]["affine"], dtype=np.float64)
    assert r["input_stats"]["image"]["dims"] == [24, 20, 16]
    return a[:, :3], a[:, 3]


@pytest.fixture(scope="module")
def voxels():
    return np.load(os.path.join(FIX, "blob_voxels_i16.npy"))


@pytest.mark.parametrize("name", ["blob_oblique.nii.gz", "blob_aligned.nii.gz"])
def test_nifti_with_nibabel(tmp_path, voxels, name):
    nib = pytest.importorskip("nibabel")
    img = nib.load(os.path.join(FIX, name))
    assert np.array_equal(np.asarray(img.dataobj), voxels)
    m, t = cli_affine(str(tmp_path), os.path.join(FIX, name))
    assert np.array_equal(img.affine[:3, :3], m) and np.array_equal(img.affine[:3, 3], t)


@pytest.mark.parametrize("name", ["blob_oblique.nrrd", "blob_oblique_gz.nrrd",
                                  "blob_oblique_detached.nhdr", "blob_aligned.nrrd"])
def test_nrrd_with_pynrrd(tmp_path, voxels, name):
    nrrd = pytest.importorskip("nrrd")
    data, h = nrrd.read(os.path.join(FIX, name))  # index order F: [i, j, k]
    assert np.array_equal(data, voxels)
    assert h["space"] == "left-posterior-superior"
    m, t = cli_affine(str(tmp_path), os.path.join(FIX, name))
    assert np.array_equal(LPS @ np.asarray(h["space directions"], dtype=np.float64).T, m)
    assert np.array_equal(LPS @ np.asarray(h["space origin"], dtype=np.float64), t)


@pytest.mark.parametrize("name", ["blob_oblique.mha", "blob_oblique.mhd", "blob_aligned.mha"])
def test_metaimage_with_simpleitk(tmp_path, voxels, name):
    sitk = pytest.importorskip("SimpleITK")
    img = sitk.ReadImage(os.path.join(FIX, name))
    assert np.array_equal(sitk.GetArrayFromImage(img).transpose(2, 1, 0), voxels)
    d = np.array(img.GetDirection()).reshape(3, 3)  # ITK: column j = axis j, LPS
    m_lps = d @ np.diag(img.GetSpacing())
    m, t = cli_affine(str(tmp_path), os.path.join(FIX, name))
    assert np.array_equal(LPS @ m_lps, m)
    assert np.array_equal(LPS @ np.array(img.GetOrigin()), t)
    # SimpleITK's own voxel-to-world agrees with the CLI's affine on a corner voxel.
    p = np.array(img.TransformIndexToPhysicalPoint((23, 19, 15)))
    assert np.allclose(LPS @ p, m @ np.array([23, 19, 15]) + t, atol=1e-12)


@pytest.mark.parametrize("name", ["blob_aligned_v2.ome.zarr", "blob_aligned_v3.ome.zarr"])
def test_ome_zarr_with_zarr(tmp_path, voxels, name):
    zarr = pytest.importorskip("zarr")
    g = zarr.open_group(os.path.join(FIX, name), mode="r")
    attrs = g.attrs.asdict()
    ms = (attrs.get("ome", attrs))["multiscales"][0]
    assert [a["name"] for a in ms["axes"]] == ["z", "y", "x"]
    ds = ms["datasets"][0]
    data = np.asarray(g[ds["path"]][...]).transpose(2, 1, 0)  # zyx -> [i, j, k]
    assert np.array_equal(data, voxels)
    tr = {c["type"]: c for c in ds["coordinateTransformations"]}
    scale = np.array(tr["scale"]["scale"][::-1])
    shift = np.array(tr["translation"]["translation"][::-1])
    m, t = cli_affine(str(tmp_path), os.path.join(FIX, name))
    assert np.array_equal(np.diag(scale), m) and np.array_equal(shift, t)


def test_the_same_volume_gives_the_same_mesh_bytes(tmp_path):
    """The Rust test checks it too; here through the files the CLI writes."""
    out = {}
    for name in ["blob_aligned.nii.gz", "blob_aligned.nrrd", "blob_aligned.mha",
                 "blob_aligned_v2.ome.zarr", "blob_aligned_v3.ome.zarr"]:
        run_mesh(str(tmp_path), os.path.join(FIX, name), name + ".ply")
        with open(os.path.join(str(tmp_path), name + ".ply"), "rb") as f:
            out[name] = f.read()
    assert len(set(out.values())) == 1


@pytest.fixture(scope="module")
def series_4d(tmp_path_factory):
    """nibabel's real fMRI series example4d.nii.gz (128 x 96 x 24 x 2, an oblique sform),
    written as 4D NRRD by pynrrd (the frames' axis first, as older Slicer DWI files, and
    last) and as 4D MetaImage by SimpleITK, with each frame as a 3D file beside it."""
    nib = pytest.importorskip("nibabel")
    nrrd = pytest.importorskip("nrrd")
    sitk = pytest.importorskip("SimpleITK")
    tmp = str(tmp_path_factory.mktemp("series4d"))
    src = os.path.join(os.path.dirname(nib.__file__), "tests", "data", "example4d.nii.gz")
    img = nib.load(src)
    d, a = np.asarray(img.dataobj), img.affine
    dirs = [list(a[:3, i]) for i in range(3)]
    none = [np.nan] * 3
    base = {"space": "right-anterior-superior", "space origin": list(a[:3, 3])}
    nrrd.write(os.path.join(tmp, "last.nrrd"), d,
               dict(base, **{"space directions": dirs + [none], "kinds": ["domain"] * 3 + ["list"]}))
    nrrd.write(os.path.join(tmp, "first.nrrd"), np.ascontiguousarray(np.moveaxis(d, 3, 0)),
               dict(base, **{"space directions": [none] + dirs, "kinds": ["list"] + ["domain"] * 3}))
    s4 = sitk.ReadImage(src)
    sitk.WriteImage(s4, os.path.join(tmp, "s.mha"))
    for t in range(2):
        nrrd.write(os.path.join(tmp, f"f{t}.nrrd"), np.ascontiguousarray(d[..., t]),
                   dict(base, **{"space directions": dirs, "kinds": ["domain"] * 3}))
        size = list(s4.GetSize()[:3]) + [0]
        sitk.WriteImage(sitk.Extract(s4, size, [0, 0, 0, t]), os.path.join(tmp, f"f{t}.mha"))
    return src, tmp


def mesh_bytes(tmp, image, out, *extra):
    if not os.path.exists(XTASK):
        pytest.skip("target/release/xtask is not built")
    path = os.path.join(tmp, out)
    cmd = [XTASK, "mesh", "-q", image, "--iso", "420.5", "--size", "6", "--no-verify",
           "-o", path, *extra]
    r = subprocess.run(cmd, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    with open(path, "rb") as f:
        return f.read(), r.stderr


@pytest.mark.parametrize("frame", [0, 1])
def test_a_4d_nrrd_frame_is_the_nifti_frame_and_pynrrds_3d_file(series_4d, frame):
    src, tmp = series_4d
    want, _ = mesh_bytes(tmp, src, f"nii{frame}.ply", "--frame", str(frame))
    three, _ = mesh_bytes(tmp, os.path.join(tmp, f"f{frame}.nrrd"), f"n3d{frame}.ply")
    assert three == want
    for name in ["first.nrrd", "last.nrrd"]:
        got, err = mesh_bytes(tmp, os.path.join(tmp, name), f"{name}{frame}.ply",
                              "--frame", str(frame))
        assert got == want, name
        assert f"frame {frame} of 2 along axis" in err and "kinds: list" in err


@pytest.mark.parametrize("frame", [0, 1])
def test_a_4d_metaimage_frame_is_simpleitks_extracted_volume(series_4d, frame):
    _, tmp = series_4d
    want, _ = mesh_bytes(tmp, os.path.join(tmp, f"f{frame}.mha"), f"m3d{frame}.ply")
    got, err = mesh_bytes(tmp, os.path.join(tmp, "s.mha"), f"m4d{frame}.ply", "--frame", str(frame))
    assert got == want
    assert f"frame {frame} of 2" in err


def test_a_4d_series_without_a_frame_names_the_range(series_4d):
    _, tmp = series_4d
    for name in ["last.nrrd", "s.mha"]:
        r = subprocess.run([XTASK, "mesh", os.path.join(tmp, name), "--iso", "420.5"],
                           capture_output=True, text=True)
        assert r.returncode != 0
        assert "pass --frame K (0 to 1)" in r.stderr, r.stderr


@pytest.fixture(scope="module")
def wide_labels(tmp_path_factory):
    """A uint64 segmentation (connectomics ids above 2^32) as nibabel writes it (NIfTI
    datatype 1280) and as zarr writes an OME-Zarr v0.5 array."""
    nib = pytest.importorskip("nibabel")
    zarr = pytest.importorskip("zarr")
    tmp = str(tmp_path_factory.mktemp("wide"))
    v = np.zeros((24, 20, 16), np.uint64)
    ids = [3, 2**40 + 7, 2**40 + 8, 2**45]
    for n, l in enumerate(ids):
        v[2 + 5 * n:6 + 5 * n, 4:12, 3:11] = l
    aff = np.diag([8.0, 8.0, 40.0, 1.0])
    nii = os.path.join(tmp, "seg.nii.gz")
    nib.save(nib.Nifti1Image(v, aff, dtype=np.uint64), nii)
    assert nib.load(nii).get_data_dtype() == np.uint64
    zyx = np.ascontiguousarray(v.transpose(2, 1, 0))
    z = os.path.join(tmp, "seg.ome.zarr")
    g = zarr.open_group(z, mode="w", zarr_format=3)
    a = g.create_array("0", shape=zyx.shape, chunks=(8, 10, 12), dtype=zyx.dtype)
    a[:] = zyx
    g.attrs["ome"] = {"version": "0.5", "multiscales": [{
        "axes": [{"name": n, "type": "space"} for n in "zyx"],
        "datasets": [{"path": "0", "coordinateTransformations": [
            {"type": "scale", "scale": [40.0, 8.0, 8.0]}]}]}]}
    return v, ids, nii, z


def test_uint64_labels_are_read_exactly(wide_labels, tmp_path):
    """Each file's labels are nibabel's ids; label 2^40 + 8 (next to 2^40 + 7) meshes to the
    same bytes from the NIfTI, from the OME-Zarr and from the array itself (as float64)."""
    rdt = pytest.importorskip("rdt_mesher")
    v, ids, nii, z = wide_labels
    for path in [nii, z]:
        assert sorted(rdt.mesh_file(path, labels="all", size=6)) == ids, path
    out = []
    for n, path in enumerate([nii, z]):
        ply = os.path.join(str(tmp_path), f"m{n}.ply")
        r = subprocess.run([XTASK, "mesh", "-q", path, "--label", str(2**40 + 8), "--size", "4",
                            "--no-verify", "-o", ply], capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        assert "u64 voxels held as f64" in r.stderr, r.stderr
        with open(ply, "rb") as f:
            out.append(f.read())
    assert out[0] == out[1]
    vert, _ = read_ply(os.path.join(str(tmp_path), "m0.ply"))
    # Fortran order, as nibabel gives a file's array (a C-ordered one is read as the
    # transposed grid: the same surface, another mesh).
    m = rdt.mesh_image(np.asfortranarray(v), affine=np.diag([8.0, 8.0, 40.0, 1.0]),
                       label=2**40 + 8, size=4)
    assert np.allclose(np.asarray(m.vertices), vert, atol=1e-9)
