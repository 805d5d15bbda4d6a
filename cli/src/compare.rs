//! `coray compare`: primary and shadow rays through coray's kd-tree and
//! Embree in one process, ray by ray, judged by the one tie rule the
//! benchmark uses too ([`crate::bench::row::judge`]); a diff image.

use crate::bench::row::{self, Verdicts};
use crate::built::Built;
use crate::method::{EmbreeCall, Method, Preset};
use crate::scene::SceneData;
use coray::kd::Traversal;
use coray::tolerance::Agreement;

/// What the comparison found.
pub struct Outcome {
    /// Rays that disagree beyond the tie rules.
    pub mismatches: usize,
    /// Rays compared.
    pub rays: usize,
}

/// Compares, prints the summary, writes the diff image (black: same,
/// yellow: documented tie, red: mismatch on the primary ray, blue: on a
/// shadow ray from that pixel).
pub fn compare(
    s: &SceneData,
    preset: Preset,
    threads: usize,
    diff: &std::path::Path,
) -> Result<Outcome, String> {
    let embree = Built::new(Method::Embree(EmbreeCall::One), &s.mesh, preset, threads)?;
    let ours = Built::new(
        Method::kd(Traversal::Hierarchical),
        &s.mesh,
        preset,
        threads,
    )?;
    let tree = ours
        .kd()
        .expect("a kd method")
        .tree(s.mesh.scene())
        .map_err(|e| e.to_string())?;
    let w = row::workload(&s.mesh, &tree);
    let theirs = row::run_rays(&embree, &w, &tree, 1, threads);
    let v: Verdicts = row::judge(&embree, &w, &tree, &theirs.hits, &theirs.occluded);
    let (wd, ht) = (s.mesh.camera.width as usize, s.mesh.camera.height as usize);
    let mut image = vec![0u8; wd * ht * 3];
    let paint = |img: &mut [u8], px: usize, c: [u8; 3]| img[3 * px..3 * px + 3].copy_from_slice(&c);
    let mut max_dt = 0.0f32;
    let (mut primary_mismatches, mut shown) = (0, 0);
    for (i, a) in v.primary.iter().enumerate() {
        let (mine, their) = (&w.hits[i], &theirs.hits[i]);
        match a {
            Agreement::Same => {
                if mine.is_hit() {
                    max_dt = max_dt.max((mine.t - their.t).abs());
                }
            }
            Agreement::TieSameDistance | Agreement::TieGrazing => {
                paint(&mut image, i, [255, 220, 0])
            }
            Agreement::Mismatch => {
                primary_mismatches += 1;
                paint(&mut image, i, [255, 0, 0]);
                if shown < 10 {
                    shown += 1;
                    println!(
                        "primary ray at pixel ({}, {}): coray {mine:?}, Embree {their:?}",
                        i % wd,
                        i / wd
                    );
                }
            }
        }
    }
    let mut shadow_mismatches = 0;
    for (k, a) in v.shadow.iter().enumerate() {
        if *a == Agreement::Mismatch {
            shadow_mismatches += 1;
            paint(&mut image, w.shadow.from[k], [0, 80, 255]);
            if shown < 10 {
                shown += 1;
                println!(
                    "shadow ray {:?}: coray occluded {}, Embree {}",
                    w.shadow.rays[k], w.occluded[k], theirs.occluded[k]
                );
            }
        }
    }
    let (mismatches, ties) = v.counts();
    let rays = w.primary.len() + w.shadow.rays.len();
    println!(
        "{}: {} objects, {wd}x{ht} primary and {} shadow rays",
        s.name,
        s.mesh.counts.objects(),
        w.shadow.rays.len()
    );
    println!(
        "mismatches: {mismatches} of {rays} rays ({primary_mismatches} primary, \
         {shadow_mismatches} shadow); {ties} documented ties (coray::tolerance)"
    );
    println!("largest |dt| on agreeing hits: {max_dt:e}");
    crate::render::write_image(diff, wd as u32, ht as u32, &image)?;
    println!("diff image: {}", diff.display());
    Ok(Outcome { mismatches, rays })
}
