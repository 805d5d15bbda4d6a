//! Guided ropes: a ray past its shaft's common leaves follows the boundary
//! rays' leaves. A right guess is one step (the leaf itself), a wrong one
//! costs a step and a rope descent, and neither ever changes a hit.
mod common;

use common::*;
use coray::kd::{KdParams, KdTree, Traversal};
use coray::lcts::guide::{Paths, FROM_START, MAX_GUIDES};
use coray::lcts::history::{trace_recorded, History};
use coray::lcts::slcts::{self, Slcts};
use coray::lcts::HistoryRecord;
use coray::{Hit, Ray, TraceStats};
use coray_scenes::spd::{self, Options};
use coray_scenes::SceneMesh;

/// A shaft with no common leaf and no entry node: the ray starts at the
/// first leaf the paths guess for it, else is traced hierarchically.
fn no_sequence() -> Slcts<'static> {
    Slcts {
        entries: &mut [],
        len: 0,
        termination: None,
        leaves: 0,
        entry: None,
        last_record: [FROM_START; MAX_GUIDES],
    }
}

fn history(tree: &KdTree, ray: &Ray) -> (Vec<HistoryRecord>, Hit, TraceStats) {
    let mut buf = vec![HistoryRecord::default(); 4096];
    let mut h = History::new(&mut buf);
    let mut st = TraceStats::default();
    trace_recorded(tree, ray, &mut h, &mut kst(), &mut st);
    assert!(!h.overflow);
    let (len, hit) = (h.len, h.hit);
    buf.truncate(len);
    (buf, hit, st)
}

/// Traces `ray` guided by the paths of `guides` (histories from the start).
fn guided(tree: &KdTree, ray: &Ray, guides: &[&[HistoryRecord]]) -> (Hit, TraceStats) {
    let hs: Vec<Option<&[HistoryRecord]>> = guides.iter().map(|h| Some(*h)).collect();
    let mut buf = vec![0u32; 4096];
    let paths = Paths::build(&hs, &[FROM_START; MAX_GUIDES], &mut buf);
    let mut st = TraceStats::default();
    let hit = slcts::trace(tree, &no_sequence(), &paths, 0, ray, &mut kst(), &mut st);
    (hit, st)
}

fn same(a: &Hit, b: &Hit) -> bool {
    (a.geom_id, a.prim_id, a.t.to_bits()) == (b.geom_id, b.prim_id, b.t.to_bits())
}

#[test]
fn a_ray_guided_by_its_own_path_visits_only_leaves() {
    let mut rng = Rng(0x9e37_79b9);
    let o = random_scene(&mut rng, 3000, 400, 200, 10.0);
    let scene = o.scene();
    let params = KdParams::paper();
    let (req, mut b) = ideal_storage(&scene, &params);
    let tree = build_with(&scene, &params, &req, &mut b);
    let rays = random_rays(&mut rng, 3000, 10.0);
    let (mut leaf_only, mut walked) = (0, 0);
    for ray in &rays {
        let (rec, hit, hier) = history(&tree, ray);
        let (g, st) = guided(&tree, ray, &[&rec]);
        assert!(same(&g, &hit), "{ray:?}: {g:?} vs {hit:?}");
        if hier.leaf_steps > 0 {
            walked += 1;
            // Every leaf guessed right: no descent, one step per leaf.
            if st.interior_steps == 0 && st.leaf_steps == hier.leaf_steps {
                leaf_only += 1;
            }
        }
    }
    assert!(walked > 2000, "{walked} rays met the tree");
    assert!(
        leaf_only * 100 >= walked * 99,
        "{leaf_only} of {walked} rays guided by their own path visited only leaves"
    );
}

#[test]
fn wrong_paths_change_steps_not_hits() {
    let mut rng = Rng(0x51ed_270b);
    let o = random_scene(&mut rng, 3000, 400, 200, 10.0);
    let scene = o.scene();
    let params = KdParams::paper();
    let (req, mut b) = ideal_storage(&scene, &params);
    let tree = build_with(&scene, &params, &req, &mut b);
    let rays = random_rays(&mut rng, 2000, 10.0);
    let recs: Vec<_> = rays.iter().map(|r| history(&tree, r).0).collect();
    let mut interior = 0;
    for (i, ray) in rays.iter().enumerate() {
        let want = tree.intersect(
            ray,
            Traversal::Hierarchical,
            &mut kst(),
            &mut TraceStats::default(),
        );
        // Paths of unrelated rays: most guesses fail, some succeed by chance.
        let others: Vec<&[HistoryRecord]> = (1..=4)
            .map(|k| recs[(i + 97 * k) % rays.len()].as_slice())
            .collect();
        let (g, st) = guided(&tree, ray, &others);
        assert!(same(&g, &want), "{ray:?}: {g:?} vs {want:?}");
        interior += st.interior_steps;
    }
    assert!(interior > 0, "wrong guesses descend by ropes");
}

#[test]
fn neighbouring_pixels_guide_each_other() {
    let m = SceneMesh::from_nff(&spd::generate("balls", Some(3), &Options::default()).unwrap());
    let scene = m.scene();
    let params = KdParams::paper();
    let (req, mut b) = ideal_storage(&scene, &params);
    let tree = build_with(&scene, &params, &req, &mut b);
    let cam = m.camera;
    let (f, r, u) = cam.basis();
    let ray = |x: u32, y: u32| cam.ray_in(f, r, u, x as f32 + 0.5, y as f32 + 0.5);
    let (mut hier_steps, mut guided_steps) = (0, 0);
    for y in (0..cam.height).step_by(7) {
        for x in (1..cam.width).step_by(3) {
            let (left, ..) = history(&tree, &ray(x - 1, y));
            let (_, hit, hier) = history(&tree, &ray(x, y));
            let (g, st) = guided(&tree, &ray(x, y), &[&left]);
            assert!(same(&g, &hit), "pixel {x},{y}");
            hier_steps += hier.traversal_steps;
            guided_steps += st.traversal_steps;
        }
    }
    // The left neighbour's leaves are mostly this ray's: far fewer steps.
    assert!(
        guided_steps * 2 < hier_steps,
        "{guided_steps} guided steps vs {hier_steps} hierarchical"
    );
}

/// Point location from the root, as every traversal does it: a point on a
/// split plane goes where the direction heads; None when the direction
/// lies in that plane. The leaf's rope record.
fn locate(tree: &KdTree, p: coray::Vec3, d: coray::Vec3) -> Option<u32> {
    let mut node = 0usize;
    loop {
        let nd = tree.parts().0[node];
        if nd.is_leaf() {
            return Some(tree.parts().2[node]);
        }
        let (a, s) = (nd.axis(), nd.split());
        node = if p[a] < s || (p[a] == s && d[a] < 0.0) {
            nd.left() as usize
        } else if p[a] > s || d[a] > 0.0 {
            nd.left() as usize + 1
        } else {
            return None;
        };
    }
}

/// A guess is accepted exactly where point location would go: points on
/// leaf faces and edges, directions into, out of and along them.
#[test]
fn a_leaf_holds_a_point_where_point_location_puts_it() {
    use coray::lcts::guide::holds;
    let mut rng = Rng(0x2545_f491);
    let o = random_scene(&mut rng, 2000, 200, 0, 10.0);
    let scene = o.scene();
    let params = KdParams::paper();
    let (req, mut b) = ideal_storage(&scene, &params);
    let tree = build_with(&scene, &params, &req, &mut b);
    let root = tree.info().bounds();
    let (mut on_faces, mut in_plane) = (0, 0);
    for _ in 0..2000 {
        let leaf = &tree.parts().1[rng.below(tree.parts().1.len())];
        let bx = leaf.bounds();
        let mut p = bx.min + (bx.max - bx.min) * rng.vec(0.0, 1.0);
        let mut d = rng.unit();
        let mut snapped = false;
        for a in 0..3 {
            // Onto a face that is a split (not the root box's face).
            let face = if rng.f() < 0.5 { bx.min[a] } else { bx.max[a] };
            if rng.f() < 0.6 && face != root.min[a] && face != root.max[a] {
                p[a] = face;
                snapped = true;
                if rng.f() < 0.25 {
                    d[a] = 0.0;
                }
            }
        }
        on_faces += snapped as usize;
        let want = locate(&tree, p, d);
        in_plane += want.is_none() as usize;
        for (i, rp) in tree.parts().1.iter().enumerate() {
            assert_eq!(
                holds(rp, p, d),
                want == Some(i as u32),
                "leaf {i}, point {p:?}, direction {d:?}, located {want:?}"
            );
        }
    }
    assert!(on_faces > 1500 && in_plane > 100, "{on_faces} {in_plane}");
}

/// A boundary ray that ended before the common part's end (an HLCTS cut
/// entry it never reached) has no path: it guides nothing, rather than
/// guiding from its own first leaf.
#[test]
fn a_boundary_ray_that_ended_early_guides_nothing() {
    use coray::lcts::guide::NO_PATH;
    let mut rng = Rng(0x1234_5678);
    let o = random_scene(&mut rng, 2000, 200, 0, 10.0);
    let scene = o.scene();
    let params = KdParams::paper();
    let (req, mut b) = ideal_storage(&scene, &params);
    let tree = build_with(&scene, &params, &req, &mut b);
    let mut guided_somewhere = 0;
    for ray in random_rays(&mut rng, 500, 10.0) {
        let (rec, hit, hier) = history(&tree, &ray);
        let mut buf = vec![0u32; 4096];
        let hs = [Some(rec.as_slice())];
        let none = Paths::build(&hs, &[NO_PATH], &mut buf);
        let mut st = TraceStats::default();
        let g = slcts::trace(&tree, &no_sequence(), &none, 0, &ray, &mut kst(), &mut st);
        assert!(same(&g, &hit));
        // Unguided and without an entry node: redone hierarchically.
        assert_eq!(st.traversal_steps, hier.traversal_steps, "{ray:?}");
        let (_, own) = guided(&tree, &ray, &[&rec]);
        guided_somewhere += (own.traversal_steps < hier.traversal_steps) as usize;
    }
    assert!(guided_somewhere > 300, "{guided_somewhere}");
}
