#!/usr/bin/env python3
"""Independent check of an image mesh with trimesh (issue 14): closed (watertight), consistently
oriented (winding), positive volume, and its component count next to scikit-image's marching
cubes at the same iso value (the voxel grid padded by one background layer, as oracle::image
continues the image by its background).

  python3 bench/marching_cubes/check_manifold.py ours.ply --nifti brain.nii.gz --iso 171.2

Prints one JSON line; exits 1 if the mesh is not watertight or not consistently oriented, and 0
with a `skipped` message when trimesh (or nibabel / scikit-image for the reference) is missing.
"""
import argparse
import json
import sys


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("mesh")
    ap.add_argument("--nifti")
    ap.add_argument("--iso", type=float)
    a = ap.parse_args()
    try:
        import numpy as np
        import trimesh
    except ImportError as e:
        print(json.dumps({"skipped": f"python module missing: {e.name}"}))
        return 0
    m = trimesh.load(a.mesh, process=False, force="mesh")
    comps = trimesh.graph.connected_components(m.face_adjacency, nodes=np.arange(len(m.faces)))
    out = {
        "faces": int(len(m.faces)),
        "watertight": bool(m.is_watertight),
        "winding_consistent": bool(m.is_winding_consistent),
        "volume": float(m.volume),
        "components": int(len(comps)),
    }
    if a.nifti is not None and a.iso is not None:
        try:
            import nibabel as nib
            from skimage import measure
        except ImportError as e:
            out["marching_cubes"] = f"skipped: python module missing: {e.name}"
        else:
            d = np.asarray(nib.load(a.nifti).dataobj).astype(np.float32)
            d = np.pad(d, 1, constant_values=min(float(d.min()), 0.0))
            v, f, _, _ = measure.marching_cubes(d, a.iso)
            mc = trimesh.Trimesh(v, f, process=True)
            cc = trimesh.graph.connected_components(mc.face_adjacency, nodes=np.arange(len(mc.faces)))
            out["marching_cubes_components"] = int(len(cc))
    print(json.dumps(out))
    return 0 if out["watertight"] and out["winding_consistent"] else 1


if __name__ == "__main__":
    sys.exit(main())
