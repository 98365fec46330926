//! Several volumes at the same slice positions in one DICOM series (echoes, time points,
//! diffusion directions), and the one `--frame` picks (ours: choosing the voxel grid of section
//! 6.6.2's image oracle; DICOM PS3.3 C.7.3.1 General Series, C.7.6.16.2.2 Frame Content).
//!
//! Rule: the planes' positions along the slice normal are grouped (equal within a thousandth of
//! a pixel). When every position holds one plane the series is one volume. When every
//! position holds the same number K > 1 of planes, the planes at each position are ranked by
//! their [`VolumeOrder`] (echo, then time point, then acquisition number, then instance or
//! frame number, then file name) and volume k (`--frame k`, from 0) is the k-th plane of every
//! position. The volumes are numbered as the scanner ordered them within one slice position,
//! which is the order dcm2niix writes them in a 4D file (its `_e1`, `_e2` echo files split by
//! the first key).
//!
//! Invariant kept: the planes returned have pairwise distinct positions (more than the grouping
//! tolerance apart), so the stack's slice step is positive; positions holding different
//! numbers of planes (a volume missing slices, a repeated slice) are refused, never guessed.

use super::super::ImageError;
use super::object::Plane;
use super::order::VolumeOrder;
use std::cmp::Ordering;
use std::path::Path;

/// One key of a [`VolumeOrder`].
type Key = fn(&VolumeOrder) -> Option<f64>;

/// The keys of [`VolumeOrder`] that can name a volume, with their names for messages (classic
/// images, then enhanced objects).
const NAMED: [(&str, &str, Key); 3] = [
    ("EchoNumbers", "EffectiveEchoTime", |o| o.echo),
    ("TemporalPositionIdentifier", "TemporalPositionIndex", |o| {
        o.time
    }),
    ("AcquisitionNumber", "AcquisitionNumber", |o| o.acquisition),
];

/// The planes of volume `frame` (`None`: the only one) of `planes` (one series, one grid),
/// and a note naming it when the series holds several; errors name the counts and the fix.
pub(crate) fn select(
    source: &Path,
    planes: Vec<Plane>,
    frame: Option<usize>,
) -> Result<(Vec<Plane>, Option<String>), ImageError> {
    let err = |detail: String| ImageError::Dicom {
        path: source.to_path_buf(),
        detail,
    };
    let p0 = &planes[0];
    let normal = p0.row_dir.cross(p0.col_dir);
    let tiny = 1e-3 * p0.spacing[0].min(p0.spacing[1]);
    let depth: Vec<f64> = planes.iter().map(|p| normal.dot(p.position)).collect();
    let mut by_depth: Vec<usize> = (0..planes.len()).collect();
    by_depth.sort_by(|&a, &b| depth[a].total_cmp(&depth[b]));
    // Positions: runs of planes whose consecutive depths are at most `tiny` apart.
    let mut positions: Vec<Vec<usize>> = Vec::new();
    for &i in &by_depth {
        match positions.last_mut() {
            Some(run) if depth[i] - depth[run[run.len() - 1]] <= tiny => run.push(i),
            _ => positions.push(vec![i]),
        }
    }
    for run in &positions {
        duplicates(source, &planes, run)?;
    }
    let (fewest, most) = positions.iter().fold((usize::MAX, 0), |(lo, hi), run| {
        (lo.min(run.len()), hi.max(run.len()))
    });
    let (n, count) = (planes.len(), positions.len());
    if fewest != most {
        let full = positions.iter().filter(|r| r.len() == most).count();
        return Err(err(format!(
            "{n} slices at {count} distinct positions, holding {fewest} to {most} slice(s) each \
             ({full} position(s) hold {most}): several volumes with slices missing, or a \
             repeated slice; re-export the complete series, or put the files of each volume in \
             a folder of its own (`dcm2niix` sorts them)"
        )));
    }
    let volumes = most;
    for run in &mut positions {
        run.sort_by(|&a, &b| rank(&planes[a], &planes[b]));
        tied(source, &planes, run)?;
    }
    let name_of = |k: usize| describe(&planes, &positions, k);
    let k = match frame {
        None if volumes == 1 => return Ok((planes, None)),
        None => {
            let list = (0..volumes.min(4))
                .map(|k| format!("--frame {k}: {}", name_of(k)))
                .collect::<Vec<_>>()
                .join("; ");
            return Err(err(format!(
                "{volumes} volumes at the same {count} slice position(s) ({n} slices: echoes, \
                 time points or diffusion directions); pick one with --frame 0 to {} ({list}{})",
                volumes - 1,
                if volumes > 4 { "; ..." } else { "" }
            )));
        }
        Some(k) if k >= volumes => {
            return Err(err(format!(
                "--frame {k}: the series holds {volumes} volume(s) at its {count} slice \
                 positions, numbered 0 to {}",
                volumes - 1
            )));
        }
        Some(k) => k,
    };
    if volumes == 1 {
        return Ok((planes, None));
    }
    let note = format!(
        "DICOM: frame {k} of {volumes} volumes at the same {count} slice position(s): {}",
        name_of(k)
    );
    let mut picked = vec![false; n];
    for run in &positions {
        picked[run[k]] = true;
    }
    let mut flags = picked.into_iter();
    let planes = planes
        .into_iter()
        .filter(|_| flags.next().unwrap_or(false))
        .collect();
    Ok((planes, Some(note)))
}

/// Errors when one image (`SOPInstanceUID` and frame) is twice at one position (`run`): a
/// copied file, not a second volume.
fn duplicates(source: &Path, planes: &[Plane], run: &[usize]) -> Result<(), ImageError> {
    let mut seen: Vec<(&str, usize, usize)> = run
        .iter()
        .map(|&i| (planes[i].instance_uid.as_str(), planes[i].frame, i))
        .filter(|(uid, _, _)| !uid.is_empty())
        .collect();
    seen.sort_unstable();
    match seen
        .windows(2)
        .find(|w| (w[0].0, w[0].1) == (w[1].0, w[1].1))
    {
        None => Ok(()),
        Some(w) => Err(ImageError::Dicom {
            path: source.to_path_buf(),
            detail: format!(
                "{} and {} are the same image (SOPInstanceUID {}): a copied file; remove the \
                 copy",
                planes[w[0].2].file.display(),
                planes[w[1].2].file.display(),
                w[0].0
            ),
        }),
    }
}

/// Errors when two planes of `run` (one position, ranked) have the same [`VolumeOrder`]:
/// only their file names would order them, so a volume could take slices of several.
fn tied(source: &Path, planes: &[Plane], run: &[usize]) -> Result<(), ImageError> {
    match run
        .windows(2)
        .find(|w| planes[w[0]].order.cmp(&planes[w[1]].order).is_eq())
    {
        None => Ok(()),
        Some(w) => Err(ImageError::Dicom {
            path: source.to_path_buf(),
            detail: format!(
                "{} and {} lie at the same slice position with the same EchoNumbers, \
                 TemporalPositionIdentifier, AcquisitionNumber and InstanceNumber: nothing \
                 tells their volumes apart; put the files of each volume in a folder of its own \
                 (`dcm2niix` sorts them)",
                planes[w[0]].name(),
                planes[w[1]].name()
            ),
        }),
    }
}

/// The order of two planes at one position: their [`VolumeOrder`], then file and frame.
fn rank(a: &Plane, b: &Plane) -> Ordering {
    a.order
        .cmp(&b.order)
        .then_with(|| a.file.cmp(&b.file))
        .then(a.frame.cmp(&b.frame))
}

/// Volume `k` (`positions`: each run ranked) named by the keys that hold one value over its planes and differ between the
/// volumes, e.g. "EchoNumbers 2"; else by its rank.
fn describe(planes: &[Plane], positions: &[Vec<usize>], k: usize) -> String {
    let members: Vec<usize> = positions.iter().map(|run| run[k]).collect();
    let names: Vec<String> = NAMED
        .iter()
        .filter_map(|(classic, enhanced, get)| {
            let order = &planes[members[0]].order;
            let name = if order.enhanced { enhanced } else { classic };
            let v = get(order)?;
            let uniform = members.iter().all(|&i| get(&planes[i].order) == Some(v));
            let varies = positions[0]
                .iter()
                .any(|&i| get(&planes[i].order) != Some(v));
            (uniform && varies).then(|| format!("{name} {v}"))
        })
        .collect();
    if names.is_empty() {
        let (by, keys) = if planes[members[0]].order.enhanced {
            ("frame number", "EffectiveEchoTime, TemporalPositionIndex")
        } else {
            ("InstanceNumber", "EchoNumbers, TemporalPositionIdentifier")
        };
        format!(
            "the {} slice at each position by {by} (no {keys} or AcquisitionNumber tells the \
             volumes apart)",
            ordinal(k + 1)
        )
    } else {
        names.join(", ")
    }
}

fn ordinal(k: usize) -> String {
    let suffix = match (k % 10, k % 100) {
        (_, 11..=13) => "th",
        (1, _) => "st",
        (2, _) => "nd",
        (3, _) => "rd",
        _ => "th",
    };
    format!("{k}{suffix}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ordinals_read_as_english() {
        let got: Vec<String> = [1, 2, 3, 4, 11, 12, 13, 21, 22, 101].map(ordinal).into();
        assert_eq!(
            got,
            [
                "1st", "2nd", "3rd", "4th", "11th", "12th", "13th", "21st", "22nd", "101st"
            ]
        );
    }
}
