//! Voxels borrowed from their owner (ours: the image backend's data of section 6.6.2 without a
//! copy): a front end that holds an array in its own memory, such as a numpy array held by the
//! Python bindings, lends it to a [`Volume`](super::Volume) as [`Voxels::Shared`](super::Voxels).
//!
//! The owner is kept alive by an `Arc` for as long as any volume uses it, and it hands out its
//! voxels as a typed slice ([`VoxelView`]), x fastest (index `x + nx * (y + ny * z)`), exactly
//! as the owned variants store them: a volume over shared voxels meshes to the same mesh as the
//! same voxels owned.
//!
//! ```
//! use oracle::image::{SharedVoxels, VoxelSource, VoxelView, Volume, Voxels};
//! use glam::DAffine3;
//! struct Mine(Vec<u8>);
//! impl VoxelSource for Mine {
//!     fn view(&self) -> VoxelView<'_> { VoxelView::U8(&self.0) }
//! }
//! let v: Vec<u8> = (0..64).map(|i| (i % 4) as u8).collect();
//! let shared = Voxels::Shared(SharedVoxels::new(std::sync::Arc::new(Mine(v.clone()))));
//! let a = Volume::new([4, 4, 4], shared, DAffine3::IDENTITY).unwrap();
//! let b = Volume::new([4, 4, 4], Voxels::U8(v), DAffine3::IDENTITY).unwrap();
//! assert_eq!(a.get(3, 1, 2), b.get(3, 1, 2));
//! assert_eq!(a.labels().unwrap(), b.labels().unwrap());
//! ```

use super::Dtype;
use std::sync::Arc;

/// A typed, borrowed view of voxels, x fastest.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum VoxelView<'a> {
    /// Unsigned bytes (also booleans as 0/1).
    U8(&'a [u8]),
    /// Signed bytes.
    I8(&'a [i8]),
    /// Unsigned 16-bit.
    U16(&'a [u16]),
    /// Signed 16-bit.
    I16(&'a [i16]),
    /// Unsigned 32-bit.
    U32(&'a [u32]),
    /// Signed 32-bit.
    I32(&'a [i32]),
    /// Single precision.
    F32(&'a [f32]),
    /// Double precision.
    F64(&'a [f64]),
}

impl VoxelView<'_> {
    /// The element type.
    pub fn dtype(&self) -> Dtype {
        match self {
            VoxelView::U8(_) => Dtype::U8,
            VoxelView::I8(_) => Dtype::I8,
            VoxelView::U16(_) => Dtype::U16,
            VoxelView::I16(_) => Dtype::I16,
            VoxelView::U32(_) => Dtype::U32,
            VoxelView::I32(_) => Dtype::I32,
            VoxelView::F32(_) => Dtype::F32,
            VoxelView::F64(_) => Dtype::F64,
        }
    }
}

/// The owner of voxels lent to a volume. `view` must return the same slice every time (the
/// owner's memory must not change while a volume uses it).
pub trait VoxelSource: Send + Sync {
    /// The voxels, x fastest.
    fn view(&self) -> VoxelView<'_>;
}

/// Voxels held by a [`VoxelSource`] (cloning shares them).
#[derive(Clone)]
pub struct SharedVoxels(Arc<dyn VoxelSource>);

impl SharedVoxels {
    /// Share the voxels of `owner`.
    pub fn new(owner: Arc<dyn VoxelSource>) -> Self {
        SharedVoxels(owner)
    }

    /// The voxels.
    pub fn view(&self) -> VoxelView<'_> {
        self.0.view()
    }
}

impl PartialEq for SharedVoxels {
    fn eq(&self, other: &Self) -> bool {
        self.view() == other.view()
    }
}

impl std::fmt::Debug for SharedVoxels {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let v = self.view();
        let len = super::with_view!(v, d => d.len());
        f.debug_struct("SharedVoxels")
            .field("dtype", &v.dtype())
            .field("len", &len)
            .finish()
    }
}

/// `with_view!(view, d => expr)` evaluates `expr` with `d: &[T]` for the view's `T`.
macro_rules! with_view {
    ($v:expr, $d:ident => $body:expr) => {
        match $v {
            $crate::image::VoxelView::U8($d) => $body,
            $crate::image::VoxelView::I8($d) => $body,
            $crate::image::VoxelView::U16($d) => $body,
            $crate::image::VoxelView::I16($d) => $body,
            $crate::image::VoxelView::U32($d) => $body,
            $crate::image::VoxelView::I32($d) => $body,
            $crate::image::VoxelView::F32($d) => $body,
            $crate::image::VoxelView::F64($d) => $body,
        }
    };
}
pub(crate) use with_view;
