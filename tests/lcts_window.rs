//! An LCTS window's rays traced eight at a time (`lcts::window`) give
//! every ray exactly what the single-ray trace (`slcts::trace` for an SLCTS
//! window, `hlcts::trace_guided` for an HLCTS cut) gives it alone: the same
//! primitive and t, and the same steps and tests counted.
mod common;

use common::*;
use coray::kd::{KdParams, KdTree};
use coray::lcts::guide::Paths;
use coray::lcts::history::{trace_recorded, History};
use coray::lcts::hlcts::{self, Boundary, Source};
use coray::lcts::window::{self, Shaft};
use coray::lcts::{slcts, HistoryRecord};
use coray::{Hit, Ray, TraceStats};
use coray_scenes::spd::{self, Options};
use coray_scenes::SceneMesh;

/// A corner ray's history, hit, and the ray.
fn corner(tree: &KdTree, ray: &Ray) -> (Vec<HistoryRecord>, Hit, Ray) {
    let mut buf = vec![HistoryRecord::default(); 4096];
    let mut h = History::new(&mut buf);
    trace_recorded(tree, ray, &mut h, &mut kst(), &mut TraceStats::default());
    assert!(!h.overflow);
    let (len, hit) = (h.len, h.hit);
    buf.truncate(len);
    (buf, hit, *ray)
}

fn bits(h: &Hit) -> (u32, u32, u32) {
    (h.geom_id, h.prim_id, h.t.to_bits())
}

/// Every `w` x `w` window of a `res` x `res` image of `name`: the window's
/// inner rays through `window::trace` in batches of up to eight, and one
/// by one through `slcts::trace`; `short` ends them halfway to the scene's
/// centre's far side (segments that end inside leaves). Returns the rays
/// that took the packet.
/// Rays that took the packet: `[SLCTS, HLCTS]` shafts with common leaves,
/// then without.
fn compare(name: &str, params: &KdParams, res: u32, w: u32, short: bool) -> [u64; 4] {
    let m = SceneMesh::from_nff(&spd::generate(name, None, &Options::default()).unwrap());
    let scene = m.scene();
    let (req, mut b) = ideal_storage(&scene, params);
    let tree = build_with(&scene, params, &req, &mut b);
    let mut cam = m.camera;
    cam.width = res;
    cam.height = res;
    let (mut packed, mut windows) = ([0u64; 4], 0);
    for y0 in (0..res - w).step_by(w as usize) {
        for x0 in (0..res - w).step_by(w as usize) {
            let (x1, y1) = (x0 + w, y0 + w);
            let cs: Vec<_> = [(x0, y0), (x1, y0), (x0, y1), (x1, y1)]
                .iter()
                .map(|&(x, y)| corner(&tree, &cam.ray(x, y)))
                .collect();
            let hs: Vec<Option<&[HistoryRecord]>> = cs.iter().map(|c| Some(&c.0[..])).collect();
            let hits: Vec<Hit> = cs.iter().map(|c| c.1).collect();
            let mut entries = vec![0u32; 4096];
            let seq = slcts::build(&tree, &hs, &hits, &mut entries);
            let mut seq_paths = vec![0u32; 4 * 4096];
            let seq_paths: Paths = seq.paths(&hs, &mut seq_paths);
            // The HLCTS cut of the same four rays, from the root.
            let bounds: Vec<Boundary> = cs
                .iter()
                .enumerate()
                .map(|(j, c)| Boundary {
                    ray: c.2,
                    records: Some(&c.0[..]),
                    source: Source::Parent(j),
                    hit: c.1,
                })
                .collect();
            let mut cut_buf = vec![hlcts::root_entry(&tree); 4096];
            let cut = hlcts::build(&tree, &[hlcts::root_entry(&tree)], &bounds, &mut cut_buf);
            let mut cut_paths = vec![0u32; 4 * 4096];
            let cut_paths: Paths = cut.paths(&hs, &mut cut_paths);
            let mut inner = Vec::new();
            for y in y0 + 1..y1 {
                for x in x0 + 1..x1 {
                    let near = ((x - x0) * 2 >= w) as usize + 2 * ((y - y0) * 2 >= w) as usize;
                    let mut ray = cam.ray(x, y);
                    if short {
                        let bx = tree.info().bounds();
                        let c = (bx.min + bx.max) * 0.5;
                        ray.t_max = 1.5 * (c - ray.origin).length() / ray.dir.length();
                    }
                    inner.push((ray, near));
                }
            }
            windows += 1;
            let shafts = [
                (
                    Shaft::Slcts(&seq),
                    &seq_paths,
                    seq.termination.is_none(),
                    seq.len == 0,
                ),
                (
                    Shaft::Hlcts(&cut),
                    &cut_paths,
                    cut.termination.is_none(),
                    cut.leading_leaves == 0,
                ),
            ];
            for (k, (shaft, paths, shared, no_common)) in shafts.into_iter().enumerate() {
                let (mut alone, mut together) = (TraceStats::default(), TraceStats::default());
                for batch in inner.chunks(8) {
                    let rays: Vec<Ray> = batch.iter().map(|b| b.0).collect();
                    let near: Vec<usize> = batch.iter().map(|b| b.1).collect();
                    let mut got = vec![Hit::MISS; batch.len()];
                    window::trace(
                        &tree,
                        shaft,
                        paths,
                        &rays,
                        &near,
                        &mut got,
                        &mut kst(),
                        &mut together,
                    );
                    for (i, r) in rays.iter().enumerate() {
                        let want = match shaft {
                            Shaft::Slcts(s) => {
                                slcts::trace(&tree, s, paths, near[i], r, &mut kst(), &mut alone)
                            }
                            Shaft::Hlcts(h) => hlcts::trace_guided(
                                &tree,
                                h,
                                paths,
                                near[i],
                                r,
                                &mut kst(),
                                &mut alone,
                            ),
                        };
                        assert_eq!(
                            bits(&got[i]),
                            bits(&want),
                            "{name} shaft {k} window ({x0}, {y0}) ray {i}"
                        );
                    }
                    if shared && batch.len() > 1 {
                        packed[k + 2 * no_common as usize] += batch.len() as u64;
                    }
                }
                assert_eq!(
                    (
                        alone.rays,
                        alone.prim_tests,
                        alone.interior_steps,
                        alone.leaf_steps
                    ),
                    (
                        together.rays,
                        together.prim_tests,
                        together.interior_steps,
                        together.leaf_steps
                    ),
                    "{name} shaft {k} window ({x0}, {y0}): counts differ"
                );
                assert_eq!(
                    (alone.empty_leaf_steps, alone.traversal_steps, alone.faults),
                    (
                        together.empty_leaf_steps,
                        together.traversal_steps,
                        together.faults
                    ),
                    "{name} shaft {k} window ({x0}, {y0}): counts differ"
                );
            }
        }
    }
    assert!(windows > 100, "{name}: {windows} windows");
    packed
}

#[test]
fn window_packets_answer_and_count_as_single_rays() {
    // Triangles (teapot, gears: long thin ones) and spheres (balls).
    for params in [KdParams::paper(), KdParams::auto_with_ropes()] {
        let mut packed = [0u64; 4];
        for name in ["teapot", "gears", "balls", "tree"] {
            let p = compare(name, &params, 96, 5, false);
            compare(name, &params, 96, 5, true);
            for (a, b) in packed.iter_mut().zip(p) {
                *a += b;
            }
        }
        // The packet path is the one under test: of 4 x 5776 inner rays,
        // about 13,000 share an SLCTS window's packet through common leaves
        // and 8,000 an HLCTS cut's (gears' windows share few leaves at this
        // size); about 9,700 and 14,600 walk apart from the start, in
        // windows without a common leaf.
        assert!(
            packed[0] >= 10_000 && packed[1] >= 6_000 && packed[2] >= 6_000 && packed[3] >= 10_000,
            "only {packed:?} rays took the packet"
        );
    }
}
