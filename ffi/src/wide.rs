//! `coray_wide_*`: the wide (8-ary) hierarchy for triangle meshes and
//! incoherent rays, the binary SAH hierarchy collapsed into nodes of eight
//! boxes tested at once:
//! parameters, requirements, build, open, info, validate, intersect,
//! occluded. Hits are the kd-tree's bit for bit.

use crate::abi::*;
use crate::bvh::{check_scene, scene_counts};
use crate::carve::{self, check_arena, Out, OutValue, Regions, Versioned};
use crate::handle::{self, Handle, Sealed, KIND_WIDE};
use crate::one_ray::one_ray;
use crate::tracer::{self, CorayTracer};
use crate::{guard, CorayStatus, CorayWide};
use coray::bvh::BvhNode;
use coray::limits::MAX_PRIMS;
use coray::wide::layout::{
    WideArenaHeader, WideArenaLayout, WideScratchLayout, WIDE_HEADER_BYTES, WIDE_MAGIC,
    WIDE_VERSION,
};
use coray::wide::{self, LeafBlock, WideBvh, WideNode, WideStackItem};
use coray::{Aabb, Scene, TraceStats};
use core::ffi::c_void;
use core::mem::size_of;

/// Parameters of a wide hierarchy build. Get them from
/// `coray_wide_params_default`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CorayWideParams {
    /// `sizeof(CorayWideParams)`.
    pub struct_size: usize,
    /// Most primitives per leaf entry (1 to 64; default 8: a leaf's
    /// triangles are tested eight at a time); below it the surface area
    /// heuristic decides whether a node splits.
    pub leaf_size: u32,
}

/// What a wide hierarchy holds, from `coray_wide_info` (O(1)).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CorayWideInfo {
    /// `sizeof(CorayWideInfo)`.
    pub struct_size: usize,
    /// Nodes in use (four entries each at most).
    pub node_count: u32,
    /// Leaf entries (runs of references).
    pub leaf_count: u32,
    /// Primitives in the hierarchy.
    pub ref_count: u32,
    /// Level of the deepest node (the root alone: 0).
    pub depth: u32,
    /// The build's leaf size.
    pub leaf_size: u32,
    /// Bytes of the arena the layout covers.
    pub arena_bytes_used: usize,
    /// Bytes of traversal stack every trace call needs.
    pub stack_bytes: usize,
    /// Lower corner of the root's box (empty hierarchy: +inf).
    pub bounds_min: [f32; 3],
    /// Upper corner of the root's box (empty hierarchy: -inf).
    pub bounds_max: [f32; 3],
}

// SAFETY (both): repr(C), size_t struct_size first, integer and float
// fields only; as first published.
unsafe impl Versioned for CorayWideParams {
    const SIZE_1_0: usize = size_of::<Self>();
}
unsafe impl Versioned for CorayWideInfo {
    const SIZE_1_0: usize = size_of::<Self>();
}

/// Default parameters (leaves of up to 8) with `struct_size` set.
#[no_mangle]
pub extern "C" fn coray_wide_params_default() -> CorayWideParams {
    CorayWideParams {
        struct_size: size_of::<CorayWideParams>(),
        leaf_size: wide::DEFAULT_LEAF_SIZE,
    }
}

/// A `CorayWideInfo` to fill, `struct_size` set.
#[no_mangle]
pub extern "C" fn coray_wide_info_default() -> CorayWideInfo {
    CorayWideInfo {
        struct_size: size_of::<CorayWideInfo>(),
        ..Default::default()
    }
}

impl CorayWideParams {
    /// The checked leaf size.
    fn leaf_size(&self) -> Result<u32, CorayStatus> {
        if !(1..=wide::MAX_LEAF_SIZE).contains(&self.leaf_size) {
            return Err(CorayStatus::InvalidParameter);
        }
        Ok(self.leaf_size)
    }
}

/// Arena and scratch layouts for `n` primitives.
fn layouts(n: usize) -> Result<(WideArenaLayout, WideScratchLayout), CorayStatus> {
    let too_many = CorayStatus::TooManyPrimitives;
    if n >= MAX_PRIMS {
        return Err(too_many);
    }
    let r = wide::requirements(n);
    Ok((
        WideArenaLayout::for_build(&r).ok_or(too_many)?,
        WideScratchLayout::of(&r).ok_or(too_many)?,
    ))
}

/// Stack entries a wide hierarchy over `n` primitives may need: its depth
/// is below that of the binary hierarchy (at most `n - 1`).
fn stack_bound(n: usize) -> usize {
    wide::stack_len_for_depth(n.saturating_sub(1))
}

/// Arena, scratch and stack sizes for a wide hierarchy over `prim_count`
/// primitives; the build needs exactly `arena_bytes` and `scratch_bytes`.
/// `stack_bytes` bounds any build over that many primitives; the built
/// hierarchy's own need (`CorayWideInfo.stack_bytes`) is far smaller.
///
/// Safety: `params` and `out` are NULL or valid pointers to their types.
#[no_mangle]
pub unsafe extern "C" fn coray_wide_requirements(
    prim_count: usize,
    params: *const CorayWideParams,
    out: *mut CorayRequirements,
) -> CorayStatus {
    guard(|| {
        let mut regions = Regions::new();
        // SAFETY: the caller passes valid pointers or NULL.
        let (p, out) = unsafe { (carve::read(params)?, Out::new(out, false, &mut regions)?) };
        p.leaf_size()?;
        let (a, s) = layouts(prim_count)?;
        out.write(CorayRequirements {
            struct_size: 0,
            arena_min_bytes: a.total_bytes,
            arena_bytes: a.total_bytes,
            scratch_min_bytes: s.total_bytes,
            scratch_bytes: s.total_bytes,
            stack_bytes: stack_bound(prim_count) * size_of::<WideStackItem>(),
        });
        Ok(())
    })
}

/// Builds a wide hierarchy over `scene` into `arena`, with `scratch` as
/// scratch (free again when this returns).
///
/// Both are 16-byte aligned and overlap neither each other nor the scene,
/// and hold the requirements' `arena_bytes` and `scratch_bytes`. On
/// `CORAY_STATUS_ARENA_TOO_SMALL`, `*needed_bytes` (if not NULL) receives
/// the size the arena or scratch that was too small needs. Degenerate
/// primitives stay out (never hit). The part of the arena the layout
/// covers is written entirely (zeros past the tree); bytes past it are not
/// touched. The tree ends at `CorayWideInfo.arena_bytes_used` (about a
/// quarter of the node room is used): only those bytes need be kept. The
/// arena holds a copy of the triangles' corners, which the leaves test
/// four at a time: after moving vertices, build again
/// (`coray_wide_validate` refuses a copy that differs from the scene).
///
/// Safety: every pointer is NULL or valid for its documented size; the
/// arenas are not read or written by anyone else during the call.
#[no_mangle]
pub unsafe extern "C" fn coray_wide_build(
    scene: *const CorayScene,
    params: *const CorayWideParams,
    arena: *mut c_void,
    arena_bytes: usize,
    scratch: *mut c_void,
    scratch_bytes: usize,
    needed_bytes: *mut usize,
) -> CorayStatus {
    guard(|| {
        let mut regions = Regions::new();
        // SAFETY: the caller passes valid scene and params pointers or NULL.
        let (scene, p) = unsafe { (carve::scene(scene, &mut regions)?, carve::read(params)?) };
        let leaf_size = p.leaf_size()?;
        let needed = OutValue::new(needed_bytes, true, &mut regions)?;
        let (base, sbase) = (arena.cast::<u8>(), scratch.cast::<u8>());
        check_arena(base)?;
        check_arena(sbase)?;
        let (arena_l, scratch_l) = layouts(scene.prim_count())?;
        for (have, need) in [
            (arena_bytes, arena_l.total_bytes),
            (scratch_bytes, scratch_l.total_bytes),
        ] {
            if have < need {
                needed.write(need);
                return Err(CorayStatus::ArenaTooSmall);
            }
        }
        regions
            .add(base, arena_l.total_bytes, true)
            .add(sbase, scratch_l.total_bytes, true)
            .check()?;
        scene.check()?;
        let c = &scratch_l.counts;
        // SAFETY: both arenas passed check_arena; each layout lies within
        // its arena (checked above), its parts do not overlap (layout
        // formulas) and the arenas overlap neither each other nor the
        // scene (Regions); the caller lends both exclusively for the call.
        let (nodes, blocks, refs, boxes, keys, links, bvh_nodes) = unsafe {
            carve::zero(base, arena_l.total_bytes);
            (
                carve::arena_mut::<WideNode>(base, arena_l.nodes_offset, arena_l.nodes),
                carve::arena_mut::<LeafBlock>(base, arena_l.blocks_offset, arena_l.blocks),
                carve::arena_mut::<u32>(sbase, scratch_l.refs_offset, c.refs),
                carve::arena_mut::<Aabb>(sbase, 0, c.boxes),
                carve::arena_mut::<f32>(sbase, scratch_l.keys_offset, c.keys),
                carve::arena_mut::<u32>(sbase, scratch_l.links_offset, c.links),
                carve::arena_mut::<BvhNode>(sbase, scratch_l.bvh_nodes_offset, c.bvh_nodes),
            )
        };
        let storage = wide::WideStorage { nodes, blocks };
        let scratch = wide::WideScratch {
            refs,
            bvh_nodes,
            boxes,
            keys,
            links,
        };
        let info = *wide::build(&scene, leaf_size, storage, scratch)?.info();
        // The nodes moved down to the corner blocks in use: the arena the
        // tree needs is the prefix up to its last node, and the header
        // records that layout.
        // SAFETY: the build's views of the arena are gone (only `info`, a
        // copy, is left); the layout's bytes are still lent exclusively.
        let bytes = unsafe { carve::arena_mut::<u8>(base, 0, arena_l.total_bytes) };
        let used = arena_l
            .pack(&info, bytes)
            .ok_or(CorayStatus::InternalError)?;
        // SAFETY: as above; the header's bytes lie below the first part.
        unsafe {
            carve::arena_mut::<WideArenaHeader>(base, 0, 1)[0] = WideArenaHeader {
                magic: WIDE_MAGIC,
                version: WIDE_VERSION,
                scene_counts: scene_counts(&scene),
                info,
                layout_bytes: used.total_bytes as u32,
                nodes_cap: used.nodes as u32,
                blocks_cap: used.blocks as u32,
            }
        };
        Ok(())
    })
}

/// Opens the wide hierarchy in `arena` with the scene it was built on:
/// O(1) checks, then `*out` is the handle every trace, info and validate
/// call takes. The arena and the scene's arrays stay in place and
/// unchanged while the handle is used. Validate an arena from untrusted
/// storage once, as for a kd-tree.
///
/// Safety: `arena` is NULL or readable for `arena_bytes`; `scene` and `out`
/// NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn coray_wide_open(
    arena: *const c_void,
    arena_bytes: usize,
    scene: *const CorayScene,
    out: *mut CorayWide,
) -> CorayStatus {
    guard(|| {
        let mut regions = Regions::new();
        // SAFETY: forwarded caller contract.
        let scene = unsafe { carve::scene(scene, &mut regions)? };
        carve::check_array(out, 1)?;
        regions.add(out, size_of::<CorayWide>(), true);
        let base = arena.cast::<u8>();
        check_arena(base)?;
        if arena_bytes < WIDE_HEADER_BYTES {
            return Err(CorayStatus::CorruptArena);
        }
        // SAFETY: aligned, readable for arena_bytes >= one header.
        let h = unsafe { carve::arena_ref::<WideArenaHeader>(base, 0, 1)[0] };
        let l = h.layout(arena_bytes)?;
        regions.add(base, arena_bytes, false).check()?;
        check_scene(h.scene_counts, &scene)?;
        let mut hd = Handle::new(KIND_WIDE, base as usize, l.total_bytes, &scene);
        hd.set_part::<WideArenaHeader>(0, 0, 1)?;
        hd.set_part::<WideNode>(1, l.nodes_offset, l.nodes)?;
        hd.set_part::<LeafBlock>(2, l.blocks_offset, l.blocks)?;
        let words = hd.words();
        // SAFETY: the handle describes the arena just checked, readable.
        unsafe { view_of(Sealed::new(&words, KIND_WIDE)?, scene)? };
        // SAFETY: out checked non-null, aligned, disjoint from the arena.
        unsafe { out.write(CorayWide { opaque: words }) };
        Ok(())
    })
}

/// The header and hierarchy a handle describes, over `scene`.
///
/// Safety: the handle's arena is readable and unchanged during `'a`.
#[inline(always)]
unsafe fn view_of<'a>(
    h: Sealed,
    scene: Scene<'a>,
) -> Result<(&'a WideArenaHeader, WideBvh<'a>), CorayStatus> {
    // SAFETY: the handle's parts lie within its arena (Handle::set_part
    // at open), readable by the caller's contract.
    unsafe {
        let header: &'a WideArenaHeader = &h.part::<WideArenaHeader>(0)[0];
        let w = WideBvh::from_parts(
            scene,
            h.part::<WideNode>(1),
            h.part::<LeafBlock>(2),
            header.info,
        )?;
        Ok((header, w))
    }
}

/// The hierarchy behind a caller's handle, its buffers noted in `regions`.
///
/// Safety: `t` is NULL or a handle `coray_wide_open` filled, whose arena
/// and scene are still in place and unchanged during `'a`.
unsafe fn open<'a>(
    t: *const CorayWide,
    regions: &mut Regions,
) -> Result<(&'a WideArenaHeader, WideBvh<'a>), CorayStatus> {
    // SAFETY: forwarded contract.
    unsafe {
        let h = handle::read(t.cast(), KIND_WIDE, regions)?;
        regions.add(h.arena() as *const u8, h.arena_bytes(), false);
        let scene = h.scene();
        regions.add_scene(&scene);
        view_of(h, scene)
    }
}

/// What the hierarchy holds, from its header (O(1)).
///
/// Safety: `wide` is a handle `coray_wide_open` filled; `out` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn coray_wide_info(
    wide: *const CorayWide,
    out: *mut CorayWideInfo,
) -> CorayStatus {
    guard(|| {
        let mut regions = Regions::new();
        // SAFETY: forwarded caller contract.
        let ((h, w), out) = unsafe {
            (
                open(wide, &mut regions)?,
                Out::new(out, false, &mut regions)?,
            )
        };
        regions.check()?;
        let i = w.info();
        let b = w.bounds();
        out.write(CorayWideInfo {
            struct_size: 0,
            node_count: i.node_count,
            leaf_count: i.leaf_count,
            ref_count: i.ref_count,
            depth: i.depth,
            leaf_size: i.leaf_size,
            arena_bytes_used: h.layout_bytes as usize,
            stack_bytes: w.stack_len().saturating_mul(size_of::<WideStackItem>()),
            bounds_min: b.min.into(),
            bounds_max: b.max.into(),
        });
        Ok(())
    })
}

/// Checks every structural invariant of the hierarchy against its scene,
/// in time linear in the hierarchy, never crashing on any bytes: a tree
/// in breadth-first order, boxes exact unions, indices in range, counts,
/// depth and reference digest as recorded, and the leaves holding exactly
/// the scene's non-degenerate primitives (a scene changed since the build
/// so that one became degenerate or stopped being so is refused).
/// `CORAY_STATUS_CORRUPT_ARENA` when anything is wrong. Once it accepts an arena, every call on it
/// gives the results of a clean build. `out` may be NULL.
///
/// Safety: as `coray_wide_info`.
#[no_mangle]
pub unsafe extern "C" fn coray_wide_validate(
    wide: *const CorayWide,
    out: *mut CorayShape,
) -> CorayStatus {
    guard(|| {
        let mut regions = Regions::new();
        // SAFETY: forwarded caller contract.
        let ((_, w), out) = unsafe {
            (
                open(wide, &mut regions)?,
                Out::new(out, true, &mut regions)?,
            )
        };
        regions.check()?;
        let s = w.validate()?;
        out.write(CorayShape {
            struct_size: 0,
            node_count: s.nodes,
            leaf_count: s.leaves,
            empty_leaf_count: 0,
            ref_count: s.refs,
            depth: s.depth,
        });
        Ok(())
    })
}

/// The body of the array trace entry points: checks the handle, the
/// arrays, the stack and the statistics first, then has `answer` write
/// the answers of the rays (the caller's array, in place), in chunks.
///
/// Safety: as `coray_wide_intersect`, with `out` holding `count` `O`s.
#[allow(clippy::too_many_arguments)]
unsafe fn batch<O>(
    wide: *const CorayWide,
    rays: *const CorayRay,
    out: *mut O,
    count: usize,
    stack: *mut c_void,
    stack_bytes: usize,
    stats: *mut CorayTraceStats,
    answer: impl Fn(&WideBvh, &[coray::Ray], &mut [O], &mut [WideStackItem], &mut TraceStats),
) -> CorayStatus {
    guard(|| {
        let mut regions = Regions::new();
        // SAFETY: forwarded caller contract for every pointer.
        let (w, rays, out, stk, stats) = unsafe {
            let (_, w) = open(wide, &mut regions)?;
            let rays = carve::input(rays, count)?;
            regions.add(rays.as_ptr(), size_of_val(rays), false);
            let out = carve::output(out, count)?;
            regions.add(out.as_ptr(), size_of_val(out), true);
            let need = if count == 0 { 0 } else { w.stack_len() };
            let stk = carve::stack::<WideStackItem>(stack, stack_bytes, need, &mut regions)?;
            (w, rays, out, stk, Out::new(stats, true, &mut regions)?)
        };
        regions.check()?;
        let mut st = TraceStats::default();
        let rays = crate::abi::core_rays(rays);
        for (r, o) in rays.chunks(CHUNK).zip(out.chunks_mut(CHUNK)) {
            answer(&w, r, o, stk, &mut st);
            // A corrupt arena: the call stops at the first group that
            // met it.
            if st.faults > 0 {
                return Err(CorayStatus::CorruptArena);
            }
        }
        stats.write(CorayTraceStats::of(&st));
        Ok(())
    })
}

/// Rays an array call hands the kernels at a time: whole packets, and few
/// enough that the any-hit answers fit on the stack.
const CHUNK: usize = 64;

/// The body of the one-ray entry points: [`one_ray`] on a wide
/// hierarchy, writing `answer` for the ray.
///
/// Safety: as `coray_wide_intersect1`, with `out` one writable `O`.
#[inline(always)]
unsafe fn one<O>(
    wide: *const CorayWide,
    ray: *const CorayRay,
    out: *mut O,
    stack: *mut c_void,
    stack_bytes: usize,
    stats: *mut CorayTraceStats,
    answer: impl FnOnce(&WideBvh, &coray::Ray, &mut [WideStackItem], &mut TraceStats) -> O,
) -> CorayStatus {
    guard(|| {
        // SAFETY: forwarded caller contract.
        unsafe {
            one_ray(
                wide.cast(),
                KIND_WIDE,
                |h, s| Ok(view_of(h, s)?.1),
                |w| w.stack_len(),
                ray,
                out,
                stack,
                stack_bytes,
                stats,
                |w, r, s, st| Ok(answer(w, r, s, st)),
            )
        }
    })
}

/// Closest hits of `count` rays: `hits[i]` for `rays[i]`. Runs of eight
/// rays that agree on their direction signs (camera tiles, shadow rays
/// towards one light) are traced together in packets where the CPU has
/// AVX2; the answers are the one-ray calls' either way. `stack` is the
/// caller's traversal stack of `stack_bytes` (at least the info's
/// `stack_bytes`, 16-byte aligned; one per thread). `stats` may be NULL.
/// Many threads may trace one hierarchy at once, each with its own stack.
///
/// Safety: `wide` as in `coray_wide_info`; `rays` and `hits` hold `count`
/// elements (may be NULL when `count` is 0); `stack` is writable for
/// `stack_bytes`; `stats` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn coray_wide_intersect(
    wide: *const CorayWide,
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
            wide,
            rays,
            hits,
            count,
            stack,
            stack_bytes,
            stats,
            |w, r, o, s, st| {
                crate::simd::wide_intersect_packets(w, r, crate::abi::core_hits(o), s, st)
            },
        )
    }
}

/// `coray_wide_intersect` for one ray, checked in full on every call. A thread
/// tracing one ray per call makes a tracer (`coray_wide_tracer`) and calls
/// `coray_wide_tracer_intersect1`: the same answer, the checks made once.
///
/// Safety: as `coray_wide_intersect` with `count` 1.
#[no_mangle]
pub unsafe extern "C" fn coray_wide_intersect1(
    wide: *const CorayWide,
    ray: *const CorayRay,
    hit: *mut CorayHit,
    stack: *mut c_void,
    stack_bytes: usize,
    stats: *mut CorayTraceStats,
) -> CorayStatus {
    if ray.is_null() || hit.is_null() {
        return CorayStatus::NullPointer;
    }
    // SAFETY: forwarded caller contract.
    unsafe {
        one(wide, ray, hit, stack, stack_bytes, stats, |w, r, s, st| {
            crate::simd::wide_intersect(w, r, s, st).into()
        })
    }
}

/// Any-hit queries (shadow rays): `occluded[i]` is 1 when something lies
/// on `rays[i]` within `[tnear, tfar]`, else 0. Otherwise as
/// `coray_wide_intersect`.
///
/// Safety: as `coray_wide_intersect`, with `occluded` holding `count` bytes.
#[no_mangle]
pub unsafe extern "C" fn coray_wide_occluded(
    wide: *const CorayWide,
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
            wide,
            rays,
            occluded,
            count,
            stack,
            stack_bytes,
            stats,
            |w, r, o, s, st| {
                let mut occ = [false; CHUNK];
                let occ = &mut occ[..r.len()];
                crate::simd::wide_occluded_packets(w, r, occ, s, st);
                for (b, &x) in o.iter_mut().zip(occ.iter()) {
                    *b = x as u8;
                }
            },
        )
    }
}

/// `coray_wide_occluded` for one ray, checked in full on every call. A thread
/// tracing one ray per call makes a tracer (`coray_wide_tracer`) and calls
/// `coray_wide_tracer_occluded1`: the same answer, the checks made once.
///
/// Safety: as `coray_wide_occluded` with `count` 1.
#[no_mangle]
pub unsafe extern "C" fn coray_wide_occluded1(
    wide: *const CorayWide,
    ray: *const CorayRay,
    occluded: *mut u8,
    stack: *mut c_void,
    stack_bytes: usize,
    stats: *mut CorayTraceStats,
) -> CorayStatus {
    if ray.is_null() || occluded.is_null() {
        return CorayStatus::NullPointer;
    }
    // SAFETY: forwarded caller contract.
    unsafe {
        one(
            wide,
            ray,
            occluded,
            stack,
            stack_bytes,
            stats,
            |w, r, s, st| crate::simd::wide_occluded(w, r, s, st) as u8,
        )
    }
}

/// Makes `tracer` trace `wide` with the caller's `stack` (at least the
/// info's `stack_bytes`, 16-byte aligned): one thread's
/// `coray_wide_tracer_intersect1` and `_occluded1` calls then skip the checks
/// this call makes. Since 1.5.
///
/// Safety: `wide` as in `coray_wide_info`; `stack` NULL or writable
/// for `stack_bytes`, and used by nothing else while the tracer is;
/// `tracer` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn coray_wide_tracer(
    wide: *const CorayWide,
    stack: *mut c_void,
    stack_bytes: usize,
    tracer: *mut CorayTracer,
) -> CorayStatus {
    guard(|| {
        // SAFETY: forwarded caller contract.
        unsafe {
            tracer::make::<_, WideStackItem>(
                tracer,
                wide.cast(),
                KIND_WIDE,
                0,
                |h, s| Ok(view_of(h, s)?.1),
                |x| x.stack_len(),
                |_| [0; tracer::HINT_WORDS],
                stack,
                stack_bytes,
            )
        }
    })
}

/// `coray_wide_tracer_intersect1` and `_occluded1` on a tracer of this family:
/// `answer` for the ray.
///
/// Safety: as `coray_wide_tracer_intersect1`, with `out` one writable `O`.
#[inline(always)]
unsafe fn traced<O>(
    tracer: *mut CorayTracer,
    ray: *const CorayRay,
    out: *mut O,
    answer: impl FnOnce(&WideBvh, &coray::Ray, &mut [WideStackItem], &mut TraceStats) -> O,
) -> Result<(), CorayStatus> {
    // SAFETY: forwarded caller contract.
    unsafe {
        tracer::trace(
            tracer,
            KIND_WIDE,
            #[inline(always)]
            |h, s, _| Ok(view_of(h, s)?.1),
            #[inline(always)]
            |x| x.stack_len(),
            ray,
            out,
            |_, _, _| None,
            #[inline(always)]
            |x, _, r, s, st| Ok(answer(x, r, s, st)),
        )
    }
}

/// The closest hit of `ray` by a tracer of this wide hierarchy (made by
/// `coray_wide_tracer`), into `hit`: `coray_wide_intersect1`'s answer, with
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
pub unsafe extern "C" fn coray_wide_tracer_intersect1(
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
                #[inline(always)]
                |x, r, s, st| crate::simd::wide_intersect(x, r, s, st).into(),
            )
        }
    })
}

/// Whether something lies on `ray` within `[tnear, tfar]` (1) or not (0),
/// by a tracer of this wide hierarchy, into `occluded`: `coray_wide_occluded1`'s
/// answer. Otherwise as `coray_wide_tracer_intersect1`. Since 1.5.
///
/// Safety: as `coray_wide_tracer_intersect1`, with `occluded` one writable
/// byte.
#[no_mangle]
pub unsafe extern "C" fn coray_wide_tracer_occluded1(
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
                #[inline(always)]
                |x, r, s, st| crate::simd::wide_occluded(x, r, s, st) as u8,
            )
        }
    })
}
