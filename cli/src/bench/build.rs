//! `coray bench --table build`: what a build costs, coray's structures
//! beside Embree's, in one run: milliseconds (best of the repeats, the
//! builders interleaved) and bytes per primitive. coray's bytes are the
//! tree's (what its C build packs at the arena's start: the caller keeps
//! only those) and, borrowed for the build, the rest of the arena its
//! requirements ask for plus the scratch; Embree's are what its device memory monitor saw the commit
//! allocate (kept, and the most held during it), the scene's own copies
//! excluded. kd-auto and Embree build at one thread and at `--threads N`
//! (coray's build jobs on N threads). Beside the builds, primary rays at
//! the scene's resolution traced through kd-auto's tree (hierarchical and
//! packets) and through Embree's scene (`rtcIntersect1`, `rtcIntersect8`),
//! interleaved, so a faster build is read beside what its tree traces.

use crate::method::Preset;
use coray::owned::{OwnedBvh, OwnedKd, OwnedWide};
use coray::Scene;
use serde::Serialize;
use std::time::Instant;

/// One builder on one scene.
#[derive(Clone, Debug, Serialize)]
pub struct BuildCell {
    /// The builder: kd-auto, kd-paper, tdbs-sah, wide, embree (threads).
    pub builder: String,
    /// Best build time (ms).
    pub ms: f64,
    /// Bytes the structure keeps, per primitive.
    pub bytes_per_prim: f64,
    /// Bytes the build borrows beyond that (coray's scratch; Embree's peak
    /// above what it keeps), per primitive.
    pub scratch_per_prim: f64,
    /// A kd build that ran out of room.
    pub truncated: bool,
}

/// One traversal of the scene's primary rays.
#[derive(Clone, Debug, Serialize)]
pub struct TraceCell {
    /// The method, as the speed table names it (kd, kd-packet, embree,
    /// embree8).
    pub method: String,
    /// Millions of rays per second, best run, one thread.
    pub mrays: f64,
    /// Rays answering otherwise than kd-auto's hierarchical traversal
    /// (Embree: beyond the tie rules).
    pub mismatches: usize,
}

/// One scene: every builder, and the primary rays traced.
#[derive(Clone, Debug, Serialize)]
pub struct BuildRow {
    /// The scene.
    pub scene: String,
    /// Primitives after triangulation.
    pub prims: usize,
    /// Every builder.
    pub cells: Vec<BuildCell>,
    /// Primary rays (width x height of the scene's camera) through
    /// kd-auto's tree and Embree's.
    pub rays: usize,
    /// Every traversal of them.
    pub trace: Vec<TraceCell>,
}

/// The methods of the traversal columns.
const TRACE_METHODS: [&str; 4] = ["kd", "kd-packet", "kd-compact", "kd-compact-packet"];

/// Primary rays through kd-auto's tree (hierarchical, packets) and
/// Embree's, one thread, methods interleaved, best of `repeat`; each
/// method's answers judged against kd-auto's hierarchical traversal.
fn trace_primary(s: &crate::scene::SceneData, repeat: usize) -> Result<Vec<TraceCell>, String> {
    use super::harness::trace;
    use super::row::{judge_closest, tally};
    use crate::built::{Built, Visit};
    use crate::shoot::Shooter;
    let methods = super::speed::with_embree(&TRACE_METHODS);
    let built: Vec<Built> = methods
        .iter()
        .map(|&m| Built::new(m, &s.mesh, Preset::Auto, 1))
        .collect::<Result<_, _>>()?;
    let row_major = super::rays::primary(&s.mesh);
    let cam = &s.mesh.camera;
    let rays: Vec<coray::Ray> = super::rays::tile_order(cam.width, cam.height)
        .iter()
        .map(|&i| row_major[i])
        .collect();
    struct Time<'a>(&'a [coray::Ray]);
    impl Visit for Time<'_> {
        type Out = (f64, Vec<coray::Hit>);
        fn visit<S: Shooter>(self, s: &S) -> Self::Out {
            let (secs, hits, _, _) = trace(s, self.0, None, false, 1);
            (secs, hits)
        }
    }
    let mut best = vec![f64::INFINITY; built.len()];
    let mut judged = Vec::new();
    let mut reference = Vec::new();
    for rep in 0..repeat.max(1) {
        for (mi, b) in built.iter().enumerate() {
            let (secs, hits) = b.visit(Time(&rays));
            best[mi] = best[mi].min(secs);
            if rep == 0 {
                if mi == 0 {
                    reference = hits.clone();
                }
                judged.push(tally(&judge_closest(b, &rays, &hits, &reference)).0);
            }
        }
    }
    Ok(methods
        .iter()
        .zip(best.iter().zip(judged))
        .map(|(m, (secs, mismatches))| TraceCell {
            method: m.to_string(),
            mrays: rays.len() as f64 / secs / 1e6,
            mismatches,
        })
        .collect())
}

fn kd(scene: &Scene, preset: Preset, name: &str, threads: usize) -> Result<BuildCell, String> {
    let params = preset.params();
    let req = coray::kd::requirements(scene.prim_count(), &params);
    let mut o = OwnedKd::with_room(&req);
    let t = Instant::now();
    o.build_with_jobs(scene, &params, threads, |jobs| {
        crate::kd_jobs::run(jobs, threads, scene.prim_count())
    })
    .map_err(|e| format!("{name}: {e}"))?;
    let ms = t.elapsed().as_secs_f64() * 1e3;
    let n = scene.prim_count().max(1) as f64;
    let scratch = coray::kd::layout::KdScratchLayout::of(&req).map_or(0, |l| l.total_bytes);
    // The C build packs the tree at its arena's start: the caller keeps
    // arena_bytes_used (o.arena_bytes()) and lends the rest of the
    // requirements' arena, with the scratch, for the build only.
    let room = coray::kd::layout::KdArenaLayout::of(&req).map_or(0, |l| l.total_bytes);
    let kept = o.arena_bytes();
    Ok(BuildCell {
        builder: name.into(),
        ms,
        bytes_per_prim: kept as f64 / n,
        scratch_per_prim: (room.saturating_sub(kept) + scratch) as f64 / n,
        truncated: o.info().truncated(),
    })
}

fn tdbs_sah(scene: &Scene) -> Result<BuildCell, String> {
    let how = coray::owned::BvhBuild::Static(coray::bvh::Builder::TdbsSah, 1);
    let mut o = OwnedBvh::with_room(scene.prim_count(), how);
    let t = Instant::now();
    o.build(scene).map_err(|e| format!("tdbs-sah: {e}"))?;
    let ms = t.elapsed().as_secs_f64() * 1e3;
    let n = scene.prim_count().max(1) as f64;
    let req = coray::bvh::requirements(scene.prim_count(), coray::bvh::Builder::TdbsSah);
    let scratch = coray::bvh::layout::BvhScratchLayout::of(&req).map_or(0, |l| l.total_bytes);
    Ok(BuildCell {
        builder: "tdbs-sah".into(),
        ms,
        bytes_per_prim: o.bytes() as f64 / n,
        scratch_per_prim: scratch as f64 / n,
        truncated: false,
    })
}

fn wide(scene: &Scene) -> Result<BuildCell, String> {
    let mut o = OwnedWide::with_room(scene.prim_count());
    let t = Instant::now();
    o.build(scene, crate::method::WIDE_LEAF_SIZE)
        .map_err(|e| format!("wide: {e}"))?;
    let ms = t.elapsed().as_secs_f64() * 1e3;
    let n = scene.prim_count().max(1) as f64;
    let req = coray::wide::requirements(scene.prim_count());
    let scratch = coray::wide::layout::WideScratchLayout::of(&req).map_or(0, |l| l.total_bytes);
    // The arena's node room bounds the nodes; the build uses fewer.
    let room = coray::wide::layout::WideArenaLayout::for_build(&req).map_or(0, |l| l.total_bytes);
    Ok(BuildCell {
        builder: "wide".into(),
        ms,
        bytes_per_prim: o.bytes() as f64 / n,
        scratch_per_prim: (room.saturating_sub(o.bytes()) + scratch) as f64 / n,
        truncated: false,
    })
}

#[cfg(feature = "embree")]
fn embree(scene: &Scene, threads: usize) -> Result<BuildCell, String> {
    let e = coray_embree::EmbreeScene::new(scene, Some(threads as u32));
    let (secs, kept, peak) = e.build_cost();
    let n = scene.prim_count().max(1) as f64;
    Ok(BuildCell {
        builder: format!("embree ({threads} thr)"),
        ms: secs * 1e3,
        bytes_per_prim: kept as f64 / n,
        scratch_per_prim: peak.saturating_sub(kept) as f64 / n,
        truncated: false,
    })
}

/// Builds every builder `repeat` times in turn on `s`; the best time of
/// each counts. Embree at 1 thread and, when `threads` > 1, at `threads`.
pub fn run(s: &crate::scene::SceneData, repeat: usize, threads: usize) -> Result<BuildRow, String> {
    type Builder<'a> = Box<dyn Fn(&Scene) -> Result<BuildCell, String> + 'a>;
    #[allow(unused_mut)] // nothing more is pushed without Embree
    let mut builders: Vec<Builder> = vec![Box::new(|sc| kd(sc, Preset::Auto, "kd-auto", 1))];
    if threads > 1 {
        let name = format!("kd-auto ({threads} thr)");
        builders.push(Box::new(move |sc| kd(sc, Preset::Auto, &name, threads)));
    }
    builders.push(Box::new(|sc| kd(sc, Preset::Paper, "kd-paper", 1)));
    builders.push(Box::new(|sc| kd(sc, Preset::Compact, "kd-compact", 1)));
    builders.push(Box::new(tdbs_sah));
    builders.push(Box::new(wide));
    #[cfg(feature = "embree")]
    {
        builders.push(Box::new(|sc| embree(sc, 1)));
        if threads > 1 {
            builders.push(Box::new(move |sc| embree(sc, threads)));
        }
    }
    let scene = s.mesh.scene();
    let mut cells: Vec<Option<BuildCell>> = vec![None; builders.len()];
    for _ in 0..repeat.max(1) {
        for (b, cell) in builders.iter().zip(cells.iter_mut()) {
            let c = b(&scene)?;
            if cell.as_ref().is_none_or(|best| c.ms < best.ms) {
                *cell = Some(c);
            }
        }
    }
    let trace = trace_primary(s, repeat)?;
    Ok(BuildRow {
        scene: s.name.clone(),
        prims: scene.prim_count(),
        cells: cells.into_iter().map(|c| c.expect("built")).collect(),
        rays: (s.mesh.camera.width * s.mesh.camera.height) as usize,
        trace,
    })
}

/// The legend under the table.
pub const LEGEND: &str = "\
columns: prims = primitives after triangulation; per builder: ms = best build time of
  --repeat runs (builders interleaved; Embree: rtcCommitScene alone, device and buffer
  copies excluded), B/p = bytes the structure keeps per primitive (coray: the tree its
  build packs at the arena's start; Embree: what its memory monitor saw the commit keep),
  +s = bytes per primitive the build borrows beyond that (coray: the rest of the arena its
  requirements ask for, and the scratch; Embree: its peak above what it keeps), T = a kd
  build that ran out of room; kd-auto (N thr) = the same build, its jobs on N threads (the
  tree is byte for byte the one-thread build's; a build that runs out of room falls back
  to one pass on one thread); x = kd-auto's time over Embree's at one thread, xN = at N.
  kd-auto keeps no ropes (hierarchical and packet traversal need none; with ropes, for
  rope traversal and the LCTS casts, a leaf takes 48 bytes more); kd-paper keeps them;
  kd-compact = kd-auto's tree without its empty leaves beside full ones.
  wide = tdbs-sah's sweep with a triangle priced at half a sphere's test (leaves of up to
  4 where the SAH prices them lower), collapsed into 4-wide nodes; its +s holds the binary
  hierarchy and the node room the collapse did not use. Primary Mr/s: the scene's
  primary rays (one per pixel at --res, in 4 x 2 pixel blocks) on one thread through
  kd-auto's tree, hierarchical (kd) and in packets (kd-packet), through kd-compact's
  alike (kd-compact, kd-compact-packet: the same steps, each node's children decoded),
  and through Embree's scene (e1 = rtcIntersect1, e8 = rtcIntersect8); best of
  --repeat runs, methods interleaved; mism = rays answering otherwise than kd.";

/// Prints the rows.
pub fn print(rows: &[BuildRow]) {
    let Some(first) = rows.first() else { return };
    let mut head = format!("{:<14} {:>7}", "scene", "prims");
    for c in &first.cells {
        head += &format!(" | {:>22}", c.builder);
    }
    let threads = first
        .cells
        .iter()
        .find_map(|c| c.builder.strip_prefix("kd-auto (")?.strip_suffix(" thr)"))
        .map(str::to_owned);
    head += " |      x";
    if let Some(t) = &threads {
        head += &format!(" | {:>6}", format!("x{t}"));
    }
    let width = 9 * first.trace.len() + 5;
    head += &format!(" | {:>width$}", "primary Mr/s");
    println!("{head}");
    let mut sub = format!("{:<14} {:>7}", "", "");
    for _ in &first.cells {
        sub += &format!(" | {:>8} {:>6} {:>6}", "ms", "B/p", "+s");
    }
    sub += &format!(" | {:>6}", "");
    if threads.is_some() {
        sub += &format!(" | {:>6}", "");
    }
    sub += " |";
    for t in &first.trace {
        let short = match t.method.as_str() {
            "embree" => "e1",
            "embree8" => "e8",
            m => m,
        };
        sub += &format!(" {short:>8}");
    }
    sub += &format!(" {:>4}", "mism");
    println!("{sub}");
    for r in rows {
        let mut line = format!("{:<14} {:>7}", r.scene, r.prims);
        for c in &r.cells {
            line += &format!(
                " | {:>7.1}{} {:>6.0} {:>6.0}",
                c.ms,
                if c.truncated { "T" } else { " " },
                c.bytes_per_prim,
                c.scratch_per_prim
            );
        }
        let ratio = |kd: &str, embree: &str| {
            let cell = |name: &str| r.cells.iter().find(|c| c.builder == name);
            match (cell(kd), cell(embree)) {
                (Some(k), Some(e)) => format!(" | {:>6.1}", k.ms / e.ms.max(1e-9)),
                _ => " |      -".to_owned(),
            }
        };
        line += &ratio("kd-auto", "embree (1 thr)");
        if let Some(t) = &threads {
            line += &ratio(&format!("kd-auto ({t} thr)"), &format!("embree ({t} thr)"));
        }
        line += " |";
        for t in &r.trace {
            line += &format!(" {:>8.2}", t.mrays);
        }
        line += &format!(
            " {:>4}",
            r.trace.iter().map(|t| t.mismatches).sum::<usize>()
        );
        println!("{line}");
    }
    println!("{LEGEND}");
}
