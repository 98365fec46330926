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
