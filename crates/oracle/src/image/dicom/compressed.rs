//! Compressed (encapsulated) DICOM pixel data, decoded by `dicom-pixeldata` (ours: the pixel
//! values of section 6.6.2's images; DICOM PS3.5 A.4, the encapsulated transfer syntaxes).
//!
//! Read: RLE Lossless, JPEG baseline, extended and lossless, JPEG 2000 (lossless or not).
//! Refused with the fix: JPEG-LS (its decoder is CharLS, a C library), HTJ2K and the rest.
//! Invariant kept: the bytes returned are exactly `rows * cols * frames` samples of
//! `BitsAllocated` bits, little-endian, as the native syntaxes give them; masking to
//! `BitsStored` and the sign are applied by the caller as for native data. A lossy syntax
//! gives approximate values: the reader's note says so.

use super::super::ImageError;
use dicom_object::{FileDicomObject, InMemDicomObject};
use dicom_pixeldata::PixelDecoder;
use std::path::Path;

/// Whether the transfer syntax is one this module decodes, and whether it is lossy.
pub(super) fn decodable(uid: &str) -> Option<bool> {
    Some(match uid {
        "1.2.840.10008.1.2.5" | "1.2.840.10008.1.2.4.57" | "1.2.840.10008.1.2.4.70" => false,
        "1.2.840.10008.1.2.4.90" => false,
        "1.2.840.10008.1.2.4.50" | "1.2.840.10008.1.2.4.51" | "1.2.840.10008.1.2.4.91" => true,
        _ => return None,
    })
}

/// The decoded pixel bytes of every frame (see the module's invariant).
pub(super) fn decode(
    path: &Path,
    ts: &str,
    obj: &FileDicomObject<InMemDicomObject>,
    need: usize,
) -> Result<Vec<u8>, ImageError> {
    let err = |detail: String| ImageError::Dicom {
        path: path.to_path_buf(),
        detail,
    };
    // The codecs are third-party code run on untrusted bytes, and dicom-rs 0.10's RLE and
    // JPEG 2000 adapters index out of bounds on damaged data (measured: 66 of 600 byte
    // mutants): such a panic is this file's error, reported in one line, not the program's end.
    let decoded = quietly(|| obj.decode_pixel_data().map(|d| d.data().to_vec()));
    let bytes = match decoded {
        Ok(Ok(bytes)) => bytes,
        Ok(Err(e)) => {
            return Err(err(format!(
                "the compressed pixel data (transfer syntax {ts}) cannot be decoded ({e}); the \
                 file is damaged: re-export it, or decompress it with `gdcmconv --raw IN OUT`"
            )));
        }
        Err(_) => {
            return Err(err(format!(
                "the compressed pixel data (transfer syntax {ts}) made the decoder fail; the \
                 file is damaged: re-export it, or decompress it with `gdcmconv --raw IN OUT`"
            )));
        }
    };
    if bytes.len() != need {
        return Err(err(format!(
            "the compressed pixel data (transfer syntax {ts}) decodes to {} bytes, but Rows x \
             Columns x NumberOfFrames needs {need}: the header does not match the data",
            bytes.len()
        )));
    }
    Ok(bytes)
}

thread_local! {
    /// Whether a panic on this thread is caught by [`quietly`] (its message not printed).
    static QUIET: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Run `f`, a panic in it caught and its message kept off stderr (the error is reported by the
/// caller). The hook installed once wraps the previous one: panics elsewhere, and on other
/// threads, are printed as before.
fn quietly<T>(f: impl FnOnce() -> T) -> std::thread::Result<T> {
    static HOOK: std::sync::Once = std::sync::Once::new();
    HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !QUIET.with(|q| q.get()) {
                previous(info);
            }
        }));
    });
    QUIET.with(|q| q.set(true));
    let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(f));
    QUIET.with(|q| q.set(false));
    r
}
