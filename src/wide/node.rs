//! The node of a wide hierarchy: eight child boxes stored plane by plane,
//! so one ray's slab test runs over the eight children in the same few
//! vector instructions (one pass of AVX, two of SSE), and what each child
//! is.

use crate::geom::Aabb;

/// Children a node holds.
pub const WIDTH: usize = 8;

/// Set in [`WideNode::child`] on a leaf entry: the bits below hold its
/// number of blocks less one ([`LEAF_BLOCKS_SHIFT`]) and its first leaf
/// block ([`super::LeafBlock`], [`LEAF_FIRST_MASK`]).
pub const LEAF_BIT: u32 = 1 << 31;

/// Where a leaf entry's block count less one starts in [`WideNode::child`].
pub const LEAF_BLOCKS_SHIFT: u32 = 27;

/// Most blocks one leaf takes: four bits of the entry hold the count less
/// one.
pub const MAX_LEAF_BLOCKS: usize = 16;

/// A leaf entry's first block within [`WideNode::child`]: 27 bits. A
/// leaf's blocks end at or below it (`2^27 - 1` blocks of 160 bytes, far
/// more than the largest arena holds), so no leaf entry is [`EMPTY_SLOT`].
pub const LEAF_FIRST_MASK: u32 = (1 << LEAF_BLOCKS_SHIFT) - 1;

/// The [`WideNode::child`] word of a leaf over `blocks` (1 to
/// [`MAX_LEAF_BLOCKS`]) blocks from `first` (below 2^27).
#[inline]
pub const fn leaf_entry(first: u32, blocks: u32) -> u32 {
    LEAF_BIT | (blocks - 1) << LEAF_BLOCKS_SHIFT | first
}

/// A leaf entry's first block and number of blocks.
#[inline(always)]
pub const fn leaf_run(entry: u32) -> (usize, usize) {
    (
        (entry & LEAF_FIRST_MASK) as usize,
        ((entry >> LEAF_BLOCKS_SHIFT) & 0xf) as usize + 1,
    )
}

/// [`WideNode::child`] of a slot that holds nothing.
pub const EMPTY_SLOT: u32 = u32::MAX;

/// Rows of [`WideNode::planes`]: the lower corners' x, y and z, then the
/// upper corners'. A ray reads the row of each axis' near and far face by
/// its direction's signs, chosen once per ray.
pub const LOWER: usize = 0;
/// The first row of the upper corners (see [`LOWER`]).
pub const UPPER: usize = 3;

/// One node: up to [`WIDTH`] entries, each an interior child or a leaf (a
/// run of leaf blocks), with its box (224 bytes: 32-byte rows, each one
/// vector load that never straddles a cache line).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(16))]
pub struct WideNode {
    /// The entries' boxes, plane by plane: `planes[LOWER + axis][slot]`
    /// and `planes[UPPER + axis][slot]`. An empty slot's box is empty
    /// (+inf lower, -inf upper), which no ray enters.
    pub planes: [[f32; WIDTH]; 6],
    /// Per slot: an interior child's node index; a leaf's entry
    /// ([`leaf_entry`]: [`LEAF_BIT`], its block count and first block);
    /// [`EMPTY_SLOT`] when unused. Used slots come first.
    pub child: [u32; WIDTH],
}

impl Default for WideNode {
    /// A node with every slot empty (empty boxes).
    fn default() -> WideNode {
        let mut planes = [[f32::INFINITY; WIDTH]; 6];
        for row in &mut planes[UPPER..] {
            *row = [f32::NEG_INFINITY; WIDTH];
        }
        WideNode {
            planes,
            child: [EMPTY_SLOT; WIDTH],
        }
    }
}

impl WideNode {
    /// Slot `i`'s box.
    #[inline]
    pub fn slot_bounds(&self, i: usize) -> Aabb {
        let p = &self.planes;
        Aabb {
            min: crate::Vec3::new(p[LOWER][i], p[LOWER + 1][i], p[LOWER + 2][i]),
            max: crate::Vec3::new(p[UPPER][i], p[UPPER + 1][i], p[UPPER + 2][i]),
        }
    }

    /// Sets slot `i`'s box.
    pub(crate) fn set_slot_bounds(&mut self, i: usize, b: &Aabb) {
        for a in 0..3 {
            self.planes[LOWER + a][i] = b.min[a];
            self.planes[UPPER + a][i] = b.max[a];
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
    fn node_is_seven_rows_and_starts_empty() {
        assert_eq!(core::mem::size_of::<WideNode>(), 224);
        let n = WideNode::default();
        assert!(n.is_empty() && n.bounds().is_empty());
        assert!((0..WIDTH).all(|i| n.slot_bounds(i).is_empty()));
        let mut m = n;
        let b = Aabb {
            min: crate::Vec3::new(-1.0, 0.0, 2.0),
            max: crate::Vec3::new(1.0, 3.0, 2.5),
        };
        m.set_slot_bounds(0, &b);
        m.child[0] = leaf_entry(7, 3);
        assert_eq!(m.slot_bounds(0), b);
        assert_eq!((m.len(), m.bounds()), (1, b));
        assert_eq!(leaf_run(m.child[0]), (7, 3));
        // The last leaf the arena limit allows is not an empty slot.
        let first = LEAF_FIRST_MASK - MAX_LEAF_BLOCKS as u32;
        let last = leaf_entry(first, MAX_LEAF_BLOCKS as u32);
        assert_ne!(last, EMPTY_SLOT);
        assert_eq!(leaf_run(last), (first as usize, MAX_LEAF_BLOCKS));
        const _: () = assert!(
            crate::limits::MAX_ARENA_BYTES / core::mem::size_of::<super::super::LeafBlock>()
                < LEAF_FIRST_MASK as usize
        );
    }
}
