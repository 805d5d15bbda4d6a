//! `coray_kdtree_*`: SAH kd-trees. Parameters, requirements, build, open,
//! info, validate, intersect, occluded. (Image casting and patch
//! visibility over a kd-tree are in `cast.rs`.)

use crate::abi::*;
use crate::carve::{self, check_arena, Out, OutValue, Regions, Versioned};
use crate::handle::{self, Handle, Sealed, KIND_KD};
use crate::one_ray::one_ray;
use crate::tracer::{self, CorayTracer};
use crate::{guard, CorayKdRunJobs, CorayKdTree, CorayStatus};
use coray::kd::layout::{KdArenaHeader, KdArenaLayout, KdScratchLayout, KD_HEADER_BYTES};
use coray::kd::{
    self, KdNode, KdRopes, KdStackItem, KdTree, Traversal, KD_STACK_LEN, PACKET_LANES,
};
use coray::limits::MAX_PRIMS;
use coray::{Accel, TraceStats};
use core::ffi::c_void;
use core::mem::size_of;

/// A kd-tree build preset: `CORAY_KD_PRESET_AUTO` or `CORAY_KD_PRESET_PAPER`.
pub type CorayKdPreset = u32;
/// SAH-driven termination, depth bound from N. The default.
pub const CORAY_KD_PRESET_AUTO: CorayKdPreset = 0;
/// The LCTS paper's settings: depth 16, leaves of at most 2 objects.
pub const CORAY_KD_PRESET_PAPER: CorayKdPreset = 1;

/// How rays walk a kd-tree: `CORAY_TRAVERSAL_HIERARCHICAL`,
/// `CORAY_TRAVERSAL_ROPES` or `CORAY_TRAVERSAL_PACKETS` (all give the same
/// hits).
pub type CorayTraversal = u32;
/// Stack traversal (Havran's TA_B^rec).
pub const CORAY_TRAVERSAL_HIERARCHICAL: CorayTraversal = 0;
/// Leaf to leaf by ropes.
pub const CORAY_TRAVERSAL_ROPES: CorayTraversal = 1;
/// Array calls trace groups of 8 consecutive rays that move alike (a tile
/// of camera rays, shadow rays from a tile towards one light) as one
/// packet, testing each primitive against 8 rays at once; other groups
/// and one-ray calls are traced hierarchically. A library built without
/// the `packets` feature (the embedded build) traces every ray
/// hierarchically here: the same hits, about 100 KiB less code.
pub const CORAY_TRAVERSAL_PACKETS: CorayTraversal = 2;

/// Bytes of the traversal stack every kd-tree trace and cast takes.
pub const CORAY_KDTREE_STACK_BYTES: usize = 4608;
const _: () = assert!(CORAY_KDTREE_STACK_BYTES == KD_STACK_LEN * size_of::<KdStackItem>());

/// Parameters of a kd-tree build. Get them from `coray_kdtree_params_default`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CorayKdParams {
    /// `sizeof(CorayKdParams)`.
    pub struct_size: usize,
    /// Deepest leaf; 0 derives it from N as round(8 + 1.3 log2 N). At most 60.
    pub max_depth: u32,
    /// A node with at most this many primitives becomes a leaf.
    pub leaf_size: u32,
    /// 1: stop where no split beats the leaf by the SAH; 0: split down to
    /// `leaf_size` or `max_depth`.
    pub sah_termination: u32,
    /// Ideal references per primitive (1 to 64): sets the ideal arena size.
    pub refs_per_prim: u32,
    /// SAH cost of a traversal step (> 0; Wald and Havran: 15).
    pub cost_traversal: f32,
    /// SAH cost of a ray-primitive test (> 0; Wald and Havran: 20).
    pub cost_intersection: f32,
    /// Cost factor of a split with an empty side, in (0, 1] (0.8).
    pub empty_bonus: f32,
    /// 1: the tree keeps no ropes (a box and six links per leaf, 48 bytes):
    /// rope traversal then walks hierarchically (same hits), and the casts
    /// and patch queries that walk ropes return `CORAY_STATUS_NO_ROPES`.
    /// 0: ropes. `CORAY_KD_PRESET_AUTO` sets 1, `_PAPER` 0. Since 1.2.
    /// 2 (since 1.5): no ropes, and a compact tree for small targets: the
    /// empty leaves that cuts of empty space make beside a full child are
    /// left out too (8 bytes each; `auto`'s trees are 16-25% smaller on
    /// most scenes), and traces decode which child a node left out (a few
    /// percent slower); the same hits, leaves and statistics.
    pub omit_ropes: u32,
    /// Threads that `coray_kdtree_build_jobs`' runner will run the jobs on
    /// (0: not known, the default). The build's top is split until each
    /// job holds about that fraction of the primitives (the whole tree for
    /// 1 thread, a half for 2, down to a sixteenth; a quarter when not
    /// known), so that two threads wait less on the top and many find jobs
    /// enough. Without a runner (`coray_kdtree_build`) the build is one
    /// job whatever it says. The tree is the same bytes whatever it says.
    /// Since 1.4.
    pub job_threads: u32,
    /// What a reference costs a split, in ray-primitive tests per ray
    /// through the scene's box (0 or more, finite): a split that adds `k`
    /// references (its straddling primitives, referenced on both sides)
    /// must save `k` times this many tests, scaled from the scene's box to
    /// the node's by their areas. 0: the plain SAH (`_PAPER`, and a struct
    /// from a header before 1.6); `CORAY_KD_PRESET_AUTO`: 1e-4, which keeps
    /// long thin triangles from being cut without end (SPD gears: 3.9
    /// references per primitive instead of 26). Since 1.6.
    pub cost_reference: f32,
}

// On 64-bit targets the 1.2 field took the 1.0 struct's tail padding (40
// bytes either way), 1.4's grew it to 48 and 1.6's took its padding; on
// 32-bit ones the struct grew from 32 to 36 bytes, then to 40 and 44.
const _: () = assert!(size_of::<CorayKdParams>() == 48 || size_of::<usize>() != 8);

/// What a built kd-tree holds, from `coray_kdtree_info` (O(1)).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CorayKdTreeInfo {
    /// `sizeof(CorayKdTreeInfo)`.
    pub struct_size: usize,
    /// Nodes stored, interior and leaf (a compact tree's node 1 is the one
    /// empty leaf the leaves it left out read as: its single leaf tree has
    /// 2 nodes).
    pub node_count: u32,
    /// Leaves.
    pub leaf_count: u32,
    /// Primitive references in leaves.
    pub ref_count: u32,
    /// Depth of the deepest leaf.
    pub depth: u32,
    /// Primitives in the tree (the scene's, less the degenerate ones).
    pub valid_prim_count: u32,
    /// 1 when room ran out and the build stopped splitting early.
    pub truncated: u32,
    /// Bytes of the arena the tree's layout covers, from its start: what
    /// a copy of the arena must hold. `coray_kdtree_build` packs the tree
    /// into exactly what it uses, so after a build this is all the caller
    /// needs to keep (shrink the arena to it, or copy it).
    pub arena_bytes_used: usize,
    /// Bytes of traversal stack every trace takes (`CORAY_KDTREE_STACK_BYTES`).
    pub stack_bytes: usize,
    /// Lower corner of the scene box.
    pub bounds_min: [f32; 3],
    /// Upper corner of the scene box.
    pub bounds_max: [f32; 3],
}

// SAFETY (both): repr(C), size_t struct_size first, integer and float
// fields only; as first published.
unsafe impl Versioned for CorayKdParams {
    // 1.0 ended at `empty_bonus`, padded to size_t's alignment.
    const SIZE_1_0: usize =
        core::mem::offset_of!(CorayKdParams, omit_ropes).next_multiple_of(align_of::<usize>());
}
unsafe impl Versioned for CorayKdTreeInfo {
    const SIZE_1_0: usize = size_of::<Self>();
}

/// The parameters of `preset` with `struct_size` set; an unknown preset
/// gives `struct_size` 0, which every call refuses.
#[no_mangle]
pub extern "C" fn coray_kdtree_params_default(preset: CorayKdPreset) -> CorayKdParams {
    let (p, size) = match preset {
        CORAY_KD_PRESET_AUTO => (kd::KdParams::auto(), size_of::<CorayKdParams>()),
        CORAY_KD_PRESET_PAPER => (kd::KdParams::paper(), size_of::<CorayKdParams>()),
        _ => (kd::KdParams::auto(), 0),
    };
    CorayKdParams {
        struct_size: size,
        max_depth: p.max_depth,
        leaf_size: p.leaf_size,
        sah_termination: p.sah_termination as u32,
        refs_per_prim: p.refs_per_prim,
        cost_traversal: p.cost_traversal,
        cost_intersection: p.cost_intersection,
        empty_bonus: p.empty_bonus,
        omit_ropes: if p.compact { 2 } else { !p.ropes as u32 },
        job_threads: 0,
        cost_reference: p.cost_reference,
    }
}

/// A `CorayKdTreeInfo` to fill, `struct_size` set.
#[no_mangle]
pub extern "C" fn coray_kdtree_info_default() -> CorayKdTreeInfo {
    CorayKdTreeInfo {
        struct_size: size_of::<CorayKdTreeInfo>(),
        ..Default::default()
    }
}

impl CorayKdParams {
    fn to_core(self) -> Result<kd::KdParams, CorayStatus> {
        if self.sah_termination > 1 || self.omit_ropes > 2 {
            return Err(CorayStatus::InvalidParameter);
        }
        let p = kd::KdParams {
            max_depth: self.max_depth,
            leaf_size: self.leaf_size,
            sah_termination: self.sah_termination == 1,
            cost_traversal: self.cost_traversal,
            cost_intersection: self.cost_intersection,
            empty_bonus: self.empty_bonus,
            cost_reference: self.cost_reference,
            refs_per_prim: self.refs_per_prim,
            ropes: self.omit_ropes == 0,
            compact: self.omit_ropes == 2,
        };
        p.check()?;
        Ok(p)
    }
}

fn traversal(t: CorayTraversal) -> Result<Traversal, CorayStatus> {
    match t {
        CORAY_TRAVERSAL_HIERARCHICAL => Ok(Traversal::Hierarchical),
        CORAY_TRAVERSAL_ROPES => Ok(Traversal::Ropes),
        CORAY_TRAVERSAL_PACKETS => Ok(Traversal::Packets),
        _ => Err(CorayStatus::InvalidParameter),
    }
}

/// Minimum and ideal layouts for `n` primitives: tree arena and scratch.
struct Sizes {
    min: KdArenaLayout,
    ideal_bytes: usize,
    scratch_min: KdScratchLayout,
    scratch_ideal: KdScratchLayout,
    ideal: kd::KdRequirements,
}

fn sizes(n: usize, p: &kd::KdParams) -> Result<Sizes, CorayStatus> {
    let too_many = CorayStatus::TooManyPrimitives;
    if n >= MAX_PRIMS {
        return Err(too_many);
    }
    let (min, ideal) = (kd::min_requirements(n, p), kd::requirements(n, p));
    let min_layout = KdArenaLayout::of(&min).ok_or(too_many)?;
    // The ideal may pass 4 GiB: a build then takes what an arena holds.
    let ideal_bytes =
        KdArenaLayout::of(&ideal).map_or(coray::limits::MAX_ARENA_BYTES, |l| l.total_bytes);
    Ok(Sizes {
        min: min_layout,
        ideal_bytes,
        scratch_min: KdScratchLayout::of(&min).ok_or(too_many)?,
        scratch_ideal: KdScratchLayout::of(&ideal)
            .or_else(|| KdScratchLayout::of(&min))
            .ok_or(too_many)?,
        ideal,
    })
}

/// Arena, scratch and stack sizes for a tree over `prim_count` primitives.
///
/// Safety: `params` and `out` are NULL or valid pointers to their types.
#[no_mangle]
pub unsafe extern "C" fn coray_kdtree_requirements(
    prim_count: usize,
    params: *const CorayKdParams,
    out: *mut CorayRequirements,
) -> CorayStatus {
    guard(|| {
        let mut regions = Regions::new();
        // SAFETY: the caller passes valid pointers or NULL.
        let (p, out) = unsafe {
            (
                carve::read(params)?.to_core()?,
                Out::new(out, false, &mut regions)?,
            )
        };
        let s = sizes(prim_count, &p)?;
        out.write(CorayRequirements {
            struct_size: 0,
            arena_min_bytes: s.min.total_bytes,
            arena_bytes: s.ideal_bytes,
            scratch_min_bytes: s.scratch_min.total_bytes,
            scratch_bytes: s.scratch_ideal.total_bytes,
            stack_bytes: CORAY_KDTREE_STACK_BYTES,
        });
        Ok(())
    })
}

/// Builds an SAH kd-tree over `scene` into `arena`, using `scratch` (free
/// again when this returns).
///
/// Both are 16-byte aligned and must not overlap each other or the scene.
/// Any arena from `arena_min_bytes` up works: with less than `arena_bytes`
/// the build stops splitting where room runs out (`truncated` in the info).
/// On `CORAY_STATUS_ARENA_TOO_SMALL`, `*needed_bytes` (if not NULL)
/// receives the minimum size of the arena or scratch that was too small.
/// The build lays out as much room as `arena_bytes` allows (up to
/// `arena_bytes` of `coray_kdtree_requirements`) and writes all of it:
/// the finished tree is packed at the arena's start, in the
/// `arena_bytes_used` bytes `coray_kdtree_info` reports, and the rest of
/// the room is zeroed (no byte of the caller's is left in it: two builds
/// of one scene with one set of parameters give the same bytes). Bytes
/// past the room are not touched. Keep only the first `arena_bytes_used`
/// bytes (shrink the arena, or copy them) and open them there.
///
/// The tree stores primitive indices: trace it with the same scene,
/// unchanged. The arena holds no pointer, so it may be copied, saved and
/// loaded at any 16-byte aligned address and opened there.
///
/// Safety: every pointer is NULL or valid for its documented size; the
/// arenas are not read or written by anyone else during the call.
#[no_mangle]
pub unsafe extern "C" fn coray_kdtree_build(
    scene: *const CorayScene,
    params: *const CorayKdParams,
    arena: *mut c_void,
    arena_bytes: usize,
    scratch: *mut c_void,
    scratch_bytes: usize,
    needed_bytes: *mut usize,
) -> CorayStatus {
    // SAFETY: the caller's contract is coray_kdtree_build_jobs' with no runner.
    unsafe {
        coray_kdtree_build_jobs(
            scene,
            params,
            arena,
            arena_bytes,
            scratch,
            scratch_bytes,
            needed_bytes,
            None,
            core::ptr::null_mut(),
        )
    }
}

/// `coray_kdtree_build`, its work shared with the caller's threads: the
/// build does the top of the tree, then calls `run_jobs(ctx, job_count,
/// flags_bytes, run_job, jobs)` (see `CorayKdRunJobs`), which runs the
/// jobs on any threads and returns when they are done, and finishes the
/// tree. The arena's bytes are exactly those `coray_kdtree_build` writes,
/// whatever ran the jobs; each thread brings `flags_bytes` bytes of its
/// own (the primitive count). A tree the room truncates is built in one
/// pass after the jobs, on this thread. `run_jobs` NULL: the build runs
/// its jobs itself, as `coray_kdtree_build` does.
///
/// Safety: as `coray_kdtree_build`; `run_jobs` keeps its contract.
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn coray_kdtree_build_jobs(
    scene: *const CorayScene,
    params: *const CorayKdParams,
    arena: *mut c_void,
    arena_bytes: usize,
    scratch: *mut c_void,
    scratch_bytes: usize,
    needed_bytes: *mut usize,
    run_jobs: CorayKdRunJobs,
    ctx: *mut c_void,
) -> CorayStatus {
    guard(|| {
        let mut regions = Regions::new();
        // SAFETY: the caller passes valid scene and params pointers or NULL.
        let (scene, c) = unsafe { (carve::scene(scene, &mut regions)?, carve::read(params)?) };
        // Without a runner every job runs here: one job, the whole tree.
        let threads = if run_jobs.is_some() {
            c.job_threads as usize
        } else {
            1
        };
        let p = c.to_core()?;
        let needed = OutValue::new(needed_bytes, true, &mut regions)?;
        let (base, sbase) = (arena.cast::<u8>(), scratch.cast::<u8>());
        check_arena(base)?;
        check_arena(sbase)?;
        let n = scene.prim_count();
        let s = sizes(n, &p)?;
        let min = kd::min_requirements(n, &p);
        let fit = arena_bytes.min(coray::limits::MAX_ARENA_BYTES);
        let Some(layout) = KdArenaLayout::fit(fit, &min, &s.ideal) else {
            needed.write(s.min.total_bytes);
            return Err(CorayStatus::ArenaTooSmall);
        };
        let Some(sl) = KdScratchLayout::fit(scratch_bytes, n, min.events) else {
            needed.write(s.scratch_min.total_bytes);
            return Err(CorayStatus::ArenaTooSmall);
        };
        regions
            .add(base, layout.total_bytes, true)
            .add(sbase, sl.total_bytes, true)
            .check()?;
        scene.check()?;
        let c = &layout.counts;
        // SAFETY: both arenas passed check_arena; the layouts lie within
        // arena_bytes and scratch_bytes (fit() checked) and their parts do
        // not overlap each other (layout formulas) nor across arenas or
        // with the scene (Regions); the caller lends the arenas exclusively.
        let (storage, scratch) = unsafe {
            carve::zero(base, layout.total_bytes);
            (
                kd::KdStorage {
                    nodes: carve::arena_mut(base, layout.nodes_offset, c.nodes),
                    ropes: carve::arena_mut(base, layout.ropes_offset, c.ropes),
                    rope_ids: carve::arena_mut(base, layout.rope_ids_offset, c.rope_ids),
                    refs: carve::arena_mut(base, layout.refs_offset, c.refs),
                },
                kd::KdScratch {
                    prim_flags: carve::arena_mut(sbase, 0, sl.prim_flags),
                    events: carve::arena_mut(sbase, sl.events_offset, sl.events),
                },
            )
        };
        let mut build = kd::build_begin_for_threads(&scene, &p, storage, scratch, threads)?;
        if let Some(run_jobs) = run_jobs {
            let entry = core::hint::black_box(&threads) as *const usize as usize;
            crate::build_jobs::run_with(build.jobs(), run_jobs, ctx, n, regions, entry);
        }
        let info = *build.finish()?.info();
        // The tree packed at the arena's start: the caller keeps only
        // arena_bytes_used of it.
        // SAFETY: the build's views of the arena are gone (only `info`, a
        // copy, is left); the layout's bytes are still lent exclusively.
        let bytes = unsafe { carve::arena_mut::<u8>(base, 0, layout.total_bytes) };
        let tight = layout
            .pack(&info, bytes)
            .ok_or(CorayStatus::InternalError)?;
        // SAFETY: as above; the header's bytes lie below the first part.
        unsafe {
            carve::arena_mut::<KdArenaHeader>(base, 0, 1)[0] = KdArenaHeader::new(info, &tight)
        };
        Ok(())
    })
}

/// Opens the kd-tree in `arena` (as `coray_kdtree_build` wrote it, or a
/// copy of it) with the scene it was built on: O(1) checks of the header,
/// the layout and the scene's counts, then `*out` is the handle every other
/// call takes. The arena and the scene's arrays must stay in place and
/// unchanged while the handle is used. Run `coray_kdtree_validate` once on
/// an arena from untrusted storage: until it accepts it, calls on the
/// handle never crash or hang, but may fail with
/// `CORAY_STATUS_CORRUPT_ARENA` and leave outputs partly written.
///
/// Safety: `arena` is NULL or readable for `arena_bytes`; `scene` and `out`
/// NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn coray_kdtree_open(
    arena: *const c_void,
    arena_bytes: usize,
    scene: *const CorayScene,
    out: *mut CorayKdTree,
) -> CorayStatus {
    guard(|| {
        let mut regions = Regions::new();
        // SAFETY: forwarded caller contract.
        let scene = unsafe { carve::scene(scene, &mut regions)? };
        carve::check_array(out, 1)?;
        regions.add(out, size_of::<CorayKdTree>(), true);
        let base = arena.cast::<u8>();
        check_arena(base)?;
        if arena_bytes < KD_HEADER_BYTES {
            return Err(CorayStatus::CorruptArena);
        }
        regions.add(base, arena_bytes, false).check()?;
        // SAFETY: aligned, readable for at least one header.
        let h = unsafe { carve::arena_ref::<KdArenaHeader>(base, 0, 1)[0] };
        let l = h.layout(arena_bytes)?;
        let c = &l.counts;
        let mut hd = Handle::new(KIND_KD, base as usize, l.total_bytes, &scene);
        hd.set_part::<KdArenaHeader>(0, 0, 1)?;
        hd.set_part::<KdNode>(1, l.nodes_offset, c.nodes)?;
        hd.set_part::<KdRopes>(2, l.ropes_offset, c.ropes)?;
        hd.set_part::<u32>(3, l.rope_ids_offset, c.rope_ids)?;
        hd.set_part::<u32>(4, l.refs_offset, c.refs)?;
        // The tree must assemble from the words stored: counts, magic,
        // version, scene.
        let words = hd.words();
        // SAFETY: the handle describes the arena just checked, readable.
        unsafe { tree_of(Sealed::new(&words, KIND_KD)?, scene)? };
        // SAFETY: out checked non-null, aligned, disjoint from the arena.
        unsafe { out.write(CorayKdTree { opaque: words }) };
        Ok(())
    })
}

/// A handle's header and arena parts: nodes, ropes, rope records,
/// references.
///
/// Safety: the handle's arena is readable and unchanged during `'a`.
#[inline(always)]
#[allow(clippy::type_complexity)]
unsafe fn parts_of<'a>(
    h: Sealed,
) -> (
    &'a coray::kd::KdInfo,
    &'a [KdNode],
    &'a [KdRopes],
    &'a [u32],
    &'a [u32],
) {
    // SAFETY: the handle's parts lie within its arena, each checked for
    // its type when the handle was opened (Handle::set_part); readable by
    // the caller's contract.
    unsafe {
        (
            &h.part::<KdArenaHeader>(0)[0].info,
            h.part(1),
            h.part(2),
            h.part(3),
            h.part(4),
        )
    }
}

/// The tree a handle describes, over `scene`.
///
/// Safety: as [`parts_of`].
#[inline(always)]
unsafe fn tree_of<'a>(h: Sealed, scene: coray::Scene<'a>) -> Result<KdTree<'a>, CorayStatus> {
    // SAFETY: forwarded contract.
    let (info, nodes, ropes, rope_ids, refs) = unsafe { parts_of(h) };
    Ok(KdTree::from_parts(
        scene, *info, nodes, ropes, rope_ids, refs,
    )?)
}

/// The tree a handle describes whose header and parts passed [`tree_of`]'s
/// checks when a tracer was made: nothing is checked again, and the parts
/// are cut to the header's counts as [`KdTree::from_parts`] cuts them (the
/// arena's parts run to their capacities: a header whose counts were
/// damaged below them was once traced over the whole capacities here and
/// over the counts by the one-ray call, and the two answered otherwise;
/// found by the C-ABI fuzzer, `fuzz/regressions/kd-tracer-damaged-count`).
///
/// `trace_box` is the tree's `trace_bounds()`, which the tracer keeps.
///
/// Safety: as [`parts_of`].
#[inline(always)]
unsafe fn known_tree_of<'a>(
    h: Sealed,
    scene: coray::Scene<'a>,
    trace_box: coray::Aabb,
) -> KdTree<'a> {
    // SAFETY: forwarded contract.
    let (info, nodes, ropes, rope_ids, refs) = unsafe { parts_of(h) };
    fn first<T>(s: &[T], n: u32) -> &[T] {
        &s[..(n as usize).min(s.len())]
    }
    KdTree::from_checked_parts_with_trace_box(
        scene,
        info,
        trace_box,
        first(nodes, info.node_count),
        first(ropes, info.rope_count()),
        first(rope_ids, info.rope_id_count()),
        first(refs, info.ref_count),
    )
}

/// A box as a tracer's hint words: its six `f32`s' bits, two a word.
fn trace_box_words(b: &coray::Aabb) -> [u64; tracer::HINT_WORDS] {
    let f = [b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z].map(f32::to_bits);
    [0, 2, 4].map(|i| u64::from(f[i]) | u64::from(f[i + 1]) << 32)
}

/// The box [`trace_box_words`] wrote.
#[inline(always)]
fn box_of_words(w: [u64; tracer::HINT_WORDS]) -> coray::Aabb {
    let f = |i: usize| f32::from_bits((w[i / 2] >> (32 * (i % 2))) as u32);
    coray::Aabb {
        min: coray::Vec3::new(f(0), f(1), f(2)),
        max: coray::Vec3::new(f(3), f(4), f(5)),
    }
}

/// The tree behind a caller's handle, its buffers noted in `regions`.
///
/// Safety: `t` is NULL or a handle `coray_kdtree_open` filled, whose arena
/// and scene are still in place and unchanged during `'a`.
#[inline(always)]
pub(crate) unsafe fn open<'a>(
    t: *const CorayKdTree,
    regions: &mut Regions,
) -> Result<KdTree<'a>, CorayStatus> {
    // SAFETY: forwarded contract. The handle is not returned (every trace
    // call opens one: no copy of it leaves this frame).
    unsafe {
        let h = handle::read(t.cast(), KIND_KD, regions)?;
        view(h, regions)
    }
}

/// The tree a handle read from the caller describes, its arena and scene
/// noted in `regions`.
///
/// Safety: as [`open`], for the handle `h` was read from.
#[inline(always)]
unsafe fn view<'a>(h: Sealed, regions: &mut Regions) -> Result<KdTree<'a>, CorayStatus> {
    // SAFETY: forwarded contract.
    unsafe {
        regions.add(h.arena() as *const u8, h.arena_bytes(), false);
        let scene = h.scene();
        regions.add_scene(&scene);
        tree_of(h, scene)
    }
}

/// [`open`], with the handle (whose `arena_bytes` is the layout's size).
///
/// Safety: as [`open`].
unsafe fn open_handle<'a>(
    t: *const CorayKdTree,
    regions: &mut Regions,
) -> Result<(Sealed<'a>, KdTree<'a>), CorayStatus> {
    // SAFETY: forwarded contract.
    unsafe {
        let h = handle::read(t.cast(), KIND_KD, regions)?;
        let t = view(h, regions)?;
        Ok((h, t))
    }
}

/// What the tree holds, from its header (O(1)).
///
/// Safety: `tree` is a handle `coray_kdtree_open` filled (see there); `out`
/// NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn coray_kdtree_info(
    tree: *const CorayKdTree,
    out: *mut CorayKdTreeInfo,
) -> CorayStatus {
    guard(|| {
        let mut regions = Regions::new();
        // SAFETY: forwarded caller contract.
        let ((h, t), out) = unsafe {
            (
                open_handle(tree, &mut regions)?,
                Out::new(out, false, &mut regions)?,
            )
        };
        regions.check()?;
        let i = t.info();
        out.write(CorayKdTreeInfo {
            struct_size: 0,
            node_count: i.node_count,
            leaf_count: i.leaf_count,
            ref_count: i.ref_count,
            depth: i.depth,
            valid_prim_count: i.valid_prim_count,
            truncated: i.truncated() as u32,
            arena_bytes_used: h.arena_bytes(),
            stack_bytes: CORAY_KDTREE_STACK_BYTES,
            bounds_min: i.bounds_min,
            bounds_max: i.bounds_max,
        });
        Ok(())
    })
}

/// Checks every structural invariant of the tree against its scene, in
/// time linear in the tree and the scene, never crashing on any bytes:
/// `CORAY_STATUS_CORRUPT_ARENA` when anything is wrong, the scene changed
/// since the build among it (a digest of every scene word is recorded at
/// build time; since 1.7). Once it accepts an arena, every call on it
/// gives the results of a clean build. `stack` is
/// unused by kd-trees (it may be NULL); `out` may be NULL.
///
/// Safety: as `coray_kdtree_info`.
#[no_mangle]
pub unsafe extern "C" fn coray_kdtree_validate(
    tree: *const CorayKdTree,
    stack: *mut c_void,
    stack_bytes: usize,
    out: *mut CorayShape,
) -> CorayStatus {
    let _ = (stack, stack_bytes);
    guard(|| {
        let mut regions = Regions::new();
        // SAFETY: forwarded caller contract.
        let (t, out) = unsafe {
            (
                open(tree, &mut regions)?,
                Out::new(out, true, &mut regions)?,
            )
        };
        regions.check()?;
        let s = Accel::validate(&t, &mut [])?;
        out.write(CorayShape {
            struct_size: 0,
            node_count: s.nodes,
            leaf_count: s.leaves,
            empty_leaf_count: s.empty_leaves,
            ref_count: s.refs,
            depth: s.depth,
        });
        Ok(())
    })
}

/// The body of every trace entry point: checks the handle, the arrays, the
/// stack and the statistics before anything is traced, then writes
/// `answer` for each ray.
///
/// Safety: as `coray_kdtree_intersect`, with `out` holding `count` `O`s.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
unsafe fn batch<O>(
    tree: *const CorayKdTree,
    method: CorayTraversal,
    rays: *const CorayRay,
    out: *mut O,
    count: usize,
    stack: *mut c_void,
    stack_bytes: usize,
    stats: *mut CorayTraceStats,
    answer: impl Fn(
        &KdTree,
        &[coray::Ray],
        &mut [O],
        Traversal,
        &mut [KdStackItem],
        &mut TraceStats,
    ) -> Result<(), coray::Error>,
) -> CorayStatus {
    guard(|| {
        let method = traversal(method)?;
        let mut regions = Regions::new();
        // SAFETY: forwarded caller contract for every pointer.
        let (t, rays, out, stk, stats) = unsafe {
            let t = open(tree, &mut regions)?;
            let rays = carve::input(rays, count)?;
            regions.add(rays.as_ptr(), size_of_val(rays), false);
            let out = carve::output(out, count)?;
            regions.add(out.as_ptr(), size_of_val(out), true);
            let need = if count == 0 { 0 } else { KD_STACK_LEN };
            let stk = carve::stack::<KdStackItem>(stack, stack_bytes, need, &mut regions)?;
            (t, rays, out, stk, Out::new(stats, true, &mut regions)?)
        };
        regions.check()?;
        let mut st = TraceStats::default();
        // The caller's rays traced in place, in groups of 8: what a packet
        // takes (the other traversals trace them ray by ray).
        let rays = crate::abi::core_rays(rays);
        let mut first = 0;
        while first < count {
            let end = count.min(first + PACKET_LANES);
            answer(
                &t,
                &rays[first..end],
                &mut out[first..end],
                method,
                stk,
                &mut st,
            )?;
            // A corrupt arena: the call stops at the first group that
            // met it.
            if st.faults > 0 {
                return Err(CorayStatus::CorruptArena);
            }
            first = end;
        }
        stats.write(CorayTraceStats::of(&st));
        Ok(())
    })
}

/// The body of the one-ray entry points: [`one_ray`] on a kd-tree, by
/// `traversal`, writing `answer` for the ray.
///
/// Safety: as `coray_kdtree_intersect1`, with `out` one writable `O`.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
unsafe fn one<O>(
    tree: *const CorayKdTree,
    traversal: CorayTraversal,
    ray: *const CorayRay,
    out: *mut O,
    stack: *mut c_void,
    stack_bytes: usize,
    stats: *mut CorayTraceStats,
    answer: impl FnOnce(&KdTree, &coray::Ray, Traversal, &mut [KdStackItem], &mut TraceStats) -> O,
) -> CorayStatus {
    guard(|| {
        let method = self::traversal(traversal)?;
        // SAFETY: forwarded caller contract.
        unsafe {
            one_ray(
                tree.cast(),
                KIND_KD,
                |h, s| tree_of(h, s),
                |_| KD_STACK_LEN,
                ray,
                out,
                stack,
                stack_bytes,
                stats,
                |t, r, s, st| Ok(answer(t, r, method, s, st)),
            )
        }
    })
}

/// Closest hits of up to [`PACKET_LANES`] rays, written in place (the
/// caller's array is the core's).
fn intersect_chunk(
    t: &KdTree,
    rays: &[coray::Ray],
    out: &mut [CorayHit],
    m: Traversal,
    s: &mut [KdStackItem],
    st: &mut TraceStats,
) -> Result<(), coray::Error> {
    let hits = crate::abi::core_hits(out);
    if cfg!(feature = "packets") && m == Traversal::Packets {
        crate::simd::intersect_packets(t, rays, hits, s, st);
    } else {
        Accel::intersect_many(t, rays, hits, m, s, st)?;
    }
    Ok(())
}

/// Any-hit answers of up to [`PACKET_LANES`] rays, as bytes.
fn occluded_chunk(
    t: &KdTree,
    rays: &[coray::Ray],
    out: &mut [u8],
    m: Traversal,
    s: &mut [KdStackItem],
    st: &mut TraceStats,
) -> Result<(), coray::Error> {
    let mut occ = [false; PACKET_LANES];
    let occ = &mut occ[..rays.len()];
    if cfg!(feature = "packets") && m == Traversal::Packets {
        crate::simd::occluded_packets(t, rays, occ, s, st);
    } else {
        Accel::occluded_many(t, rays, occ, m, s, st)?;
    }
    for (o, b) in out.iter_mut().zip(occ.iter()) {
        *o = *b as u8;
    }
    Ok(())
}

/// Closest hits of `count` rays: `hits[i]` for `rays[i]`, by `traversal`.
/// `stack` is `CORAY_KDTREE_STACK_BYTES` of traversal stack (16-byte
/// aligned; one per thread). `stats` may be NULL. Many threads may trace
/// one tree at once, each with its own stack.
///
/// Safety: `tree` as in `coray_kdtree_info`; `rays` and `hits` hold `count`
/// elements (may be NULL when `count` is 0); `stack` is writable for
/// `stack_bytes`; `stats` is NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn coray_kdtree_intersect(
    tree: *const CorayKdTree,
    traversal: CorayTraversal,
    rays: *const CorayRay,
    hits: *mut CorayHit,
    count: usize,
    stack: *mut c_void,
    stack_bytes: usize,
    stats: *mut CorayTraceStats,
) -> CorayStatus {
    // SAFETY: forwarded caller contract.
    unsafe {
        batch(
            tree,
            traversal,
            rays,
            hits,
            count,
            stack,
            stack_bytes,
            stats,
            intersect_chunk,
        )
    }
}

/// `coray_kdtree_intersect` for one ray, checked in full on every call. A thread
/// tracing one ray per call makes a tracer (`coray_kdtree_tracer`) and calls
/// `coray_kdtree_tracer_intersect1`: the same answer, the checks made once.
///
/// Safety: as `coray_kdtree_intersect` with `count` 1.
#[no_mangle]
pub unsafe extern "C" fn coray_kdtree_intersect1(
    tree: *const CorayKdTree,
    traversal: CorayTraversal,
    ray: *const CorayRay,
    hit: *mut CorayHit,
    stack: *mut c_void,
    stack_bytes: usize,
    stats: *mut CorayTraceStats,
) -> CorayStatus {
    // SAFETY: forwarded caller contract.
    unsafe {
        one(
            tree,
            traversal,
            ray,
            hit,
            stack,
            stack_bytes,
            stats,
            |t, r, m, s, st| CorayHit::from(KdTree::intersect(t, r, m, s, st)),
        )
    }
}

/// Any-hit queries (shadow rays) of `count` rays: `occluded[i]` is 1 when
/// something lies on `rays[i]` within `[tnear, tfar]`, else 0. Otherwise
/// as `coray_kdtree_intersect`.
///
/// Safety: as `coray_kdtree_intersect`, with `occluded` holding `count` bytes.
#[no_mangle]
pub unsafe extern "C" fn coray_kdtree_occluded(
    tree: *const CorayKdTree,
    traversal: CorayTraversal,
    rays: *const CorayRay,
    occluded: *mut u8,
    count: usize,
    stack: *mut c_void,
    stack_bytes: usize,
    stats: *mut CorayTraceStats,
) -> CorayStatus {
    // SAFETY: forwarded caller contract.
    unsafe {
        batch(
            tree,
            traversal,
            rays,
            occluded,
            count,
            stack,
            stack_bytes,
            stats,
            occluded_chunk,
        )
    }
}

/// `coray_kdtree_occluded` for one ray, checked in full on every call. A thread
/// tracing one ray per call makes a tracer (`coray_kdtree_tracer`) and calls
/// `coray_kdtree_tracer_occluded1`: the same answer, the checks made once.
///
/// Safety: as `coray_kdtree_occluded` with `count` 1.
#[no_mangle]
pub unsafe extern "C" fn coray_kdtree_occluded1(
    tree: *const CorayKdTree,
    traversal: CorayTraversal,
    ray: *const CorayRay,
    occluded: *mut u8,
    stack: *mut c_void,
    stack_bytes: usize,
    stats: *mut CorayTraceStats,
) -> CorayStatus {
    // SAFETY: forwarded caller contract.
    unsafe {
        one(
            tree,
            traversal,
            ray,
            occluded,
            stack,
            stack_bytes,
            stats,
            |t, r, m, s, st| KdTree::occluded(t, r, m, s, st) as u8,
        )
    }
}

/// Makes `tracer` trace `tree` by `traversal` with the caller's `stack`
/// (`CORAY_KDTREE_STACK_BYTES`, 16-byte aligned): one thread's
/// `coray_kdtree_tracer_intersect1` and `_occluded1` calls then skip the checks
/// this call makes. Since 1.5.
///
/// Safety: `tree` as in `coray_kdtree_info`; `stack` NULL or writable for
/// `stack_bytes`, and used by nothing else while the tracer is; `tracer`
/// NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn coray_kdtree_tracer(
    tree: *const CorayKdTree,
    traversal: CorayTraversal,
    stack: *mut c_void,
    stack_bytes: usize,
    tracer: *mut CorayTracer,
) -> CorayStatus {
    guard(|| {
        self::traversal(traversal)?;
        // SAFETY: forwarded caller contract.
        unsafe {
            tracer::make::<_, KdStackItem>(
                tracer,
                tree.cast(),
                KIND_KD,
                traversal as u64,
                |h, s| tree_of(h, s),
                |_| KD_STACK_LEN,
                |t| trace_box_words(&t.info().trace_bounds()),
                stack,
                stack_bytes,
            )
        }
    })
}

/// `coray_kdtree_tracer_intersect1` and `_occluded1`: `answer` for the
/// ray, by the tracer's traversal, or `missed` for a ray that misses the
/// tree's box (`kd::misses_trace_box`, the traversal's own first test,
/// asked before the tree's view is rebuilt: a missing ray's call costs
/// the checks and the clip).
///
/// Safety: as `coray_kdtree_tracer_intersect1`, with `out` one writable `O`.
#[inline(always)]
unsafe fn traced<O>(
    tracer: *mut CorayTracer,
    ray: *const CorayRay,
    out: *mut O,
    missed: O,
    answer: impl FnOnce(&KdTree, &coray::Ray, Traversal, &mut [KdStackItem], &mut TraceStats) -> O,
) -> Result<(), CorayStatus> {
    // SAFETY: forwarded caller contract.
    unsafe {
        tracer::trace(
            tracer,
            KIND_KD,
            #[inline(always)]
            |h, s, hint| Ok(known_tree_of(h, s, box_of_words(hint))),
            #[inline(always)]
            |_| KD_STACK_LEN,
            ray,
            out,
            #[inline(always)]
            |hint, r, st| {
                let outside =
                    kd::misses_trace_box(&coray::geom::ClipBox::of(&box_of_words(hint)), r);
                // As the traversal counts a ray it does not walk.
                st.rays += u64::from(outside);
                outside.then_some(missed)
            },
            #[inline(always)]
            |t, m, r, s, st| Ok(answer(t, r, traversal(m as CorayTraversal)?, s, st)),
        )
    }
}

/// The closest hit of `ray` by a tracer of this kd-tree (made by
/// `coray_kdtree_tracer`), into `hit`: `coray_kdtree_intersect1`'s answer, with
/// the checks made once when the tracer was made. Each call checks the
/// tracer (made by that call, not moved or copied since; of this family),
/// its handle's seal word, `ray` and `hit` (non-null, aligned, apart, and
/// `hit` over none of the tracer, its stack, handle, arena or scene, nor
/// the ray over the tracer or stack), and adds its statistics to the
/// tracer's (`coray_tracer_stats`). Since 1.5.
///
/// Safety: `tracer` NULL or a tracer its make call filled, used by one
/// thread at a time, whose handle, arena, scene and stack are in place and
/// (but the stack) unchanged; `ray` NULL or readable; `hit` NULL or
/// writable.
#[no_mangle]
pub unsafe extern "C" fn coray_kdtree_tracer_intersect1(
    tracer: *mut CorayTracer,
    ray: *const CorayRay,
    hit: *mut CorayHit,
) -> CorayStatus {
    guard(|| {
        // SAFETY: forwarded caller contract.
        unsafe {
            traced(
                tracer,
                ray,
                hit,
                coray::Hit::MISS.into(),
                #[inline(always)]
                |t, r, m, s, st| KdTree::intersect(t, r, m, s, st).into(),
            )
        }
    })
}

/// Whether something lies on `ray` within `[tnear, tfar]` (1) or not (0),
/// by a tracer of this kd-tree, into `occluded`: `coray_kdtree_occluded1`'s
/// answer. Otherwise as `coray_kdtree_tracer_intersect1`. Since 1.5.
///
/// Safety: as `coray_kdtree_tracer_intersect1`, with `occluded` one writable
/// byte.
#[no_mangle]
pub unsafe extern "C" fn coray_kdtree_tracer_occluded1(
    tracer: *mut CorayTracer,
    ray: *const CorayRay,
    occluded: *mut u8,
) -> CorayStatus {
    guard(|| {
        // SAFETY: forwarded caller contract.
        unsafe {
            traced(
                tracer,
                ray,
                occluded,
                0,
                #[inline(always)]
                |t, r, m, s, st| KdTree::occluded(t, r, m, s, st) as u8,
            )
        }
    })
}
