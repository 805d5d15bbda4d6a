//! Every hierarchy builder against the brute-force oracle; memory bounds;
//! R-tree insert and delete.
mod common;

use common::*;
use coray::bvh::{
    self, Builder, Bvh, BvhNode, BvhScratch, BvhStackItem, BvhStorage, InsertOrder, RTree,
    RTreeParams, Split,
};
use coray::TraceStats;
use coray::{oracle, Aabb, Error, Hit, Ray, Scene};

/// Storage for a static build, sized by `requirements` minus `less` nodes.
struct Static {
    nodes: Vec<BvhNode>,
    refs: Vec<u32>,
    boxes: Vec<Aabb>,
    keys: Vec<f32>,
    links: Vec<u32>,
    clusters: Vec<BvhNode>,
}

impl Static {
    fn new(n: usize, b: Builder, less: usize) -> Static {
        let r = bvh::requirements(n, b);
        Static {
            nodes: vec![BvhNode::default(); r.nodes - less],
            refs: vec![0; r.refs],
            boxes: vec![Aabb::EMPTY; r.boxes],
            keys: vec![0.0; r.keys],
            links: vec![0; r.links],
            clusters: vec![BvhNode::default(); r.clusters],
        }
    }
    fn build<'a>(&'a mut self, scene: &Scene<'a>, b: Builder) -> Result<Bvh<'a>, Error> {
        let storage = BvhStorage {
            nodes: &mut self.nodes,
            refs: &mut self.refs,
        };
        let scratch = BvhScratch {
            boxes: &mut self.boxes,
            keys: &mut self.keys,
            links: &mut self.links,
            clusters: &mut self.clusters,
        };
        bvh::build(scene, b, 1, storage, scratch)
    }
}

fn same(a: &Hit, b: &Hit) -> bool {
    a.is_hit() == b.is_hit() && (!a.is_hit() || a.t == b.t)
}

/// Closest and any hit of `bvh` against `want` (closest) for every ray;
/// returns the hits seen.
fn check(bvh: &Bvh, rays: &[Ray], what: &str, want: impl Fn(&Ray) -> (Hit, bool)) -> usize {
    let mut stack = vec![BvhStackItem::default(); bvh.stack_len()];
    let mut hits = 0;
    for (i, r) in rays.iter().enumerate() {
        let (w, w_any) = want(r);
        let mut st = TraceStats::default();
        let got = bvh.intersect(r, &mut stack, &mut st);
        assert!(
            same(&got, &w),
            "{what}: ray {i} {r:?}: got {got:?}, want {w:?}"
        );
        assert_eq!(
            bvh.occluded(r, &mut stack, &mut st),
            w_any,
            "{what}: ray {i} occluded"
        );
        assert_eq!(st.rays, 2);
        if bvh.info().ref_count > 0 {
            assert!(st.box_tests >= 2 && st.box_cost >= 2 * st.box_tests);
        }
        hits += w.is_hit() as usize;
    }
    hits
}

fn oracle_of<'a>(scene: &'a Scene<'a>) -> impl Fn(&Ray) -> (Hit, bool) + 'a {
    move |r| (oracle::intersect(scene, r), oracle::occluded(scene, r))
}

const STATIC: [Builder; 4] = [
    Builder::Tdbs,
    Builder::TdbsSah,
    Builder::Nn,
    Builder::NnChain,
];

fn rtree_params() -> Vec<(String, RTreeParams)> {
    let mut v = Vec::new();
    for split in [Split::Quadratic, Split::RStar] {
        for order in [
            InsertOrder::Scene,
            InsertOrder::Shuffled(7),
            InsertOrder::Sorted,
        ] {
            for (big, small) in [(4, 2), (8, 3), (32, 12)] {
                v.push((
                    format!("{split:?}/{order:?}/M{big}m{small}"),
                    RTreeParams {
                        split,
                        max_children: big,
                        min_children: small,
                        order,
                        forced_reinsert: false,
                    },
                ));
            }
            for (big, small) in [(4, 2), (8, 3), (32, 12)] {
                v.push((
                    format!("{split:?}/{order:?}/M{big}m{small}/reinsert"),
                    RTreeParams {
                        split,
                        max_children: big,
                        min_children: small,
                        order,
                        forced_reinsert: true,
                    },
                ));
            }
        }
    }
    v
}

fn build_rtree<'a>(
    scene: &Scene<'a>,
    p: RTreeParams,
    nodes: &'a mut Vec<BvhNode>,
    refs: &'a mut Vec<u32>,
) -> RTree<'a> {
    let req = RTree::requirements(scene.prim_count(), &p);
    nodes.resize(req.nodes, BvhNode::default());
    refs.resize(req.refs, 0);
    let mut order = vec![0u32; req.scratch];
    RTree::build(scene, p, nodes, refs, &mut order).expect("room from RTree::requirements")
}

#[test]
fn every_builder_matches_the_oracle() {
    let mut rng = Rng(11);
    let o = random_scene(&mut rng, 900, 200, 200, 10.0);
    let scene = o.scene();
    let rays = random_rays(&mut rng, 1500, 10.0);
    let n = scene.prim_count();
    for b in STATIC {
        let mut s = Static::new(n, b, 0);
        let bvh = s.build(&scene, b).unwrap();
        let v = bvh
            .validate(None, &mut vec![BvhStackItem::default(); bvh.stack_len()])
            .unwrap();
        assert_eq!(v.refs as usize, n, "{b:?}");
        assert_eq!(v.leaves as usize, n, "{b:?}: one object per leaf");
        assert_eq!(bvh.info().node_count as usize, 2 * n - 1, "{b:?}");
        let hits = check(&bvh, &rays, &format!("{b:?}"), oracle_of(&scene));
        assert!(hits > 300, "{b:?}: {hits} hits");
    }
    for (name, p) in rtree_params() {
        let (mut nodes, mut refs) = (Vec::new(), Vec::new());
        let t = build_rtree(&scene, p, &mut nodes, &mut refs);
        assert_eq!(t.len() as usize, n);
        let v = t
            .validate(&mut vec![BvhStackItem::default(); t.bvh().stack_len()])
            .unwrap();
        assert_eq!(v.refs as usize, n, "{name}");
        assert_eq!(v.nodes, t.bvh().info().node_count, "{name}");
        let bvh = t.bvh();
        check(&bvh, &rays, &name, oracle_of(&scene));
    }
}

#[test]
fn empty_single_and_degenerate_scenes() {
    let mut o = OwnedScene::default();
    // Degenerate only: nothing enters the hierarchy.
    o.add_triangle(coray::Vec3::ZERO, coray::Vec3::ZERO, coray::Vec3::X);
    let scene = o.scene();
    let rays = random_rays(&mut Rng(3), 50, 2.0);
    for b in STATIC {
        let mut s = Static::new(scene.prim_count(), b, 0);
        let bvh = s.build(&scene, b).unwrap();
        assert_eq!(bvh.info().ref_count, 0);
        bvh.validate(None, &mut vec![BvhStackItem::default(); bvh.stack_len()])
            .unwrap();
        check(&bvh, &rays, "degenerate", oracle_of(&scene));
    }
    o.add_triangle(
        coray::Vec3::new(-1.0, -1.0, 0.0),
        coray::Vec3::new(1.0, -1.0, 0.0),
        coray::Vec3::new(0.0, 1.0, 0.0),
    );
    let scene = o.scene();
    for b in STATIC {
        let mut s = Static::new(scene.prim_count(), b, 0);
        let bvh = s.build(&scene, b).unwrap();
        assert_eq!((bvh.info().ref_count, bvh.info().depth), (1, 0));
        check(&bvh, &rays, "single", oracle_of(&scene));
    }
    for (name, p) in rtree_params() {
        let (mut nodes, mut refs) = (Vec::new(), Vec::new());
        let t = build_rtree(&scene, p, &mut nodes, &mut refs);
        assert_eq!(t.len(), 1, "{name}");
        check(&t.bvh(), &rays, &name, oracle_of(&scene));
    }
}

/// The interior boxes of a hierarchy, sorted: two builds made the same
/// joins exactly when these agree.
fn joins(bvh: &Bvh) -> Vec<[u32; 6]> {
    let mut v: Vec<[u32; 6]> = bvh.parts().0[..bvh.info().node_count as usize]
        .iter()
        .filter(|n| !n.is_leaf())
        .map(|n| {
            let b = n.bounds();
            [b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z].map(f32::to_bits)
        })
        .collect();
    v.sort_unstable();
    v
}

/// The nearest-neighbour chain makes the same joins as the thesis'
/// quadratic search (random boxes: no exact ties), and nearly all of them
/// on a symmetric SPD scene.
#[test]
fn nn_chain_makes_the_quadratic_joins() {
    let mut rng = Rng(8);
    for (nt, ns, nc) in [(2, 0, 0), (3, 1, 0), (40, 10, 10), (700, 150, 150)] {
        let o = random_scene(&mut rng, nt, ns, nc, 10.0);
        let scene = o.scene();
        let n = scene.prim_count();
        let mut a = Static::new(n, Builder::Nn, 0);
        let mut b = Static::new(n, Builder::NnChain, 0);
        let (qa, qb) = (
            a.build(&scene, Builder::Nn).unwrap(),
            b.build(&scene, Builder::NnChain).unwrap(),
        );
        qb.validate(None, &mut vec![BvhStackItem::default(); qb.stack_len()])
            .unwrap();
        assert_eq!(joins(&qa), joins(&qb), "n = {n}");
        assert_eq!(qa.info().depth, qb.info().depth, "n = {n}");
    }
    use coray_scenes::spd::{generate, Options};
    let m = coray_scenes::SceneMesh::from_nff(
        &generate("balls", Some(2), &Options::default()).unwrap(),
    );
    let scene = m.scene();
    let n = scene.prim_count();
    let mut a = Static::new(n, Builder::Nn, 0);
    let mut b = Static::new(n, Builder::NnChain, 0);
    let (qa, qb) = (
        a.build(&scene, Builder::Nn).unwrap(),
        b.build(&scene, Builder::NnChain).unwrap(),
    );
    // The sphereflake is symmetric: equal joint areas are common, and the
    // two searches may break those ties differently, then diverge a little.
    let (ja, jb) = (joins(&qa), joins(&qb));
    let shared = ja.iter().filter(|j| jb.binary_search(j).is_ok()).count();
    assert_eq!(ja.len(), jb.len());
    assert!(
        shared * 10 >= ja.len() * 9,
        "balls 2: {shared} of {} joins shared",
        ja.len()
    );
}

/// Forced reinsertion changes the tree (it is not a no-op) and keeps it
/// exact; a tree built with it holds the same objects.
#[test]
fn forced_reinsertion_changes_the_tree() {
    let mut rng = Rng(12);
    let o = random_scene(&mut rng, 800, 200, 0, 10.0);
    let scene = o.scene();
    let rays = random_rays(&mut rng, 500, 10.0);
    let mut built = Vec::new();
    for forced_reinsert in [false, true] {
        let p = RTreeParams {
            forced_reinsert,
            ..RTreeParams::rstar()
        };
        let (mut nodes, mut refs) = (Vec::new(), Vec::new());
        let t = build_rtree(&scene, p, &mut nodes, &mut refs);
        t.validate(&mut vec![BvhStackItem::default(); t.bvh().stack_len()])
            .unwrap();
        check(&t.bvh(), &rays, "reinsert", oracle_of(&scene));
        built.push(joins(&t.bvh()));
    }
    assert_ne!(built[0], built[1]);
}

/// Coincident copies (equal t): every hierarchy reports the lowest index,
/// as the oracle does, whatever order it meets them in.
#[test]
fn ties_go_to_the_lowest_index() {
    let mut o = OwnedScene::default();
    for _ in 0..40 {
        o.add_triangle(
            coray::Vec3::new(-1.0, -1.0, 0.2),
            coray::Vec3::new(1.0, -1.0, 0.0),
            coray::Vec3::new(0.0, 1.0, -0.2),
        );
    }
    let scene = o.scene();
    let rays = random_rays(&mut Rng(6), 600, 1.0);
    let mut hits = 0;
    for b in STATIC {
        let mut s = Static::new(scene.prim_count(), b, 0);
        let bvh = s.build(&scene, b).unwrap();
        let mut stack = vec![BvhStackItem::default(); bvh.stack_len()];
        for r in &rays {
            let want = oracle::intersect(&scene, r);
            let got = bvh.intersect(r, &mut stack, &mut TraceStats::default());
            assert_eq!((got.prim_id, got.t), (want.prim_id, want.t), "{b:?} {r:?}");
            hits += got.is_hit() as usize;
        }
    }
    assert!(hits > 200, "{hits}");
}

/// Static builds: exactly `requirements` succeeds, one node less fails
/// with the slice and count needed.
#[test]
fn exact_fit_and_one_less() {
    let mut rng = Rng(5);
    for n in [1usize, 2, 3, 7, 200] {
        let o = random_scene(&mut rng, n, 0, 0, 5.0);
        let scene = o.scene();
        for b in STATIC {
            let need = bvh::requirements(n, b).nodes;
            let mut s = Static::new(n, b, 0);
            let bvh = s.build(&scene, b).unwrap();
            assert_eq!(bvh.info().node_count as usize, need, "{b:?} n={n}");
            let mut s = Static::new(n, b, 1);
            match s.build(&scene, b) {
                Err(Error::SliceTooSmall { slice, needed, got }) => {
                    assert_eq!((slice, needed, got), ("nodes", need, need - 1));
                }
                other => panic!("{b:?} n={n}: {:?}", other.map(|t| *t.info())),
            }
        }
    }
}

/// Inserting into a full R-tree returns a capacity status and leaves a
/// valid tree holding everything inserted before.
#[test]
fn rtree_insert_into_a_full_arena() {
    let mut rng = Rng(9);
    let o = random_scene(&mut rng, 600, 0, 0, 5.0);
    let scene = o.scene();
    let reinsert = RTreeParams {
        forced_reinsert: true,
        ..RTreeParams::rstar()
    };
    for p in [RTreeParams::rtree(), RTreeParams::rstar(), reinsert] {
        let req = RTree::requirements(100, &p);
        let mut nodes = vec![BvhNode::default(); req.nodes];
        let mut refs = vec![0u32; req.refs];
        let mut t = RTree::new(&scene, p, &mut nodes, &mut refs).unwrap();
        let mut inserted = 0;
        let err = loop {
            match t.insert(inserted) {
                Ok(()) => inserted += 1,
                Err(e) => break e,
            }
            assert!(inserted < 600, "{p:?}: never full");
        };
        assert!(matches!(err, Error::SliceTooSmall { .. }), "{err:?}");
        assert!(
            inserted >= 100,
            "{p:?}: full after {inserted} of the 100 it was sized for"
        );
        assert_eq!(t.len(), inserted);
        t.validate(&mut vec![BvhStackItem::default(); t.bvh().stack_len()])
            .unwrap();
        let bvh = t.bvh();
        // It holds exactly the first `inserted` triangles.
        let rays = random_rays(&mut rng, 400, 5.0);
        check(&bvh, &rays, "full", |r| brute(&scene, r, |q| q < inserted));
    }
}

/// Brute force over the primitives `keep` selects.
fn brute(scene: &Scene, r: &Ray, keep: impl Fn(u32) -> bool) -> (Hit, bool) {
    let pr = coray::geom::PreparedRay::new(r);
    let mut best = Hit::MISS;
    for p in 0..scene.prim_count() as u32 {
        if keep(p) {
            let limit = if best.is_hit() { best.t } else { r.t_max };
            if let Some(h) = scene.intersect_prim(p as usize, &pr, limit) {
                best = h;
            }
        }
    }
    (best, best.is_hit())
}

/// Deleting objects (with CondenseTree) keeps a valid tree that finds
/// exactly the objects left; deleting an absent object reports false.
#[test]
fn rtree_delete_and_reinsert() {
    let mut rng = Rng(21);
    let o = random_scene(&mut rng, 500, 100, 0, 5.0);
    let scene = o.scene();
    let n = scene.prim_count() as u32;
    let rays = random_rays(&mut rng, 300, 5.0);
    let reinsert = RTreeParams {
        forced_reinsert: true,
        ..RTreeParams::rstar()
    };
    for p in [RTreeParams::rtree(), RTreeParams::rstar(), reinsert] {
        let (mut nodes, mut refs) = (Vec::new(), Vec::new());
        let mut t = build_rtree(&scene, p, &mut nodes, &mut refs);
        let mut orphans = vec![0u32; n as usize];
        let mut gone = vec![false; n as usize];
        for round in 0..4 {
            for _ in 0..120 {
                let q = rng.below(n as usize) as u32;
                let was = t.delete(q, &mut orphans).unwrap();
                assert_eq!(was, !gone[q as usize], "{p:?}: delete {q}");
                gone[q as usize] = true;
            }
            let left = gone.iter().filter(|g| !**g).count() as u32;
            assert_eq!(t.len(), left);
            let v = t
                .validate(&mut vec![BvhStackItem::default(); t.bvh().stack_len()])
                .unwrap();
            assert_eq!(v.nodes, t.bvh().info().node_count);
            let bvh = t.bvh();
            check(&bvh, &rays, &format!("{p:?} round {round}"), |r| {
                brute(&scene, r, |q| !gone[q as usize])
            });
        }
        // Everything out, then back in.
        for q in 0..n {
            t.delete(q, &mut orphans).unwrap();
        }
        assert!(t.is_empty());
        t.validate(&mut vec![BvhStackItem::default(); t.bvh().stack_len()])
            .unwrap();
        for q in 0..n {
            t.insert(q).unwrap();
        }
        check(&t.bvh(), &rays, "reinserted", oracle_of(&scene));
        // Taken up again from its slices and state, it is the same tree.
        let state = t.state();
        // (`t` is not used again: its borrow of the slices ends here.)
        let mut t = RTree::resume(&scene, p, &mut nodes, &mut refs, state).unwrap();
        t.validate(&mut vec![BvhStackItem::default(); t.bvh().stack_len()])
            .unwrap();
        t.delete(0, &mut orphans).unwrap();
        check(&t.bvh(), &rays, "resumed", |r| brute(&scene, r, |q| q != 0));
        // A corrupt free list is caught by validate, a bad state by resume.
        let mut bad = t.state();
        bad.free_node_blocks += 1;
        let state = t.state();
        assert!(RTree::resume(&scene, p, &mut nodes, &mut refs, bad)
            .map(|t| t
                .validate(&mut vec![BvhStackItem::default(); t.bvh().stack_len()])
                .is_err())
            .unwrap_or(true));
        bad = state;
        bad.node_blocks = u32::MAX / 64;
        assert!(RTree::resume(&scene, p, &mut nodes, &mut refs, bad).is_err());
    }
}

/// Rays whose direction has a component so small that its inverse
/// overflows, started on faces, edges and corners of boxes: the slab test
/// takes that axis as parallel (`(face - origin) * inf` would be NaN on a
/// face and cull the box), so every builder's hierarchy answers as the
/// oracle, closest `t` and any hit.
#[test]
fn overflowing_inverse_directions_match_the_oracle() {
    let (o, rays) = faces_and_tiny_directions();
    check_builders(&o, &rays, rays.len() / 2);
}

/// Rays through the edges and corners of a lattice of boxes find the
/// triangles that touch a corner from a diagonal cell.
#[test]
fn rays_through_box_edges_and_corners_match_the_oracle() {
    let (o, rays) = lattice_corners();
    check_builders(&o, &rays, 60);
}

/// Every static builder and the R-trees against the oracle on `rays`, more
/// than `min_hits` of them hitting.
fn check_builders(o: &OwnedScene, rays: &[Ray], min_hits: usize) {
    let scene = o.scene();
    let n = scene.prim_count();
    for b in STATIC {
        let mut s = Static::new(n, b, 0);
        let bvh = s.build(&scene, b).unwrap();
        let hits = check(&bvh, rays, &format!("{b:?}"), oracle_of(&scene));
        assert!(hits > min_hits, "{b:?}: {hits} of {} hit", rays.len());
    }
    for (name, p) in rtree_params() {
        let (mut nodes, mut refs) = (Vec::new(), Vec::new());
        let t = build_rtree(&scene, p, &mut nodes, &mut refs);
        check(&t.bvh(), rays, &name, oracle_of(&scene));
    }
}
