//! LCTS over an opened kd-tree (Havran and Bittner 2000):
//! `coray_kdtree_cast_image` (one primary ray per pixel, seven schemes) and
//! `coray_kdtree_patch_visibility`, each with its requirements.

use crate::abi::*;
use crate::carve::{self, check_arena, Out, Regions, Versioned};
use crate::kdtree::{open, CORAY_KDTREE_STACK_BYTES};
use crate::{guard, CorayKdTree, CorayStatus};
use coray::kd::{KdStackItem, KD_STACK_LEN};
use coray::lcts::layout::{ImageScratchLayout, PatchScratchLayout};
use coray::lcts::{self, patch, ImageScratch, PixelRect, Scheme};
use coray::limits::MAX_HISTORY_CAPACITY;
use coray::{Camera, Vec3};
use core::ffi::c_void;
use core::mem::size_of;

/// How an image is cast: one of the `CORAY_CAST_*` schemes.
pub type CorayCastScheme = u32;
/// Every pixel by hierarchical traversal (the reference).
pub const CORAY_CAST_HIERARCHICAL: CorayCastScheme = 0;
/// Every pixel by rope traversal.
pub const CORAY_CAST_ROPES: CorayCastScheme = 1;
/// SLCTS on each scanline, windows of `window_width x 1` pixels.
pub const CORAY_CAST_SLCTS_1D: CorayCastScheme = 2;
/// SLCTS in windows of `window_width x window_height` pixels.
pub const CORAY_CAST_SLCTS_2D: CorayCastScheme = 3;
/// HLCTS by bisection of each scanline.
pub const CORAY_CAST_HLCTS_1D: CorayCastScheme = 4;
/// HLCTS by 2D bisection, alternating axes.
pub const CORAY_CAST_HLCTS_2D: CorayCastScheme = 5;
/// Every 4 x 2 pixel tile as one packet of eight rays that walk the tree
/// together (the widest kernel this CPU runs): no ropes, no scratch; the
/// fastest scheme on primary rays. Since 1.6.
pub const CORAY_CAST_PACKETS: CorayCastScheme = 6;

/// A pinhole camera as NFF's `v` block gives it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CorayCamera {
    /// `sizeof(CorayCamera)`.
    pub struct_size: usize,
    /// Eye.
    pub from: [f32; 3],
    /// Point looked at (not the eye).
    pub at: [f32; 3],
    /// Up vector (not along the view direction).
    pub up: [f32; 3],
    /// Field of view in degrees, in (0, 180) (NFF's angle).
    pub angle_deg: f32,
    /// Image width in pixels (1 to 32768).
    pub width: u32,
    /// Image height in pixels (1 to 32768).
    pub height: u32,
}

/// How an image is cast. Get it from `coray_cast_params_default`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CorayCastParams {
    /// `sizeof(CorayCastParams)`.
    pub struct_size: usize,
    /// `CORAY_CAST_*`.
    pub scheme: CorayCastScheme,
    /// SLCTS window width (at least 2; the paper's 5).
    pub window_width: u32,
    /// SLCTS-2D window height (at least 2; the paper's 5).
    pub window_height: u32,
    /// Records kept per traversal history (1 to 2^20): larger shares more,
    /// never changes results.
    pub history_capacity: u32,
    /// The pixels to cast (since 1.6): columns `rect_x` to `rect_x +
    /// rect_width - 1` and rows `rect_y` to `rect_y + rect_height - 1` of
    /// the camera's image, which must hold them; `hits` then holds
    /// `rect_width * rect_height` answers, row by row. Each pixel gets what
    /// the whole image's cast gives it, so threads may cast an image's tiles
    /// at once, each with its own scratch, stack and hits. All four 0 (the
    /// default, and a struct from before 1.6): the whole image.
    pub rect_x: u32,
    /// See `rect_x`.
    pub rect_y: u32,
    /// See `rect_x`.
    pub rect_width: u32,
    /// See `rect_x`.
    pub rect_height: u32,
}

/// Result of a patch-to-patch visibility query.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CorayPatchResult {
    /// `sizeof(CorayPatchResult)`.
    pub struct_size: usize,
    /// Sample segments that meet nothing.
    pub visible: u32,
    /// Sample segments cast (`samples_per_side^4`).
    pub samples: u32,
    /// Entries of the HLCTS the segments started from.
    pub cut_len: u32,
}

// SAFETY (all): repr(C), size_t struct_size first, integer and float
// fields only; as first published.
unsafe impl Versioned for CorayCamera {
    const SIZE_1_0: usize = size_of::<Self>();
}
unsafe impl Versioned for CorayCastParams {
    // 1.0 ended at `history_capacity` (a size_t and four u32s: no padding).
    const SIZE_1_0: usize = core::mem::offset_of!(CorayCastParams, rect_x);
}
unsafe impl Versioned for CorayPatchResult {
    const SIZE_1_0: usize = size_of::<Self>();
}

/// A camera at (0, 0, 1) looking at the origin, y up, 45 degrees, 64 x 64
/// pixels, `struct_size` set.
#[no_mangle]
pub extern "C" fn coray_camera_default() -> CorayCamera {
    CorayCamera {
        struct_size: size_of::<CorayCamera>(),
        from: [0.0, 0.0, 1.0],
        at: [0.0, 0.0, 0.0],
        up: [0.0, 1.0, 0.0],
        angle_deg: 45.0,
        width: 64,
        height: 64,
    }
}

/// A `CorayPatchResult` to fill, `struct_size` set.
#[no_mangle]
pub extern "C" fn coray_patch_result_default() -> CorayPatchResult {
    CorayPatchResult {
        struct_size: size_of::<CorayPatchResult>(),
        ..Default::default()
    }
}

/// Default cast parameters: `CORAY_CAST_PACKETS` (the fastest scheme, and
/// one a tree without ropes casts), and for the LCTS schemes 5 x 5 windows
/// and 256 records per history. (Before 1.6 the default scheme was
/// `CORAY_CAST_SLCTS_2D`; every scheme gives the same hits.)
#[no_mangle]
pub extern "C" fn coray_cast_params_default() -> CorayCastParams {
    CorayCastParams {
        struct_size: size_of::<CorayCastParams>(),
        scheme: CORAY_CAST_PACKETS,
        window_width: 5,
        window_height: 5,
        history_capacity: 256,
        ..Default::default()
    }
}

/// The core's camera, or `InvalidParameter` for a degenerate one (an eye
/// on the point looked at, an up vector along the view, NaN).
pub(crate) fn camera(c: &CorayCamera) -> Result<Camera, CorayStatus> {
    let cam = Camera {
        from: Vec3::from(c.from),
        at: Vec3::from(c.at),
        up: Vec3::from(c.up),
        angle_deg: c.angle_deg,
        width: c.width,
        height: c.height,
    };
    match cam.fault() {
        None => Ok(cam),
        Some(_) => Err(CorayStatus::InvalidParameter),
    }
}

fn scheme(p: &CorayCastParams) -> Result<(Scheme, usize), CorayStatus> {
    if !(1..=MAX_HISTORY_CAPACITY).contains(&p.history_capacity) {
        return Err(CorayStatus::InvalidParameter);
    }
    let s = match p.scheme {
        CORAY_CAST_HIERARCHICAL => Scheme::Hierarchical,
        CORAY_CAST_ROPES => Scheme::Ropes,
        CORAY_CAST_SLCTS_1D if p.window_width >= 2 => Scheme::Slcts1d { n: p.window_width },
        CORAY_CAST_SLCTS_2D if p.window_width >= 2 && p.window_height >= 2 => Scheme::Slcts2d {
            n: p.window_width,
            m: p.window_height,
        },
        CORAY_CAST_HLCTS_1D => Scheme::Hlcts1d,
        CORAY_CAST_HLCTS_2D => Scheme::Hlcts2d,
        CORAY_CAST_PACKETS => Scheme::Packets,
        _ => return Err(CorayStatus::InvalidParameter),
    };
    Ok((s, p.history_capacity as usize))
}

/// The pixels `p` names of `cam`'s image: its rectangle, or the whole
/// image when all four fields are 0; `InvalidParameter` for an empty one or
/// one that leaves the image.
fn pixels(cam: &Camera, p: &CorayCastParams) -> Result<PixelRect, CorayStatus> {
    let rect = PixelRect {
        x: p.rect_x,
        y: p.rect_y,
        width: p.rect_width,
        height: p.rect_height,
    };
    if rect == PixelRect::default() {
        return Ok(PixelRect::whole(cam));
    }
    if rect.fits(cam) {
        Ok(rect)
    } else {
        Err(CorayStatus::InvalidParameter)
    }
}

/// The cast's scratch (without its stack, which is a separate argument).
fn layout(rect: &PixelRect, s: Scheme, cap: usize) -> Result<ImageScratchLayout, CorayStatus> {
    let req = lcts::image_requirements(rect.width, rect.height, s, cap);
    ImageScratchLayout::of(&lcts::ImageRequirements { stack: 0, ..req })
        .ok_or(CorayStatus::InvalidParameter)
}

/// Scratch and stack bytes `coray_kdtree_cast_image` needs for this camera
/// and these parameters (`scratch_bytes`, with `scratch_min_bytes` the
/// same; the arena fields are 0).
///
/// Safety: every pointer is NULL or valid for its type.
#[no_mangle]
pub unsafe extern "C" fn coray_kdtree_cast_requirements(
    camera_in: *const CorayCamera,
    params: *const CorayCastParams,
    out: *mut CorayRequirements,
) -> CorayStatus {
    guard(|| {
        let mut regions = Regions::new();
        // SAFETY: the caller passes valid pointers or NULL.
        let (c, params, out) = unsafe {
            (
                camera(&carve::read(camera_in)?)?,
                carve::read(params)?,
                Out::new(out, false, &mut regions)?,
            )
        };
        let (s, cap) = scheme(&params)?;
        let bytes = layout(&pixels(&c, &params)?, s, cap)?.total_bytes;
        out.write(CorayRequirements {
            struct_size: 0,
            arena_min_bytes: 0,
            arena_bytes: 0,
            scratch_min_bytes: bytes,
            scratch_bytes: bytes,
            stack_bytes: CORAY_KDTREE_STACK_BYTES,
        });
        Ok(())
    })
}

/// Casts one primary ray per pixel of the camera (or of the rectangle of
/// `params`) through the tree with the scheme of `params`: `hits[y * width
/// + x]` receives the closest hit of pixel (x, y) (of the rectangle's
/// pixel (x, y): `hits[y * rect_width + x]`), exactly what hierarchical
/// traversal gives (every scheme).
/// `scratch` (16-byte aligned, the requirements' `scratch_bytes`; NULL
/// when that is 0) is free again afterwards; `stack` as for
/// `coray_kdtree_intersect`; `stats` may be NULL. Every scheme but
/// `CORAY_CAST_HIERARCHICAL` and `CORAY_CAST_PACKETS` walks ropes: a tree
/// without them gets `CORAY_STATUS_NO_ROPES` and nothing is written.
///
/// Safety: `tree` as in `coray_kdtree_info`; `hits` holds `width * height`
/// elements; `scratch` and `stack` are writable for their sizes and used
/// by nobody else during the call.
#[no_mangle]
pub unsafe extern "C" fn coray_kdtree_cast_image(
    tree: *const CorayKdTree,
    camera_in: *const CorayCamera,
    params: *const CorayCastParams,
    scratch: *mut c_void,
    scratch_bytes: usize,
    stack: *mut c_void,
    stack_bytes: usize,
    hits: *mut CorayHit,
    stats: *mut CorayTraceStats,
) -> CorayStatus {
    guard(|| {
        let mut regions = Regions::new();
        // SAFETY: forwarded caller contract for every pointer.
        let (t, c, params) = unsafe {
            (
                open(tree, &mut regions)?,
                camera(&carve::read(camera_in)?)?,
                carve::read(params)?,
            )
        };
        let (s, cap) = scheme(&params)?;
        let rect = pixels(&c, &params)?;
        let count = rect.width as usize * rect.height as usize;
        let l = layout(&rect, s, cap)?;
        let base = scratch.cast::<u8>();
        if l.total_bytes > 0 {
            check_arena(base)?;
            if scratch_bytes < l.total_bytes {
                return Err(CorayStatus::ArenaTooSmall);
            }
            regions.add(base, l.total_bytes, true);
        }
        // SAFETY: forwarded caller contract: a hit for each pixel cast
        // writable, a writable stack, NULL or a writable stats struct.
        let (out, stk, stats) = unsafe {
            let out = carve::output(hits, count)?;
            regions.add(out.as_ptr(), size_of_val(out), true);
            (
                out,
                carve::stack::<KdStackItem>(stack, stack_bytes, KD_STACK_LEN, &mut regions)?,
                Out::new(stats, true, &mut regions)?,
            )
        };
        regions.check()?;
        let n = &l.counts;
        // SAFETY: base passed check_arena (or every part is empty, and a
        // dangling aligned pointer serves for empty slices); the parts lie
        // within scratch_bytes at 16-aligned offsets without overlap
        // (ImageScratchLayout) and apart from every other buffer
        // (Regions); the caller lends the scratch exclusively.
        let sc = unsafe {
            let b = if l.total_bytes == 0 {
                core::ptr::NonNull::<u128>::dangling().as_ptr().cast::<u8>()
            } else {
                base
            };
            ImageScratch {
                records: carve::arena_mut(b, l.offsets[0], n.records),
                entries: carve::arena_mut(b, l.offsets[1], n.entries),
                corners: carve::arena_mut(b, l.offsets[2], n.corners),
                starts: carve::arena_mut(b, l.offsets[3], n.starts),
                hlcts: carve::arena_mut(b, l.offsets[4], n.hlcts),
                stack: stk,
            }
        };
        let w = rect.width as usize;
        let st = crate::simd::cast_rect_with(&t, &c, rect, s, sc, |x, y, h| {
            out[(y - rect.y) as usize * w + (x - rect.x) as usize] = (*h).into();
        })?;
        if st.trace.faults > 0 {
            return Err(CorayStatus::CorruptArena);
        }
        let mut cs = CorayTraceStats::of(&st.trace);
        cs.windows = st.windows;
        cs.windows_shared = st.windows_shared;
        cs.windows_terminated = st.windows_terminated;
        cs.windows_entered = st.windows_entered;
        stats.write(cs);
        Ok(())
    })
}

/// Scratch and stack bytes of `coray_kdtree_patch_visibility` for
/// histories of up to `history_capacity` records (1 to 2^20).
///
/// Safety: `out` is NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn coray_kdtree_patch_requirements(
    history_capacity: u32,
    out: *mut CorayRequirements,
) -> CorayStatus {
    guard(|| {
        let mut regions = Regions::new();
        // SAFETY: the caller passes a valid pointer or NULL.
        let out = unsafe { Out::new(out, false, &mut regions)? };
        if !(1..=MAX_HISTORY_CAPACITY).contains(&history_capacity) {
            return Err(CorayStatus::InvalidParameter);
        }
        let l = patch_layout(history_capacity as usize)?;
        let min = patch_layout(1)?;
        out.write(CorayRequirements {
            struct_size: 0,
            arena_min_bytes: 0,
            arena_bytes: 0,
            scratch_min_bytes: min.stack_offset,
            scratch_bytes: l.stack_offset,
            stack_bytes: CORAY_KDTREE_STACK_BYTES,
        });
        Ok(())
    })
}

/// The patch scratch of `cap`: records, cut and paths (the stack is its
/// own argument, so the scratch ends where the layout's stack part starts).
fn patch_layout(cap: usize) -> Result<PatchScratchLayout, CorayStatus> {
    PatchScratchLayout::of(cap).ok_or(CorayStatus::InvalidParameter)
}

/// Visibility between two convex patches (3 or 4 vertices each, `x y z`
/// per vertex): `samples_per_side x samples_per_side` points on each patch
/// (1 to 255), every segment between them trimmed by `eps` (in [0, 0.5))
/// of its length at both ends, all started from one HLCTS of the
/// vertex-to-vertex segments. The visible fraction is `visible / samples`;
/// each segment's answer is exactly what hierarchical traversal gives.
/// `scratch` (16-byte aligned; its size sets the history capacity),
/// `stack` as for `coray_kdtree_intersect`; `stats` (may be NULL) counts
/// every segment, boundary and sample.
///
/// Safety: `tree` as in `coray_kdtree_info`; `patch_a` and `patch_b` hold
/// `3 * count` floats; `scratch` and `stack` writable for their sizes;
/// `out` writable; `stats` NULL or writable.
#[no_mangle]
pub unsafe extern "C" fn coray_kdtree_patch_visibility(
    tree: *const CorayKdTree,
    patch_a: *const f32,
    count_a: u32,
    patch_b: *const f32,
    count_b: u32,
    samples_per_side: u32,
    eps: f32,
    scratch: *mut c_void,
    scratch_bytes: usize,
    stack: *mut c_void,
    stack_bytes: usize,
    out: *mut CorayPatchResult,
    stats: *mut CorayTraceStats,
) -> CorayStatus {
    guard(|| {
        let mut regions = Regions::new();
        // SAFETY: forwarded caller contract for every pointer.
        let (t, a, b, out, stats) = unsafe {
            let t = open(tree, &mut regions)?;
            let a = carve::input(patch_a.cast::<[f32; 3]>(), count_a as usize)?;
            let b = carve::input(patch_b.cast::<[f32; 3]>(), count_b as usize)?;
            regions
                .add(a.as_ptr(), size_of_val(a), false)
                .add(b.as_ptr(), size_of_val(b), false);
            let out = Out::new(out, false, &mut regions)?;
            (t, a, b, out, Out::new(stats, true, &mut regions)?)
        };
        let n = patch::MAX_PATCH_VERTICES;
        if !(3..=n).contains(&a.len()) || !(3..=n).contains(&b.len()) {
            return Err(CorayStatus::InvalidParameter);
        }
        let base = scratch.cast::<u8>();
        check_arena(base)?;
        // The largest history capacity whose records, cut and paths fit.
        let l =
            PatchScratchLayout::fit(scratch_bytes.saturating_add(CORAY_KDTREE_STACK_BYTES + 16))
                .filter(|l| l.stack_offset <= scratch_bytes)
                .ok_or(CorayStatus::ArenaTooSmall)?;
        regions.add(base, l.stack_offset, true);
        // SAFETY: forwarded caller contract: a writable stack.
        let stk =
            unsafe { carve::stack::<KdStackItem>(stack, stack_bytes, KD_STACK_LEN, &mut regions)? };
        regions.check()?;
        let pa: [Vec3; 4] = core::array::from_fn(|i| Vec3::from(*a.get(i).unwrap_or(&a[0])));
        let pb: [Vec3; 4] = core::array::from_fn(|i| Vec3::from(*b.get(i).unwrap_or(&b[0])));
        let k = lcts::hlcts::MAX_RAYS * l.capacity;
        // SAFETY: aligned scratch (checked); the three parts lie within
        // l.stack_offset <= scratch_bytes at 16-aligned offsets without
        // overlap (PatchScratchLayout), apart from the other buffers
        // (Regions); lent exclusively by the caller.
        let sc = unsafe {
            patch::PatchScratch {
                records: carve::arena_mut(base, 0, k),
                hlcts: carve::arena_mut(base, l.hlcts_offset, k),
                paths: carve::arena_mut(base, l.paths_offset, k),
                stack: stk,
            }
        };
        let r = patch::patch_visibility(
            &t,
            &pa[..a.len()],
            &pb[..b.len()],
            samples_per_side,
            eps,
            sc,
        )?;
        let mut all = r.trace;
        all.add(&r.boundary);
        if all.faults > 0 {
            return Err(CorayStatus::CorruptArena);
        }
        out.write(CorayPatchResult {
            struct_size: 0,
            visible: r.visible,
            samples: r.samples,
            cut_len: r.cut_len,
        });
        stats.write(CorayTraceStats::of(&all));
        Ok(())
    })
}
