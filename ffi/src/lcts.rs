//! `coray_kdtree_cast_image` and `coray_kdtree_patch_visibility`: LCTS
//! (Havran and Bittner 2000) over a built kd-tree, in caller scratch.

use crate::carve::{self, check_arena, slice_mut};
use crate::kdtree::tree;
use crate::types::*;
use crate::{guard, CorayStatus};
use coray::arena::ImageScratchLayout;
use coray::lcts::{self, patch, ImageScratch, Scheme};
use coray::{Camera, Vec3};
use core::ffi::c_void;

/// Every pixel by hierarchical traversal (the reference).
pub const CORAY_SCHEME_HIERARCHICAL: u32 = 0;
/// Every pixel by rope traversal.
pub const CORAY_SCHEME_ROPES: u32 = 1;
/// SLCTS on each scanline, windows of `window_width x 1` pixels.
pub const CORAY_SCHEME_SLCTS_1D: u32 = 2;
/// SLCTS in windows of `window_width x window_height` pixels.
pub const CORAY_SCHEME_SLCTS_2D: u32 = 3;
/// HLCTS by bisection of each scanline.
pub const CORAY_SCHEME_HLCTS_1D: u32 = 4;
/// HLCTS by 2D bisection, alternating axes.
pub const CORAY_SCHEME_HLCTS_2D: u32 = 5;

/// A pinhole camera as NFF's `v` block gives it.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CorayCamera {
    /// `sizeof(CorayCamera)`.
    pub struct_size: usize,
    /// Eye.
    pub from: [f32; 3],
    /// Point looked at.
    pub at: [f32; 3],
    /// Up vector.
    pub up: [f32; 3],
    /// Field of view in degrees (NFF's angle).
    pub angle_deg: f32,
    /// Image width in pixels (1 to 32768).
    pub width: u32,
    /// Image height in pixels (1 to 32768).
    pub height: u32,
}

/// How an image is cast. Get it from [`coray_cast_params_default`].
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CorayCastParams {
    /// `sizeof(CorayCastParams)`.
    pub struct_size: usize,
    /// `CORAY_SCHEME_*`.
    pub scheme: u32,
    /// SLCTS window width (at least 2; the paper's 5).
    pub window_width: u32,
    /// SLCTS-2D window height (at least 2; the paper's 5).
    pub window_height: u32,
    /// Records kept per traversal history (at least 1): larger shares more,
    /// never changes results.
    pub history_capacity: u32,
}

/// What a cast did.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CorayCastStats {
    /// Work of all rays cast (boundary rays included).
    pub trace: CorayTraceStats,
    /// Shafts (windows, intervals, rectangles) given a common sequence.
    pub windows: u64,
    /// Of those, shafts whose sequence starts with a shared leaf (gamma = this / windows).
    pub windows_shared: u64,
    /// Shafts with a termination object.
    pub windows_terminated: u64,
    /// SLCTS windows without a shared leaf whose rays started below the
    /// root, at their corners' deepest common node.
    pub windows_entered: u64,
}

/// Result of a patch-to-patch visibility query.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct CorayPatchResult {
    /// Sample segments that meet nothing.
    pub visible: u32,
    /// Sample segments cast (`samples_per_side^4`).
    pub samples: u32,
    /// Entries of the HLCTS the segments started from.
    pub cut_len: u32,
    /// Work of the vertex-to-vertex segments that built the HLCTS.
    pub boundary: CorayTraceStats,
    /// Work of the sample segments.
    pub trace: CorayTraceStats,
}

/// Default cast parameters: SLCTS-2D, 5 x 5 windows, 256 records per history.
#[no_mangle]
pub extern "C" fn coray_cast_params_default() -> CorayCastParams {
    CorayCastParams {
        struct_size: core::mem::size_of::<CorayCastParams>(),
        scheme: CORAY_SCHEME_SLCTS_2D,
        window_width: 5,
        window_height: 5,
        history_capacity: 256,
    }
}

pub(crate) fn camera(c: &CorayCamera) -> Result<Camera, CorayStatus> {
    let ok = c.struct_size == core::mem::size_of::<CorayCamera>()
        && (1..=1 << 15).contains(&c.width)
        && (1..=1 << 15).contains(&c.height)
        && c.angle_deg > 0.0
        && c.angle_deg < 180.0
        && [c.from, c.at, c.up]
            .iter()
            .all(|v| Vec3::from(*v).is_finite());
    if !ok {
        return Err(CorayStatus::InvalidParameter);
    }
    Ok(Camera {
        from: c.from.into(),
        at: c.at.into(),
        up: c.up.into(),
        angle_deg: c.angle_deg,
        width: c.width,
        height: c.height,
    })
}

fn scheme(p: &CorayCastParams) -> Result<(Scheme, usize), CorayStatus> {
    if p.struct_size != core::mem::size_of::<CorayCastParams>()
        || p.history_capacity == 0
        || p.history_capacity > 1 << 20
    {
        return Err(CorayStatus::InvalidParameter);
    }
    let s = match p.scheme {
        CORAY_SCHEME_HIERARCHICAL => Scheme::Hierarchical,
        CORAY_SCHEME_ROPES => Scheme::Ropes,
        CORAY_SCHEME_SLCTS_1D if p.window_width >= 2 => Scheme::Slcts1d { n: p.window_width },
        CORAY_SCHEME_SLCTS_2D if p.window_width >= 2 && p.window_height >= 2 => Scheme::Slcts2d {
            n: p.window_width,
            m: p.window_height,
        },
        CORAY_SCHEME_HLCTS_1D => Scheme::Hlcts1d,
        CORAY_SCHEME_HLCTS_2D => Scheme::Hlcts2d,
        _ => return Err(CorayStatus::InvalidParameter),
    };
    Ok((s, p.history_capacity as usize))
}

fn layout(cam: &Camera, s: Scheme, cap: usize) -> ImageScratchLayout {
    ImageScratchLayout::of(&lcts::image_requirements(cam.width, cam.height, s, cap))
}

/// Bytes of scratch `coray_kdtree_cast_image` needs for this camera and
/// these parameters (0 for the hierarchical and rope schemes).
///
/// # Safety
/// Every pointer is NULL or valid for its type.
#[no_mangle]
pub unsafe extern "C" fn coray_cast_requirements(
    cam: *const CorayCamera,
    params: *const CorayCastParams,
    scratch_bytes: *mut usize,
) -> CorayStatus {
    guard(|| {
        // SAFETY: the caller passes valid pointers or NULL.
        let (c, p) = unsafe {
            (
                camera(carve::input_ref(cam)?)?,
                scheme(carve::input_ref(params)?)?,
            )
        };
        let bytes = layout(&c, p.0, p.1).total_bytes;
        // SAFETY: NULL or a writable size_t (caller's contract).
        *unsafe { carve::output(scratch_bytes, 1)? }
            .first_mut()
            .ok_or(CorayStatus::NullPointer)? = bytes;
        Ok(())
    })
}

/// Casts one primary ray per pixel of `cam` through the tree with the
/// scheme of `params`. `t_out[y * width + x]` receives the hit distance
/// (infinity on a miss), `prim_out` the global primitive index (triangles,
/// then spheres, then cones; `CORAY_INVALID_ID` on a miss): every scheme
/// gives exactly what hierarchical traversal gives. `scratch` (16-byte
/// aligned, `coray_cast_requirements` bytes; may be NULL when that is 0) is
/// free again afterwards. `stats` may be NULL.
///
/// # Safety
/// As `coray_kdtree_intersect`; `t_out` and `prim_out` hold `width * height`
/// elements; the scratch is used by nobody else during the call.
#[no_mangle]
pub unsafe extern "C" fn coray_kdtree_cast_image(
    tree_arena: *const c_void,
    tree_bytes: usize,
    scene: *const CorayScene,
    cam: *const CorayCamera,
    params: *const CorayCastParams,
    scratch: *mut c_void,
    scratch_bytes: usize,
    t_out: *mut f32,
    prim_out: *mut u32,
    stats: *mut CorayCastStats,
) -> CorayStatus {
    guard(|| {
        // SAFETY: forwarded caller contract for every pointer.
        let (t, c, (s, cap)) = unsafe {
            (
                tree(tree_arena, tree_bytes, carve::scene(scene)?)?,
                camera(carve::input_ref(cam)?)?,
                scheme(carve::input_ref(params)?)?,
            )
        };
        let pixels = c.width as usize * c.height as usize;
        // SAFETY: caller's contract: width * height writable elements each.
        let (t_buf, p_buf) = unsafe {
            (
                carve::output(t_out, pixels)?,
                carve::output(prim_out, pixels)?,
            )
        };
        let l = layout(&c, s, cap);
        let base = scratch.cast::<u8>();
        if l.total_bytes > 0 {
            check_arena(base)?;
            if scratch_bytes < l.total_bytes {
                return Err(CorayStatus::ArenaTooSmall);
            }
        }
        let n = &l.counts;
        // SAFETY: base passed check_arena (or every part is empty, and a
        // dangling aligned pointer serves for empty slices); the parts lie
        // within scratch_bytes at 16-aligned offsets without overlap
        // (ImageScratchLayout); the caller lends the scratch exclusively.
        let sc = unsafe {
            let b = if l.total_bytes == 0 {
                core::ptr::NonNull::<u128>::dangling().as_ptr().cast::<u8>()
            } else {
                base
            };
            ImageScratch {
                records: slice_mut(b, l.offsets[0], n.records),
                entries: slice_mut(b, l.offsets[1], n.entries),
                corners: slice_mut(b, l.offsets[2], n.corners),
                starts: slice_mut(b, l.offsets[3], n.starts),
                hlcts: slice_mut(b, l.offsets[4], n.hlcts),
            }
        };
        let st = lcts::cast_image(&t, &c, s, sc, t_buf, p_buf)?;
        if !stats.is_null() {
            // SAFETY: non-null; writable by the caller's contract.
            if let Some(o) = unsafe { carve::output(stats, 1)? }.first_mut() {
                *o = CorayCastStats {
                    trace: st.trace.into(),
                    windows: st.windows,
                    windows_shared: st.windows_shared,
                    windows_terminated: st.windows_terminated,
                    windows_entered: st.windows_entered,
                };
            }
        }
        Ok(())
    })
}

/// Scratch bytes of `coray_kdtree_patch_visibility` for histories of up to
/// `history_capacity` records.
#[no_mangle]
pub extern "C" fn coray_patch_requirements(history_capacity: u32) -> usize {
    patch_layout(history_capacity.max(1) as usize).2
}

/// Offsets of the cut's entries and of the paths in a patch scratch of
/// history capacity `cap`, and its bytes: `[records | entries | paths]`,
/// each part 16-byte aligned.
fn patch_layout(cap: usize) -> (usize, usize, usize) {
    let k = lcts::hlcts::MAX_RAYS * cap;
    let entries = coray::arena::align_up(k * core::mem::size_of::<lcts::HistoryRecord>());
    let paths =
        entries + coray::arena::align_up(k * core::mem::size_of::<lcts::hlcts::HlctsEntry>());
    (entries, paths, paths + coray::arena::align_up(k * 4))
}

/// Visibility between two convex patches (3 or 4 vertices each, `x y z`
/// per vertex): `samples_per_side x samples_per_side` points on each patch,
/// every segment between them trimmed by `eps` of its length at both ends,
/// all started from one HLCTS of the vertex-to-vertex segments. The visible
/// fraction is `visible / samples`; each segment's answer is exactly what
/// hierarchical traversal gives.
///
/// # Safety
/// As `coray_kdtree_intersect`; `patch_a` and `patch_b` hold `3 * count`
/// floats; `scratch` holds `scratch_bytes` (16-byte aligned); `out` is writable.
#[no_mangle]
pub unsafe extern "C" fn coray_kdtree_patch_visibility(
    tree_arena: *const c_void,
    tree_bytes: usize,
    scene: *const CorayScene,
    patch_a: *const f32,
    count_a: u32,
    patch_b: *const f32,
    count_b: u32,
    samples_per_side: u32,
    eps: f32,
    scratch: *mut c_void,
    scratch_bytes: usize,
    out: *mut CorayPatchResult,
) -> CorayStatus {
    guard(|| {
        // SAFETY: forwarded caller contract for every pointer.
        let (t, a, b) = unsafe {
            (
                tree(tree_arena, tree_bytes, carve::scene(scene)?)?,
                carve::input(patch_a.cast::<[f32; 3]>(), count_a as usize)?,
                carve::input(patch_b.cast::<[f32; 3]>(), count_b as usize)?,
            )
        };
        let n = patch::MAX_PATCH_VERTICES;
        if a.len() < 3
            || a.len() > n
            || b.len() < 3
            || b.len() > n
            || samples_per_side == 0
            || samples_per_side > 256
        {
            return Err(CorayStatus::InvalidParameter);
        }
        let pa: [Vec3; 4] = core::array::from_fn(|i| Vec3::from(*a.get(i).unwrap_or(&a[0])));
        let pb: [Vec3; 4] = core::array::from_fn(|i| Vec3::from(*b.get(i).unwrap_or(&b[0])));
        let base = scratch.cast::<u8>();
        check_arena(base)?;
        // Split the scratch as coray_patch_requirements lays it out, for
        // the largest history capacity that fits.
        let k = lcts::hlcts::MAX_RAYS;
        let per_cap = k
            * (core::mem::size_of::<lcts::HistoryRecord>()
                + core::mem::size_of::<lcts::hlcts::HlctsEntry>()
                + 4);
        let mut cap = scratch_bytes / per_cap;
        while cap > 0 && patch_layout(cap).2 > scratch_bytes {
            cap -= 1;
        }
        if cap == 0 {
            return Err(CorayStatus::ArenaTooSmall);
        }
        let (entries_at, paths_at, _) = patch_layout(cap);
        // SAFETY: aligned arena (checked); the three parts lie within
        // scratch_bytes (patch_layout(cap) fits) at 16-aligned offsets and do
        // not overlap; lent exclusively by the caller.
        let sc = unsafe {
            patch::PatchScratch {
                records: slice_mut(base, 0, k * cap),
                hlcts: slice_mut(base, entries_at, k * cap),
                paths: slice_mut(base, paths_at, k * cap),
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
        // SAFETY: NULL or writable (caller's contract).
        *unsafe { carve::output(out, 1)? }
            .first_mut()
            .ok_or(CorayStatus::NullPointer)? = CorayPatchResult {
            visible: r.visible,
            samples: r.samples,
            cut_len: r.cut_len,
            boundary: r.boundary.into(),
            trace: r.trace.into(),
        };
        Ok(())
    })
}
