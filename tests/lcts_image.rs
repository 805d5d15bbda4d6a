//! LCTS image casting is exact: every scheme gives every pixel the primitive
//! and the t of hierarchical traversal, on all eight SPD scenes at 256x256.
mod common;

use common::*;
use coray::kd::KdParams;
use coray::lcts::hlcts::HlctsEntry;
use coray::lcts::{
    cast_image, image_requirements, CornerInfo, HistoryRecord, ImageScratch, Scheme,
};
use coray_scenes::spd::{self, Options};
use coray_scenes::SceneMesh;

const SCHEMES: [Scheme; 6] = [
    Scheme::Ropes,
    Scheme::Slcts1d { n: 5 },
    Scheme::Slcts2d { n: 5, m: 5 },
    Scheme::Slcts2d { n: 2, m: 3 },
    Scheme::Hlcts1d,
    Scheme::Hlcts2d,
];

struct Buffers {
    records: Vec<HistoryRecord>,
    entries: Vec<u32>,
    corners: Vec<CornerInfo>,
    starts: Vec<u32>,
    hlcts: Vec<HlctsEntry>,
}

impl Buffers {
    fn new(cam: &coray::Camera, scheme: Scheme, cap: usize) -> Buffers {
        let req = image_requirements(cam.width, cam.height, scheme, cap);
        Buffers {
            records: vec![HistoryRecord::default(); req.records],
            entries: vec![0u32; req.entries],
            corners: vec![CornerInfo::default(); req.corners],
            starts: vec![0u32; req.starts],
            hlcts: vec![HlctsEntry::default(); req.hlcts],
        }
    }

    fn scratch(&mut self) -> ImageScratch<'_> {
        ImageScratch {
            records: &mut self.records,
            entries: &mut self.entries,
            corners: &mut self.corners,
            starts: &mut self.starts,
            hlcts: &mut self.hlcts,
        }
    }
}

fn cast(
    tree: &coray::kd::KdTree,
    cam: &coray::Camera,
    scheme: Scheme,
    cap: usize,
) -> (Vec<f32>, Vec<u32>, coray::lcts::CastStats) {
    let mut b = Buffers::new(cam, scheme, cap);
    let n = (cam.width * cam.height) as usize;
    let (mut t, mut p) = (vec![0.0f32; n], vec![0u32; n]);
    let st = cast_image(tree, cam, scheme, b.scratch(), &mut t, &mut p).unwrap();
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
        for params in [KdParams::paper(), KdParams::auto()] {
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
