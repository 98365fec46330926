//! DICOM volumes (ours: an input of section 6.6.2's image oracle): a folder holding one
//! series of single-frame images (CT, MR, PET), or one multi-frame file (enhanced CT/MR with
//! per-frame functional groups, RT Dose).
//!
//! Read: the native transfer syntaxes (implicit and explicit VR little endian, explicit VR
//! big endian) and deflate, RLE, JPEG lossless, baseline and extended, and JPEG 2000
//! (`compressed`); 8, 16 or 32-bit integers (masked to `BitsStored`, signed when
//! `PixelRepresentation` is 1) and float pixel data; `RescaleSlope`/`RescaleIntercept` (per
//! frame in enhanced objects; `DoseGridScaling` in RT Dose); one volume of several at the same
//! slice positions with `--frame` (`volumes`). Refused with the fix: JPEG-LS and HTJ2K pixel
//! data, colour images, several series in one folder without `--series`, several volumes at
//! the same positions without `--frame`, missing or uneven slices, a single slice. The world
//! frame is RAS+ (the patient's LPS with x and y negated), as for NIfTI.

mod compressed;
mod lengths;
mod object;
mod order;
mod series;
mod volumes;

use super::ImageError;
use super::Volume;
use std::path::{Path, PathBuf};

/// Whether `path` is a file with the DICOM preamble (`DICM` at byte 128).
///
/// ```
/// assert!(!oracle::image::is_dicom_file("Cargo.toml".as_ref()));
/// ```
pub fn is_dicom_file(path: &Path) -> bool {
    path.is_file() && object::has_preamble(path)
}

/// Whether the folder holds at least one DICOM file (its files, not its subfolders).
pub fn is_dicom_folder(dir: &Path) -> bool {
    files_of(dir).is_ok_and(|f| f.iter().any(|p| object::has_preamble(p)))
}

/// Read a DICOM series (a folder of its files, in any order, other files ignored) or a
/// multi-frame DICOM file as one volume. `wanted` picks one series of a folder that holds
/// several, by its `SeriesNumber` or `SeriesInstanceUID` (`--series`); without it such a
/// folder is refused, the error listing them. Errors name the file, the field and the fix.
///
/// ```no_run
/// let vol = oracle::image::read_dicom("ct_series/".as_ref(), None)?;
/// println!("{:?} voxels", vol.dims());
/// # Ok::<(), oracle::image::ImageError>(())
/// ```
pub fn read_dicom(path: &Path, wanted: Option<&str>) -> Result<Volume, ImageError> {
    read_dicom_frame(path, wanted, None)
}

/// [`read_dicom`] for a series holding several volumes at the same slice positions (echoes,
/// time points, diffusion directions): `frame` picks volume k (from 0, `--frame`), the k-th
/// slice at every position in the scanner's order (`EchoNumbers`, then
/// `TemporalPositionIdentifier`, `AcquisitionNumber`, `InstanceNumber`); without it such a
/// series is refused, the error listing the volumes.
///
/// ```no_run
/// let echo2 = oracle::image::read_dicom_frame("multi_echo/".as_ref(), None, Some(1))?;
/// # Ok::<(), oracle::image::ImageError>(())
/// ```
pub fn read_dicom_frame(
    path: &Path,
    wanted: Option<&str>,
    frame: Option<usize>,
) -> Result<Volume, ImageError> {
    if path.is_dir() {
        let files = files_of(path)?;
        let mut planes = Vec::new();
        let mut skipped = 0;
        for f in &files {
            if !object::has_preamble(f) {
                skipped += 1;
                continue;
            }
            match object::read_planes(f)? {
                Some(p) => planes.extend(p),
                None => skipped += 1,
            }
        }
        if planes.is_empty() {
            return Err(ImageError::Dicom {
                path: path.to_path_buf(),
                detail: "no DICOM image in the folder (files with the 'DICM' preamble and pixel \
                         data); pass the folder of one series"
                    .into(),
            });
        }
        let planes = series::pick(path, planes, wanted)?;
        series::stack(path, planes, skipped, frame)
    } else {
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().to_ascii_uppercase())
            .unwrap_or_default();
        match object::read_planes(path)? {
            Some(planes) => series::stack(path, series::pick(path, planes, wanted)?, 0, frame),
            None if name == "DICOMDIR" => Err(ImageError::Dicom {
                path: path.to_path_buf(),
                detail: "a DICOMDIR index, not an image; pass the folder that holds the files \
                         of one series"
                    .into(),
            }),
            None => Err(ImageError::Dicom {
                path: path.to_path_buf(),
                detail: "a DICOM object without pixel data (a report, a structure set or a \
                         presentation state); pass the folder of an image series"
                    .into(),
            }),
        }
    }
}

/// The folders under `dir` (at most 5 levels down) that hold DICOM files, each with its
/// count of them, by name: where an export (`DICOM/PA0/ST0/SE0/...`) keeps its series.
pub fn dicom_subfolders(dir: &Path) -> Vec<(PathBuf, usize)> {
    let mut found = Vec::new();
    let mut todo = vec![(dir.to_path_buf(), 0)];
    let mut seen = 0usize;
    while let Some((d, depth)) = todo.pop() {
        let Ok(entries) = std::fs::read_dir(&d) else {
            continue;
        };
        let mut count = 0;
        for e in entries.filter_map(|e| e.ok()) {
            seen += 1;
            if seen > 100_000 {
                break;
            }
            let p = e.path();
            if p.is_dir() && depth < 5 {
                todo.push((p, depth + 1));
            } else if depth > 0 && p.is_file() && object::has_preamble(&p) {
                count += 1;
            }
        }
        if count > 0 {
            found.push((d, count));
        }
    }
    found.sort();
    found
}

/// The regular files of `dir`, sorted by name (the order of equal positions in errors).
fn files_of(dir: &Path) -> Result<Vec<PathBuf>, ImageError> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|source| ImageError::Io {
            path: dir.to_path_buf(),
            source,
        })?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file())
        .collect();
    files.sort();
    Ok(files)
}
