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
  structural checks below, plus trimesh / nibabel / gzip where they are installed);
- bad-message: a non-zero exit whose stderr is not one `error:` line naming the file.

Python 3 standard library only; numpy, trimesh and nibabel add reference readers when present.
Usage: scripts/mutate.py [--bin target/release/xtask] [--per-format 300] [--seed 0]
       [--formats ply_ascii,...] [--keep DIR]. Exit status 1 if any panic, timeout or
accepted-bad run was found; the offending inputs are copied to --keep.
"""

import argparse
import gzip
import io
import json
import logging
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
import warnings
import zlib

warnings.simplefilter("ignore")
for _name in ("nibabel", "trimesh"):
    logging.getLogger(_name).setLevel(logging.CRITICAL + 1)

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
    b = {
        "ply_ascii": (".ply", mesh_models + [("ico", ply_bytes(v, f, "ascii"), [], "0.4")]),
        "ply_binary": (".ply", [
            ("ico_le", ply_bytes(v, f, "binary_little_endian"), [], "0.4"),
            ("ico_be", ply_bytes(v, f, "binary_big_endian"), [], "0.4"),
            ("tet_le", ply_bytes(tet, tetf, "binary_little_endian"), [], "0.3"),
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
        "raw": (".raw", [
            ("ball_u8", ball_voxels(12, "u8"),
             ["--dims", "12,12,12", "--dtype", "u8", "--iso", "50"], "2"),
            ("ball_f32", ball_voxels(10, "f32"),
             ["--dims", "10,10,10", "--dtype", "f32", "--iso", "50"], "2"),
        ]),
    }
    return b


# ---------------------------------------------------------------- reference checks


class Reject(Exception):
    pass


NUM = re.compile(r"^[+-]?((\d+\.?\d*|\.\d+)([eE][+-]?\d+)?|inf|infinity|nan)$", re.I)
INT = re.compile(r"^[+-]?\d+$")


def num(tok, finite=True):
    if not NUM.match(tok):
        raise Reject("not a number: %r" % tok)
    x = float(tok)
    if finite and not math.isfinite(x):
        raise Reject("non-finite %r" % tok)
    return x


def integer(tok, lo=None, hi=None):
    if not INT.match(tok):
        raise Reject("not an integer: %r" % tok)
    i = int(tok)
    if (lo is not None and i < lo) or (hi is not None and i > hi):
        raise Reject("integer %d out of range" % i)
    return i


def text(data):
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        raise Reject("not UTF-8")


# The readers' definitions: lines end at "\n" (a trailing "\r" dropped); tokens are split at
# Unicode white space (Rust's `char::is_whitespace`; Python's str.split() also splits at
# \x1c-\x1f, and str.splitlines() at a lone "\r").
RS_WS = re.compile("[\t\n\x0b\x0c\r \x85\xa0\u1680\u2000-\u200a\u2028\u2029\u202f\u205f\u3000]+")


def rs_lines(s):
    return [ln[:-1] if ln.endswith("\r") else ln for ln in s.split("\n")]


def rs_split(s):
    return [t for t in RS_WS.split(s) if t]


def lines_nc(s, comment="#"):
    """Non-blank lines with comments stripped, as token lists."""
    out = []
    for ln in rs_lines(s):
        t = rs_split(ln.split(comment)[0]) if comment else rs_split(ln)
        if t:
            out.append(t)
    return out


def faces_ok(faces, nv):
    if not faces:
        raise Reject("no faces")
    for p in faces:
        if len(p) < 3:
            raise Reject("face with %d corners" % len(p))
        for i in p:
            if not 0 <= i < nv:
                raise Reject("index %d out of range" % i)


PLY_T = {"char": "b", "int8": "b", "uchar": "B", "uint8": "B", "short": "h", "int16": "h",
         "ushort": "H", "uint16": "H", "int": "i", "int32": "i", "uint": "I", "uint32": "I",
         "float": "f", "float32": "f", "double": "d", "float64": "d"}


def check_ply(data):
    pos, hl = 0, []
    while True:
        nl = data.find(b"\n", pos)
        if nl < 0:
            raise Reject("no end_header line")
        try:
            ln = data[pos:nl].decode("ascii")
        except UnicodeDecodeError:
            raise Reject("header not ASCII")
        pos = nl + 1
        if ln.strip() == "end_header":
            break
        hl.append(ln)
    if not hl or hl[0].strip() != "ply":
        raise Reject("no ply magic")
    fmt = rs_split(hl[1]) if len(hl) > 1 else []
    if len(fmt) != 3 or fmt[0] != "format" or fmt[2] not in ("1.0", "1") or \
            fmt[1] not in ("ascii", "binary_little_endian", "binary_big_endian"):
        raise Reject("bad format line")
    els = []
    for ln in hl[2:]:
        t = rs_split(ln)
        if not t or t[0] in ("comment", "obj_info"):
            continue
        if t[0] == "element" and len(t) == 3:
            if any(e[0] == t[1] for e in els):
                raise Reject("duplicate element")
            els.append((t[1], integer(t[2], 0), []))
        elif t[0] == "property" and els:
            props = els[-1][2]
            if len(t) == 3 and t[1] in PLY_T:
                prop = (t[2], PLY_T[t[1]], None)
            elif len(t) == 5 and t[1] == "list" and t[2] in PLY_T and t[3] in PLY_T \
                    and PLY_T[t[2]] not in "fd":
                prop = (t[4], PLY_T[t[3]], PLY_T[t[2]])
            else:
                raise Reject("bad property line")
            if any(p[0] == prop[0] for p in props):
                raise Reject("duplicate property")
            props.append(prop)
        else:
            raise Reject("bad header line %r" % ln)
    body = data[pos:]
    values = {}
    if fmt[1] == "ascii":
        rows = [rs_split(r) for r in rs_lines(text(body)) if rs_split(r)]
        k = 0
        for name, count, props in els:
            vals = []
            for _ in range(count):
                if k >= len(rows):
                    raise Reject("truncated")
                row, k, pos, rec = rows[k], k + 1, 0, []
                for pname, code, lcode in props:
                    if lcode:
                        if pos >= len(row):
                            raise Reject("short row")
                        n = integer(row[pos], 0)
                        items = row[pos + 1:pos + 1 + n]
                        if len(items) != n:
                            raise Reject("short list")
                        rec.append([num(x, False) if code in "fd" else integer(x) for x in items])
                        pos += 1 + n
                    else:
                        if pos >= len(row):
                            raise Reject("short row")
                        rec.append(num(row[pos], False) if code in "fd" else integer(row[pos]))
                        pos += 1
                if pos != len(row):
                    raise Reject("extra tokens on a row")
                vals.append(rec)
            values[name] = (props, vals)
        if k != len(rows):
            raise Reject("data after the last element")
    else:
        e = "<" if fmt[1] == "binary_little_endian" else ">"
        pos = 0
        for name, count, props in els:
            vals = []
            for _ in range(count):
                rec = []
                for pname, code, lcode in props:
                    if lcode:
                        sz = struct.calcsize(lcode)
                        if pos + sz > len(body):
                            raise Reject("truncated")
                        (n,) = struct.unpack_from(e + lcode, body, pos)
                        if n < 0:
                            raise Reject("negative list count")
                        pos += sz
                        sz = struct.calcsize(code) * n
                        if pos + sz > len(body):
                            raise Reject("truncated")
                        rec.append(list(struct.unpack_from(e + code * n, body, pos)))
                        pos += sz
                    else:
                        sz = struct.calcsize(code)
                        if pos + sz > len(body):
                            raise Reject("truncated")
                        rec.append(struct.unpack_from(e + code, body, pos)[0])
                        pos += sz
                vals.append(rec)
                if count > 10 ** 6:
                    raise Reject("count too large for this checker")
            values[name] = (props, vals)
        if pos != len(body):
            raise Reject("%d bytes after the last element" % (len(body) - pos))
    if "vertex" not in values:
        raise Reject("no vertex element")
    props, vals = values["vertex"]
    names = [p[0] for p in props]
    if not all(c in names and props[names.index(c)][2] is None for c in "xyz"):
        raise Reject("vertex without x y z")
    ix = [names.index(c) for c in "xyz"]
    for rec in vals:
        if not all(math.isfinite(rec[i]) for i in ix):
            raise Reject("non-finite vertex")
    if "face" in values and values["face"][1]:
        fprops, fvals = values["face"]
        fn = [p[0] for p in fprops]
        li = [i for i, p in enumerate(fprops) if p[2] and p[0] in ("vertex_indices", "vertex_index")]
        if not li:
            raise Reject("face without vertex_indices")
        if fprops[li[0]][1] in "fd":
            raise Reject("float face indices")
        faces_ok([rec[li[0]] for rec in fvals], len(vals))
        return "mesh"
    if not vals:
        raise Reject("no vertices")
    return "points"


def check_off(data):
    rows = lines_nc(text(data))
    if not rows:
        raise Reject("empty")
    head = rows[0]
    kw = head[0]
    if kw not in ("OFF", "COFF", "NOFF", "CNOFF"):
        raise Reject("bad OFF keyword")
    normals, colours = "N" in kw, "C" in kw
    rest = head[1:]
    k = 1
    if not rest:
        if len(rows) < 2:
            raise Reject("no counts")
        rest, k = rows[1], 2
    if len(rest) not in (2, 3):
        raise Reject("bad counts")
    nv, nf = integer(rest[0], 0), integer(rest[1], 0)
    if len(rest) == 3:
        integer(rest[2], 0)
    if len(rows) != k + nv + nf:
        raise Reject("%d rows for %d vertices and %d faces" % (len(rows) - k, nv, nf))
    per = 6 if normals else 3
    for r in rows[k:k + nv]:
        if not (len(r) == per or (colours and len(r) - per in (3, 4))):
            raise Reject("bad vertex row")
        [num(x, i >= 3 or True) for i, x in enumerate(r)]
    faces = []
    for r in rows[k + nv:]:
        n = integer(r[0], 0)
        if len(r) - 1 - n not in (0, 1, 3, 4):
            raise Reject("bad face row")
        faces.append([integer(x) for x in r[1:1 + n]])
        [num(x) for x in r[1 + n:]]
    faces_ok(faces, nv)
    return "mesh"


OBJ_KNOWN = {"vp", "g", "o", "s", "usemtl", "mtllib", "l", "p", "mg", "cstype", "deg", "curv"}


def check_obj(data):
    v, faces, nt, nn, refs = 0, [], 0, 0, []
    for r in lines_nc(text(data)):
        kw = r[0]
        if kw == "v":
            if len(r) - 1 not in (3, 4, 6, 7):
                raise Reject("bad v line")
            [num(x) for x in r[1:]]
            v += 1
        elif kw == "vt":
            nt += 1
        elif kw == "vn":
            nn += 1
        elif kw == "f":
            poly = []
            for c in r[1:]:
                parts = c.split("/")
                if len(parts) > 3 or parts[0] == "" or (len(parts) == 3 and parts[2] == "") \
                        or (len(parts) == 2 and parts[1] == ""):
                    raise Reject("bad corner %r" % c)
                ids = [integer(p) if p else None for p in parts]
                if any(i == 0 for i in ids):
                    raise Reject("index 0")
                i = ids[0]
                poly.append(i - 1 if i > 0 else v + i)
                for j, cnt in ((1, nt), (2, nn)):
                    if j < len(ids) and ids[j] is not None:
                        t = ids[j]
                        refs.append((t - 1 if t > 0 else cnt + t, cnt, j))
            faces.append(poly)
        elif kw not in OBJ_KNOWN:
            raise Reject("unknown statement %r" % kw)
    for idx, _cnt, j in refs:
        total = nt if j == 1 else nn
        if not 0 <= idx < total:
            raise Reject("bad vt/vn reference")
    faces_ok(faces, v)
    return "mesh"


def check_stl(data):
    if len(data) >= 84:
        (n,) = struct.unpack_from("<I", data, 80)
        if len(data) == 84 + 50 * n:
            if n == 0:
                raise Reject("no facets")
            for k in range(n):
                c = struct.unpack_from("<9f", data, 84 + 50 * k + 12)
                if not all(math.isfinite(x) for x in c):
                    raise Reject("non-finite")
            return "mesh"
    if not data.lstrip().startswith(b"solid"):
        raise Reject("not ASCII STL and wrong binary size")
    try:
        s = data.decode("ascii")
    except UnicodeDecodeError:
        raise Reject("not ASCII")
    rows = [rs_split(ln) for ln in rs_lines(s) if rs_split(ln)]
    state, facets, k = "solid", 0, 0
    for r in rows:
        w = r[0]
        if state == "solid" and w == "solid":
            state = "facet"
        elif state == "facet" and w == "endsolid":
            state = "solid"
        elif state == "facet" and w == "facet" and len(r) == 5 and r[1] == "normal":
            [num(x, False) for x in r[2:]]
            state = "outer"
        elif state == "outer" and r == ["outer", "loop"]:
            state, k = "vertex", 0
        elif state == "vertex" and w == "vertex" and len(r) == 4:
            [num(x) for x in r[1:]]
            k += 1
            state = "vertex" if k < 3 else "endloop"
        elif state == "endloop" and r == ["endloop"]:
            state = "endfacet"
        elif state == "endfacet" and r == ["endfacet"]:
            state, facets = "facet", facets + 1
        else:
            raise Reject("unexpected %r in state %s" % (r[0], state))
    if state != "solid":
        raise Reject("ends in state %s" % state)
    if facets == 0:
        raise Reject("no facets")
    return "mesh"


def check_xyz(data):
    cols, n = 0, 0
    for ln in rs_lines(text(data)):
        t = " ".join(rs_split(ln))
        if not t or t.startswith("#") or t.startswith("//"):
            continue
        toks = [x for x in re.split(r"[ ,]+", t) if x]
        [num(x) for x in toks]
        if len(toks) not in (3, 6) or (cols and len(toks) != cols):
            raise Reject("bad column count")
        cols, n = len(toks), n + 1
    if n == 0:
        raise Reject("no points")
    return "points"


NIFTI_SIZES = {2: 1, 4: 2, 8: 4, 16: 4, 64: 8, 256: 1, 512: 2, 768: 4}


def check_nifti(data):
    if len(data) < 348:
        raise Reject("short header")
    for e in "<>":
        if struct.unpack_from(e + "i", data, 0)[0] == 348:
            break
    else:
        raise Reject("sizeof_hdr != 348")
    if data[344:348] not in (b"n+1\0", b"ni1\0"):
        raise Reject("bad magic")
    dim = struct.unpack_from(e + "8h", data, 40)
    if not 1 <= dim[0] <= 7 or any(d < 1 for d in dim[1:1 + dim[0]]):
        raise Reject("bad dim")
    if dim[0] < 3 or any(d != 1 for d in dim[4:1 + dim[0]]):
        raise Reject("not a 3D volume")
    code, bits = struct.unpack_from(e + "hh", data, 70)
    if code not in NIFTI_SIZES or bits != 8 * NIFTI_SIZES[code]:
        raise Reject("bad datatype/bitpix")
    pix = struct.unpack_from(e + "8f", data, 76)
    qcode, scode = struct.unpack_from(e + "hh", data, 252)
    if scode <= 0 and not all(math.isfinite(p) and p > 0 for p in pix[1:4]):
        raise Reject("bad pixdim (and no sform)")
    (off,) = struct.unpack_from(e + "f", data, 108)
    if not math.isfinite(off) or off < 352 or off != int(off):
        raise Reject("bad vox_offset")
    slope, inter = struct.unpack_from(e + "ff", data, 112)
    # nibabel: a slope of 0 or NaN means no scaling (the intercept is then unused).
    if math.isinf(slope) or (slope != 0 and not math.isnan(slope) and not math.isfinite(inter)):
        raise Reject("non-finite scaling")
    need = int(off) + dim[1] * dim[2] * dim[3] * NIFTI_SIZES[code]
    if len(data) < need:
        raise Reject("truncated voxels")
    sform = struct.unpack_from(e + "12f", data, 280)
    if scode > 0 and not all(math.isfinite(x) for x in sform):
        raise Reject("non-finite sform")
    try:  # nibabel as the reference for everything it checks
        import nibabel
        import numpy as np
        img = nibabel.Nifti1Image.from_bytes(data)
        vox = np.asanyarray(img.dataobj)
        if not np.all(np.isfinite(img.affine)) or abs(np.linalg.det(img.affine[:3, :3])) == 0:
            raise Reject("nibabel: singular or non-finite affine")
        if vox.dtype.kind == "f" and not np.all(np.isfinite(vox)):
            raise Reject("non-finite voxels")
    except Reject:
        raise
    except ImportError:
        pass
    except Exception as ex:  # nibabel rejects it
        raise Reject("nibabel: %s" % str(ex).splitlines()[0][:80] if str(ex) else type(ex))
    return "image"


def check_nii_gz(data):
    try:
        raw = gzip.decompress(data)  # checks every member's CRC-32 and length
    except (OSError, EOFError, zlib.error) as ex:
        raise Reject("gzip: %s" % ex)
    return check_nifti(raw)


def raw_checker(args):
    try:
        dims = [int(x) for x in args[args.index("--dims") + 1].split(",")]
    except ValueError:
        dims = []
    dtype = args[args.index("--dtype") + 1]
    sizes = {"u8": 1, "i8": 1, "u16": 2, "i16": 2, "u32": 4, "i32": 4, "f32": 4, "f64": 8}
    alias = {"uint8": "u8", "int8": "i8", "uint16": "u16", "int16": "i16", "uint32": "u32",
             "int32": "i32", "float32": "f32", "float": "f32", "float64": "f64", "double": "f64"}
    dtype = alias.get(dtype.lower(), dtype.lower())
    if dtype not in sizes:
        return lambda data: (_ for _ in ()).throw(Reject("bad --dtype"))
    size = sizes[dtype]

    def check(data):
        try:
            if len(dims) != 3 or min(dims) < 1 or \
                    len(set(a for a in args if a.startswith("--"))) != \
                    len([a for a in args if a.startswith("--")]):
                raise Reject("bad --dims")
            if "--spacing" in args:
                sp = [float(x) for x in args[args.index("--spacing") + 1].split(",")]
                if len(sp) != 3 or not all(math.isfinite(x) and x > 0 for x in sp):
                    raise Reject("bad --spacing")
        except ValueError:
            raise Reject("bad flag")
        if len(data) != dims[0] * dims[1] * dims[2] * size:
            raise Reject("size != nx*ny*nz*%d" % size)
        if dtype in ("f32", "f64"):
            code = "f" if dtype == "f32" else "d"
            n = len(data) // size
            be = "--big-endian" in args
            if not all(math.isfinite(x) for x in struct.unpack((">" if be else "<") + code * n, data)):
                raise Reject("non-finite voxels")
        return "image"
    return check


def trimesh_rejects(path, kind):
    """trimesh as a second reference for meshes (None when it is missing or agrees)."""
    try:
        import trimesh
    except ImportError:
        return None
    try:
        m = trimesh.load(path, force="mesh" if kind == "mesh" else None, process=False)
    except Exception as ex:
        return "trimesh: %s" % type(ex).__name__
    if kind == "mesh" and len(getattr(m, "faces", [])) == 0:
        return "trimesh: no faces"
    return None


CHECKS = {"ply_ascii": check_ply, "ply_binary": check_ply, "off": check_off, "obj": check_obj,
          "stl_ascii": check_stl, "stl_binary": check_stl, "xyz": check_xyz, "nii": check_nifti,
          "nii_gz": check_nii_gz}

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


def m_gzip(d, r):
    """Corrupt a gzip stream: a byte in the deflate data, the CRC, the length, a cut, junk."""
    op = r.randrange(6)
    if op == 0 and len(d) > 20:
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
               "bad_messages": 0, "exit0": 0, "rejected_by_reference": 0, "seconds": 0.0}
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
            try:
                kind = check(data)
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
            elif not message_ok(err, path):
                verdict = "bad-message"
                row["bad_messages"] += 1
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
    cols = ["format", "mutations", "panics", "timeouts", "accepted_bad", "bad_messages",
            "exit0", "rejected_by_reference", "seconds"]
    print("\n| " + " | ".join(cols) + " |\n|" + "---|" * len(cols))
    for row in table:
        print("| " + " | ".join(str(row[c]) for c in cols) + " |")
    if a.json:
        with open(a.json, "w") as fh:
            json.dump({"table": table, "findings": findings}, fh, indent=1)
    bad = sum(r["panics"] + r["timeouts"] + r["accepted_bad"] for r in table)
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
