"""World coordinates: the affine (oblique, anisotropic) and nibabel's axis order."""

import nibabel as nib
import numpy as np
import pytest

import rdt_mesher


def oblique_affine():
    a, b = np.radians(30.0), np.radians(20.0)
    rz = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
    rx = np.array([[1, 0, 0], [0, np.cos(b), -np.sin(b)], [0, np.sin(b), np.cos(b)]])
    m = np.eye(4)
    m[:3, :3] = rz @ rx @ np.diag([0.8, 1.1, 1.7])
    m[:3, 3] = [10.0, -20.0, 5.0]
    return m


def ellipsoid_volume(affine, center, radius, shape=(48, 44, 30)):
    """Signed distance to a world-space sphere, sampled at the voxel centres (inside > 0)."""
    i, j, k = np.meshgrid(*(np.arange(n) for n in shape), indexing="ij")
    ijk1 = np.stack([i, j, k, np.ones_like(i)], axis=-1).astype(np.float64)
    w = ijk1 @ affine.T
    return (radius - np.linalg.norm(w[..., :3] - center, axis=-1)).astype(np.float32)


@pytest.mark.parametrize("order", ["C", "F"])
def test_oblique_anisotropic_affine_gives_world_coordinates(order):
    aff = oblique_affine()
    center = aff[:3, :3] @ np.array([24.0, 22.0, 15.0]) + aff[:3, 3]
    vol = ellipsoid_volume(aff, center, 14.0)
    vol = np.asfortranarray(vol) if order == "F" else np.ascontiguousarray(vol)
    m = rdt_mesher.mesh_image(vol, affine=aff, iso=0.0, size=1.5)
    d = np.linalg.norm(m.vertices - center, axis=1)
    # The level set of the trilinear interpolant of a sampled distance: within a fraction
    # of the largest voxel size (1.7) of the world sphere.
    assert np.abs(d - 14.0).max() < 0.5
    assert m.to_trimesh().is_watertight


def test_axis_order_is_nibabels(tmp_path):
    """volume[i, j, k] lies at affine @ (i, j, k, 1), as nibabel says of get_fdata()."""
    aff = np.diag([2.0, 3.0, 0.5, 1.0])
    aff[:3, 3] = [-7.0, 1.0, 4.0]
    vol = np.zeros((30, 20, 40), dtype=np.uint8)
    vol[5:15, 4:10, 10:30] = 1  # a box of 10 x 6 x 20 voxels
    path = tmp_path / "box.nii.gz"
    nib.save(nib.Nifti1Image(vol, aff), str(path))
    img = nib.load(str(path))
    data = img.get_fdata()
    assert data.shape == (30, 20, 40) and data[5, 4, 10] == 1.0
    for m in (rdt_mesher.mesh_image(data, affine=img.affine, label=1, size=0.5),
              rdt_mesher.mesh_image(vol, affine=aff, label=1, size=0.5),
              rdt_mesher.mesh_file(str(path), label=1, size=0.5)):
        lo, hi = m.vertices.min(0), m.vertices.max(0)
        # The label's boundary is halfway between voxel centres: i in [4.5, 14.5] etc.
        want_lo = aff[:3, :3] @ np.array([4.5, 3.5, 9.5]) + aff[:3, 3]
        want_hi = aff[:3, :3] @ np.array([14.5, 9.5, 29.5]) + aff[:3, 3]
        assert np.allclose(lo, want_lo, atol=0.3 * np.array([2, 3, 0.5]) + 1e-9)
        assert np.allclose(hi, want_hi, atol=0.3 * np.array([2, 3, 0.5]) + 1e-9)


def test_spacing_and_origin_equal_the_diagonal_affine():
    from conftest import ball_volume

    vol = ball_volume(32, 10.0)
    a = rdt_mesher.mesh_image(vol, spacing=(1.0, 2.0, 0.5), origin=(1, 2, 3), iso=0.0, size=1.0)
    aff = np.diag([1.0, 2.0, 0.5, 1.0])
    aff[:3, 3] = [1, 2, 3]
    b = rdt_mesher.mesh_image(vol, affine=aff, iso=0.0, size=1.0)
    assert np.array_equal(a.vertices, b.vertices)
