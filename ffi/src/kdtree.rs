//! `coray_kdtree_*`: requirements, build, info, validate, intersect, occluded.

use crate::carve::{self, check_arena, slice_mut, slice_ref};
use crate::types::*;
use crate::{guard, CorayStatus};
use coray::arena::{KdArenaHeader, KdArenaLayout, KdScratchLayout, KD_HEADER_BYTES};
use coray::kd::{self, KdScratch, KdStorage, KdTree, Traversal};
use coray::{Scene, TraceStats};
use core::ffi::c_void;

const MAX_PRIMS: usize = 1 << 30;

fn traversal(t: u32) -> Result<Traversal, CorayStatus> {
    match t {
        CORAY_TRAVERSAL_HIERARCHICAL => Ok(Traversal::Hierarchical),
        CORAY_TRAVERSAL_ROPES => Ok(Traversal::Ropes),
        _ => Err(CorayStatus::InvalidParameter),
    }
}

/// Minimum and ideal element counts for `n` primitives, or the status when
/// their arenas could not be addressed with 32-bit offsets.
fn counts(
    n: usize,
    p: &kd::KdParams,
) -> Result<(kd::KdRequirements, kd::KdRequirements), CorayStatus> {
    if n >= MAX_PRIMS || KdArenaLayout::of(&kd::min_requirements(n)).total_bytes > u32::MAX as usize
    {
        return Err(CorayStatus::TooManyPrimitives);
    }
    Ok((kd::min_requirements(n), kd::requirements(n, p)))
}

/// Arena sizes for a tree over `prim_count` primitives with `params`.
///
/// # Safety
/// `params` and `out` are NULL or valid pointers to their types.
#[no_mangle]
pub unsafe extern "C" fn coray_kdtree_requirements(
    prim_count: usize,
    params: *const CorayKdParams,
    out: *mut CorayKdRequirements,
) -> CorayStatus {
    guard(|| {
        // SAFETY: the caller passes a valid params pointer or NULL.
        let p = unsafe { carve::input_ref(params)? }.to_core()?;
        let (min, ideal) = counts(prim_count, &p)?;
        let r = CorayKdRequirements {
            tree_min_bytes: KdArenaLayout::of(&min).total_bytes,
            tree_bytes: KdArenaLayout::of(&ideal).total_bytes.min(u32::MAX as usize),
            scratch_min_bytes: KdScratchLayout::bytes_for(&min),
            scratch_bytes: KdScratchLayout::bytes_for(&ideal),
        };
        // SAFETY: the caller passes a valid, writable out pointer or NULL.
        *unsafe { carve::output(out, 1)? }
            .first_mut()
            .ok_or(CorayStatus::NullPointer)? = r;
        Ok(())
    })
}

/// Builds an SAH kd-tree over `scene` into `tree_arena`, using
/// `scratch_arena` as scratch (free again when this returns).
///
/// Both arenas must be 16-byte aligned and must not overlap. Any tree arena
/// from `tree_min_bytes` up works: with less than `tree_bytes` the build stops
/// splitting where room runs out (see `CorayKdTreeInfo.truncated`). On
/// `CORAY_STATUS_ARENA_TOO_SMALL`, `*needed_bytes` (if not NULL) receives the
/// minimum size of the arena that was too small. Bytes of either arena past
/// what its layout uses are never written.
///
/// The tree stores primitive indices: trace it with the same scene, unchanged.
/// The arena holds no pointer, so it may be copied, saved and loaded to any
/// 16-byte aligned address and traced there.
///
/// # Safety
/// Every pointer is NULL or valid for its documented size; the arenas are
/// not read or written by anyone else during the call.
#[no_mangle]
pub unsafe extern "C" fn coray_kdtree_build(
    scene: *const CorayScene,
    params: *const CorayKdParams,
    tree_arena: *mut c_void,
    tree_bytes: usize,
    scratch_arena: *mut c_void,
    scratch_bytes: usize,
    needed_bytes: *mut usize,
) -> CorayStatus {
    guard(|| {
        // SAFETY: the caller passes valid scene and params pointers or NULL.
        let (scene, p) = unsafe { (carve::scene(scene)?, carve::input_ref(params)?.to_core()?) };
        let (base, sbase) = (tree_arena.cast::<u8>(), scratch_arena.cast::<u8>());
        check_arena(base)?;
        check_arena(sbase)?;
        let n = scene.prim_count();
        let (min, ideal) = counts(n, &p)?;
        let too_small = |bytes: usize| {
            if !needed_bytes.is_null()
                && (needed_bytes as usize).is_multiple_of(core::mem::align_of::<usize>())
            {
                // SAFETY: non-null and aligned; the caller promises it writable.
                unsafe { *needed_bytes = bytes };
            }
            Err(CorayStatus::ArenaTooSmall)
        };
        let Some(layout) = KdArenaLayout::fit(tree_bytes.min(u32::MAX as usize), &min, &ideal)
        else {
            return too_small(KdArenaLayout::of(&min).total_bytes);
        };
        let Some(sl) = KdScratchLayout::fit(scratch_bytes, n, min.events) else {
            return too_small(KdScratchLayout::bytes_for(&min));
        };
        let scratch_used = sl.events_offset + sl.events * core::mem::size_of::<kd::KdEvent>();
        let (t0, s0) = (base as usize, sbase as usize);
        if t0 < s0 + scratch_used && s0 < t0 + layout.total_bytes {
            return Err(CorayStatus::InvalidParameter);
        }
        scene.check()?;
        let c = &layout.counts;
        // SAFETY: both arenas passed check_arena; the layout and scratch
        // layout lie within tree_bytes and scratch_bytes (fit() checked) and
        // their parts do not overlap each other (layout formulas) nor across
        // arenas (checked above); the caller gives us the arenas exclusively.
        let (header, storage, scratch) = unsafe {
            (
                slice_mut::<KdArenaHeader>(base, 0, 1),
                KdStorage {
                    nodes: slice_mut(base, layout.nodes_offset, c.nodes),
                    leaves: slice_mut(base, layout.leaves_offset, c.leaves),
                    ropes: slice_mut(base, layout.ropes_offset, c.ropes),
                    refs: slice_mut(base, layout.refs_offset, c.refs),
                },
                KdScratch {
                    prim_flags: slice_mut(sbase, 0, sl.prim_flags),
                    events: slice_mut(sbase, sl.events_offset, sl.events),
                },
            )
        };
        let tree = kd::build_sah(&scene, &p, storage, scratch)?;
        header[0] = KdArenaHeader::new(tree.info, &layout);
        Ok(())
    })
}

/// The tree in an arena, checked in O(1) (header, layout, scene counts).
///
/// # Safety
/// `arena` is NULL or valid for reads of `bytes` bytes that nobody writes
/// during `'a`; `scene`'s arrays likewise.
pub(crate) unsafe fn tree<'a>(
    arena: *const c_void,
    bytes: usize,
    scene: Scene<'a>,
) -> Result<KdTree<'a>, CorayStatus> {
    let base = arena.cast::<u8>();
    check_arena(base)?;
    if bytes < KD_HEADER_BYTES {
        return Err(CorayStatus::CorruptArena);
    }
    // SAFETY: aligned, readable for bytes >= KD_HEADER_BYTES >= one header.
    let header = unsafe { slice_ref::<KdArenaHeader>(base, 0, 1)[0] };
    let l = header.layout(bytes)?;
    let c = &l.counts;
    // SAFETY: the layout lies within `bytes` (checked by layout()), its
    // offsets are multiples of 16, and the arena is only read.
    let (nodes, leaves, ropes, refs) = unsafe {
        (
            slice_ref(base, l.nodes_offset, c.nodes),
            slice_ref(base, l.leaves_offset, c.leaves),
            slice_ref(base, l.ropes_offset, c.ropes),
            slice_ref(base, l.refs_offset, c.refs),
        )
    };
    Ok(KdTree::from_parts(
        scene,
        header.info,
        nodes,
        leaves,
        ropes,
        refs,
    )?)
}

/// What the tree in `tree_arena` holds, from its header (O(1)).
///
/// # Safety
/// `tree_arena` is valid for reads of `tree_bytes`; `out` is NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn coray_kdtree_info(
    tree_arena: *const c_void,
    tree_bytes: usize,
    out: *mut CorayKdTreeInfo,
) -> CorayStatus {
    guard(|| {
        let base = tree_arena.cast::<u8>();
        check_arena(base)?;
        if tree_bytes < KD_HEADER_BYTES {
            return Err(CorayStatus::CorruptArena);
        }
        // SAFETY: aligned, readable for at least one header.
        let h = unsafe { slice_ref::<KdArenaHeader>(base, 0, 1)[0] };
        h.layout(tree_bytes)?;
        let i = &h.info;
        let info = CorayKdTreeInfo {
            node_count: i.node_count,
            leaf_count: i.leaf_count,
            ref_count: i.ref_count,
            depth: i.depth,
            valid_prim_count: i.valid_prim_count,
            truncated: i.truncated() as u32,
            arena_bytes_used: h.layout_bytes as usize,
            bounds_min: i.bounds_min,
            bounds_max: i.bounds_max,
        };
        // SAFETY: out is NULL or writable (caller's contract).
        *unsafe { carve::output(out, 1)? }
            .first_mut()
            .ok_or(CorayStatus::NullPointer)? = info;
        Ok(())
    })
}

/// Checks every structural invariant of the tree against `scene` (O(size));
/// run it on an arena loaded from untrusted storage before tracing.
/// `CORAY_STATUS_CORRUPT_ARENA` when anything is wrong.
///
/// # Safety
/// As [`coray_kdtree_info`]; `scene` is valid.
#[no_mangle]
pub unsafe extern "C" fn coray_kdtree_validate(
    tree_arena: *const c_void,
    tree_bytes: usize,
    scene: *const CorayScene,
    out: *mut CorayKdTreeStats,
) -> CorayStatus {
    guard(|| {
        // SAFETY: forwarded caller contract.
        let t = unsafe { tree(tree_arena, tree_bytes, carve::scene(scene)?)? };
        let s = t.validate()?;
        if !out.is_null() {
            // SAFETY: non-null; writable by the caller's contract.
            *unsafe { carve::output(out, 1)? }
                .first_mut()
                .ok_or(CorayStatus::NullPointer)? = CorayKdTreeStats {
                node_count: s.nodes,
                leaf_count: s.leaves,
                empty_leaf_count: s.empty_leaves,
                ref_count: s.refs,
                depth: s.depth,
                sah_cost: s.sah_cost,
            };
        }
        Ok(())
    })
}

/// Writes `s` to `stats` unless it is NULL.
fn put_stats(stats: *mut CorayTraceStats, s: TraceStats) -> Result<(), CorayStatus> {
    if !stats.is_null() {
        // SAFETY: non-null; the caller promises a writable CorayTraceStats.
        if let Some(o) = unsafe { carve::output(stats, 1)? }.first_mut() {
            *o = s.into();
        }
    }
    Ok(())
}

/// Closest hits of `count` rays: `hits[i]` for `rays[i]`. `traversal` is
/// `CORAY_TRAVERSAL_HIERARCHICAL` or `CORAY_TRAVERSAL_ROPES` (same hits).
/// `stats` may be NULL; otherwise it receives this call's counts.
/// Thread-safe: many threads may trace one tree at once.
///
/// # Safety
/// `rays` and `hits` hold `count` elements (may be NULL when `count` is 0);
/// the arena and scene as in [`coray_kdtree_validate`].
#[no_mangle]
pub unsafe extern "C" fn coray_kdtree_intersect(
    tree_arena: *const c_void,
    tree_bytes: usize,
    scene: *const CorayScene,
    traversal_method: u32,
    rays: *const CorayRay,
    hits: *mut CorayHit,
    count: usize,
    stats: *mut CorayTraceStats,
) -> CorayStatus {
    guard(|| {
        let method = traversal(traversal_method)?;
        // SAFETY: forwarded caller contract for every pointer.
        let (t, rays, hits) = unsafe {
            (
                tree(tree_arena, tree_bytes, carve::scene(scene)?)?,
                carve::input(rays, count)?,
                carve::output(hits, count)?,
            )
        };
        let mut st = TraceStats::default();
        for (r, h) in rays.iter().zip(hits.iter_mut()) {
            *h = t.intersect(&r.into(), method, &mut st).into();
        }
        put_stats(stats, st)
    })
}

/// [`coray_kdtree_intersect`] for one ray.
///
/// # Safety
/// As [`coray_kdtree_intersect`] with `count` = 1.
#[no_mangle]
pub unsafe extern "C" fn coray_kdtree_intersect1(
    tree_arena: *const c_void,
    tree_bytes: usize,
    scene: *const CorayScene,
    traversal_method: u32,
    ray: *const CorayRay,
    hit: *mut CorayHit,
    stats: *mut CorayTraceStats,
) -> CorayStatus {
    if ray.is_null() || hit.is_null() {
        return CorayStatus::NullPointer;
    }
    // SAFETY: forwarded caller contract.
    unsafe {
        coray_kdtree_intersect(
            tree_arena,
            tree_bytes,
            scene,
            traversal_method,
            ray,
            hit,
            1,
            stats,
        )
    }
}

/// Any-hit queries (shadow rays) for `count` rays: `occluded[i]` is 1 when
/// something lies on `rays[i]` within `[tnear, tfar]`, else 0.
///
/// # Safety
/// As [`coray_kdtree_intersect`], with `occluded` holding `count` bytes.
#[no_mangle]
pub unsafe extern "C" fn coray_kdtree_occluded(
    tree_arena: *const c_void,
    tree_bytes: usize,
    scene: *const CorayScene,
    traversal_method: u32,
    rays: *const CorayRay,
    occluded: *mut u8,
    count: usize,
    stats: *mut CorayTraceStats,
) -> CorayStatus {
    guard(|| {
        let method = traversal(traversal_method)?;
        // SAFETY: forwarded caller contract for every pointer.
        let (t, rays, out) = unsafe {
            (
                tree(tree_arena, tree_bytes, carve::scene(scene)?)?,
                carve::input(rays, count)?,
                carve::output(occluded, count)?,
            )
        };
        let mut st = TraceStats::default();
        for (r, o) in rays.iter().zip(out.iter_mut()) {
            *o = t.occluded(&r.into(), method, &mut st) as u8;
        }
        put_stats(stats, st)
    })
}

/// [`coray_kdtree_occluded`] for one ray.
///
/// # Safety
/// As [`coray_kdtree_occluded`] with `count` = 1.
#[no_mangle]
pub unsafe extern "C" fn coray_kdtree_occluded1(
    tree_arena: *const c_void,
    tree_bytes: usize,
    scene: *const CorayScene,
    traversal_method: u32,
    ray: *const CorayRay,
    occluded: *mut u8,
    stats: *mut CorayTraceStats,
) -> CorayStatus {
    if ray.is_null() || occluded.is_null() {
        return CorayStatus::NullPointer;
    }
    // SAFETY: forwarded caller contract.
    unsafe {
        coray_kdtree_occluded(
            tree_arena,
            tree_bytes,
            scene,
            traversal_method,
            ray,
            occluded,
            1,
            stats,
        )
    }
}
