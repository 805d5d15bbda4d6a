//! Tracers: one thread's binding of an opened structure (kd-tree, BVH,
//! projection hierarchy, wide hierarchy) to a traversal method and a
//! traversal stack, made once by `coray_<object>_tracer` with every check
//! an array call makes, and kept in caller memory. The one-ray calls on a
//! tracer (`coray_<object>_tracer_intersect1`, `_occluded1`; one pair per
//! family, so that a firmware links only the traversals it calls) then
//! check only what can differ from ray to ray (the ray's and the answer's places), so a
//! renderer that traces one ray per call pays about what an array call
//! pays per ray. A tracer also sums the statistics of its calls.
//!
//! What a tracer trusts, and why it may: its words hold a check over
//! themselves and their own address (a tracer the make call did not fill,
//! or one copied elsewhere, is refused); the handle's seal word, compared
//! on every call (a handle opened again, or damaged there, is refused);
//! and the caller's contract that a handle, its arena and scene stay
//! unchanged while they are used, as for every call on a handle.

use crate::abi::{CorayRay, CorayTraceStats};
use crate::carve::{self, Plain, ReadSpans, Span};
use crate::handle::{self, Sealed};
use crate::{guard, CorayStatus};
use coray::{Scene, TraceStats};
use core::ffi::c_void;
use core::mem::{align_of, size_of};

/// One thread's tracer: fill it with `coray_kdtree_tracer`,
/// `coray_bvh_tracer`, `coray_proj_tracer` or `coray_wide_tracer`, then
/// pass it to that family's `_tracer_intersect1` and `_tracer_occluded1`.
/// Written by every call on it: one thread at a time.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CorayTracer {
    /// Opaque to the caller.
    pub opaque: [u64; 32],
}

/// Words of a tracer: the binding's (its check first) and, after them,
/// the running statistics; 7 of its 32 words are free for later fields
/// (the size is the handles', 256 bytes, and part of the ABI).
const BINDING_WORDS: usize = 14;

/// Words a family keeps in its tracers for its view of the structure,
/// computed once by the make call (the kd-tree: its trace box, six `f32`).
pub(crate) const HINT_WORDS: usize = 3;
const TOTALS_AT: usize = BINDING_WORDS;
const _: () = assert!(TOTALS_AT + size_of::<TraceStats>() / 8 <= 32);
const _: () = assert!(size_of::<TraceStats>() == 11 * 8 && align_of::<TraceStats>() == 8);

/// What a tracer's make call checked, as its words keep it.
#[derive(Clone, Copy, Debug, Default)]
struct Binding {
    /// [`Binding::check_of`] over the rest and the tracer's address.
    check: u64,
    /// The handle's kind.
    kind: u64,
    /// The traversal method (kd-trees) or scheme (projection hierarchies).
    mode: u64,
    /// The handle's address and its seal word then.
    handle: usize,
    handle_seal: u64,
    /// The stack's address and bytes.
    stack: usize,
    stack_bytes: usize,
    /// Where an answer may start, `[first, last]` (so that it lies in the
    /// gap the last call that checked one against every buffer found;
    /// empty, `first > last`, until a call does).
    out: (usize, usize),
    /// Where a ray may start, likewise.
    ray: (usize, usize),
    /// The family's words for its view ([`HINT_WORDS`]).
    hint: [u64; HINT_WORDS],
}

impl Binding {
    /// The check word: each other word rotated by its own amount and
    /// folded with xor, with the tracer's address, into a constant. Memory
    /// the make call did not write (zeros, another tracer's copy, damage)
    /// fails it.
    #[inline(always)]
    fn check_of(&self, at: usize) -> u64 {
        let w = self.words();
        let mut c = 0xC0A4_7EAC_E500_0001u64 ^ at as u64;
        for (i, x) in w[1..].iter().enumerate() {
            c ^= x.rotate_left(7 * i as u32 + 3);
        }
        c
    }

    #[inline(always)]
    fn words(&self) -> [u64; BINDING_WORDS] {
        [
            self.check,
            self.kind,
            self.mode,
            self.handle as u64,
            self.handle_seal,
            self.stack as u64,
            self.stack_bytes as u64,
            self.out.0 as u64,
            self.out.1 as u64,
            self.ray.0 as u64,
            self.ray.1 as u64,
            self.hint[0],
            self.hint[1],
            self.hint[2],
        ]
    }

    #[inline(always)]
    fn of_words(w: [u64; BINDING_WORDS]) -> Binding {
        Binding {
            check: w[0],
            kind: w[1],
            mode: w[2],
            handle: w[3] as usize,
            handle_seal: w[4],
            stack: w[5] as usize,
            stack_bytes: w[6] as usize,
            out: (w[7] as usize, w[8] as usize),
            ray: (w[9] as usize, w[10] as usize),
            hint: [w[11], w[12], w[13]],
        }
    }
}

/// Whether `p` is one of the starts `[first, last]` (`first` is at least 1,
/// so never NULL): two compares a call, the subtraction of the object's
/// size made once, by [`starts_in_gap`].
#[inline(always)]
fn starts_in(p: usize, (first, last): (usize, usize)) -> bool {
    p >= first && p <= last
}

/// The starts `[first, last]` of objects of `bytes` that lie in the widest
/// gap around `[p, p + bytes)` meeting none of `spans` (which it must not
/// meet).
#[inline]
fn starts_in_gap(p: usize, bytes: usize, spans: &[Span]) -> (usize, usize) {
    let (lo, hi) = Span::gap_around(p, bytes, spans);
    // `hi` is at least `p + bytes`: no wrap.
    (lo, hi - bytes)
}

/// Makes the tracer at `tracer` for the structure behind `handle` (of
/// `kind`), traced by `mode`, with the stack at `stack`, keeping `hint`'s
/// words for the view (see [`trace`]).
///
/// In order: the handle (null, alignment, seal), `view`'s header checks of
/// its arena over its scene, the stack (null, alignment, at least
/// `stack_len` entries of `I`), the tracer (null, alignment), then neither
/// written buffer (stack, tracer) may overlap the other or anything read
/// (handle, arena, scene arrays). Only then is the tracer written.
///
/// # Safety
/// `handle` is NULL or points to a readable handle; its arena and scene
/// are in place; `stack` is NULL or writable for `stack_bytes`; `tracer`
/// is NULL or writable.
#[allow(clippy::too_many_arguments)]
pub(crate) unsafe fn make<'a, S, I: Plain>(
    tracer: *mut CorayTracer,
    handle: *const [u64; 32],
    kind: u64,
    mode: u64,
    view: impl FnOnce(Sealed<'a>, Scene<'a>) -> Result<S, CorayStatus>,
    stack_len: impl FnOnce(&S) -> usize,
    hint: impl FnOnce(&S) -> [u64; HINT_WORDS],
    stack: *mut c_void,
    stack_bytes: usize,
) -> Result<(), CorayStatus> {
    // SAFETY: forwarded contract; every pointer is checked (null,
    // alignment, size) before it is read, and nothing is written before
    // the overlap check.
    let (h, scene, hint) = unsafe {
        let h = handle::read_unnoted(handle, kind)?;
        let scene = h.scene();
        let s = view(h, scene)?;
        let hint = hint(&s);
        let need = stack_len(&s).max(1);
        carve::check_arena(stack.cast::<u8>())?;
        if stack_bytes > isize::MAX as usize {
            return Err(CorayStatus::InvalidParameter);
        }
        if need
            .checked_mul(size_of::<I>())
            .is_none_or(|b| b > stack_bytes)
        {
            return Err(CorayStatus::ArenaTooSmall);
        }
        carve::check_array(tracer, 1)?;
        (h, scene, hint)
    };
    let [handle_words, arena] = h.spans();
    let [vertices, triangles, spheres, cones] = Span::of_scene(&scene);
    let read = ReadSpans::<8>::new([handle_words, arena, vertices, triangles, spheres, cones]);
    let written = [
        Span::of(stack.cast::<u8>(), stack_bytes),
        Span::of(tracer, size_of::<CorayTracer>()),
    ];
    if carve::overlap(&written, &read) {
        return Err(CorayStatus::InvalidParameter);
    }
    let mut b = Binding {
        check: 0,
        kind,
        mode,
        handle: handle as usize,
        handle_seal: h.seal(),
        stack: stack as usize,
        stack_bytes,
        out: (1, 0),
        ray: (1, 0),
        hint,
    };
    b.check = b.check_of(tracer as usize);
    let mut words = [0u64; 32];
    words[..BINDING_WORDS].copy_from_slice(&b.words());
    // SAFETY: checked non-null and aligned, writable by the contract, and
    // disjoint from everything this call read.
    unsafe { tracer.write(CorayTracer { opaque: words }) };
    Ok(())
}

/// The binding of a tracer the make call filled: null, alignment, check,
/// and of `kind` when given (a tracer of another family is refused).
///
/// # Safety
/// `tracer` is NULL or readable.
#[inline(always)]
unsafe fn binding(tracer: *const CorayTracer, kind: Option<u64>) -> Result<Binding, CorayStatus> {
    carve::check_array(tracer, 1)?;
    // SAFETY: non-null and aligned (checked), readable by the contract;
    // read by value, nothing kept borrowed.
    let b = Binding::of_words(unsafe { tracer.cast::<[u64; BINDING_WORDS]>().read() });
    if b.check != b.check_of(tracer as usize) || kind.is_some_and(|k| k != b.kind) {
        return Err(CorayStatus::InvalidParameter);
    }
    Ok(b)
}

/// Traces `ray` with the tracer at `tracer` (of `kind`) and writes the
/// answer to `out`; adds the call's statistics to the tracer's.
///
/// In order: the tracer ([`binding`]: null, alignment, check word, of
/// `kind`), its handle's seal word (unchanged since the make call), the ray and `out` (null,
/// alignment), then neither may overlap a buffer the call writes (stack,
/// tracer, each other) nor `out` one it reads (handle, arena, scene
/// arrays): places inside the ranges the last such check found are taken
/// as they are, others are checked and the ranges found again. Then
/// `early`, given the hint words the make call kept: an answer the family
/// knows without its structure (a kd-tree's for a ray that misses its box,
/// counted as its traversal counts it) is written as it is. Otherwise
/// `view`'s view of the structure (checked when the tracer was made; given
/// the hint words), its stack need (at most the tracer's stack), and
/// `answer`; a fault it meets gives `CORAY_STATUS_CORRUPT_ARENA` and
/// nothing is written.
///
/// # Safety
/// `tracer` is NULL or points to a writable tracer that no other thread
/// uses during the call; its handle, arena, scene and stack are those of
/// its make call, in place, and (but the stack) unchanged; `ray` is NULL
/// or one readable ray, `out` NULL or one writable `O`.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) unsafe fn trace<'a, S, I: Plain, O>(
    tracer: *mut CorayTracer,
    kind: u64,
    view: impl FnOnce(Sealed<'a>, Scene<'a>, [u64; HINT_WORDS]) -> Result<S, CorayStatus>,
    stack_len: impl FnOnce(&S) -> usize,
    ray: *const CorayRay,
    out: *mut O,
    early: impl FnOnce([u64; HINT_WORDS], &coray::Ray, &mut TraceStats) -> Option<O>,
    answer: impl FnOnce(&S, u64, &coray::Ray, &mut [I], &mut TraceStats) -> Result<O, CorayStatus>,
) -> Result<(), CorayStatus> {
    // SAFETY: forwarded contract (`tracer` NULL or readable).
    let mut b = unsafe { binding(tracer, Some(kind)) }?;
    let handle = b.handle as *const [u64; 32];
    // SAFETY: the make call checked the handle non-null, aligned and
    // sealed; readable by the contract.
    let hw = unsafe { &*handle };
    if hw[0] != b.handle_seal {
        return Err(CorayStatus::InvalidParameter);
    }
    // SAFETY: the handle passed `Sealed::new` for this kind when the
    // tracer was made, and its seal word is unchanged.
    let h = unsafe { Sealed::known(hw) };
    // The scene's slices are cut where they are used (the ranges' check,
    // the view), not on the way of a ray answered early.
    // SAFETY: as `Sealed::scene`: its arrays are in place (contract).
    let scene = || unsafe { h.scene() };
    carve::check_array(ray, 1)?;
    carve::check_array(out, 1)?;
    let (r, o) = (ray as usize, out as usize);
    let (rb, ob) = (size_of::<CorayRay>(), size_of::<O>());
    let apart = r + rb <= o || o + ob <= r;
    // (Null and alignment were checked just above.)
    let placed = starts_in(o, b.out) && starts_in(r, b.ray);
    // Whether the binding's ranges (and so its check word) change: known
    // here, not by comparing the words after (a memcmp call a trace).
    let moved = !(apart && placed);
    if moved {
        let [handle_words, arena] = h.spans();
        let [vertices, triangles, spheres, cones] = Span::of_scene(&scene());
        let stack = Span::of(b.stack as *const u8, b.stack_bytes);
        let own = Span::of(tracer, size_of::<CorayTracer>());
        let out_meets = [
            handle_words,
            arena,
            vertices,
            triangles,
            spheres,
            cones,
            stack,
            own,
        ];
        let read = ReadSpans::<8>::new(out_meets);
        let out_span = Span::of(out, ob);
        let ray_span = Span::of(ray, rb);
        if !apart
            || carve::overlap(&[out_span], &read)
            || carve::overlap(&[ray_span], &ReadSpans::<8>::new([stack, own]))
        {
            return Err(CorayStatus::InvalidParameter);
        }
        b.out = starts_in_gap(o, ob, &out_meets);
        b.ray = starts_in_gap(r, rb, &[stack, own]);
        b.check = b.check_of(tracer as usize);
    }
    // SAFETY: checked non-null and aligned, readable (contract), and
    // written by nothing during the call (it meets neither the stack, the
    // tracer nor `out`: checked above).
    let ray = crate::abi::core_ray(unsafe { &*ray });
    let mut st = TraceStats::default();
    let answer = match early(b.hint, ray, &mut st) {
        Some(a) => a,
        None => {
            // SAFETY: the arena's header and parts passed `view`'s checks
            // when the tracer was made and are unchanged (contract).
            let s = view(h, scene(), b.hint)?;
            let need = stack_len(&s);
            if need > b.stack_bytes / size_of::<I>() {
                return Err(CorayStatus::ArenaTooSmall);
            }
            // SAFETY: the make call checked the stack non-null, 16-aligned,
            // `stack_bytes` long (`need` items fit, just checked) and
            // disjoint from every buffer read (handle, arena, scene) and
            // from the tracer; `ray` and `out` meet it nowhere (checked
            // above); the calling thread owns it (contract).
            let stk: &mut [I] = unsafe { carve::arena_mut(b.stack as *mut u8, 0, need) };
            let a = answer(&s, b.mode, ray, stk, &mut st)?;
            if st.faults > 0 {
                return Err(CorayStatus::CorruptArena);
            }
            a
        }
    };
    let totals = tracer
        .cast::<u64>()
        .wrapping_add(TOTALS_AT)
        .cast::<TraceStats>();
    // SAFETY: the totals' words lie within the tracer (asserted above),
    // 8-aligned; any bits are a valid TraceStats; the tracer is writable
    // (contract) and no reference to it is alive. Its ranges change only
    // with a call that succeeds.
    unsafe {
        let mut t = totals.read();
        t.add(&st);
        totals.write(t);
        if moved {
            tracer.cast::<[u64; BINDING_WORDS]>().write(b.words());
        }
    }
    // SAFETY: checked non-null and aligned, and disjoint from every buffer
    // this call reads or writes.
    unsafe { out.write(answer) };
    Ok(())
}

/// The statistics of every successful call on `tracer` since it was made,
/// summed, into `stats` (its `struct_size` set). Since 1.5.
///
/// Safety: `tracer` NULL or readable; `stats` NULL or writable for its
/// `struct_size`.
#[no_mangle]
pub unsafe extern "C" fn coray_tracer_stats(
    tracer: *const CorayTracer,
    stats: *mut CorayTraceStats,
) -> CorayStatus {
    guard(|| {
        // SAFETY: forwarded contract; both checked before use, read by
        // value.
        unsafe {
            binding(tracer, None)?;
            let out = carve::Out::open(stats, false)?;
            if carve::overlap(
                &[out.span()],
                &ReadSpans::<8>::new([Span::of(tracer, size_of::<CorayTracer>())]),
            ) {
                return Err(CorayStatus::InvalidParameter);
            }
            let totals = tracer
                .cast::<u64>()
                .add(TOTALS_AT)
                .cast::<TraceStats>()
                .read();
            out.write(CorayTraceStats::of(&totals));
        }
        Ok(())
    })
}
