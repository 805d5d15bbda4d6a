//! Every size limit of the library, in one place, with its reason.

/// Primitives any structure indexes: 2^30. Leaf and node words keep 2 tag
/// bits beside a 30-bit index, and event words keep a primitive beside a
/// 2-bit kind.
pub const MAX_PRIMS: usize = 1 << 30;

/// Nodes a kd-tree holds: 2^28 (2 GiB of them, half the largest arena).
/// An interior node's word keeps its axis (2 bits) and a compact tree's
/// flags of a child left out (2 bits) beside a 28-bit child index; a build
/// that would need more stops splitting there (truncated).
pub const KD_MAX_NODES: usize = 1 << 28;

/// Bytes any arena may span: its parts are found by 32-bit offsets, so an
/// arena can be saved and mapped at any address of any target.
pub const MAX_ARENA_BYTES: usize = u32::MAX as usize;

/// Deepest kd-tree leaf any build makes; kd traversal stacks are sized from
/// it, so a tree that validates cannot overflow one.
pub const KD_MAX_DEPTH: u32 = 60;

/// Most entries of an R-tree node (M).
pub const RTREE_MAX_CHILDREN: u32 = 32;

/// Widest and tallest image a cast or a camera takes, in pixels.
pub const MAX_IMAGE_SIDE: u32 = 1 << 15;

/// Most records a traversal history keeps.
pub const MAX_HISTORY_CAPACITY: u32 = 1 << 20;

/// Most sample points per patch side in patch-to-patch visibility: the
/// segments, `samples^4`, are counted in 32 bits.
pub const MAX_PATCH_SAMPLES_PER_SIDE: u32 = 255;

/// `a * b + c` in `usize`, or `None` past [`MAX_ARENA_BYTES`]: the layout
/// arithmetic of every arena, which must not wrap on 32-bit targets.
#[inline]
pub const fn bytes(a: usize, b: usize, c: usize) -> Option<usize> {
    match a.checked_mul(b) {
        Some(m) => match m.checked_add(c) {
            Some(s) if s <= MAX_ARENA_BYTES => Some(s),
            _ => None,
        },
        None => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bytes_stops_at_four_gib() {
        assert_eq!(bytes(3, 4, 5), Some(17));
        assert_eq!(bytes(1, MAX_ARENA_BYTES, 0), Some(MAX_ARENA_BYTES));
        assert_eq!(bytes(1, MAX_ARENA_BYTES, 1), None);
        assert_eq!(bytes(0x2000_0001, 8, 128), None);
        assert_eq!(bytes(usize::MAX, 2, 0), None);
        assert_eq!(bytes(2, 3, usize::MAX), None);
    }

    #[test]
    fn patch_samples_fit_32_bits() {
        let s = MAX_PATCH_SAMPLES_PER_SIDE as u64;
        assert!(s.pow(4) <= u32::MAX as u64);
        assert!((s + 1).pow(4) > u32::MAX as u64);
    }
}
