//! One 3D volume of a 4D array (ours: file format support; section 6.6.2 meshes the volume):
//! the frames of NRRD and MetaImage files with one non-spatial axis (diffusion gradients,
//! time points, the values of a vector voxel), picked with `--frame` as NIfTI's `dim[4]`.
//!
//! Invariant: the spatial axes keep their order (axis 0 fastest), so frame `k` is the 3D
//! volume the same file would hold with only the elements whose frame index is `k`.

use super::ImageError;
use std::path::Path;

/// The non-spatial axis of a 4D array: where it is, how long, and how the header names it
/// (for the notes and errors, e.g. `kinds: list`).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct FrameAxis {
    /// Its index among the four axes (0: the fastest).
    pub axis: usize,
    /// Its length: the number of frames.
    pub frames: usize,
    /// What the header says about it, for the user.
    pub label: String,
}

impl FrameAxis {
    /// The frame to read: `frame`, checked. A series of more than one frame needs one
    /// (`--frame`); a lone frame is read without it.
    pub fn pick(
        &self,
        path: &Path,
        sizes: &[usize],
        frame: Option<usize>,
    ) -> Result<usize, ImageError> {
        let err = |detail: String| ImageError::Frame {
            path: path.to_path_buf(),
            dims: sizes.iter().map(|&d| d as u64).collect(),
            detail,
        };
        let (n, a, what) = (self.frames, self.axis, &self.label);
        match frame {
            None if n > 1 => Err(err(format!(
                "{n} values per voxel along axis {a} ({what}): a series of {n} 3D volumes; pass \
                 --frame K (0 to {}) to mesh one of them",
                n - 1
            ))),
            Some(k) if k >= n => Err(err(format!(
                "--frame {k}: the file has {n} frame(s) along axis {a} ({what}), numbered 0 to {}",
                n - 1
            ))),
            _ => Ok(frame.unwrap_or(0)),
        }
    }

    /// The note naming the frame read (`None` for a lone frame).
    pub fn note(&self, path: &Path, k: usize) -> Option<String> {
        (self.frames > 1).then(|| {
            format!(
                "{}: frame {k} of {} along axis {} ({}; --frame)",
                path.display(),
                self.frames,
                self.axis,
                self.label
            )
        })
    }
}

/// The frame to read of a file whose frames' axis is `axis` ([`FrameAxis::pick`]), or of a
/// file holding one 3D volume (`None`): frame 0, and `--frame` above 0 an error.
pub(crate) fn pick(
    axis: Option<&FrameAxis>,
    path: &Path,
    sizes: &[usize],
    frame: Option<usize>,
) -> Result<usize, ImageError> {
    match (axis, frame) {
        (Some(fa), _) => fa.pick(path, sizes, frame),
        (None, Some(k)) if k > 0 => Err(ImageError::Frame {
            path: path.to_path_buf(),
            dims: sizes.iter().map(|&d| d as u64).collect(),
            detail: format!("--frame {k}: this file holds one 3D volume (frame 0)"),
        }),
        (None, _) => Ok(0),
    }
}

/// The bytes of frame `k` along `axis` of an array of `sizes` (axis 0 fastest) whose
/// elements are `elem` bytes: the other three axes in their order. `raw` holds exactly the
/// whole array.
pub(crate) fn frame_bytes(
    raw: &[u8],
    sizes: [usize; 4],
    axis: usize,
    k: usize,
    elem: usize,
) -> Vec<u8> {
    debug_assert_eq!(raw.len(), sizes.iter().product::<usize>() * elem);
    debug_assert!(axis < 4 && k < sizes[axis]);
    let mut stride = [elem; 4];
    for i in 1..4 {
        stride[i] = stride[i - 1] * sizes[i - 1];
    }
    let spatial: Vec<usize> = (0..4).filter(|&i| i != axis).collect();
    let (d, s) = (
        spatial.iter().map(|&i| sizes[i]).collect::<Vec<_>>(),
        spatial.iter().map(|&i| stride[i]).collect::<Vec<_>>(),
    );
    let base = k * stride[axis];
    let mut out = Vec::with_capacity(d[0] * d[1] * d[2] * elem);
    // The fastest spatial axis is contiguous unless the frame axis is axis 0.
    let run = if axis == 0 { elem } else { d[0] * elem };
    for c in 0..d[2] {
        for b in 0..d[1] {
            let row = base + c * s[2] + b * s[1];
            if axis == 0 {
                for a in 0..d[0] {
                    let at = row + a * s[0];
                    out.extend_from_slice(&raw[at..at + elem]);
                }
            } else {
                out.extend_from_slice(&raw[row..row + run]);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every layout: frame `k` of an array whose element at (i0, i1, i2, i3) encodes its
    /// indices holds, in order, the elements with index `k` on the frame axis.
    #[test]
    fn a_frame_keeps_the_other_axes_in_order() {
        let sizes = [3usize, 4, 2, 5];
        for elem in [1usize, 2, 8] {
            let mut raw = Vec::new();
            for i3 in 0..sizes[3] {
                for i2 in 0..sizes[2] {
                    for i1 in 0..sizes[1] {
                        for i0 in 0..sizes[0] {
                            let code = (i0 + 10 * i1 + 100 * i2 + 1000 * i3) as u64;
                            raw.extend_from_slice(&code.to_le_bytes()[..elem]);
                        }
                    }
                }
            }
            for axis in 0..4 {
                for k in 0..sizes[axis] {
                    let got = frame_bytes(&raw, sizes, axis, k, elem);
                    let mut want = Vec::new();
                    for i3 in 0..sizes[3] {
                        for i2 in 0..sizes[2] {
                            for i1 in 0..sizes[1] {
                                for i0 in 0..sizes[0] {
                                    if [i0, i1, i2, i3][axis] == k {
                                        let code = (i0 + 10 * i1 + 100 * i2 + 1000 * i3) as u64;
                                        want.extend_from_slice(&code.to_le_bytes()[..elem]);
                                    }
                                }
                            }
                        }
                    }
                    assert_eq!(got, want, "axis {axis} frame {k} elem {elem}");
                }
            }
        }
    }

    #[test]
    fn a_series_needs_a_frame_in_range_and_a_lone_frame_none() {
        let p = Path::new("dwi.nrrd");
        let fa = FrameAxis {
            axis: 0,
            frames: 7,
            label: "kinds: list".into(),
        };
        let e = fa.pick(p, &[7, 4, 4, 4], None).unwrap_err().to_string();
        assert!(e.contains("pass --frame K (0 to 6)"), "{e}");
        let e = fa.pick(p, &[7, 4, 4, 4], Some(7)).unwrap_err().to_string();
        assert!(
            e.contains("--frame 7: the file has 7 frame(s) along axis 0"),
            "{e}"
        );
        assert_eq!(fa.pick(p, &[7, 4, 4, 4], Some(6)).unwrap(), 6);
        let lone = FrameAxis { frames: 1, ..fa };
        assert_eq!(lone.pick(p, &[1, 4, 4, 4], None).unwrap(), 0);
        assert!(lone.note(p, 0).is_none());
    }
}
