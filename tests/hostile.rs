//! Hostile structures: every case of issue 16 that the core sees. Each
//! runs under a watchdog, so a hang fails the test instead of stalling it.
mod common;

use common::*;
use coray::bvh::{self, Builder, Bvh, BvhNode, BvhScratch, BvhStackItem, BvhStats, BvhStorage};
use coray::kd::{KdNode, KdParams, Traversal, NO_NODE};
use coray::{Aabb, Camera, Ray, Vec3};
use std::sync::mpsc;
use std::time::Duration;

/// Runs `f` on its own thread; fails when it panics or takes longer than `secs`.
fn watchdog(secs: u64, what: &str, f: impl FnOnce() + Send + 'static) {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        f();
        let _ = tx.send(());
    });
    match rx.recv_timeout(Duration::from_secs(secs)) {
        Ok(()) => {}
        Err(mpsc::RecvTimeoutError::Timeout) => panic!("{what}: no answer within {secs} s"),
        Err(mpsc::RecvTimeoutError::Disconnected) => panic!("{what}: panicked"),
    }
}

fn scene(seed: u64) -> OwnedScene {
    random_scene(&mut Rng(seed), 60, 20, 10, 10.0)
}

fn rays() -> Vec<Ray> {
    random_rays(&mut Rng(7), 64, 10.0)
}

/// Every interior node made its own left child, one at a time: validate
/// rejects each quickly, and traversal of the corrupt tree returns.
#[test]
fn kd_node_that_is_its_own_child() {
    watchdog(20, "kd self child", || {
        let s = scene(1);
        let sc = s.scene();
        let (req, mut b) = ideal_storage(&sc, &KdParams::auto());
        let clean = build_with(&sc, &KdParams::auto(), &req, &mut b);
        let n = clean.info.node_count as usize;
        let nodes0 = clean.nodes.to_vec();
        let rays = rays();
        for i in 0..n {
            let nd = nodes0[i];
            if nd.is_leaf() {
                continue;
            }
            let mut nodes = nodes0.clone();
            nodes[i] = KdNode::interior(nd.axis(), nd.split(), i as u32);
            let t = coray::kd::KdTree { nodes: &nodes, ..clean };
            assert!(t.validate().is_err(), "node {i} made its own child passed validate");
            let mut st = coray::TraceStats::default();
            for r in &rays {
                t.intersect(r, Traversal::Hierarchical, &mut st);
                t.intersect(r, Traversal::Ropes, &mut st);
                t.occluded(r, Traversal::Ropes, &mut st);
            }
        }
    });
}

/// Ropes that point anywhere: validate never panics and rejects them.
#[test]
fn kd_ropes_pointing_anywhere() {
    watchdog(20, "kd ropes", || {
        let s = scene(2);
        let sc = s.scene();
        let (req, mut b) = ideal_storage(&sc, &KdParams::auto());
        let clean = build_with(&sc, &KdParams::auto(), &req, &mut b);
        let n = clean.info.node_count;
        let ropes0 = clean.ropes.to_vec();
        let rays = rays();
        for leaf in 0..ropes0.len() {
            for face in 0..6 {
                for bad in [0, n - 1, n, n + 1, NO_NODE - 1, leaf as u32] {
                    if ropes0[leaf].neighbor[face] == bad {
                        continue;
                    }
                    let mut ropes = ropes0.clone();
                    ropes[leaf].neighbor[face] = bad;
                    let t = coray::kd::KdTree { ropes: &ropes, ..clean };
                    let ok = t.validate().is_ok();
                    let mut st = coray::TraceStats::default();
                    for r in &rays {
                        let h = t.intersect(r, Traversal::Ropes, &mut st);
                        if ok {
                            let want = clean.intersect(r, Traversal::Hierarchical, &mut st);
                            assert_eq!((h.prim_id, h.t), (want.prim_id, want.t));
                        }
                    }
                }
            }
        }
    });
}

/// Leaves and references out of range: validate says so; every traversal
/// and every image scheme returns.
#[test]
fn kd_leaves_and_refs_out_of_range() {
    watchdog(30, "kd leaves and refs", || {
        let s = scene(3);
        let sc = s.scene();
        let (req, mut b) = ideal_storage(&sc, &KdParams::paper());
        let clean = build_with(&sc, &KdParams::paper(), &req, &mut b);
        let prims = sc.prim_count() as u32;
        let rays = rays();
        let cam = Camera {
            from: Vec3::new(0.0, 3.0, -30.0),
            at: Vec3::ZERO,
            up: Vec3::Y,
            angle_deg: 45.0,
            width: 12,
            height: 9,
        };
        let mut cases: Vec<Box<dyn Fn(&mut Built)>> = Vec::new();
        for bad in [prims, prims + 7, u32::MAX, u32::MAX >> 3] {
            cases.push(Box::new(move |b: &mut Built| b.refs[0] = bad));
            cases.push(Box::new(move |b: &mut Built| b.leaves[1].ref_count = bad));
            cases.push(Box::new(move |b: &mut Built| b.leaves[2].first_ref = bad));
            cases.push(Box::new(move |b: &mut Built| {
                let i = b.nodes.iter().position(|n| n.is_leaf()).unwrap();
                b.nodes[i] = KdNode::leaf(bad >> 2);
            }));
            cases.push(Box::new(move |b: &mut Built| {
                b.nodes[0] = KdNode::interior(0, 0.0, bad >> 2);
            }));
        }
        for (k, corrupt) in cases.iter().enumerate() {
            let mut c = Built {
                nodes: clean.nodes.to_vec(),
                leaves: clean.leaves.to_vec(),
                ropes: clean.ropes.to_vec(),
                refs: clean.refs.to_vec(),
            };
            corrupt(&mut c);
            let t = coray::kd::KdTree {
                nodes: &c.nodes,
                leaves: &c.leaves,
                ropes: &c.ropes,
                refs: &c.refs,
                ..clean
            };
            assert!(t.validate().is_err(), "case {k} passed validate");
            let mut st = coray::TraceStats::default();
            for r in &rays {
                t.intersect(r, Traversal::Hierarchical, &mut st);
                t.intersect(r, Traversal::Ropes, &mut st);
                t.occluded(r, Traversal::Hierarchical, &mut st);
            }
            for scheme in lcts_schemes() {
                let req = coray::lcts::image_requirements(12, 9, scheme, 64);
                let mut o = OwnedCast::new(&req);
                let mut tt = vec![0f32; 108];
                let mut pp = vec![0u32; 108];
                let _ = coray::lcts::cast_image(&t, &cam, scheme, o.scratch(), &mut tt, &mut pp);
            }
        }
    });
}

fn lcts_schemes() -> Vec<coray::lcts::Scheme> {
    use coray::lcts::Scheme::*;
    vec![
        Hierarchical,
        Ropes,
        Slcts1d { n: 5 },
        Slcts2d { n: 5, m: 5 },
        Hlcts1d,
        Hlcts2d,
    ]
}

struct OwnedCast {
    records: Vec<coray::lcts::HistoryRecord>,
    entries: Vec<u32>,
    corners: Vec<coray::lcts::CornerInfo>,
    starts: Vec<u32>,
    hlcts: Vec<coray::lcts::hlcts::HlctsEntry>,
}

impl OwnedCast {
    fn new(r: &coray::lcts::ImageRequirements) -> OwnedCast {
        OwnedCast {
            records: vec![Default::default(); r.records],
            entries: vec![0; r.entries],
            corners: vec![Default::default(); r.corners],
            starts: vec![0; r.starts],
            hlcts: vec![Default::default(); r.hlcts],
        }
    }
    fn scratch(&mut self) -> coray::lcts::ImageScratch<'_> {
        coray::lcts::ImageScratch {
            records: &mut self.records,
            entries: &mut self.entries,
            corners: &mut self.corners,
            starts: &mut self.starts,
            hlcts: &mut self.hlcts,
        }
    }
}

/// A static hierarchy built with `builder` over `scene`, owned.
fn build_bvh(sc: &coray::Scene, builder: Builder) -> (Vec<BvhNode>, Vec<u32>, bvh::BvhInfo) {
    let r = bvh::requirements(sc.prim_count(), builder);
    let mut nodes = vec![BvhNode::default(); r.nodes];
    let mut refs = vec![0u32; r.refs];
    let (mut boxes, mut keys, mut links, mut clusters) = (
        vec![Aabb::EMPTY; r.boxes],
        vec![0f32; r.keys],
        vec![0u32; r.links],
        vec![BvhNode::default(); r.clusters],
    );
    let info = bvh::build(
        sc,
        builder,
        1,
        BvhStorage {
            nodes: &mut nodes,
            refs: &mut refs,
        },
        BvhScratch {
            boxes: &mut boxes,
            keys: &mut keys,
            links: &mut links,
            clusters: &mut clusters,
        },
    )
    .unwrap()
    .info;
    (nodes, refs, info)
}

/// A leaf naming a primitive past the scene: validate rejects it, tracing returns.
#[test]
fn bvh_reference_past_the_scene() {
    watchdog(20, "bvh reference past the scene", || {
        let s = scene(4);
        let sc = s.scene();
        let rays = rays();
        for builder in [Builder::Tdbs, Builder::TdbsSah, Builder::Nn, Builder::NnChain] {
            let (nodes, mut refs, info) = build_bvh(&sc, builder);
            refs[3] = sc.prim_count() as u32 + 2;
            let t = Bvh {
                scene: sc,
                nodes: &nodes,
                refs: &refs,
                info,
            };
            assert!(t.validate(None).is_err(), "{builder:?}");
            let mut stack = vec![BvhStackItem::default(); t.stack_len()];
            let mut st = BvhStats::default();
            for r in &rays {
                t.intersect(r, &mut stack, &mut st);
                t.occluded(r, &mut stack, &mut st);
            }
        }
    });
}

/// A hierarchy rewritten as a shared graph, node k -> k+1, k+2, 44 deep:
/// validate must answer in linear time.
#[test]
fn bvh_shared_graph_is_rejected_in_linear_time() {
    watchdog(10, "bvh shared graph", || {
        let mut s = OwnedScene::default();
        s.add_triangle(Vec3::ZERO, Vec3::X, Vec3::Y);
        let sc = s.scene();
        let depth = 44u32;
        let b = sc.prim_bounds(0).unwrap();
        let mut nodes = vec![BvhNode::leaf(&b, 0, 1); depth as usize + 2];
        for k in 0..depth as usize {
            nodes[k] = BvhNode::interior(&b, k as u32 + 1, 2);
        }
        let refs = [0u32];
        let t = Bvh {
            scene: sc,
            nodes: &nodes,
            refs: &refs,
            info: bvh::BvhInfo {
                root: 0,
                node_count: nodes.len() as u32,
                leaf_count: 2,
                ref_count: 1,
                depth,
                max_children: 2,
            },
        };
        assert!(t.validate(None).is_err());
    });
}

/// The root as its own child in a hierarchy that claims to be deeper than
/// the validator's stack: validate rejects it, and tracing returns.
#[test]
fn bvh_deep_root_that_is_its_own_child() {
    watchdog(10, "bvh deep self loop", || {
        let mut s = OwnedScene::default();
        s.add_triangle(Vec3::ZERO, Vec3::X, Vec3::Y);
        let sc = s.scene();
        let b = sc.prim_bounds(0).unwrap();
        let nodes = [BvhNode::interior(&b, 0, 2), BvhNode::leaf(&b, 0, 1)];
        let refs = [0u32];
        let t = Bvh {
            scene: sc,
            nodes: &nodes,
            refs: &refs,
            info: bvh::BvhInfo {
                root: 0,
                node_count: 2,
                leaf_count: 1,
                ref_count: 1,
                depth: 3000,
                max_children: 2,
            },
        };
        assert!(t.validate(None).is_err());
        let mut stack = vec![BvhStackItem::default(); t.stack_len()];
        let mut st = BvhStats::default();
        let r = Ray::new(Vec3::new(0.2, 0.2, 5.0), -Vec3::Z, 0.0, f32::INFINITY);
        t.intersect(&r, &mut stack, &mut st);
        t.occluded(&r, &mut stack, &mut st);
    });
}
