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

#[cfg(test)]
mod tests {
    use super::*;

    /// The leaf bit and the count share one word without touching each
    /// other; the box and the first index are kept as given.
    #[test]
    fn node_fields_round_trip() {
        let b = Aabb {
            min: Vec3::new(-1.0, 2.0, -0.0),
            max: Vec3::new(3.0, 4.5, 1e-30),
        };
        let l = BvhNode::leaf(&b, 17, 5);
        assert!(l.is_leaf() && l.len() == 5 && l.first == 17 && l.bounds() == b);
        let mut n = BvhNode::interior(&b, 3, 32);
        assert!(!n.is_leaf() && n.len() == 32);
        n.set_len(2);
        assert!(!n.is_leaf() && n.len() == 2);
        let mut m = l;
        m.set_len(0);
        assert!(m.is_leaf() && m.is_empty());
        assert!(BvhNode::default().is_leaf() && BvhNode::default().bounds().is_empty());
        assert_eq!(core::mem::size_of::<BvhNode>(), 32);
    }
}
