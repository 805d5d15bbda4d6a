//! Turning caller pointers into references and slices: every `unsafe` of
//! coray-ffi that makes one lives here, behind checks of null, alignment,
//! size and overlap. An entry point checks every pointer it will write
//! before it does any work ([`Out`], [`Regions`]), so outputs are written
//! only on success.

use crate::CorayStatus;
use coray::arena::ARENA_ALIGN;
use core::mem::{align_of, size_of};

/// Types that may be viewed in caller memory: `repr(C)`, fields of `u8`,
/// `u32`, `u64`, `f32` (and arrays of them) only, no padding, alignment at most
/// [`ARENA_ALIGN`]. Every bit pattern is then a value, so reading
/// arbitrary caller bytes as `T` is defined (whether the values make a
/// structure is `validate`'s question).
///
/// # Safety
/// Implement only for types with exactly those properties.
pub(crate) unsafe trait Plain: Copy {}

/// C structs that start with `size_t struct_size`, have no field whose
/// bit patterns are not all valid (integers, floats, pointers), and were
/// `SIZE_1_0` bytes long in ABI 1.0.
///
/// # Safety
/// Implement only for `repr(C)` types with exactly those properties.
pub(crate) unsafe trait Versioned: Copy + Default {
    /// The size of the first published version: the least `struct_size`
    /// accepted.
    const SIZE_1_0: usize;
}

// SAFETY (all impls): each type is repr(C) with u64/u32/f32/u8 fields (or
// arrays of them) only; the asserts below prove there is no padding and
// the alignment is at most 16.
unsafe impl Plain for u8 {}
unsafe impl Plain for u32 {}
unsafe impl Plain for f32 {}
unsafe impl Plain for coray::kd::KdNode {}
unsafe impl Plain for coray::kd::KdRopes {}
unsafe impl Plain for coray::kd::KdEvent {}
unsafe impl Plain for coray::kd::KdStackItem {}
unsafe impl Plain for coray::kd::layout::KdArenaHeader {}
unsafe impl Plain for coray::lcts::HistoryRecord {}
unsafe impl Plain for coray::lcts::CornerInfo {}
unsafe impl Plain for coray::lcts::hlcts::HlctsEntry {}
unsafe impl Plain for coray::Aabb {}
unsafe impl Plain for coray::bvh::BvhNode {}
unsafe impl Plain for coray::bvh::BvhStackItem {}
unsafe impl Plain for coray::bvh::layout::BvhArenaHeader {}
unsafe impl Plain for coray::proj::layout::ProjArenaHeader {}
unsafe impl Plain for coray::proj::Rect {}
unsafe impl Plain for coray::wide::WideNode {}
unsafe impl Plain for coray::Corners4 {}
unsafe impl Plain for coray::wide::LeafBlock {}
unsafe impl Plain for coray::wide::WideStackItem {}
unsafe impl Plain for coray::wide::layout::WideArenaHeader {}

const _: () = {
    use coray::kd::*;
    assert!(size_of::<KdNode>() == 8 && align_of::<KdNode>() <= ARENA_ALIGN);
    assert!(size_of::<KdRopes>() == 48);
    assert!(size_of::<KdEvent>() == 8 && align_of::<KdEvent>() <= ARENA_ALIGN);
    assert!(size_of::<KdStackItem>() == 8 && align_of::<KdStackItem>() == 4);
    assert!(size_of::<layout::KdArenaHeader>() == 124);
    assert!(size_of::<coray::Sphere>() == 16 && align_of::<coray::Sphere>() == 4);
    assert!(size_of::<coray::Cone>() == 32 && align_of::<coray::Cone>() == 4);
    assert!(size_of::<coray::lcts::HistoryRecord>() == 8);
    assert!(
        size_of::<coray::lcts::CornerInfo>() == 40 && align_of::<coray::lcts::CornerInfo>() == 4
    );
    assert!(size_of::<coray::lcts::hlcts::HlctsEntry>() == 96);
    assert!(size_of::<coray::Aabb>() == 24 && align_of::<coray::Aabb>() == 4);
    assert!(size_of::<coray::bvh::BvhNode>() == 32 && align_of::<coray::bvh::BvhNode>() == 4);
    assert!(size_of::<coray::bvh::BvhStackItem>() == 8);
    assert!(size_of::<coray::bvh::layout::BvhArenaHeader>() == 124);
    assert!(size_of::<coray::proj::layout::ProjArenaHeader>() == 128);
    assert!(size_of::<coray::proj::Rect>() == 20 && align_of::<coray::proj::Rect>() == 4);
    assert!(size_of::<coray::Corners4>() == 144 && align_of::<coray::Corners4>() == 4);
    assert!(
        size_of::<coray::wide::LeafBlock>() == 160
            && align_of::<coray::wide::LeafBlock>() <= ARENA_ALIGN
    );
    assert!(
        size_of::<coray::wide::WideNode>() == 224
            && align_of::<coray::wide::WideNode>() <= ARENA_ALIGN
    );
    assert!(size_of::<coray::wide::WideStackItem>() == 8);
    assert!(size_of::<coray::wide::layout::WideArenaHeader>() == 64);
};

/// A byte range `[start, end)` that one call reads or writes (its end
/// saturates at the top of memory). An empty range is `(0, 0)`: it meets
/// no range.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Span {
    start: usize,
    end: usize,
}

impl Span {
    /// `bytes` at `p` (the empty span when `bytes` is 0).
    #[inline(always)]
    pub(crate) fn of<T>(p: *const T, bytes: usize) -> Span {
        if bytes == 0 {
            return Span::default();
        }
        let start = p as usize;
        Span {
            start,
            end: start.saturating_add(bytes),
        }
    }

    /// The widest range around `[p, p + bytes)` that meets none of
    /// `spans`, as `(lo, hi)`: `lo` at least 1, so that a place inside it
    /// is never NULL. `[p, p + bytes)` must meet none of them.
    #[inline]
    pub(crate) fn gap_around(p: usize, bytes: usize, spans: &[Span]) -> (usize, usize) {
        let (mut lo, mut hi) = (1usize, usize::MAX);
        for s in spans.iter().filter(|s| s.end > s.start) {
            debug_assert!(s.end <= p || s.start >= p.saturating_add(bytes));
            if s.end <= p {
                lo = lo.max(s.end);
            } else {
                hi = hi.min(s.start);
            }
        }
        (lo, hi)
    }

    /// The four arrays of `s`.
    #[inline(always)]
    pub(crate) fn of_scene(s: &coray::Scene) -> [Span; 4] {
        [
            Span::of(s.vertices.as_ptr(), size_of_val(s.vertices)),
            Span::of(s.triangles.as_ptr(), size_of_val(s.triangles)),
            Span::of(s.spheres.as_ptr(), size_of_val(s.spheres)),
            Span::of(s.cones.as_ptr(), size_of_val(s.cones)),
        ]
    }
}

/// The spans a call reads, as two arrays (starts, ends; unused entries
/// empty), so that one written span is tested against all of them on
/// SIMD lanes.
#[derive(Clone, Copy)]
pub(crate) struct ReadSpans<const N: usize> {
    start: [usize; N],
    end: [usize; N],
}

impl<const N: usize> ReadSpans<N> {
    /// `spans` and, past them, empty entries.
    #[inline(always)]
    pub(crate) fn new<const K: usize>(spans: [Span; K]) -> ReadSpans<N> {
        let mut r = ReadSpans {
            start: [0; N],
            end: [0; N],
        };
        for (i, s) in spans.iter().enumerate().take(N) {
            r.start[i] = s.start;
            r.end[i] = s.end;
        }
        r
    }
}

/// Whether a `written` span meets a `read` one or another written one
/// (reads may share memory with each other). Branch-free over the pairs.
/// When every end lies in the lower half of the address space (always,
/// for a 64-bit process's addresses), "a < b" is the top bit of `a - b`:
/// a pair is two subtractions and an AND, ORed over all pairs and tested
/// once; otherwise every pair is compared.
#[inline(always)]
pub(crate) fn overlap<const N: usize>(written: &[Span], read: &ReadSpans<N>) -> bool {
    let top = written.iter().fold(0, |o, w| o | w.end) | read.end.iter().fold(0, |o, e| o | e);
    const TOP: u32 = usize::BITS - 1;
    if top >> TOP == 0 {
        let signs = any_pair(written, read, |w, s, e| {
            w.start.wrapping_sub(e) & s.wrapping_sub(w.end)
        });
        signs >> TOP != 0
    } else {
        any_pair(written, read, |w, s, e| {
            ((w.start < e) & (s < w.end)) as usize
        }) != 0
    }
}

/// OR of `meets(w, start, end)` over every written span `w` and every read
/// or later written span.
#[inline(always)]
fn any_pair<const N: usize>(
    written: &[Span],
    read: &ReadSpans<N>,
    meets: impl Fn(Span, usize, usize) -> usize,
) -> usize {
    let mut o = 0;
    for (i, w) in written.iter().enumerate() {
        o |= read
            .start
            .iter()
            .zip(&read.end)
            .fold(0, |o, (&s, &e)| o | meets(*w, s, e));
        for x in &written[i + 1..] {
            o |= meets(*w, x.start, x.end);
        }
    }
    o
}

/// The byte ranges one call reads and writes: a written range may overlap
/// no other range of the call (reads may share memory with each other).
#[derive(Clone, Copy)]
pub(crate) struct Regions {
    read: ReadSpans<READS>,
    written: [Span; WRITES],
    reads: usize,
    writes: usize,
    /// More ranges were added than the lists hold: `check` refuses.
    overflow: bool,
}

/// Ranges one call may read and write (the busiest entry points read 9
/// and write 4).
const READS: usize = 12;
const WRITES: usize = 6;

impl Regions {
    pub(crate) fn new() -> Regions {
        Regions {
            read: ReadSpans::new::<0>([]),
            written: [Span::default(); WRITES],
            reads: 0,
            writes: 0,
            overflow: false,
        }
    }

    /// Adds `bytes` at `p` (nothing for an empty range).
    #[inline(always)]
    pub(crate) fn add<T>(&mut self, p: *const T, bytes: usize, written: bool) -> &mut Regions {
        self.add_span(Span::of(p, bytes), written)
    }

    /// Adds `span` (nothing for an empty one).
    #[inline(always)]
    fn add_span(&mut self, span: Span, written: bool) -> &mut Regions {
        if span == Span::default() {
            return self;
        }
        if written {
            match self.written.get_mut(self.writes) {
                Some(w) => *w = span,
                None => self.overflow = true,
            }
            self.writes += 1;
        } else {
            match (
                self.read.start.get_mut(self.reads),
                self.read.end.get_mut(self.reads),
            ) {
                (Some(s), Some(e)) => (*s, *e) = (span.start, span.end),
                _ => self.overflow = true,
            }
            self.reads += 1;
        }
        self
    }

    /// Adds the four arrays of `s` as read.
    #[inline(always)]
    pub(crate) fn add_scene(&mut self, s: &coray::Scene) -> &mut Regions {
        for span in Span::of_scene(s) {
            self.add_span(span, false);
        }
        self
    }

    /// `InvalidParameter` when a written range overlaps another.
    #[inline(always)]
    pub(crate) fn check(&self) -> Result<(), CorayStatus> {
        if self.overflow {
            return Err(CorayStatus::InternalError);
        }
        if overlap(&self.written[..self.writes], &self.read) {
            return Err(CorayStatus::InvalidParameter);
        }
        Ok(())
    }
}

/// Checks an arena, scratch or stack pointer: not null, 16-byte aligned.
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
pub(crate) unsafe fn arena_mut<'a, T: Plain>(
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
/// As [`arena_mut`], for reads, with nobody writing the range during `'a`.
pub(crate) unsafe fn arena_ref<'a, T: Plain>(
    base: *const u8,
    offset: usize,
    count: usize,
) -> &'a [T] {
    debug_assert!(offset.is_multiple_of(ARENA_ALIGN));
    // SAFETY: as in arena_mut; shared access only.
    unsafe { core::slice::from_raw_parts(base.add(offset).cast::<T>(), count) }
}

/// Zeroes `bytes` bytes at `base`: a build leaves no byte of the caller's
/// in the part of the arena its layout covers.
///
/// # Safety
/// `base` is valid for writes of `bytes` bytes, lent exclusively.
pub(crate) unsafe fn zero(base: *mut u8, bytes: usize) {
    // SAFETY: the caller's contract above.
    unsafe { core::ptr::write_bytes(base, 0, bytes) }
}

/// Checks an array of `count` `T`s at `p`: not null unless empty, aligned,
/// at most `isize::MAX` bytes; returns its byte length.
#[inline]
pub(crate) fn check_array<T>(p: *const T, count: usize) -> Result<usize, CorayStatus> {
    if count == 0 {
        return Ok(0);
    }
    if p.is_null() {
        return Err(CorayStatus::NullPointer);
    }
    if !(p as usize).is_multiple_of(align_of::<T>()) {
        return Err(CorayStatus::Misaligned);
    }
    match count.checked_mul(size_of::<T>()) {
        Some(b) if b <= isize::MAX as usize => Ok(b),
        _ => Err(CorayStatus::InvalidParameter),
    }
}

/// A caller's input array of `count` elements (NULL is fine when `count`
/// is 0).
///
/// # Safety
/// When `count > 0`, `p` points to `count` readable elements that stay
/// unchanged during `'a`.
#[inline]
pub(crate) unsafe fn input<'a, T>(p: *const T, count: usize) -> Result<&'a [T], CorayStatus> {
    check_array(p, count)?;
    if count == 0 {
        return Ok(&[]);
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
#[inline]
pub(crate) unsafe fn output<'a, T>(p: *mut T, count: usize) -> Result<&'a mut [T], CorayStatus> {
    check_array(p, count)?;
    if count == 0 {
        return Ok(&mut []);
    }
    // SAFETY: non-null, aligned, size within isize::MAX (checked above);
    // exclusive for 'a by the caller's contract.
    Ok(unsafe { core::slice::from_raw_parts_mut(p, count) })
}

/// Reads a versioned input struct: at least its 1.0 size, fields past the
/// caller's `struct_size` (a struct from an older header) read as zero,
/// bytes past ours (a newer header) must be zero.
///
/// # Safety
/// `p` is NULL or points to a readable struct of `struct_size` bytes.
pub(crate) unsafe fn read<T: Versioned>(p: *const T) -> Result<T, CorayStatus> {
    if p.is_null() {
        return Err(CorayStatus::NullPointer);
    }
    if !(p as usize).is_multiple_of(align_of::<T>()) {
        return Err(CorayStatus::Misaligned);
    }
    // SAFETY: non-null, aligned; every struct's first field is its size_t
    // struct_size, readable by the contract.
    let declared = unsafe { p.cast::<usize>().read() };
    if declared < T::SIZE_1_0 || declared > isize::MAX as usize {
        return Err(CorayStatus::InvalidParameter);
    }
    let ours = size_of::<T>();
    let bytes = p.cast::<u8>();
    if declared > ours {
        // SAFETY: the caller's struct has `declared` readable bytes.
        let tail = unsafe { core::slice::from_raw_parts(bytes.add(ours), declared - ours) };
        if tail.iter().any(|&b| b != 0) {
            return Err(CorayStatus::InvalidParameter);
        }
    }
    let mut v = T::default();
    // SAFETY: copies min(declared, ours) readable bytes into a T; every
    // bit pattern is a valid T (`Versioned`), the rest stays zero/default.
    unsafe {
        core::ptr::copy_nonoverlapping(bytes, (&mut v as *mut T).cast::<u8>(), declared.min(ours))
    };
    Ok(v)
}

/// A checked place for one output struct, written only once the call
/// succeeds (or never, when the caller passed NULL and may).
pub(crate) struct Out<T> {
    p: *mut T,
    bytes: usize,
}

impl<T: Versioned> Out<T> {
    /// Checks `p` (NULL gives `NullPointer` unless `optional`): aligned,
    /// `struct_size` at least the 1.0 size; notes its bytes in `regions`.
    ///
    /// # Safety
    /// `p` is NULL or points to a writable struct of `struct_size` bytes.
    pub(crate) unsafe fn new(
        p: *mut T,
        optional: bool,
        regions: &mut Regions,
    ) -> Result<Out<T>, CorayStatus> {
        // SAFETY: forwarded contract.
        let out = unsafe { Out::open(p, optional)? };
        regions.add(p, out.bytes, true);
        Ok(out)
    }

    /// [`Out::new`] without a region list: the caller checks
    /// [`Out::span`] for overlaps itself.
    ///
    /// # Safety
    /// As [`Out::new`].
    #[inline(always)]
    pub(crate) unsafe fn open(p: *mut T, optional: bool) -> Result<Out<T>, CorayStatus> {
        if p.is_null() {
            return if optional {
                Ok(Out { p, bytes: 0 })
            } else {
                Err(CorayStatus::NullPointer)
            };
        }
        if !(p as usize).is_multiple_of(align_of::<T>()) {
            return Err(CorayStatus::Misaligned);
        }
        // SAFETY: non-null, aligned, starts with a readable size_t.
        let declared = unsafe { p.cast::<usize>().read() };
        if declared < T::SIZE_1_0 || declared > isize::MAX as usize {
            return Err(CorayStatus::InvalidParameter);
        }
        Ok(Out {
            p,
            bytes: declared.min(size_of::<T>()),
        })
    }

    /// The bytes `write` will write (empty for NULL).
    #[inline(always)]
    pub(crate) fn span(&self) -> Span {
        Span::of(self.p, self.bytes)
    }

    /// Writes `v` (the caller's `struct_size` bytes of it; `struct_size`
    /// itself is left as the caller set it).
    pub(crate) fn write(self, v: T) {
        if self.p.is_null() {
            return;
        }
        let src = (&v as *const T).cast::<u8>();
        let w = core::mem::size_of::<usize>();
        // SAFETY: `p` was checked writable for `bytes` >= SIZE_1_0 > w
        // bytes by `new`, disjoint from every other buffer of the call
        // (`Regions`); `v` is a T of at least `bytes` bytes.
        unsafe {
            core::ptr::copy_nonoverlapping(src.add(w), self.p.cast::<u8>().add(w), self.bytes - w)
        };
    }
}

/// A checked place for one plain output value (a `size_t`, a `uint8_t`).
pub(crate) struct OutValue<T> {
    p: *mut T,
}

impl<T: Copy> OutValue<T> {
    /// Checks `p`: NULL is fine when `optional` (nothing is written then).
    pub(crate) fn new(
        p: *mut T,
        optional: bool,
        regions: &mut Regions,
    ) -> Result<OutValue<T>, CorayStatus> {
        if p.is_null() {
            return if optional {
                Ok(OutValue { p })
            } else {
                Err(CorayStatus::NullPointer)
            };
        }
        check_array(p, 1)?;
        regions.add(p, size_of::<T>(), true);
        Ok(OutValue { p })
    }

    /// Writes `v`.
    pub(crate) fn write(self, v: T) {
        if !self.p.is_null() {
            // SAFETY: checked non-null and aligned by `new`, writable by
            // the caller's contract, disjoint from the call's other buffers.
            unsafe { self.p.write(v) }
        }
    }
}

/// The core's view of a caller scene, with its arrays noted in `regions`.
///
/// # Safety
/// `s` is NULL or points to a `CorayScene` whose arrays hold the counts it
/// gives and stay unchanged during `'a`.
pub(crate) unsafe fn scene<'a>(
    s: *const crate::CorayScene,
    regions: &mut Regions,
) -> Result<coray::Scene<'a>, CorayStatus> {
    // SAFETY: forwarded contract.
    let s = unsafe { read(s)? };
    // SAFETY (four calls): each array pointer and its element count come
    // from the caller's scene, which promises them readable; [f32; 3],
    // [u32; 3], Sphere and Cone are repr(C) runs of 4-byte fields, the C
    // layout.
    let scene = unsafe {
        coray::Scene {
            vertices: input(s.vertices.cast::<[f32; 3]>(), s.vertex_count)?,
            triangles: input(s.indices.cast::<[u32; 3]>(), s.triangle_count)?,
            spheres: input(s.spheres.cast::<coray::Sphere>(), s.sphere_count)?,
            cones: input(s.cones.cast::<coray::Cone>(), s.cone_count)?,
        }
    };
    regions.add_scene(&scene);
    Ok(scene)
}

/// A caller's traversal stack of `bytes` bytes as `need` entries of `T`
/// (none needed, as for a call with no rays: any pointer, even NULL).
///
/// # Safety
/// `p` is NULL or valid for writes of `bytes` bytes, lent exclusively.
#[inline(always)]
pub(crate) unsafe fn stack<'a, T: Plain>(
    p: *mut core::ffi::c_void,
    bytes: usize,
    need: usize,
    regions: &mut Regions,
) -> Result<&'a mut [T], CorayStatus> {
    // SAFETY: forwarded contract.
    let s: &mut [T] = unsafe { stack_unnoted(p, bytes, need)? };
    regions.add(s.as_ptr(), size_of_val(s), true);
    Ok(s)
}

/// [`stack`] without a region list: the caller checks its span for
/// overlaps itself.
///
/// # Safety
/// As [`stack`].
#[inline(always)]
pub(crate) unsafe fn stack_unnoted<'a, T: Plain>(
    p: *mut core::ffi::c_void,
    bytes: usize,
    need: usize,
) -> Result<&'a mut [T], CorayStatus> {
    if need == 0 {
        return Ok(&mut []);
    }
    let base = p.cast::<u8>();
    check_arena(base)?;
    let need_bytes = need
        .checked_mul(size_of::<T>())
        .ok_or(CorayStatus::ArenaTooSmall)?;
    if bytes < need_bytes {
        return Err(CorayStatus::ArenaTooSmall);
    }
    // SAFETY: aligned (checked), `need_bytes <= bytes` writable bytes lent
    // exclusively by the caller.
    Ok(unsafe { arena_mut(base, 0, need) })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn written_regions_may_not_overlap() {
        let buf = [0u8; 64];
        let p = buf.as_ptr();
        let mut r = Regions::new();
        r.add(p, 16, false).add(p.wrapping_add(8), 16, false);
        assert!(r.check().is_ok(), "reads may share memory");
        r.add(p.wrapping_add(20), 4, true);
        assert!(r.check().is_err());
        let mut r = Regions::new();
        r.add(p, 16, true).add(p.wrapping_add(16), 16, true);
        assert!(r.check().is_ok(), "touching is not overlapping");
        r.add(p, 0, true);
        assert!(r.check().is_ok(), "an empty range overlaps nothing");
        r.add(p.wrapping_add(31), 2, true);
        assert!(r.check().is_err(), "two written ranges overlap");
        let mut r = Regions::new();
        r.add(p.wrapping_add(40), 8, true).add(p, 64, false);
        assert!(
            r.check().is_err(),
            "a read added after the write is compared too"
        );
        let mut r = Regions::new();
        r.add(usize::MAX as *const u8, 8, true).add(p, 8, false);
        assert!(r.check().is_ok(), "a range at the top of memory saturates");
    }

    #[test]
    fn more_regions_than_the_lists_hold_are_refused() {
        let buf = [0u8; 64];
        let mut r = Regions::new();
        for i in 0..READS {
            r.add(buf.as_ptr().wrapping_add(i), 1, false);
        }
        for i in 0..WRITES {
            r.add(buf.as_ptr().wrapping_add(32 + i), 1, true);
        }
        assert!(r.check().is_ok());
        let (mut reads, mut writes) = (r, r);
        reads.add(buf.as_ptr(), 1, false);
        assert_eq!(reads.check(), Err(CorayStatus::InternalError));
        writes.add(buf.as_ptr().wrapping_add(48), 1, true);
        assert_eq!(writes.check(), Err(CorayStatus::InternalError));
    }

    #[test]
    fn both_overlap_tests_agree_on_every_pair() {
        // Spans over 0..8 (and at the top of memory, where only the exact
        // test runs): the sign-bit test and the comparisons agree.
        let spans = |base: usize| {
            let mut v = std::vec![Span::default()];
            for a in 0..8 {
                for b in a + 1..=8 {
                    v.push(Span {
                        start: base + a,
                        end: base + b,
                    });
                }
            }
            v
        };
        for base in [16usize, usize::MAX - 8] {
            for &w in &spans(base) {
                for &r in &spans(base) {
                    let want = w != Span::default()
                        && r != Span::default()
                        && w.start < r.end
                        && r.start < w.end;
                    let read = ReadSpans::<3>::new([r]);
                    assert_eq!(overlap(&[w], &read), want, "{w:?} {r:?}");
                    assert_eq!(overlap(&[w, r], &ReadSpans::<2>::new([])), want);
                }
            }
        }
    }
}
