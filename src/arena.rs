//! What every arena layout shares: the alignment, and [`Parts`], which lays
//! parts out one after another with checked arithmetic. Each family's own
//! `layout` module (`kd::layout`, `bvh::layout`, `proj::layout`,
//! `lcts::layout`) says which parts its arenas hold; the C ABI carves
//! arenas with those layouts and the core itself only sees typed slices.
//!
//! Every part starts on a multiple of [`ARENA_ALIGN`] from the arena's
//! start and is found from offsets in a header, never pointers: an arena
//! can be copied, saved and mapped at any aligned address. No layout spans
//! more than [`crate::limits::MAX_ARENA_BYTES`]: offsets fit 32 bits, and
//! the arithmetic cannot wrap on a 32-bit target.

use crate::limits::MAX_ARENA_BYTES;
use core::mem::size_of;

/// Alignment every arena's start must have, and that every part keeps.
pub const ARENA_ALIGN: usize = 16;

/// `n` rounded up to a multiple of [`ARENA_ALIGN`], or `None` past
/// [`MAX_ARENA_BYTES`].
pub const fn align_up(n: usize) -> Option<usize> {
    match n.checked_add(ARENA_ALIGN - 1) {
        Some(m) if m & !(ARENA_ALIGN - 1) <= MAX_ARENA_BYTES => Some(m & !(ARENA_ALIGN - 1)),
        _ => None,
    }
}

/// Parts laid out one after another, each aligned, every sum checked.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Parts {
    at: usize,
}

impl Parts {
    /// Parts after a header of `header` bytes (a multiple of [`ARENA_ALIGN`]).
    pub const fn after(header: usize) -> Parts {
        Parts { at: header }
    }

    /// Room for `count` elements of `T` at the next aligned offset, which
    /// it returns; `None` when the layout would pass [`MAX_ARENA_BYTES`].
    pub fn push<T>(&mut self, count: usize) -> Option<usize> {
        let offset = align_up(self.at)?;
        self.at = crate::limits::bytes(count, size_of::<T>(), offset)?;
        Some(offset)
    }

    /// Bytes the parts so far span, rounded up to [`ARENA_ALIGN`] (so an
    /// arena of exactly this size ends on an aligned address).
    pub fn total(&self) -> Option<usize> {
        align_up(self.at)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parts_align_and_stop_at_four_gib() {
        let mut p = Parts::after(128);
        assert_eq!(p.push::<u8>(3), Some(128));
        assert_eq!(p.push::<u32>(5), Some(144));
        assert_eq!(p.total(), Some(176));
        // The 32-bit wrap of issue 16: 0x2000_0001 nodes of 8 bytes.
        let mut q = Parts::after(128);
        assert_eq!(q.push::<[u32; 2]>(0x2000_0001), None);
        let mut r = Parts::after(128);
        assert_eq!(r.push::<u8>(MAX_ARENA_BYTES), None);
        assert_eq!(align_up(MAX_ARENA_BYTES), None);
        assert_eq!(align_up(17), Some(32));
    }
}
