//! Patch-to-patch visibility through an HLCTS gives the visible fraction
//! that brute-force hierarchical casting of the same segments gives.
mod common;

use common::*;
use coray::kd::{KdParams, Traversal};
use coray::lcts::hlcts::HlctsEntry;
use coray::lcts::patch::{patch_point, patch_visibility, segment, PatchScratch};
use coray::lcts::HistoryRecord;
use coray::{TraceStats, Vec3};
use coray_scenes::spd::{self, Options};
use coray_scenes::SceneMesh;

fn quad(rng: &mut Rng, c: Vec3, size: f32) -> Vec<Vec3> {
    let (u, v) = (rng.unit() * size, rng.unit() * size);
    // A parallelogram: convex whatever u and v are.
    vec![c - u - v, c + u - v, c + u + v, c - u + v]
}

#[test]
fn visible_fraction_equals_brute_force() {
    let mut rng = Rng(77);
    let (mut steps_lcts, mut steps_ref, mut pairs, mut partial) = (0u64, 0u64, 0, 0);
    for &(name, _) in spd::SCENES {
        let m = SceneMesh::from_nff(&spd::generate(name, None, &Options::default()).unwrap());
        let scene = m.scene();
        let bounds = scene.bounds();
        let params = KdParams::paper();
        let (req, mut b) = ideal_storage(&scene, &params);
        let tree = build_with(&scene, &params, &req, &mut b);
        for _ in 0..6 {
            let pick = |rng: &mut Rng| {
                let t = Vec3::new(rng.f(), rng.f(), rng.f());
                bounds.min + (bounds.max - bounds.min) * t
            };
            let size = (bounds.max - bounds.min).length() * 0.02;
            let (pa, pb) = (pick(&mut rng), pick(&mut rng));
            let (a, bq) = (quad(&mut rng, pa, size), quad(&mut rng, pb, size));
            let n = 5;
            let mut records = vec![HistoryRecord::default(); 16 * 512];
            let mut hl = vec![HlctsEntry::default(); 16 * 512];
            let mut paths = vec![0u32; 16 * 512];
            let got = patch_visibility(
                &tree,
                &a,
                &bq,
                n,
                1e-4,
                PatchScratch {
                    records: &mut records,
                    hlcts: &mut hl,
                    paths: &mut paths,
                    stack: &mut kst(),
                },
            )
            .unwrap();
            // Brute force: the same segments, hierarchical traversal.
            let mut st = TraceStats::default();
            let mut visible = 0;
            let step = |i: u32| i as f32 / (n - 1) as f32;
            for ia in 0..n * n {
                let p = patch_point(&a, step(ia % n), step(ia / n));
                for ib in 0..n * n {
                    let q = patch_point(&bq, step(ib % n), step(ib / n));
                    visible += !tree
                        .intersect(
                            &segment(p, q, 1e-4),
                            Traversal::Hierarchical,
                            &mut kst(),
                            &mut st,
                        )
                        .is_hit() as u32;
                }
            }
            assert_eq!(got.samples, n.pow(4));
            assert_eq!(got.visible, visible, "{name}: visible segments");
            steps_lcts += got.trace.traversal_steps;
            steps_ref += st.traversal_steps;
            pairs += 1;
            partial += (visible > 0 && visible < got.samples) as u32;
        }
    }
    println!("{pairs} patch pairs ({partial} partly visible): {steps_lcts} traversal steps through the cut, {steps_ref} hierarchical");
    assert!(partial > 3, "too few partly visible pairs to mean anything");
    assert!(steps_lcts < steps_ref);
}
