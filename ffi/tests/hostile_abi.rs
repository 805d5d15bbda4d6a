//! Issue 16's C-ABI findings, each as a test (written against the ABI of
//! e4d0fb4 first, where all failed, then carried to ABI 1.0): aliasing,
//! outputs written on a failing call, statuses that differ between
//! families, the sample count that wrapped.
use coray_ffi::*;
use core::ffi::c_void;
use core::mem::size_of;

#[repr(C, align(16))]
#[derive(Clone, Copy)]
struct Block([u8; 16]);

fn arena(bytes: usize) -> Vec<Block> {
    vec![Block([0; 16]); bytes.div_ceil(16).max(1)]
}

struct Floor {
    vertices: Vec<f32>,
    indices: Vec<u32>,
}

fn floor() -> Floor {
    Floor {
        vertices: vec![-5., 0., -5., 5., 0., -5., 5., 0., 5., -5., 0., 5.],
        indices: vec![0, 1, 2, 0, 2, 3],
    }
}

fn scene(f: &Floor) -> CorayScene {
    let mut s = coray_scene_default();
    s.vertices = f.vertices.as_ptr();
    s.vertex_count = 4;
    s.indices = f.indices.as_ptr();
    s.triangle_count = 2;
    s
}

fn requirements() -> CorayRequirements {
    CorayRequirements {
        struct_size: size_of::<CorayRequirements>(),
        ..Default::default()
    }
}

/// A kd-tree over `s` with ropes (every call takes it), opened.
fn kd(s: &CorayScene) -> (Vec<Block>, CorayKdTree) {
    let p = CorayKdParams {
        omit_ropes: 0,
        ..coray_kdtree_params_default(CORAY_KD_PRESET_AUTO)
    };
    let mut r = requirements();
    unsafe {
        assert_eq!(
            coray_kdtree_requirements(s.triangle_count, &p, &mut r),
            CorayStatus::Ok
        );
        let mut t = arena(r.arena_bytes);
        let mut sc = arena(r.scratch_bytes);
        assert_eq!(
            coray_kdtree_build(
                s,
                &p,
                t.as_mut_ptr().cast(),
                r.arena_bytes,
                sc.as_mut_ptr().cast(),
                r.scratch_bytes,
                core::ptr::null_mut()
            ),
            CorayStatus::Ok
        );
        let mut h = CorayKdTree { opaque: [0; 32] };
        assert_eq!(
            coray_kdtree_open(t.as_ptr().cast(), r.arena_bytes, s, &mut h),
            CorayStatus::Ok
        );
        (t, h)
    }
}

/// A wide hierarchy over `s`, opened.
fn wide(s: &CorayScene) -> (Vec<Block>, CorayWide) {
    let p = coray_wide_params_default();
    let mut r = requirements();
    unsafe {
        assert_eq!(
            coray_wide_requirements(s.triangle_count, &p, &mut r),
            CorayStatus::Ok
        );
        let mut a = arena(r.arena_bytes);
        let mut sc = arena(r.scratch_bytes);
        assert_eq!(
            coray_wide_build(
                s,
                &p,
                a.as_mut_ptr().cast(),
                r.arena_bytes,
                sc.as_mut_ptr().cast(),
                r.scratch_bytes,
                core::ptr::null_mut()
            ),
            CorayStatus::Ok
        );
        let mut h = CorayWide { opaque: [0; 32] };
        assert_eq!(
            coray_wide_open(a.as_ptr().cast(), r.arena_bytes, s, &mut h),
            CorayStatus::Ok
        );
        (a, h)
    }
}

/// A TDBS hierarchy over `s`, opened.
fn bvh(s: &CorayScene) -> (Vec<Block>, CorayBvh) {
    let p = coray_bvh_params_default(CORAY_BVH_BUILDER_TDBS);
    let mut r = requirements();
    unsafe {
        assert_eq!(
            coray_bvh_requirements(s.triangle_count, &p, &mut r),
            CorayStatus::Ok
        );
        let mut a = arena(r.arena_bytes);
        let mut sc = arena(r.scratch_bytes);
        let null = core::ptr::null_mut();
        let (ap, bytes) = (a.as_mut_ptr().cast(), r.arena_bytes);
        let st = coray_bvh_build(
            s,
            &p,
            ap,
            bytes,
            sc.as_mut_ptr().cast(),
            r.scratch_bytes,
            null,
        );
        assert_eq!(st, CorayStatus::Ok);
        let mut h = CorayBvh { opaque: [0; 32] };
        assert_eq!(coray_bvh_open(ap, bytes, s, &mut h), CorayStatus::Ok);
        (a, h)
    }
}

/// A projection hierarchy over `s` on [`camera`]'s image plane, opened.
fn proj(s: &CorayScene) -> (Vec<Block>, CorayProj) {
    unsafe {
        let mut plane = CorayProjPlane {
            struct_size: size_of::<CorayProjPlane>(),
            ..Default::default()
        };
        assert_eq!(
            coray_proj_camera_plane(&camera(), &mut plane),
            CorayStatus::Ok
        );
        let p = coray_proj_params_default(CORAY_PROJ_CRITERIA_2D, CORAY_BVH_BUILDER_NN_CHAIN);
        let mut r = requirements();
        assert_eq!(
            coray_proj_requirements(s.triangle_count, &p, &mut r),
            CorayStatus::Ok
        );
        let mut a = arena(r.arena_bytes);
        let mut sc = arena(r.scratch_bytes);
        let null = core::ptr::null_mut();
        let (ap, bytes) = (a.as_mut_ptr().cast(), r.arena_bytes);
        let st = coray_proj_build(
            s,
            &p,
            &plane,
            ap,
            bytes,
            sc.as_mut_ptr().cast(),
            r.scratch_bytes,
            null,
        );
        assert_eq!(st, CorayStatus::Ok);
        let mut h = CorayProj { opaque: [0; 32] };
        assert_eq!(coray_proj_open(ap, bytes, s, &mut h), CorayStatus::Ok);
        (a, h)
    }
}

fn down() -> CorayRay {
    CorayRay {
        org: [0.5, 3.0, 0.5],
        tnear: 0.0,
        dir: [0.0, -1.0, 0.0],
        tfar: f32::INFINITY,
    }
}

/// Rays and hits in the same memory: rejected, nothing written.
#[test]
fn rays_and_hits_may_not_overlap() {
    let f = floor();
    let s = scene(&f);
    let (_a, t) = kd(&s);
    let mut stack = arena(CORAY_KDTREE_STACK_BYTES);
    let mut buf = [Block([0; 16]); 8];
    let rays = buf.as_mut_ptr().cast::<CorayRay>();
    unsafe {
        *rays = down();
        let st = coray_kdtree_intersect(
            &t,
            CORAY_TRAVERSAL_HIERARCHICAL,
            rays,
            rays.cast::<CorayHit>(),
            1,
            stack.as_mut_ptr().cast(),
            CORAY_KDTREE_STACK_BYTES,
            core::ptr::null_mut(),
        );
        assert_eq!(st, CorayStatus::InvalidParameter);
    }
}

/// A misaligned statistics pointer fails the call before any hit is written.
#[test]
fn a_misaligned_stats_pointer_writes_no_hit() {
    let f = floor();
    let s = scene(&f);
    let (_a, t) = kd(&s);
    let mut stack = arena(CORAY_KDTREE_STACK_BYTES);
    let ray = down();
    let mut hit = CorayHit {
        t: -7.0,
        ..Default::default()
    };
    let mut stats = [0u64; 32];
    let bad = unsafe {
        stats
            .as_mut_ptr()
            .cast::<u8>()
            .add(1)
            .cast::<CorayTraceStats>()
    };
    let st = unsafe {
        coray_kdtree_intersect(
            &t,
            CORAY_TRAVERSAL_HIERARCHICAL,
            &ray,
            &mut hit,
            1,
            stack.as_mut_ptr().cast(),
            CORAY_KDTREE_STACK_BYTES,
            bad,
        )
    };
    assert_eq!(st, CorayStatus::Misaligned);
    assert_eq!(hit.t, -7.0, "the hit was written on a failing call");
}

/// Tracing no rays needs no stack, in every family.
#[test]
fn zero_rays_need_no_stack() {
    let f = floor();
    let s = scene(&f);
    let (_a, t) = kd(&s);
    let p = coray_bvh_params_default(CORAY_BVH_BUILDER_TDBS);
    let mut r = requirements();
    let null = core::ptr::null_mut::<c_void>();
    unsafe {
        assert_eq!(
            coray_kdtree_intersect(
                &t,
                0,
                core::ptr::null(),
                core::ptr::null_mut(),
                0,
                null,
                0,
                core::ptr::null_mut()
            ),
            CorayStatus::Ok
        );
        assert_eq!(coray_bvh_requirements(2, &p, &mut r), CorayStatus::Ok);
        let mut a = arena(r.arena_bytes);
        let mut sc = arena(r.scratch_bytes);
        assert_eq!(
            coray_bvh_build(
                &s,
                &p,
                a.as_mut_ptr().cast(),
                r.arena_bytes,
                sc.as_mut_ptr().cast(),
                r.scratch_bytes,
                core::ptr::null_mut()
            ),
            CorayStatus::Ok
        );
        let mut h = CorayBvh { opaque: [0; 32] };
        assert_eq!(
            coray_bvh_open(a.as_ptr().cast(), r.arena_bytes, &s, &mut h),
            CorayStatus::Ok
        );
        let st = coray_bvh_intersect(
            &h,
            core::ptr::null(),
            core::ptr::null_mut(),
            0,
            null,
            0,
            core::ptr::null_mut(),
        );
        assert_eq!(st, CorayStatus::Ok);
        let (_w, wh) = wide(&s);
        let st = coray_wide_occluded(
            &wh,
            core::ptr::null(),
            core::ptr::null_mut(),
            0,
            null,
            0,
            core::ptr::null_mut(),
        );
        assert_eq!(st, CorayStatus::Ok);
    }
}

/// An R-tree arena whose recorded M and m break the rules is corrupt, not
/// a bad parameter of the call.
#[test]
fn corrupt_rtree_parameters_are_a_corrupt_arena() {
    let f = floor();
    let s = scene(&f);
    let p = coray_bvh_params_default(CORAY_BVH_BUILDER_RTREE);
    let mut r = requirements();
    unsafe {
        assert_eq!(coray_bvh_requirements(2, &p, &mut r), CorayStatus::Ok);
        let mut a = arena(r.arena_bytes);
        let mut sc = arena(r.scratch_bytes);
        assert_eq!(
            coray_bvh_build(
                &s,
                &p,
                a.as_mut_ptr().cast(),
                r.arena_bytes,
                sc.as_mut_ptr().cast(),
                r.scratch_bytes,
                core::ptr::null_mut()
            ),
            CorayStatus::Ok
        );
        // max_children: after magic, version, builder, 3 counts and the 8-word info.
        let words = a.as_mut_ptr().cast::<u32>();
        assert_eq!(*words.add(14), 8);
        *words.add(14) = 1000;
        let mut h = CorayBvh { opaque: [0; 32] };
        let st = coray_bvh_open(a.as_ptr().cast(), r.arena_bytes, &s, &mut h);
        assert_eq!(st, CorayStatus::CorruptArena);
        let st = coray_bvh_insert(
            a.as_mut_ptr().cast(),
            r.arena_bytes,
            &s,
            CORAY_GEOM_TRIANGLES,
            0,
        );
        assert_eq!(st, CorayStatus::CorruptArena);
    }
}

fn camera() -> CorayCamera {
    CorayCamera {
        struct_size: size_of::<CorayCamera>(),
        from: [0.0, 5.0, -5.0],
        at: [0.0, 0.0, 0.0],
        up: [0.0, 1.0, 0.0],
        angle_deg: 60.0,
        width: 4,
        height: 4,
    }
}

/// Cast scratch inside the tree arena, or over the hits: rejected.
#[test]
fn cast_scratch_may_not_overlap_the_tree_or_the_hits() {
    let f = floor();
    let s = scene(&f);
    let (mut a, t) = kd(&s);
    let mut stack = arena(CORAY_KDTREE_STACK_BYTES);
    let cam = camera();
    // A scheme with scratch (the default, packets, takes none).
    let p = CorayCastParams {
        scheme: CORAY_CAST_SLCTS_2D,
        ..coray_cast_params_default()
    };
    let mut r = requirements();
    unsafe {
        assert_eq!(
            coray_kdtree_cast_requirements(&cam, &p, &mut r),
            CorayStatus::Ok
        );
        let mut hits = [CorayHit::default(); 16];
        let st = coray_kdtree_cast_image(
            &t,
            &cam,
            &p,
            a.as_mut_ptr().cast::<c_void>(),
            r.scratch_bytes,
            stack.as_mut_ptr().cast(),
            CORAY_KDTREE_STACK_BYTES,
            hits.as_mut_ptr(),
            core::ptr::null_mut(),
        );
        assert_eq!(st, CorayStatus::InvalidParameter);
        let mut both = arena(r.scratch_bytes.max(16 * size_of::<CorayHit>()));
        let st = coray_kdtree_cast_image(
            &t,
            &cam,
            &p,
            both.as_mut_ptr().cast(),
            r.scratch_bytes,
            stack.as_mut_ptr().cast(),
            CORAY_KDTREE_STACK_BYTES,
            both.as_mut_ptr().cast(),
            core::ptr::null_mut(),
        );
        assert_eq!(st, CorayStatus::InvalidParameter);
    }
}

/// 256 samples per side would make 2^32 sample segments: refused, not wrapped.
#[test]
fn patch_sample_count_does_not_wrap() {
    let f = floor();
    let s = scene(&f);
    let (_a, t) = kd(&s);
    let mut stack = arena(CORAY_KDTREE_STACK_BYTES);
    let a = [-1.0f32, 1.0, -1.0, 1.0, 1.0, -1.0, 1.0, 1.0, 1.0];
    let b = [-1.0f32, 4.0, -1.0, 1.0, 4.0, -1.0, 1.0, 4.0, 1.0];
    let mut r = requirements();
    let mut out = CorayPatchResult {
        struct_size: size_of::<CorayPatchResult>(),
        ..Default::default()
    };
    unsafe {
        assert_eq!(coray_kdtree_patch_requirements(16, &mut r), CorayStatus::Ok);
        let mut sc = arena(r.scratch_bytes);
        let st = coray_kdtree_patch_visibility(
            &t,
            a.as_ptr(),
            3,
            b.as_ptr(),
            3,
            256,
            1e-3,
            sc.as_mut_ptr().cast(),
            r.scratch_bytes,
            stack.as_mut_ptr().cast(),
            CORAY_KDTREE_STACK_BYTES,
            &mut out,
            core::ptr::null_mut(),
        );
        assert_eq!(st, CorayStatus::InvalidParameter, "samples {}", out.samples);
    }
}

/// Two builds into arenas full of different garbage give the same bytes,
/// for every family: nothing of the caller's memory is left in an arena.
#[test]
fn built_arenas_are_a_function_of_scene_and_parameters() {
    let f = floor();
    let s = scene(&f);
    let build = |fill: u8, family: u32| -> Vec<u8> {
        let mut r = requirements();
        unsafe {
            let (bytes, scratch) = match family {
                0 => {
                    let p = coray_kdtree_params_default(CORAY_KD_PRESET_AUTO);
                    assert_eq!(coray_kdtree_requirements(2, &p, &mut r), CorayStatus::Ok);
                    (r.arena_bytes, r.scratch_bytes)
                }
                1 | 2 => {
                    let b = if family == 1 {
                        CORAY_BVH_BUILDER_TDBS
                    } else {
                        CORAY_BVH_BUILDER_RSTAR
                    };
                    let p = coray_bvh_params_default(b);
                    assert_eq!(coray_bvh_requirements(2, &p, &mut r), CorayStatus::Ok);
                    (r.arena_bytes, r.scratch_bytes)
                }
                3 => {
                    let p = coray_proj_params_default(
                        CORAY_PROJ_CRITERIA_2D,
                        CORAY_BVH_BUILDER_NN_CHAIN,
                    );
                    assert_eq!(coray_proj_requirements(2, &p, &mut r), CorayStatus::Ok);
                    (r.arena_bytes, r.scratch_bytes)
                }
                _ => {
                    let p = coray_wide_params_default();
                    assert_eq!(coray_wide_requirements(2, &p, &mut r), CorayStatus::Ok);
                    (r.arena_bytes, r.scratch_bytes)
                }
            };
            let mut a = arena(bytes);
            let mut sc = arena(scratch);
            for b in a.iter_mut().chain(sc.iter_mut()) {
                b.0 = [fill; 16];
            }
            let (ap, sp) = (
                a.as_mut_ptr().cast::<c_void>(),
                sc.as_mut_ptr().cast::<c_void>(),
            );
            let null = core::ptr::null_mut();
            let st = match family {
                0 => coray_kdtree_build(
                    &s,
                    &coray_kdtree_params_default(0),
                    ap,
                    bytes,
                    sp,
                    scratch,
                    null,
                ),
                1 => coray_bvh_build(
                    &s,
                    &coray_bvh_params_default(CORAY_BVH_BUILDER_TDBS),
                    ap,
                    bytes,
                    sp,
                    scratch,
                    null,
                ),
                2 => coray_bvh_build(
                    &s,
                    &coray_bvh_params_default(CORAY_BVH_BUILDER_RSTAR),
                    ap,
                    bytes,
                    sp,
                    scratch,
                    null,
                ),
                4 => coray_wide_build(
                    &s,
                    &coray_wide_params_default(),
                    ap,
                    bytes,
                    sp,
                    scratch,
                    null,
                ),
                _ => {
                    let mut cam_plane = CorayProjPlane {
                        struct_size: size_of::<CorayProjPlane>(),
                        ..Default::default()
                    };
                    assert_eq!(
                        coray_proj_camera_plane(&camera(), &mut cam_plane),
                        CorayStatus::Ok
                    );
                    let p = coray_proj_params_default(
                        CORAY_PROJ_CRITERIA_2D,
                        CORAY_BVH_BUILDER_NN_CHAIN,
                    );
                    coray_proj_build(&s, &p, &cam_plane, ap, bytes, sp, scratch, null)
                }
            };
            assert_eq!(st, CorayStatus::Ok);
            a.iter().flat_map(|b| b.0).collect()
        }
    };
    for family in 0..5 {
        assert!(
            build(0x00, family) == build(0xA5, family),
            "family {family}"
        );
    }
}

/// One trace call on a handle's words: (handle, ray, out, stack, stats).
type Trace = unsafe fn(
    *const [u64; 32],
    *const CorayRay,
    *mut u8,
    *mut u8,
    *mut CorayTraceStats,
) -> CorayStatus;

/// The one-ray calls check their buffers on their own path (spans known
/// at compile time, not the array calls' region list): for one family,
/// every placement of ray, out, stack and statistics gets the status the
/// array call gives for one ray, and a refused call writes nothing.
/// `calls` are intersect1, intersect (count 1), occluded1, occluded
/// (count 1); `open` builds and opens the family's structure over a scene;
/// `ray` hits the floor.
fn one_ray_parity(
    family: &str,
    open: impl Fn(&CorayScene) -> (Vec<Block>, [u64; 32]),
    ray: CorayRay,
    calls: [(&str, usize, Trace); 4],
) {
    // One block of memory holds the scene's vertices, the ray, the output,
    // the statistics and the stack, so that each can be put over another.
    const STACK: usize = 1024;
    const RAY: usize = 8192;
    const HIT: usize = 8448;
    const STATS: usize = 8704;
    let mut mem = arena(16384);
    let base = mem.as_mut_ptr().cast::<u8>();
    let f = floor();
    // SAFETY (whole function): every offset below lies inside `mem`,
    // aligned for its type; the calls get raw pointers only.
    unsafe {
        core::ptr::copy_nonoverlapping(f.vertices.as_ptr(), base.cast::<f32>(), 12);
        let mut s = scene(&f);
        s.vertices = base.cast::<f32>();
        let (tree_arena, h) = open(&s);
        let at = |off: usize| base.add(off);
        let stats_at = |off: usize| {
            let p = at(off).cast::<CorayTraceStats>();
            p.write(CorayTraceStats {
                struct_size: size_of::<CorayTraceStats>(),
                ..Default::default()
            });
            p
        };
        let arena_out = tree_arena.as_ptr().cast::<u8>().add(64) as *mut u8;
        let mut handle_copy = h;
        let zeroed = [0u64; 32];
        // (what, handle, ray, out, stack, stats, the status).
        type Case = (
            &'static str,
            *const [u64; 32],
            usize,
            *mut u8,
            *mut u8,
            *mut CorayTraceStats,
            CorayStatus,
        );
        let ok = CorayStatus::Ok;
        let bad = CorayStatus::InvalidParameter;
        let none = core::ptr::null_mut::<CorayTraceStats>();
        let hp: *const [u64; 32] = &h;
        let cases: Vec<Case> = vec![
            (
                "clean, no statistics",
                hp,
                RAY,
                at(HIT),
                at(STACK),
                none,
                ok,
            ),
            (
                "clean, statistics",
                hp,
                RAY,
                at(HIT),
                at(STACK),
                stats_at(STATS),
                ok,
            ),
            ("out over the ray", hp, RAY, at(RAY), at(STACK), none, bad),
            (
                "out at the stack's start",
                hp,
                RAY,
                at(STACK),
                at(STACK),
                none,
                bad,
            ),
            (
                "out inside the arena",
                hp,
                RAY,
                arena_out,
                at(STACK),
                none,
                bad,
            ),
            (
                "out inside the handle",
                &handle_copy,
                RAY,
                (&mut handle_copy as *mut [u64; 32]).cast(),
                at(STACK),
                none,
                bad,
            ),
            ("stack at the ray", hp, RAY, at(HIT), at(RAY), none, bad),
            (
                "stack over the vertices",
                hp,
                RAY,
                at(HIT),
                at(0),
                none,
                bad,
            ),
            (
                "statistics over the out",
                hp,
                RAY,
                at(HIT),
                at(STACK),
                stats_at(HIT),
                bad,
            ),
            (
                "statistics at the stack's start",
                hp,
                RAY,
                at(HIT),
                at(STACK),
                stats_at(STACK),
                bad,
            ),
            (
                "statistics over the ray",
                hp,
                RAY,
                at(HIT),
                at(STACK),
                at(RAY).cast(),
                bad,
            ),
            (
                "misaligned statistics",
                hp,
                RAY,
                at(HIT),
                at(STACK),
                at(STATS + 1).cast(),
                CorayStatus::Misaligned,
            ),
            (
                "misaligned stack",
                hp,
                RAY,
                at(HIT),
                at(STACK + 4),
                none,
                CorayStatus::Misaligned,
            ),
            (
                "no stack",
                hp,
                RAY,
                at(HIT),
                core::ptr::null_mut(),
                none,
                CorayStatus::NullPointer,
            ),
            (
                "no ray",
                hp,
                0,
                at(HIT),
                at(STACK),
                none,
                CorayStatus::NullPointer,
            ),
            (
                "no out",
                hp,
                RAY,
                core::ptr::null_mut(),
                at(STACK),
                none,
                CorayStatus::NullPointer,
            ),
            (
                "a handle never opened",
                &zeroed,
                RAY,
                at(HIT),
                at(STACK),
                none,
                bad,
            ),
        ];
        for (what, h, ray_at, out, stack, stats, want) in cases {
            let r: *const CorayRay = if ray_at == 0 {
                core::ptr::null()
            } else {
                at(ray_at).cast()
            };
            at(RAY).cast::<CorayRay>().write(ray);
            let fill = 0xA5u8;
            let mut answers = Vec::new();
            for (name, bytes, call) in calls {
                // Outputs in the caller's free memory are filled first: a
                // refused call must leave them so.
                let free = out >= at(HIT) && out < at(STATS);
                if free {
                    core::ptr::write_bytes(out, fill, bytes);
                }
                let arena_before = tree_arena.iter().map(|b| b.0).collect::<Vec<_>>();
                assert_eq!(
                    call(h, r, out, stack, stats),
                    want,
                    "{family}, {what}: {name}"
                );
                if want == ok {
                    answers.push(core::slice::from_raw_parts(out, bytes).to_vec());
                    continue;
                }
                if free {
                    let o = core::slice::from_raw_parts(out, bytes);
                    assert!(
                        o.iter().all(|&b| b == fill),
                        "{family}, {what}: {name} wrote"
                    );
                }
                assert!(
                    tree_arena.iter().map(|b| b.0).eq(arena_before),
                    "{family}, {what}: {name} wrote into the arena"
                );
            }
            if want == ok {
                assert_eq!(answers[0], answers[1], "{family}, {what}: hits differ");
                assert_eq!(answers[2], answers[3], "{family}, {what}: answers differ");
                assert_eq!(
                    answers[2],
                    [1],
                    "{family}, {what}: the floor blocks the ray"
                );
                let hit = answers[0].as_ptr().cast::<CorayHit>().read_unaligned();
                assert_eq!(hit.geom_id, CORAY_GEOM_TRIANGLES, "{family}, {what}");
            }
        }
    }
}

const KD_STACK: usize = CORAY_KDTREE_STACK_BYTES;

#[test]
fn the_kd_one_ray_calls_refuse_what_the_array_calls_refuse() {
    let open = |s: &CorayScene| {
        let (a, t) = kd(s);
        (a, t.opaque)
    };
    let calls: [(&str, usize, Trace); 4] = [
        (
            "intersect1",
            size_of::<CorayHit>(),
            |h, r, o, s, st| unsafe {
                coray_kdtree_intersect1(h.cast(), 0, r, o.cast(), s.cast(), KD_STACK, st)
            },
        ),
        (
            "intersect",
            size_of::<CorayHit>(),
            |h, r, o, s, st| unsafe {
                coray_kdtree_intersect(h.cast(), 0, r, o.cast(), 1, s.cast(), KD_STACK, st)
            },
        ),
        ("occluded1", 1, |h, r, o, s, st| unsafe {
            coray_kdtree_occluded1(h.cast(), 1, r, o, s.cast(), KD_STACK, st)
        }),
        ("occluded", 1, |h, r, o, s, st| unsafe {
            coray_kdtree_occluded(h.cast(), 1, r, o, 1, s.cast(), KD_STACK, st)
        }),
    ];
    one_ray_parity("kd", open, down(), calls);
    // An unknown traversal is refused first, by both.
    let f = floor();
    let s = scene(&f);
    let (_a, t) = kd(&s);
    let mut stack = arena(KD_STACK);
    let mut hit = CorayHit::default();
    let sp = stack.as_mut_ptr().cast();
    let none = core::ptr::null_mut();
    unsafe {
        assert_eq!(
            coray_kdtree_intersect1(&t, 9, &down(), &mut hit, sp, KD_STACK, none),
            CorayStatus::InvalidParameter
        );
        assert_eq!(
            coray_kdtree_intersect(&t, 9, &down(), &mut hit, 1, sp, KD_STACK, none),
            CorayStatus::InvalidParameter
        );
    }
}

/// A hierarchy's stack: generous for the two-triangle floor.
const BVH_STACK: usize = 1024;

#[test]
fn the_bvh_one_ray_calls_refuse_what_the_array_calls_refuse() {
    let open = |s: &CorayScene| {
        let (a, h) = bvh(s);
        (a, h.opaque)
    };
    let calls: [(&str, usize, Trace); 4] = [
        (
            "intersect1",
            size_of::<CorayHit>(),
            |h, r, o, s, st| unsafe {
                coray_bvh_intersect1(h.cast(), r, o.cast(), s.cast(), BVH_STACK, st)
            },
        ),
        (
            "intersect",
            size_of::<CorayHit>(),
            |h, r, o, s, st| unsafe {
                coray_bvh_intersect(h.cast(), r, o.cast(), 1, s.cast(), BVH_STACK, st)
            },
        ),
        ("occluded1", 1, |h, r, o, s, st| unsafe {
            coray_bvh_occluded1(h.cast(), r, o, s.cast(), BVH_STACK, st)
        }),
        ("occluded", 1, |h, r, o, s, st| unsafe {
            coray_bvh_occluded(h.cast(), r, o, 1, s.cast(), BVH_STACK, st)
        }),
    ];
    one_ray_parity("bvh", open, down(), calls);
}

#[test]
fn the_wide_one_ray_calls_refuse_what_the_array_calls_refuse() {
    let open = |s: &CorayScene| {
        let (a, h) = wide(s);
        (a, h.opaque)
    };
    let calls: [(&str, usize, Trace); 4] = [
        (
            "intersect1",
            size_of::<CorayHit>(),
            |h, r, o, s, st| unsafe {
                coray_wide_intersect1(h.cast(), r, o.cast(), s.cast(), BVH_STACK, st)
            },
        ),
        (
            "intersect",
            size_of::<CorayHit>(),
            |h, r, o, s, st| unsafe {
                coray_wide_intersect(h.cast(), r, o.cast(), 1, s.cast(), BVH_STACK, st)
            },
        ),
        ("occluded1", 1, |h, r, o, s, st| unsafe {
            coray_wide_occluded1(h.cast(), r, o, s.cast(), BVH_STACK, st)
        }),
        ("occluded", 1, |h, r, o, s, st| unsafe {
            coray_wide_occluded(h.cast(), r, o, 1, s.cast(), BVH_STACK, st)
        }),
    ];
    one_ray_parity("wide", open, down(), calls);
}

#[test]
fn the_proj_one_ray_calls_refuse_what_the_array_calls_refuse() {
    let open = |s: &CorayScene| {
        let (a, h) = proj(s);
        (a, h.opaque)
    };
    // A camera ray from the eye towards the floor's centre.
    let c = camera();
    let ray = CorayRay {
        org: c.from,
        tnear: 0.0,
        dir: [0.0, -1.0, 1.0],
        tfar: f32::INFINITY,
    };
    let calls: [(&str, usize, Trace); 4] = [
        (
            "intersect1",
            size_of::<CorayHit>(),
            |h, r, o, s, st| unsafe {
                coray_proj_intersect1(
                    h.cast(),
                    CORAY_PROJ_SCHEME_2D,
                    r,
                    o.cast(),
                    s.cast(),
                    BVH_STACK,
                    st,
                )
            },
        ),
        (
            "intersect",
            size_of::<CorayHit>(),
            |h, r, o, s, st| unsafe {
                coray_proj_intersect(
                    h.cast(),
                    CORAY_PROJ_SCHEME_2D,
                    r,
                    o.cast(),
                    1,
                    s.cast(),
                    BVH_STACK,
                    st,
                )
            },
        ),
        ("occluded1", 1, |h, r, o, s, st| unsafe {
            coray_proj_occluded1(
                h.cast(),
                CORAY_PROJ_SCHEME_2D,
                r,
                o,
                s.cast(),
                BVH_STACK,
                st,
            )
        }),
        ("occluded", 1, |h, r, o, s, st| unsafe {
            coray_proj_occluded(
                h.cast(),
                CORAY_PROJ_SCHEME_2D,
                r,
                o,
                1,
                s.cast(),
                BVH_STACK,
                st,
            )
        }),
    ];
    one_ray_parity("proj", open, ray, calls);
    // A ray off the plane's eye: refused by both, after the buffers.
    let f = floor();
    let s = scene(&f);
    let (_a, h) = open(&s);
    let mut stack = arena(BVH_STACK);
    let mut hit = CorayHit::default();
    let (sp, none) = (stack.as_mut_ptr().cast(), core::ptr::null_mut());
    let hp = (&h as *const [u64; 32]).cast::<CorayProj>();
    let sc = CORAY_PROJ_SCHEME_2D;
    unsafe {
        assert_eq!(
            coray_proj_intersect1(hp, sc, &down(), &mut hit, sp, BVH_STACK, none),
            CorayStatus::InvalidParameter
        );
        assert_eq!(
            coray_proj_intersect(hp, sc, &down(), &mut hit, 1, sp, BVH_STACK, none),
            CorayStatus::InvalidParameter
        );
        assert_eq!(
            coray_proj_intersect1(hp, 77, &ray, &mut hit, sp, BVH_STACK, none),
            CorayStatus::InvalidParameter
        );
        // A tracer: the one-ray call's answers and refusals.
        let mut tr = Box::new(CorayTracer { opaque: [0; 32] });
        let mut tstack = arena(BVH_STACK);
        let tsp = tstack.as_mut_ptr().cast();
        assert_eq!(
            coray_proj_tracer(hp, 77, tsp, BVH_STACK, &mut *tr),
            CorayStatus::InvalidParameter
        );
        assert_eq!(
            coray_proj_tracer(hp, sc, tsp, BVH_STACK, &mut *tr),
            CorayStatus::Ok
        );
        let (mut want, mut got) = (CorayHit::default(), CorayHit::default());
        assert_eq!(
            coray_proj_intersect1(hp, sc, &ray, &mut want, sp, BVH_STACK, none),
            CorayStatus::Ok
        );
        assert_eq!(
            coray_proj_tracer_intersect1(&mut *tr, &ray, &mut got),
            CorayStatus::Ok
        );
        assert_eq!(format!("{got:?}"), format!("{want:?}"));
        assert_eq!(want.geom_id, 0, "the camera ray hits the floor");
        let (mut o1, mut o2) = (5u8, 6u8);
        assert_eq!(
            coray_proj_occluded1(hp, sc, &ray, &mut o1, sp, BVH_STACK, none),
            CorayStatus::Ok
        );
        assert_eq!(
            coray_proj_tracer_occluded1(&mut *tr, &ray, &mut o2),
            CorayStatus::Ok
        );
        assert_eq!((o1, o2), (1, 1));
        let before = got;
        assert_eq!(
            coray_proj_tracer_intersect1(&mut *tr, &down(), &mut got),
            CorayStatus::InvalidParameter,
            "a ray off the eye"
        );
        assert_eq!(format!("{got:?}"), format!("{before:?}"), "nothing written");
        // Another family's call refuses it.
        assert_eq!(
            coray_kdtree_tracer_intersect1(&mut *tr, &ray, &mut got),
            CorayStatus::InvalidParameter,
            "a projection hierarchy's tracer on the kd-tree's call"
        );
    }
}

/// The wide hierarchy's statuses: a bad leaf size, arenas and scratch too
/// small (with the size needed), another scene, a damaged header, a
/// damaged node, a short stack.
#[test]
fn wide_statuses() {
    let f = floor();
    let s = scene(&f);
    let null = core::ptr::null_mut::<c_void>();
    unsafe {
        let bad = CorayWideParams {
            leaf_size: 0,
            ..coray_wide_params_default()
        };
        let mut r = requirements();
        assert_eq!(
            coray_wide_requirements(2, &bad, &mut r),
            CorayStatus::InvalidParameter
        );
        let p = coray_wide_params_default();
        assert_eq!(coray_wide_requirements(2, &p, &mut r), CorayStatus::Ok);
        let mut a = arena(r.arena_bytes);
        let mut sc = arena(r.scratch_bytes);
        let (ap, sp) = (a.as_mut_ptr().cast::<c_void>(), sc.as_mut_ptr().cast());
        let mut needed = 0usize;
        for (ab, sb, want) in [
            (r.arena_bytes - 1, r.scratch_bytes, r.arena_bytes),
            (r.arena_bytes, r.scratch_bytes - 1, r.scratch_bytes),
        ] {
            needed = 0;
            assert_eq!(
                coray_wide_build(&s, &p, ap, ab, sp, sb, &mut needed),
                CorayStatus::ArenaTooSmall
            );
            assert_eq!(needed, want);
        }
        assert_eq!(
            coray_wide_build(
                &s,
                &bad,
                ap,
                r.arena_bytes,
                sp,
                r.scratch_bytes,
                &mut needed
            ),
            CorayStatus::InvalidParameter
        );
        assert_eq!(
            coray_wide_build(&s, &p, ap, r.arena_bytes, sp, r.scratch_bytes, null.cast()),
            CorayStatus::Ok
        );
        // Another scene (one triangle fewer).
        let mut other = s;
        other.triangle_count = 1;
        let mut h = CorayWide { opaque: [0; 32] };
        assert_eq!(
            coray_wide_open(ap, r.arena_bytes, &other, &mut h),
            CorayStatus::SceneMismatch
        );
        assert_eq!(
            coray_wide_open(ap, 8, &s, &mut h),
            CorayStatus::CorruptArena
        );
        assert_eq!(
            coray_wide_open(ap, r.arena_bytes, &s, &mut h),
            CorayStatus::Ok
        );
        let mut info = coray_wide_info_default();
        assert_eq!(coray_wide_info(&h, &mut info), CorayStatus::Ok);
        assert_eq!(
            (info.ref_count, info.node_count, info.leaf_size),
            (2, 1, p.leaf_size)
        );
        let mut shape = coray_shape_default();
        assert_eq!(coray_wide_validate(&h, &mut shape), CorayStatus::Ok);
        // The tree is a prefix of the arena: those bytes alone open, and
        // one byte fewer does not.
        assert!(info.arena_bytes_used <= r.arena_bytes);
        let mut kept = arena(info.arena_bytes_used);
        core::ptr::copy_nonoverlapping(
            ap.cast::<u8>(),
            kept.as_mut_ptr().cast::<u8>(),
            info.arena_bytes_used,
        );
        let mut hk = CorayWide { opaque: [0; 32] };
        let kp = kept.as_ptr().cast::<c_void>();
        assert_eq!(
            coray_wide_open(kp, info.arena_bytes_used - 1, &s, &mut hk),
            CorayStatus::CorruptArena
        );
        assert_eq!(
            coray_wide_open(kp, info.arena_bytes_used, &s, &mut hk),
            CorayStatus::Ok
        );
        assert_eq!(coray_wide_validate(&hk, &mut shape), CorayStatus::Ok);
        // A short stack, then a damaged box: validate refuses it.
        let mut stack = arena(info.stack_bytes);
        let mut hit = CorayHit::default();
        assert_eq!(
            coray_wide_intersect1(
                &h,
                &down(),
                &mut hit,
                stack.as_mut_ptr().cast(),
                4,
                null.cast()
            ),
            CorayStatus::ArenaTooSmall
        );
        assert_eq!(
            coray_wide_intersect1(
                &h,
                &down(),
                &mut hit,
                stack.as_mut_ptr().cast(),
                info.stack_bytes,
                null.cast()
            ),
            CorayStatus::Ok
        );
        assert_eq!(hit.t, 3.0);
        let bytes = core::slice::from_raw_parts_mut(ap.cast::<u8>(), r.arena_bytes);
        // The root node follows the 128-byte header; its first box's min x.
        bytes[128..132].copy_from_slice(&1e30f32.to_le_bytes());
        assert_eq!(
            coray_wide_validate(&h, &mut shape),
            CorayStatus::CorruptArena
        );
        bytes[0] ^= 1;
        assert_eq!(
            coray_wide_open(ap, r.arena_bytes, &s, &mut h),
            CorayStatus::CorruptArena
        );
    }
}

/// Rays over and off the floor, from above and below, some invalid: the
/// rays every tracer test traces.
fn tracer_rays() -> Vec<CorayRay> {
    let mut rays = Vec::new();
    for i in 0..12 {
        for j in 0..12 {
            let (x, z) = (i as f32 - 5.5, j as f32 - 5.5);
            let up = (i + j) % 3 == 0;
            rays.push(CorayRay {
                org: [x, if up { -2.0 } else { 3.0 }, z],
                tnear: 0.0,
                dir: [0.1, if up { 1.0 } else { -1.0 }, -0.05],
                tfar: if (i * j) % 7 == 3 { 1.0 } else { f32::INFINITY },
            });
        }
    }
    rays.push(CorayRay {
        dir: [0.0; 3],
        ..down()
    });
    rays
}

/// A tracer of each family answers every ray as the family's array call
/// does, bit for bit, and sums the array call's statistics.
#[test]
fn a_tracer_answers_what_the_array_call_answers() {
    let f = floor();
    let s = scene(&f);
    let rays = tracer_rays();
    let n = rays.len();
    let (_ka, kt) = kd(&s);
    let (_wa, wt) = wide(&s);
    let (_ba, bt) = bvh(&s);
    let mut stack = arena(KD_STACK);
    let sp: *mut c_void = stack.as_mut_ptr().cast();
    let stats = || CorayTraceStats {
        struct_size: size_of::<CorayTraceStats>(),
        ..Default::default()
    };
    // (family, make, array intersect, array occluded)
    type Make<'a> = Box<dyn Fn(*mut CorayTracer) -> CorayStatus + 'a>;
    type Arrays<'a> = Box<
        dyn Fn(&mut [CorayHit], &mut [u8], *mut CorayTraceStats) -> (CorayStatus, CorayStatus) + 'a,
    >;
    type OnTracer = (
        unsafe extern "C" fn(*mut CorayTracer, *const CorayRay, *mut CorayHit) -> CorayStatus,
        unsafe extern "C" fn(*mut CorayTracer, *const CorayRay, *mut u8) -> CorayStatus,
    );
    let mut cases: Vec<(String, Make, Arrays, OnTracer)> = Vec::new();
    for trav in [
        CORAY_TRAVERSAL_HIERARCHICAL,
        CORAY_TRAVERSAL_ROPES,
        CORAY_TRAVERSAL_PACKETS,
    ] {
        let (kt, rays) = (&kt, &rays);
        cases.push((
            format!("kd traversal {trav}"),
            Box::new(move |t| unsafe { coray_kdtree_tracer(kt, trav, sp, KD_STACK, t) }),
            Box::new(move |h, o, st| unsafe {
                (
                    coray_kdtree_intersect(
                        kt,
                        trav,
                        rays.as_ptr(),
                        h.as_mut_ptr(),
                        n,
                        sp,
                        KD_STACK,
                        st,
                    ),
                    coray_kdtree_occluded(
                        kt,
                        trav,
                        rays.as_ptr(),
                        o.as_mut_ptr(),
                        n,
                        sp,
                        KD_STACK,
                        core::ptr::null_mut(),
                    ),
                )
            }),
            (
                coray_kdtree_tracer_intersect1 as _,
                coray_kdtree_tracer_occluded1 as _,
            ),
        ));
    }
    {
        let (wt, rays) = (&wt, &rays);
        cases.push((
            "wide".into(),
            Box::new(move |t| unsafe { coray_wide_tracer(wt, sp, KD_STACK, t) }),
            Box::new(move |h, o, st| unsafe {
                (
                    coray_wide_intersect(wt, rays.as_ptr(), h.as_mut_ptr(), n, sp, KD_STACK, st),
                    coray_wide_occluded(
                        wt,
                        rays.as_ptr(),
                        o.as_mut_ptr(),
                        n,
                        sp,
                        KD_STACK,
                        core::ptr::null_mut(),
                    ),
                )
            }),
            (
                coray_wide_tracer_intersect1 as _,
                coray_wide_tracer_occluded1 as _,
            ),
        ));
    }
    {
        let (bt, rays) = (&bt, &rays);
        cases.push((
            "bvh".into(),
            Box::new(move |t| unsafe { coray_bvh_tracer(bt, sp, KD_STACK, t) }),
            Box::new(move |h, o, st| unsafe {
                (
                    coray_bvh_intersect(bt, rays.as_ptr(), h.as_mut_ptr(), n, sp, KD_STACK, st),
                    coray_bvh_occluded(
                        bt,
                        rays.as_ptr(),
                        o.as_mut_ptr(),
                        n,
                        sp,
                        KD_STACK,
                        core::ptr::null_mut(),
                    ),
                )
            }),
            (
                coray_bvh_tracer_intersect1 as _,
                coray_bvh_tracer_occluded1 as _,
            ),
        ));
    }
    for (what, make, arrays, (intersect1, occluded1)) in &cases {
        let mut want = vec![CorayHit::default(); n];
        let mut want_occ = vec![0u8; n];
        let mut want_st = stats();
        assert_eq!(
            arrays(&mut want, &mut want_occ, &mut want_st),
            (CorayStatus::Ok, CorayStatus::Ok),
            "{what}"
        );
        let mut tracer = Box::new(CorayTracer { opaque: [0; 32] });
        assert_eq!(make(&mut *tracer), CorayStatus::Ok, "{what}");
        let mut got_st = stats();
        unsafe {
            for (i, r) in rays.iter().enumerate() {
                let mut hit = CorayHit::default();
                assert_eq!(
                    intersect1(&mut *tracer, r, &mut hit),
                    CorayStatus::Ok,
                    "{what} ray {i}"
                );
                assert_eq!(
                    format!("{hit:?}"),
                    format!("{:?}", want[i]),
                    "{what} ray {i}"
                );
            }
            assert_eq!(coray_tracer_stats(&*tracer, &mut got_st), CorayStatus::Ok);
            assert_eq!(
                format!("{got_st:?}"),
                format!("{want_st:?}"),
                "{what}: the array call's statistics"
            );
            for (i, r) in rays.iter().enumerate() {
                let mut o = 7u8;
                assert_eq!(
                    occluded1(&mut *tracer, r, &mut o),
                    CorayStatus::Ok,
                    "{what} ray {i}"
                );
                assert_eq!(o, want_occ[i], "{what} ray {i}");
            }
            assert_eq!(coray_tracer_stats(&*tracer, &mut got_st), CorayStatus::Ok);
            assert_eq!(got_st.rays, 2 * n as u64, "{what}");
        }
        // The floor is hit from above, not from below where the
        // ray's interval is long enough; some rays miss.
        assert!(
            want.iter().any(|h| h.geom_id == 0)
                && want.iter().any(|h| h.geom_id == CORAY_INVALID_ID),
            "{what}"
        );
    }
}

/// Every refusal of the tracer calls, each leaving the answer and the
/// tracer as they were: after each, a good call still gives the floor.
#[test]
fn a_tracer_refuses_what_it_cannot_trust() {
    use CorayStatus::*;
    let f = floor();
    let s = scene(&f);
    let (arena_k, t) = kd(&s);
    let (_other_arena, other) = kd(&s);
    // One block holds the stack, a tracer, rays and hits, so that each can
    // be put over another.
    const TRACER: usize = KD_STACK;
    const RAY: usize = TRACER + 256;
    const HIT: usize = RAY + 64;
    let mut mem = arena(HIT + 256);
    let base = mem.as_mut_ptr().cast::<u8>();
    let sp: *mut c_void = base.cast();
    let at = |off: usize| unsafe { base.add(off) };
    let tr = at(TRACER).cast::<CorayTracer>();
    let ray = at(RAY).cast::<CorayRay>();
    let hit = at(HIT).cast::<CorayHit>();
    let none = core::ptr::null_mut();
    let hier = CORAY_TRAVERSAL_HIERARCHICAL;
    unsafe {
        *ray = down();
        // Making one.
        assert_eq!(
            coray_kdtree_tracer(core::ptr::null(), hier, sp, KD_STACK, tr),
            NullPointer
        );
        assert_eq!(
            coray_kdtree_tracer(&t, hier, none, KD_STACK, tr),
            NullPointer
        );
        assert_eq!(
            coray_kdtree_tracer(&t, hier, sp, KD_STACK, none.cast()),
            NullPointer
        );
        assert_eq!(
            coray_kdtree_tracer(&t, hier, at(4).cast(), KD_STACK - 16, tr),
            Misaligned
        );
        assert_eq!(
            coray_kdtree_tracer(&t, hier, sp, KD_STACK - 1, tr),
            ArenaTooSmall
        );
        assert_eq!(
            coray_kdtree_tracer(&t, hier, sp, usize::MAX, tr),
            InvalidParameter,
            "a stack of more bytes than an object can have"
        );
        assert_eq!(
            coray_kdtree_tracer(&t, 9, sp, KD_STACK, tr),
            InvalidParameter
        );
        let zeroed = CorayKdTree { opaque: [0; 32] };
        assert_eq!(
            coray_kdtree_tracer(&zeroed, hier, sp, KD_STACK, tr),
            InvalidParameter
        );
        assert_eq!(
            coray_kdtree_tracer(&t, hier, sp, KD_STACK, at(8).cast()),
            InvalidParameter,
            "the tracer inside its stack"
        );
        let arena_k_ptr = arena_k.as_ptr() as *mut c_void;
        assert_eq!(
            coray_kdtree_tracer(&t, hier, arena_k_ptr, KD_STACK, tr),
            InvalidParameter,
            "the stack over the arena"
        );
        let mut handle_copy = t;
        let hp: *mut CorayKdTree = &mut handle_copy;
        assert_eq!(
            coray_kdtree_tracer(hp, hier, sp, KD_STACK, hp.cast()),
            InvalidParameter,
            "the tracer over the handle"
        );
        // The wide hierarchy's make call refuses a kd handle.
        assert_eq!(
            coray_wide_tracer((&t as *const CorayKdTree).cast(), sp, KD_STACK, tr),
            InvalidParameter
        );
        assert_eq!(coray_kdtree_tracer(&t, hier, sp, KD_STACK, tr), Ok);
        let made = *tr;
        let good = |what: &str| {
            let mut h = CorayHit::default();
            assert_eq!(
                coray_kdtree_tracer_intersect1(tr, &down(), &mut h),
                Ok,
                "after {what}"
            );
            assert_eq!((h.geom_id, h.t), (0, 3.0), "after {what}");
        };
        good("making it");
        // Tracing: each refusal writes no answer.
        let sentinel = CorayHit {
            t: -7.0,
            ..Default::default()
        };
        let refuse_only = |what: &str,
                           t: *mut CorayTracer,
                           r: *const CorayRay,
                           h: *mut CorayHit,
                           want: CorayStatus| {
            let h_ok = !h.is_null() && (h as usize).is_multiple_of(4);
            if h_ok {
                h.write_unaligned(sentinel);
            }
            let words = |t: *mut CorayTracer| {
                (!t.is_null() && (t as usize).is_multiple_of(8)).then(|| (*t).opaque)
            };
            let before = words(t);
            assert_eq!(coray_kdtree_tracer_intersect1(t, r, h), want, "{what}");
            if h_ok {
                assert_eq!(h.read_unaligned().t, -7.0, "{what}: the answer was written");
            }
            if !(t as usize..t as usize + size_of::<CorayTracer>()).contains(&(h as usize)) {
                assert_eq!(words(t), before, "{what}: the tracer was written");
            }
            let o = h.cast::<u8>();
            if !o.is_null() {
                o.write(9);
            }
            assert_eq!(
                coray_kdtree_tracer_occluded1(t, r, o),
                want,
                "{what} (occluded)"
            );
            if !o.is_null() {
                assert_eq!(o.read(), 9, "{what}: the answer was written (occluded)");
            }
        };
        let refuse = |what: &str,
                      t: *mut CorayTracer,
                      r: *const CorayRay,
                      h: *mut CorayHit,
                      want: CorayStatus| {
            refuse_only(what, t, r, h, want);
            good(what);
        };
        refuse("a null tracer", none.cast(), ray, hit, NullPointer);
        refuse("a null ray", tr, core::ptr::null(), hit, NullPointer);
        refuse("a null answer", tr, ray, none.cast(), NullPointer);
        refuse(
            "a misaligned tracer",
            at(TRACER + 4).cast(),
            ray,
            hit,
            Misaligned,
        );
        let mut zero = CorayTracer { opaque: [0; 32] };
        refuse("a zeroed tracer", &mut zero, ray, hit, InvalidParameter);
        let mut copy = made;
        refuse(
            "a tracer copied elsewhere",
            &mut copy,
            ray,
            hit,
            InvalidParameter,
        );
        // Each of the binding's 14 words (check, kind, mode, handle and
        // its seal, stack, the answer's and the ray's ranges, the kd view's
        // trace box).
        for w in 0..14 {
            let mut damaged = *tr;
            damaged.opaque[w] ^= 1 << 40;
            tr.write(damaged);
            refuse_only(&format!("word {w} damaged"), tr, ray, hit, InvalidParameter);
            tr.write(made);
            good("a word restored");
        }
        // The handle it was made with, replaced by another tree's.
        let mut h2 = t;
        let mut tr2 = Box::new(CorayTracer { opaque: [0; 32] });
        let mut stack2 = arena(KD_STACK);
        assert_eq!(
            coray_kdtree_tracer(&h2, hier, stack2.as_mut_ptr().cast(), KD_STACK, &mut *tr2),
            Ok
        );
        h2 = other;
        let mut out = CorayHit::default();
        assert_eq!(
            coray_kdtree_tracer_intersect1(&mut *tr2, &down(), &mut out),
            InvalidParameter,
            "a handle opened on another arena"
        );
        let _ = h2;
        // Answers and rays where they may not lie.
        refuse(
            "the answer over the ray",
            tr,
            ray,
            ray.cast(),
            InvalidParameter,
        );
        refuse(
            "the answer inside the stack",
            tr,
            ray,
            at(512).cast(),
            InvalidParameter,
        );
        refuse(
            "the answer over the tracer",
            tr,
            ray,
            // Over its statistics: the sentinel this writes there must not
            // damage the binding's words (the first 112 bytes).
            at(TRACER + 128).cast(),
            InvalidParameter,
        );
        // (no sentinel written in the handle, arena or scene: they must
        // stay as made)
        let th = (&t as *const CorayKdTree as *mut CorayKdTree).cast::<CorayHit>();
        assert_eq!(
            coray_kdtree_tracer_intersect1(tr, ray, th),
            InvalidParameter,
            "the answer over the handle"
        );
        assert_eq!(
            coray_kdtree_tracer_occluded1(tr, ray, th.cast()),
            InvalidParameter,
            "the answer over the handle"
        );
        good("the answer over the handle");
        let p = arena_k.as_ptr().cast::<u8>().add(64) as *mut CorayHit;
        assert_eq!(
            coray_kdtree_tracer_intersect1(tr, ray, p),
            InvalidParameter,
            "the answer over the arena"
        );
        assert_eq!(
            coray_kdtree_tracer_occluded1(tr, ray, p.cast()),
            InvalidParameter,
            "the answer over the arena"
        );
        good("the answer over the arena");
        let p = f.vertices.as_ptr() as *mut CorayHit;
        assert_eq!(
            coray_kdtree_tracer_intersect1(tr, ray, p),
            InvalidParameter,
            "the answer over the vertices"
        );
        assert_eq!(
            coray_kdtree_tracer_occluded1(tr, ray, p.cast()),
            InvalidParameter,
            "the answer over the vertices"
        );
        good("the answer over the vertices");
        at(256).cast::<CorayRay>().write(down());
        refuse(
            "the ray inside the stack",
            tr,
            at(256).cast(),
            hit,
            InvalidParameter,
        );
        at(TRACER + 128).cast::<CorayRay>().write(down());
        refuse(
            "the ray over the tracer's statistics",
            tr,
            at(TRACER + 128).cast(),
            hit,
            InvalidParameter,
        );
        // Places that may: a new answer place after many calls at another.
        *ray = down();
        let mut far = [CorayHit::default(); 3];
        for (i, h) in far.iter_mut().enumerate() {
            assert_eq!(coray_kdtree_tracer_intersect1(tr, ray, h), Ok, "answer {i}");
            assert_eq!(h.t, 3.0);
        }
        // Statistics.
        let mut st = CorayTraceStats {
            struct_size: size_of::<CorayTraceStats>(),
            ..Default::default()
        };
        assert_eq!(coray_tracer_stats(none.cast(), &mut st), NullPointer);
        assert_eq!(coray_tracer_stats(tr, none.cast()), NullPointer);
        let mut short = CorayTraceStats {
            struct_size: 4,
            ..Default::default()
        };
        assert_eq!(coray_tracer_stats(tr, &mut short), InvalidParameter);
        let over = at(TRACER + 8).cast::<CorayTraceStats>();
        over.cast::<usize>().write(size_of::<CorayTraceStats>());
        assert_eq!(
            coray_tracer_stats(tr, over),
            InvalidParameter,
            "the statistics over the tracer"
        );
        tr.write(made);
        assert_eq!(coray_tracer_stats(tr, &mut st), Ok);
        assert_eq!(st.rays, 0, "a tracer rewritten as made counts from 0");
        good("its statistics");
        assert_eq!(coray_tracer_stats(tr, &mut st), Ok);
        assert_eq!(st.rays, 1, "only successful calls count");
    }
}

/// An R-tree deepened by inserts past its tracer's stack: the tracer's
/// calls refuse with `ARENA_TOO_SMALL` (no trace runs), and a tracer made
/// again with the info's new `stack_bytes` traces it.
#[test]
fn a_deepened_rtree_needs_a_new_tracer() {
    // A strip of 16 triangles along x.
    let mut vertices = Vec::new();
    let mut indices = Vec::new();
    for i in 0..17u32 {
        vertices.extend_from_slice(&[i as f32, 0.0, 0.0, i as f32, 0.0, 1.0]);
        if i < 16 {
            indices.extend_from_slice(&[2 * i, 2 * i + 2, 2 * i + 1]);
        }
    }
    let mut s = coray_scene_default();
    s.vertices = vertices.as_ptr();
    s.vertex_count = 34;
    s.indices = indices.as_ptr();
    s.triangle_count = 16;
    let p = coray_bvh_params_default(CORAY_BVH_BUILDER_RTREE);
    let mut r = requirements();
    unsafe {
        assert_eq!(coray_bvh_requirements(400, &p, &mut r), CorayStatus::Ok);
        let mut a = arena(r.arena_bytes);
        let mut sc = arena(r.scratch_bytes);
        let ap: *mut c_void = a.as_mut_ptr().cast();
        let st = coray_bvh_build(
            &s,
            &p,
            ap,
            r.arena_bytes,
            sc.as_mut_ptr().cast(),
            r.scratch_bytes,
            core::ptr::null_mut(),
        );
        assert_eq!(st, CorayStatus::Ok);
        let mut h = CorayBvh { opaque: [0; 32] };
        assert_eq!(
            coray_bvh_open(ap, r.arena_bytes, &s, &mut h),
            CorayStatus::Ok
        );
        let mut info = coray_bvh_info_default();
        assert_eq!(coray_bvh_info(&h, &mut info), CorayStatus::Ok);
        let (depth0, bytes0) = (info.depth, info.stack_bytes);
        let mut stack = arena(bytes0);
        let mut tr = Box::new(CorayTracer { opaque: [0; 32] });
        assert_eq!(
            coray_bvh_tracer(&h, stack.as_mut_ptr().cast(), bytes0, &mut *tr),
            CorayStatus::Ok
        );
        let ray = CorayRay {
            org: [3.3, 2.0, 0.5],
            tnear: 0.0,
            dir: [0.0, -1.0, 0.0],
            tfar: f32::INFINITY,
        };
        let mut hit = CorayHit::default();
        assert_eq!(
            coray_bvh_tracer_intersect1(&mut *tr, &ray, &mut hit),
            CorayStatus::Ok
        );
        assert_eq!((hit.prim_id, hit.t), (3, 2.0));
        // Every triangle again, many times: the tree deepens.
        for k in 0..380u32 {
            let st = coray_bvh_insert(ap, r.arena_bytes, &s, CORAY_GEOM_TRIANGLES, k % 16);
            assert_eq!(st, CorayStatus::Ok, "insert {k}");
        }
        assert_eq!(coray_bvh_info(&h, &mut info), CorayStatus::Ok);
        assert!(
            info.depth > depth0 && info.stack_bytes > bytes0,
            "{depth0} -> {}",
            info.depth
        );
        let mut sentinel = CorayHit {
            t: -7.0,
            ..Default::default()
        };
        assert_eq!(
            coray_bvh_tracer_intersect1(&mut *tr, &ray, &mut sentinel),
            CorayStatus::ArenaTooSmall
        );
        assert_eq!(sentinel.t, -7.0, "nothing written");
        let mut stack2 = arena(info.stack_bytes);
        assert_eq!(
            coray_bvh_tracer(&h, stack2.as_mut_ptr().cast(), info.stack_bytes, &mut *tr),
            CorayStatus::Ok
        );
        assert_eq!(
            coray_bvh_tracer_intersect1(&mut *tr, &ray, &mut hit),
            CorayStatus::Ok
        );
        assert_eq!((hit.prim_id, hit.t), (3, 2.0));
        drop(stack);
    }
}

/// A reference cost that is negative, NaN or infinite is refused; 0 (the
/// plain SAH, and what a struct from a header before 1.6 reads as) and the
/// presets' are taken.
#[test]
fn kd_cost_reference_out_of_range_is_refused() {
    let auto = coray_kdtree_params_default(CORAY_KD_PRESET_AUTO);
    assert_eq!(auto.cost_reference, 1e-4);
    assert_eq!(
        coray_kdtree_params_default(CORAY_KD_PRESET_PAPER).cost_reference,
        0.0
    );
    for (cost, want) in [
        (-1e-4, CorayStatus::InvalidParameter),
        (f32::NAN, CorayStatus::InvalidParameter),
        (f32::INFINITY, CorayStatus::InvalidParameter),
        (0.0, CorayStatus::Ok),
        (1e-4, CorayStatus::Ok),
        (f32::MAX, CorayStatus::Ok),
    ] {
        let p = CorayKdParams {
            cost_reference: cost,
            ..auto
        };
        let mut r = requirements();
        // SAFETY: valid params and requirements structs on the stack.
        let got = unsafe { coray_kdtree_requirements(100, &p, &mut r) };
        assert_eq!(got, want, "cost_reference {cost}");
    }
}

/// A tracer's running statistics are caller memory the check word does not
/// cover: any bits there are counts, and a call adds its own to them modulo
/// 2^64, whatever the build's overflow checks (a sum that overflowed once
/// panicked in builds with them, and the call answered
/// `CORAY_STATUS_INTERNAL_ERROR`).
#[test]
fn a_tracers_totals_wrap_whatever_they_hold() {
    let f = floor();
    let s = scene(&f);
    let (_arena, t) = kd(&s);
    let mut stack = arena(KD_STACK);
    let sp: *mut c_void = stack.as_mut_ptr().cast();
    let mut tr = CorayTracer { opaque: [0; 32] };
    let ray = down();
    let mut first = CorayHit::default();
    let mut again = CorayHit::default();
    let mut st = CorayTraceStats {
        struct_size: size_of::<CorayTraceStats>(),
        ..Default::default()
    };
    // SAFETY: the handle, stack, tracer, ray and hits are live locals; the
    // tracer is made by its make call, then only its statistics' words
    // (those past the binding's 14) are overwritten.
    unsafe {
        let hier = CORAY_TRAVERSAL_HIERARCHICAL;
        assert_eq!(
            coray_kdtree_tracer(&t, hier, sp, KD_STACK, &mut tr),
            CorayStatus::Ok
        );
        assert_eq!(
            coray_kdtree_tracer_intersect1(&mut tr, &ray, &mut first),
            CorayStatus::Ok
        );
        assert!(first.t.is_finite(), "the ray hits the floor");
        for w in &mut tr.opaque[14..] {
            *w = u64::MAX;
        }
        assert_eq!(
            coray_kdtree_tracer_intersect1(&mut tr, &ray, &mut again),
            CorayStatus::Ok
        );
        assert_eq!(again.t.to_bits(), first.t.to_bits());
        assert_eq!(coray_tracer_stats(&tr, &mut st), CorayStatus::Ok);
    }
    // u64::MAX and the call's one ray: 0.
    assert_eq!(st.rays, 0);
    assert!(st.traversal_steps < 64, "{}", st.traversal_steps);
}

/// An array call over a corrupt arena stops at the first group of rays
/// that meets the damage (a packet's eight for the kd-tree, a chunk of 64
/// for the wide hierarchy, one ray for the others): the rest of `hits`
/// stays as it was. It traced every ray first, each until its walk's
/// budget ran out. The damage: everything after the arena's first `k`
/// bytes overwritten (0xff, zero, or words drawn among small indices and
/// far coordinates), for the first `k` at which the arena still opens and
/// the call reports it corrupt.
#[test]
fn array_calls_stop_at_the_first_fault() {
    // The floor cut into 16 x 16 squares: hierarchies with interior nodes.
    let n = 16u32;
    let mut f = Floor {
        vertices: Vec::new(),
        indices: Vec::new(),
    };
    for j in 0..=n {
        for i in 0..=n {
            let (x, z) = (i as f32 / n as f32, j as f32 / n as f32);
            f.vertices.extend([10.0 * x - 5.0, 0.0, 10.0 * z - 5.0]);
        }
    }
    for j in 0..n {
        for i in 0..n {
            let v = j * (n + 1) + i;
            f.indices
                .extend([v, v + 1, v + n + 2, v, v + n + 2, v + n + 1]);
        }
    }
    let mut s = scene(&f);
    s.vertex_count = f.vertices.len() / 3;
    s.triangle_count = f.indices.len() / 3;
    let rays = vec![down(); 1000];
    // The projection hierarchy takes rays from its camera's eye.
    let c = camera();
    let eye_rays = vec![
        CorayRay {
            org: c.from,
            tnear: 0.0,
            dir: [0.0, -1.0, 1.0],
            tfar: f32::INFINITY,
        };
        1000
    ];
    let sentinel = CorayHit {
        t: -1.0,
        ..Default::default()
    };
    let mut stack = arena(1 << 20);
    let (stk, stk_bytes) = (stack.as_mut_ptr().cast::<c_void>(), 1usize << 20);
    let null = core::ptr::null_mut();
    // (family, arena, most rays a call may answer before it stops, call)
    type Call<'a> = Box<dyn Fn(&[Block], &mut [CorayHit]) -> Option<CorayStatus> + 'a>;
    let (kd_a, _) = kd(&s);
    let (wide_a, _) = wide(&s);
    let (bvh_a, _) = bvh(&s);
    let (proj_a, _) = proj(&s);
    let families: Vec<(&str, Vec<Block>, usize, Call)> = vec![
        (
            "kd",
            kd_a,
            8,
            Box::new(|a: &[Block], hits: &mut [CorayHit]| unsafe {
                let mut h = CorayKdTree { opaque: [0; 32] };
                let bytes = a.len() * 16;
                (coray_kdtree_open(a.as_ptr().cast(), bytes, &s, &mut h) == CorayStatus::Ok).then(
                    || {
                        let t = CORAY_TRAVERSAL_HIERARCHICAL;
                        let (r, n) = (rays.as_ptr(), rays.len());
                        coray_kdtree_intersect(&h, t, r, hits.as_mut_ptr(), n, stk, stk_bytes, null)
                    },
                )
            }),
        ),
        (
            "wide",
            wide_a,
            64,
            Box::new(|a: &[Block], hits: &mut [CorayHit]| unsafe {
                let mut h = CorayWide { opaque: [0; 32] };
                let bytes = a.len() * 16;
                (coray_wide_open(a.as_ptr().cast(), bytes, &s, &mut h) == CorayStatus::Ok).then(
                    || {
                        let (r, n) = (rays.as_ptr(), rays.len());
                        coray_wide_intersect(&h, r, hits.as_mut_ptr(), n, stk, stk_bytes, null)
                    },
                )
            }),
        ),
        (
            "bvh",
            bvh_a,
            1,
            Box::new(|a: &[Block], hits: &mut [CorayHit]| unsafe {
                let mut h = CorayBvh { opaque: [0; 32] };
                let bytes = a.len() * 16;
                (coray_bvh_open(a.as_ptr().cast(), bytes, &s, &mut h) == CorayStatus::Ok).then(
                    || {
                        let (r, n) = (rays.as_ptr(), rays.len());
                        coray_bvh_intersect(&h, r, hits.as_mut_ptr(), n, stk, stk_bytes, null)
                    },
                )
            }),
        ),
        (
            "proj",
            proj_a,
            1,
            Box::new(|a: &[Block], hits: &mut [CorayHit]| unsafe {
                let mut h = CorayProj { opaque: [0; 32] };
                let bytes = a.len() * 16;
                (coray_proj_open(a.as_ptr().cast(), bytes, &s, &mut h) == CorayStatus::Ok).then(
                    || {
                        let (r, n) = (eye_rays.as_ptr(), eye_rays.len());
                        let sch = CORAY_PROJ_SCHEME_2D;
                        coray_proj_intersect(&h, sch, r, hits.as_mut_ptr(), n, stk, stk_bytes, null)
                    },
                )
            }),
        ),
    ];
    for (what, clean, most, call) in &families {
        let mut hits = vec![sentinel; rays.len()];
        assert_eq!(call(clean, &mut hits), Some(CorayStatus::Ok), "{what}");
        let mut stopped = false;
        for (k, fill) in (1..clean.len()).flat_map(|k| (0..10u64).map(move |f| (k, f))) {
            // Fills 0 and 1: every byte 0xff, every byte 0; the others
            // words drawn by a generator seeded by the fill among small
            // indices and coordinates far out (boxes that hold everything).
            let mut bad = clean.clone();
            let mut x = fill.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1;
            let words = [0, 1, 2, 3, (-1e30f32).to_bits(), 1e30f32.to_bits()];
            for b in &mut bad[k..] {
                let w: [u32; 4] = core::array::from_fn(|_| {
                    x ^= x << 13;
                    x ^= x >> 7;
                    x ^= x << 17;
                    words[(x % 6) as usize]
                });
                *b = match fill {
                    0 => Block([0xff; 16]),
                    1 => Block([0; 16]),
                    _ => Block(core::array::from_fn(|i| w[i / 4].to_le_bytes()[i % 4])),
                };
            }
            let mut hits = vec![sentinel; rays.len()];
            if call(&bad, &mut hits) != Some(CorayStatus::CorruptArena) {
                continue;
            }
            let written = hits.iter().filter(|h| h.t != -1.0).count();
            assert!(
                written <= *most,
                "{what}, damage from byte {}: {written} hits written",
                16 * k
            );
            stopped = true;
            break;
        }
        assert!(stopped, "{what}: no damage made the call fault");
    }
}

/// What a hostile job runner hands `run_job` as a job's flags.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum JobFlags {
    /// The job table itself (`jobs`).
    Table,
    /// The runner's stack below its own frame: where `run_job` and the
    /// job itself will have theirs.
    StackBelow,
    /// Just past the job table, where the build's own frames lie.
    PastTable,
    /// One buffer for every job, from two threads at once.
    Shared,
}

struct Runner {
    how: JobFlags,
    statuses: std::sync::Mutex<Vec<CorayStatus>>,
    buffer: std::sync::Mutex<Vec<u8>>,
}

unsafe extern "C" fn hostile_runner(
    ctx: *mut c_void,
    job_count: usize,
    flags_bytes: usize,
    run_job: CorayKdRunJob,
    jobs: *mut c_void,
) {
    let r = unsafe { &*ctx.cast::<Runner>() };
    let flags: *mut u8 = match r.how {
        JobFlags::Table => jobs.cast(),
        JobFlags::StackBelow => {
            let here = 0u8;
            (core::hint::black_box(&here) as *const u8)
                .cast_mut()
                .wrapping_sub(2048 + flags_bytes)
        }
        JobFlags::PastTable => jobs.cast::<u8>().wrapping_add(8192),
        JobFlags::Shared => r.buffer.lock().unwrap().as_mut_ptr(),
    };
    let (f, jb) = (flags as usize, jobs as usize);
    let run =
        move |job: usize| unsafe { run_job(jb as *mut c_void, job, f as *mut u8, flags_bytes) };
    if r.how == JobFlags::Shared {
        let half = job_count / 2;
        std::thread::scope(|s| {
            let a = s.spawn(|| (0..half).map(run).collect::<Vec<_>>());
            let b = s.spawn(|| (half..job_count).map(run).collect::<Vec<_>>());
            let mut st = r.statuses.lock().unwrap();
            st.extend(a.join().unwrap());
            st.extend(b.join().unwrap());
        });
    } else {
        let st: Vec<_> = (0..job_count).map(run).collect();
        r.statuses.lock().unwrap().extend(st);
    }
}

/// A job runner that hands `run_job` flags inside the job table, inside
/// the stack where the job will run or the build's own frames lie, or
/// one buffer to two threads at once: each such call is refused with
/// `INVALID_PARAMETER` (the job then runs on the building thread), never
/// a panic or a crash, and the arena is `coray_kdtree_build`'s. Before,
/// these returned `INTERNAL_ERROR` (a panic in the build) or crashed.
#[test]
fn hostile_job_runners_get_statuses() {
    // 3,000 small triangles in a row: a tree with many jobs.
    let mut v = Vec::new();
    let mut idx = Vec::new();
    for i in 0..3000u32 {
        let x = i as f32 * 0.01;
        v.extend([x, 0.0, 0.0, x + 0.005, 0.0, 0.0, x, 0.005, 0.3]);
        idx.extend([3 * i, 3 * i + 1, 3 * i + 2]);
    }
    let mut s = coray_scene_default();
    s.vertices = v.as_ptr();
    s.vertex_count = v.len() / 3;
    s.indices = idx.as_ptr();
    s.triangle_count = 3000;
    let p = CorayKdParams {
        job_threads: 4,
        ..coray_kdtree_params_default(CORAY_KD_PRESET_AUTO)
    };
    let mut r = requirements();
    unsafe {
        assert_eq!(coray_kdtree_requirements(3000, &p, &mut r), CorayStatus::Ok);
        let mut clean = arena(r.arena_bytes);
        let mut sc = arena(r.scratch_bytes);
        let null = core::ptr::null_mut();
        let (cp, sp) = (clean.as_mut_ptr().cast(), sc.as_mut_ptr().cast());
        assert_eq!(
            coray_kdtree_build(&s, &p, cp, r.arena_bytes, sp, r.scratch_bytes, null),
            CorayStatus::Ok
        );
        for how in [
            JobFlags::Table,
            JobFlags::StackBelow,
            JobFlags::PastTable,
            JobFlags::Shared,
        ] {
            let runner = Runner {
                how,
                statuses: Default::default(),
                buffer: std::sync::Mutex::new(vec![0; 3000]),
            };
            let mut a = arena(r.arena_bytes);
            let ctx = (&runner as *const Runner).cast_mut().cast();
            let st = coray_kdtree_build_jobs(
                &s,
                &p,
                a.as_mut_ptr().cast(),
                r.arena_bytes,
                sp,
                r.scratch_bytes,
                null,
                Some(hostile_runner),
                ctx,
            );
            assert_eq!(st, CorayStatus::Ok, "{how:?}");
            let statuses = runner.statuses.lock().unwrap().clone();
            assert!(statuses.len() > 2, "{how:?}: {} jobs", statuses.len());
            for s in &statuses {
                assert!(
                    matches!(s, CorayStatus::Ok | CorayStatus::InvalidParameter),
                    "{how:?}: {s:?}"
                );
            }
            if how != JobFlags::Shared {
                assert!(
                    statuses.iter().all(|&s| s == CorayStatus::InvalidParameter),
                    "{how:?}: {statuses:?}"
                );
            }
            let bytes = |b: &[Block]| {
                b.iter()
                    .flat_map(|x| x.0)
                    .take(r.arena_bytes)
                    .collect::<Vec<u8>>()
            };
            assert!(bytes(&a) == bytes(&clean), "{how:?}: the arena differs");
        }
    }
}
