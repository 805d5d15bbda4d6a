//! Every family's `validate` accepts what its own build made over a scene
//! that holds degenerate primitives (which stay out of the structure): a
//! caller that validates what it loads must not refuse good arenas. Each
//! structure is built, opened and validated through the C ABI, over
//! scenes with a NaN vertex, an infinite one, a triangle whose box passes
//! FLT_MAX, a subnormal triangle, spheres of NaN, zero, negative and
//! infinite radius, and a cone of NaN radius, beside good primitives.

use coray_ffi::*;
use core::ffi::c_void;
use core::mem::size_of;

#[repr(C, align(16))]
#[derive(Clone, Copy)]
struct Block([u8; 16]);

fn arena(bytes: usize) -> Vec<Block> {
    vec![Block([0; 16]); bytes.div_ceil(16).max(1)]
}

/// A scene's arrays: two good triangles, a good sphere and a good cone,
/// and the degenerate primitive(s) `kind` names.
struct Arrays {
    vertices: Vec<f32>,
    indices: Vec<u32>,
    spheres: Vec<f32>,
    cones: Vec<f32>,
}

fn arrays(kind: usize) -> Arrays {
    let mut a = Arrays {
        vertices: vec![
            -1., 0., -1., 1., 0., -1., 1., 0., 1., -1., 0., 1., // a quad
        ],
        indices: vec![0, 1, 2, 0, 2, 3],
        spheres: vec![0., 1., 0., 0.5],
        cones: vec![2., 0., 0., 0.3, 2., 1., 0., 0.1],
    };
    let tri = |a: &mut Arrays, v: [[f32; 3]; 3]| {
        let first = (a.vertices.len() / 3) as u32;
        for p in v {
            a.vertices.extend_from_slice(&p);
        }
        a.indices.extend_from_slice(&[first, first + 1, first + 2]);
    };
    match kind {
        0 => tri(&mut a, [[f32::NAN, 0., 0.], [1., 0., 0.], [0., 1., 0.]]),
        1 => tri(
            &mut a,
            [[f32::INFINITY, 0., 0.], [1., 0., 0.], [0., 1., 0.]],
        ),
        2 => tri(&mut a, [[-3e38, 0., 0.], [3e38, 0., 0.], [0., 3e38, 1.]]),
        3 => tri(&mut a, [[0., 0., 0.], [1e-40, 0., 0.], [0., 1e-40, 0.]]),
        4 => a.spheres.extend_from_slice(&[0., 0., 0., f32::NAN]),
        5 => a.spheres.extend_from_slice(&[0., 0., 0., 0.]),
        6 => a.spheres.extend_from_slice(&[0., 0., 0., -1.]),
        7 => a.spheres.extend_from_slice(&[f32::INFINITY, 0., 0., 1.]),
        8 => a
            .cones
            .extend_from_slice(&[0., 0., 0., f32::NAN, 0., 1., 0., 0.2]),
        _ => {
            // All of them at once.
            for k in 0..9 {
                let b = arrays(k);
                let first = (a.vertices.len() / 3) as u32;
                a.vertices.extend_from_slice(&b.vertices[12..]);
                a.indices
                    .extend(b.indices[6..].iter().map(|&i| i - 4 + first));
                a.spheres.extend_from_slice(&b.spheres[4..]);
                a.cones.extend_from_slice(&b.cones[8..]);
            }
        }
    }
    a
}

/// Primitives of `a` that are not degenerate.
fn valid_prims(a: &Arrays) -> u32 {
    let vertices: Vec<[f32; 3]> = a.vertices.chunks(3).map(|v| [v[0], v[1], v[2]]).collect();
    let triangles: Vec<[u32; 3]> = a.indices.chunks(3).map(|t| [t[0], t[1], t[2]]).collect();
    let spheres: Vec<coray::Sphere> = a
        .spheres
        .chunks(4)
        .map(|s| coray::Sphere {
            center: [s[0], s[1], s[2]],
            radius: s[3],
        })
        .collect();
    let cones: Vec<coray::Cone> = a
        .cones
        .chunks(8)
        .map(|c| coray::Cone {
            base: [c[0], c[1], c[2]],
            base_radius: c[3],
            apex: [c[4], c[5], c[6]],
            apex_radius: c[7],
        })
        .collect();
    let s = coray::Scene {
        vertices: &vertices,
        triangles: &triangles,
        spheres: &spheres,
        cones: &cones,
    };
    (0..s.prim_count())
        .filter(|&p| s.prim_bounds(p).is_some())
        .count() as u32
}

fn scene(a: &Arrays) -> CorayScene {
    let mut s = coray_scene_default();
    s.vertices = a.vertices.as_ptr();
    s.vertex_count = a.vertices.len() / 3;
    s.indices = a.indices.as_ptr();
    s.triangle_count = a.indices.len() / 3;
    s.spheres = a.spheres.as_ptr();
    s.sphere_count = a.spheres.len() / 4;
    s.cones = a.cones.as_ptr();
    s.cone_count = a.cones.len() / 8;
    s
}

fn prims(s: &CorayScene) -> usize {
    s.triangle_count + s.sphere_count + s.cone_count
}

fn requirements() -> CorayRequirements {
    CorayRequirements {
        struct_size: size_of::<CorayRequirements>(),
        ..Default::default()
    }
}

fn shape() -> CorayShape {
    CorayShape {
        struct_size: size_of::<CorayShape>(),
        ..Default::default()
    }
}

/// `validate`'s status and shape for a kd-tree of `preset` over `s`.
fn kd(s: &CorayScene, preset: CorayKdPreset) -> (CorayStatus, CorayShape) {
    let p = coray_kdtree_params_default(preset);
    let mut r = requirements();
    unsafe {
        assert_eq!(
            coray_kdtree_requirements(prims(s), &p, &mut r),
            CorayStatus::Ok
        );
        let mut t = arena(r.arena_bytes);
        let mut sc = arena(r.scratch_bytes);
        let st = coray_kdtree_build(
            s,
            &p,
            t.as_mut_ptr().cast(),
            r.arena_bytes,
            sc.as_mut_ptr().cast(),
            r.scratch_bytes,
            core::ptr::null_mut(),
        );
        assert_eq!(st, CorayStatus::Ok);
        let mut h = CorayKdTree { opaque: [0; 32] };
        assert_eq!(
            coray_kdtree_open(t.as_ptr().cast(), r.arena_bytes, s, &mut h),
            CorayStatus::Ok
        );
        let mut stack = arena(CORAY_KDTREE_STACK_BYTES);
        let mut out = shape();
        let v = coray_kdtree_validate(
            &h,
            stack.as_mut_ptr().cast::<c_void>(),
            CORAY_KDTREE_STACK_BYTES,
            &mut out,
        );
        (v, out)
    }
}

/// `validate`'s status and shape for a hierarchy of `builder` over `s`.
fn bvh(s: &CorayScene, builder: CorayBvhBuilder) -> (CorayStatus, CorayShape) {
    let p = coray_bvh_params_default(builder);
    let mut r = requirements();
    unsafe {
        assert_eq!(
            coray_bvh_requirements(prims(s), &p, &mut r),
            CorayStatus::Ok
        );
        let mut t = arena(r.arena_bytes);
        let mut sc = arena(r.scratch_bytes);
        let st = coray_bvh_build(
            s,
            &p,
            t.as_mut_ptr().cast(),
            r.arena_bytes,
            sc.as_mut_ptr().cast(),
            r.scratch_bytes,
            core::ptr::null_mut(),
        );
        assert_eq!(st, CorayStatus::Ok, "builder {builder}");
        let mut h = CorayBvh { opaque: [0; 32] };
        assert_eq!(
            coray_bvh_open(t.as_ptr().cast(), r.arena_bytes, s, &mut h),
            CorayStatus::Ok
        );
        let mut stack = arena(r.stack_bytes);
        let mut out = shape();
        let v = coray_bvh_validate(&h, stack.as_mut_ptr().cast(), r.stack_bytes, &mut out);
        (v, out)
    }
}

/// `validate`'s status and shape for a wide hierarchy over `s`.
fn wide(s: &CorayScene) -> (CorayStatus, CorayShape) {
    let p = coray_wide_params_default();
    let mut r = requirements();
    unsafe {
        assert_eq!(
            coray_wide_requirements(prims(s), &p, &mut r),
            CorayStatus::Ok
        );
        let mut t = arena(r.arena_bytes);
        let mut sc = arena(r.scratch_bytes);
        let st = coray_wide_build(
            s,
            &p,
            t.as_mut_ptr().cast(),
            r.arena_bytes,
            sc.as_mut_ptr().cast(),
            r.scratch_bytes,
            core::ptr::null_mut(),
        );
        assert_eq!(st, CorayStatus::Ok);
        let mut h = CorayWide { opaque: [0; 32] };
        assert_eq!(
            coray_wide_open(t.as_ptr().cast(), r.arena_bytes, s, &mut h),
            CorayStatus::Ok
        );
        let mut out = shape();
        (coray_wide_validate(&h, &mut out), out)
    }
}

#[test]
fn every_build_validates_over_degenerate_primitives() {
    let mut refused = Vec::new();
    for kind in 0..10 {
        let a = arrays(kind);
        let s = scene(&a);
        // The primitives a structure holds: the core's verdict on each
        // (the huge triangle of kind 2 has a finite box and stays).
        let good = valid_prims(&a);
        let mut results = vec![
            ("kd auto", kd(&s, CORAY_KD_PRESET_AUTO)),
            ("kd paper", kd(&s, CORAY_KD_PRESET_PAPER)),
            ("wide", wide(&s)),
        ];
        for (name, b) in [
            ("tdbs", CORAY_BVH_BUILDER_TDBS),
            ("tdbs-sah", CORAY_BVH_BUILDER_TDBS_SAH),
            ("nn", CORAY_BVH_BUILDER_NN),
            ("nn-chain", CORAY_BVH_BUILDER_NN_CHAIN),
            ("rtree", CORAY_BVH_BUILDER_RTREE),
            ("rstar", CORAY_BVH_BUILDER_RSTAR),
        ] {
            results.push((name, bvh(&s, b)));
        }
        for (name, (status, sh)) in results {
            if status != CorayStatus::Ok {
                refused.push(format!("{name} over degenerate kind {kind}: {status:?}"));
            } else if !name.starts_with("kd") {
                // The hierarchies hold each good primitive once.
                assert_eq!(sh.ref_count, good, "{name} kind {kind}");
            }
        }
    }
    assert!(
        refused.is_empty(),
        "{} refusals:\n{}",
        refused.len(),
        refused.join("\n")
    );
}
