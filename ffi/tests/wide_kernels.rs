//! The wide hierarchy's AVX2 kernels, reached through coray-ffi's dispatch
//! (`coray_ffi::simd`), against its portable walk: the one-ray walk and
//! the packets of eight give every ray the portable walk's hit bit for bit
//! (and so the kd-tree's, which `tests/wide_oracle.rs` holds the portable
//! walk to), on scenes of every kind, on coherent tiles and on the rays
//! that make packets fall back (signs that differ, zero components, axes
//! that change within a packet, invalid rays, arrays not a multiple of
//! eight); and on corrupted hierarchies they never panic or hang. Where
//! the CPU has no AVX2 the dispatch runs the portable walk and the tests
//! hold trivially.

#[path = "../../tests/common/mod.rs"]
mod common;

use common::*;
use coray::owned::{stack, OwnedWide};
use coray::wide::{WideBvh, WideStackItem};
use coray::{Hit, Ray, Scene, TraceStats, Vec3};
use coray_ffi::simd;

/// The same answer to the bit: distance, weights, normal, primitive.
fn same(a: &Hit, b: &Hit) -> bool {
    a.is_hit() == b.is_hit()
        && (!a.is_hit()
            || (a.t.to_bits() == b.t.to_bits()
                && a.u.to_bits() == b.u.to_bits()
                && a.v.to_bits() == b.v.to_bits()
                && a.ng == b.ng
                && (a.geom_id, a.prim_id) == (b.geom_id, b.prim_id)))
}

/// A closed mesh: a sphere of `n` x `2n` quads (as triangles) of radius
/// `r` about `c`, the kind of surface camera tiles and shadow rays meet.
fn sphere_mesh(o: &mut OwnedScene, c: Vec3, r: f32, n: usize) {
    let p = |i: usize, j: usize| {
        let th = core::f32::consts::PI * i as f32 / n as f32;
        let ph = core::f32::consts::PI * j as f32 / n as f32;
        c + Vec3::new(th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin()) * r
    };
    for i in 0..n {
        for j in 0..2 * n {
            let (a, b, cc, d) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
            o.add_triangle(a, b, cc);
            o.add_triangle(a, cc, d);
        }
    }
}

/// Camera rays through a `w` x `h` image from `from` towards the origin,
/// in 4 x 2 tiles (the order packets take them in).
fn tiles(from: Vec3, w: usize, h: usize, fov: f32) -> Vec<Ray> {
    let f = (-from).normalize();
    let r = f.cross(Vec3::Y).normalize();
    let u = r.cross(f);
    let mut rays = Vec::new();
    for by in (0..h).step_by(2) {
        for bx in (0..w).step_by(4) {
            for y in by..by + 2 {
                for x in bx..bx + 4 {
                    let sx = (x as f32 + 0.5) / w as f32 * 2.0 - 1.0;
                    let sy = (y as f32 + 0.5) / h as f32 * 2.0 - 1.0;
                    let d = f + r * (sx * fov) + u * (sy * fov);
                    rays.push(Ray::new(from, d.normalize(), 0.0, f32::INFINITY));
                }
            }
        }
    }
    rays
}

/// Shadow rays from each hit of `rays` towards `light` (segments ending at
/// it, starting a little off the surface).
fn shadows(rays: &[Ray], hits: &[Hit], light: Vec3) -> Vec<Ray> {
    rays.iter()
        .zip(hits)
        .filter(|(_, h)| h.is_hit())
        .map(|(r, h)| {
            let p = r.origin + r.dir * h.t;
            let d = light - p;
            Ray::new(p, d, 1e-4, 1.0)
        })
        .collect()
}

/// Every kernel of the dispatch against the portable walk on `rays`:
/// one ray at a time, and the arrays in packets (closest and any hit).
/// Returns how many rays hit.
fn agree(w: &WideBvh, rays: &[Ray], what: &str) -> usize {
    let mut stk = stack::<WideStackItem>(w.stack_len());
    let mut st = TraceStats::default();
    let want: Vec<Hit> = rays
        .iter()
        .map(|r| w.intersect(r, &mut stk, &mut st))
        .collect();
    let want_any: Vec<bool> = rays
        .iter()
        .map(|r| w.occluded(r, &mut stk, &mut st))
        .collect();
    assert_eq!(st.faults, 0, "{what}");
    for (i, r) in rays.iter().enumerate() {
        let h = simd::wide_intersect(w, r, &mut stk, &mut st);
        assert!(
            same(&h, &want[i]),
            "{what}: ray {i} {r:?}: {h:?}, portable {:?}",
            want[i]
        );
        assert_eq!(
            simd::wide_occluded(w, r, &mut stk, &mut st),
            want_any[i],
            "{what}: ray {i}"
        );
    }
    let mut hits = vec![Hit::MISS; rays.len()];
    let mut occ = vec![false; rays.len()];
    let mut ps = TraceStats::default();
    simd::wide_intersect_packets(w, rays, &mut hits, &mut stk, &mut ps);
    simd::wide_occluded_packets(w, rays, &mut occ, &mut stk, &mut ps);
    assert_eq!(ps.faults, 0, "{what}");
    assert_eq!(
        ps.rays,
        2 * rays.len() as u64,
        "{what}: every ray counted once"
    );
    for i in 0..rays.len() {
        assert!(
            same(&hits[i], &want[i]),
            "{what}: packet ray {i} {:?}: {:?}, portable {:?}",
            rays[i],
            hits[i],
            want[i]
        );
        assert_eq!(occ[i], want_any[i], "{what}: packet ray {i} {:?}", rays[i]);
    }
    want.iter().filter(|h| h.is_hit()).count()
}

#[test]
fn one_ray_kernel_answers_as_the_portable_walk_on_every_kind() {
    for (tris, spheres, cones, seed) in [(900, 0, 0, 1), (500, 150, 150, 2), (0, 200, 200, 3)] {
        let mut rng = Rng(seed);
        let o = random_scene(&mut rng, tris, spheres, cones, 6.0);
        let scene = o.scene();
        let mut rays = random_rays(&mut rng, 3000, 6.0);
        rays.extend(faces_and_tiny_directions().1);
        for leaf in [1, 4, 9] {
            let owned = OwnedWide::new(&scene, leaf).unwrap();
            let w = owned.view(scene).unwrap();
            let hits = agree(&w, &rays, &format!("scene {seed} leaf {leaf}"));
            assert!(hits > 300, "scene {seed} leaf {leaf}: {hits} hits");
        }
    }
}

#[test]
fn packets_answer_as_the_portable_walk_on_tiles_and_shadows() {
    let mut o = OwnedScene::default();
    sphere_mesh(&mut o, Vec3::ZERO, 1.0, 24);
    sphere_mesh(&mut o, Vec3::new(1.2, 0.8, -0.5), 0.6, 12);
    o.add_quad(1, -1.0, [-4.0, -4.0], [4.0, 4.0]);
    let scene = o.scene();
    for leaf in [1, 4, 9] {
        let owned = OwnedWide::new(&scene, leaf).unwrap();
        let w = owned.view(scene).unwrap();
        // Along a diagonal, so that tiles straddle the change of dominant
        // axis (their watertight axes differ within a packet); and head on.
        for (k, from) in [Vec3::new(3.0, 3.0, 3.0), Vec3::new(0.3, 0.2, 5.0)]
            .into_iter()
            .enumerate()
        {
            let rays = tiles(from, 48, 40, 0.6);
            let what = format!("leaf {leaf} view {k}");
            let hit = agree(&w, &rays, &what);
            assert!(hit > rays.len() / 3, "{what}: {hit} hits");
            let mut stk = stack::<WideStackItem>(w.stack_len());
            let mut st = TraceStats::default();
            let hits: Vec<Hit> = rays
                .iter()
                .map(|r| w.intersect(r, &mut stk, &mut st))
                .collect();
            let sh = shadows(&rays, &hits, Vec3::new(4.0, 6.0, 2.0));
            agree(&w, &sh, &format!("{what} shadows"));
            // Arrays of every length up to two packets and a half, from
            // every start: partial packets.
            for start in [0, 3, 8] {
                for len in 1..=20 {
                    agree(
                        &w,
                        &rays[start..start + len],
                        &format!("{what} [{start}; {len}]"),
                    );
                }
            }
        }
    }
}

/// Packets over a scene of triangles, spheres and cones: the spheres and
/// cones of a leaf tested lane by lane answer as the portable walk's.
#[test]
fn packets_with_spheres_and_cones_answer_as_the_portable_walk() {
    let mut rng = Rng(31);
    let mut o = random_scene(&mut rng, 300, 300, 300, 1.5);
    sphere_mesh(&mut o, Vec3::new(0.0, -0.5, 0.0), 0.8, 12);
    let scene = o.scene();
    for leaf in [1, 8] {
        let owned = OwnedWide::new(&scene, leaf).unwrap();
        let w = owned.view(scene).unwrap();
        let rays = tiles(Vec3::new(0.4, 0.9, 4.0), 40, 32, 0.5);
        let what = format!("mixed leaf {leaf}");
        let hit = agree(&w, &rays, &what);
        assert!(hit > rays.len() / 4, "{what}: {hit} hits");
        let mut stk = stack::<WideStackItem>(w.stack_len());
        let mut st = TraceStats::default();
        let hits: Vec<Hit> = rays
            .iter()
            .map(|r| w.intersect(r, &mut stk, &mut st))
            .collect();
        assert!(hits.iter().any(|h| h.geom_id == 1) && hits.iter().any(|h| h.geom_id == 2));
        agree(
            &w,
            &shadows(&rays, &hits, Vec3::new(3.0, 5.0, 2.0)),
            &format!("{what} shadows"),
        );
    }
}

/// Packets that cannot be traced together, or only in part: mixed
/// direction signs, zero and subnormal components, invalid rays, segments
/// ending before the surface, starting past it.
#[test]
fn packets_that_fall_back_answer_as_the_portable_walk() {
    let mut o = OwnedScene::default();
    sphere_mesh(&mut o, Vec3::ZERO, 1.0, 16);
    let scene = o.scene();
    let owned = OwnedWide::new(&scene, 4).unwrap();
    let w = owned.view(scene).unwrap();
    let base = tiles(Vec3::new(0.2, 0.1, 4.0), 16, 8, 0.4);
    let mut rng = Rng(11);
    let mut rays = Vec::new();
    for (p, chunk) in base.chunks(8).enumerate() {
        for (i, r) in chunk.iter().enumerate() {
            let mut r = *r;
            match (p + i) % 9 {
                0 if i == 3 => r.dir = -r.dir,
                1 if i == 5 => r.dir.x = 0.0,
                2 if i == 1 => r.dir.y = 1e-40,
                3 if i == 6 => r.origin.x = f32::NAN,
                4 if i == 2 => r.t_max = -1.0,
                5 => r.t_max = 3.0 + rng.f(),
                6 => r.t_min = 4.0 + rng.f(),
                7 if i == 0 => r.dir = Vec3::ZERO,
                _ => {}
            }
            rays.push(r);
        }
    }
    let hits = agree(&w, &rays, "fallbacks");
    assert!(hits > 20, "{hits} hits");
    // Rays from inside the sphere, in every direction (no two alike).
    let inside: Vec<Ray> = (0..200)
        .map(|_| Ray::new(rng.vec(-0.3, 0.3), rng.unit(), 0.0, f32::INFINITY))
        .collect();
    assert_eq!(agree(&w, &inside, "inside"), inside.len());
}

/// Hierarchies with one word changed, traced by every kernel: no panic, no
/// hang; a fault where the walk meets the damage.
#[test]
fn kernels_survive_corrupted_hierarchies() {
    let mut rng = Rng(21);
    let mut o = random_scene(&mut rng, 400, 0, 0, 4.0);
    sphere_mesh(&mut o, Vec3::ZERO, 1.0, 10);
    let scene: Scene = o.scene();
    let rays = tiles(Vec3::new(0.5, 0.5, 6.0), 16, 16, 0.7);
    for round in 0..400 {
        let mut bad = OwnedWide::new(&scene, 4).unwrap();
        {
            let (nodes, blocks, info) = bad.parts_mut();
            let v = rng.next_u64();
            let slot = (v >> 8) as usize % 8;
            match round % 6 {
                0 => nodes[v as usize % nodes.len()].child[slot] = (v >> 20) as u32,
                1 => nodes[v as usize % nodes.len()].child[slot] = (v >> 20) as u32 % 64,
                2 => {
                    nodes[v as usize % nodes.len()].planes[slot % 6][slot] =
                        f32::from_bits((v >> 24) as u32)
                }
                3 => blocks[v as usize % blocks.len()].prims[slot % 4] = (v >> 20) as u32,
                4 => {
                    blocks[v as usize % blocks.len()].corners[slot % 3][(v >> 30) as usize % 3]
                        [slot % 4] = f32::from_bits((v >> 32) as u32)
                }
                _ => info.depth = (v >> 20) as u32 % 4,
            }
        }
        let Ok(w) = bad.view(scene) else {
            continue;
        };
        let mut stk = stack::<WideStackItem>(w.stack_len().min(1 << 12));
        let mut st = TraceStats::default();
        let mut hits = vec![Hit::MISS; rays.len()];
        let mut occ = vec![false; rays.len()];
        simd::wide_intersect_packets(&w, &rays, &mut hits, &mut stk, &mut st);
        simd::wide_occluded_packets(&w, &rays, &mut occ, &mut stk, &mut st);
        for r in &rays {
            simd::wide_intersect(&w, r, &mut stk, &mut st);
            simd::wide_occluded(&w, r, &mut stk, &mut st);
        }
        // What validate accepts traces as a clean build does.
        if w.validate().is_ok() {
            assert_eq!(st.faults, 0, "round {round}: validated, then faulted");
        }
    }
}
