//! Handles: what `coray_<object>_open` learns from an arena and a scene in
//! its O(1) checks, kept in caller memory so that every later call starts
//! from it without checking again. A handle holds pointers into the
//! caller's arena and scene arrays (it is valid while they are, in this
//! process) and a seal over them, so a handle the open call did not fill
//! (uninitialised, zeroed, overwritten) is refused with
//! `CORAY_STATUS_INVALID_PARAMETER`, never followed.

use crate::carve::{self, Regions};
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

/// What every handle holds: the arena, the scene's arrays, and the byte
/// offsets and element counts of the arena's parts (at most 8), all as
/// words, and the seal over them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Handle {
    /// Which object: a tag per kind, part of the seal.
    pub kind: u64,
    /// The arena's address and bytes.
    pub arena: usize,
    pub arena_bytes: usize,
    /// The scene's arrays: address and count of vertices, triangles,
    /// spheres, cones.
    pub scene: [usize; 8],
    /// Byte offsets and counts of the arena's parts.
    pub parts: [(usize, usize); 8],
    /// Object-specific words (a kd-tree's info, a plane, a builder).
    pub extra: [u32; 16],
}

/// Handle kinds (any values; the seal binds them).
pub(crate) const KIND_KD: u64 = 0x4b44;
pub(crate) const KIND_BVH: u64 = 0x4256;
pub(crate) const KIND_PROJ: u64 = 0x504a;

const WORDS: usize = 32;

impl Handle {
    /// The seal over words 1 to 27 (kind to extra): one multiply-xorshift
    /// per word and a final avalanche. It catches a handle the caller
    /// damaged or never opened (any changed word changes it), at about 4
    /// instructions a word: every trace call checks it.
    fn seal_of(w: &[u64; WORDS]) -> u64 {
        let mut h = 0xC0A4_5EA1_0000_0001u64;
        for &x in &w[1..28] {
            h = (h ^ x).wrapping_mul(0x9E37_79B9_7F4A_7C15);
            h ^= h >> 29;
        }
        coray::rng::mix64(h)
    }

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
        for (i, pair) in self.extra.chunks(2).enumerate() {
            w[20 + i] = (pair[0] as u64) << 32 | pair[1] as u64;
        }
        w[0] = Self::seal_of(&w);
        w
    }

    /// The handle in `w`, if its seal holds and it is of `kind`.
    pub(crate) fn from_words(w: &[u64; WORDS], kind: u64) -> Result<Handle, CorayStatus> {
        if w[1] != kind || Self::seal_of(w) != w[0] {
            return Err(CorayStatus::InvalidParameter);
        }
        let mut h = Handle {
            kind: w[1],
            arena: w[2] as usize,
            arena_bytes: w[3] as usize,
            ..Handle::default()
        };
        for i in 0..8 {
            h.scene[i] = w[4 + i] as usize;
            h.parts[i] = ((w[12 + i] >> 32) as usize, w[12 + i] as u32 as usize);
        }
        for i in 0..8 {
            h.extra[2 * i] = (w[20 + i] >> 32) as u32;
            h.extra[2 * i + 1] = w[20 + i] as u32;
        }
        Ok(h)
    }

    /// Records the scene's arrays.
    pub(crate) fn set_scene(&mut self, s: &Scene) {
        self.scene = [
            s.vertices.as_ptr() as usize,
            s.vertices.len(),
            s.triangles.as_ptr() as usize,
            s.triangles.len(),
            s.spheres.as_ptr() as usize,
            s.spheres.len(),
            s.cones.as_ptr() as usize,
            s.cones.len(),
        ];
    }

    /// The scene the handle was opened with, its arrays noted in `regions`.
    ///
    /// # Safety
    /// The arrays the open call was given are still readable and unchanged
    /// (the caller's contract for every call on a handle).
    pub(crate) unsafe fn scene<'a>(&self, regions: &mut Regions) -> Scene<'a> {
        let s = &self.scene;
        // SAFETY (four calls): address and count were checked by
        // carve::input when the handle was opened (non-null unless empty,
        // aligned, size in range) and sealed since; readable by the contract.
        let scene = unsafe {
            Scene {
                vertices: slice(s[0], s[1]),
                triangles: slice(s[2], s[3]),
                spheres: slice(s[4], s[5]),
                cones: slice(s[6], s[7]),
            }
        };
        regions
            .add(scene.vertices.as_ptr(), size_of_val(scene.vertices), false)
            .add(
                scene.triangles.as_ptr(),
                size_of_val(scene.triangles),
                false,
            )
            .add(scene.spheres.as_ptr(), size_of_val(scene.spheres), false)
            .add(scene.cones.as_ptr(), size_of_val(scene.cones), false);
        scene
    }

    /// Part `i` of the arena as a slice of `T`, within the arena's bytes.
    ///
    /// # Safety
    /// The arena the open call was given is still readable, and nobody
    /// writes the part during `'a`.
    pub(crate) unsafe fn part<'a, T: carve::Plain>(
        &self,
        i: usize,
    ) -> Result<&'a [T], CorayStatus> {
        let (offset, count) = self.parts[i];
        let end = count
            .checked_mul(core::mem::size_of::<T>())
            .and_then(|b| b.checked_add(offset));
        if end.is_none_or(|e| e > self.arena_bytes) || !offset.is_multiple_of(16) {
            return Err(CorayStatus::InvalidParameter);
        }
        // SAFETY: the arena passed check_arena at open and holds
        // `arena_bytes` readable bytes; the part lies within them (checked
        // above), at a 16-aligned offset.
        Ok(unsafe { carve::arena_ref(self.arena as *const u8, offset, count) })
    }
}

/// A slice of `n` elements at address `a` (dangling but aligned when `n` is 0).
///
/// # Safety
/// As `core::slice::from_raw_parts` for `n > 0`.
unsafe fn slice<'a, T>(a: usize, n: usize) -> &'a [T] {
    if n == 0 {
        return &[];
    }
    // SAFETY: the caller's contract.
    unsafe { core::slice::from_raw_parts(a as *const T, n) }
}

/// The handle behind a caller's pointer, noted in `regions` as read.
///
/// # Safety
/// `p` is NULL or points to a readable handle.
pub(crate) unsafe fn read(
    p: *const [u64; WORDS],
    kind: u64,
    regions: &mut Regions,
) -> Result<Handle, CorayStatus> {
    carve::check_array(p, 1)?;
    regions.add(p, core::mem::size_of::<[u64; WORDS]>(), false);
    // SAFETY: non-null and aligned (checked); readable by the contract.
    Handle::from_words(unsafe { &*p }, kind)
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
        h.extra[3] = 9;
        let w = h.words();
        assert_eq!(Handle::from_words(&w, KIND_KD), Ok(h));
        assert!(Handle::from_words(&w, KIND_BVH).is_err());
        assert!(Handle::from_words(&[0; WORDS], KIND_KD).is_err());
        for i in 0..WORDS {
            let mut bad = w;
            bad[i] ^= 1 << (i % 61);
            if i < 28 {
                assert!(Handle::from_words(&bad, KIND_KD).is_err(), "word {i}");
            }
        }
    }
}
