//! Byte layouts of the LCTS scratch arenas: an image cast's
//! `[records | entries | corners | starts | hlcts | stack]` and a patch
//! query's `[records | hlcts | paths | stack]`. Counts in, bytes out, checked.

use super::hlcts::{HlctsEntry, MAX_RAYS};
use super::{CornerInfo, HistoryRecord, ImageRequirements};
use crate::arena::Parts;
use crate::kd::{KdStackItem, KD_STACK_LEN};

/// Where the parts of an image-casting scratch arena lie.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ImageScratchLayout {
    /// Element counts.
    pub counts: ImageRequirements,
    /// Byte offsets of the six parts, in the order above.
    pub offsets: [usize; 6],
    /// Bytes the layout covers.
    pub total_bytes: usize,
}

impl ImageScratchLayout {
    /// The layout of `counts`, or `None` past the limit.
    pub fn of(counts: &ImageRequirements) -> Option<ImageScratchLayout> {
        let mut p = Parts::after(0);
        let offsets = [
            p.push::<HistoryRecord>(counts.records)?,
            p.push::<u32>(counts.entries)?,
            p.push::<CornerInfo>(counts.corners)?,
            p.push::<u32>(counts.starts)?,
            p.push::<HlctsEntry>(counts.hlcts)?,
            p.push::<KdStackItem>(counts.stack)?,
        ];
        Some(ImageScratchLayout {
            counts: *counts,
            offsets,
            total_bytes: p.total()?,
        })
    }
}

/// Where the parts of a patch-visibility scratch arena lie, for histories
/// of `capacity` records: each part holds [`MAX_RAYS`] times that.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PatchScratchLayout {
    /// Records per boundary segment's history.
    pub capacity: usize,
    /// Offset of the cut's entries.
    pub hlcts_offset: usize,
    /// Offset of the paths.
    pub paths_offset: usize,
    /// Offset of the traversal stack.
    pub stack_offset: usize,
    /// Bytes the layout covers.
    pub total_bytes: usize,
}

impl PatchScratchLayout {
    /// The layout for histories of `capacity` records (at least 1).
    pub fn of(capacity: usize) -> Option<PatchScratchLayout> {
        let k = MAX_RAYS.checked_mul(capacity.max(1))?;
        let mut p = Parts::after(0);
        p.push::<HistoryRecord>(k)?;
        let hlcts_offset = p.push::<HlctsEntry>(k)?;
        let paths_offset = p.push::<u32>(k)?;
        let stack_offset = p.push::<KdStackItem>(KD_STACK_LEN)?;
        Some(PatchScratchLayout {
            capacity: capacity.max(1),
            hlcts_offset,
            paths_offset,
            stack_offset,
            total_bytes: p.total()?,
        })
    }

    /// The largest capacity whose layout fits in `bytes`, if any.
    pub fn fit(bytes: usize) -> Option<PatchScratchLayout> {
        let per = MAX_RAYS
            * (core::mem::size_of::<HistoryRecord>() + core::mem::size_of::<HlctsEntry>() + 4);
        let mut cap = bytes / per;
        while cap > 0 {
            match PatchScratchLayout::of(cap) {
                Some(l) if l.total_bytes <= bytes => return Some(l),
                _ => cap -= 1,
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn patch_fit_is_the_largest_that_fits() {
        let l = PatchScratchLayout::of(16).unwrap();
        assert_eq!(PatchScratchLayout::fit(l.total_bytes), Some(l));
        assert_eq!(
            PatchScratchLayout::fit(l.total_bytes - 1).unwrap().capacity,
            15
        );
        assert_eq!(PatchScratchLayout::fit(10), None);
        assert!(PatchScratchLayout::of(usize::MAX / 8).is_none());
    }

    #[test]
    fn image_layout_is_checked() {
        let r = ImageRequirements {
            records: usize::MAX / 4,
            ..Default::default()
        };
        assert!(ImageScratchLayout::of(&r).is_none());
    }
}
