//! The wide hierarchy against the brute-force oracle and, bit for bit,
//! against the kd-tree's hierarchical traversal; its shape, its memory
//! bound, and rays parallel to the box faces.
mod common;

use common::*;
use coray::kd::{KdParams, Traversal};
use coray::owned::{stack, OwnedKd, OwnedWide};
use coray::wide::{self, WideBvh, WideNode, WideScratch, WideStackItem, WideStorage, WIDTH};
use coray::{oracle, Aabb, Error, Hit, Ray, Scene, TraceStats, Vec3};

/// Hit for hit: the same t (bits), primitive and normal.
fn identical(a: &Hit, b: &Hit) -> bool {
    a.is_hit() == b.is_hit()
        && (!a.is_hit()
            || (a.t.to_bits() == b.t.to_bits()
                && (a.geom_id, a.prim_id) == (b.geom_id, b.prim_id)
                && a.ng == b.ng))
}

/// Traces `rays` through `w` and through the kd-tree over the same scene
/// and checks both against the oracle (closest t, any hit) and against
/// each other bit for bit; returns the hits.
fn check(w: &WideBvh, kd: &coray::kd::KdTree, rays: &[Ray], what: &str) -> usize {
    let scene = w.scene();
    let mut stk = stack::<WideStackItem>(w.stack_len());
    let mut kst = kst();
    let mut hits = 0;
    for (i, r) in rays.iter().enumerate() {
        let mut st = TraceStats::default();
        let got = w.intersect(r, &mut stk, &mut st);
        let any = w.occluded(r, &mut stk, &mut st);
        assert_eq!(st.faults, 0, "{what}: ray {i} faulted");
        let want = oracle::intersect(scene, r);
        assert_eq!(
            (got.is_hit(), got.is_hit().then_some(got.t)),
            (want.is_hit(), want.is_hit().then_some(want.t)),
            "{what}: ray {i} {r:?}: got {got:?}, oracle {want:?}"
        );
        assert_eq!(any, oracle::occluded(scene, r), "{what}: ray {i} occluded");
        let k = kd.intersect(r, Traversal::Hierarchical, &mut kst, &mut st);
        assert!(
            identical(&got, &k),
            "{what}: ray {i}: wide {got:?}, kd {k:?}"
        );
        hits += got.is_hit() as usize;
    }
    hits
}

/// Rays along the axes and in the planes of the scene's coordinates (zero
/// direction components, origins on box faces), plus random ones.
fn rays_with_parallels(rng: &mut Rng, scene: &Scene, n: usize, s: f32) -> Vec<Ray> {
    let mut rays = random_rays(rng, n, s);
    for p in 0..scene.prim_count().min(200) {
        let Some(b) = scene.prim_bounds(p) else {
            continue;
        };
        let c = (b.min + b.max) * 0.5;
        for axis in 0..3 {
            let mut d = Vec3::ZERO;
            d[axis] = 1.0;
            // From far below the box along an axis, through its centre and
            // along its faces.
            for o in [c, b.min, b.max] {
                let mut from = o;
                from[axis] = -4.0 * s;
                rays.push(Ray::new(from, d, 0.0, f32::INFINITY));
                rays.push(Ray::new(-from, -d, 0.0, f32::INFINITY));
            }
            // In a coordinate plane through the box's corner.
            let mut e = Vec3::new(1.0, 1.0, 1.0);
            e[axis] = 0.0;
            rays.push(Ray::new(b.min - e * 2.0 * s, e, 0.0, f32::INFINITY));
        }
    }
    rays
}

#[test]
fn every_leaf_size_matches_the_oracle_and_the_kd_tree() {
    let mut rng = Rng(31);
    let o = random_scene(&mut rng, 900, 200, 200, 10.0);
    let scene = o.scene();
    let rays = rays_with_parallels(&mut rng, &scene, 1500, 10.0);
    let kd = OwnedKd::new(&scene, &KdParams::auto()).unwrap();
    let tree = kd.tree(scene).unwrap();
    let n = scene.prim_count();
    for leaf in [1, 2, 4, 9] {
        let owned = OwnedWide::new(&scene, leaf).unwrap();
        let w = owned.view(scene).unwrap();
        let shape = w.validate().unwrap();
        let info = w.info();
        assert_eq!(shape.refs as usize, n, "leaf {leaf}");
        assert_eq!(
            (shape.nodes, shape.leaves),
            (info.node_count, info.leaf_count)
        );
        // Every binary interior node is a wide node or opened into one:
        // fewer wide nodes than primitives, and with leaves of one
        // primitive exactly one leaf entry a primitive.
        assert!((info.node_count as usize) < n);
        assert!(info.node_count as usize <= wide::nodes_bound(info.leaf_count as usize));
        if leaf == 1 {
            assert_eq!(info.leaf_count as usize, n);
        }
        // A wide tree is much shallower than the binary one.
        assert!(info.depth <= 12, "leaf {leaf}: depth {}", info.depth);
        let hits = check(&w, &tree, &rays, &format!("leaf {leaf}"));
        assert!(hits > 600, "leaf {leaf}: {hits} hits");
    }
}

/// Leaf entries: how many, how many hold more than one primitive, and
/// whether each takes exactly the blocks its primitives need (full blocks
/// but its last, which holds its primitives first).
fn leaf_blocks(w: &WideBvh) -> (usize, usize, bool) {
    let (nodes, blocks) = w.parts();
    let (mut leaves, mut long, mut tight) = (0, 0, true);
    for nd in nodes {
        for i in 0..nd.len() {
            if nd.child[i] & wide::LEAF_BIT != 0 {
                let (f, count) = wide::leaf_run(nd.child[i]);
                let held: Vec<u32> = blocks[f..f + count]
                    .iter()
                    .flat_map(|b| b.prims)
                    .take_while(|&p| p != wide::NO_PRIM)
                    .collect();
                leaves += 1;
                long += usize::from(held.len() > 1);
                tight &= count == held.len().div_ceil(wide::BLOCK_SLOTS);
            }
        }
    }
    (leaves, long, tight)
}

/// On SPD scenes whose leaves hold two to four triangles, each leaf takes
/// the fewest blocks its primitives fill, and the hierarchy still traces
/// as the kd-tree.
#[test]
fn leaves_take_the_fewest_blocks_on_spd_scenes() {
    for name in ["teapot", "gears"] {
        let nff = coray_scenes::spd::generate(name, Some(2), &Default::default()).unwrap();
        let mesh = coray_scenes::SceneMesh::from_nff(&nff);
        let scene = mesh.scene();
        let owned = OwnedWide::new(&scene, 4).unwrap();
        let w = owned.view(scene).unwrap();
        w.validate().unwrap();
        let (leaves, long, tight) = leaf_blocks(&w);
        assert!(
            long * 2 > leaves,
            "{name}: {long} of {leaves} leaves longer than one"
        );
        assert!(tight, "{name}: a leaf takes more blocks than it fills");
        assert_eq!(
            leaves,
            w.info().block_count as usize,
            "{name}: one block a leaf"
        );
        let kd = OwnedKd::new(&scene, &KdParams::auto()).unwrap();
        // Rays between two points of the scene's box.
        let mut rng = Rng(5);
        let b = scene.bounds();
        let mut point = || {
            let f = Vec3::new(
                rng.range(0.0, 1.0),
                rng.range(0.0, 1.0),
                rng.range(0.0, 1.0),
            );
            b.min + (b.max - b.min) * f
        };
        let rays: Vec<Ray> = (0..2000)
            .map(|_| {
                let o = point();
                Ray::new(o, point() - o, 0.0, f32::INFINITY)
            })
            .collect();
        let hits = check(&w, &kd.tree(scene).unwrap(), &rays, name);
        assert!(hits > 500, "{name}: {hits} hits");
    }
}

/// Blocks hold every kind: spheres and cones in slots of NaN corners
/// beside triangles, one block for every four primitives of a leaf; each
/// scene traces as the kd-tree.
#[test]
fn blocks_hold_every_kind() {
    for (tris, others, seed) in [(0, 300, 41), (300, 300, 42), (600, 0, 43)] {
        let mut rng = Rng(seed);
        let o = random_scene(&mut rng, tris, others / 2, others - others / 2, 5.0);
        let scene = o.scene();
        for leaf in [4, 9] {
            let owned = OwnedWide::new(&scene, leaf).unwrap();
            let w = owned.view(scene).unwrap();
            w.validate().unwrap();
            let (_, _, tight) = leaf_blocks(&w);
            assert!(tight);
            let (_, blocks) = w.parts();
            let held = blocks
                .iter()
                .flat_map(|b| b.prims)
                .filter(|&p| p != wide::NO_PRIM)
                .count();
            assert_eq!(held, scene.prim_count());
            // Slots of spheres and cones have NaN corners.
            let nt = scene.triangles.len() as u32;
            for b in blocks {
                for lane in 0..wide::BLOCK_SLOTS {
                    let triangle = b.prims[lane] < nt;
                    assert_eq!(!b.corners[0][0][lane].is_nan(), triangle);
                }
            }
            let mixed = mixed_leaves(&w);
            if tris > 0 && others > 0 {
                assert!(mixed > 0, "{mixed} mixed leaves");
            } else {
                assert_eq!(mixed, 0);
            }
            let kd = OwnedKd::new(&scene, &KdParams::auto()).unwrap();
            let rays = random_rays(&mut rng, 1000, 5.0);
            let hits = check(&w, &kd.tree(scene).unwrap(), &rays, "blocks");
            assert!(hits > 100, "{hits} hits");
        }
    }
}

/// Leaf entries holding a triangle and a sphere or cone.
fn mixed_leaves(w: &WideBvh) -> usize {
    let (nodes, blocks) = w.parts();
    let nt = w.scene().triangles.len() as u32;
    let mut mixed = 0;
    for n in nodes {
        for i in 0..WIDTH {
            if n.child[i] != wide::EMPTY_SLOT && n.child[i] & wide::LEAF_BIT != 0 {
                let (f, count) = wide::leaf_run(n.child[i]);
                let run: Vec<u32> = blocks[f..f + count]
                    .iter()
                    .flat_map(|b| b.prims)
                    .filter(|&p| p != wide::NO_PRIM)
                    .collect();
                mixed += (run.iter().any(|&p| p < nt) && run.iter().any(|&p| p >= nt)) as usize;
            }
        }
    }
    mixed
}

/// Reading ahead changes no answer and no count: every ray's hit, any-hit
/// answer and statistics are the same with it on and off, on a scene of
/// triangles, spheres and cones at every leaf size. By default a
/// hierarchy reads ahead exactly when its nodes and corner blocks pass
/// `READ_AHEAD_BYTES`.
#[test]
fn reading_ahead_changes_no_answer() {
    let mut rng = Rng(47);
    let o = random_scene(&mut rng, 700, 150, 150, 8.0);
    let scene = o.scene();
    let rays = rays_with_parallels(&mut rng, &scene, 1500, 8.0);
    for leaf in [1, 4] {
        let owned = OwnedWide::new(&scene, leaf).unwrap();
        let w = owned.view(scene).unwrap();
        // Small: reads ahead only where every hierarchy does (x86-64).
        assert_eq!(w.read_ahead(), wide::READ_AHEAD_BYTES == 0);
        let (on, off) = (w.with_read_ahead(true), w.with_read_ahead(false));
        assert!(on.read_ahead() && !off.read_ahead());
        let mut stk = stack::<WideStackItem>(w.stack_len());
        let (mut st_on, mut st_off) = (TraceStats::default(), TraceStats::default());
        let mut hits = 0;
        for (i, r) in rays.iter().enumerate() {
            let a = on.intersect(r, &mut stk, &mut st_on);
            let b = off.intersect(r, &mut stk, &mut st_off);
            assert!(
                identical(&a, &b),
                "leaf {leaf} ray {i}: {a:?} against {b:?}"
            );
            assert_eq!(
                on.occluded(r, &mut stk, &mut st_on),
                off.occluded(r, &mut stk, &mut st_off),
                "leaf {leaf} ray {i}"
            );
            hits += a.is_hit() as usize;
        }
        assert!(hits > 500, "leaf {leaf}: {hits} hits");
        assert_eq!(st_on, st_off, "leaf {leaf}");
    }
    // The default follows the bytes: a view over more nodes than
    // `READ_AHEAD_BYTES` hold reads ahead, one over exactly that many not
    // (where that is a hierarchy: on x86-64 the bound is 0 and one node
    // reads ahead).
    let per = core::mem::size_of::<WideNode>();
    for (count, reads) in [
        (1, per > wide::READ_AHEAD_BYTES),
        (wide::READ_AHEAD_BYTES / per, false),
        (wide::READ_AHEAD_BYTES / per + 1, true),
    ] {
        if count == 0 {
            continue;
        }
        let nodes = vec![WideNode::default(); count];
        let info = wide::WideInfo {
            node_count: count as u32,
            ..Default::default()
        };
        let w = WideBvh::from_parts(Scene::default(), &nodes, &[], info).unwrap();
        assert_eq!(w.read_ahead(), reads, "{count} nodes");
    }
}

/// Rays whose box tests fall exactly on a face: the parallel-axis test
/// takes a face as inside (1 / 0 = inf would make 0 * inf NaN there).
#[test]
fn axis_parallel_rays_along_box_faces() {
    let mut o = OwnedScene::default();
    // Unit quads on the six faces of a cube, and one inside.
    for axis in 0..3 {
        for pos in [0.0, 1.0] {
            o.add_quad(axis, pos, [0.0, 0.0], [1.0, 1.0]);
        }
    }
    o.add_quad(1, 0.5, [0.25, 0.25], [0.75, 0.75]);
    let scene = o.scene();
    let kd = OwnedKd::new(&scene, &KdParams::auto()).unwrap();
    let tree = kd.tree(scene).unwrap();
    let mut rays = Vec::new();
    for axis in 0..3 {
        for u in [0.0, 0.25, 0.5, 1.0] {
            for v in [0.0, 0.5, 0.75, 1.0] {
                let mut from = Vec3::splat(0.0);
                let (a1, a2) = ((axis + 1) % 3, (axis + 2) % 3);
                from[a1] = u;
                from[a2] = v;
                from[axis] = -2.0;
                let mut d = Vec3::ZERO;
                d[axis] = 1.0;
                rays.push(Ray::new(from, d, 0.0, f32::INFINITY));
                from[axis] = 3.0;
                rays.push(Ray::new(from, -d, 0.0, f32::INFINITY));
            }
        }
    }
    for leaf in [1, 2] {
        let owned = OwnedWide::new(&scene, leaf).unwrap();
        let w = owned.view(scene).unwrap();
        w.validate().unwrap();
        let hits = check(&w, &tree, &rays, "faces");
        assert!(hits >= rays.len() / 2, "{hits} of {}", rays.len());
    }
}

#[test]
fn empty_single_and_degenerate_scenes() {
    let mut rng = Rng(5);
    let rays = random_rays(&mut rng, 200, 1.0);
    // Empty: one node with no entries, every ray misses.
    let empty = OwnedScene::default();
    let owned = OwnedWide::new(&empty.scene(), 1).unwrap();
    let w = owned.view(empty.scene()).unwrap();
    let shape = w.validate().unwrap();
    assert_eq!(
        (shape.nodes, shape.leaves, shape.refs, shape.depth),
        (1, 0, 0, 0)
    );
    let mut stk = stack::<WideStackItem>(w.stack_len());
    let mut st = TraceStats::default();
    for r in &rays {
        assert!(!w.intersect(r, &mut stk, &mut st).is_hit());
        assert!(!w.occluded(r, &mut stk, &mut st));
    }
    // One triangle: one node holding one leaf entry.
    let mut one = OwnedScene::default();
    one.add_triangle(Vec3::ZERO, Vec3::X, Vec3::Y);
    let owned = OwnedWide::new(&one.scene(), 1).unwrap();
    let w = owned.view(one.scene()).unwrap();
    let shape = w.validate().unwrap();
    assert_eq!(
        (shape.nodes, shape.leaves, shape.refs, shape.depth),
        (1, 1, 1, 0)
    );
    let down = Ray::new(Vec3::new(0.2, 0.2, 1.0), -Vec3::Z, 0.0, f32::INFINITY);
    assert_eq!(w.intersect(&down, &mut stk, &mut st).t, 1.0);
    // Degenerate triangles stay out: two of three references.
    let mut deg = one.clone();
    deg.add_triangle(Vec3::X, Vec3::X, Vec3::X);
    deg.add_triangle(Vec3::Z, Vec3::X + Vec3::Z, Vec3::Y + Vec3::Z);
    let owned = OwnedWide::new(&deg.scene(), 1).unwrap();
    let w = owned.view(deg.scene()).unwrap();
    let shape = w.validate().unwrap();
    assert_eq!((shape.nodes, shape.leaves, shape.refs), (1, 2, 2));
    assert_eq!(w.intersect(&down, &mut stk, &mut st).t, 0.0);
    assert_eq!(st.faults, 0);
}

/// Exact counts on a grid of 64 unit quads (128 triangles): leaves of one
/// primitive give 128 leaf entries and 128 blocks, every node full but the
/// last level's.
#[test]
fn grid_counts() {
    let mut o = OwnedScene::default();
    for i in 0..8 {
        for j in 0..8 {
            let (x, y) = (i as f32 * 2.0, j as f32 * 2.0);
            o.add_quad(2, 0.0, [x, y], [x + 1.0, y + 1.0]);
        }
    }
    let scene = o.scene();
    let owned = OwnedWide::new(&scene, 1).unwrap();
    let w = owned.view(scene).unwrap();
    let shape = w.validate().unwrap();
    assert_eq!((shape.refs, shape.leaves), (128, 128));
    assert_eq!(w.info().block_count, 128);
    // The SAH splits the grid into a perfect binary tree of depth 7; the
    // collapse takes three binary levels a node: 1 + 8 + 64 nodes, the
    // last level's holding two leaves each.
    assert_eq!((shape.nodes, shape.depth), (73, 2));
    assert!(w.parts().0.iter().all(|n| n.len() == WIDTH || n.len() == 2));
}

/// A build fits in exactly the requirements and refuses one node or one
/// leaf block less.
#[test]
fn exact_fit_and_one_less() {
    let mut rng = Rng(8);
    let o = random_scene(&mut rng, 300, 40, 40, 5.0);
    let scene = o.scene();
    let req = wide::requirements(scene.prim_count());
    for (less_nodes, less_blocks) in [(0, 0), (1, 0), (0, 1)] {
        let mut nodes = vec![WideNode::default(); req.nodes - less_nodes];
        let mut refs = vec![0u32; req.refs];
        let mut blocks = vec![wide::EMPTY_BLOCK; req.blocks - less_blocks];
        let mut bvh_nodes = vec![coray::bvh::BvhNode::default(); req.bvh_nodes];
        let mut boxes = vec![Aabb::EMPTY; req.boxes];
        let mut keys = vec![0.0; req.keys];
        let mut links = vec![0u32; req.links];
        let r = wide::build(
            &scene,
            2,
            WideStorage {
                nodes: &mut nodes,
                blocks: &mut blocks,
            },
            WideScratch {
                refs: &mut refs,
                bvh_nodes: &mut bvh_nodes,
                boxes: &mut boxes,
                keys: &mut keys,
                links: &mut links,
            },
        );
        match (less_nodes, less_blocks) {
            (0, 0) => {
                let w = r.unwrap();
                w.validate().unwrap();
                assert!(w.info().node_count as usize <= req.nodes);
            }
            (1, _) => assert!(matches!(
                r.map(|_| ()),
                Err(Error::SliceTooSmall { slice: "nodes", .. })
            )),
            _ => assert!(matches!(
                r.map(|_| ()),
                Err(Error::SliceTooSmall {
                    slice: "blocks",
                    ..
                })
            )),
        }
    }
}

/// A stack shorter than `stack_len` ends the walk with a fault, never a
/// panic; the Accel contract refuses it up front.
#[test]
fn short_stack_faults() {
    use coray::Accel;
    let mut rng = Rng(9);
    let o = random_scene(&mut rng, 500, 0, 0, 5.0);
    let scene = o.scene();
    let owned = OwnedWide::new(&scene, 1).unwrap();
    let w = owned.view(scene).unwrap();
    let rays = random_rays(&mut rng, 100, 5.0);
    let mut st = TraceStats::default();
    let mut short = stack::<WideStackItem>(2);
    for r in &rays {
        w.intersect(r, &mut short, &mut st);
    }
    assert!(st.faults > 0);
    assert!(Accel::intersect(&w, &rays[0], (), &mut short, &mut st).is_err());
    assert!(WideBvh::intersect(&w, &rays[0], &mut [], &mut st) == Hit::MISS);
}

/// Rays whose direction has a component so small that its inverse
/// overflows (subnormal), started on faces, edges and corners of the
/// scene's boxes: the slab test takes that axis as parallel, as the
/// kd-tree's clip does (`(face - origin) * inf` would be NaN on a face and
/// cull the box). The closest `t` and the any-hit answer are the oracle's.
#[test]
fn overflowing_inverse_directions_match_the_oracle() {
    let (o, rays) = faces_and_tiny_directions();
    check_with_leaves(&o, &rays, rays.len() / 2);
}

/// Rays through the edges and corners of a lattice of boxes find the
/// triangles that touch a corner from a diagonal cell.
#[test]
fn rays_through_box_edges_and_corners_match_the_oracle() {
    let (o, rays) = lattice_corners();
    check_with_leaves(&o, &rays, 60);
}

/// The wide hierarchy at leaves of 1 and 4 against the oracle on `rays`:
/// closest `t`, any-hit answers, more than `min_hits` hits.
fn check_with_leaves(o: &OwnedScene, rays: &[Ray], min_hits: usize) {
    let scene = o.scene();
    for leaf in [1, 4] {
        let owned = OwnedWide::new(&scene, leaf).unwrap();
        let w = owned.view(scene).unwrap();
        let mut stk = stack::<WideStackItem>(w.stack_len());
        let mut st = TraceStats::default();
        let mut hits = 0;
        for (i, r) in rays.iter().enumerate() {
            let want = oracle::intersect(&scene, r);
            let t = |h: &Hit| h.is_hit().then_some(h.t);
            let got = w.intersect(r, &mut stk, &mut st);
            assert_eq!(t(&got), t(&want), "leaf {leaf} ray {i} {r:?}");
            let any = w.occluded(r, &mut stk, &mut st);
            assert_eq!(any, oracle::occluded(&scene, r), "leaf {leaf} ray {i}");
            hits += got.is_hit() as usize;
        }
        assert_eq!(st.faults, 0);
        assert!(hits > min_hits, "leaf {leaf}: {hits} of {} hit", rays.len());
    }
}
