//! A scene and its kd-tree in one file, to build once and trace from any
//! process (`coray build SCENE -o scene.coray`; `examples/trace_saved.c`
//! maps it and traces). The arena is the C ABI's, byte for byte: it holds
//! offsets, not pointers, so it opens at whatever address the file is
//! mapped. `coray_saved_open` checks a file and opens it; the writer
//! (`kdtree_file`) needs `std`.
//!
//! Layout, format version 3 (all offsets from the file's start, every
//! array 16-byte aligned, every word in the writer's byte order):
//!
//! | bytes | field |
//! |---|---|
//! | 0..8 | magic `CORAYSV1` |
//! | 8..12 | format version (3), `uint32_t` |
//! | 12..16 | byte order mark `0x01020304`, `uint32_t` |
//! | 16..20 | the kd-tree's preset (`CorayKdPreset`) |
//! | 20..24 | zero |
//! | 24..32 | checksum: XXH3-64 of the whole file with these 8 bytes zero |
//! | 32..64 | vertex, triangle, sphere and cone counts, `uint64_t` each |
//! | 64..96 | offsets of vertices (3 floats each), triangle indices (3 `uint32_t`), spheres (4 floats), cones (8 floats), `uint64_t` each |
//! | 96..112 | offset and bytes of the kd-tree arena, `uint64_t` each |
//! | 112..120 | the file's bytes, `uint64_t` |
//! | 120..128 | offset of the view, `uint64_t`; 0 when the file has none |
//!
//! The view is the camera the scene was saved with (`coray build` saves
//! the scene's own): 48 bytes, `from`, `at`, `up` (three floats each), the
//! angle in degrees (a float), width and height (`uint32_t` each), as
//! `CorayCamera` holds them after its `struct_size`. Version 2 (1.7) is
//! version 3 without a view (bytes 120..128 zero): it still opens.
//!
//! `coray_saved_open` refuses with `CORAY_STATUS_DAMAGED_FILE` a file whose
//! magic, version, byte order, length, checksum or array bounds are wrong:
//! any damage on the way (one flipped bit anywhere) is caught by the
//! checksum before a word of the scene or the tree is trusted. It then
//! opens and validates the tree over the file's scene: a file written
//! with a tree that does not fit its scene is `CORAY_STATUS_CORRUPT_ARENA`.
//! A view that is no usable camera (NaN, an eye on the point it looks at)
//! is damage too. Version 1 files (no checksum) are refused: build them
//! again.

use crate::*;
use core::ffi::c_void;
use xxhash_rust::xxh3::Xxh3;

/// The file's first eight bytes: `CORAYSV1`.
pub const SAVED_MAGIC: [u8; 8] = *b"CORAYSV1";
/// Version of the saved-scene file format (`coray build -o`) written: 3
/// since 1.8 (the view); 2 since 1.7 (the checksum, the byte order mark
/// and the file's length), still read.
pub const CORAY_SAVED_VERSION: u32 = 3;
/// Bytes of a saved-scene file's header; its arrays follow, 16-byte aligned.
pub const CORAY_SAVED_HEADER_BYTES: usize = 128;
/// The byte order mark: this word, as the writer stores words.
pub const CORAY_SAVED_BYTE_ORDER: u32 = 0x0102_0304;

/// Where the header keeps its checksum.
const CHECKSUM_AT: usize = 24;
/// Bytes of the view record: nine floats of position, the angle, two sides.
const VIEW_BYTES: usize = 48;

/// A saved file opened by `coray_saved_open`: the scene, its arrays inside
/// the file, and the kd-tree over it, opened and validated. Both borrow
/// the file's bytes: keep the file mapped, unchanged, while they are used.
/// Since 1.7.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct CoraySaved {
    /// `sizeof(CoraySaved)`.
    pub struct_size: usize,
    /// The preset the tree was built with (`CorayKdPreset`).
    pub preset: CorayKdPreset,
    /// 1 when the file holds a view (`camera`), else 0 (since 1.8; 1.7
    /// wrote 0 here).
    pub has_camera: u32,
    /// The scene, its arrays pointing into the file.
    pub scene: CorayScene,
    /// The tree over `scene`, for every `coray_kdtree_*` call.
    pub tree: CorayKdTree,
    /// The camera the scene was saved with, when `has_camera` is 1 (its
    /// `struct_size` set; a usable camera, checked). Since 1.8.
    pub camera: CorayCamera,
}

impl Default for CoraySaved {
    fn default() -> Self {
        CoraySaved {
            struct_size: core::mem::size_of::<CoraySaved>(),
            preset: 0,
            has_camera: 0,
            scene: coray_scene_default(),
            tree: CorayKdTree { opaque: [0; 32] },
            camera: CorayCamera::default(),
        }
    }
}

// SAFETY: repr(C) of usize, u32, a Versioned struct of pointers and
// sizes, u64 words and a camera of usize, f32 and u32 fields: every bit
// pattern valid, `struct_size` first, no padding (8-byte fields after two
// u32; the camera 8-aligned after the u64 words). The first published
// struct (1.7) ended at `tree`.
unsafe impl carve::Versioned for CoraySaved {
    const SIZE_1_0: usize = core::mem::offset_of!(CoraySaved, camera);
}

/// A `CoraySaved` with its `struct_size` set: pass it to
/// `coray_saved_open`.
#[no_mangle]
pub extern "C" fn coray_saved_default() -> CoraySaved {
    CoraySaved::default()
}

/// XXH3-64 of `file` (a whole saved file, at least its header) with its
/// checksum field read as zero: what bytes 24..32 hold.
pub fn checksum(file: &[u8]) -> u64 {
    let mut h = Xxh3::new();
    h.update(&file[..CHECKSUM_AT]);
    h.update(&[0; 8]);
    h.update(&file[CHECKSUM_AT + 8..]);
    h.digest()
}

/// The header's `k`-th 64-bit word (bytes `8 * k..8 * k + 8`).
fn word(file: &[u8], k: usize) -> u64 {
    let mut w = [0; 8];
    w.copy_from_slice(&file[8 * k..8 * k + 8]);
    u64::from_ne_bytes(w)
}

/// The header's 32-bit word at byte `at`.
fn word32(file: &[u8], at: usize) -> u32 {
    let mut w = [0; 4];
    w.copy_from_slice(&file[at..at + 4]);
    u32::from_ne_bytes(w)
}

/// What a sound file's header says: the preset, per array (vertices,
/// triangles, spheres, cones, arena) its offset, element count and
/// element bytes.
struct Parts {
    preset: CorayKdPreset,
    arrays: [(usize, usize, usize); 5],
    camera: Option<CorayCamera>,
}

/// Checks everything of `file` but the tree: magic, version, byte order,
/// length, checksum, every array inside the file and 16-byte aligned.
fn parts(file: &[u8]) -> Result<Parts, CorayStatus> {
    let damaged = Err(CorayStatus::DamagedFile);
    if file.len() < CORAY_SAVED_HEADER_BYTES || file[..8] != SAVED_MAGIC {
        return damaged;
    }
    let version = word32(file, 8);
    if !(version == 2 || version == 3) || word32(file, 12) != CORAY_SAVED_BYTE_ORDER {
        return damaged;
    }
    if word(file, 14) != file.len() as u64 || checksum(file) != word(file, 3) {
        return damaged;
    }
    let elem: [u64; 5] = [12, 12, 16, 32, 1];
    let mut arrays = [(0, 0, 0); 5];
    for (k, a) in arrays.iter_mut().enumerate() {
        let count = if k < 4 {
            word(file, 4 + k)
        } else {
            word(file, 13)
        };
        let offset = word(file, 8 + k.min(4));
        let fits = offset.is_multiple_of(16)
            && offset >= CORAY_SAVED_HEADER_BYTES as u64
            && offset <= file.len() as u64
            && count <= (file.len() as u64 - offset) / elem[k];
        if !fits {
            return damaged;
        }
        *a = (offset as usize, count as usize, elem[k] as usize);
    }
    let view_at = word(file, 15);
    let camera = match view_at {
        0 => None,
        _ if version == 2 => return damaged,
        at => {
            let fits = at.is_multiple_of(16)
                && at >= CORAY_SAVED_HEADER_BYTES as u64
                && at <= (file.len() - VIEW_BYTES) as u64;
            if !fits {
                return damaged;
            }
            let at = at as usize;
            let f = |k: usize| f32::from_bits(word32(file, at + 4 * k));
            let c = CorayCamera {
                struct_size: core::mem::size_of::<CorayCamera>(),
                from: [f(0), f(1), f(2)],
                at: [f(3), f(4), f(5)],
                up: [f(6), f(7), f(8)],
                angle_deg: f(9),
                width: word32(file, at + 40),
                height: word32(file, at + 44),
            };
            if crate::cast::camera(&c).is_err() {
                return damaged;
            }
            Some(c)
        }
    };
    Ok(Parts {
        preset: word32(file, 16),
        arrays,
        camera,
    })
}

/// Checks a saved file (`coray build SCENE -o FILE`) mapped or read at
/// `file` (16-byte aligned, as `mmap` and `malloc` give) and opens it:
/// `out->scene` points into the file, `out->tree` is its kd-tree, opened
/// and validated over that scene. `CORAY_STATUS_DAMAGED_FILE` when the
/// magic, the format version, the byte order, the length, the checksum or
/// an array's place is wrong (nothing of the file is trusted before the
/// checksum passes); the statuses of `coray_kdtree_open` and
/// `coray_kdtree_validate` after that. Time linear in the file. Since 1.7.
///
/// Safety: `file` is NULL or readable for `file_bytes` and stays mapped
/// and unchanged while `out` is used; `out` is NULL or writable for its
/// `struct_size`.
#[no_mangle]
pub unsafe extern "C" fn coray_saved_open(
    file: *const c_void,
    file_bytes: usize,
    out: *mut CoraySaved,
) -> CorayStatus {
    guard(|| {
        let mut regions = carve::Regions::new();
        let base = file.cast::<u8>();
        carve::check_arena(base)?;
        // SAFETY: forwarded caller contract: out NULL or writable.
        let out = unsafe { carve::Out::new(out, false, &mut regions)? };
        regions.add(base, file_bytes, false).check()?;
        // SAFETY: non-null, aligned, readable for file_bytes (caller).
        let bytes = unsafe { core::slice::from_raw_parts(base, file_bytes) };
        let p = parts(bytes)?;
        let at = |k: usize| {
            let (offset, count, _) = p.arrays[k];
            // An empty array may be NULL; a present one lies in the file.
            // SAFETY: offset + count * elem <= file_bytes (checked).
            (count > 0).then(|| unsafe { base.add(offset) })
        };
        let mut scene = coray_scene_default();
        scene.vertices = at(0).map_or(core::ptr::null(), |q| q.cast());
        scene.vertex_count = p.arrays[0].1;
        scene.indices = at(1).map_or(core::ptr::null(), |q| q.cast());
        scene.triangle_count = p.arrays[1].1;
        scene.spheres = at(2).map_or(core::ptr::null(), |q| q.cast());
        scene.sphere_count = p.arrays[2].1;
        scene.cones = at(3).map_or(core::ptr::null(), |q| q.cast());
        scene.cone_count = p.arrays[3].1;
        let (arena_at, arena_bytes, _) = p.arrays[4];
        // SAFETY: inside the file (checked above).
        let arena = unsafe { base.add(arena_at) }.cast::<c_void>();
        let mut tree = CorayKdTree { opaque: [0; 32] };
        // SAFETY: the arena and the scene's arrays lie inside the file,
        // readable for the call; scene and tree are live locals.
        let s = unsafe { coray_kdtree_open(arena, arena_bytes, &scene, &mut tree) };
        if s != CorayStatus::Ok {
            return Err(s);
        }
        // SAFETY: tree was just filled by coray_kdtree_open.
        let s = unsafe {
            coray_kdtree_validate(&tree, core::ptr::null_mut(), 0, core::ptr::null_mut())
        };
        if s != CorayStatus::Ok {
            return Err(s);
        }
        out.write(CoraySaved {
            struct_size: 0,
            preset: p.preset,
            has_camera: p.camera.is_some() as u32,
            scene,
            tree,
            camera: p.camera.unwrap_or_default(),
        });
        Ok(())
    })
}

#[cfg(feature = "std")]
fn align16(n: usize) -> usize {
    n.div_ceil(16) * 16
}

/// 16-byte aligned memory for an arena or scratch.
#[cfg(feature = "std")]
pub(crate) fn aligned(bytes: usize) -> std::vec::Vec<u128> {
    std::vec![0u128; bytes.div_ceil(16).max(1)]
}

/// A kd-tree built on `scene` with `preset` and `omit_ropes` (0 ropes, 1
/// none, 2 none and compact: `CorayKdParams::omit_ropes`), by
/// `coray_kdtree_build`: the arena (16-byte aligned words, cut to what the
/// tree uses) and the bytes the tree uses (`arena_bytes_used`).
#[cfg(feature = "std")]
pub(crate) fn build_arena(
    scene: &coray::Scene,
    preset: CorayKdPreset,
    omit_ropes: u32,
) -> Result<(std::vec::Vec<u128>, usize), CorayStatus> {
    let mut params = coray_kdtree_params_default(preset);
    if params.struct_size == 0 {
        return Err(CorayStatus::InvalidParameter);
    }
    params.omit_ropes = omit_ropes;
    let c = c_scene(scene);
    let mut req = coray_requirements_default();
    // SAFETY: params and req are live locals with struct_size set.
    let s = unsafe { coray_kdtree_requirements(scene.prim_count(), &params, &mut req) };
    if s != CorayStatus::Ok {
        return Err(s);
    }
    let mut arena = aligned(req.arena_bytes);
    let mut scratch = aligned(req.scratch_bytes);
    // SAFETY: c's arrays are `scene`'s, live for the call (Sphere and Cone
    // are repr(C) runs of f32, triangles runs of u32); arena and scratch
    // are 16-byte aligned and at least as long as passed.
    let s = unsafe {
        coray_kdtree_build(
            &c,
            &params,
            arena.as_mut_ptr().cast(),
            req.arena_bytes,
            scratch.as_mut_ptr().cast(),
            req.scratch_bytes,
            core::ptr::null_mut(),
        )
    };
    if s != CorayStatus::Ok {
        return Err(s);
    }
    let mut tree = CorayKdTree { opaque: [0; 32] };
    let mut info = CorayKdTreeInfo {
        struct_size: core::mem::size_of::<CorayKdTreeInfo>(),
        ..Default::default()
    };
    // SAFETY: the arena was just built (aligned, req.arena_bytes long); c
    // points to `scene`'s arrays; tree and info are live locals.
    let s = unsafe {
        match coray_kdtree_open(arena.as_ptr().cast(), req.arena_bytes, &c, &mut tree) {
            CorayStatus::Ok => coray_kdtree_info(&tree, &mut info),
            e => e,
        }
    };
    if s != CorayStatus::Ok {
        return Err(s);
    }
    arena.truncate(info.arena_bytes_used.div_ceil(16).max(1));
    arena.shrink_to_fit();
    Ok((arena, info.arena_bytes_used))
}

/// `scene` as the C ABI's struct (pointers to its arrays).
#[cfg(feature = "std")]
pub(crate) fn c_scene(scene: &coray::Scene) -> CorayScene {
    let mut c = coray_scene_default();
    c.vertices = scene.vertices.as_ptr().cast();
    c.vertex_count = scene.vertices.len();
    c.indices = scene.triangles.as_ptr().cast();
    c.triangle_count = scene.triangles.len();
    c.spheres = scene.spheres.as_ptr().cast();
    c.sphere_count = scene.spheres.len();
    c.cones = scene.cones.as_ptr().cast();
    c.cone_count = scene.cones.len();
    c
}

/// The file holding `scene`, its view `camera` when given, and a kd-tree
/// built on it with `preset` and `omit_ropes`: with ropes (0: every call
/// works on it, the casts too), without (1: smaller) or compact (2:
/// smaller still).
#[cfg(feature = "std")]
pub fn kdtree_file(
    scene: &coray::Scene,
    camera: Option<&coray::Camera>,
    preset: CorayKdPreset,
    omit_ropes: u32,
) -> Result<std::vec::Vec<u8>, CorayStatus> {
    use std::vec::Vec;
    let (arena, arena_bytes) = build_arena(scene, preset, omit_ropes)?;
    let arena: Vec<u8> = arena
        .iter()
        .flat_map(|w| w.to_ne_bytes())
        .take(arena_bytes)
        .collect();
    let f32s = |v: &mut dyn Iterator<Item = f32>| v.flat_map(f32::to_ne_bytes).collect::<Vec<u8>>();
    let parts: [(Vec<u8>, usize); 5] = [
        (
            f32s(&mut scene.vertices.iter().flatten().copied()),
            scene.vertices.len(),
        ),
        (
            scene
                .triangles
                .iter()
                .flatten()
                .flat_map(|i| i.to_ne_bytes())
                .collect(),
            scene.triangles.len(),
        ),
        (
            f32s(
                &mut scene
                    .spheres
                    .iter()
                    .flat_map(|s| [s.center[0], s.center[1], s.center[2], s.radius]),
            ),
            scene.spheres.len(),
        ),
        (
            f32s(&mut scene.cones.iter().flat_map(|c| {
                [
                    c.base[0],
                    c.base[1],
                    c.base[2],
                    c.base_radius,
                    c.apex[0],
                    c.apex[1],
                    c.apex[2],
                    c.apex_radius,
                ]
            })),
            scene.cones.len(),
        ),
        (arena, 1),
    ];
    let mut out = std::vec![0u8; CORAY_SAVED_HEADER_BYTES];
    let mut offsets = [0u64; 5];
    for (k, (bytes, _)) in parts.iter().enumerate() {
        out.resize(align16(out.len()), 0);
        offsets[k] = out.len() as u64;
        out.extend_from_slice(bytes);
    }
    let mut view_at = 0u64;
    if let Some(c) = camera {
        out.resize(align16(out.len()), 0);
        view_at = out.len() as u64;
        let floats = [c.from.to_array(), c.at.to_array(), c.up.to_array()];
        for x in floats.iter().flatten().chain([&c.angle_deg]) {
            out.extend_from_slice(&x.to_ne_bytes());
        }
        out.extend_from_slice(&c.width.to_ne_bytes());
        out.extend_from_slice(&c.height.to_ne_bytes());
    }
    out[0..8].copy_from_slice(&SAVED_MAGIC);
    out[8..12].copy_from_slice(&CORAY_SAVED_VERSION.to_ne_bytes());
    out[12..16].copy_from_slice(&CORAY_SAVED_BYTE_ORDER.to_ne_bytes());
    out[16..20].copy_from_slice(&preset.to_ne_bytes());
    let words: [u64; 12] = [
        parts[0].1 as u64,
        parts[1].1 as u64,
        parts[2].1 as u64,
        parts[3].1 as u64,
        offsets[0],
        offsets[1],
        offsets[2],
        offsets[3],
        offsets[4],
        arena_bytes as u64,
        out.len() as u64,
        view_at,
    ];
    for (k, w) in words.iter().enumerate() {
        out[32 + 8 * k..40 + 8 * k].copy_from_slice(&w.to_ne_bytes());
    }
    let sum = checksum(&out);
    out[CHECKSUM_AT..CHECKSUM_AT + 8].copy_from_slice(&sum.to_ne_bytes());
    Ok(out)
}
