"""A NIfTI fixture meshed from Python (nibabel's arrays, or the library's reader) gives the
CLI's mesh, bit for bit, and the CLI's report."""

import json

import meshio
import nibabel as nib
import numpy as np

import rdt_mesher
from conftest import PHANTOM, run_cli

# Fields that differ by nature between two runs or two front ends (timings, the scheduler's
# batch counters, the paths).
VOLATILE = {"time_total_s", "time_delaunay_s", "time_oracle_s", "time_verify_s", "input", "output"}


def strip(v):
    if isinstance(v, dict):
        return {k: strip(x) for k, x in v.items() if k not in VOLATILE and not k.startswith("time_") and not k.endswith("_batches")}
    if isinstance(v, list):
        return [strip(x) for x in v]
    return v


def cli_mesh(xtask, tmp_path):
    ply = tmp_path / "cli.ply"
    rep = tmp_path / "cli.json"
    run_cli(xtask, PHANTOM, "--iso", "300", "-o", str(ply), "--report", str(rep))
    m = meshio.read(ply)
    return m.points, m.cells_dict["triangle"], json.loads(rep.read_text())


def test_nibabel_image_meshes_to_the_cli_mesh(xtask, tmp_path):
    v_cli, f_cli, rep_cli = cli_mesh(xtask, tmp_path)
    img = nib.load(PHANTOM)
    m = rdt_mesher.mesh_nifti(img, iso=300)
    assert m.vertices.dtype == np.float64 and m.faces.dtype == np.int64
    assert m.vertices.shape == v_cli.shape
    assert np.array_equal(m.vertices, v_cli)  # bit-identical
    assert np.array_equal(m.faces, f_cli)
    # The same run from get_fdata() (float64, nibabel's axis order) and the affine.
    m2 = rdt_mesher.mesh_image(img.get_fdata(), affine=img.affine, iso=300)
    assert np.array_equal(m2.vertices, v_cli)
    assert m.report["stats"]["vertices"] == rep_cli["stats"]["vertices"] == len(v_cli)


def test_mesh_file_gives_the_cli_mesh_and_report(xtask, tmp_path):
    v_cli, f_cli, rep_cli = cli_mesh(xtask, tmp_path)
    m = rdt_mesher.mesh_file(PHANTOM, iso=300)
    assert np.array_equal(m.vertices, v_cli) and np.array_equal(m.faces, f_cli)
    assert strip(m.report) == strip(rep_cli)
    assert m.report["input"] == PHANTOM
    assert m.passed is True
    assert m.certificate is not None


def test_save_writes_what_the_cli_writes(xtask, tmp_path):
    v_cli, f_cli, _ = cli_mesh(xtask, tmp_path)
    m = rdt_mesher.mesh_file(PHANTOM, iso=300)
    out = tmp_path / "py.ply"
    m.save(out)
    assert out.read_bytes() == (tmp_path / "cli.ply").read_bytes()
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []


FUNCTIONAL = PHANTOM.replace("phantom_i16_32.nii.gz", "nibabel_functional.nii.gz")
RESAMPLED = PHANTOM.replace("phantom_i16_32.nii.gz", "nibabel_resampled_anat_moved.nii")


def test_a_frame_of_a_series_is_the_mesh_of_that_volume(tmp_path):
    # nibabel's functional.nii (17 x 21 x 3 x 20 int16, scl_slope 0.0754): frame k read by the
    # library meshes, bit for bit, as the 3D file nibabel writes from its volume k (the same
    # int16 voxels and scaling: the library treats quantized voxels as such, so the float64
    # array of get_fdata() is not the same input); a series without a frame is refused with
    # the flag's name.
    img = nib.load(FUNCTIONAL)
    assert img.shape == (17, 21, 3, 20)
    raw = np.asanyarray(img.dataobj.get_unscaled())
    for k in (0, 7, 19):
        one = nib.Nifti1Image(raw[..., k], img.affine, header=img.header)
        one.header.set_slope_inter(img.dataobj.slope, img.dataobj.inter)
        path = tmp_path / f"frame{k}.nii"
        nib.save(one, path)
        back = nib.load(path)
        assert np.array_equal(np.asanyarray(back.dataobj.get_unscaled()), raw[..., k])
        assert (back.dataobj.slope, back.dataobj.inter) == (img.dataobj.slope, img.dataobj.inter)
        m = rdt_mesher.mesh_file(FUNCTIONAL, frame=k, iso=3752, size=4.0, verify=False)
        ref = rdt_mesher.mesh_file(path, iso=3752, size=4.0, verify=False)
        assert len(m.vertices) > 100
        assert np.array_equal(m.vertices, ref.vertices) and np.array_equal(m.faces, ref.faces), k
    try:
        rdt_mesher.mesh_file(FUNCTIONAL, iso=3752)
    except ValueError as e:
        assert "--frame K (0 to 19)" in str(e), e
    else:
        raise AssertionError("a series without a frame was meshed")


def test_nan_voxels_take_nan_as_like_numpy_nan_to_num():
    # nibabel's resampled_anat_moved.nii: 153 NaN voxels outside the original field of view.
    img = nib.load(RESAMPLED)
    data = img.get_fdata()
    assert int(np.isnan(data).sum()) == 153
    m = rdt_mesher.mesh_file(RESAMPLED, iso=5000, nan_as=0, size=1.0, verify=False)
    ref = rdt_mesher.mesh_image(np.nan_to_num(data, nan=0.0), affine=img.affine, iso=5000, size=1.0, verify=False)
    assert np.array_equal(m.vertices, ref.vertices) and np.array_equal(m.faces, ref.faces)
    try:
        rdt_mesher.mesh_file(RESAMPLED, iso=5000)
    except ValueError as e:
        assert "--nan-as VALUE" in str(e), e
    else:
        raise AssertionError("NaN voxels were meshed without nan_as")


NIFTI2 = PHANTOM.replace("phantom_i16_32.nii.gz", "nibabel_example_nifti2.nii.gz")


def test_a_nifti2_file_meshes_as_nibabel_reads_it():
    # nibabel's example_nifti2.nii.gz (NIfTI-2, 32 x 20 x 12 x 2 int16): each frame's mesh is
    # the mesh of nibabel's volume with nibabel's affine, bit for bit.
    img = nib.load(NIFTI2)
    assert isinstance(img, nib.Nifti2Image)
    for k in (0, 1):
        m = rdt_mesher.mesh_file(NIFTI2, frame=k, iso=500, size=2.0, verify=False)
        ref = rdt_mesher.mesh_image(img.get_fdata()[..., k], affine=img.affine, iso=500, size=2.0, verify=False)
        assert len(m.vertices) > 100
        assert np.array_equal(m.vertices, ref.vertices) and np.array_equal(m.faces, ref.faces), k


MGZ = PHANTOM.replace("phantom_i16_32.nii.gz", "nibabel_test.mgz")
CROP = PHANTOM.replace("phantom_i16_32.nii.gz", "mni_t1_crop56.nii.gz")


def test_freesurfer_volumes_mesh_as_nibabel_reads_them(tmp_path):
    # nibabel's test.mgz (3 x 4 x 5 x 2 float32, an oblique affine): each frame meshes as
    # mesh_image of nibabel's data and affine, bit for bit.
    img = nib.load(MGZ)
    for k in (0, 1):
        m = rdt_mesher.mesh_file(MGZ, frame=k, iso=0.0, verify=False)
        ref = rdt_mesher.mesh_image(img.get_fdata()[..., k], affine=img.affine, iso=0.0, verify=False)
        assert len(m.vertices) > 100
        assert np.array_equal(m.vertices, ref.vertices) and np.array_equal(m.faces, ref.faces), k
    # The T1 crop written by nibabel as .mgz and .mgh with an oblique, anisotropic affine:
    # nibabel's affine of the file (float32 directions and sizes), nibabel's voxels.
    crop = nib.load(CROP)
    a = crop.affine.copy()
    c, s = np.cos(0.3), np.sin(0.3)
    a[:3, :3] = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]) @ np.diag([1.0, 1.2, 0.9])
    data = np.asanyarray(crop.dataobj)
    for ext in ("mgz", "mgh"):
        path = tmp_path / f"crop.{ext}"
        nib.save(nib.MGHImage(data, a), path)
        back = nib.load(path)
        m = rdt_mesher.mesh_file(path, iso=171.2, size=2.0, verify=False)
        ref = rdt_mesher.mesh_image(np.asanyarray(back.dataobj), affine=back.affine, iso=171.2, size=2.0, verify=False)
        assert len(m.vertices) > 1000
        assert np.array_equal(m.vertices, ref.vertices) and np.array_equal(m.faces, ref.faces), ext
