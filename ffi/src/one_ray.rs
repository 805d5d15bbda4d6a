//! The body of every one-ray entry point (`coray_<object>_intersect1`,
//! `_occluded1`): the array calls' checks, statuses and their order for one
//! ray, on spans known at compile time. No region list is filled, no chunk
//! loop runs and no statistics are merged; still, every check runs on every
//! call (about 590 instructions on x86-64 beyond what an array call spends
//! per ray). A renderer that traces one ray per call makes a tracer
//! (`tracer.rs`), which makes these checks once.

use crate::abi::{CorayRay, CorayTraceStats};
use crate::carve::{self, Out, Plain, ReadSpans, Span};
use crate::handle::{self, Sealed};
use crate::CorayStatus;
use coray::{Scene, TraceStats};
use core::ffi::c_void;
use core::mem::size_of;

/// Traces `ray` through the structure behind `handle` (of `kind`) and
/// writes the answer to `out`.
///
/// In order: the handle (null, alignment, seal, then `view`'s header
/// checks of the arena over the handle's scene), the ray and `out` (null, alignment), the stack (`stack_len`
/// entries of `I`: null, alignment, size), the statistics (null allowed,
/// alignment, `struct_size`), then no written buffer (stack, `out`,
/// statistics) may overlap another or anything read (handle, arena, scene
/// arrays, ray). Only then does `answer` run; a fault it meets gives
/// `CORAY_STATUS_CORRUPT_ARENA` and nothing is written.
///
/// # Safety
/// `handle` is NULL or points to a readable handle; its arena and scene
/// are still in place and unchanged; `ray` is NULL or one readable ray,
/// `out` NULL or one writable `O`; `stack` NULL or writable for
/// `stack_bytes`; `stats` NULL or writable for its `struct_size`.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) unsafe fn one_ray<'a, S, I: Plain, O>(
    handle: *const [u64; 32],
    kind: u64,
    view: impl FnOnce(Sealed<'a>, Scene<'a>) -> Result<S, CorayStatus>,
    stack_len: impl FnOnce(&S) -> usize,
    ray: *const CorayRay,
    out: *mut O,
    stack: *mut c_void,
    stack_bytes: usize,
    stats: *mut CorayTraceStats,
    answer: impl FnOnce(&S, &coray::Ray, &mut [I], &mut TraceStats) -> Result<O, CorayStatus>,
) -> Result<(), CorayStatus> {
    // SAFETY: forwarded caller contract for every pointer; each is checked
    // (null, alignment, size) before it is read or viewed, and nothing is
    // written before the overlap check below. The ray is borrowed, not
    // copied (`abi::core_ray` says why): no buffer the call writes meets it
    // (that check).
    let (h, scene, s, r, stk, stats) = unsafe {
        let h = handle::read_unnoted(handle, kind)?;
        let scene = h.scene();
        let s = view(h, scene)?;
        carve::check_array(ray, 1)?;
        carve::check_array(out, 1)?;
        let need = stack_len(&s);
        let stk = carve::stack_unnoted::<I>(stack, stack_bytes, need)?;
        let stats = Out::open(stats, true)?;
        (h, scene, s, crate::abi::core_ray(&*ray), stk, stats)
    };
    let [handle_words, arena] = h.spans();
    let [vertices, triangles, spheres, cones] = Span::of_scene(&scene);
    let read = ReadSpans::<8>::new([
        handle_words,
        arena,
        vertices,
        triangles,
        spheres,
        cones,
        Span::of(ray, size_of::<CorayRay>()),
    ]);
    let stk_span = Span::of(stk.as_ptr(), size_of_val(stk));
    let out_span = Span::of(out, size_of::<O>());
    // Most one-ray callers pass no statistics: a third of the pairs less.
    let overlap = if stats.span() == Span::default() {
        carve::overlap(&[stk_span, out_span], &read)
    } else {
        carve::overlap(&[stk_span, out_span, stats.span()], &read)
    };
    if overlap {
        return Err(CorayStatus::InvalidParameter);
    }
    let mut st = TraceStats::default();
    let o = answer(&s, r, stk, &mut st)?;
    if st.faults > 0 {
        return Err(CorayStatus::CorruptArena);
    }
    // SAFETY: checked non-null and aligned above, and disjoint from every
    // buffer this call reads or writes.
    unsafe { out.write(o) };
    stats.write(CorayTraceStats::of(&st));
    Ok(())
}
