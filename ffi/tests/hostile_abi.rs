//! Issue 16's C-ABI findings, each as a test: aliasing, outputs written on
//! a failing call, statuses that differ between families.
use coray_ffi::*;
use core::ffi::c_void;

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

fn kd(s: &CorayScene) -> (Vec<Block>, usize) {
    let p = coray_kd_params_default(CORAY_KD_PRESET_AUTO);
    let mut r = CorayKdRequirements::default();
    unsafe {
        assert_eq!(
            coray_kdtree_requirements(2, &p, &mut r),
            CorayStatus::Ok
        );
        let mut t = arena(r.tree_bytes);
        let mut sc = arena(r.scratch_bytes);
        assert_eq!(
            coray_kdtree_build(
                s,
                &p,
                t.as_mut_ptr().cast(),
                r.tree_bytes,
                sc.as_mut_ptr().cast(),
                r.scratch_bytes,
                core::ptr::null_mut()
            ),
            CorayStatus::Ok
        );
        (t, r.tree_bytes)
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
    let (t, bytes) = kd(&s);
    let mut buf = [Block([0; 16]); 8];
    let rays = buf.as_mut_ptr().cast::<CorayRay>();
    unsafe {
        *rays = down();
        let st = coray_kdtree_intersect(
            t.as_ptr().cast(),
            bytes,
            &s,
            CORAY_TRAVERSAL_HIERARCHICAL,
            rays,
            rays.cast::<CorayHit>(),
            1,
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
    let (t, bytes) = kd(&s);
    let ray = down();
    let mut hit = CorayHit {
        t: -7.0,
        ..Default::default()
    };
    let mut stats = [0u64; 16];
    let bad = unsafe { stats.as_mut_ptr().cast::<u8>().add(1).cast::<CorayTraceStats>() };
    let st = unsafe {
        coray_kdtree_intersect(
            t.as_ptr().cast(),
            bytes,
            &s,
            CORAY_TRAVERSAL_HIERARCHICAL,
            &ray,
            &mut hit,
            1,
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
    let p = coray_bvh_params_default(CORAY_BVH_TDBS);
    let mut r = CorayBvhRequirements::default();
    unsafe {
        assert_eq!(coray_bvh_requirements(2, &p, &mut r), CorayStatus::Ok);
        let mut a = arena(r.bvh_bytes);
        let mut sc = arena(r.scratch_bytes);
        assert_eq!(
            coray_bvh_build(
                &s,
                &p,
                a.as_mut_ptr().cast(),
                r.bvh_bytes,
                sc.as_mut_ptr().cast(),
                r.scratch_bytes,
                core::ptr::null_mut()
            ),
            CorayStatus::Ok
        );
        let st = coray_bvh_intersect(
            a.as_ptr().cast(),
            r.bvh_bytes,
            &s,
            core::ptr::null(),
            core::ptr::null_mut(),
            0,
            core::ptr::null_mut(),
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
    let p = coray_bvh_params_default(CORAY_BVH_RTREE);
    let mut r = CorayBvhRequirements::default();
    unsafe {
        assert_eq!(coray_bvh_requirements(2, &p, &mut r), CorayStatus::Ok);
        let mut a = arena(r.bvh_bytes);
        let mut sc = arena(r.scratch_bytes);
        assert_eq!(
            coray_bvh_build(
                &s,
                &p,
                a.as_mut_ptr().cast(),
                r.bvh_bytes,
                sc.as_mut_ptr().cast(),
                r.scratch_bytes,
                core::ptr::null_mut()
            ),
            CorayStatus::Ok
        );
        // max_children sits after magic, version, builder, 3 counts and the 6-word info.
        let words = a.as_mut_ptr().cast::<u32>();
        *words.add(12) = 1000;
        let st = coray_bvh_validate(a.as_ptr().cast(), r.bvh_bytes, &s, core::ptr::null_mut());
        assert_eq!(st, CorayStatus::CorruptArena);
        let st = coray_bvh_insert(a.as_mut_ptr().cast(), r.bvh_bytes, &s, 0);
        assert_eq!(st, CorayStatus::CorruptArena);
    }
}

/// Cast scratch inside the tree arena: rejected.
#[test]
fn cast_scratch_inside_the_tree_is_rejected() {
    let f = floor();
    let s = scene(&f);
    let (mut t, bytes) = kd(&s);
    let cam = CorayCamera {
        struct_size: core::mem::size_of::<CorayCamera>(),
        from: [0.0, 5.0, -5.0],
        at: [0.0, 0.0, 0.0],
        up: [0.0, 1.0, 0.0],
        angle_deg: 60.0,
        width: 4,
        height: 4,
    };
    let p = coray_cast_params_default();
    let mut need = 0usize;
    unsafe {
        assert_eq!(coray_cast_requirements(&cam, &p, &mut need), CorayStatus::Ok);
        let mut ts = [0f32; 16];
        let mut ps = [0u32; 16];
        let st = coray_kdtree_cast_image(
            t.as_ptr().cast(),
            bytes,
            &s,
            &cam,
            &p,
            t.as_mut_ptr().cast::<c_void>(),
            need,
            ts.as_mut_ptr(),
            ps.as_mut_ptr(),
            core::ptr::null_mut(),
        );
        assert_eq!(st, CorayStatus::InvalidParameter);
        // And the two outputs in one buffer.
        let mut sc = arena(need);
        let mut both = [0u32; 16];
        let st = coray_kdtree_cast_image(
            t.as_ptr().cast(),
            bytes,
            &s,
            &cam,
            &p,
            sc.as_mut_ptr().cast(),
            need,
            both.as_mut_ptr().cast(),
            both.as_mut_ptr(),
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
    let (t, bytes) = kd(&s);
    let a = [-1.0f32, 1.0, -1.0, 1.0, 1.0, -1.0, 1.0, 1.0, 1.0];
    let b = [-1.0f32, 4.0, -1.0, 1.0, 4.0, -1.0, 1.0, 4.0, 1.0];
    let need = coray_patch_requirements(16);
    let mut sc = arena(need);
    let mut out = CorayPatchResult::default();
    let st = unsafe {
        coray_kdtree_patch_visibility(
            t.as_ptr().cast(),
            bytes,
            &s,
            a.as_ptr(),
            3,
            b.as_ptr(),
            3,
            256,
            1e-3,
            sc.as_mut_ptr().cast(),
            need,
            &mut out,
        )
    };
    assert_eq!(st, CorayStatus::InvalidParameter, "samples {}", out.samples);
}
