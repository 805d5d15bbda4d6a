//! The Embree cross-check from Rust: the same scene in coray (both kd presets,
//! both traversals; the wide hierarchy) and in Embree through coray-embree; camera, random and
//! surface rays with unit directions. Same hit or miss, same primitive,
//! |dt| <= 1e-4 max(1, t), except documented ties (same distance; grazing an
//! edge, silhouette or rim), which are counted and printed.
use coray::kd::{KdParams, Traversal, KD_STACK_LEN};
use coray::owned::{stack, OwnedKd, OwnedWide};
use coray::rng::SplitMix64;
use coray::wide::WideStackItem;
use coray::{Camera, Cone, Hit, Ray, Scene, Sphere, TraceStats, Vec3};
use coray_embree::{classify, grazing, Agreement, EmbreeScene};

struct Rng(SplitMix64);
impl Rng {
    fn f(&mut self) -> f32 {
        self.0.next_f32()
    }
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.f()
    }
    fn vec(&mut self, s: f32) -> Vec3 {
        Vec3::new(self.range(-s, s), self.range(-s, s), self.range(-s, s))
    }
    fn unit(&mut self) -> Vec3 {
        loop {
            let v = self.vec(1.0);
            if (1e-4..=1.0).contains(&v.length_squared()) {
                return v.normalize();
            }
        }
    }
}

#[test]
fn coray_matches_embree_on_a_million_rays() {
    let mut rng = Rng(SplitMix64(21));
    let mut vertices = Vec::new();
    let mut triangles = Vec::new();
    for q in 0..6000u32 {
        let c = rng.vec(1.0);
        let (a, b) = (rng.unit() * 0.05, rng.unit() * 0.05);
        vertices.extend([(c - a - b), (c + a - b), (c + a + b), (c - a + b)].map(|v| v.to_array()));
        triangles.extend([[4 * q, 4 * q + 1, 4 * q + 2], [4 * q, 4 * q + 2, 4 * q + 3]]);
    }
    let spheres: Vec<Sphere> = (0..2000)
        .map(|_| Sphere {
            center: rng.vec(1.0).into(),
            radius: rng.range(0.005, 0.04),
        })
        .collect();
    let cones: Vec<Cone> = (0..2000)
        .map(|i| {
            let b = rng.vec(1.0);
            let r0 = rng.range(0.002, 0.03);
            Cone {
                base: b.into(),
                base_radius: r0,
                apex: (b + rng.unit() * rng.range(0.02, 0.1)).into(),
                apex_radius: if i % 3 == 0 { r0 } else { rng.range(0.0, 0.03) },
            }
        })
        .collect();
    let scene = Scene {
        vertices: &vertices,
        triangles: &triangles,
        spheres: &spheres,
        cones: &cones,
    };
    let embree = EmbreeScene::new(&scene, None);

    let cam = Camera {
        from: Vec3::new(0.3, 0.9, 2.8),
        at: Vec3::ZERO,
        up: Vec3::Y,
        angle_deg: 60.0,
        width: 640,
        height: 640,
    };
    let mut rays: Vec<Ray> = Vec::new();
    for y in 0..cam.height {
        for x in 0..cam.width {
            rays.push(cam.ray(x, y));
        }
    }
    for i in 0..400_000 {
        if i % 2 == 0 {
            let o = rng.unit() * 3.0;
            rays.push(Ray::new(o, rng.vec(1.0) - o, 0.0, f32::INFINITY));
        } else {
            rays.push(Ray::new(rng.vec(1.0), rng.unit(), 0.0, rng.range(0.1, 3.0)));
        }
    }
    let n_primary = rays.len();
    for i in 0..(cam.width * cam.height) as usize {
        let h = embree.intersect(&rays[i]);
        if h.is_hit() {
            let p = rays[i].origin + rays[i].dir * h.t;
            rays.push(Ray::new(p, rng.unit(), 1e-3, f32::INFINITY));
        }
    }
    for r in rays.iter_mut() {
        let l = r.dir.length();
        *r = Ray::new(r.origin, r.dir / l, r.t_min * l, r.t_max * l);
    }
    println!(
        "{} rays ({} camera and random, {} from surfaces)",
        rays.len(),
        n_primary,
        rays.len() - n_primary
    );
    assert!(rays.len() >= 1_000_000);
    let reference: Vec<Hit> = rays.iter().map(|r| embree.intersect(r)).collect();
    let reference_any: Vec<bool> = rays.iter().map(|r| embree.occluded(r)).collect();

    for (name, params) in [
        ("auto (with ropes)", KdParams::auto_with_ropes()),
        ("paper", KdParams::paper()),
    ] {
        let owned = OwnedKd::new(&scene, &params).unwrap();
        let tree = owned.tree(scene).unwrap();
        tree.validate().unwrap();
        for method in [Traversal::Hierarchical, Traversal::Ropes] {
            // A stack for each closure.
            let (mut s1, mut s2) = (stack(KD_STACK_LEN), stack(KD_STACK_LEN));
            cross_check(
                &format!("{name}/{method:?}"),
                &rays,
                &reference,
                &reference_any,
                |r, st| tree.intersect(r, method, &mut s1, st),
                |r, st| tree.occluded(r, method, &mut s2, st),
            );
        }
    }

    // The wide hierarchy: the same primitive tests, so the same rules.
    for leaf in [1, 4] {
        let owned = OwnedWide::new(&scene, leaf).unwrap();
        let w = owned.view(scene).unwrap();
        w.validate().unwrap();
        let mut s1 = stack::<WideStackItem>(w.stack_len());
        let mut s2 = s1.clone();
        cross_check(
            &format!("wide leaf {leaf}"),
            &rays,
            &reference,
            &reference_any,
            |r, st| w.intersect(r, &mut s1, st),
            |r, st| w.occluded(r, &mut s2, st),
        );
    }
}

/// One structure's answers against Embree's on every ray: closest hits
/// equal but for documented ties, any-hit answers equal but for grazing
/// rays, no faults; prints the tally.
fn cross_check(
    what: &str,
    rays: &[Ray],
    reference: &[Hit],
    reference_any: &[bool],
    mut intersect: impl FnMut(&Ray, &mut TraceStats) -> Hit,
    mut occluded: impl FnMut(&Ray, &mut TraceStats) -> bool,
) {
    let (mut hits, mut same_t, mut graze, mut bad, mut bad_any) = (0, 0, 0, 0, 0);
    let mut st = TraceStats::default();
    for (i, r) in rays.iter().enumerate() {
        let a = intersect(r, &mut st);
        let b = &reference[i];
        hits += a.is_hit() as usize;
        let any = occluded(r, &mut st);
        assert_eq!(any, a.is_hit(), "occluded and intersect disagree in coray");
        if any != reference_any[i] && !(grazing(r, &a) || grazing(r, b)) {
            bad_any += 1;
        }
        match classify(r, &a, b) {
            Agreement::Same => {}
            Agreement::TieSameDistance => same_t += 1,
            Agreement::TieGrazing => graze += 1,
            Agreement::Mismatch => {
                bad += 1;
                if bad <= 10 {
                    println!("{what} disagreement on ray {i} {r:?}: coray {a:?}, embree {b:?}");
                }
            }
        }
    }
    println!(
        "{what}: {} rays, {hits} hits, {same_t} same-distance ties, {graze} grazing ties, \
         {bad} disagreements, {bad_any} any-hit disagreements",
        rays.len()
    );
    assert_eq!(st.faults, 0);
    assert!(hits > rays.len() / 4);
    assert_eq!(bad, 0);
    assert_eq!(bad_any, 0);
}

/// Documents why the cross-check uses unit directions: Embree 3.13's linear
/// cone curves misplace hits when the direction is not of unit length,
/// while coray's t scales exactly with the direction.
#[test]
fn embree_cones_need_unit_directions_coray_does_not() {
    let cones = [Cone {
        base: [0.0, -0.5, 0.0],
        base_radius: 0.3,
        apex: [0.0, 0.5, 0.0],
        apex_radius: 0.1,
    }];
    let scene = Scene {
        cones: &cones,
        ..Scene::default()
    };
    let embree = EmbreeScene::new(&scene, Some(1));
    let unit = Ray::new(Vec3::new(-3.0, 0.0, 0.0), Vec3::X, 0.0, f32::INFINITY);
    let long = Ray::new(unit.origin, unit.dir * 2.0, 0.0, f32::INFINITY);
    let (eu, el) = (embree.intersect(&unit), embree.intersect(&long));
    let exact = 3.0 - 0.2; // radius 0.2 at the middle of the axis
    assert!(
        (eu.t - exact).abs() < 1e-5,
        "Embree, unit direction: {}",
        eu.t
    );
    println!(
        "Embree cone hit: unit direction t = {}, direction x2 t = {} (exact {})",
        eu.t,
        el.t,
        exact / 2.0
    );
    let c = coray::oracle::intersect(&scene, &long);
    assert!((c.t - exact / 2.0).abs() < 1e-6, "coray: {}", c.t);
}
