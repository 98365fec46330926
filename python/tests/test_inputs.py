"""The other inputs: expressions and callables, meshes, point sets, verify; aliases; labels."""

import numpy as np
import pytest

import rdt_mesher
from conftest import FIXTURES, ball_volume


def test_expression_and_callable():
    e = rdt_mesher.mesh_implicit("x^2 + y^2 + z^2 - 1", bounding_sphere=((0, 0, 0), 2.0), size=0.2)
    assert np.allclose(np.linalg.norm(e.vertices, axis=1), 1.0, atol=1e-6)
    calls = []

    def f(p):
        calls.append(len(p))
        return (p * p).sum(axis=1) - 1.0

    c = rdt_mesher.mesh_implicit(f, bounding_sphere=((0, 0, 0), 2.0), grid=64, batch=50_000, size=0.2)
    assert max(calls) == 50_000 and sum(calls) == 64**3  # batches, not points
    assert np.abs(np.linalg.norm(c.vertices, axis=1) - 1.0).max() < 0.02
    assert c.to_trimesh().is_watertight


def test_cgal_aliases_are_the_same_criteria():
    vol = ball_volume(32, 11.0)
    a = rdt_mesher.mesh_image(vol, iso=0.0, size=1.5, min_angle=30, max_distance=1.0)
    b = rdt_mesher.mesh_image(vol, iso=0.0, max_radius_surface_delaunay_ball=1.5,
                              min_facet_angle=30, max_facet_distance=1.0)
    assert np.array_equal(a.vertices, b.vertices)
    assert a.report["distance"] == 1.0


def test_remesh_points_and_verify():
    s = rdt_mesher.mesh_implicit("sphere", bounding_sphere=((0, 0, 0), 2.0), size=0.15)
    r = rdt_mesher.remesh(s.vertices, s.faces, size=0.3)
    assert r.to_trimesh().is_watertight and len(r.vertices) < len(s.vertices)
    p = rdt_mesher.mesh_points(s.vertices, s.vertices.copy(), size=0.3)
    assert np.abs(np.linalg.norm(p.vertices, axis=1) - 1).max() < 0.05
    ok = rdt_mesher.verify(s.vertices, s.faces, against="implicit:sphere", epsilon=0.2)
    assert all(c["status"] != "FAIL" for c in ok["checks"]), ok["checks"]
    broken = rdt_mesher.verify(s.vertices, s.faces[1:])
    assert any(c["status"] == "FAIL" for c in broken["checks"])


def test_mesh_file_reads_a_mesh_file():
    m = rdt_mesher.mesh_file(f"{FIXTURES}/meshes/cube.off", size=0.2)
    assert m.report["input_kind"] == "polyhedron"
    assert m.to_trimesh().is_watertight


def test_labels_all_one_mesh_per_label():
    vol = np.zeros((30, 30, 30), dtype=np.int16)
    vol[3:12, 3:12, 3:12] = 2
    vol[15:27, 15:27, 15:27] = 5
    out = rdt_mesher.mesh_image(vol, labels="all", size=1.0)
    assert sorted(out) == [2, 5]
    assert all(m.to_trimesh().is_watertight for m in out.values())
    one = rdt_mesher.mesh_image(vol, label=5, size=1.0)
    assert np.array_equal(one.vertices, out[5].vertices)


def test_labels_all_reads_once_and_gives_each_labels_own_mesh(tmp_path):
    """``labels=`` reads the volume once and meshes each label on its own crop (the CLI's
    ``--labels all``): the same vertices and faces as one call per label with ``label=``, from
    an array and from a file of it."""
    nib = pytest.importorskip("nibabel")
    vol = np.zeros((28, 24, 20), dtype=np.uint16)
    vol[2:12, 3:13, 2:10] = 7
    vol[14:26, 10:22, 8:18] = 300
    vol[20:24, 2:6, 2:6] = 9
    affine = np.diag([0.5, 0.75, 1.5, 1.0])
    affine[:3, 3] = [10.0, -4.0, 2.0]
    path = tmp_path / "labels.nii.gz"
    nib.save(nib.Nifti1Image(vol, affine), str(path))
    arr = rdt_mesher.mesh_image(vol, affine=affine, labels="all", size=0.6)
    some = rdt_mesher.mesh_image(vol, affine=affine, labels=[300, 9], size=0.6)
    fil = rdt_mesher.mesh_file(path, labels="all", size=0.6)
    assert sorted(arr) == sorted(fil) == [7, 9, 300] and sorted(some) == [9, 300]
    for lab in (7, 9, 300):
        one = rdt_mesher.mesh_image(vol, affine=affine, label=lab, size=0.6)
        one_file = rdt_mesher.mesh_file(path, label=lab, size=0.6)
        for got in [arr[lab]] + ([some[lab]] if lab in some else []):
            assert np.array_equal(got.vertices, one.vertices), lab
            assert np.array_equal(got.faces, one.faces), lab
        # (The file's mesh is compared with the file's: a C-ordered array is read as the
        # transposed grid, another mesh of the same surface; see Known limits.)
        assert np.array_equal(fil[lab].vertices, one_file.vertices), lab
        assert np.array_equal(fil[lab].faces, one_file.faces), lab
        assert fil[lab].to_trimesh().is_watertight
    # Not a label image: the error says so, for a list of labels as for "all".
    with pytest.raises(ValueError, match="label"):
        rdt_mesher.mesh_image(vol.astype(np.float32) + 0.5, labels=[7], size=0.6)


def test_uint64_label_ids_are_exact():
    """Connectomics ids are uint64: those a uint32 holds mesh as the uint32 volume does (they
    were refused before), larger ones up to 9e15 through float64 (exact), and beyond that the
    error says why (consecutive ids would merge)."""
    vol = np.zeros((24, 24, 24), dtype=np.uint64)
    big = 2**32 - 7
    vol[3:11, 3:11, 3:11] = big
    vol[13:21, 13:21, 13:21] = 5
    want = rdt_mesher.mesh_image(vol.astype(np.uint32), label=big, size=1.0)
    got = rdt_mesher.mesh_image(vol, label=big, size=1.0)
    assert np.array_equal(want.vertices, got.vertices) and np.array_equal(want.faces, got.faces)
    huge = vol.copy()
    huge[huge == big] = 2**45 + 1
    out = rdt_mesher.mesh_image(huge, labels="all", size=1.0)
    assert sorted(out) == [5, 2**45 + 1]
    assert np.array_equal(out[5].vertices, rdt_mesher.mesh_image(vol, label=5, size=1.0).vertices)
    huge[huge == 5] = 2**60
    with pytest.raises(ValueError, match="beyond 9e15"):
        rdt_mesher.mesh_image(huge, labels="all", size=1.0)


@pytest.mark.parametrize("dtype", [np.bool_, np.uint8, np.int16, np.uint16, np.int32, np.float32, np.float64])
def test_every_dtype(dtype):
    vol = ball_volume(24, 8.0) > 0
    m = rdt_mesher.mesh_image(vol.astype(dtype), iso=0.5, size=1.0)
    assert m.to_trimesh().is_watertight


def test_epsilon_on_a_mesh_meshes_its_smooth_approximation():
    # The exact triangles have d_M = 0 at their edges (no eps-sample): mesh_file and remesh
    # mesh the IMLS approximation for an epsilon without dm_inf, as the CLI does.
    m = rdt_mesher.mesh_file(f"{FIXTURES}/models/fertility.ply", epsilon=0.5)
    notes = " ".join(m.report["notes"])
    assert "--epsilon on a mesh: meshing its smooth IMLS approximation" in notes
    assert m.report["adaptive"]["converged"] and m.report["genus"] == [4]
    assert m.report["verify"]["certificate"]["eps_achieved"] <= 0.5
    r = rdt_mesher.remesh(m.vertices, m.faces, epsilon=0.5)
    assert "--epsilon on a mesh" in " ".join(r.report["notes"])
    assert r.to_trimesh().is_watertight
