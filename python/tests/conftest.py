"""Shared paths and helpers of the rdt_mesher Python tests (tests fetch nothing: fixtures/)."""

import os
import subprocess

import numpy as np
import pytest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
FIXTURES = os.path.join(ROOT, "fixtures")
PHANTOM = os.path.join(FIXTURES, "images", "phantom_i16_32.nii.gz")
XTASK = os.environ.get("RDT_XTASK", os.path.join(ROOT, "target", "release", "xtask"))


@pytest.fixture(scope="session")
def xtask():
    if not os.path.exists(XTASK):
        pytest.fail(f"{XTASK} is missing: build it with `cargo build --release -p xtask` (build_and_test.sh does)")
    return XTASK


def run_cli(xtask, *args):
    r = subprocess.run([xtask, "mesh", *args, "--quiet"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    return r


def ball_volume(n=40, radius=12.0, dtype=np.float32):
    """A solid ball of `radius` voxels (value = radius - distance, inside positive), C order."""
    c = (n - 1) / 2.0
    i, j, k = np.meshgrid(*(np.arange(n) - c,) * 3, indexing="ij")
    return (radius - np.sqrt(i * i + j * j + k * k)).astype(dtype)


def sample_surface(vertices, faces, n, seed=0):
    """n points uniformly on a triangle mesh (area-weighted)."""
    rng = np.random.default_rng(seed)
    t = vertices[faces]
    area = 0.5 * np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1)
    f = rng.choice(len(faces), size=n, p=area / area.sum())
    u, v = rng.random(n), rng.random(n)
    flip = u + v > 1
    u[flip], v[flip] = 1 - u[flip], 1 - v[flip]
    a = t[f]
    return a[:, 0] + u[:, None] * (a[:, 1] - a[:, 0]) + v[:, None] * (a[:, 2] - a[:, 0])
