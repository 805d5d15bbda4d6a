//! Turning caller pointers into slices: every `unsafe` of coray-ffi that
//! makes a reference lives here, behind checks of null, alignment and size.

use crate::{CorayScene, CorayStatus};
use coray::arena::{KdArenaHeader, ARENA_ALIGN};
use coray::kd::{KdEvent, KdLeaf, KdNode, KdRopes};
use coray::{Cone, Scene, Sphere};
use core::mem::{align_of, size_of};

/// Types that may be viewed in caller memory: `repr(C)`, only `u32`, `f32`
/// and `u8` fields, no padding, alignment at most [`ARENA_ALIGN`]. Every bit
/// pattern is then a value, so reading arbitrary caller bytes as `T` is
/// defined (whether the values make a tree is `validate`'s question).
///
/// # Safety
/// Implement only for types with exactly those properties.
pub(crate) unsafe trait Plain: Copy {}

// SAFETY (all impls): each type is repr(C) with u32/f32/u8 fields only; the
// asserts below prove there is no padding and the alignment is small.
unsafe impl Plain for KdNode {}
unsafe impl Plain for KdLeaf {}
unsafe impl Plain for KdRopes {}
unsafe impl Plain for KdEvent {}
unsafe impl Plain for KdArenaHeader {}
unsafe impl Plain for u32 {}
unsafe impl Plain for coray::lcts::HistoryRecord {}
unsafe impl Plain for coray::lcts::CornerInfo {}
unsafe impl Plain for coray::lcts::hlcts::HlctsEntry {}
unsafe impl Plain for u8 {}
unsafe impl Plain for f32 {}
unsafe impl Plain for coray::Aabb {}
unsafe impl Plain for coray::bvh::BvhNode {}
unsafe impl Plain for coray::bvh::BvhStackItem {}
unsafe impl Plain for coray::arena::BvhArenaHeader {}
unsafe impl Plain for coray::arena::ProjArenaHeader {}
unsafe impl Plain for coray::proj::Rect {}

const _: () = {
    assert!(size_of::<KdNode>() == 8 && align_of::<KdNode>() <= ARENA_ALIGN);
    assert!(size_of::<KdLeaf>() == 8);
    assert!(size_of::<KdRopes>() == 48);
    assert!(size_of::<KdEvent>() == 8);
    assert!(size_of::<KdArenaHeader>() == 100 && align_of::<KdArenaHeader>() == 4);
    assert!(size_of::<Sphere>() == 16 && align_of::<Sphere>() == 4);
    assert!(size_of::<Cone>() == 32 && align_of::<Cone>() == 4);
    assert!(size_of::<coray::lcts::HistoryRecord>() == 8);
    assert!(
        size_of::<coray::lcts::CornerInfo>() == 40 && align_of::<coray::lcts::CornerInfo>() == 4
    );
    assert!(size_of::<coray::lcts::hlcts::HlctsEntry>() == 96);
    assert!(size_of::<coray::Aabb>() == 24 && align_of::<coray::Aabb>() == 4);
    assert!(size_of::<coray::bvh::BvhNode>() == 32 && align_of::<coray::bvh::BvhNode>() == 4);
    assert!(size_of::<coray::bvh::BvhStackItem>() == 8);
    assert!(size_of::<coray::arena::BvhArenaHeader>() == 108);
    assert!(size_of::<coray::arena::ProjArenaHeader>() == 120);
    assert!(size_of::<coray::proj::Rect>() == 20 && align_of::<coray::proj::Rect>() == 4);
};

/// Checks an arena pointer: not null, aligned to [`ARENA_ALIGN`].
pub(crate) fn check_arena(p: *const u8) -> Result<(), CorayStatus> {
    if p.is_null() {
        return Err(CorayStatus::NullPointer);
    }
    if !(p as usize).is_multiple_of(ARENA_ALIGN) {
        return Err(CorayStatus::Misaligned);
    }
    Ok(())
}

/// A mutable view of `count` `T`s at `base + offset`.
///
/// # Safety
/// `base` passed [`check_arena`] and is valid for writes of
/// `offset + count * size_of::<T>()` bytes for `'a`, with no other reference
/// to that range alive; `offset` is a multiple of [`ARENA_ALIGN`].
pub(crate) unsafe fn slice_mut<'a, T: Plain>(
    base: *mut u8,
    offset: usize,
    count: usize,
) -> &'a mut [T] {
    debug_assert!(offset.is_multiple_of(ARENA_ALIGN));
    // SAFETY: in bounds of the caller's arena (caller's contract above), so
    // `add` stays inside one allocation; aligned since base and offset are
    // multiples of 16 and align_of::<T>() divides 16; `T: Plain` makes any
    // bytes found there a valid T; exclusive for 'a by the contract.
    unsafe { core::slice::from_raw_parts_mut(base.add(offset).cast::<T>(), count) }
}

/// A shared view of `count` `T`s at `base + offset`.
///
/// # Safety
/// As [`slice_mut`], for reads, with nobody writing the range during `'a`.
pub(crate) unsafe fn slice_ref<'a, T: Plain>(
    base: *const u8,
    offset: usize,
    count: usize,
) -> &'a [T] {
    debug_assert!(offset.is_multiple_of(ARENA_ALIGN));
    // SAFETY: as in slice_mut; shared access only.
    unsafe { core::slice::from_raw_parts(base.add(offset).cast::<T>(), count) }
}

/// A caller's input array of `count` elements, or the status for a NULL,
/// misaligned or impossibly long one. NULL is fine when `count` is 0.
///
/// # Safety
/// When `count > 0`, `p` points to `count` readable elements that stay
/// unchanged during `'a`.
pub(crate) unsafe fn input<'a, T>(p: *const T, count: usize) -> Result<&'a [T], CorayStatus> {
    if count == 0 {
        return Ok(&[]);
    }
    if p.is_null() {
        return Err(CorayStatus::NullPointer);
    }
    if !(p as usize).is_multiple_of(align_of::<T>()) {
        return Err(CorayStatus::Misaligned);
    }
    if count
        .checked_mul(size_of::<T>())
        .is_none_or(|b| b > isize::MAX as usize)
    {
        return Err(CorayStatus::TooManyPrimitives);
    }
    // SAFETY: non-null, aligned, size within isize::MAX (checked above);
    // readable and unchanged for 'a by the caller's contract.
    Ok(unsafe { core::slice::from_raw_parts(p, count) })
}

/// A caller's output array of `count` elements (same rules as [`input`]).
///
/// # Safety
/// When `count > 0`, `p` points to `count` writable elements that nothing
/// else touches during `'a`.
pub(crate) unsafe fn output<'a, T>(p: *mut T, count: usize) -> Result<&'a mut [T], CorayStatus> {
    if count == 0 {
        return Ok(&mut []);
    }
    if p.is_null() {
        return Err(CorayStatus::NullPointer);
    }
    if !(p as usize).is_multiple_of(align_of::<T>()) {
        return Err(CorayStatus::Misaligned);
    }
    if count
        .checked_mul(size_of::<T>())
        .is_none_or(|b| b > isize::MAX as usize)
    {
        return Err(CorayStatus::InvalidParameter);
    }
    // SAFETY: non-null, aligned, size within isize::MAX (checked above);
    // exclusive for 'a by the caller's contract.
    Ok(unsafe { core::slice::from_raw_parts_mut(p, count) })
}

/// Reads one caller struct by reference.
///
/// # Safety
/// `p` is NULL or points to a readable, aligned `T`.
pub(crate) unsafe fn input_ref<'a, T>(p: *const T) -> Result<&'a T, CorayStatus> {
    if p.is_null() {
        return Err(CorayStatus::NullPointer);
    }
    if !(p as usize).is_multiple_of(align_of::<T>()) {
        return Err(CorayStatus::Misaligned);
    }
    // SAFETY: non-null and aligned (checked); readable by the contract.
    Ok(unsafe { &*p })
}

/// The core's view of a caller scene.
///
/// # Safety
/// `s` is NULL or points to a `CorayScene` whose arrays hold the counts it
/// gives and stay unchanged during `'a`.
pub(crate) unsafe fn scene<'a>(s: *const CorayScene) -> Result<Scene<'a>, CorayStatus> {
    // SAFETY: forwarded contract.
    let s = unsafe { input_ref(s)? };
    if s.struct_size != size_of::<CorayScene>() {
        return Err(CorayStatus::InvalidParameter);
    }
    // SAFETY (four calls): each array pointer and its element count come from
    // the caller's scene, which promises them readable; [f32; 3], [u32; 3],
    // Sphere and Cone are repr(C) runs of 4-byte fields, the C layout.
    unsafe {
        Ok(Scene {
            vertices: input(s.vertices.cast::<[f32; 3]>(), s.vertex_count)?,
            triangles: input(s.indices.cast::<[u32; 3]>(), s.triangle_count)?,
            spheres: input(s.spheres.cast::<Sphere>(), s.sphere_count)?,
            cones: input(s.cones.cast::<Cone>(), s.cone_count)?,
        })
    }
}
