#!/usr/bin/env python3
"""Marching-cubes baseline for the image oracle (issue 5 acceptance).

Runs scikit-image's marching cubes on the same volume and iso value as `rdt-mesher`, in world
coordinates (the NIfTI affine is applied, sform > qform > pixdim as in oracle::image), and
optionally compares it with our mesh: vertex counts and the symmetric Hausdorff distance
(dense point samples of both triangle meshes), in world units and in voxels.

  pip install scikit-image scipy nibabel
  python3 bench/marching_cubes/mc.py --tanglecube 128 --iso 0 [--compare ours.ply] [--out mc.ply]
  python3 bench/marching_cubes/mc.py --nifti brain.nii.gz --iso 300 [--compare ours.ply]

The tanglecube volume is sampled exactly as `oracle::image::synthetic::tanglecube_volume(n)`:
voxel (i, j, k) at world (-2.6 + i h, ...) with h = 5.2 / (n - 1). Prints one JSON line.
"""
import argparse
import json
import struct
import sys
import time

import numpy as np


def tanglecube_volume(n):
    h = 5.2 / (n - 1)
    c = -2.6 + h * np.arange(n, dtype=np.float64)
    x, y, z = np.meshgrid(c, c, c, indexing="ij")
    q = lambda t: t**4 - 5 * t**2
    vol = (q(x) + q(y) + q(z) + 11.8).astype(np.float32)
    aff = np.diag([h, h, h, 1.0])
    aff[:3, 3] = -2.6
    return vol, aff


def nifti_volume(path):
    import nibabel as nib

    img = nib.load(path)
    hdr = img.header
    if int(hdr["sform_code"]) > 0:
        aff = img.get_sform()
    elif int(hdr["qform_code"]) > 0:
        aff = img.get_qform()
    else:
        pix = [float(p) if p != 0 else 1.0 for p in hdr["pixdim"][1:4]]
        aff = np.diag(pix + [1.0])
    vol = np.asanyarray(img.dataobj, dtype=np.float64)  # applies scl_slope / scl_inter
    return np.squeeze(vol), aff


def read_ply(path):
    """Minimal PLY reader: ascii or binary_little_endian, vertex x y z (float/double) and a face
    list (uchar/int count, int/uint indices)."""
    with open(path, "rb") as f:
        fmt, elems = None, []
        while True:
            line = f.readline().decode("ascii").strip()
            if line.startswith("format"):
                fmt = line.split()[1]
            elif line.startswith("element"):
                _, name, cnt = line.split()
                elems.append([name, int(cnt), []])
            elif line.startswith("property"):
                elems[-1][2].append(line.split()[1:])
            elif line == "end_header":
                break
        sizes = {"char": "b", "uchar": "B", "int8": "b", "uint8": "B", "short": "h",
                 "ushort": "H", "int16": "h", "uint16": "H", "int": "i", "uint": "I",
                 "int32": "i", "uint32": "I", "float": "f", "float32": "f",
                 "double": "d", "float64": "d"}
        verts, faces = [], []
        if fmt == "ascii":
            rest = f.read().decode("ascii").split("\n")
            li = 0
            for name, cnt, props in elems:
                for _ in range(cnt):
                    vals = rest[li].split()
                    li += 1
                    if name == "vertex":
                        verts.append([float(v) for v in vals[:3]])
                    elif name == "face":
                        k = int(vals[0])
                        faces.append([int(v) for v in vals[1:1 + k]])
        else:
            assert fmt == "binary_little_endian", fmt
            for name, cnt, props in elems:
                for _ in range(cnt):
                    row = []
                    for p in props:
                        if p[0] == "list":
                            (k,) = struct.unpack("<" + sizes[p[1]], f.read(struct.calcsize(sizes[p[1]])))
                            t = "<" + sizes[p[2]] * k
                            row.append(list(struct.unpack(t, f.read(struct.calcsize(t)))))
                        else:
                            t = "<" + sizes[p[0]]
                            (v,) = struct.unpack(t, f.read(struct.calcsize(t)))
                            row.append(v)
                    if name == "vertex":
                        verts.append(row[:3])
                    elif name == "face":
                        faces.append(row[0])
        return np.array(verts, dtype=np.float64), np.array([fc[:3] for fc in faces], dtype=np.int64)


def write_ply(path, v, f):
    with open(path, "w") as o:
        o.write("ply\nformat ascii 1.0\nelement vertex %d\nproperty double x\nproperty double y\n"
                "property double z\nelement face %d\nproperty list uchar int vertex_indices\n"
                "end_header\n" % (len(v), len(f)))
        for p in v:
            o.write("%.9g %.9g %.9g\n" % tuple(p))
        for t in f:
            o.write("3 %d %d %d\n" % tuple(t))


def sample_mesh(v, f, spacing, rng):
    """Points on the triangles at about `spacing` apart (vertices included)."""
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    n = np.maximum(1, np.ceil(area / (spacing * spacing) * 2)).astype(np.int64)
    idx = np.repeat(np.arange(len(f)), n)
    r1, r2 = rng.random(len(idx)), rng.random(len(idx))
    s = np.sqrt(r1)
    pts = (1 - s)[:, None] * a[idx] + (s * (1 - r2))[:, None] * b[idx] + (s * r2)[:, None] * c[idx]
    return np.vstack([v, pts])


def main():
    ap = argparse.ArgumentParser()
    g = ap.add_mutually_exclusive_group(required=True)
    g.add_argument("--tanglecube", type=int, metavar="N")
    g.add_argument("--nifti")
    ap.add_argument("--iso", type=float, required=True)
    ap.add_argument("--dark", action="store_true",
                    help="foreground below iso (default: above; the tanglecube is always dark)")
    ap.add_argument("--compare", help="our mesh (PLY) to compare with")
    ap.add_argument("--out", help="write the marching-cubes mesh (ascii PLY)")
    args = ap.parse_args()
    from scipy.spatial import cKDTree
    from skimage.measure import marching_cubes

    vol, aff = tanglecube_volume(args.tanglecube) if args.tanglecube else nifti_volume(args.nifti)
    # Pad with the background so that surfaces touching the box are closed (as the oracle does).
    lo, hi = float(vol.min()), float(vol.max())
    bg = hi if (args.tanglecube or args.dark) else lo
    vol = np.pad(vol, 1, constant_values=bg)
    t0 = time.perf_counter()
    verts, faces, _, _ = marching_cubes(vol, level=args.iso)
    t_mc = time.perf_counter() - t0
    verts = verts - 1.0  # undo the padding
    world = verts @ aff[:3, :3].T + aff[:3, 3]
    voxel = float(np.cbrt(abs(np.linalg.det(aff[:3, :3]))))
    out = {"input": args.nifti or "tanglecube%d" % args.tanglecube, "iso": args.iso,
           "mc_vertices": int(len(world)), "mc_faces": int(len(faces)),
           "mc_seconds": round(t_mc, 3), "voxel_size": voxel}
    if args.out:
        write_ply(args.out, world, faces)
    if args.compare:
        ov, of = read_ply(args.compare)
        rng = np.random.default_rng(0)
        s = 0.25 * voxel
        pa, pb = sample_mesh(world, faces, s, rng), sample_mesh(ov, of, s, rng)
        d_ab = cKDTree(pb).query(pa)[0]
        d_ba = cKDTree(pa).query(pb)[0]
        h = max(d_ab.max(), d_ba.max())
        out.update({"our_vertices": int(len(ov)), "our_faces": int(len(of)),
                    "vertex_ratio_mc_over_ours": round(len(world) / max(1, len(ov)), 2),
                    "hausdorff_world": float(h), "hausdorff_voxels": float(h / voxel),
                    "mean_mc_to_ours_voxels": float(d_ab.mean() / voxel),
                    "mean_ours_to_mc_voxels": float(d_ba.mean() / voxel)})
    print(json.dumps(out))


if __name__ == "__main__":
    sys.exit(main())
