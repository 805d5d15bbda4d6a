//! Handles: what `coray_<object>_open` learns from an arena and a scene in
//! its O(1) checks, kept in caller memory so that every later call starts
//! from it without checking again. A handle holds pointers into the
//! caller's arena and scene arrays (it is valid while they are, in this
//! process) and a seal over them, so a handle the open call did not fill
//! (uninitialised, zeroed, overwritten) is refused with
//! `CORAY_STATUS_INVALID_PARAMETER`, never followed.

use crate::carve::{self, Regions, Span};
use crate::CorayStatus;
use coray::Scene;

/// An opened kd-tree: fill it with `coray_kdtree_open`, pass it to every
/// call on that tree. Read-only: many threads may share one.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CorayKdTree {
    /// Opaque to the caller.
    pub opaque: [u64; 32],
}

/// An opened hierarchy: fill it with `coray_bvh_open`. It reads the
/// arena's header on each call, so an R-tree changed by `coray_bvh_insert`
/// and `coray_bvh_delete` needs no new handle.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CorayBvh {
    /// Opaque to the caller.
    pub opaque: [u64; 32],
}

/// An opened projection hierarchy: fill it with `coray_proj_open`.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CorayProj {
    /// Opaque to the caller.
    pub opaque: [u64; 32],
}

/// An opened wide hierarchy: fill it with `coray_wide_open`. Read-only:
/// many threads may share one.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CorayWide {
    /// Opaque to the caller.
    pub opaque: [u64; 32],
}

/// What every handle holds: the arena, the scene's arrays, and the byte
/// offsets and element counts of the arena's parts (at most 8). The open
/// calls fill one and store its [`Handle::words`]; every later call reads
/// those words in place through [`Sealed`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Handle {
    /// Which object: a tag per kind, part of the seal.
    kind: u64,
    /// The arena's address and bytes.
    arena: usize,
    arena_bytes: usize,
    /// The scene's arrays: address and count of vertices, triangles,
    /// spheres, cones.
    scene: [usize; 8],
    /// Byte offsets and counts of the arena's parts, each checked by
    /// [`Handle::set_part`] (the only way to set one).
    parts: [(usize, usize); 8],
}

/// Handle kinds (any values; the seal binds them).
pub(crate) const KIND_KD: u64 = 0x4b44;
pub(crate) const KIND_BVH: u64 = 0x4256;
pub(crate) const KIND_PROJ: u64 = 0x504a;
pub(crate) const KIND_WIDE: u64 = 0x5744;

const WORDS: usize = 32;
/// Word 0 is the seal; words 1 to `SEALED_END - 1` are what it covers:
/// kind (1), arena (2, 3), scene (4..12), parts (12..20), and word 20,
/// always 0 (five groups of four). The rest are 0 and unused.
const SEALED_END: usize = 21;

/// The seal over the covered words: four independent lanes (so a trace
/// call's check is not one long dependency chain) of xor and rotate per
/// word, joined by one avalanche. Each step is a bijection of its lane and
/// the lanes are joined by xor of distinct rotations, so any single
/// changed word changes the seal: it catches a handle the caller damaged
/// or never opened. Every trace call checks it (about 2 instructions a
/// word, none of them a multiply).
#[inline(always)]
fn seal_of(w: &[u64; WORDS]) -> u64 {
    let mut l = [
        0xC0A4_5EA1_0000_0001u64,
        0x6A09_E667_F3BC_C908,
        0xBB67_AE85_84CA_A73B,
        0x3C6E_F372_FE94_F82B,
    ];
    for group in w[1..SEALED_END].chunks_exact(4) {
        for (lane, &x) in l.iter_mut().zip(group) {
            *lane = (*lane ^ x).rotate_left(23);
        }
    }
    coray::rng::mix64(l[0] ^ l[1].rotate_left(16) ^ l[2].rotate_left(32) ^ l[3].rotate_left(48))
}

impl Handle {
    /// The handle as the words a caller keeps.
    pub(crate) fn words(&self) -> [u64; WORDS] {
        let mut w = [0u64; WORDS];
        w[1] = self.kind;
        w[2] = self.arena as u64;
        w[3] = self.arena_bytes as u64;
        for (i, s) in self.scene.iter().enumerate() {
            w[4 + i] = *s as u64;
        }
        for (i, (o, n)) in self.parts.iter().enumerate() {
            w[12 + i] = (*o as u64) << 32 | *n as u64;
        }
        w[0] = seal_of(&w);
        w
    }

    /// Records part `i` of the arena: `count` `T`s at byte `offset`, which
    /// must lie within the arena's bytes at a 16-aligned offset (the open
    /// calls' check; trace calls then read the part unchecked).
    pub(crate) fn set_part<T>(
        &mut self,
        i: usize,
        offset: usize,
        count: usize,
    ) -> Result<(), CorayStatus> {
        let end = count
            .checked_mul(core::mem::size_of::<T>())
            .and_then(|b| b.checked_add(offset));
        if end.is_none_or(|e| e > self.arena_bytes)
            || !offset.is_multiple_of(16)
            || offset > u32::MAX as usize
            || count > u32::MAX as usize
        {
            return Err(CorayStatus::CorruptArena);
        }
        self.parts[i] = (offset, count);
        Ok(())
    }

    /// A handle of `kind` on the arena at `arena` (its layout `arena_bytes`
    /// long) and `scene`'s arrays, with no parts yet.
    pub(crate) fn new(kind: u64, arena: usize, arena_bytes: usize, s: &Scene) -> Handle {
        Handle {
            kind,
            arena,
            arena_bytes,
            scene: [
                s.vertices.as_ptr() as usize,
                s.vertices.len(),
                s.triangles.as_ptr() as usize,
                s.triangles.len(),
                s.spheres.as_ptr() as usize,
                s.spheres.len(),
                s.cones.as_ptr() as usize,
                s.cones.len(),
            ],
            parts: [(0, 0); 8],
        }
    }
}

/// A handle's words whose seal holds, read where they lie (in the caller's
/// handle, or in the words an open call is about to store): nothing is
/// decoded or copied, each accessor reads the word it needs.
#[derive(Clone, Copy)]
pub(crate) struct Sealed<'h> {
    w: &'h [u64; WORDS],
}

impl<'h> Sealed<'h> {
    /// The words `w`, if their seal holds and they are of `kind`.
    #[inline(always)]
    pub(crate) fn new(w: &'h [u64; WORDS], kind: u64) -> Result<Sealed<'h>, CorayStatus> {
        if w[1] != kind || seal_of(w) != w[0] {
            return Err(CorayStatus::InvalidParameter);
        }
        Ok(Sealed { w })
    }

    /// The words `w` without checking their seal again: for a one-ray call
    /// whose memo records that these words, at this address and with this
    /// seal word, passed [`Sealed::new`] for the memo's kind.
    ///
    /// # Safety
    /// `w` passed `Sealed::new` for this kind, and the caller's contract
    /// (a handle stays unchanged while it is used) holds since.
    #[inline(always)]
    pub(crate) unsafe fn known(w: &'h [u64; WORDS]) -> Sealed<'h> {
        Sealed { w }
    }

    /// The seal word, which changes with any word it covers.
    #[inline(always)]
    pub(crate) fn seal(&self) -> u64 {
        self.w[0]
    }

    /// The arena's address.
    #[inline]
    pub(crate) fn arena(&self) -> usize {
        self.w[2] as usize
    }

    /// The arena's bytes (its layout's size).
    #[inline]
    pub(crate) fn arena_bytes(&self) -> usize {
        self.w[3] as usize
    }

    /// What a call on this handle reads besides its own arguments: the
    /// handle's words, and the arena.
    #[inline(always)]
    pub(crate) fn spans(&self) -> [Span; 2] {
        [
            Span::of(self.w.as_ptr(), core::mem::size_of::<[u64; WORDS]>()),
            Span::of(self.arena() as *const u8, self.arena_bytes()),
        ]
    }

    /// Byte offset and count of the arena's part `i`.
    #[inline]
    fn part_at(&self, i: usize) -> (usize, usize) {
        let x = self.w[12 + i];
        ((x >> 32) as usize, x as u32 as usize)
    }

    /// The scene the handle was opened with.
    ///
    /// # Safety
    /// The arrays the open call was given are still readable and unchanged
    /// (the caller's contract for every call on a handle).
    #[inline(always)]
    pub(crate) unsafe fn scene<'a>(&self) -> Scene<'a> {
        let s = |i: usize| (self.w[4 + i] as usize, self.w[5 + i] as usize);
        // SAFETY (four calls): address and count were checked by
        // carve::input when the handle was opened (non-null unless empty,
        // aligned, size in range) and sealed since; readable by the contract.
        unsafe {
            Scene {
                vertices: slice(s(0)),
                triangles: slice(s(2)),
                spheres: slice(s(4)),
                cones: slice(s(6)),
            }
        }
    }

    /// Part `i` of the arena as a slice of `T`. Not checked again: the
    /// open call checked it ([`Handle::set_part`]) before sealing.
    ///
    /// # Safety
    /// The arena the open call was given is still readable, and nobody
    /// writes the part during `'a`; `T` is the type the open call checked
    /// part `i` for.
    #[inline(always)]
    pub(crate) unsafe fn part<'a, T: carve::Plain>(&self, i: usize) -> &'a [T] {
        let (offset, count) = self.part_at(i);
        // SAFETY: the arena passed check_arena at open and holds
        // `arena_bytes` readable bytes; the part lies within them at a
        // 16-aligned offset (Handle::set_part at open, sealed since).
        unsafe { carve::arena_ref(self.arena() as *const u8, offset, count) }
    }
}

/// A slice of `n` elements at address `a` (dangling but aligned when `n` is 0).
///
/// # Safety
/// As `core::slice::from_raw_parts` for `n > 0`.
#[inline]
unsafe fn slice<'a, T>((a, n): (usize, usize)) -> &'a [T] {
    if n == 0 {
        return &[];
    }
    // SAFETY: the caller's contract.
    unsafe { core::slice::from_raw_parts(a as *const T, n) }
}

/// The handle behind a caller's pointer, read in place, noted in
/// `regions` as read.
///
/// # Safety
/// `p` is NULL or points to a readable handle that stays unchanged during
/// `'h`.
#[inline(always)]
pub(crate) unsafe fn read<'h>(
    p: *const [u64; WORDS],
    kind: u64,
    regions: &mut Regions,
) -> Result<Sealed<'h>, CorayStatus> {
    // SAFETY: forwarded contract.
    let h = unsafe { read_unnoted(p, kind)? };
    regions.add(p, core::mem::size_of::<[u64; WORDS]>(), false);
    Ok(h)
}

/// [`read`] without a region list: the caller checks overlaps with
/// [`Sealed::spans`] itself.
///
/// # Safety
/// As [`read`].
#[inline(always)]
pub(crate) unsafe fn read_unnoted<'h>(
    p: *const [u64; WORDS],
    kind: u64,
) -> Result<Sealed<'h>, CorayStatus> {
    carve::check_array(p, 1)?;
    // SAFETY: non-null and aligned (checked); readable and unchanged for
    // 'h by the contract.
    Sealed::new(unsafe { &*p }, kind)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_handle_survives_its_words_and_nothing_else_does() {
        let mut h = Handle {
            kind: KIND_KD,
            arena: 0x1000,
            arena_bytes: 4096,
            ..Handle::default()
        };
        h.parts[0] = (128, 7);
        h.scene[3] = 9;
        let w = h.words();
        let s = Sealed::new(&w, KIND_KD).expect("sealed");
        assert_eq!(
            (s.arena(), s.arena_bytes(), s.part_at(0)),
            (0x1000, 4096, (128, 7))
        );
        assert_eq!(s.w[7], 9);
        assert!(Sealed::new(&w, KIND_BVH).is_err());
        assert!(Sealed::new(&[0; WORDS], KIND_KD).is_err());
        for i in 0..SEALED_END {
            for bit in [0, 17, 32, 63] {
                let mut bad = w;
                bad[i] ^= 1 << bit;
                assert!(Sealed::new(&bad, KIND_KD).is_err(), "word {i} bit {bit}");
            }
        }
    }

    #[test]
    fn a_part_outside_the_arena_is_refused_at_open() {
        let mut h = Handle::new(KIND_KD, 0x1000, 4096, &Scene::default());
        assert_eq!(h.set_part::<u32>(1, 4096 - 16, 4), Ok(()), "exact fit");
        assert_eq!(
            h.set_part::<u32>(1, 4096 - 16, 5),
            Err(CorayStatus::CorruptArena)
        );
        assert_eq!(
            h.set_part::<u32>(1, 8, 1),
            Err(CorayStatus::CorruptArena),
            "misaligned"
        );
        let huge = usize::MAX / 2;
        assert_eq!(
            h.set_part::<u32>(1, 16, huge),
            Err(CorayStatus::CorruptArena),
            "overflow"
        );
        assert_eq!(h.parts[1], (4096 - 16, 4), "a refused part is not recorded");
    }
}
