//! `coray compare`: primary and shadow rays through coray and Embree in one
//! process, ray by ray, with the cross-check's tie rules; a diff image.

use crate::bench::{lit_shadow_rays, primary_rays};
use crate::kdbuild::OwnedKd;
use crate::scene::SceneData;
use coray::kd::{KdParams, Traversal};
use coray::TraceStats;
use coray_embree::{classify, Agreement, EmbreeScene};

pub struct Outcome {
    pub mismatches: usize,
    pub rays: usize,
}

/// Compares, prints the summary, writes the diff image (black: same,
/// yellow: documented tie, red: mismatch on the primary ray, blue: on a
/// shadow ray from that pixel).
pub fn compare(
    s: &SceneData,
    params: &KdParams,
    diff: &std::path::Path,
) -> Result<Outcome, String> {
    let owned = OwnedKd::build(&s.mesh.scene(), params)?;
    let tree = owned.tree(s.mesh.scene());
    let embree = EmbreeScene::new(&s.mesh.scene(), None);
    let primary = primary_rays(s);
    let mut st = TraceStats::default();
    let mine: Vec<_> = primary
        .iter()
        .map(|r| tree.intersect(r, Traversal::Hierarchical, &mut st))
        .collect();
    let theirs: Vec<_> = primary.iter().map(|r| embree.intersect(r)).collect();
    let (w, h) = (s.mesh.camera.width as usize, s.mesh.camera.height as usize);
    let mut image = vec![0u8; w * h * 3];
    let paint = |img: &mut [u8], px: usize, c: [u8; 3]| img[3 * px..3 * px + 3].copy_from_slice(&c);
    let (mut mismatches, mut ties, mut max_dt) = (0usize, 0usize, 0.0f32);
    for (i, r) in primary.iter().enumerate() {
        let (a, b) = (&mine[i], &theirs[i]);
        if a.is_hit() && b.is_hit() && (a.geom_id, a.prim_id) == (b.geom_id, b.prim_id) {
            max_dt = max_dt.max((a.t - b.t).abs());
        }
        match classify(r, a, b) {
            Agreement::Same => {}
            Agreement::TieSameDistance | Agreement::TieGrazing => {
                ties += 1;
                paint(&mut image, i, [255, 220, 0]);
            }
            Agreement::Mismatch => {
                mismatches += 1;
                paint(&mut image, i, [255, 0, 0]);
                if mismatches <= 10 {
                    println!(
                        "primary ray at pixel ({}, {}): coray {a:?}, Embree {b:?}",
                        i % w,
                        i / w
                    );
                }
            }
        }
    }
    // Shadow rays from the points both agree on, one per light.
    let shadow: Vec<_> = lit_shadow_rays(s, &mine)
        .into_iter()
        .map(|(_, r)| r)
        .collect();
    let mut owner = Vec::with_capacity(shadow.len());
    for (i, hit) in mine.iter().enumerate() {
        if hit.is_hit() {
            for _ in &s.mesh.lights {
                owner.push(i);
            }
        }
    }
    let mut shadow_mismatches = 0;
    for (k, r) in shadow.iter().enumerate() {
        let a = tree.occluded(r, Traversal::Hierarchical, &mut st);
        if a != embree.occluded(r) {
            // Judge by the closest hits: a tie there explains the difference.
            let (ca, cb) = (
                tree.intersect(r, Traversal::Hierarchical, &mut st),
                embree.intersect(r),
            );
            match classify(r, &ca, &cb) {
                Agreement::Mismatch | Agreement::Same => {
                    shadow_mismatches += 1;
                    if shadow_mismatches <= 10 {
                        println!("shadow ray {r:?}: coray occluded {a}, closest {ca:?}; Embree closest {cb:?}");
                    }
                    paint(&mut image, owner.get(k).copied().unwrap_or(0), [0, 80, 255]);
                }
                _ => ties += 1,
            }
        }
    }
    let rays = primary.len() + shadow.len();
    let total = mismatches + shadow_mismatches;
    println!(
        "{}: {} objects, {}x{} primary and {} shadow rays",
        s.name,
        s.mesh.counts.objects(),
        w,
        h,
        shadow.len()
    );
    println!("mismatches: {total} of {rays} rays ({mismatches} primary, {shadow_mismatches} shadow); {ties} documented ties");
    println!("largest |dt| on agreeing hits: {max_dt:e}");
    crate::render::write_png(diff, w as u32, h as u32, &image)?;
    println!("diff image: {}", diff.display());
    Ok(Outcome {
        mismatches: total,
        rays,
    })
}
