"""Mesh every label of a segmentation in parallel on a Dask cluster, and check that the
result is the serial loop's, mesh for mesh.

    python python/examples/dask_labels.py [segmentation.nii.gz] [--workers 2] [--size S]

Without a file it makes a small synthetic segmentation. The same code runs on a cluster of
machines: replace LocalCluster by the scheduler's address (dask.distributed.Client("tcp://...")).
Each task receives the label map once (scattered) and returns (vertices, faces) numpy arrays.
"""

from __future__ import annotations

import argparse

import numpy as np

import rdt_mesher


def synthetic_segmentation(n: int = 40) -> tuple[np.ndarray, np.ndarray]:
    """Three labelled balls and a box on an anisotropic grid; (labels, affine)."""
    i, j, k = np.meshgrid(*(np.arange(n),) * 3, indexing="ij")
    seg = np.zeros((n, n, n), dtype=np.uint8)
    for label, (c, r) in enumerate([((10, 10, 10), 7), ((28, 12, 20), 8), ((14, 28, 28), 6)], 1):
        seg[(i - c[0]) ** 2 + (j - c[1]) ** 2 + (k - c[2]) ** 2 <= r * r] = label
    seg[26:36, 26:36, 4:14] = 7
    affine = np.diag([0.9, 1.0, 1.2, 1.0])
    return seg, affine


def mesh_label(seg: np.ndarray, affine: np.ndarray, label: int, size: float):
    """One task: the mesh of one label as plain arrays (picklable)."""
    m = rdt_mesher.mesh_image(seg, affine=affine, label=label, size=size, threads=1)
    return label, m.vertices, m.faces


def labels_of(seg: np.ndarray) -> list[int]:
    return [int(v) for v in np.unique(seg) if v != 0]


def mesh_serial(seg, affine, size):
    return {l: mesh_label(seg, affine, l, size)[1:] for l in labels_of(seg)}


def mesh_dask(seg, affine, size, workers: int = 2, processes: bool = True):
    from dask.distributed import Client, LocalCluster

    with LocalCluster(n_workers=workers, threads_per_worker=1, processes=processes,
                      dashboard_address=None) as cluster, Client(cluster) as client:
        seg_f, aff_f = client.scatter([seg, affine], broadcast=True)
        futures = [client.submit(mesh_label, seg_f, aff_f, l, size, pure=False) for l in labels_of(seg)]
        return {l: (v, f) for l, v, f in client.gather(futures)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("segmentation", nargs="?")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--size", type=float, default=1.0)
    ap.add_argument("--threads", action="store_true", help="a cluster of threads, not processes")
    a = ap.parse_args(argv)
    if a.segmentation:
        import nibabel as nib

        img = nib.load(a.segmentation)
        seg, affine = np.asanyarray(img.dataobj), img.affine
    else:
        seg, affine = synthetic_segmentation()
    parallel = mesh_dask(seg, affine, a.size, a.workers, processes=not a.threads)
    serial = mesh_serial(seg, affine, a.size)
    same = sorted(parallel) == sorted(serial) and all(
        np.array_equal(parallel[l][0], serial[l][0]) and np.array_equal(parallel[l][1], serial[l][1])
        for l in serial
    )
    for l in sorted(parallel):
        print(f"label {l}: {len(parallel[l][0])} vertices, {len(parallel[l][1])} faces")
    print("identical to the serial loop" if same else "DIFFERENT from the serial loop")
    return 0 if same else 1


if __name__ == "__main__":
    raise SystemExit(main())
