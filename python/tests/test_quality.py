"""Against scikit-image's marching cubes at the same iso; trimesh's checks; the per-facet
arrays; the Mesh object's conversions."""

import numpy as np
import pytest
from scipy.spatial import cKDTree

import rdt_mesher
from conftest import sample_surface


def torus_volume(n=96):
    """A torus (R = 26, r = 10 voxels) as a float32 signed distance, inside positive."""
    c = (n - 1) / 2.0
    i, j, k = np.meshgrid(*(np.arange(n) - c,) * 3, indexing="ij")
    q = np.sqrt(i * i + j * j) - 26.0
    return (10.0 - np.sqrt(q * q + k * k)).astype(np.float32)


@pytest.fixture(scope="module")
def torus():
    vol = torus_volume()
    spacing = (0.5, 0.5, 0.5)
    # Three voxels: the size bound of a mesh ten times lighter than marching cubes.
    return vol, spacing, rdt_mesher.mesh_image(vol, spacing=spacing, iso=0.0, size=1.5)


def test_marching_cubes_within_one_voxel_with_ten_times_fewer_vertices(torus):
    from skimage.measure import marching_cubes

    vol, spacing, m = torus
    mv, mf, _, _ = marching_cubes(vol, level=0.0, spacing=spacing)
    assert len(mv) >= 10 * len(m.vertices), (len(mv), len(m.vertices))
    # Two-sided Hausdorff between the surfaces, from dense samples of each (a sample gap
    # of a few hundredths of a voxel, counted against us).
    a = np.vstack([m.vertices, sample_surface(m.vertices, m.faces, 300_000, 1)])
    b = np.vstack([mv, sample_surface(mv, mf, 300_000, 2)])
    h = max(cKDTree(b).query(a)[0].max(), cKDTree(a).query(b)[0].max())
    voxel = max(spacing)
    assert h < voxel, h
    # Quality: marching cubes has many facets under 30 degrees, the mesher none.
    assert m.min_angle.min() >= 30.0 - 1e-9
    assert m.report["stats"]["min_angle_deg"] == pytest.approx(m.min_angle.min())


def test_trimesh_watertight_and_outward(torus):
    _, _, m = torus
    t = m.to_trimesh()
    assert t.is_watertight and t.is_winding_consistent
    want = 2 * np.pi**2 * 26.0 * 10.0**2 * 0.5**3
    assert t.volume > 0
    assert abs(t.volume - want) / want < 0.05
    assert t.euler_number == 0  # genus 1


def test_per_facet_arrays(torus):
    _, _, m = torus
    nf = len(m.faces)
    assert m.min_angle.shape == m.r_over_sigma.shape == m.ball_radius.shape == (nf,)
    assert np.all(m.r_over_sigma <= 1.0 + 1e-9)
    assert np.allclose(m.r_over_sigma * m.sigma, m.ball_radius)
    assert m.report["stats"]["max_r_over_sigma"] == pytest.approx(m.r_over_sigma.max())


def test_to_meshio_and_save_formats(torus, tmp_path):
    import meshio

    _, _, m = torus
    mm = m.to_meshio()
    assert np.array_equal(mm.cells_dict["triangle"], m.faces)
    for ext in ("ply", "off", "obj", "stl"):
        p = tmp_path / f"t.{ext}"
        m.save(p)
        back = meshio.read(p)
        assert len(back.cells_dict["triangle"]) == len(m.faces), ext
    with pytest.raises(ValueError, match="t.xyz"):
        m.save(tmp_path / "t.xyz")
    with pytest.raises(FileNotFoundError):
        m.save(tmp_path / "missing" / "t.ply")
