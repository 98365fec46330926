//! The keys that order the volumes of one DICOM series at a slice position (ours: for the
//! voxel grid of section 6.6.2's images; DICOM PS3.3 C.7.6.1 General Image, C.7.6.16.2.2
//! Frame Content, C.8.13.5.4 MR Echo), read from one image or frame.

use dicom_dictionary_std::tags;
use dicom_object::InMemDicomObject;
use std::cmp::Ordering;

/// What tells the volumes of a series apart, read from one plane (`None`: absent or not a
/// number). Only the order of the planes at one position depends on it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct VolumeOrder {
    /// `EchoNumbers` (0018,0086); in an enhanced object the frame's `EffectiveEchoTime`
    /// (0018,9082).
    pub echo: Option<f64>,
    /// `TemporalPositionIdentifier` (0020,0100); in an enhanced object the frame's
    /// `TemporalPositionIndex` (0020,9128).
    pub time: Option<f64>,
    /// `AcquisitionNumber` (0020,0012).
    pub acquisition: Option<f64>,
    /// `InstanceNumber` (0020,0013); in a multi-frame object the frame's number.
    pub instance: Option<f64>,
    /// Whether `echo` and `time` come from an enhanced object's functional groups.
    pub enhanced: bool,
}

impl VolumeOrder {
    /// The keys of frame `f` of `obj`, `per_frame` its per-frame functional group (enhanced
    /// objects).
    pub fn of(obj: &InMemDicomObject, per_frame: Option<&InMemDicomObject>, f: usize) -> Self {
        let num = |o: &InMemDicomObject, tag| {
            let e = o.element_opt(tag).ok().flatten()?;
            e.to_multi_float64()
                .ok()?
                .first()
                .copied()
                .filter(|v: &f64| v.is_finite())
        };
        let group = |seq, tag| {
            let item = per_frame?
                .element_opt(seq)
                .ok()
                .flatten()?
                .items()?
                .first()?;
            num(item, tag)
        };
        let enhanced = per_frame.is_some();
        let (echo, time) = if enhanced {
            (
                group(tags::MR_ECHO_SEQUENCE, tags::EFFECTIVE_ECHO_TIME),
                group(tags::FRAME_CONTENT_SEQUENCE, tags::TEMPORAL_POSITION_INDEX),
            )
        } else {
            (
                num(obj, tags::ECHO_NUMBERS),
                num(obj, tags::TEMPORAL_POSITION_IDENTIFIER),
            )
        };
        let instance = match per_frame {
            Some(_) => Some(f as f64),
            None => num(obj, tags::INSTANCE_NUMBER),
        };
        VolumeOrder {
            echo,
            time,
            acquisition: num(obj, tags::ACQUISITION_NUMBER),
            instance,
            enhanced,
        }
    }

    /// Echo, then time point, then acquisition, then instance; an absent key first.
    pub fn cmp(&self, other: &Self) -> Ordering {
        let key = |o: &Self| [o.echo, o.time, o.acquisition, o.instance];
        let (a, b) = (key(self), key(other));
        a.iter()
            .zip(&b)
            .map(|(x, y)| match (x, y) {
                (Some(x), Some(y)) => x.total_cmp(y),
                (x, y) => x.is_some().cmp(&y.is_some()),
            })
            .find(|o| o.is_ne())
            .unwrap_or(Ordering::Equal)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn order(echo: Option<f64>, instance: f64) -> VolumeOrder {
        VolumeOrder {
            echo,
            instance: Some(instance),
            ..Default::default()
        }
    }

    #[test]
    fn the_echo_orders_before_the_instance_and_absent_keys_first() {
        let a = order(Some(2.0), 1.0);
        let b = order(Some(1.0), 7.0);
        assert_eq!(a.cmp(&b), Ordering::Greater);
        assert_eq!(order(None, 9.0).cmp(&b), Ordering::Less);
        assert_eq!(order(None, 3.0).cmp(&order(None, 4.0)), Ordering::Less);
        assert_eq!(b.cmp(&b), Ordering::Equal);
    }
}
