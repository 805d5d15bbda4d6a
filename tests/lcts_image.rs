//! LCTS image casting is exact: every scheme gives every pixel the primitive
//! and the t of hierarchical traversal, on all eight SPD scenes at 256x256.
mod common;

use common::*;
use coray::kd::KdParams;
use coray::lcts::hlcts::HlctsEntry;
use coray::lcts::{cast_image, image_requirements, HistoryRecord, Scheme};
use coray_scenes::spd::{self, Options};
use coray_scenes::SceneMesh;

const SCHEMES: [Scheme; 7] = [
    Scheme::Ropes,
    Scheme::Packets,
    Scheme::Slcts1d { n: 5 },
    Scheme::Slcts2d { n: 5, m: 5 },
    Scheme::Slcts2d { n: 2, m: 3 },
    Scheme::Hlcts1d,
    Scheme::Hlcts2d,
];

/// A cast's scratch for `scheme` over `cam` with histories of `cap` records.
fn buffers(cam: &coray::Camera, scheme: Scheme, cap: usize) -> coray::owned::OwnedCast {
    coray::owned::OwnedCast::new(&image_requirements(cam.width, cam.height, scheme, cap))
}

fn cast(
    tree: &coray::kd::KdTree,
    cam: &coray::Camera,
    scheme: Scheme,
    cap: usize,
) -> (Vec<f32>, Vec<u32>, coray::lcts::CastStats) {
    let mut b = buffers(cam, scheme, cap);
    let n = (cam.width * cam.height) as usize;
    let mut hits = vec![coray::Hit::MISS; n];
    let st = cast_image(tree, cam, scheme, b.scratch(), &mut hits).unwrap();
    let t = hits.iter().map(|h| h.t).collect();
    let p = hits.iter().map(|h| global_prim(tree.scene(), h)).collect();
    (t, p, st)
}

#[test]
fn every_scheme_matches_hierarchical_on_the_spd_scenes() {
    for &(name, _) in spd::SCENES {
        let m = SceneMesh::from_nff(&spd::generate(name, None, &Options::default()).unwrap());
        let scene = m.scene();
        let mut cam = m.camera;
        cam.width = 256;
        cam.height = 256;
        for params in [KdParams::paper(), KdParams::auto_with_ropes()] {
            let (req, mut b) = ideal_storage(&scene, &params);
            let tree = build_with(&scene, &params, &req, &mut b);
            let (t0, p0, s0) = cast(&tree, &cam, Scheme::Hierarchical, 256);
            assert!(
                p0.iter().filter(|&&p| p != u32::MAX).count() > 1000,
                "{name}: too few hits"
            );
            for scheme in SCHEMES {
                let (t, p, st) = cast(&tree, &cam, scheme, 256);
                let bad = (0..t.len())
                    .filter(|&i| p[i] != p0[i] || t[i].to_bits() != t0[i].to_bits())
                    .count();
                assert_eq!(
                    bad, 0,
                    "{name} {scheme:?}: {bad} pixels differ from hierarchical traversal"
                );
                // Every scheme traces each pixel's ray once.
                assert_eq!(st.trace.rays, s0.trace.rays, "{name} {scheme:?}");
                if matches!(scheme, Scheme::Slcts2d { n: 5, .. } | Scheme::Hlcts1d) {
                    // The point of it: fewer traversal steps.
                    assert!(
                        st.trace.traversal_steps < s0.trace.traversal_steps,
                        "{name} {scheme:?}"
                    );
                }
            }
        }
    }
}

#[test]
fn tiny_history_buffers_change_speed_not_results() {
    let m = SceneMesh::from_nff(&spd::generate("balls", Some(2), &Options::default()).unwrap());
    let scene = m.scene();
    let mut cam = m.camera;
    cam.width = 61;
    cam.height = 47;
    let params = KdParams::paper();
    let (req, mut b) = ideal_storage(&scene, &params);
    let tree = build_with(&scene, &params, &req, &mut b);
    let (t0, p0, _) = cast(&tree, &cam, Scheme::Hierarchical, 1);
    for cap in [1usize, 2, 5, 1000] {
        for scheme in [
            Scheme::Slcts1d { n: 7 },
            Scheme::Slcts2d { n: 4, m: 6 },
            Scheme::Hlcts1d,
            Scheme::Hlcts2d,
        ] {
            let (t, p, _) = cast(&tree, &cam, scheme, cap);
            assert_eq!(p, p0, "cap {cap} {scheme:?}");
            assert!(
                t.iter().zip(&t0).all(|(a, b)| a.to_bits() == b.to_bits()),
                "cap {cap} {scheme:?}"
            );
        }
    }
}

/// Images one pixel wide or high (and 2 x 2): every scheme puts each pixel
/// exactly once, with hierarchical traversal's hit.
#[test]
fn thin_images_get_every_pixel_once() {
    use coray::lcts::{cast_image_with, image_requirements as reqs};
    let m = SceneMesh::from_nff(&spd::generate("teapot", Some(3), &Options::default()).unwrap());
    let scene = m.scene();
    let params = KdParams::paper();
    let (req, mut b) = ideal_storage(&scene, &params);
    let tree = build_with(&scene, &params, &req, &mut b);
    for (w, h) in [(61, 1), (1, 47), (1, 1), (2, 2), (7, 2), (2, 9)] {
        let mut cam = m.camera;
        cam.width = w;
        cam.height = h;
        let (t0, p0, _) = cast(&tree, &cam, Scheme::Hierarchical, 64);
        for scheme in SCHEMES {
            let n = (w * h) as usize;
            let (mut t, mut p, mut seen) = (vec![f32::NAN; n], vec![0u32; n], vec![0u32; n]);
            let mut room = coray::owned::OwnedCast::new(&reqs(w, h, scheme, 64));
            cast_image_with(&tree, &cam, scheme, room.scratch(), |x, y, hit| {
                let k = (y * w + x) as usize;
                t[k] = hit.t;
                p[k] = global_prim(tree.scene(), hit);
                seen[k] += 1;
            })
            .unwrap();
            assert!(
                seen.iter().all(|&c| c == 1),
                "{w} x {h} {scheme:?}: {seen:?}"
            );
            assert_eq!(p, p0, "{w} x {h} {scheme:?}");
            assert!(t.iter().zip(&t0).all(|(a, b)| a.to_bits() == b.to_bits()));
        }
    }
}

/// Tiles of an image, cast each on its own (uneven tiles, a one-pixel
/// column among them), give every pixel the whole image's hit bit for bit,
/// by every scheme, and each tile's pixels exactly once; rectangles that
/// are empty or leave the image are refused.
#[test]
fn tiles_cast_alone_give_the_whole_images_pixels() {
    use coray::lcts::{cast_rect_with_by, window::Baseline, PixelRect};
    let m = SceneMesh::from_nff(&spd::generate("teapot", Some(3), &Options::default()).unwrap());
    let scene = m.scene();
    let mut cam = m.camera;
    cam.width = 61;
    cam.height = 47;
    let params = KdParams::paper();
    let (req, mut b) = ideal_storage(&scene, &params);
    let tree = build_with(&scene, &params, &req, &mut b);
    let (t0, p0, _) = cast(&tree, &cam, Scheme::Hierarchical, 64);
    assert!(p0.iter().filter(|&&p| p != u32::MAX).count() > 300);
    let (xs, ys) = ([0u32, 1, 23, 61], [0u32, 17, 18, 47]);
    for scheme in std::iter::once(Scheme::Hierarchical).chain(SCHEMES) {
        let n = (cam.width * cam.height) as usize;
        let (mut t, mut p, mut seen) = (vec![f32::NAN; n], vec![0u32; n], vec![0u32; n]);
        for j in 0..3 {
            for i in 0..3 {
                let rect = PixelRect {
                    x: xs[i],
                    y: ys[j],
                    width: xs[i + 1] - xs[i],
                    height: ys[j + 1] - ys[j],
                };
                let r = image_requirements(rect.width, rect.height, scheme, 64);
                let mut room = coray::owned::OwnedCast::new(&r);
                cast_rect_with_by(
                    Baseline,
                    &tree,
                    &cam,
                    rect,
                    scheme,
                    room.scratch(),
                    |x, y, h| {
                        assert!(x >= rect.x && x < rect.x + rect.width, "{scheme:?} x {x}");
                        assert!(y >= rect.y && y < rect.y + rect.height, "{scheme:?} y {y}");
                        let k = (y * cam.width + x) as usize;
                        t[k] = h.t;
                        p[k] = global_prim(tree.scene(), h);
                        seen[k] += 1;
                    },
                )
                .unwrap();
            }
        }
        assert!(
            seen.iter().all(|&c| c == 1),
            "{scheme:?}: a pixel not put once"
        );
        assert_eq!(p, p0, "{scheme:?}");
        assert!(
            t.iter().zip(&t0).all(|(a, b)| a.to_bits() == b.to_bits()),
            "{scheme:?}"
        );
    }
    let r = image_requirements(61, 47, Scheme::Hierarchical, 64);
    for bad in [
        PixelRect {
            x: 0,
            y: 0,
            width: 0,
            height: 5,
        },
        PixelRect {
            x: 60,
            y: 0,
            width: 2,
            height: 5,
        },
        PixelRect {
            x: 0,
            y: 40,
            width: 5,
            height: 8,
        },
        PixelRect {
            x: u32::MAX,
            y: 0,
            width: 2,
            height: 1,
        },
    ] {
        let mut room = coray::owned::OwnedCast::new(&r);
        let got = cast_rect_with_by(
            Baseline,
            &tree,
            &cam,
            bad,
            Scheme::Hierarchical,
            room.scratch(),
            |_, _, _| panic!("{bad:?}: a pixel put"),
        );
        assert!(
            matches!(got, Err(coray::Error::InvalidParameter { .. })),
            "{bad:?}: {got:?}"
        );
    }
}

/// The root-to-leaf path point location takes for `p` (going left on a tie
/// when the direction points left, as the traversals do).
fn locate_path(tree: &coray::kd::KdTree, p: coray::Vec3, d: coray::Vec3) -> Vec<u32> {
    let mut path = vec![0u32];
    let mut node = 0u32;
    loop {
        let nd = tree.parts().0[node as usize];
        if nd.is_leaf() {
            return path;
        }
        let (a, s) = (nd.axis(), nd.split());
        node = if p[a] < s || (p[a] == s && d[a] < 0.0) {
            nd.left()
        } else {
            nd.left() + 1
        };
        path.push(node);
    }
}

#[test]
fn entry_node_is_where_the_corners_descents_part() {
    use coray::lcts::history::{trace_recorded, History};
    use coray::lcts::slcts::entry_node;
    let m = SceneMesh::from_nff(&spd::generate("lattice", None, &Options::default()).unwrap());
    let scene = m.scene();
    let mut cam = m.camera;
    cam.width = 256;
    cam.height = 256;
    let params = KdParams::paper();
    let (req, mut b) = ideal_storage(&scene, &params);
    let tree = build_with(&scene, &params, &req, &mut b);
    let (f, r, u) = cam.basis();
    let ray = |x: u32, y: u32| cam.ray_in(f, r, u, x as f32 + 0.5, y as f32 + 0.5);
    let root = tree.info().trace_bounds();
    let mut rng = Rng(7);
    let (mut below_root, mut checked_points) = (0, 0);
    for wy in (0..252).step_by(4) {
        for wx in (0..252).step_by(4) {
            let corners = [(wx, wy), (wx + 4, wy), (wx, wy + 4), (wx + 4, wy + 4)];
            let mut bufs = vec![vec![HistoryRecord::default(); 512]; 4];
            let mut lens = [0usize; 4];
            for (j, buf) in bufs.iter_mut().enumerate() {
                let mut h = History::new(buf);
                trace_recorded(
                    &tree,
                    &ray(corners[j].0, corners[j].1),
                    &mut h,
                    &mut kst(),
                    &mut Default::default(),
                );
                assert!(!h.overflow);
                lens[j] = h.len;
            }
            let hs: Vec<Option<&[HistoryRecord]>> =
                bufs.iter().zip(lens).map(|(b, n)| Some(&b[..n])).collect();
            let Some(e) = entry_node(&tree, &hs) else {
                // Only a corner that misses the scene has no descent.
                assert!(lens.contains(&0));
                continue;
            };
            below_root += (e.node != 0) as usize;
            // On every corner's descent; below it the descents part (unless
            // the entry node is a first leaf they all share).
            let mut next = Vec::new();
            for (j, h) in hs.iter().enumerate() {
                let h = h.unwrap();
                let descent: Vec<u32> = h
                    .iter()
                    .take_while(|rec| rec.kind() < 4)
                    .map(|rec| rec.node)
                    .chain(h.iter().find(|rec| rec.kind() == 4).map(|rec| rec.node))
                    .collect();
                let at = descent.iter().position(|&n| n == e.node);
                assert!(
                    at.is_some(),
                    "window {wx},{wy}: entry {} not on corner {j}",
                    e.node
                );
                next.push(descent.get(at.unwrap() + 1).copied());
            }
            if !tree.parts().0[e.node as usize].is_leaf() {
                assert!(
                    next.iter().any(|n| *n != next[0]),
                    "window {wx},{wy}: not the deepest"
                );
            }
            // The contract: a point the entry node holds is located through it.
            // Points around the node's region, in and out of it.
            let lo = e.lo.max(root.min);
            let hi = e.hi.min(root.max);
            let pad = (hi - lo) * 0.2;
            for _ in 0..20 {
                let p = rng.vec(0.0, 1.0) * (hi - lo + pad * 2.0) + lo - pad;
                let d = rng.unit();
                if e.holds(p) {
                    checked_points += 1;
                    assert!(
                        locate_path(&tree, p, d).contains(&e.node),
                        "window {wx},{wy}: {p:?}"
                    );
                }
            }
        }
    }
    assert!(
        below_root > 500,
        "{below_root} windows start below the root"
    );
    assert!(checked_points > 100, "{checked_points} points held");
    // And casting uses it: lattice's small surface leaves leave many
    // windows without a common leaf.
    let (_, _, st) = cast(&tree, &cam, Scheme::Slcts2d { n: 5, m: 5 }, 256);
    assert!(
        st.windows_entered > 100,
        "{} windows entered",
        st.windows_entered
    );
}

/// A ray traced from a cut tests the cut's entries in order: every entry
/// tested is a traversal step, the ones its segment misses included (they
/// were once free, which flattered HLCTS's alpha on sparse scenes).
#[test]
fn every_cut_entry_a_ray_tests_is_a_step() {
    use coray::lcts::hlcts::{self, Hlcts, NONE};
    use coray::TraceStats;
    let m = SceneMesh::from_nff(&spd::generate("tetra", None, &Options::default()).unwrap());
    let scene = m.scene();
    let params = KdParams::paper();
    let (req, mut b) = ideal_storage(&scene, &params);
    let tree = build_with(&scene, &params, &req, &mut b);
    let cam = m.camera;
    let (f, r, u) = cam.basis();
    let mut checked = 0;
    for (x, y) in (0..20).flat_map(|i| (0..20).map(move |j| (i as f32 / 20.0, j as f32 / 20.0))) {
        let ray = cam.ray_in(f, r, u, x * cam.width as f32, y * cam.height as f32);
        let mut hier = TraceStats::default();
        let hit = tree.intersect(
            &ray,
            coray::kd::Traversal::Hierarchical,
            &mut kst(),
            &mut hier,
        );
        if !hit.is_hit() {
            continue;
        }
        // A leaf the ray misses, then the root: the ray tests the leaf's
        // box (one step), then walks the whole tree as hierarchical traversal.
        let missed = (0..tree.parts().0.len())
            .filter(|&n| tree.parts().0[n].is_leaf())
            .map(|n| (n, tree.parts().1[tree.parts().2[n] as usize].bounds()))
            .find(|(_, bx)| {
                bx.clip_ray(ray.origin, ray.dir.recip(), ray.t_min, ray.t_max)
                    .is_none()
            })
            .unwrap();
        let entry = |node: usize, bx: coray::Aabb| HlctsEntry {
            node: node as u32,
            flags: 0,
            min: bx.min.into(),
            max: bx.max.into(),
            ptr: [NONE; hlcts::MAX_RAYS],
        };
        let mut entries = [entry(missed.0, missed.1), hlcts::root_entry(&tree)];
        let cut = Hlcts {
            entries: &mut entries,
            len: 2,
            leading_leaves: 1,
            termination: None,
        };
        let mut st = TraceStats::default();
        let h = hlcts::trace(&tree, &cut, &ray, None, &mut kst(), &mut st);
        assert_eq!((h.prim_id, h.t), (hit.prim_id, hit.t));
        assert_eq!(
            st.traversal_steps,
            hier.traversal_steps + 1,
            "pixel {x},{y}"
        );
        checked += 1;
    }
    assert!(checked > 20, "{checked} rays hit");
}
