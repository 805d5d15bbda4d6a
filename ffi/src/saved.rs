//! A scene and its kd-tree in one file, to build once and trace from any
//! process (`coray build SCENE -o scene.coray`; `examples/trace_saved.c`
//! maps it and traces). The arena is the C ABI's, byte for byte: it holds
//! offsets, not pointers, so it opens at whatever address the file is
//! mapped. Native byte order; little-endian targets read each other's files.
//!
//! Layout (all offsets from the file's start, every array 16-byte aligned):
//!
//! | bytes | field |
//! |---|---|
//! | 0..8 | magic `CORAYSV1` |
//! | 8..12 | format version (1), `uint32_t` |
//! | 12..16 | the kd-tree's preset (`CorayKdPreset`) |
//! | 16..48 | vertex, triangle, sphere and cone counts, `uint64_t` each |
//! | 48..80 | offsets of vertices (3 floats each), triangle indices (3 `uint32_t`), spheres (4 floats), cones (8 floats), `uint64_t` each |
//! | 80..96 | offset and bytes of the kd-tree arena, `uint64_t` each |
//!
//! The reader checks the magic, the version, that every array lies inside
//! the file, then hands the arena to `coray_kdtree_open` and
//! `coray_kdtree_validate`: a damaged file is refused, never traced.

use crate::*;
use coray::Scene;
use std::vec::Vec;

/// The file's first eight bytes: `CORAYSV1`.
pub const SAVED_MAGIC: [u8; 8] = *b"CORAYSV1";
/// Version of the saved-scene file format (`coray build -o`).
pub const CORAY_SAVED_VERSION: u32 = 1;
/// Bytes of a saved-scene file's header; its arrays follow, 16-byte aligned.
pub const CORAY_SAVED_HEADER_BYTES: usize = 96;

fn align16(n: usize) -> usize {
    n.div_ceil(16) * 16
}

/// 16-byte aligned memory for an arena or scratch.
pub(crate) fn aligned(bytes: usize) -> Vec<u128> {
    std::vec![0u128; bytes.div_ceil(16).max(1)]
}

/// A kd-tree built on `scene` with `preset` and `omit_ropes` (0 ropes, 1
/// none, 2 none and compact: `CorayKdParams::omit_ropes`), by
/// `coray_kdtree_build`: the arena (16-byte aligned words, cut to what the
/// tree uses) and the bytes the tree uses (`arena_bytes_used`).
pub(crate) fn build_arena(
    scene: &Scene,
    preset: CorayKdPreset,
    omit_ropes: u32,
) -> Result<(Vec<u128>, usize), CorayStatus> {
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
pub(crate) fn c_scene(scene: &Scene) -> CorayScene {
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

/// The file holding `scene` and a kd-tree built on it with `preset` and
/// `omit_ropes`: with ropes (0: every call works on it, the casts too),
/// without (1: smaller) or compact (2: smaller still).
pub fn kdtree_file(
    scene: &Scene,
    preset: CorayKdPreset,
    omit_ropes: u32,
) -> Result<Vec<u8>, CorayStatus> {
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
    out[0..8].copy_from_slice(&SAVED_MAGIC);
    out[8..12].copy_from_slice(&CORAY_SAVED_VERSION.to_ne_bytes());
    out[12..16].copy_from_slice(&preset.to_ne_bytes());
    let words: [u64; 10] = [
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
    ];
    for (k, w) in words.iter().enumerate() {
        out[16 + 8 * k..24 + 8 * k].copy_from_slice(&w.to_ne_bytes());
    }
    Ok(out)
}
