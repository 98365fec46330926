"""DICOM series (a folder of classic single-frame slices) read by the library, against
reference readers: SimpleITK (GDCM) for the geometry and the voxels, dcm2niix for both; the
transfer syntaxes and bit depths give the same mesh; bad series are refused with one line
naming the folder. The series are written here by pydicom from the fixture volumes (nothing
is fetched)."""

import json
import os
import re
import shutil
import subprocess
import sys

import meshio
import nibabel as nib
import numpy as np
import pydicom
import pytest
import SimpleITK as sitk
from pydicom.dataset import Dataset, FileMetaDataset
from pydicom.uid import (
    ExplicitVRBigEndian,
    ExplicitVRLittleEndian,
    ImplicitVRLittleEndian,
    JPEG2000Lossless,
    RLELossless,
    generate_uid,
)
from pydicom.valuerep import DS

import rdt_mesher
from conftest import FIXTURES

CROP = os.path.join(FIXTURES, "images", "mni_t1_crop56.nii.gz")
ANAT = os.path.join(FIXTURES, "images", "nibabel_anatomical.nii.gz")
MR_IMAGE = "1.2.840.10008.5.1.4.1.1.4"
LPS_TO_RAS = np.diag([-1.0, -1.0, 1.0, 1.0])

# Three series: the MNI T1 crop (u8 voxels) stored as unsigned 16-bit with slope 2, intercept
# -100 (the other tests' level 171.2 becomes 242.4); nibabel's anatomical.nii (real MRI, int16
# with negative values) as signed 16-bit, slices written in decreasing InstanceNumber; the same
# volume as unsigned 16-bit stored 32768 higher (values above 32767) with intercept -32768.
# Each is oblique (rotated 20 degrees), with anisotropic voxels (spacing: along i, j, k).
CASES = {
    "crop-u16": dict(src=CROP, dtype=np.uint16, add=0, slope=2, inter=-100, iso=242.4, size=3.0,
                     rot=(20, (1, 2, 3)), spacing=(1.1, 0.9, 1.3), origin=(-30.5, 42.25, -17.0)),
    "anat-i16": dict(src=ANAT, dtype=np.int16, add=0, slope=1, inter=0, iso=7373.5, size=4.0,
                     rot=(20, (0, 1, 0.5)), spacing=(2.0, 1.8, 2.5), origin=(40.0, -12.5, 30.25),
                     descending=True),
    "anat-u16": dict(src=ANAT, dtype=np.uint16, add=32768, slope=1, inter=-32768, iso=7373.5,
                     size=4.0, rot=(20, (0, 1, 0.5)), spacing=(2.0, 1.8, 2.5),
                     origin=(40.0, -12.5, 30.25)),
}


def rotation(deg, axis):
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    t = np.radians(deg)
    return np.eye(3) + np.sin(t) * k + (1 - np.cos(t)) * k @ k


def ds(values):
    """Decimal strings of at most 16 characters (DICOM's DS), as pydicom formats them."""
    return [DS(float(v), auto_format=True) for v in values]


def write_series(folder, raw, *, rot, spacing, origin, slope, inter, syntax=ExplicitVRLittleEndian,
                 bits=16, stored=None, series=None, number=1, descending=False, seed=0, slopes=None,
                 study=None, extra=None, instance_base=0, instance_stride=1, **_):
    """Write `raw` (stored values; raw[i, j, k] is column i, row j of the k-th slice along the
    normal) as a classic MR Image Storage series: one file per slice under shuffled random
    names (a third without extension), plus a README.txt. Returns the file names by slice and
    the RAS voxel-to-world affine the spec gives from the tags as written (decimal strings).
    Several volumes of one series are written by calls sharing `series` and `study`, each with
    its `extra` attributes (e.g. EchoNumbers) and InstanceNumbers `instance_base + 1 +
    instance_stride * k`."""
    os.makedirs(folder, exist_ok=True)
    nx, ny, nz = raw.shape
    r = rotation(*rot)
    iop = ds(np.concatenate([r[:, 0], r[:, 1]]))
    row, col = np.array(iop[:3], float), np.array(iop[3:], float)
    normal = np.cross(row, col)
    series = series or generate_uid()
    study = study or generate_uid()
    frame = generate_uid(prefix=None, entropy_srcs=[study])
    rng = np.random.default_rng(seed)
    names = [f"{rng.integers(1 << 40):010x}" + (".dcm" if k % 3 else "") for k in range(nz)]
    signed = raw.dtype.kind == "i"
    dt = np.dtype(f"{'>' if syntax == ExplicitVRBigEndian else '<'}{'i' if signed else 'u'}{bits // 8}")
    ipp = {}
    for k in rng.permutation(nz):
        meta = FileMetaDataset()
        meta.MediaStorageSOPClassUID = MR_IMAGE
        meta.MediaStorageSOPInstanceUID = generate_uid()
        compressed = syntax in (RLELossless, JPEG2000Lossless)
        meta.TransferSyntaxUID = ExplicitVRLittleEndian if compressed else syntax
        d = Dataset()
        d.file_meta = meta
        d.SOPClassUID, d.SOPInstanceUID = MR_IMAGE, meta.MediaStorageSOPInstanceUID
        d.StudyInstanceUID, d.SeriesInstanceUID, d.FrameOfReferenceUID = study, series, frame
        d.Modality, d.Manufacturer, d.PatientName, d.PatientID = "MR", "rdt", "Test^Dicom", "rdt"
        d.PatientPosition, d.ProtocolName, d.SeriesNumber = "HFS", "t1", number
        d.InstanceNumber = int(instance_base + 1 + instance_stride * (nz - 1 - k if descending else k))
        for key, value in (extra or {}).items():
            setattr(d, key, value)
        d.ImagePositionPatient = ipp[k] = ds(np.asarray(origin) + k * spacing[2] * normal)
        d.ImageOrientationPatient = iop
        d.PixelSpacing = ds([spacing[1], spacing[0]])  # row spacing (along j), column spacing (i)
        d.SliceThickness = DS(spacing[2], auto_format=True)
        d.Rows, d.Columns, d.SamplesPerPixel, d.PhotometricInterpretation = ny, nx, 1, "MONOCHROME2"
        d.BitsAllocated, d.BitsStored = bits, stored or bits
        d.HighBit, d.PixelRepresentation = d.BitsStored - 1, int(signed)
        d.RescaleSlope = DS(slopes[k] if slopes is not None else slope)
        d.RescaleIntercept = DS(inter)
        px = np.ascontiguousarray(raw[:, :, k].T.astype(dt))
        d.PixelData = px.tobytes()
        path = os.path.join(folder, names[k])
        if compressed:  # pydicom's RLE encoder; JPEG 2000 through pylibjpeg-openjpeg
            d.compress(syntax, px.astype(px.dtype.newbyteorder("=")), generate_instance_uid=False)
            d.save_as(path, enforce_file_format=True)
        else:
            d.save_as(path, enforce_file_format=True, implicit_vr=syntax == ImplicitVRLittleEndian,
                      little_endian=syntax != ExplicitVRBigEndian)
    with open(os.path.join(folder, "README.txt"), "w") as f:
        f.write("Not DICOM: a series written by test_dicom.py\n")
    first, last = np.array(ipp[0], float), np.array(ipp[nz - 1], float)
    a = np.eye(4)
    a[:3, 0], a[:3, 1] = row * float(d.PixelSpacing[1]), col * float(d.PixelSpacing[0])
    a[:3, 2], a[:3, 3] = (last - first) / max(nz - 1, 1), first
    return names, LPS_TO_RAS @ a


def stored_voxels(case):
    c = CASES[case]
    return (np.asanyarray(nib.load(c["src"]).dataobj).astype(np.int32) + c["add"]).astype(c["dtype"])


def mesh_cli(xtask, path, out, *extra):
    cmd = [xtask, "mesh", str(path), *extra, "--quiet", "-o", str(out)]
    return subprocess.run(cmd, capture_output=True, text=True)


@pytest.fixture(scope="module", params=list(CASES))
def series(request, tmp_path_factory, xtask):
    """A case's series, meshed by the CLI (mesh and report), and its expected values."""
    case, c = request.param, CASES[request.param]
    tmp = tmp_path_factory.mktemp(case)
    raw = stored_voxels(case)
    names, spec = write_series(tmp / "series", raw, **c)
    ply, rep = tmp / "cli.ply", tmp / "cli.json"
    r = mesh_cli(xtask, tmp / "series", ply, "--iso", str(c["iso"]), "--size", str(c["size"]),
                 "--no-verify", "--report", str(rep))
    assert r.returncode == 0, r.stderr
    values = raw.astype(np.float64) * c["slope"] + c["inter"]
    return dict(case=case, c=c, tmp=tmp, folder=tmp / "series", names=names, raw=raw,
                values=values, spec=spec, ply=ply, report=json.loads(rep.read_text()))


def report_affine(report):
    a = np.eye(4)
    a[:3] = np.array(report["input_stats"]["image"]["affine"], dtype=np.float64)
    return a


def simpleitk(folder):
    """SimpleITK's volume of the series: values indexed (x, y, z) and its RAS affine."""
    reader = sitk.ImageSeriesReader()
    reader.SetFileNames(sitk.ImageSeriesReader.GetGDCMSeriesFileNames(str(folder)))
    img = reader.Execute()
    a = np.eye(4)
    a[:3, :3] = np.array(img.GetDirection()).reshape(3, 3) @ np.diag(img.GetSpacing())
    a[:3, 3] = img.GetOrigin()
    return sitk.GetArrayFromImage(img).transpose(2, 1, 0), LPS_TO_RAS @ a, img.GetSize()


# The crop series written otherwise: the stored values, the scaling and the geometry are the
# same. pydicom 3 writes explicit VR big endian (little_endian=False; the pixel bytes are given
# big endian), RLE Lossless with its own encoder and JPEG 2000 lossless with pylibjpeg-openjpeg
# (compressed pixel data, decoded by dicom-pixeldata since 2026-12-07).
VARIANTS = {
    "explicit-le": dict(),
    "implicit-le": dict(syntax=ImplicitVRLittleEndian),
    "explicit-be": dict(syntax=ExplicitVRBigEndian),
    "rle": dict(syntax=RLELossless),
    "j2k": dict(syntax=JPEG2000Lossless),
    "u8": dict(bits=8),
    "u12": dict(stored=12),
}


@pytest.mark.parametrize("variant", ["explicit-le", "implicit-le", "explicit-be", "rle", "j2k", "u8", "u12"])
def test_the_writer_writes_what_pydicom_reads(tmp_path, variant):
    # The writer itself (no library involved): every file is a DICOM file of the requested
    # transfer syntax whose pixels are its slice; the names are not in slice order.
    raw = stored_voxels("crop-u16")
    kw = VARIANTS[variant]
    raw = raw.astype(np.uint8) if kw.get("bits") == 8 else raw
    names, _ = write_series(tmp_path, raw, **{**CASES["crop-u16"], **kw})
    assert sorted(os.listdir(tmp_path)) == sorted(names + ["README.txt"])
    assert any("." not in n for n in names) and sorted(names) != names
    for k, n in enumerate(names):
        with open(tmp_path / n, "rb") as f:
            assert f.read(132)[128:] == b"DICM"
        d = pydicom.dcmread(tmp_path / n)
        assert d.file_meta.TransferSyntaxUID == kw.get("syntax", ExplicitVRLittleEndian)
        assert (d.BitsAllocated, d.BitsStored) == (kw.get("bits", 16), kw.get("stored") or kw.get("bits", 16))
        assert np.array_equal(d.pixel_array, raw[:, :, k].T)
        assert d.InstanceNumber == k + 1


def test_slices_scaled_apart_are_read_as_float32(tmp_path, xtask):
    # Per-slice RescaleSlope (Philips MR, PET): each slice's values are its stored ones times
    # its own slope plus the intercept, as float32; the mesh is the one of that float32 array.
    c = CASES["crop-u16"]
    raw = stored_voxels("crop-u16")
    slopes = [2.0 if k % 2 else 2.5 for k in range(raw.shape[2])]
    write_series(tmp_path / "s", raw, **{**c, "slopes": slopes})
    r = subprocess.run([xtask, "mesh", str(tmp_path / "s"), "--iso", str(c["iso"]), "--size",
                        str(c["size"]), "--no-verify", "-o", str(tmp_path / "s.ply"), "--report",
                        str(tmp_path / "r.json")], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert "scaled to float32" in r.stderr
    a = report_affine(json.load(open(tmp_path / "r.json")))
    values = (raw.astype(np.float64) * np.array(slopes) + c["inter"]).astype(np.float32)
    m = rdt_mesher.mesh_file(tmp_path / "s", iso=c["iso"], size=c["size"], verify=False)
    ref = rdt_mesher.mesh_image(values, affine=a, iso=c["iso"], size=c["size"], verify=False)
    assert np.array_equal(m.vertices, ref.vertices) and np.array_equal(m.faces, ref.faces)
    # And not the mesh of one slope for all: the slices' scaling matters.
    one = rdt_mesher.mesh_image((raw * 2.0 + c["inter"]).astype(np.float32), affine=a, iso=c["iso"],
                                size=c["size"], verify=False)
    assert len(one.vertices) != len(m.vertices) or not np.array_equal(one.vertices, m.vertices)


def test_geometry_is_simpleitks(series):
    # The report's dims and RAS affine are SimpleITK's (GDCM's sorting and geometry, LPS
    # negated in x and y) within 1e-6 mm, and the spec's affine from the tags as written.
    values, a_sitk, size = simpleitk(series["folder"])
    img = series["report"]["input_stats"]["image"]
    assert img["dims"] == list(size) == list(series["raw"].shape)
    a = report_affine(series["report"])
    assert np.abs(a - a_sitk).max() < 1e-6, (a, a_sitk)
    assert np.abs(a - series["spec"]).max() < 1e-9, (a, series["spec"])
    # Oblique indeed: no axis of the affine is along a world axis.
    assert np.all(np.abs(a[:3, :3]) > 0.02)


def test_voxels_are_simpleitks(series):
    # SimpleITK applies RescaleSlope/Intercept: its values are the stored ones scaled.
    values, _, _ = simpleitk(series["folder"])
    assert np.array_equal(values, series["values"])
    c, a = series["c"], report_affine(series["report"])
    m = rdt_mesher.mesh_file(series["folder"], iso=c["iso"], size=c["size"], verify=False)
    assert len(m.vertices) > 1000
    cli = meshio.read(series["ply"])
    assert np.array_equal(m.vertices, cli.points) and np.array_equal(m.faces, cli.cells_dict["triangle"])
    assert report_affine(m.report).tolist() == a.tolist()
    # The reader keeps the stored integers and the rescale as the volume's scaling (as NIfTI's
    # scl_slope: rounding and the quantum differ from a float array's, hence the mesh), so the
    # reference with the same values, affine and scaling is a NIfTI-2 (float64 affine, slope
    # and intercept) that nibabel writes from SimpleITK's values.
    stored = ((values - c["inter"]) / c["slope"]).astype(c["dtype"])
    assert np.array_equal(stored.astype(np.float64) * c["slope"] + c["inter"], values)
    ni = nib.Nifti2Image(stored, a)
    ni.set_sform(a, 1)
    ni.header.set_slope_inter(c["slope"], c["inter"])
    nib.save(ni, series["tmp"] / "sitk.nii")
    ref = rdt_mesher.mesh_file(series["tmp"] / "sitk.nii", iso=c["iso"], size=c["size"], verify=False)
    assert np.array_equal(m.vertices, ref.vertices) and np.array_equal(m.faces, ref.faces)
    if (c["slope"], c["inter"]) == (1, 0):
        # No scaling: SimpleITK's array itself, meshed with the report's affine.
        ref = rdt_mesher.mesh_image(values, affine=a, iso=c["iso"], size=c["size"], verify=False)
        assert np.array_equal(m.vertices, ref.vertices) and np.array_equal(m.faces, ref.faces)


def dcm2niix_binary():
    exe = os.path.join(os.path.dirname(sys.executable), "dcm2niix")
    exe = exe if os.path.exists(exe) else shutil.which("dcm2niix")
    if exe is None:
        pytest.fail("dcm2niix is missing: pip install dcm2niix (python/requirements-test.txt)")
    return exe


def test_dcm2niix_puts_every_voxel_where_we_do(series):
    # dcm2niix's NIfTI (its own sorting, axis flips and affine): every voxel's world point by
    # the report's affine is, by dcm2niix's inverse affine, a voxel centre (within 1e-3 voxel)
    # holding our value (get_fdata applies dcm2niix's scl_slope/scl_inter if it stored them).
    out = series["tmp"] / "dcm2niix"
    out.mkdir()
    r = subprocess.run([dcm2niix_binary(), "-z", "n", "-f", "out", "-o", str(out), str(series["folder"])],
                       capture_output=True, text=True)
    if r.returncode != 0 or not (out / "out.nii").exists():
        pytest.skip(f"dcm2niix refused the series (exit {r.returncode}): {r.stdout[-500:]} {r.stderr[-500:]}")
    ref = nib.load(out / "out.nii")
    data = ref.get_fdata()
    dims = series["raw"].shape
    assert sorted(data.shape) == sorted(dims), (data.shape, dims)
    ijk = np.indices(dims).reshape(3, -1)
    a = report_affine(series["report"])
    world = a[:3, :3] @ ijk + a[:3, 3:]
    q = np.linalg.solve(ref.affine[:3, :3], world - ref.affine[:3, 3:])
    qi = np.rint(q).astype(np.int64)
    assert np.abs(q - qi).max() < 1e-3
    assert np.all(qi >= 0) and np.all(qi < np.array(data.shape)[:, None])
    assert len(np.unique(qi, axis=1).T) == qi.shape[1]  # one to one
    assert np.array_equal(data[qi[0], qi[1], qi[2]], series["values"].reshape(-1))


@pytest.fixture(scope="module")
def crop_mesh(tmp_path_factory):
    """The crop series, explicit VR little endian, unsigned 16-bit, meshed by the library."""
    c = CASES["crop-u16"]
    folder = tmp_path_factory.mktemp("base")
    write_series(folder, stored_voxels("crop-u16"), **c)
    return rdt_mesher.mesh_file(folder, iso=c["iso"], size=c["size"], verify=False)


@pytest.mark.parametrize("variant", ["implicit-le", "explicit-be", "rle", "j2k", "u8", "u12", "i16"])
def test_transfer_syntaxes_and_bit_depths_give_the_same_mesh(tmp_path, variant, crop_mesh):
    # The same stored values, scaling and geometry, written otherwise (other file names and
    # order): the same mesh, bit for bit, and the same image report.
    c = CASES["crop-u16"]
    raw = stored_voxels("crop-u16")
    if variant == "i16":
        raw, kw = raw.astype(np.int16), {}
    else:
        raw, kw = (raw.astype(np.uint8) if variant == "u8" else raw), VARIANTS[variant]
    write_series(tmp_path, raw, **{**c, **kw, "seed": 1})
    base = crop_mesh
    m = rdt_mesher.mesh_file(tmp_path, iso=c["iso"], size=c["size"], verify=False)
    assert len(base.vertices) > 1000
    assert np.array_equal(m.vertices, base.vertices) and np.array_equal(m.faces, base.faces)
    assert m.report["input_stats"]["image"] == base.report["input_stats"]["image"]


def one_error_line(r, out, *words):
    assert r.returncode != 0
    assert not out.exists(), "an output was written for a refused input"
    err = r.stderr.strip()
    assert err and "\n" not in err, r.stderr
    assert "panicked" not in err and "backtrace" not in err.lower(), err
    for w in words:
        assert w in err, (w, err)
    return err


def test_bad_series_are_refused_with_one_line(tmp_path, xtask, crop_mesh):
    c = CASES["crop-u16"]
    raw = stored_voxels("crop-u16")
    out = tmp_path / "out.ply"
    # A missing slice in the middle: the step there is twice the others.
    names, _ = write_series(tmp_path / "missing", raw, **c)
    os.remove(tmp_path / "missing" / names[20])
    err = one_error_line(mesh_cli(xtask, tmp_path / "missing", out, "--iso", "100"), out, "missing")
    assert str(tmp_path / "missing") in err
    # Two series (two SeriesInstanceUID) in one folder: the crop and a second series of the
    # same geometry.
    write_series(tmp_path / "two", raw, **c)
    write_series(tmp_path / "two", raw[:, :, :8], **{**c, "seed": 2, "number": 2})
    err = one_error_line(mesh_cli(xtask, tmp_path / "two", out, "--iso", "100"), out, "series")
    assert str(tmp_path / "two") in err
    # ... unless one is picked (--series, its SeriesNumber): the crop's mesh.
    m = rdt_mesher.mesh_file(tmp_path / "two", series=1, iso=c["iso"], size=c["size"], verify=False)
    assert np.array_equal(m.vertices, crop_mesh.vertices) and np.array_equal(m.faces, crop_mesh.faces)
    # One slice given as a file: refused, pointing at its folder (the folder's path by itself,
    # not only as the start of the file's).
    names, _ = write_series(tmp_path / "one", raw[:, :, :1], **c)
    for path in (tmp_path / "one" / names[0], tmp_path / "one" / "slice.dcm"):  # found by preamble, by name
        if not path.exists():
            os.rename(tmp_path / "one" / names[0], path)
        err = one_error_line(mesh_cli(xtask, path, out, "--iso", "100"), out, "one slice", str(path))
        assert re.search(re.escape(str(tmp_path / "one")) + r"(?![\w/.-])", err), err
    # The library refuses them as the CLI does, with a ValueError of one line.
    for bad, word in ((tmp_path / "missing", "missing"), (tmp_path / "two", "series"), (path, "one slice")):
        with pytest.raises(ValueError) as e:
            rdt_mesher.mesh_file(bad, iso=100)
        assert word in str(e.value) and "\n" not in str(e.value).strip(), e.value


def test_echoes_are_frames_in_the_scanners_order(tmp_path, xtask):
    # Two echoes of one series in one folder (shared SeriesInstanceUID, EchoNumbers 1 and 2,
    # InstanceNumbers interleaved, shuffled names): without --frame a one-line error listing
    # them; --frame k meshes echo k+1 exactly as a folder holding that echo alone; dcm2niix
    # splits the same echoes (_e1, _e2) with the same values at the same voxels.
    c = CASES["crop-u16"]
    raw = stored_voxels("crop-u16")
    echoes = [raw, (raw.astype(np.float64) * 0.8 + 3).astype(raw.dtype)]
    uid, study = generate_uid(), generate_uid()
    both = tmp_path / "both"
    for e, vol in enumerate(echoes):
        kw = dict(series=uid, study=study, seed=10 + e, extra={"EchoNumbers": e + 1, "EchoTime": 10 * (e + 1)},
                  instance_base=e, instance_stride=2)
        write_series(both, vol, **{**c, **kw})
        write_series(tmp_path / f"alone{e}", vol, **{**c, **kw})
    out = tmp_path / "out.ply"
    err = one_error_line(mesh_cli(xtask, both, out, "--iso", "100"), out, "2 volumes", "--frame 0 to 1",
                         "EchoNumbers 1", "EchoNumbers 2", str(both))
    one_error_line(mesh_cli(xtask, both, out, "--iso", "100", "--frame", "2"), out, "--frame 2", "0 to 1")
    meshes = []
    for e in range(2):
        rep = tmp_path / f"frame{e}.json"
        r = mesh_cli(xtask, both, out, "--iso", str(c["iso"]), "--size", str(c["size"]), "--frame", str(e),
                     "--no-verify", "--report", str(rep))
        assert r.returncode == 0, r.stderr
        assert f"frame {e} of 2 volumes" in r.stdout + r.stderr and f"EchoNumbers {e + 1}" in r.stdout + r.stderr
        m = rdt_mesher.mesh_file(both, frame=e, iso=c["iso"], size=c["size"], verify=False)
        alone = rdt_mesher.mesh_file(tmp_path / f"alone{e}", iso=c["iso"], size=c["size"], verify=False)
        assert len(m.vertices) > 1000
        assert np.array_equal(m.vertices, alone.vertices) and np.array_equal(m.faces, alone.faces)
        cli = meshio.read(out)
        assert np.array_equal(cli.points, m.vertices)
        meshes.append((m, json.loads(rep.read_text())))
    assert len(meshes[0][0].vertices) != len(meshes[1][0].vertices)
    d2n = tmp_path / "dcm2niix"
    d2n.mkdir()
    r = subprocess.run([dcm2niix_binary(), "-z", "n", "-f", "out", "-o", str(d2n), str(both)],
                       capture_output=True, text=True)
    files = sorted(p.name for p in d2n.glob("*.nii"))
    assert r.returncode == 0 and files == ["out_e1.nii", "out_e2.nii"], (files, r.stdout[-800:])
    ijk = np.indices(raw.shape).reshape(3, -1)
    for e, name in enumerate(files):
        ref = nib.load(d2n / name)
        a = report_affine(meshes[e][1])
        q = np.linalg.solve(ref.affine[:3, :3], a[:3, :3] @ ijk + a[:3, 3:] - ref.affine[:3, 3:])
        qi = np.rint(q).astype(np.int64)
        assert np.abs(q - qi).max() < 1e-3
        values = echoes[e].astype(np.float64) * c["slope"] + c["inter"]
        assert np.array_equal(ref.get_fdata()[qi[0], qi[1], qi[2]], values.reshape(-1))


def test_volumes_without_a_distinguishing_tag_follow_instance_numbers(tmp_path, xtask):
    # Three time points told apart by InstanceNumber alone (volume after volume), and the same
    # series with one slice of the last volume removed: the first meshes its second volume with
    # --frame 1 (and says how it chose), the second is refused (positions hold 2 or 3 slices).
    c = CASES["crop-u16"]
    raw = stored_voxels("crop-u16")[:, :, :24]
    nz = raw.shape[2]
    vols = [raw, raw // 2 + 60, raw // 3 + 90]
    uid, study = generate_uid(), generate_uid()
    names = []
    for t, vol in enumerate(vols):
        n, _ = write_series(tmp_path / "three", vol, **{**c, "series": uid, "study": study, "seed": 20 + t,
                                                         "instance_base": t * nz})
        names.append(n)
    write_series(tmp_path / "second", vols[1], **c)
    m = rdt_mesher.mesh_file(tmp_path / "three", frame=1, iso=150, size=c["size"], verify=False)
    ref = rdt_mesher.mesh_file(tmp_path / "second", iso=150, size=c["size"], verify=False)
    assert len(m.vertices) > 100
    assert np.array_equal(m.vertices, ref.vertices) and np.array_equal(m.faces, ref.faces)
    out = tmp_path / "out.ply"
    r = mesh_cli(xtask, tmp_path / "three", out, "--iso", "150", "--frame", "1", "--no-verify")
    assert r.returncode == 0 and "2nd slice at each position by InstanceNumber" in r.stdout + r.stderr, r.stderr
    os.remove(tmp_path / "three" / names[2][5])
    out = tmp_path / "refused.ply"
    one_error_line(mesh_cli(xtask, tmp_path / "three", out, "--iso", "100", "--frame", "1"), out,
                   "holding 2 to 3 slice(s)", str(tmp_path / "three"))


def write_enhanced(path, vols, *, spacing, origin, rot, slope, inter, **_):
    """`vols` (stored values, each (nx, ny, nz)) as one Enhanced MR Image Storage file: frames
    volume after volume, each with its PlanePositionSequence and FrameContentSequence
    (TemporalPositionIndex t + 1), the orientation, spacing and rescale shared."""
    from pydicom.sequence import Sequence
    nx, ny, nz = vols[0].shape
    r = rotation(*rot)
    iop = ds(np.concatenate([r[:, 0], r[:, 1]]))
    normal = np.cross(np.array(iop[:3], float), np.array(iop[3:], float))
    meta = FileMetaDataset()
    meta.MediaStorageSOPClassUID = "1.2.840.10008.5.1.4.1.1.4.1"
    meta.MediaStorageSOPInstanceUID = generate_uid()
    meta.TransferSyntaxUID = ExplicitVRLittleEndian
    d = Dataset()
    d.file_meta = meta
    d.SOPClassUID, d.SOPInstanceUID = meta.MediaStorageSOPClassUID, meta.MediaStorageSOPInstanceUID
    d.StudyInstanceUID, d.SeriesInstanceUID, d.FrameOfReferenceUID = generate_uid(), generate_uid(), generate_uid()
    d.Modality, d.SeriesNumber, d.InstanceNumber = "MR", 5, 1
    d.Rows, d.Columns, d.SamplesPerPixel, d.PhotometricInterpretation = ny, nx, 1, "MONOCHROME2"
    d.BitsAllocated, d.BitsStored, d.HighBit, d.PixelRepresentation = 16, 16, 15, 0
    d.NumberOfFrames = nz * len(vols)
    shared = Dataset()
    o, m, t = Dataset(), Dataset(), Dataset()
    o.ImageOrientationPatient = iop
    m.PixelSpacing, m.SliceThickness = ds([spacing[1], spacing[0]]), DS(spacing[2], auto_format=True)
    t.RescaleSlope, t.RescaleIntercept, t.RescaleType = DS(slope), DS(inter), "US"
    shared.PlaneOrientationSequence = Sequence([o])
    shared.PixelMeasuresSequence = Sequence([m])
    shared.PixelValueTransformationSequence = Sequence([t])
    d.SharedFunctionalGroupsSequence = Sequence([shared])
    frames = []
    for ti in range(len(vols)):
        for k in range(nz):
            f, p, c = Dataset(), Dataset(), Dataset()
            p.ImagePositionPatient = ds(np.asarray(origin) + k * spacing[2] * normal)
            c.TemporalPositionIndex = ti + 1
            c.StackID, c.InStackPositionNumber = "1", k + 1
            f.PlanePositionSequence, f.FrameContentSequence = Sequence([p]), Sequence([c])
            frames.append(f)
    d.PerFrameFunctionalGroupsSequence = Sequence(frames)
    px = np.concatenate([v.transpose(2, 1, 0) for v in vols]).astype("<u2")
    d.PixelData = px.tobytes()
    d.save_as(path, enforce_file_format=True)


def test_an_enhanced_file_of_two_time_points_gives_each_as_its_classic_series(tmp_path, xtask):
    # One enhanced multi-frame file holding two volumes (TemporalPositionIndex 1 and 2, frames
    # volume after volume): --frame k meshes volume k as the classic series of its slices does.
    c = CASES["crop-u16"]
    raw = stored_voxels("crop-u16")[:, :, :20]
    vols = [raw, (raw.astype(np.float64) * 0.8 + 3).astype(raw.dtype)]
    write_enhanced(tmp_path / "dce.dcm", vols, **c)
    out = tmp_path / "out.ply"
    one_error_line(mesh_cli(xtask, tmp_path / "dce.dcm", out, "--iso", "100"), out, "2 volumes",
                   "TemporalPositionIndex 1", "TemporalPositionIndex 2")
    for t, vol in enumerate(vols):
        write_series(tmp_path / f"classic{t}", vol, **c)
        m = rdt_mesher.mesh_file(tmp_path / "dce.dcm", frame=t, iso=150, size=c["size"], verify=False)
        ref = rdt_mesher.mesh_file(tmp_path / f"classic{t}", iso=150, size=c["size"], verify=False)
        assert len(m.vertices) > 500
        assert np.array_equal(m.vertices, ref.vertices) and np.array_equal(m.faces, ref.faces)
        assert report_affine(m.report).tolist() == report_affine(ref.report).tolist()
