#!/usr/bin/env python3
"""Black-box mutation fuzz of the `mesh` CLI over every input format (issue 17).

For each format, start from fixtures and small generated files, apply N random mutations
(byte flips, truncations, inserted/deleted tokens, changed counts and header fields, huge
numbers, NaN/inf, gzip corruption, wrong raw-volume flags), and run each mutant through

    xtask mesh FILE --size S --max-vertices 20000 --time-limit 20 -o OUT.ply --no-verify -q

with a wall-clock timeout. Each run is classified:

- panic: exit 101 or "panicked" in stderr;
- timeout: still running after the time limit plus a margin (killed);
- accepted-bad: exit 0 on a file a strict reference reader rejects (the format's own
  structural checks below, plus trimesh / nibabel / pydicom / gzip where they are installed);
- misread: exit 0, but the input note's vertex/triangle (or point) counts, or a DICOM
  volume's columns, rows and frames, differ from the reference reader's;
- bad-message: a non-zero exit whose stderr is not one `error:` line naming the file;
- refused-readable (not a failure, listed for review): a non-zero exit on a file the
  reference reads, e.g. a reader stricter than the reference or a mesh the mesher refuses.

Python 3 standard library only; numpy, trimesh, nibabel, pydicom add reference readers when present.
Usage: scripts/mutate.py [--bin target/release/xtask] [--per-format 300] [--seed 0]
       [--formats ply_ascii,...] [--keep DIR] [--json FILE]. Exit status 1 if any panic,
timeout, accepted-bad or misread run was found; the offending inputs are copied to --keep.
"""

import argparse
import gzip
import io
import json
import math
import os
import random
import re
import shutil
import struct
import subprocess
import sys
import tempfile
import time
import zlib

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from mutate_ref import CHECKS, Reject, raw_checker, trimesh_rejects  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# ---------------------------------------------------------------- base files


def icosphere():
    """An octahedron subdivided once, on the unit sphere: 18 vertices, 32 triangles."""
    v = [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)]
    f = [(0, 2, 4), (2, 1, 4), (1, 3, 4), (3, 0, 4), (2, 0, 5), (1, 2, 5), (3, 1, 5), (0, 3, 5)]
    v = [tuple(float(c) for c in p) for p in v]
    mid = {}

    def m(a, b):
        k = (min(a, b), max(a, b))
        if k not in mid:
            p = [(v[a][i] + v[b][i]) / 2 for i in range(3)]
            n = math.sqrt(sum(c * c for c in p))
            v.append(tuple(c / n for c in p))
            mid[k] = len(v) - 1
        return mid[k]

    out = []
    for a, b, c in f:
        ab, bc, ca = m(a, b), m(b, c), m(c, a)
        out += [(a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca)]
    return v, out


def ply_bytes(v, f, fmt):
    head = "ply\nformat %s 1.0\nelement vertex %d\nproperty float x\nproperty float y\n" \
           "property float z\nelement face %d\nproperty list uchar int vertex_indices\n" \
           "end_header\n" % (fmt, len(v), len(f))
    if fmt == "ascii":
        body = "".join("%r %r %r\n" % p for p in v) + "".join("3 %d %d %d\n" % t for t in f)
        return (head + body).encode()
    e = "<" if fmt == "binary_little_endian" else ">"
    body = b"".join(struct.pack(e + "3f", *p) for p in v)
    body += b"".join(struct.pack(e + "B3i", 3, *t) for t in f)
    return head.encode() + body


def ply_rich_bytes(v, f, fmt):
    """PLY with normals, a colour, double coordinates and uint indices, plus an extra element."""
    head = "ply\nformat %s 1.0\ncomment rich\nelement vertex %d\nproperty double x\n" \
           "property double y\nproperty double z\nproperty float nx\nproperty float ny\n" \
           "property float nz\nproperty uchar red\nelement face %d\n" \
           "property list uint8 uint32 vertex_indices\nproperty int flags\nelement extra 1\n" \
           "property short s\nend_header\n" % (fmt, len(v), len(f))
    if fmt == "ascii":
        body = "".join("%r %r %r %r %r %r 200\n" % (p + p) for p in v)
        body += "".join("3 %d %d %d 7\n" % t for t in f) + "-5\n"
        return (head + body).encode()
    e = "<" if fmt == "binary_little_endian" else ">"
    body = b"".join(struct.pack(e + "3d3fB", *(p + p), 200) for p in v)
    body += b"".join(struct.pack(e + "B3Ii", 3, *t, 7) for t in f) + struct.pack(e + "h", -5)
    return head.encode() + body


def off_bytes(v, f):
    s = "OFF\n%d %d 0\n" % (len(v), len(f))
    s += "".join("%r %r %r\n" % p for p in v) + "".join("3 %d %d %d\n" % t for t in f)
    return s.encode()


def obj_bytes(v, f):
    s = "# icosphere\n" + "".join("v %r %r %r\n" % p for p in v)
    return (s + "".join("f %d %d %d\n" % (a + 1, b + 1, c + 1) for a, b, c in f)).encode()


def stl_tris(v, f):
    return [(v[a], v[b], v[c]) for a, b, c in f]


def stl_ascii_bytes(v, f):
    s = "solid ico\n"
    for t in stl_tris(v, f):
        s += " facet normal 0 0 0\n  outer loop\n"
        s += "".join("   vertex %r %r %r\n" % p for p in t)
        s += "  endloop\n endfacet\n"
    return (s + "endsolid ico\n").encode()


def stl_binary_bytes(v, f):
    tris = stl_tris(v, f)
    out = b"binary stl".ljust(80, b" ") + struct.pack("<I", len(tris))
    for t in tris:
        out += struct.pack("<12fH", 0, 0, 0, *t[0], *t[1], *t[2], 0)
    return out


def xyz_bytes(n, normals, seed):
    r = random.Random(seed)
    s = "# points on the unit sphere\n"
    for _ in range(n):
        while True:
            p = [r.uniform(-1, 1) for _ in range(3)]
            q = math.sqrt(sum(c * c for c in p))
            if 0.1 < q <= 1:
                break
        p = [c / q for c in p]
        s += " ".join("%.6f" % c for c in (p + p if normals else p)) + "\n"
    return s.encode()


def ball_voxels(n, dtype):
    """An n^3 ball (value 100 inside, 0 outside) as raw little-endian bytes."""
    c = (n - 1) / 2
    vals = [100 if (i - c) ** 2 + (j - c) ** 2 + (k - c) ** 2 <= (n / 3) ** 2 else 0
            for k in range(n) for j in range(n) for i in range(n)]
    code = {"u8": "B", "i16": "h", "f32": "f"}[dtype]
    return struct.pack("<%d%s" % (len(vals), code), *vals)


NIFTI_DT = {"u8": (2, 8), "i16": (4, 16), "f32": (16, 32)}


def nifti1_bytes(n, dtype, spacing=2.0):
    """A minimal single-file NIfTI-1 (sform = diag(spacing), vox_offset 352)."""
    h = bytearray(348)
    struct.pack_into("<i", h, 0, 348)
    struct.pack_into("<8h", h, 40, 3, n, n, n, 1, 1, 1, 1)
    code, bits = NIFTI_DT[dtype]
    struct.pack_into("<hh", h, 70, code, bits)
    struct.pack_into("<8f", h, 76, 1, spacing, spacing, spacing, 1, 1, 1, 1)
    struct.pack_into("<f", h, 108, 352.0)
    struct.pack_into("<ff", h, 112, 1.0, 0.0)  # scl_slope, scl_inter
    struct.pack_into("<hh", h, 252, 0, 1)  # qform_code, sform_code
    struct.pack_into("<4f", h, 280, spacing, 0, 0, 0)
    struct.pack_into("<4f", h, 296, 0, spacing, 0, 0)
    struct.pack_into("<4f", h, 312, 0, 0, spacing, 0)
    h[344:348] = b"n+1\0"
    return bytes(h) + b"\0" * 4 + ball_voxels(n, dtype)


def read(path):
    with open(os.path.join(ROOT, path), "rb") as fh:
        return fh.read()


def bases():
    """Per format: extension, [(name, bytes, extra CLI args, size)], reference checker."""
    v, f = icosphere()
    tet = [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)]
    tetf = [(0, 2, 1), (0, 1, 3), (1, 2, 3), (0, 3, 2)]
    mesh_models = [("tetrahedron", read("fixtures/meshes/tetrahedron.ply"), [], "0.3")]
    rtdose = read("fixtures/images/dicom/rtdose.dcm")
    b = {
        "ply_ascii": (".ply", mesh_models + [("ico", ply_bytes(v, f, "ascii"), [], "0.4"),
                                             ("rich", ply_rich_bytes(v, f, "ascii"), [], "0.4")]),
        "ply_binary": (".ply", [
            ("ico_le", ply_bytes(v, f, "binary_little_endian"), [], "0.4"),
            ("ico_be", ply_bytes(v, f, "binary_big_endian"), [], "0.4"),
            ("tet_le", ply_bytes(tet, tetf, "binary_little_endian"), [], "0.3"),
            ("rich_be", ply_rich_bytes(v, f, "binary_big_endian"), [], "0.4"),
        ]),
        "off": (".off", [("cube", read("fixtures/meshes/cube.off"), [], "0.4"),
                         ("ico", off_bytes(v, f), [], "0.4")]),
        "obj": (".obj", [("cube_quads", read("fixtures/meshes/cube_quads.obj"), [], "0.4"),
                         ("ico", obj_bytes(v, f), [], "0.4")]),
        "stl_ascii": (".stl", [("tetrahedron", read("fixtures/meshes/tetrahedron.stl"), [], "0.3"),
                               ("ico", stl_ascii_bytes(v, f), [], "0.4")]),
        "stl_binary": (".stl", [("ico", stl_binary_bytes(v, f), [], "0.4"),
                                ("tet", stl_binary_bytes(tet, tetf), [], "0.3")]),
        "xyz": (".xyz", [("sphere", xyz_bytes(300, False, 1), [], "0.4"),
                         ("sphere_n", xyz_bytes(300, True, 2), [], "0.4")]),
        "nii": (".nii", [("ball_u8", nifti1_bytes(12, "u8"), ["--iso", "50"], "3"),
                         ("ball_f32", nifti1_bytes(10, "f32"), ["--iso", "50"], "3")]),
        "nii_gz": (".nii.gz", [
            ("phantom", read("fixtures/images/phantom_i16_32.nii.gz"), ["--iso", "100"], "8"),
            ("ball_i16", gzip.compress(nifti1_bytes(12, "i16"), mtime=0), ["--iso", "50"], "3"),
        ]),
        "nii2": (".nii", [
            ("example_nifti2", gzip.decompress(read("fixtures/images/nibabel_example_nifti2.nii.gz")),
             ["--iso", "500", "--frame", "1"], "3"),
        ]),
        "mgh": (".mgh", [
            ("test_mgz", gzip.decompress(read("fixtures/images/nibabel_test.mgz")),
             ["--iso", "0", "--frame", "1"], "1"),
        ]),
        # An RT Dose, and it with DoseGridScaling 1 at an iso that a damaged scaling read as 1 meshes.
        "dicom": (".dcm", [("rtdose", rtdose, ["--iso", "1"], "20"), ("rtdose_scale1", dicom_value(
            rtdose, None, 0x3004000E, b"1 "), ["--iso", "1000000"], "20")]),
        "raw": (".raw", [
            ("ball_u8", ball_voxels(12, "u8"),
             ["--dims", "12,12,12", "--dtype", "u8", "--iso", "50"], "2"),
            ("ball_f32", ball_voxels(10, "f32"),
             ["--dims", "10,10,10", "--dtype", "f32", "--iso", "50"], "2"),
        ]),
    }
    return b


# ---------------------------------------------------------------- mutations

TOKENS = [b"0", b"-1", b"1", b"3", b"255", b"65536", b"4294967296", b"1e308", b"1e400", b"-1e300",
          b"nan", b"inf", b"-inf", b"9223372036854775808", b"0x10", b"1.5.2", b"x", b"#", b"\n",
          b" ", b"\t", b"\r\n", b"\0", b"//", b"/", b"1/2/3", b"-0", b"1_0", b"+", b"e5"]
HUGE = [b"1e308", b"-1e308", b"1e400", b"3.4e38", b"1e30", b"1e20", b"9999999999", b"-2147483649",
        b"4294967295", b"1e-320", b"nan", b"inf", b"-nan"]
NUMRE = re.compile(rb"[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?")


def m_flip(d, r):
    if not d:
        return d
    d = bytearray(d)
    i = r.randrange(len(d))
    d[i] = d[i] ^ (1 << r.randrange(8)) if r.random() < 0.7 else r.randrange(256)
    return bytes(d)


def m_truncate(d, r):
    return d[:r.randrange(len(d) + 1)]


def m_insert(d, r):
    i = r.randrange(len(d) + 1)
    t = r.choice(TOKENS)
    if r.random() < 0.5:
        t = b" " + t
    return d[:i] + t + d[i:]


def m_delete(d, r):
    spans = [m.span() for m in re.finditer(rb"\S+", d[:200000])]
    if not spans:
        return m_truncate(d, r)
    a, b = r.choice(spans)
    return d[:a] + d[b:]


def numbers(d):
    return [m.span() for m in NUMRE.finditer(d[:200000])]


def m_number(d, r, pool=HUGE):
    sp = numbers(d)
    if not sp:
        return m_flip(d, r)
    a, b = r.choice(sp)
    return d[:a] + r.choice(pool) + d[b:]


def m_count(d, r):
    """Change a small integer (counts, list lengths, indices) by a small amount."""
    sp = [s for s in numbers(d) if re.fullmatch(rb"\d+", d[s[0]:s[1]])]
    if not sp:
        return m_flip(d, r)
    a, b = r.choice(sp[:40] if r.random() < 0.6 else sp)
    n = int(d[a:b]) + r.choice([-2, -1, 1, 2, 100, -10 ** 9, 10 ** 9, 2 ** 32])
    return d[:a] + str(n).encode() + d[b:]


def m_lines(d, r):
    ls = d.split(b"\n")
    if len(ls) < 2:
        return m_flip(d, r)
    i, j = r.randrange(len(ls)), r.randrange(len(ls))
    op = r.randrange(3)
    if op == 0:
        ls.insert(j, ls[i])
    elif op == 1:
        del ls[i]
    else:
        ls[i], ls[j] = ls[j], ls[i]
    return b"\n".join(ls)


def m_header_word(d, r):
    """PLY/OFF/STL keywords: swap one header word for another plausible one."""
    words = [b"ascii", b"binary_little_endian", b"binary_big_endian", b"1.0", b"2.0", b"float",
             b"double", b"uchar", b"int", b"uint", b"char", b"list", b"vertex", b"face", b"x",
             b"OFF", b"COFF", b"4OFF", b"solid", b"facet", b"endloop", b"outer", b"vertex_indices",
             b"v", b"f", b"vt", b"vn"]
    sp = [m.span() for m in re.finditer(rb"[A-Za-z_0-9.]+", d[:3000])]
    if not sp:
        return m_flip(d, r)
    a, b = r.choice(sp)
    return d[:a] + r.choice(words) + d[b:]


def binary_values(d, r, start, step, fmt):
    """Overwrite one binary value at start + k*step with a special value."""
    n = (len(d) - start) // step
    if n <= 0:
        return m_flip(d, r)
    i = start + step * r.randrange(n)
    specials = [float("nan"), float("inf"), 1e38, -3.4e38, 1e-45, 0.0] if fmt in "fd" else \
        [-1, 0, 255, 2 ** 31 - 1, -2 ** 31]
    v = r.choice(specials)
    if fmt == "i":
        return d[:i] + struct.pack("<i", v) + d[i + 4:]
    if fmt == "B":
        return d[:i] + bytes([v & 255]) + d[i + 1:]
    return d[:i] + struct.pack("<" + fmt, v) + d[i + struct.calcsize(fmt):]


NIFTI_FIELDS = [(0, "i"), (40, "h"), (42, "h"), (44, "h"), (46, "h"), (48, "h"), (70, "h"),
                (72, "h"), (76, "f"), (80, "f"), (84, "f"), (88, "f"), (108, "f"), (112, "f"),
                (116, "f"), (252, "h"), (254, "h"), (280, "f"), (284, "f"), (292, "f"),
                (300, "f"), (316, "f"), (256, "f"), (268, "f")]


# NIfTI-2 header fields (offset, struct format): sizeof_hdr, datatype, bitpix, dim[0..4],
# pixdim[1..4], vox_offset, scl_slope, scl_inter, qform_code, sform_code, quatern_b, srow_x[0].
NIFTI2_FIELDS = [(0, "i"), (12, "h"), (14, "h"), (16, "q"), (24, "q"), (40, "q"), (48, "q"),
                 (112, "d"), (120, "d"), (128, "d"), (168, "q"), (176, "d"), (184, "d"),
                 (344, "i"), (348, "i"), (352, "d"), (400, "d")]


def header_field(d, r, size, fields, endian, values):
    """Overwrite one header field (offset, struct format) with one of `values[format]`."""
    if len(d) < size:
        return m_flip(d, r)
    off, fmt = r.choice(fields)
    v = r.choice(values[fmt])
    return d[:off] + struct.pack(endian + fmt, v) + d[off + struct.calcsize(fmt):]


NIFTI2_VALUES = {
    "d": [0.0, -1.0, 1e300, 1e-300, float("nan"), float("inf"), 0.5, 2.0],
    "q": [0, -1, 1, 2, 3, 4, 7, 8, 544, 545, 2 ** 40, 2 ** 63 - 1, -2 ** 63],
    "i": [0, 348, 540, -1, 1, 4, 5, 2 ** 31 - 1],
    "h": [0, -1, 2, 4, 8, 16, 64, 512, 32767, -32768],
}


def m_nifti2_field(d, r):
    return header_field(d, r, 540, NIFTI2_FIELDS, "<", NIFTI2_VALUES)


# MGH header fields (offset, big-endian struct format): version, width, height, depth, nframes,
# type, goodRASFlag, delta, Mdc[0], Mdc[4], Pxyz_c[0].
MGH_FIELDS = [(0, "i"), (4, "i"), (8, "i"), (12, "i"), (16, "i"), (20, "i"), (28, "h"),
              (30, "f"), (34, "f"), (38, "f"), (42, "f"), (58, "f"), (78, "f")]


MGH_VALUES = {
    "f": [0.0, -1.0, 1e30, 1e-30, float("nan"), float("inf"), 0.5, 2.0],
    "h": [0, 1, -1, 2],
    "i": [0, -1, 1, 2, 3, 4, 5, 7, 1000, 2 ** 31 - 1],
}


def m_mgh_field(d, r):
    return header_field(d, r, 284, MGH_FIELDS, ">", MGH_VALUES)


def m_nifti_field(d, r):
    if len(d) < 348:
        return m_flip(d, r)
    off, fmt = r.choice(NIFTI_FIELDS)
    if fmt == "f":
        v = r.choice([0.0, -1.0, 1e20, 3.4e38, 1e-30, float("nan"), float("inf"), 352.0, 353.0,
                      1024.0, 1e9, -100.0, 0.5, 2.0])
    else:
        v = r.choice([0, -1, 1, 2, 3, 4, 7, 8, 16, 64, 512, 32767, -32768, 1000])
        if fmt == "i":
            v = r.choice([0, 348, 540, 347, -1, 2 ** 31 - 1])
    try:
        return d[:off] + struct.pack("<" + fmt, v) + d[off + struct.calcsize(fmt):]
    except struct.error:
        return d


def dicom_elements(d):
    """The top-level elements of an implicit-VR DICOM file after its meta group:
    {tag: (offset of its 4-byte length, length)}."""
    out, p = {}, 144 + struct.unpack_from("<I", d, 140)[0] if len(d) >= 144 else len(d)
    while p + 8 <= len(d):
        g, e, n = struct.unpack_from("<HHI", d, p)
        out[g << 16 | e], p = (p + 4, n), p + 8 + n
    return out


def dicom_value(d, r, tag, v):
    """Element `tag`'s value replaced by `v`, its length set to match (a flip if it is absent)."""
    at, n = dicom_elements(d).get(tag, (None, 0))
    return m_flip(d, r) if at is None else d[:at] + struct.pack("<I", len(v)) + v + d[at + 4 + n:]


# Rows, Columns, BitsAllocated, BitsStored, PixelRepresentation, SamplesPerPixel (US);
# NumberOfFrames (IS), ImagePositionPatient, ImageOrientationPatient, PixelSpacing,
# GridFrameOffsetVector, DoseGridScaling (DS).
DICOM_US = [0x00280010, 0x00280011, 0x00280100, 0x00280101, 0x00280103, 0x00280002]
DICOM_DS = [0x00280008, 0x00200032, 0x00200037, 0x00280030, 0x3004000C, 0x3004000E]


def m_dicom_field(d, r):
    """One header value: a US to another number; in a decimal string, one value changed (to a
    near or far number, nan, 1e400, nothing), dropped, or one added."""
    if r.random() < 0.4:
        v = r.choice([0, 1, 2, 3, 8, 9, 11, 16, 31, 32, 33, 64, 65535])
        return dicom_value(d, r, r.choice(DICOM_US), struct.pack("<H", v))
    tag = r.choice(DICOM_DS)
    at, n = dicom_elements(d).get(tag, (0, 0))
    vals = d[at + 4:at + 4 + n].strip().split(b"\\")
    i = r.randrange(len(vals))
    x = float(vals[i]) if NUMRE.fullmatch(vals[i]) else 1.0
    new = r.choice([b"0", b"-1", b"2", b"14", b"16", b"nan", b"1e400", b"", b"1.5",
                    repr(x * r.choice([1.0005, 1.02, -1, 10])).encode(), repr(x + 1).encode()])
    vals[i:i + 1] = r.choice([[new], [new], [], [vals[i], new]])
    v = b"\\".join(vals)
    return dicom_value(d, r, tag, v + b" " * (len(v) % 2))


def m_dicom_length(d, r):
    """One element's length field changed, or the pixel data cut or padded (its length set to
    match) by a byte, a row or a frame."""
    els = dicom_elements(d)
    if r.random() < 0.5 and 0x7FE00010 in els:
        at, n = els[0x7FE00010]
        v, k = d[at + 4:at + 4 + n], r.choice([1, 2, 4, 40, 400, 800])
        return dicom_value(d, r, 0x7FE00010, v[:-k] if r.random() < 0.5 else v + b"\0" * k)
    at, n = r.choice(list(els.values()) or [(0, 0)])
    n = r.choice([0, 0xFFFFFFFF, 0x7FFFFFFF, (n + r.choice([-4, -2, -1, 1, 2, 4, 400])) % 2 ** 32])
    return d[:at] + struct.pack("<I", n) + d[at + 4:]


def m_gzip(d, r):
    """Corrupt a gzip stream: a byte in the deflate data, the CRC, the length, a cut, junk."""
    if len(d) < 20:  # cut by an earlier mutation: no stream left to corrupt
        return m_flip(d, r)
    op = r.randrange(6)
    if op == 0:
        i = r.randrange(10, len(d) - 8)
        return d[:i] + bytes([d[i] ^ (1 << r.randrange(8))]) + d[i + 1:]
    if op == 1:
        return d[:-8] + bytes([d[-8] ^ 1]) + d[-7:]
    if op == 2:
        return d[:-4] + struct.pack("<I", (struct.unpack("<I", d[-4:])[0] + r.choice([1, -1, 2 ** 20])) % 2 ** 32)
    if op == 3:
        return d[:r.randrange(len(d))]
    if op == 4:
        return d + r.choice([b"\0" * 8, b"junk", gzip.compress(b"x" * 100)])
    try:
        raw = gzip.decompress(d)
    except (OSError, EOFError, zlib.error):
        return m_flip(d, r)
    raw = r.choice([m_nifti_field, m_flip, m_truncate])(raw, r)
    return gzip.compress(raw, mtime=0)


def mutators(fmt):
    common = [m_flip, m_truncate, m_insert, m_delete, m_number, m_count, m_lines]
    if fmt in ("ply_ascii", "off", "obj", "stl_ascii", "xyz"):
        return common + [m_header_word, m_header_word, lambda d, r: m_number(d, r, [b"nan", b"inf", b"-inf"])]
    if fmt == "ply_binary":
        return [m_flip, m_flip, m_truncate, m_header_word, m_header_word, m_count, m_insert,
                lambda d, r: binary_values(d, r, d.find(b"end_header\n") + 11, 4, "f"),
                lambda d, r: binary_values(d, r, d.find(b"end_header\n") + 11, 1, "B")]
    if fmt == "stl_binary":
        return [m_flip, m_flip, m_truncate, m_insert,
                lambda d, r: binary_values(d, r, 84, 4, "f"),
                lambda d, r: d[:80] + struct.pack("<I", r.choice([0, 1, 31, 33, 2 ** 32 - 1])) + d[84:],
                lambda d, r: d + b"\0" * r.choice([1, 2, 49, 50, 51])]
    if fmt == "nii":
        return [m_flip, m_truncate, m_nifti_field, m_nifti_field, m_nifti_field,
                lambda d, r: d + b"\0" * r.choice([1, 100]),
                lambda d, r: binary_values(d, r, 352, 4, "f")]
    if fmt == "nii2":
        return [m_flip, m_truncate, m_nifti2_field, m_nifti2_field, m_nifti2_field,
                lambda d, r: d + b"\0" * r.choice([1, 100]),
                lambda d, r: binary_values(d, r, 544, 4, "i")]
    if fmt == "mgh":
        return [m_flip, m_truncate, m_mgh_field, m_mgh_field, m_mgh_field,
                lambda d, r: d + b"\0" * r.choice([1, 100]),
                lambda d, r: binary_values(d, r, 284, 4, "i")]
    if fmt == "dicom":
        return [m_flip, m_flip, m_truncate, m_dicom_field, m_dicom_field, m_dicom_field, m_dicom_field,
                m_dicom_length, m_dicom_length, lambda d, r: d + b"\0" * r.choice([1, 8, 100]),
                lambda d, r: binary_values(d, r, max(0, len(d) - 6000), 4, "i")]
    if fmt == "nii_gz":
        return [m_gzip, m_gzip, m_gzip, m_flip, m_truncate]
    if fmt == "raw":
        return [m_flip, m_truncate, lambda d, r: d + b"\0" * r.choice([1, 7]),
                lambda d, r: binary_values(d, r, 0, 4, "f"), None, None]
    raise ValueError(fmt)


def mutate_raw_args(args, r):
    """Wrong raw-volume flags (a None mutator above)."""
    a = list(args)
    k = r.randrange(4)
    if k == 0:
        i = a.index("--dims") + 1
        a[i] = r.choice(["12,12,13", "0,12,12", "12,12", "-1,2,3", "1,1,1", "1e3,1,1",
                         "18446744073709551615,2,2", "4294967296,4294967296,1", "6,24,12"])
    elif k == 1:
        i = a.index("--dtype") + 1
        a[i] = r.choice(["u16", "i16", "f64", "u8", "f32", "float", "u64", ""])
    elif k == 2:
        a.append("--big-endian")
    else:
        a += ["--spacing", r.choice(["0,1,1", "-1,1,1", "nan,1,1", "1e308,1e308,1e308", "1,1"])]
    return a


# ---------------------------------------------------------------- driver

PANIC = re.compile(r"panicked|RUST_BACKTRACE|stack overflow|memory allocation of")


def run_one(exe, path, args, size, out, time_limit):
    # `--flag=VALUE`: a value starting with `-` is otherwise taken for a flag by clap.
    flags, k = [], 0
    while k < len(args):
        if args[k].startswith("--") and k + 1 < len(args) and not args[k + 1].startswith("--"):
            flags.append(args[k] + "=" + args[k + 1])
            k += 2
        else:
            flags.append(args[k])
            k += 1
    cmd = [exe, "mesh", path, "--size", size, "--max-vertices", "20000", "--time-limit",
           str(time_limit), "-o", out, "--no-verify", "-q"] + flags
    t0 = time.time()
    try:
        p = subprocess.run(cmd, capture_output=True, timeout=time_limit + 20)
        return p.returncode, p.stderr.decode("utf-8", "replace"), time.time() - t0
    except subprocess.TimeoutExpired:
        return None, "", time.time() - t0


def read_counts(stderr):
    """(vertices, triangles) or (points, None) as the CLI's input note reports them."""
    m = re.search(r"note: polyhedron: (\d+) vertices, (\d+) triangles", stderr)
    if m:
        return int(m.group(1)), int(m.group(2))
    m = re.search(r"note: DICOM: (\d+) slices of (\d+) x (\d+) pixels", stderr)
    if m:  # (columns, rows, frames), as check_dicom reports them
        return int(m.group(2)), int(m.group(3)), int(m.group(1))
    m = re.search(r"note: point set: (\d+) points", stderr)
    return (int(m.group(1)), None) if m else None


def counts_agree(ref, got):
    """None in the reference: not compared (STL vertices are merged by the reader)."""
    return all(a is None or b is None or a == b for a, b in zip(ref, got))


def message_ok(stderr, path):
    errs = [ln for ln in stderr.splitlines() if ln.startswith("error")]
    if len(errs) != 1:
        return False
    e = errs[0]
    return (os.path.basename(path) in e or "--" in e) and "Error {" not in e and \
        "kind:" not in e and "ParseError" not in e


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--bin", default=os.path.join(ROOT, "target/release/xtask"))
    ap.add_argument("--per-format", type=int, default=300)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--formats", default="")
    ap.add_argument("--time-limit", type=int, default=20)
    ap.add_argument("--keep", default=os.path.join(ROOT, "target/mutate"))
    ap.add_argument("--json", default="")
    a = ap.parse_args()
    if not os.path.exists(a.bin):
        sys.exit("%s: not built; run `cargo build --release -p xtask` first" % a.bin)
    all_bases = bases()
    fmts = a.formats.split(",") if a.formats else list(all_bases)
    os.makedirs(a.keep, exist_ok=True)
    work = tempfile.mkdtemp(prefix="mutate-")
    table, findings = [], []
    for fmt in fmts:
        ext, base_list = all_bases[fmt]
        r = random.Random("%s-%d" % (fmt, a.seed))
        muts = mutators(fmt)
        row = {"format": fmt, "mutations": 0, "panics": 0, "timeouts": 0, "accepted_bad": 0,
               "misread": 0, "bad_messages": 0, "refused_readable": 0, "exit0": 0, "rejected_by_reference": 0, "seconds": 0.0}
        t_fmt = time.time()
        for k in range(a.per_format):
            name, data, args, size = base_list[k % len(base_list)]
            steps = 1 if r.random() < 0.7 else r.randint(2, 4)
            desc = []
            for _ in range(steps):
                m = r.choice(muts)
                if m is None:
                    args = mutate_raw_args(args, r)
                    desc.append("flags")
                else:
                    data = m(data, r)
                    desc.append(getattr(m, "__name__", "m"))
            path = os.path.join(work, "%s_%04d_%s%s" % (fmt, k, name, ext))
            with open(path, "wb") as fh:
                fh.write(data)
            check = raw_checker(args) if fmt == "raw" else CHECKS[fmt]
            counts = None
            try:
                kind = check(data)
                if isinstance(kind, tuple):
                    kind, counts = kind[0], kind[1:]
                why = None
                if fmt in ("ply_ascii", "ply_binary", "off", "obj", "stl_ascii", "stl_binary") \
                        and kind == "mesh":
                    why = trimesh_rejects(path, kind)
            except Reject as ex:
                why = str(ex)
            except Exception as ex:  # a checker bug must not stop the run
                why = None
                desc.append("checker-error:%s" % ex)
            out = os.path.join(work, "out.ply")
            rc, err, secs = run_one(a.bin, path, args, size, out, a.time_limit)
            row["mutations"] += 1
            row["rejected_by_reference"] += why is not None
            verdict = None
            if rc is None:
                verdict = "timeout"
                row["timeouts"] += 1
            elif rc == 101 or PANIC.search(err):
                verdict = "panic"
                row["panics"] += 1
            elif rc == 0:
                row["exit0"] += 1
                if why is not None:
                    verdict = "accepted-bad"
                    row["accepted_bad"] += 1
                elif counts and read_counts(err) and not counts_agree(counts, read_counts(err)):
                    verdict = "misread"
                    why = "reference reads %s, the CLI %s" % (counts, read_counts(err))
                    row["misread"] += 1
            elif not message_ok(err, path):
                verdict = "bad-message"
                row["bad_messages"] += 1
            elif why is None:
                # Not a failure: the reference reads it but the CLI refuses it (a reader
                # stricter than the reference, or an input the mesher cannot use). Listed in
                # the JSON for review.
                row["refused_readable"] += 1
                findings.append({"format": fmt, "verdict": "refused-readable", "args": args,
                                 "mutations": desc, "exit": rc,
                                 "stderr": err.strip().splitlines()[-1:]})
            if verdict:
                kept = os.path.join(a.keep, os.path.basename(path))
                shutil.copy(path, kept)
                findings.append({"format": fmt, "verdict": verdict, "file": kept, "args": args,
                                 "size": size, "mutations": desc, "reference": why, "exit": rc,
                                 "stderr": err.strip().splitlines()[-3:], "seconds": round(secs, 2)})
                print("%-12s %-13s %s %s ref=%s exit=%s %s" % (fmt, verdict, kept, " ".join(args), why,
                                                             rc, err.strip().splitlines()[-1:] if err else ""),
                      flush=True)
            os.remove(path)
        row["seconds"] = round(time.time() - t_fmt, 1)
        table.append(row)
        print(json.dumps(row), flush=True)
    shutil.rmtree(work, ignore_errors=True)
    cols = ["format", "mutations", "panics", "timeouts", "accepted_bad", "misread", "bad_messages",
            "refused_readable",
            "exit0", "rejected_by_reference", "seconds"]
    print("\n| " + " | ".join(cols) + " |\n|" + "---|" * len(cols))
    for row in table:
        print("| " + " | ".join(str(row[c]) for c in cols) + " |")
    if a.json:
        with open(a.json, "w") as fh:
            json.dump({"table": table, "findings": findings}, fh, indent=1)
    bad = sum(r["panics"] + r["timeouts"] + r["accepted_bad"] + r["misread"] for r in table)
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
