//! The kd build as jobs (`build_begin`, `KdJob::run`, `finish`) against the
//! one-pass depth-first build: the same bytes whatever runs the jobs, in
//! whatever order, on however many threads.

mod common;

use common::{random_scene, with_empty_leaves, Rng};
use coray::kd::{
    self, KdEvent, KdInfo, KdJobReport, KdNode, KdParams, KdRequirements, KdRopes, KdScratch,
    KdStorage, KD_FLAG_ROPES, KD_FLAG_TRUNCATED,
};
use coray::Scene;
use coray_scenes::spd::{self, Options};
use coray_scenes::SceneMesh;

/// A build's slices, owned.
struct Room {
    nodes: Vec<KdNode>,
    ropes: Vec<KdRopes>,
    rope_ids: Vec<u32>,
    refs: Vec<u32>,
    events: Vec<KdEvent>,
    flags: Vec<u8>,
}

impl Room {
    fn new(r: &KdRequirements) -> Room {
        Room {
            nodes: vec![KdNode::default(); r.nodes],
            ropes: vec![KdRopes::default(); r.ropes],
            rope_ids: vec![0; r.rope_ids],
            refs: vec![0; r.refs],
            events: vec![KdEvent::default(); r.events],
            flags: vec![0; r.prim_flags],
        }
    }
    fn parts(&mut self) -> (KdStorage<'_>, KdScratch<'_>) {
        (
            KdStorage {
                nodes: &mut self.nodes,
                ropes: &mut self.ropes,
                rope_ids: &mut self.rope_ids,
                refs: &mut self.refs,
            },
            KdScratch {
                events: &mut self.events,
                prim_flags: &mut self.flags,
            },
        )
    }
}

/// What a tree is, byte for byte: its info and its four parts.
#[derive(Debug, PartialEq)]
struct Made {
    info: KdInfo,
    nodes: Vec<KdNode>,
    ropes: Vec<KdRopes>,
    rope_ids: Vec<u32>,
    refs: Vec<u32>,
}

fn made(t: &kd::KdTree) -> Made {
    t.validate().expect("validate");
    let (nodes, ropes, rope_ids, refs) = t.parts();
    Made {
        info: *t.info(),
        nodes: nodes.to_vec(),
        ropes: ropes.to_vec(),
        rope_ids: rope_ids.to_vec(),
        refs: refs.to_vec(),
    }
}

fn depth_first(scene: &Scene, params: &KdParams, req: &KdRequirements) -> Made {
    let mut room = Room::new(req);
    let (storage, scratch) = room.parts();
    made(&kd::build_depth_first(scene, params, storage, scratch).expect("build"))
}

/// How the jobs are run.
#[derive(Clone, Copy, Debug)]
enum Run {
    /// None: `finish` runs them all.
    ByFinish,
    /// Last first, each with its own flags.
    Reversed,
    /// Shared out to this many threads.
    Threads(usize),
}

fn by_jobs(
    scene: &Scene,
    params: &KdParams,
    req: &KdRequirements,
    run: Run,
) -> (Made, KdJobReport) {
    let mut room = Room::new(req);
    let (storage, scratch) = room.parts();
    // Jobs made for the threads that will run them (as many as not known
    // otherwise).
    let threads = match run {
        Run::Threads(t) => t,
        _ => 0,
    };
    let mut b =
        kd::build_begin_for_threads(scene, params, storage, scratch, threads).expect("begin");
    let jobs = b.job_count();
    let n = scene.prim_count();
    match run {
        Run::ByFinish => {}
        Run::Reversed => {
            let all: Vec<_> = b.jobs().collect();
            assert_eq!(all.len(), jobs);
            for job in all.into_iter().rev() {
                job.run(&mut vec![0xA5; n]).expect("run");
            }
        }
        Run::Threads(t) => {
            let queue = std::sync::Mutex::new(b.jobs().collect::<Vec<_>>());
            std::thread::scope(|s| {
                for _ in 0..t {
                    s.spawn(|| {
                        let mut flags = vec![0u8; n];
                        while let Some(job) = queue.lock().unwrap().pop() {
                            job.run(&mut flags).expect("run");
                        }
                    });
                }
            });
        }
    }
    let (tree, report) = b.finish_with_report().expect("finish");
    assert_eq!(report.jobs, jobs);
    (made(&tree), report)
}

fn spd_mesh(name: &str, size: Option<u32>) -> SceneMesh {
    SceneMesh::from_nff(&spd::generate(name, size, &Options::default()).unwrap())
}

/// Every way of running the jobs gives the same bytes, the depth-first
/// build's when that one is not truncated, and the scene was cut into
/// several jobs. Returns whether the depth-first build was truncated, and
/// that build.
fn check_equal(scene: &Scene, params: &KdParams, what: &str) -> (bool, Made) {
    let req = kd::requirements(scene.prim_count(), params);
    let reference = depth_first(scene, params, &req);
    let truncated = reference.info.flags & KD_FLAG_TRUNCATED != 0;
    let mut first: Option<Made> = None;
    for run in [
        Run::ByFinish,
        Run::Reversed,
        Run::Threads(3),
        Run::Threads(2),
    ] {
        let (m, report) = by_jobs(scene, params, &req, run);
        assert!(report.jobs >= 2, "{what}: {report:?}");
        if truncated {
            // The depth-first build spends the room on the subtrees it
            // reaches first; when every job fits its share, the job build
            // is the untruncated tree, else it is the depth-first one.
            if m.info.flags & KD_FLAG_TRUNCATED != 0 {
                assert!(m == reference, "{what} {run:?}: the fallback differs");
            }
            if let Some(f) = &first {
                assert!(&m == f, "{what} {run:?}: runs differ");
            }
            first = Some(m);
        } else {
            // Made by the jobs, not by the one-pass fallback.
            assert!(!report.one_pass, "{what}: {report:?}");
            assert!(m == reference, "{what} {run:?}: the job build differs");
        }
    }
    (truncated, reference)
}

/// The trees themselves are pinned too: a change that means to make the
/// build faster must leave every tree as it was (these digests are taken
/// in the layout of a159a8c, `auto` with ropes as every tree had then;
/// `paper`'s are a159a8c's trees, `auto`'s those that costing references,
/// `KdParams::cost_reference`, made). A change that means to make other
/// trees updates them, and shows in its message what the new trees trace
/// like.
const PINNED: [(&str, u64, u64); 8] = [
    ("balls", 0x547a7f8d966c1688, 0x0d62d546331a9f41),
    ("gears", 0x1921d685876db7bc, 0x7c3ee7c8ba72459f),
    ("lattice", 0xf3509eea6a1b0056, 0x757537e532e584d4),
    ("mount", 0xb50751e0706a2a36, 0x1a3331569486fb64),
    ("rings", 0x384ccea214729f2f, 0xf5de540b458671ef),
    ("teapot", 0xc700aab3c9b27eed, 0x691424b4c8d73566),
    ("tetra", 0x117416b91fc79c06, 0x117416b91fc79c06),
    ("tree", 0xb96285487ad5315e, 0xd7e19bcedf884d9f),
];

#[test]
fn job_build_equals_depth_first_on_spd_scenes_whose_trees_are_pinned() {
    let mut truncated = Vec::new();
    let mut digests = Vec::new();
    let mut elided = Vec::new();
    for &(name, _) in spd::SCENES {
        let mesh = spd_mesh(name, None);
        let scene = mesh.scene();
        let mut check = |params: KdParams| {
            let (t, reference) = check_equal(&scene, &params, &format!("{name} {params:?}"));
            if t {
                truncated.push((name, params.sah_termination));
            }
            reference
        };
        // `auto` builds no ropes: its jobs run without rope slots. The tree
        // is `auto` with ropes less its ropes (pinned with them).
        let (auto, paper) = (check(KdParams::auto()), check(KdParams::paper()));
        // Compact: `auto` less its empty leaves beside full ones (node 1
        // stands for them); put back, `auto`'s nodes.
        let compact = check(KdParams::compact());
        let put_back = with_empty_leaves(&compact.nodes);
        assert!(
            put_back == auto.nodes && compact.refs == auto.refs,
            "{name}"
        );
        assert_eq!(
            KdInfo {
                flags: auto.info.flags | kd::KD_FLAG_COMPACT,
                node_count: compact.info.node_count,
                node_digest: compact.info.node_digest,
                ..auto.info
            },
            compact.info,
            "{name}"
        );
        elided.push(auto.nodes.len() + 1 - compact.nodes.len());
        let with_ropes = KdParams::auto_with_ropes();
        let roped = depth_first(
            &scene,
            &with_ropes,
            &kd::requirements(scene.prim_count(), &with_ropes),
        );
        assert!(auto.ropes.is_empty() && auto.rope_ids.is_empty(), "{name}");
        assert!(!auto.info.has_ropes(), "{name}");
        assert_eq!(roped.ropes.len(), roped.info.leaf_count as usize, "{name}");
        assert_eq!(roped.rope_ids.len(), roped.nodes.len(), "{name}");
        assert_eq!(
            KdInfo {
                flags: roped.info.flags & !KD_FLAG_ROPES,
                ..roped.info
            },
            auto.info,
            "{name}"
        );
        assert!(
            (&roped.nodes, &roped.refs) == (&auto.nodes, &auto.refs),
            "{name}: the ropes changed the tree"
        );
        digests.push((name, tree_digest(&roped), tree_digest(&paper)));
    }
    // Every tree fits the default room (gears too, since references are
    // costed: it wants 26 per primitive under the plain SAH).
    assert_eq!(truncated, []);
    // Empty leaves compact trees leave out, per scene (all of `auto`'s).
    assert_eq!(elided, [1314, 10632, 0, 6040, 7044, 7531, 1364, 6211]);
    assert_eq!(digests, PINNED, "digests (name, auto, paper)");
}

#[test]
fn job_build_equals_depth_first_on_random_scenes() {
    let mut rng = Rng(7);
    for (tris, spheres, cones) in [(3000, 300, 100), (5000, 0, 0), (0, 2000, 500)] {
        let o = random_scene(&mut rng, tris, spheres, cones, 10.0);
        for params in [KdParams::auto(), KdParams::compact()] {
            let what = format!("random {tris} {params:?}");
            assert!(!check_equal(&o.scene(), &params, &what).0);
        }
    }
}

/// Jobs made for two threads are fewer than those made for an unknown
/// number, and those for sixteen more; the tree is the same.
#[test]
fn the_thread_count_sets_the_number_of_jobs_not_the_tree() {
    let mut rng = Rng(11);
    let o = random_scene(&mut rng, 4000, 300, 100, 10.0);
    let (scene, params) = (o.scene(), KdParams::auto());
    let req = kd::requirements(scene.prim_count(), &params);
    let reference = depth_first(&scene, &params, &req);
    let mut counts = Vec::new();
    for threads in [2, 0, 16] {
        let mut room = Room::new(&req);
        let (storage, scratch) = room.parts();
        let b = kd::build_begin_for_threads(&scene, &params, storage, scratch, threads).unwrap();
        counts.push(b.job_count());
        let tree = b.finish().unwrap();
        assert!(
            made(&tree) == reference,
            "{threads} threads: the tree differs"
        );
    }
    assert!(counts[0] < counts[1] && counts[1] < counts[2], "{counts:?}");
}

/// One thread gets one job, the whole tree in all the room: no share to
/// outgrow; the depth-first build's tree.
#[test]
fn one_thread_gets_one_job() {
    let mesh = spd_mesh("teapot", None);
    let scene = mesh.scene();
    let params = KdParams::auto();
    let req = kd::requirements(scene.prim_count(), &params);
    let reference = depth_first(&scene, &params, &req);
    let (m, report) = by_jobs(&scene, &params, &req, Run::Threads(1));
    assert_eq!(report.jobs, 1, "{report:?}");
    assert_eq!((report.reruns, report.one_pass), (0, false), "{report:?}");
    assert!(m == reference);
}

/// At the ideal room SPD gears' jobs for two threads fit their shares:
/// its tree takes 3.9 references per primitive and one of its two jobs
/// more than 4, so before the references' slack (`kd::REFS_SLACK`) that
/// job ran out of its share and ran again alone in `finish`.
#[test]
fn gears_jobs_for_two_threads_fit_their_shares_at_the_ideal_room() {
    let mesh = spd_mesh("gears", None);
    let scene = mesh.scene();
    let params = KdParams::auto();
    let req = kd::requirements(scene.prim_count(), &params);
    let reference = depth_first(&scene, &params, &req);
    let (m, report) = by_jobs(&scene, &params, &req, Run::Threads(2));
    assert_eq!(report.jobs, 2, "{report:?}");
    assert_eq!((report.reruns, report.one_pass), (0, false), "{report:?}");
    assert!(m == reference);
}

/// With the least room every job runs out of its share; `finish` then
/// builds in one pass: the depth-first build's (truncated) tree.
#[test]
fn job_build_falls_back_to_one_pass_when_a_share_runs_out() {
    let mesh = spd_mesh("teapot", Some(12));
    let scene = mesh.scene();
    let params = KdParams::auto();
    let ideal = kd::requirements(scene.prim_count(), &params);
    let least = kd::KdRequirements {
        refs: 2 * scene.prim_count(),
        nodes: 2 * scene.prim_count(),
        ..ideal
    };
    let reference = depth_first(&scene, &params, &least);
    assert_ne!(reference.info.flags & KD_FLAG_TRUNCATED, 0);
    for run in [Run::ByFinish, Run::Threads(2)] {
        let (m, report) = by_jobs(&scene, &params, &least, run);
        assert!(report.one_pass, "{report:?}");
        assert!(m == reference, "{run:?}");
    }
}

/// SPD gears under the plain SAH (no reference cost: 26 references per
/// primitive) outgrows the default room: its jobs run out of their
/// reference shares by more than the whole room holds, so `finish` skips
/// the greedy pass (it would run out too) and shares the room fairly from
/// the start: the depth-first build's tree, one pass less.
#[test]
fn jobs_that_show_the_room_too_small_skip_the_greedy_pass() {
    let mesh = spd_mesh("gears", None);
    let scene = mesh.scene();
    let params = KdParams {
        cost_reference: 0.0,
        ..KdParams::auto()
    };
    let req = kd::requirements(scene.prim_count(), &params);
    let reference = depth_first(&scene, &params, &req);
    assert_ne!(reference.info.flags & KD_FLAG_TRUNCATED, 0);
    for run in [Run::ByFinish, Run::Threads(2)] {
        let (m, report) = by_jobs(&scene, &params, &req, run);
        assert!(report.one_pass && report.fair_pass_only, "{report:?}");
        assert!(m == reference, "{run:?}");
    }
    // With room for the untruncated tree the jobs fit: no pass is skipped.
    let roomy = KdRequirements {
        refs: 40 * scene.prim_count(),
        nodes: 60 * scene.prim_count(),
        events: 12 * 40 * scene.prim_count(),
        ..req
    };
    let (m, report) = by_jobs(&scene, &params, &roomy, Run::ByFinish);
    assert!(!report.fair_pass_only, "{report:?}");
    assert_eq!(m.info.flags & KD_FLAG_TRUNCATED, 0, "{report:?}");
}

/// Whatever the reference room, from far too little to plenty, the job
/// build (and the one job of a build for one thread) is the depth-first
/// build's tree: the greedy pass is skipped only
/// where it would have run out (and it is, on some of these rooms; on
/// others the one pass runs greedy first, or the jobs make the tree).
#[test]
fn job_build_equals_depth_first_at_every_room() {
    let mut rng = Rng(23);
    let params = KdParams::auto();
    let (mut skipped, mut greedy, mut jobs) = (0, 0, 0);
    for (tris, spheres, cones) in [(1500, 0, 0), (800, 200, 100), (2500, 0, 0)] {
        let o = random_scene(&mut rng, tris, spheres, cones, 10.0);
        let scene = o.scene();
        let n = scene.prim_count();
        let ideal = kd::requirements(n, &params);
        // References from 1.1 to 6 per primitive; nodes as many as the
        // ideal room has, or only two per primitive (jobs then run out of
        // nodes, which proves nothing about references).
        // And exactly the references the untruncated tree holds: the
        // greedy pass fits there, however many jobs outgrow their shares.
        let exact = depth_first(&scene, &params, &ideal).info.ref_count as usize;
        let rooms = [11, 13, 16, 20, 25, 30, 40, 60]
            .map(|t| [(n * t / 10, ideal.nodes), (n * t / 10, 2 * n)]);
        for (refs, nodes) in rooms.into_iter().flatten().chain([(exact, ideal.nodes)]) {
            let req = KdRequirements {
                refs,
                nodes,
                events: ideal.events.max(kd::EVENTS_PER_REF * refs),
                ..ideal
            };
            let reference = depth_first(&scene, &params, &req);
            let (m, report) = by_jobs(&scene, &params, &req, Run::ByFinish);
            assert!(m == reference, "{tris} {refs}: {report:?}");
            // One job for one thread (as `kd::build` makes): the same tree.
            let (one, one_report) = by_jobs(&scene, &params, &req, Run::Threads(1));
            assert_eq!(one_report.jobs, 1);
            assert!(one == reference, "{tris} {refs}, one job: {one_report:?}");
            match (report.one_pass, report.fair_pass_only) {
                (true, true) => skipped += 1,
                (true, false) => greedy += 1,
                _ => jobs += 1,
            }
        }
    }
    assert!(
        skipped > 0 && greedy > 0 && jobs > 0,
        "{skipped} {greedy} {jobs}"
    );
}

/// With references for the tree and barely more, shares in proportion to
/// primitives are too small for some jobs; `finish` runs those again in
/// the room the others left, and the tree is still the one-pass build's.
#[test]
fn a_job_that_outgrows_its_share_runs_again_in_finish() {
    let mesh = spd_mesh("teapot", None);
    let scene = mesh.scene();
    let params = KdParams::auto();
    let ideal = kd::requirements(scene.prim_count(), &params);
    let reference = depth_first(&scene, &params, &ideal);
    let refs = reference.info.ref_count as usize;
    let tight = KdRequirements {
        refs: refs + refs / 50,
        ..ideal
    };
    for run in [Run::ByFinish, Run::Threads(2)] {
        let (m, report) = by_jobs(&scene, &params, &tight, run);
        assert!(report.reruns > 0 && !report.one_pass, "{report:?}");
        assert!(m == reference, "{run:?}");
    }
}

#[test]
fn a_job_given_too_few_flags_is_refused() {
    let mesh = spd_mesh("tree", Some(6));
    let scene = mesh.scene();
    let params = KdParams::auto();
    let mut room = Room::new(&kd::requirements(scene.prim_count(), &params));
    let (storage, scratch) = room.parts();
    let mut b = kd::build_begin(&scene, &params, storage, scratch).unwrap();
    let job = b.jobs().next().unwrap();
    let n = scene.prim_count();
    assert_eq!(
        job.run(&mut vec![0; n - 1]),
        Err(coray::Error::SliceTooSmall {
            slice: "prim_flags",
            needed: n,
            got: n - 1
        })
    );
    // The refused job runs in `finish`.
    let t = b.finish().unwrap();
    t.validate().unwrap();
}

/// FNV-1a over a tree's words as a159a8c laid them out, so the pins
/// outlive layout changes: the nodes (a leaf's word its preorder number
/// `<< 2 | 3`, its data 0), then a leaf record per leaf in preorder (first
/// reference, count), the rope records (in leaf preorder) and the
/// references.
fn tree_digest(m: &Made) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    let mut word = |w: u32| {
        for b in w.to_le_bytes() {
            h = (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3);
        }
    };
    // Leaf preorder numbers: left subtrees first, as the builds number them.
    let mut number = vec![u32::MAX; m.nodes.len()];
    let mut leaves = Vec::new();
    let mut stack = vec![0usize];
    while let Some(i) = stack.pop() {
        let n = m.nodes[i];
        if n.is_leaf() {
            number[i] = leaves.len() as u32;
            leaves.push((n.first_ref(), n.ref_count()));
        } else {
            stack.push(n.left() as usize + 1);
            stack.push(n.left() as usize);
        }
    }
    // Interior nodes in the pinned trees' encoding (the left child above
    // the axis' two bits; these trees store every child).
    m.nodes.iter().enumerate().for_each(|(i, n)| {
        if n.is_leaf() {
            word(number[i] << 2 | 3);
            word(0);
        } else {
            assert_eq!(n.elided(), 0);
            word(n.left() << 2 | n.axis() as u32);
            word(n.data);
        }
    });
    leaves.iter().for_each(|&(first, count)| {
        word(first);
        word(count);
    });
    for r in &m.ropes {
        r.neighbor.iter().for_each(|&w| word(w));
        r.min.iter().chain(&r.max).for_each(|x| word(x.to_bits()));
    }
    m.refs.iter().for_each(|&w| word(w));
    h
}
