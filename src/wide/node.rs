//! The node of a wide hierarchy: four child boxes stored axis by axis, so
//! one ray's slab test runs over the four children in the same few vector
//! instructions, and what each child is.

use crate::geom::Aabb;

/// Children a node holds.
pub const WIDTH: usize = 4;

/// Set in [`WideNode::child`] on a leaf entry: the rest is its first
/// reference.
pub const LEAF_BIT: u32 = 1 << 31;

/// [`WideNode::child`] of a slot that holds nothing.
pub const EMPTY_SLOT: u32 = u32::MAX;

/// One node: up to [`WIDTH`] entries, each an interior child or a leaf (a
/// run of references), with its box (128 bytes, two cache lines).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(16))]
pub struct WideNode {
    /// Lower corners of the entries' boxes: `min[axis][slot]`.
    pub min: [[f32; WIDTH]; 3],
    /// Upper corners of the entries' boxes: `max[axis][slot]`.
    pub max: [[f32; WIDTH]; 3],
    /// Per slot: an interior child's node index; a leaf's first reference
    /// with [`LEAF_BIT`] set; [`EMPTY_SLOT`] when unused. Used slots come
    /// first.
    pub child: [u32; WIDTH],
    /// Per slot: a leaf's number of references (0 otherwise).
    pub count: [u32; WIDTH],
}

impl Default for WideNode {
    /// A node with every slot empty (empty boxes).
    fn default() -> WideNode {
        WideNode {
            min: [[f32::INFINITY; WIDTH]; 3],
            max: [[f32::NEG_INFINITY; WIDTH]; 3],
            child: [EMPTY_SLOT; WIDTH],
            count: [0; WIDTH],
        }
    }
}

impl WideNode {
    /// Slot `i`'s box.
    #[inline]
    pub fn slot_bounds(&self, i: usize) -> Aabb {
        Aabb {
            min: crate::Vec3::new(self.min[0][i], self.min[1][i], self.min[2][i]),
            max: crate::Vec3::new(self.max[0][i], self.max[1][i], self.max[2][i]),
        }
    }

    /// Sets slot `i`'s box.
    pub(crate) fn set_slot_bounds(&mut self, i: usize, b: &Aabb) {
        for a in 0..3 {
            self.min[a][i] = b.min[a];
            self.max[a][i] = b.max[a];
        }
    }

    /// Slots in use.
    #[inline]
    pub fn len(&self) -> usize {
        self.child.iter().filter(|&&c| c != EMPTY_SLOT).count()
    }

    /// True when no slot is used (only the root of an empty scene).
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.child[0] == EMPTY_SLOT
    }

    /// The union of the used slots' boxes.
    pub fn bounds(&self) -> Aabb {
        (0..self.len()).fold(Aabb::EMPTY, |b, i| b.union(&self.slot_bounds(i)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn node_is_two_cache_lines_and_starts_empty() {
        assert_eq!(core::mem::size_of::<WideNode>(), 128);
        let n = WideNode::default();
        assert!(n.is_empty() && n.bounds().is_empty());
        let mut m = n;
        let b = Aabb {
            min: crate::Vec3::new(-1.0, 0.0, 2.0),
            max: crate::Vec3::new(1.0, 3.0, 2.5),
        };
        m.set_slot_bounds(0, &b);
        m.child[0] = LEAF_BIT | 7;
        assert_eq!(m.slot_bounds(0), b);
        assert_eq!((m.len(), m.bounds()), (1, b));
    }
}
