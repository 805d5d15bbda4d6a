//! Packets of 8 rays (Traversal::Packets) give, ray by ray and bit for
//! bit, the hits and any-hit answers of hierarchical traversal: on camera
//! tiles (packets), shadow rays from a tile towards a light (packets),
//! mixed and random rays (groups that do not move alike fall back to
//! single rays), over random and SPD-like scenes with every primitive
//! kind.
mod common;

use common::*;
use coray::kd::{KdParams, KdTree, Traversal, PACKET_LANES};
use coray::{Accel, Hit, Ray, TraceStats, Vec3};

/// Camera rays over `w` x `h` pixels in 4 x 2 tiles (packet order).
fn camera_tiles(eye: Vec3, at: Vec3, w: usize, h: usize, fov: f32) -> Vec<Ray> {
    let f = (at - eye).normalize();
    let r = f.cross(Vec3::Y).normalize();
    let u = r.cross(f);
    let mut rays = Vec::new();
    for by in (0..h).step_by(2) {
        for bx in (0..w).step_by(4) {
            for y in by..by + 2 {
                for x in bx..bx + 4 {
                    let sx = (2.0 * (x as f32 + 0.5) / w as f32 - 1.0) * fov;
                    let sy = (1.0 - 2.0 * (y as f32 + 0.5) / h as f32) * fov;
                    rays.push(Ray::new(eye, f + r * sx + u * sy, 0.0, f32::INFINITY));
                }
            }
        }
    }
    rays
}

/// Asserts packets answer exactly as hierarchical traversal; returns
/// (hits, packet-eligible groups) so callers can assert the test bites.
fn same_as_hierarchical(t: &KdTree, rays: &[Ray], what: &str) -> (usize, usize) {
    let mut stack = kst();
    let (mut sa, mut sb) = (TraceStats::default(), TraceStats::default());
    let mut want = vec![Hit::MISS; rays.len()];
    let mut got = vec![Hit::MISS; rays.len()];
    t.intersect_many(
        rays,
        &mut want,
        Traversal::Hierarchical,
        &mut stack,
        &mut sa,
    )
    .unwrap();
    t.intersect_many(rays, &mut got, Traversal::Packets, &mut stack, &mut sb)
        .unwrap();
    for i in 0..rays.len() {
        assert_eq!(got[i], want[i], "{what}: ray {i} {:?}", rays[i]);
    }
    let mut want_o = vec![false; rays.len()];
    let mut got_o = vec![false; rays.len()];
    t.occluded_many(
        rays,
        &mut want_o,
        Traversal::Hierarchical,
        &mut stack,
        &mut sa,
    )
    .unwrap();
    t.occluded_many(rays, &mut got_o, Traversal::Packets, &mut stack, &mut sb)
        .unwrap();
    assert_eq!(got_o, want_o, "{what}: occluded");
    assert_eq!(sa.rays, sb.rays);
    // Every packet lane tests at least what its ray alone would test.
    assert!(
        sb.prim_tests >= sa.prim_tests / 2,
        "{what}: {sb:?} against {sa:?}"
    );
    let groups = rays
        .chunks(PACKET_LANES)
        .filter(|g| g.windows(2).all(|w| w[0].dir.signum() == w[1].dir.signum()))
        .count();
    (want.iter().filter(|h| h.is_hit()).count(), groups)
}

/// Shadow rays from the hits of `primary` towards `light`, in tile order.
fn shadows(t: &KdTree, primary: &[Ray], light: Vec3) -> Vec<Ray> {
    let mut stack = kst();
    let mut st = TraceStats::default();
    primary
        .iter()
        .map(|r| {
            let h = t.intersect(r, Traversal::Hierarchical, &mut stack, &mut st);
            let p = if h.is_hit() {
                r.origin + r.dir * h.t
            } else {
                r.origin + r.dir
            };
            let d = light - p;
            Ray::new(p, d, 1e-4, 1.0)
        })
        .collect()
}

#[test]
fn packets_answer_as_hierarchical_traversal() {
    let mut rng = Rng(8);
    let scenes = [
        ("mixed", random_scene(&mut rng, 3000, 400, 400, 5.0)),
        ("triangles", random_scene(&mut rng, 5000, 0, 0, 5.0)),
        ("spheres", random_scene(&mut rng, 0, 2000, 0, 5.0)),
        ("cones", random_scene(&mut rng, 0, 0, 3000, 5.0)),
    ];
    for (name, o) in &scenes {
        let sc = o.scene();
        for params in [KdParams::auto(), KdParams::paper()] {
            let kd = coray::owned::OwnedKd::new(&sc, &params).unwrap();
            let t = kd.tree(sc).unwrap();
            for (eye, w, h) in [
                (Vec3::new(1.0, 2.0, 14.0), 64, 48),
                (Vec3::new(-3.0, 0.5, 2.0), 37, 23),
            ] {
                let cam = camera_tiles(eye, Vec3::ZERO, w, h, 0.6);
                let (hits, groups) = same_as_hierarchical(&t, &cam, &format!("{name} camera"));
                assert!(
                    hits > cam.len() / 10 && groups > cam.len() / 16,
                    "{name}: {hits} {groups}"
                );
                let sh = shadows(&t, &cam, Vec3::new(2.0, 9.0, 3.0));
                same_as_hierarchical(&t, &sh, &format!("{name} shadows"));
            }
            let rays = random_rays(&mut rng, 2000, 5.0);
            same_as_hierarchical(&t, &rays, &format!("{name} random"));
        }
    }
}

/// Rays with a zero direction component, invalid rays (a packet's first
/// lane, an infinite origin, a NaN direction, NaN and reversed intervals,
/// a whole packet of them) and a short tail group: packets take what they
/// can, the rest goes ray by ray, answers unchanged.
#[test]
fn packets_with_odd_lanes() {
    let mut rng = Rng(9);
    let o = random_scene(&mut rng, 2000, 200, 200, 3.0);
    let sc = o.scene();
    let kd = coray::owned::OwnedKd::new(&sc, &KdParams::auto()).unwrap();
    let t = kd.tree(sc).unwrap();
    let mut rays = camera_tiles(Vec3::new(0.0, 0.0, 9.0), Vec3::ZERO, 16, 8, 0.5);
    rays[3].dir.x = 0.0;
    rays[12] = Ray::new(Vec3::ZERO, Vec3::ZERO, 0.0, 1.0);
    rays[21].t_min = f32::NAN;
    rays[0].t_max = -1.0;
    rays[5].origin.y = f32::INFINITY;
    rays[9].dir.z = f32::NAN;
    for r in &mut rays[24..32] {
        (r.t_min, r.t_max) = (2.0, 1.0);
    }
    rays.truncate(rays.len() - 3);
    same_as_hierarchical(&t, &rays, "odd lanes");
}

/// Packets whose rays agree on every direction sign but lead on different
/// axes (x for some lanes, y for others): the watertight test orders its
/// axes by the leading one, so those lanes test triangles alone inside
/// the packet; every answer as the single ray's.
#[test]
fn packets_whose_lanes_lead_on_different_axes() {
    let mut rng = Rng(10);
    let o = random_scene(&mut rng, 4000, 100, 100, 3.0);
    let sc = o.scene();
    let kd = coray::owned::OwnedKd::new(&sc, &KdParams::auto()).unwrap();
    let t = kd.tree(sc).unwrap();
    let mut rays = Vec::new();
    for _ in 0..400 {
        let aim = rng.vec(-2.0, 2.0);
        let sign = |rng: &mut Rng| if rng.f() < 0.5 { 1.0 } else { -1.0 };
        let (sx, sz) = (sign(&mut rng), sign(&mut rng));
        for i in 0..PACKET_LANES {
            // |y| from 0.95 to 1.09 against |x| = 1: lanes 0-2 lead on
            // x, lanes 3-7 on y.
            let d = Vec3::new(sx, 0.95 + 0.02 * i as f32, sz * (0.2 + 0.01 * i as f32));
            rays.push(Ray::new(aim - d * 8.0, d, 0.0, f32::INFINITY));
        }
    }
    let (hits, groups) = same_as_hierarchical(&t, &rays, "mixed leading axes");
    assert!(groups == 400 && hits > rays.len() / 4, "{hits} {groups}");
    let sh = shadows(&t, &rays, Vec3::new(2.0, 9.0, 3.0));
    same_as_hierarchical(&t, &sh, "mixed leading axes, shadows");
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(24))]

    /// Random scenes of every primitive kind, random cameras (shrunk to
    /// the smallest failing case): packets answer as hierarchical
    /// traversal, and that as the brute-force oracle.
    #[test]
    fn packets_match_the_oracle(
        seed in 0u64..1 << 40,
        tris in 0usize..400,
        spheres in 0usize..80,
        cones in 0usize..80,
        eye in proptest::array::uniform3(-12.0f32..12.0),
    ) {
        let mut rng = Rng(seed);
        let o = random_scene(&mut rng, tris, spheres, cones, 3.0);
        let sc = o.scene();
        let kd = coray::owned::OwnedKd::new(&sc, &KdParams::auto()).unwrap();
        let t = kd.tree(sc).unwrap();
        let eye = Vec3::from(eye);
        proptest::prop_assume!(eye.length() > 4.0);
        let rays = camera_tiles(eye, Vec3::ZERO, 16, 8, 0.5);
        same_as_hierarchical(&t, &rays, "random camera");
        let mut stack = kst();
        let mut st = TraceStats::default();
        for r in &rays {
            let h = t.intersect(r, Traversal::Hierarchical, &mut stack, &mut st);
            let want = coray::oracle::intersect(&sc, r);
            proptest::prop_assert!(h.is_hit() == want.is_hit() && (!h.is_hit() || h.t == want.t), "{r:?}: {h:?} vs {want:?}");
        }
    }
}
