//! The labels of a segmentation, read once and meshed one by one (section 6.6.2's voxel
//! oracle on each label's own region, `oracle::image::LabelBox`; `--labels all`).
//!
//! Opening each label from the file again read, decompressed and scanned the whole grid for
//! every label. [`LabelImage`] reads the volume once, finds every label's bounding box in one
//! pass, and gives each label an [`Input`] on the crop of its box: the same input as
//! `Input::open` with that label gives (`ImageSurface::new_shared` crops a label the same
//! way), so `--labels all` and `--label L` write the same mesh for L.

use std::path::Path;
use std::sync::Arc;

use oracle::image::{ImageOptions, ImageSurface, LabelBox, LoadOptions, Volume};

use super::{Input, PipelineError, stem};

/// Labels present in a label image, without the background label 0 (one mesh per label:
/// open each with `InputOptions::image.label`, or with [`LabelImage::input`]).
///
/// ```
/// use rdt_mesher::pipeline::image_labels;
/// let dir = env!("CARGO_MANIFEST_DIR");
/// let p = format!("{dir}/../../fixtures/images/phantom_i16_32.nii.gz");
/// // The phantom holds intensities, not labels: an error that says so.
/// assert!(image_labels(&p, &Default::default()).is_err());
/// ```
pub fn image_labels(spec: &str, load: &LoadOptions) -> Result<Vec<i64>, PipelineError> {
    Ok(LabelImage::open(spec, load)?.labels())
}

/// A label image read once, with the bounding box of each of its labels.
pub struct LabelImage {
    spec: String,
    vol: Arc<Volume>,
    boxes: Vec<LabelBox>,
}

impl LabelImage {
    /// Read `spec` and find its labels (errors: the reader's, or `NotALabelImage`).
    pub fn open(spec: &str, load: &LoadOptions) -> Result<LabelImage, PipelineError> {
        let vol = oracle::image::load_volume(Path::new(spec), load)
            .map_err(|e| PipelineError::opening_image(spec, e))?;
        LabelImage::from_volume(vol, spec)
    }

    /// A volume in memory (a numpy array, for example) as a label image named `name` (errors:
    /// `NotALabelImage`).
    pub fn from_volume(vol: Volume, name: &str) -> Result<LabelImage, PipelineError> {
        let boxes = vol
            .label_boxes()
            .map_err(|source| PipelineError::NotALabelImage {
                spec: name.to_string(),
                source: Box::new(source),
            })?;
        Ok(LabelImage {
            spec: name.to_string(),
            vol: Arc::new(vol),
            boxes,
        })
    }

    /// The labels but the background 0, in increasing order.
    pub fn labels(&self) -> Vec<i64> {
        self.boxes
            .iter()
            .map(|b| b.label)
            .filter(|&l| l != 0)
            .collect()
    }

    /// The input of `opts.label` (which must be set) on its crop, as `Input::open` of the
    /// file with those image options gives it.
    pub fn input(&self, opts: &ImageOptions) -> Result<Input<'static>, PipelineError> {
        self.input_named(opts, stem(Path::new(&self.spec)))
    }

    /// [`LabelImage::input`] with the input named `name`.
    pub fn input_named(
        &self,
        opts: &ImageOptions,
        name: String,
    ) -> Result<Input<'static>, PipelineError> {
        let crop = opts
            .label
            .and_then(|l| self.boxes.iter().find(|b| b.label == l))
            .and_then(|b| self.vol.label_crop(b));
        let vol = crop.map_or_else(|| self.vol.clone(), Arc::new);
        let img = ImageSurface::new_shared(vol, opts)
            .map_err(|e| PipelineError::opening_image(&self.spec, e))?;
        Ok(Input::image(img, name))
    }
}
