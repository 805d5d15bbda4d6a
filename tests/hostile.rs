//! Hostile structures: every case of issue 16 that the core sees, and
//! seeded sweeps of corrupted values over every structure. Each runs under
//! a watchdog, so a hang fails the test instead of stalling it. The rules:
//! `validate` never panics and answers in linear time; traversal of any
//! structure, validated or not, never panics or hangs; a structure that
//! `validate` accepts gives the hits of the clean one, and no faults.
mod common;

use common::*;
use coray::bvh::{Builder, Bvh, BvhInfo, BvhNode, BvhStackItem, RTreeParams};
use coray::kd::{KdNode, KdParams, KdTree, Traversal, NO_NODE};
use coray::owned::{
    stack, BvhBuild, OwnedBvh, OwnedCast, OwnedKd, OwnedPatch, OwnedProj, OwnedWide,
};
use coray::proj::{Criteria, ProjBuilder, ProjPlane, ProjScheme};
use coray::wide::WideStackItem;
use coray::{Accel, Camera, Hit, Ray, TraceStats, Vec3};

fn scene(seed: u64) -> OwnedScene {
    random_scene(&mut Rng(seed), 60, 20, 10, 10.0)
}

fn rays() -> Vec<Ray> {
    random_rays(&mut Rng(7), 64, 10.0)
}

fn camera() -> Camera {
    Camera {
        from: Vec3::new(0.0, 3.0, -30.0),
        at: Vec3::ZERO,
        up: Vec3::Y,
        angle_deg: 45.0,
        width: 12,
        height: 9,
    }
}

fn same(a: &Hit, b: &Hit) -> bool {
    (a.geom_id, a.prim_id, a.t.to_bits()) == (b.geom_id, b.prim_id, b.t.to_bits())
}

/// Everything a kd-tree serves, on `t`: every traversal, every image
/// scheme, a patch query. Returns the hits of the rays (both traversals)
/// and whether any call counted a fault.
fn exercise_kd(t: &KdTree, rays: &[Ray]) -> (Vec<Hit>, bool) {
    let mut st = TraceStats::default();
    let mut stk = kst();
    let mut hits = Vec::new();
    for r in rays {
        for m in [Traversal::Hierarchical, Traversal::Ropes] {
            hits.push(t.intersect(r, m, &mut stk, &mut st));
            t.occluded(r, m, &mut stk, &mut st);
        }
    }
    let cam = camera();
    use coray::lcts::Scheme::*;
    for scheme in [
        Hierarchical,
        Ropes,
        Slcts1d { n: 5 },
        Slcts2d { n: 5, m: 5 },
        Hlcts1d,
        Hlcts2d,
        Packets,
    ] {
        let req = coray::lcts::image_requirements(12, 9, scheme, 64);
        let mut o = OwnedCast::new(&req);
        let mut out = vec![Hit::MISS; 108];
        if let Ok(c) = coray::lcts::cast_image(t, &cam, scheme, o.scratch(), &mut out) {
            st.add(&c.trace);
        }
    }
    let a = [
        Vec3::new(-5.0, -5.0, -9.0),
        Vec3::new(5.0, -5.0, -9.0),
        Vec3::new(0.0, 5.0, -9.0),
    ];
    let b = [
        Vec3::new(-5.0, -5.0, 9.0),
        Vec3::new(5.0, -5.0, 9.0),
        Vec3::new(0.0, 5.0, 9.0),
    ];
    let mut o = OwnedPatch::new(64);
    if let Ok(p) = coray::lcts::patch::patch_visibility(t, &a, &b, 3, 1e-3, o.scratch()) {
        st.add(&p.trace);
        st.add(&p.boundary);
    }
    (hits, st.faults > 0)
}

/// Applies `corrupt` to a copy of a clean tree over `s`, then checks the
/// rules above.
fn kd_case(
    s: &OwnedScene,
    params: &KdParams,
    rays: &[Ray],
    what: &str,
    corrupt: impl Fn(&mut OwnedKd) -> bool,
) -> bool {
    let sc = s.scene();
    let clean = OwnedKd::new(&sc, params).unwrap();
    let mut bad = OwnedKd::new(&sc, params).unwrap();
    if !corrupt(&mut bad) {
        return false;
    }
    let want = exercise_kd(&clean.tree(sc).unwrap(), rays).0;
    let Ok(t) = bad.tree(sc) else {
        return true; // refused in O(1)
    };
    let ok = t.validate().is_ok();
    let (got, faulted) = exercise_kd(&t, rays);
    if ok {
        assert!(!faulted, "{what}: validated, then faulted");
        let diff = got.iter().zip(&want).filter(|(a, b)| !same(a, b)).count();
        assert_eq!(diff, 0, "{what}: validated, then {diff} different hits");
    }
    ok
}

/// Every interior node made its own left child, one at a time: validate
/// rejects each quickly (it hung in `check_rope`), and traversal returns.
#[test]
fn kd_node_that_is_its_own_child() {
    watchdog(60, "kd self child", || {
        let s = scene(1);
        let rays = rays();
        let n = OwnedKd::new(&s.scene(), &KdParams::auto_with_ropes())
            .unwrap()
            .info()
            .node_count;
        for i in 0..n as usize {
            let ok = kd_case(&s, &KdParams::auto_with_ropes(), &rays, "self child", |b| {
                let nodes = b.parts_mut().0;
                let nd = nodes[i];
                if nd.is_leaf() {
                    return false;
                }
                nodes[i] = KdNode::interior(nd.axis(), nd.split(), i as u32);
                true
            });
            assert!(!ok, "node {i} made its own child passed validate");
        }
    });
}

/// A cast over a tree whose root is its own child stops at the first
/// fault, every scheme: it cast the whole image first (2.8 s at 1024 x
/// 1024 against 0.05 s for the clean tree; hours at the largest camera).
#[test]
fn casts_stop_at_the_first_fault() {
    let s = scene(1);
    let sc = s.scene();
    let mut bad = OwnedKd::new(&sc, &KdParams::auto_with_ropes()).unwrap();
    let root = bad.parts_mut().0[0];
    assert!(!root.is_leaf());
    bad.parts_mut().0[0] = KdNode::interior(root.axis(), root.split(), 0);
    let t = bad.tree(sc).unwrap();
    let mut cam = camera();
    (cam.width, cam.height) = (64, 48);
    use coray::lcts::Scheme::*;
    for scheme in [
        Hierarchical,
        Ropes,
        Slcts1d { n: 5 },
        Slcts2d { n: 5, m: 5 },
        Hlcts1d,
        Hlcts2d,
        Packets,
    ] {
        let req = coray::lcts::image_requirements(64, 48, scheme, 64);
        let mut o = OwnedCast::new(&req);
        let mut out = vec![Hit::MISS; 64 * 48];
        let st = coray::lcts::cast_image(&t, &cam, scheme, o.scratch(), &mut out).unwrap();
        assert!(st.trace.faults > 0, "{scheme:?}");
        assert!(
            st.trace.rays <= 8,
            "{scheme:?}: {} rays cast after the first fault",
            st.trace.rays
        );
    }
}

/// Ropes that point anywhere: validate never panics (it did on nodes the
/// preorder pass had not vetted yet); what it accepts traces alike.
#[test]
fn kd_ropes_pointing_anywhere() {
    watchdog(120, "kd ropes", || {
        let s = scene(2);
        let rays = rays();
        let sc = s.scene();
        let clean = OwnedKd::new(&sc, &KdParams::auto_with_ropes()).unwrap();
        let (n, leaves) = (clean.info().node_count, clean.info().leaf_count);
        for leaf in (0..leaves as usize).step_by(3) {
            for face in 0..6 {
                for bad in [0, n - 1, n, n + 1, NO_NODE - 1, leaf as u32] {
                    // A rope to a node higher up that still covers the face
                    // (the root, say) is slower but right: validate may
                    // accept it, and kd_case then checks the hits.
                    kd_case(&s, &KdParams::auto_with_ropes(), &rays, "rope", |b| {
                        let ropes = b.parts_mut().1;
                        if ropes[leaf].neighbor[face] == bad {
                            return false;
                        }
                        ropes[leaf].neighbor[face] = bad;
                        true
                    });
                }
            }
        }
    });
}

/// Leaves, references and children out of range: validate says so (or
/// `from_parts` does); every traversal, image scheme and patch query returns.
#[test]
fn kd_leaves_and_refs_out_of_range() {
    watchdog(60, "kd leaves and refs", || {
        let s = scene(3);
        let rays = rays();
        let prims = s.scene().prim_count() as u32;
        type Corrupt = Box<dyn Fn(&mut OwnedKd)>;
        let mut cases: Vec<Corrupt> = Vec::new();
        for bad in [prims, prims + 7, u32::MAX, u32::MAX >> 3] {
            cases.push(Box::new(move |b| b.parts_mut().3[0] = bad));
            // A leaf's count, its first reference, both; a rope index.
            let leaf = |b: &mut OwnedKd, k: usize| {
                let nodes = b.parts_mut().0;
                nodes
                    .iter()
                    .enumerate()
                    .filter(|n| n.1.is_leaf())
                    .nth(k)
                    .unwrap()
                    .0
            };
            cases.push(Box::new(move |b| {
                let i = leaf(b, 1);
                let n = &mut b.parts_mut().0[i];
                *n = KdNode::leaf(n.first_ref(), bad >> 2);
            }));
            cases.push(Box::new(move |b| {
                let i = leaf(b, 2);
                let n = &mut b.parts_mut().0[i];
                *n = KdNode::leaf(bad, n.ref_count());
            }));
            cases.push(Box::new(move |b| {
                let i = leaf(b, 0);
                b.parts_mut().0[i] = KdNode::leaf(bad, bad >> 2);
            }));
            cases.push(Box::new(move |b| {
                let i = leaf(b, 3);
                b.parts_mut().2[i] = bad;
            }));
            cases.push(Box::new(move |b| {
                b.parts_mut().0[0] = KdNode::interior(0, 0.0, bad >> 2);
            }));
        }
        // A reference changed to another primitive: only the digest sees it.
        cases.push(Box::new(|b| {
            let refs = b.parts_mut().3;
            refs[0] = if refs[0] == 0 { 1 } else { 0 };
        }));
        for (k, corrupt) in cases.iter().enumerate() {
            let ok = kd_case(&s, &KdParams::paper(), &rays, "leaf or ref", |b| {
                corrupt(b);
                true
            });
            assert!(!ok, "case {k} passed validate");
        }
    });
}

/// Seeded sweep: single words of every kd part set to hostile values.
#[test]
fn kd_random_words() {
    watchdog(240, "kd random words", || {
        let s = scene(4);
        let rays = rays()[..16].to_vec();
        let mut rng = Rng(11);
        let mut accepted = 0;
        for trial in 0..300 {
            let part = rng.below(4);
            let pick = rng.next_u64();
            let value = match rng.below(4) {
                0 => rng.next_u64() as u32,
                1 => rng.below(64) as u32,
                2 => u32::MAX - rng.below(4) as u32,
                _ => f32::NAN.to_bits(),
            };
            let acc = kd_case(
                &s,
                &KdParams::auto_with_ropes(),
                &rays,
                "random word",
                |b| {
                    let (nodes, ropes, rope_ids, refs) = b.parts_mut();
                    let (n, ri, rp, rf) = (nodes.len(), rope_ids.len(), ropes.len(), refs.len());
                    match part {
                        0 => {
                            let nd = &mut nodes[(pick % n as u64) as usize];
                            if pick & 1 << 40 == 0 {
                                nd.word = value
                            } else {
                                nd.data = value
                            }
                        }
                        1 => rope_ids[(pick % ri as u64) as usize] = value,
                        2 => {
                            let r = &mut ropes[(pick % rp as u64) as usize];
                            match pick >> 40 & 3 {
                                0 => r.neighbor[(pick >> 44) as usize % 6] = value,
                                1 => r.min[(pick >> 44) as usize % 3] = f32::from_bits(value),
                                _ => r.max[(pick >> 44) as usize % 3] = f32::from_bits(value),
                            }
                        }
                        _ => refs[(pick % rf as u64) as usize] = value,
                    }
                    true
                },
            );
            if acc {
                eprintln!("accepted: trial {trial} part {part} value {value:#x}");
            }
            accepted += acc as u32;
        }
        // A few values equal the clean ones; the rest must all be refused.
        assert!(accepted < 30, "{accepted} of 300 corruptions accepted");
    });
}

/// The tree's box moved, one face at a time, out or in (found by the C-ABI
/// fuzzer: a header byte took the box's top from 2.5 to 2e32, the tree
/// validated, and a ray grazing a triangle's plane was answered otherwise,
/// its rounded hit now inside the first leaf's span). The box is the
/// scene's: a tree whose box is any other must not validate, and one that
/// does gives the clean hits.
#[test]
fn kd_scene_box_moved() {
    watchdog(120, "kd scene box moved", || {
        let s = scene(5);
        let sc = s.scene();
        let rays = rays();
        for params in [
            KdParams::auto(),
            KdParams::auto_with_ropes(),
            KdParams::paper(),
        ] {
            let clean = OwnedKd::new(&sc, &params).unwrap();
            let t = clean.tree(sc).unwrap();
            let want = exercise_kd(&t, &rays).0;
            let (nodes, ropes, rope_ids, refs) = t.parts();
            let b = t.info().bounds();
            let mut accepted = 0;
            for face in 0..6 {
                let (axis, top) = (face / 2, face % 2 == 1);
                let extent = b.max[axis] - b.min[axis];
                // Far out, a little out, a little in (past no split: the
                // splits lie well inside a random scene's box).
                for step in [1e30, 0.01 * extent, -0.001 * extent] {
                    let mut info = *t.info();
                    if top {
                        info.bounds_max[axis] += step;
                    } else {
                        info.bounds_min[axis] -= step;
                    }
                    let Ok(bad) = KdTree::from_parts(sc, info, nodes, ropes, rope_ids, refs) else {
                        continue;
                    };
                    let ok = bad.validate().is_ok();
                    let (got, faulted) = exercise_kd(&bad, &rays);
                    if ok {
                        accepted += 1;
                        assert!(
                            !faulted,
                            "face {face} moved by {step}: validated, then faulted"
                        );
                        let diff = got.iter().zip(&want).filter(|(a, b)| !same(a, b)).count();
                        assert_eq!(
                            diff, 0,
                            "face {face} moved by {step}: validated, then {diff} different hits"
                        );
                    }
                }
            }
            assert_eq!(accepted, 0, "{accepted} moved boxes validated");
        }
    });
}

fn builders() -> Vec<BvhBuild> {
    vec![
        BvhBuild::Static(Builder::Tdbs, 1),
        BvhBuild::Static(Builder::TdbsSah, 2),
        BvhBuild::Static(Builder::Nn, 1),
        BvhBuild::Static(Builder::NnChain, 1),
        BvhBuild::RTree(RTreeParams::rtree()),
        BvhBuild::RTree(RTreeParams {
            forced_reinsert: true,
            ..RTreeParams::rstar()
        }),
    ]
}

/// Everything a hierarchy serves on `o`: traces, and for an R-tree inserts
/// and deletes. Returns the hits and whether a trace faulted.
fn exercise_bvh(o: &mut OwnedBvh, s: &OwnedScene, rays: &[Ray]) -> (Vec<Hit>, bool) {
    let sc = s.scene();
    let mut st = TraceStats::default();
    let mut hits = Vec::new();
    if let Ok(b) = o.view(sc) {
        let mut stk = stack::<BvhStackItem>(b.stack_len().min(1 << 16));
        for r in rays {
            hits.push(b.intersect(r, &mut stk, &mut st));
            b.occluded(r, &mut stk, &mut st);
        }
    }
    (hits, st.faults > 0)
}

/// Corrupts a copy of each hierarchy of `s` by `corrupt`, then checks the rules.
fn bvh_cases(s: &OwnedScene, rays: &[Ray], what: &str, corrupt: impl Fn(&mut OwnedBvh) -> bool) {
    let sc = s.scene();
    for how in builders() {
        let mut clean = OwnedBvh::new(&sc, how).unwrap();
        let mut bad = OwnedBvh::new(&sc, how).unwrap();
        if !corrupt(&mut bad) {
            continue;
        }
        let want = exercise_bvh(&mut clean, s, rays).0;
        let ok = bad.validate(sc).is_ok();
        let (got, faulted) = exercise_bvh(&mut bad, s, rays);
        if ok {
            assert!(!faulted, "{what} {how:?}: validated, then faulted");
            let diff = got.iter().zip(&want).filter(|(a, b)| !same(a, b)).count();
            assert_eq!(
                diff, 0,
                "{what} {how:?}: validated, then {diff} different hits"
            );
        }
        // Inserts and deletes on the corrupt R-tree: a status, never a panic.
        if let BvhBuild::RTree(_) = how {
            for p in 0..sc.prim_count() as u32 {
                let _ = bad.update(&sc, p, p % 2 == 0);
            }
        }
    }
}

/// A leaf naming a primitive past the scene: validate rejects it (it
/// panicked), tracing returns.
#[test]
fn bvh_reference_past_the_scene() {
    watchdog(30, "bvh reference past the scene", || {
        let s = scene(4);
        let n = s.scene().prim_count() as u32;
        for bad in [n, n + 2, u32::MAX] {
            bvh_cases(&s, &rays(), "reference past the scene", |b| {
                let (nodes, refs, _) = b.parts_mut();
                let leaf = nodes.iter().find(|n| n.is_leaf() && !n.is_empty()).unwrap();
                refs[leaf.first as usize] = bad;
                true
            });
        }
    });
}

/// Seeded sweep over every word of every hierarchy.
#[test]
fn bvh_random_words() {
    watchdog(240, "bvh random words", || {
        let s = scene(5);
        let rays = rays()[..16].to_vec();
        let mut rng = Rng(12);
        for _ in 0..60 {
            let (part, pick, value) = (rng.below(3), rng.next_u64(), rng.next_u64() as u32);
            let small = rng.below(40) as u32;
            bvh_cases(&s, &rays, "random word", |b| {
                let (nodes, refs, info) = b.parts_mut();
                match part {
                    0 => {
                        let i = (pick % info.node_count.max(1) as u64) as usize;
                        let nd = &mut nodes[i];
                        match pick >> 40 & 3 {
                            0 => nd.first = small,
                            1 => nd.count = value,
                            2 => nd.count ^= 1 << 31,
                            _ => nd.min[0] = f32::from_bits(value),
                        }
                    }
                    1 => refs[(pick % refs.len().max(1) as u64) as usize] = small,
                    _ => info.depth = value % 64,
                }
                true
            });
        }
    });
}

/// A hierarchy rewritten as a shared graph, node k -> k+1, k+2, 44 deep:
/// validate answers in linear time (it took exponential time).
#[test]
fn bvh_shared_graph_is_rejected_in_linear_time() {
    watchdog(10, "bvh shared graph", || {
        let mut s = OwnedScene::default();
        s.add_triangle(Vec3::ZERO, Vec3::X, Vec3::Y);
        let sc = s.scene();
        let depth = 44u32;
        let b = sc.prim_bounds(0).unwrap();
        let mut nodes = vec![BvhNode::leaf(&b, 0, 1); depth as usize + 2];
        for (k, n) in nodes.iter_mut().enumerate().take(depth as usize) {
            *n = BvhNode::interior(&b, k as u32 + 1, 2);
        }
        let refs = [0u32];
        let info = BvhInfo {
            root: 0,
            node_count: nodes.len() as u32,
            leaf_count: 2,
            ref_count: 1,
            depth,
            max_children: 2,
            ref_digest: [0; 2],
        };
        let t = Bvh::from_parts(sc, &nodes, &refs, info).unwrap();
        let mut stk = stack::<BvhStackItem>(t.stack_len());
        assert!(t.validate(None, &mut stk).is_err());
        let mut st = TraceStats::default();
        let r = Ray::new(Vec3::new(0.2, 0.2, 5.0), -Vec3::Z, 0.0, f32::INFINITY);
        t.intersect(&r, &mut stk, &mut st);
        t.occluded(&r, &mut stk, &mut st);
    });
}

/// The root as its own child in a hierarchy that claims to be deeper than
/// the old validator's fixed stack: validate rejects it (it said OK), and
/// tracing returns (it looped forever).
#[test]
fn bvh_deep_root_that_is_its_own_child() {
    watchdog(10, "bvh deep self loop", || {
        let mut s = OwnedScene::default();
        s.add_triangle(Vec3::ZERO, Vec3::X, Vec3::Y);
        let sc = s.scene();
        let b = sc.prim_bounds(0).unwrap();
        let nodes = vec![BvhNode::interior(&b, 0, 2); 3001];
        let refs = [0u32];
        let info = BvhInfo {
            root: 0,
            node_count: 3001,
            leaf_count: 1,
            ref_count: 1,
            depth: 3000,
            max_children: 2,
            ref_digest: [0; 2],
        };
        let t = Bvh::from_parts(sc, &nodes, &refs, info).unwrap();
        let mut stk = stack::<BvhStackItem>(t.stack_len());
        assert!(t.validate(None, &mut stk).is_err());
        let mut st = TraceStats::default();
        let r = Ray::new(Vec3::new(0.2, 0.2, 5.0), -Vec3::Z, 0.0, f32::INFINITY);
        t.intersect(&r, &mut stk, &mut st);
        t.occluded(&r, &mut stk, &mut st);
        assert!(st.faults > 0);
    });
}

/// Projection hierarchies: a reference past the scene and random words;
/// validate never panics, traversal returns, accepted ones trace alike.
#[test]
fn proj_corruptions() {
    watchdog(120, "proj", || {
        let s = scene(6);
        let sc = s.scene();
        let cam = camera();
        let plane = ProjPlane::camera(&cam);
        let (f, r, u) = cam.basis();
        let rays: Vec<Ray> = (0..40)
            .map(|i| cam.ray_in(f, r, u, (i % 12) as f32 + 0.5, (i / 12) as f32 + 0.5))
            .collect();
        let n = sc.prim_count() as u32;
        let mut rng = Rng(13);
        for builder in [
            ProjBuilder::Static(Builder::Tdbs),
            ProjBuilder::Static(Builder::NnChain),
            ProjBuilder::RTree(RTreeParams::rstar()),
        ] {
            for criteria in [Criteria::TwoD, Criteria::Dummy] {
                let clean = OwnedProj::new(&sc, plane, builder, criteria).unwrap();
                let trace = |o: &OwnedProj| -> (Vec<Hit>, bool) {
                    let Ok(h) = o.view(sc) else {
                        return (Vec::new(), false);
                    };
                    let mut stk = stack::<BvhStackItem>(h.stack_len().min(1 << 16));
                    let mut st = TraceStats::default();
                    let hits = rays
                        .iter()
                        .map(|r| h.intersect(r, ProjScheme::Combination, &mut stk, &mut st))
                        .map(|x| x.unwrap_or(Hit::MISS))
                        .collect();
                    (hits, st.faults > 0)
                };
                let want = trace(&clean).0;
                for k in 0..40 {
                    let mut bad = OwnedProj::new(&sc, plane, builder, criteria).unwrap();
                    let (nodes, refs, rects, prim_rects) = bad.parts_mut();
                    let pick = rng.next_u64();
                    match k % 5 {
                        0 => refs[(pick % refs.len() as u64) as usize] = n + (k as u32),
                        1 => nodes[(pick % 8) as usize].first = (pick >> 32) as u32 % 50,
                        2 => nodes[(pick % 8) as usize].count = (pick >> 32) as u32,
                        3 => rects[(pick % 8) as usize].min[0] = -1e30,
                        _ => prim_rects[(pick % n as u64) as usize].max[1] = 1e30,
                    }
                    let ok = bad.view(sc).is_ok_and(|h| {
                        let mut stk = stack::<BvhStackItem>(h.stack_len().min(1 << 16));
                        Accel::validate(&h, &mut stk).is_ok()
                    });
                    let (got, faulted) = trace(&bad);
                    if ok {
                        assert!(!faulted);
                        assert!(got.iter().zip(&want).all(|(a, b)| same(a, b)));
                    }
                }
            }
        }
    });
}

/// Scenes at the edge of f32: coordinates near f32::MAX make box areas
/// infinite. Every builder (kd-tree, each hierarchy, projections) builds,
/// validates and traces them like any other scene. (Found by the C-ABI
/// fuzzer: the NN chain indexed slot u32::MAX when every candidate's
/// joint area was infinite, and the R-tree's quadratic split picked no
/// entry when every preference was NaN.)
#[test]
fn builds_over_infinite_areas() {
    let big = 1.0e38f32;
    let vertices = vec![
        [-big, 0.0, -big],
        [big, 0.0, -big],
        [big, 0.0, big],
        [-big, 0.0, big],
        [0.0, big, 0.0],
        [0.0, -big, 0.0],
        [1.0, 1.0, 1.0],
        [2.0, 1.0, 1.0],
        [1.0, 2.0, 1.0],
    ];
    let triangles = vec![[0, 1, 2], [0, 2, 3], [0, 4, 1], [2, 5, 3], [6, 7, 8]];
    // Enough small triangles beside the huge ones for R-tree splits.
    let (mut vertices, mut triangles) = (vertices, triangles);
    for k in 0..60u32 {
        let x = k as f32 * 0.1;
        let i = vertices.len() as u32;
        vertices.extend([[x, 0.5, 0.0], [x + 0.05, 0.5, 0.0], [x, 0.6, 0.1]]);
        triangles.push([i, i + 1, i + 2]);
        if k % 7 == 0 {
            let j = vertices.len() as u32;
            vertices.extend([[x, -big, -big], [x, big, -big], [x, 0.0, big]]);
            triangles.push([j, j + 1, j + 2]);
        }
    }
    let owned = OwnedScene {
        vertices,
        triangles,
        spheres: vec![coray::Sphere {
            center: [0.0, 3.0, 0.0],
            radius: big,
        }],
        cones: Vec::new(),
    };
    let sc = owned.scene();
    let rays: Vec<Ray> = (0..16)
        .map(|k| {
            let a = k as f32 * 0.4;
            Ray::new(
                Vec3::new(5.0 * a.cos(), 7.0, 5.0 * a.sin()),
                Vec3::new(-a.cos(), -1.0, -a.sin()),
                0.0,
                f32::INFINITY,
            )
        })
        .collect();
    let kd = OwnedKd::new(&sc, &KdParams::auto_with_ropes()).expect("kd build");
    let tree = kd.tree(sc).unwrap();
    tree.validate().expect("kd validates");
    let (reference, _) = exercise_kd(&tree, &rays);
    for b in builders() {
        let mut o = OwnedBvh::new(&sc, b).unwrap_or_else(|e| panic!("{b:?}: {e}"));
        o.validate(sc).unwrap_or_else(|e| panic!("{b:?}: {e}"));
        let (hits, faulted) = exercise_bvh(&mut o, &owned, &rays);
        assert!(!faulted, "{b:?}");
        for (h, r) in hits.iter().zip(&reference) {
            assert!(same(h, r), "{b:?}: {h:?} against the kd-tree's {r:?}");
        }
    }
}

/// An R-tree whose state disagrees with its hierarchy in a word only an
/// update reads (the reference digest it carries on) must not validate:
/// the update after it would leave an invalid tree. (Found by the C-ABI
/// fuzzer: a flipped state digest passed validate; delete and insert then
/// wrote it into the hierarchy, and validate failed.)
#[test]
fn rtree_state_must_agree_with_its_hierarchy() {
    let s = scene(7);
    let sc = s.scene();
    for p in [RTreeParams::rtree(), RTreeParams::rstar()] {
        let clean = OwnedBvh::new(&sc, BvhBuild::RTree(p)).unwrap();
        clean.validate(sc).unwrap();
        type Corrupt = fn(&mut coray::bvh::RTreeState);
        let corruptions: [(&str, Corrupt); 3] = [
            ("digest low word", |st| st.ref_digest[0] ^= 0x54),
            ("digest high word", |st| st.ref_digest[1] ^= 1),
            ("length", |st| st.len += 1),
        ];
        for (what, corrupt) in corruptions {
            let mut o = OwnedBvh::new(&sc, BvhBuild::RTree(p)).unwrap();
            corrupt(o.rtree_state_mut());
            assert!(o.validate(sc).is_err(), "{what}: accepted");
        }
    }
}

/// Everything a wide hierarchy serves on `o`: closest and any hit.
/// Returns the hits and whether a trace faulted.
fn exercise_wide(o: &OwnedWide, s: &OwnedScene, rays: &[Ray]) -> (Vec<Hit>, bool) {
    let sc = s.scene();
    let mut st = TraceStats::default();
    let mut hits = Vec::new();
    if let Ok(w) = o.view(sc) {
        let mut stk = stack::<WideStackItem>(w.stack_len().min(1 << 16));
        for r in rays {
            hits.push(w.intersect(r, &mut stk, &mut st));
            w.occluded(r, &mut stk, &mut st);
        }
    }
    (hits, st.faults > 0)
}

/// Corrupts a copy of the wide hierarchy of `s` (leaves of 1 and of 3) by
/// `corrupt`; a copy `validate` accepts traces as the clean one, without
/// faults. Returns whether validate accepted it.
fn wide_cases(s: &OwnedScene, rays: &[Ray], what: &str, corrupt: impl Fn(&mut OwnedWide)) -> usize {
    let sc = s.scene();
    let mut accepted = 0;
    for leaf in [1, 3] {
        let clean = OwnedWide::new(&sc, leaf).unwrap();
        let mut bad = OwnedWide::new(&sc, leaf).unwrap();
        corrupt(&mut bad);
        let want = exercise_wide(&clean, s, rays).0;
        let ok = bad.view(sc).is_ok_and(|w| w.validate().is_ok());
        let (got, faulted) = exercise_wide(&bad, s, rays);
        if ok {
            accepted += 1;
            assert!(!faulted, "{what} leaf {leaf}: validated, then faulted");
            let diff = got.iter().zip(&want).filter(|(a, b)| !same(a, b)).count();
            assert_eq!(
                diff, 0,
                "{what} leaf {leaf}: validated, then {diff} different hits"
            );
        }
    }
    accepted
}

/// Seeded sweep over every field of the wide hierarchy: node boxes, child
/// indices, counts, references and the info. Nothing panics or hangs; what
/// validate accepts traces as the clean build.
#[test]
fn wide_random_words() {
    watchdog(120, "wide random words", || {
        let s = scene(6);
        let rays = rays();
        let mut rng = Rng(14);
        let mut accepted = 0;
        for _ in 0..300 {
            let (part, pick, value) = (rng.below(5), rng.next_u64(), rng.next_u64() as u32);
            let small = rng.below(40) as u32;
            accepted += wide_cases(&s, &rays, "random word", |w| {
                let (nodes, blocks, info) = w.parts_mut();
                let slot = (pick >> 20) as usize % coray::wide::WIDTH;
                let lane = slot % 4;
                match part {
                    0 => {
                        let nd = &mut nodes[(pick % info.node_count as u64) as usize];
                        match pick >> 40 & 7 {
                            0 => nd.child[slot] = small,
                            1 => nd.child[slot] = value,
                            2 => nd.child[slot] ^= 1 << 31,
                            3 => nd.child[slot] ^= 1 << (27 + (pick >> 50) % 4),
                            4 => nd.child[slot] = coray::wide::leaf_entry(small, 1 + small % 16),
                            5 => nd.planes[slot % 3][slot] = f32::from_bits(value),
                            6 => nd.planes[3 + slot % 3][slot] = f32::from_bits(value),
                            _ => nd.child[slot] = coray::wide::EMPTY_SLOT,
                        }
                    }
                    1 | 2 => {
                        let b = &mut blocks[(pick % blocks.len().max(1) as u64) as usize];
                        b.prims[lane] = if part == 1 { small } else { value };
                    }
                    3 => {
                        let b = &mut blocks[(pick % blocks.len().max(1) as u64) as usize];
                        let (k, a) = ((pick >> 8) as usize % 3, (pick >> 12) as usize % 3);
                        b.corners[k][a][lane] = match pick >> 40 & 1 {
                            0 => f32::from_bits(value),
                            _ => b.corners[k][a][lane] + small as f32 * 0.25,
                        };
                    }
                    _ => match pick >> 40 & 7 {
                        0 => info.depth = value % 64,
                        1 => info.node_count = value % (2 * info.node_count + 2),
                        2 => info.ref_count = value % (2 * info.ref_count + 2),
                        3 | 4 => info.block_count = value % (2 * info.block_count + 2),
                        _ => info.leaf_count = small,
                    },
                }
            });
        }
        // A few corruptions leave values as they were; the rest are refused.
        assert!(accepted < 80, "{accepted} of 600 corruptions accepted");
    });
}

/// A child index pointing back up (a cycle) and a leaf naming a primitive
/// past the scene: validate refuses both, traversal returns.
#[test]
fn wide_cycle_and_reference_past_the_scene() {
    watchdog(30, "wide cycle", || {
        let s = scene(4);
        let n = s.scene().prim_count() as u32;
        assert_eq!(
            wide_cases(&s, &rays(), "cycle", |w| {
                let (nodes, _, info) = w.parts_mut();
                let last = info.node_count as usize - 1;
                let slot = nodes[last].child.iter().position(|&c| c & (1 << 31) == 0);
                nodes[last].child[slot.unwrap_or(0)] = 0;
            }),
            0
        );
        for bad in [n, n + 2, u32::MAX] {
            assert_eq!(
                wide_cases(&s, &rays(), "reference past the scene", |w| {
                    let (_, blocks, _) = w.parts_mut();
                    blocks[0].prims[0] = bad;
                }),
                0
            );
        }
    });
}
