"""Strict reference readers for scripts/mutate.py: each format's structure checked the way
the format defines it (every count, token, index and header field), plus trimesh, nibabel and
Python's gzip where they are installed. A checker returns the kind of input it accepts (with
the vertex/triangle or point counts it read) or raises Reject with the reason.
"""

import gzip
import io
import logging
import math
import re
import struct
import warnings
import zlib

warnings.simplefilter("ignore")
for _name in ("nibabel", "trimesh", "pydicom"):
    logging.getLogger(_name).setLevel(logging.CRITICAL + 1)

class Reject(Exception):
    pass


NUM = re.compile(r"^[+-]?((\d+\.?\d*|\.\d+)([eE][+-]?\d+)?|inf|infinity|nan)$", re.I)
INT = re.compile(r"^[+-]?\d+$")
DS = re.compile(rb" *[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)? *")  # DICOM decimal string


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
    """Non-blank lines with comments stripped (a `#` at the start of a token), as token
    lists."""
    out = []
    for ln in rs_lines(s):
        t = rs_split(ln)
        if comment:
            cut = [k for k, tok in enumerate(t) if tok.startswith(comment)]
            t = t[:cut[0]] if cut else t
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
    return sum(len(p) - 2 for p in faces)


PLY_T = {"char": "b", "int8": "b", "uchar": "B", "uint8": "B", "short": "h", "int16": "h",
         "ushort": "H", "uint16": "H", "int": "i", "int32": "i", "uint": "I", "uint32": "I",
         "float": "f", "float32": "f", "double": "d", "float64": "d"}


RANGE = {c: (-2 ** (8 * struct.calcsize(c) - 1), 2 ** (8 * struct.calcsize(c) - 1) - 1)
         for c in "bhi"}
RANGE.update({c: (0, 2 ** (8 * struct.calcsize(c)) - 1) for c in "BHI"})


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
                        n = integer(row[pos], 0, RANGE[lcode][1])
                        items = row[pos + 1:pos + 1 + n]
                        if len(items) != n:
                            raise Reject("short list")
                        rec.append([num(x, False) if code in "fd" else integer(x, *RANGE[code])
                                    for x in items])
                        pos += 1 + n
                    else:
                        if pos >= len(row):
                            raise Reject("short row")
                        rec.append(num(row[pos], False) if code in "fd"
                                   else integer(row[pos], *RANGE[code]))
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
        return "mesh", len(vals), faces_ok([rec[li[0]] for rec in fvals], len(vals))
    if not vals:
        raise Reject("no vertices")
    return "points", len(vals), None


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
    return "mesh", nv, faces_ok(faces, nv)


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
    return "mesh", v, faces_ok(faces, v)


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
            return "mesh", None, n
    if not data.lstrip().startswith(b"solid"):
        raise Reject("not ASCII STL and wrong binary size")
    try:
        s = data.decode("ascii")
    except UnicodeDecodeError:
        raise Reject("not ASCII")
    # Keywords are case-insensitive, as several exporters write them in capitals.
    rows = [rs_split(ln.lower()) for ln in rs_lines(s) if rs_split(ln)]
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
    return "mesh", None, facets


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
    return "points", n, None


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
    return nibabel_check(data, "Nifti1Image", None)


def nibabel_check(data, kind, frame):
    """nibabel as the reference for everything it checks: the image class `kind` reads the
    bytes, its affine is finite and invertible, the voxels (of `frame`) are finite."""
    try:
        import nibabel
        import numpy as np
        img = getattr(nibabel, kind).from_bytes(data)
        vox = np.asanyarray(img.dataobj)
        if frame is not None:  # the fourth axis (dimensions past it are 1 here)
            vox = vox[:, :, :, frame]
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


def check_nifti2(data, frame=1):
    """A NIfTI-2 file read at --frame `frame` (the fixture's args)."""
    if len(data) < 540:
        raise Reject("short header")
    for e in "<>":
        if struct.unpack_from(e + "i", data, 0)[0] == 540:
            break
    else:
        raise Reject("sizeof_hdr != 540")
    if data[4:8] not in (b"n+2\0", b"ni2\0") or data[8:12] != b"\r\n\x1a\n":
        raise Reject("bad magic")
    dim = struct.unpack_from(e + "8q", data, 16)
    if not 1 <= dim[0] <= 7 or any(d < 1 for d in dim[1:1 + dim[0]]):
        raise Reject("bad dim")
    if dim[0] < 3 or dim[3] == 1:
        raise Reject("not a 3D volume")
    if any(d != 1 for d in dim[5:1 + dim[0]]):
        raise Reject("vector voxels")
    frames = dim[4] if dim[0] >= 4 else 1
    if frame >= frames:
        raise Reject("no such frame")
    code, bits = struct.unpack_from(e + "hh", data, 12)
    if code not in NIFTI_SIZES or bits != 8 * NIFTI_SIZES[code]:
        raise Reject("bad datatype/bitpix")
    pix = struct.unpack_from(e + "8d", data, 104)
    qcode, scode = struct.unpack_from(e + "ii", data, 344)
    if not 1 <= scode <= 4 and not all(math.isfinite(p) and p != 0 for p in pix[1:4]):
        raise Reject("bad pixdim (and no sform)")
    (off,) = struct.unpack_from(e + "q", data, 168)
    if off < 544 or off > 1e15:
        raise Reject("bad vox_offset")
    slope, inter = struct.unpack_from(e + "dd", data, 176)
    if math.isinf(slope) or (slope != 0 and not math.isnan(slope) and not math.isfinite(inter)):
        raise Reject("non-finite scaling")
    if dim[1] * dim[2] * dim[3] * frames > 2 ** 40:
        raise Reject("too large")
    need = off + dim[1] * dim[2] * dim[3] * frames * NIFTI_SIZES[code]
    if len(data) < need:
        raise Reject("truncated voxels")
    return nibabel_check(data, "Nifti2Image", frame)


MGH_SIZES = {0: 1, 1: 4, 3: 4, 4: 2}


def check_mgh(data, frame=1):
    """A FreeSurfer .mgh read at --frame `frame` (the fixture's args)."""
    if len(data) < 284:
        raise Reject("short header")
    version, w, h, dpt, frames, ty = struct.unpack_from(">6i", data, 0)
    if version != 1:
        raise Reject("bad version")
    if min(w, h, dpt, frames) < 1:
        raise Reject("bad dims")
    if frame >= frames:
        raise Reject("no such frame")
    if ty not in MGH_SIZES:
        raise Reject("bad type")
    if len(data) - 284 < w * h * dpt * frames * MGH_SIZES[ty]:
        raise Reject("truncated voxels")
    (good,) = struct.unpack_from(">h", data, 28)
    if good and not all(math.isfinite(x) and x != 0 for x in struct.unpack_from(">3f", data, 30)):
        raise Reject("bad delta")
    return nibabel_check(data, "MGHImage", frame)


def dicom_walk(data):
    """The preamble; the meta group (explicit VR LE, as long as (0002,0000) says, the transfer
    syntax UID of digits and dots); in implicit VR LE, the data set as dicom_set checks it. The
    other UIDs of the meta group (SOP class and instance, implementation class) are not checked:
    the reader does not use them and reads the same voxels whatever they hold (a space in one
    was an "accepted-bad" of session 40's seed 5 with the reader of session 39 too)."""
    if len(data) < 144 or data[128:138] != b"DICM\2\0\0\0UL":
        raise Reject("no DICM preamble or meta group length")
    p, end, ts = 144, 144 + struct.unpack_from("<I", data, 140)[0], None
    while p < min(end, len(data) - 8):
        g, e, vr = struct.unpack_from("<HH2s", data, p)
        lv = vr in (b"OB", b"OW", b"OF", b"SQ", b"UT", b"UN")  # a 4-byte length after 2 zeros
        n, q = struct.unpack_from("<I" if lv else "<H", data, p + 6 + 2 * lv)[0], p + 8 + 4 * lv
        if g != 2 or (vr == b"UI" and e == 0x10 and not re.fullmatch(rb"[\d.]*\0?", data[q:q + n])):
            raise Reject("meta group: bad (%04X,%04X)" % (g, e))
        ts, p = data[q:q + n] if e == 0x10 else ts, q + n
    if p != end or data[p:p + 2] == b"\2\0":
        raise Reject("meta group length wrong")
    if ts == b"1.2.840.10008.1.2\0":  # other syntaxes: pydicom's checks
        dicom_set(data, p, len(data), True)


def is_sq(tag):
    try:
        from pydicom.datadict import dictionary_VR
        return dictionary_VR(tag) == "SQ"
    except KeyError:
        return False
    except ImportError:  # no pydicom: the base file's sequences
        return tag in (0x300C0002, 0x300C0004, 0x300C0020)


def binary_vr(tag):
    try:
        from pydicom.datadict import dictionary_VR
        return dictionary_VR(tag) in ("US", "UL", "SS", "SL", "FL", "FD", "AT", "OW", "US or SS")
    except (KeyError, ImportError):
        return False


def dicom_set(data, p, end, top=False):
    """Implicit VR LE elements from p: in tag order, of even lengths, filling up to `end` (None:
    up to an item delimitation item), each sequence (undefined length, or SQ in the dictionary)
    walked item by item, every item a data set; returns where the set ends.
    dicom-object ignores < 4 trailing bytes (it refuses 4 to 7), does not check tag order, and
    reads a binary element of odd length (US, UL, ...) as its whole words; the values read are
    unaffected. So < 4 bytes at the end of the top level, elements out of order and such odd
    lengths (not PixelData's: the reader checks it) are accepted, but not a tag repeated
    (dicom-object keeps the later value), except (0000,0000) empty ones."""
    seen, lim = set(), len(data) if end is None else end
    while p < lim:
        if top and lim - p < 4:
            return lim
        if lim - p < 8:
            raise Reject("%d bytes after the last element" % (lim - p))
        g, e, n = struct.unpack_from("<HHI", data, p)
        tag, p = g << 16 | e, p + 8
        if end is None and tag == 0xFFFEE00D and n == 0:  # the end of an undefined-length item
            return p
        if g == 0xFFFE or (tag in seen and not tag == n == 0):
            raise Reject("(%04X,%04X) repeated or out of place" % (g, e))
        seen.add(tag)
        if n != 0xFFFFFFFF and n % 2 and tag != 0x7FE00010 and binary_vr(tag):
            n -= 1
        if n != 0xFFFFFFFF and (n % 2 or p + n > lim):
            raise Reject("(%04X,%04X) of odd length or past the end" % (g, e))
        if n == 0xFFFFFFFF or is_sq(tag):
            p = dicom_items(data, p, None if n == 0xFFFFFFFF else p + n, lim)
        else:
            p += n
    if p != lim or end is None:
        raise Reject("a sequence item overruns its end or has no delimitation item")
    return p


def dicom_items(data, p, end, lim):
    """A sequence's items from p, filling up to `end` (None: up to a sequence delimitation item)
    within `lim`; returns where the sequence ends."""
    while end is None or p < end:
        g, e, n = struct.unpack_from("<HHI", data, p) if p + 8 <= lim else (0, 0, 0)
        p += 8
        if end is None and (g, e, n) == (0xFFFE, 0xE0DD, 0):
            return p
        if (g, e) != (0xFFFE, 0xE000) or (n != 0xFFFFFFFF and p + n > (end or lim)):
            raise Reject("(%04X,%04X) in a sequence: not an item, or past its end" % (g, e))
        p = dicom_set(data, p, None if n == 0xFFFFFFFF else p + n)
    if p != end:
        raise Reject("a sequence overruns its length")
    return p


def check_dicom(data):
    """A multi-frame RT Dose file (frames placed by GridFrameOffsetVector): its structure, then
    pydicom's reading, the image pixel module and the geometry checked; (cols, rows, frames)."""
    dicom_walk(data)

    def floats(tag, n):
        v = getattr(ds.get_item(tag), "value", None)  # the raw decimal strings
        t = v.split(b"\\") if isinstance(v, bytes) else []
        if len(t) != n or not all(DS.fullmatch(x) and math.isfinite(float(x)) for x in t):
            raise Reject("(%04X,%04X): not %d finite numbers" % (tag >> 16, tag & 0xFFFF, n))
        return [float(x) for x in t]
    try:
        import pydicom
        ds = pydicom.dcmread(io.BytesIO(data))
        px = [ds.get(k) for k in ("Rows", "Columns", "SamplesPerPixel", "BitsAllocated",
                                  "BitsStored", "HighBit", "PixelRepresentation")]
        rows, cols, spp, ba, bs, hb, pr = px
        if not all(isinstance(x, int) for x in px) or min(rows, cols) < 1 or spp != 1 or \
                ba not in (8, 16, 32) or not 1 <= bs <= ba or hb != bs - 1 or pr not in (0, 1) or \
                ds.get("PhotometricInterpretation") not in ("MONOCHROME1", "MONOCHROME2"):
            raise Reject("image pixel module %r" % px)
        nf = getattr(ds.get_item(0x00280008), "value", None)
        if not isinstance(nf, bytes) or not re.fullmatch(rb" *\+?\d{1,9} *", nf) or int(nf) < 2:
            raise Reject("NumberOfFrames %r: not a whole number >= 2" % nf)
        frames, ps, _ = int(nf), floats(0x00280030, 2), floats(0x00200032, 3)
        ax, ay, az, bx, by, bz = floats(0x00200037, 6)
        if abs(math.hypot(ax, ay, az) - 1) >= 1e-3 or abs(math.hypot(bx, by, bz) - 1) >= 1e-3 or \
                abs(ax * bx + ay * by + az * bz) >= 1e-3 or min(ps) <= 0:
            raise Reject("ImageOrientationPatient or PixelSpacing wrong")
        off = sorted(floats(0x3004000C, frames))
        mean = (off[-1] - off[0]) / (frames - 1)
        if any(b - a <= 1e-3 * min(ps) or abs(b - a - mean) > 0.01 * mean
               for a, b in zip(off, off[1:])):
            raise Reject("GridFrameOffsetVector: not distinct and evenly spaced")
        if ds.get_item(0x3004000E) is not None and floats(0x3004000E, 1) == [0]:
            raise Reject("DoseGridScaling 0")
        need = rows * cols * frames * ba // 8
        if len(ds.get_item(0x7FE00010).value) != need + need % 2:
            raise Reject("PixelData is not Rows x Columns x NumberOfFrames x BitsAllocated")
        ds.pixel_array
    except Reject:
        raise
    except ImportError:  # no pydicom: the structure only
        return "image"
    except Exception as ex:  # pydicom rejects it
        raise Reject("pydicom: %s" % (str(ex).splitlines() or [type(ex).__name__])[0][:80])
    return "image", cols, rows, frames


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
    """trimesh as a second reference for meshes (None when it is missing or agrees). Its
    ASCII PLY reader fails on blank lines, which PLY allows, and its text readers split at
    spaces only: it reads a copy without blank PLY lines and with \\v, \\f as spaces."""
    try:
        import trimesh
    except ImportError:
        return None
    with open(path, "rb") as fh:
        data = fh.read()
    if not path.endswith((".ply", ".stl")) or b"format ascii" in data[:200] or \
            data.lstrip().startswith(b"solid"):
        data = data.replace(b"\x0b", b" ").replace(b"\x0c", b" ").replace(b"\t", b" ")
    if path.endswith(".ply") and b"format ascii" in data[:200]:
        cut = data.find(b"end_header")
        if cut > 0:
            body = data[cut:].split(b"\n")
            keep = [ln for k, ln in enumerate(body) if ln.strip() or k == len(body) - 1]
            data = data[:cut] + b"\n".join(keep)
    try:
        m = trimesh.load(io.BytesIO(data), file_type=path.rsplit(".", 1)[-1],
                         force="mesh" if kind == "mesh" else None, process=False)
    except Exception as ex:
        return "trimesh: %s" % type(ex).__name__
    if kind == "mesh" and len(getattr(m, "faces", [])) == 0:
        return "trimesh: no faces"
    return None


CHECKS = {"ply_ascii": check_ply, "ply_binary": check_ply, "off": check_off, "obj": check_obj,
          "stl_ascii": check_stl, "stl_binary": check_stl, "xyz": check_xyz, "nii": check_nifti,
          "nii_gz": check_nii_gz, "nii2": check_nifti2, "mgh": check_mgh, "dicom": check_dicom}
