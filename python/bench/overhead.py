"""Overhead of the Python bindings (a benchmark, not a test): the 128^3 tanglecube volume
(as `cargo xtask bench image` builds it: f32 samples of x^4 - 5x^2 + ... + 11.8 over
[-4, 4]^3, iso 0, dark foreground; criteria angle 30, radius = distance = 0.06) meshed from a
numpy array with rdt_mesher.mesh_image and from the Rust CLI (`xtask mesh` on the same volume
saved as NIfTI), alternating run by run, in one run of this script.

    python python/bench/overhead.py [--runs 3] [--xtask target/release/xtask]

Prints the median wall time of each (the CLI's includes its process start, reading the NIfTI
file and writing the PLY; the Python call's includes returning the numpy arrays) and the
overhead of Python over the CLI. Both runs verify the mesh (the default).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import tempfile
import time

import nibabel as nib
import numpy as np

import rdt_mesher

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))


def tanglecube_volume(n: int = 128, half: float = 4.0) -> tuple[np.ndarray, np.ndarray]:
    h = 2.0 * half / (n - 1)
    x = -half + h * np.arange(n)
    i, j, k = np.meshgrid(x, x, x, indexing="ij")
    q = lambda t: t**4 - 5.0 * t**2  # noqa: E731
    vol = (q(i) + q(j) + q(k) + 11.8).astype(np.float32)
    aff = np.diag([h, h, h, 1.0])
    aff[:3, 3] = -half
    return vol, aff


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--xtask", default=os.path.join(ROOT, "target", "release", "xtask"))
    a = ap.parse_args()
    r = 0.06
    with tempfile.TemporaryDirectory() as d:
        vol, aff = tanglecube_volume()
        path = os.path.join(d, "tanglecube_128.nii")
        nib.save(nib.Nifti1Image(vol, aff), path)
        img = nib.load(path)
        data = np.asanyarray(img.dataobj)  # read once: the benchmark times meshing
        affine = img.affine
        cli_t, py_t, cli_mesher, py_mesher = [], [], [], []
        cli_n = py_n = None
        for _ in range(a.runs):
            t = time.perf_counter()
            subprocess.run(
                [a.xtask, "mesh", path, "--iso", "0", "--dark-foreground", "--size", str(r),
                 "--distance", str(r), "-o", os.path.join(d, "cli.ply"), "--report",
                 os.path.join(d, "cli.json"), "--quiet"],
                check=True, capture_output=True)
            cli_t.append(time.perf_counter() - t)
            rep = json.load(open(os.path.join(d, "cli.json")))
            cli_mesher.append(rep["stats"]["time_total_s"])
            cli_n = rep["stats"]["vertices"]
            t = time.perf_counter()
            m = rdt_mesher.mesh_image(data, affine=affine, iso=0.0, dark_foreground=True,
                                      size=r, max_distance=r)
            py_t.append(time.perf_counter() - t)
            py_mesher.append(m.report["stats"]["time_total_s"])
            py_n = len(m.vertices)
    c, p = statistics.median(cli_t), statistics.median(py_t)
    print(f"tanglecube 128^3, r = {r}: {py_n} vertices from numpy, {cli_n} from the CLI "
          f"({'the same mesh' if py_n == cli_n else 'DIFFERENT meshes'})")
    print(f"wall, median of {a.runs}: CLI {c:.3f} s, Python {p:.3f} s: overhead {100 * (p / c - 1):+.1f}%")
    print(f"mesher's own time_total_s, median: CLI {statistics.median(cli_mesher):.3f} s, "
          f"Python {statistics.median(py_mesher):.3f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
