//! The node every hierarchy shares: a box and a run of children or of
//! primitive references. Children of one node sit side by side
//! (`nodes[first..first + count]`), so a binary node's are `first` and
//! `first + 1` and an R-tree node's fill part of its block of `max_children`.

use crate::geom::Aabb;
use crate::Vec3;

/// Set in [`BvhNode::count`] on leaves.
pub(crate) const LEAF_BIT: u32 = 1 << 31;

/// One hierarchy object (32 bytes).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct BvhNode {
    /// Lower corner of the node's box.
    pub min: [f32; 3],
    /// Upper corner of the node's box.
    pub max: [f32; 3],
    /// First child (interior) or first reference (leaf).
    pub first: u32,
    /// Children or references, with bit 31 set on leaves.
    pub count: u32,
}

impl Default for BvhNode {
    fn default() -> BvhNode {
        BvhNode::leaf(&Aabb::EMPTY, 0, 0)
    }
}

impl BvhNode {
    /// A leaf over `refs[first..first + count]`.
    pub fn leaf(b: &Aabb, first: u32, count: u32) -> BvhNode {
        BvhNode {
            min: b.min.into(),
            max: b.max.into(),
            first,
            count: count | LEAF_BIT,
        }
    }

    /// An interior node over `nodes[first..first + count]`.
    pub fn interior(b: &Aabb, first: u32, count: u32) -> BvhNode {
        BvhNode {
            min: b.min.into(),
            max: b.max.into(),
            first,
            count,
        }
    }

    /// True on leaves.
    #[inline]
    pub fn is_leaf(&self) -> bool {
        self.count & LEAF_BIT != 0
    }

    /// Children (interior) or references (leaf).
    #[inline]
    pub fn len(&self) -> u32 {
        self.count & !LEAF_BIT
    }

    /// True when the node holds nothing.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The node's box.
    #[inline]
    pub fn bounds(&self) -> Aabb {
        Aabb {
            min: Vec3::from(self.min),
            max: Vec3::from(self.max),
        }
    }

    pub(crate) fn set_bounds(&mut self, b: &Aabb) {
        self.min = b.min.into();
        self.max = b.max.into();
    }

    pub(crate) fn set_len(&mut self, n: u32) {
        self.count = (self.count & LEAF_BIT) | n;
    }
}
