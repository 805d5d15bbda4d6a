//! `coray bench --table speed`: per scene and ray set, every method's
//! Mrays/s on the same rays in one run, the best coray method, and its
//! ratio to Embree's one-ray and packet calls. Runs are interleaved (each
//! repeat times every method once, in turn) and the best run counts.

use super::harness::{timed, trace};
use super::rays::{self, RaySet, Rays};
use super::row::{judge_any, judge_closest, tally};
use super::Settings;
use crate::built::{Built, Visit};
use crate::method::{EmbreeCall, Method};
use crate::scene::SceneData;
use crate::shoot::Shooter;
use coray::kd::{KdTree, Traversal};
use coray::lcts::{image_requirements, Scheme};
use coray::owned::OwnedCast;
use coray::{Hit, TraceStats};
use coray_ffi::simd::cast_image;
use serde::Serialize;

/// Incoherent rays per scene.
pub const INCOHERENT_RAYS: usize = 1_000_000;

/// The coray methods traced ray by ray on every set; `kd-c`, `kd-c1` and
/// `kd-c1-handle` are `kd` through the C ABI (array calls; one call per
/// ray on a tracer per thread; one call per ray with the handle and
/// stack), `wide-c1` is `wide` one call per ray on a tracer (the fastest
/// one-ray C call on incoherent rays).
pub const RAY_METHODS: [&str; 10] = [
    "kd",
    "kd-rope",
    "kd-packet",
    "tdbs-sah",
    "wide",
    "wide-packet",
    "kd-c",
    "kd-c1",
    "kd-c1-handle",
    "wide-c1",
];

/// The image casts timed on the primary set (one thread: a cast is one
/// call over the camera's image): the two 2D LCTS schemes, and the packet
/// tiles (the C cast's default).
pub const CASTS: [Scheme; 3] = [
    Scheme::Slcts2d { n: 5, m: 5 },
    Scheme::Hlcts2d,
    Scheme::Packets,
];

/// One method on one ray set.
#[derive(Clone, Debug, Serialize)]
pub struct Cell {
    /// The method's name.
    pub method: String,
    /// Millions of rays per second, best run.
    pub mrays: f64,
    /// Rays answering otherwise than the kd-tree's hierarchical traversal
    /// beyond the tie rules.
    pub mismatches: usize,
    /// Differences the tie rules explain.
    pub ties: usize,
}

/// One scene, one ray set, one thread count: every method.
#[derive(Clone, Debug, Serialize)]
pub struct SpeedRow {
    /// The scene.
    pub scene: String,
    /// The ray set.
    pub set: RaySet,
    /// Rays in it.
    pub rays: usize,
    /// Threads tracing.
    pub threads: usize,
    /// Every method.
    pub cells: Vec<Cell>,
}

impl SpeedRow {
    /// The fastest coray method.
    pub fn best(&self) -> Option<&Cell> {
        self.cells
            .iter()
            .filter(|c| !c.method.starts_with("embree"))
            .max_by(|a, b| a.mrays.total_cmp(&b.mrays))
    }

    /// A method's cell.
    pub fn cell(&self, method: &str) -> Option<&Cell> {
        self.cells.iter().find(|c| c.method == method)
    }
}

/// A set with its reference answers.
struct Set {
    rays: Rays,
    hits: Vec<Hit>,
    occluded: Vec<bool>,
}

fn reference(tree: &KdTree, rays: Rays) -> Set {
    let mut stk = coray::owned::stack(coray::kd::KD_STACK_LEN);
    let mut st = TraceStats::default();
    let m = Traversal::Hierarchical;
    let (mut hits, mut occluded) = (Vec::new(), Vec::new());
    if rays.set.any_hit() {
        occluded = rays
            .rays
            .iter()
            .map(|r| tree.occluded(r, m, &mut stk, &mut st))
            .collect();
    } else {
        hits = rays
            .rays
            .iter()
            .map(|r| tree.intersect(r, m, &mut stk, &mut st))
            .collect();
    }
    Set {
        rays,
        hits,
        occluded,
    }
}

/// Times one set through one built method.
struct TimeSet<'a> {
    set: &'a Set,
    threads: usize,
}

impl Visit for TimeSet<'_> {
    type Out = (f64, Vec<Hit>, Vec<bool>);
    fn visit<S: Shooter>(self, s: &S) -> Self::Out {
        let r = &self.set.rays;
        let lights = (!r.lights.is_empty()).then_some(&r.lights[..]);
        let (secs, hits, occ, _) = trace(s, &r.rays, lights, r.set.any_hit(), self.threads);
        (secs, hits, occ)
    }
}

/// The methods named (each registered), then Embree's one-ray and packet
/// calls when the build has them: the rows every table sets beside
/// Embree's.
pub fn with_embree(names: &[&str]) -> Vec<Method> {
    with_embree_methods(
        names
            .iter()
            .map(|m| Method::parse(m).expect("registered"))
            .collect(),
    )
}

/// `methods`, then Embree's one-ray and packet calls when the build has
/// them.
pub fn with_embree_methods(mut methods: Vec<Method>) -> Vec<Method> {
    if cfg!(feature = "embree") {
        methods.push(Method::Embree(EmbreeCall::One));
        methods.push(Method::Embree(EmbreeCall::Eight));
    }
    methods
}

/// Runs the speed table on one scene at each thread count: `methods`
/// (default [`RAY_METHODS`] and the casts) beside Embree's calls. The
/// reference answers and the casts' trees are built whether or not their
/// methods are listed; the casts run only by default.
pub fn run(
    s: &SceneData,
    set: &Settings,
    thread_counts: &[usize],
    methods: Option<&[Method]>,
) -> Result<Vec<SpeedRow>, String> {
    let methods = match methods {
        Some(m) => {
            let mut m = m.to_vec();
            m.retain(|m| !matches!(m, Method::Embree(_)));
            with_embree_methods(m)
        }
        None => with_embree(&RAY_METHODS),
    };
    let casts: &[Scheme] = if methods.len() == RAY_METHODS.len() + 2 {
        &CASTS
    } else {
        &[]
    };
    let threads_max = thread_counts.iter().copied().max().unwrap_or(1);
    let built: Vec<Built> = methods
        .iter()
        .map(|&m| Built::new(m, &s.mesh, set.preset, threads_max))
        .collect::<Result<_, _>>()?;
    let reference_kd = Built::new(
        Method::kd(Traversal::Hierarchical),
        &s.mesh,
        set.preset,
        threads_max,
    )?;
    let kd = reference_kd.kd().expect("a kd method");
    let tree = kd.tree(s.mesh.scene()).map_err(|e| e.to_string())?;
    // The casts walk ropes: kd-rope's tree (the same nodes, with ropes).
    let roped = Built::new(Method::kd_for_casts(), &s.mesh, set.preset, threads_max)?;
    let roped = roped.kd().expect("a kd method");
    let cast_tree = roped.tree(s.mesh.scene()).map_err(|e| e.to_string())?;
    let cam = &s.mesh.camera;
    // Primary rays in 4 x 2 pixel blocks, the order packets take them in.
    let row_major = rays::primary(&s.mesh);
    let order = rays::tile_order(cam.width, cam.height);
    let primary = reference(
        &tree,
        Rays {
            set: RaySet::Primary,
            rays: order.iter().map(|&i| row_major[i]).collect(),
            lights: Vec::new(),
            from: order.clone(),
        },
    );
    let mut row_hits = vec![Hit::MISS; row_major.len()];
    for (k, &px) in order.iter().enumerate() {
        row_hits[px] = primary.hits[k];
    }
    let shadow = rays::shadow(&s.mesh, &primary.rays.rays, &primary.hits);
    let sets = [
        primary,
        reference(&tree, shadow),
        reference(&tree, rays::incoherent(&s.mesh, INCOHERENT_RAYS)),
        reference(&tree, rays::diffuse(&row_major, &row_hits)),
    ];
    let pb = super::progress(thread_counts.len() * set.repeat * sets.len(), set.progress);
    pb.set_message(s.name.clone());
    let mut out = Vec::new();
    for &threads in thread_counts {
        // best[set][method] seconds; verdicts from the first run.
        let n_cast = if threads == 1 { casts.len() } else { 0 };
        let mut best = vec![vec![f64::INFINITY; built.len() + n_cast]; sets.len()];
        let mut judged: Vec<Vec<(usize, usize)>> = vec![Vec::new(); sets.len()];
        let mut cast_room: Vec<OwnedCast> = casts[..n_cast]
            .iter()
            .map(|&sc| OwnedCast::new(&image_requirements(cam.width, cam.height, sc, 512)))
            .collect();
        let mut cast_hits = vec![Hit::MISS; row_major.len()];
        // Casts trace the camera's own rays (directions not unit): their
        // reference is the hierarchical cast of the same pixels.
        let mut cast_ref = vec![Hit::MISS; row_major.len()];
        if n_cast > 0 {
            let req = image_requirements(cam.width, cam.height, Scheme::Hierarchical, 512);
            cast_image(
                &cast_tree,
                cam,
                Scheme::Hierarchical,
                OwnedCast::new(&req).scratch(),
                &mut cast_ref,
            )
            .map_err(|e| e.to_string())?;
        }
        for rep in 0..set.repeat {
            for (si, st) in sets.iter().enumerate() {
                for (mi, b) in built.iter().enumerate() {
                    let (secs, hits, occ) = b.visit(TimeSet { set: st, threads });
                    best[si][mi] = best[si][mi].min(secs);
                    if rep == 0 {
                        let v = if st.rays.set.any_hit() {
                            judge_any(b, &tree, &st.rays.rays, &occ, &st.occluded)
                        } else {
                            judge_closest(b, &st.rays.rays, &hits, &st.hits)
                        };
                        judged[si].push(tally(&v));
                    }
                }
                if st.rays.set == RaySet::Primary {
                    for (ci, &sc) in casts[..n_cast].iter().enumerate() {
                        let (secs, r) = timed(|| {
                            cast_image(&cast_tree, cam, sc, cast_room[ci].scratch(), &mut cast_hits)
                        });
                        r.map_err(|e| e.to_string())?;
                        best[si][built.len() + ci] = best[si][built.len() + ci].min(secs);
                        if rep == 0 {
                            judged[si].push(super::row::cast_agreement(&cast_hits, &cast_ref));
                        }
                    }
                }
                pb.inc(1);
            }
        }
        for (si, st) in sets.iter().enumerate() {
            let n = st.rays.rays.len();
            let names = methods.iter().map(|m| m.to_string()).chain(
                casts[..n_cast]
                    .iter()
                    .map(|&scheme| Method::Cast { scheme }.to_string()),
            );
            let cells = names
                .enumerate()
                .filter(|&(mi, _)| mi < built.len() || st.rays.set == RaySet::Primary)
                .map(|(mi, method)| Cell {
                    method,
                    mrays: n as f64 / best[si][mi] / 1e6,
                    mismatches: judged[si][mi].0,
                    ties: judged[si][mi].1,
                })
                .collect();
            out.push(SpeedRow {
                scene: s.name.clone(),
                set: st.rays.set,
                rays: n,
                threads,
                cells,
            });
        }
    }
    pb.finish_and_clear();
    Ok(out)
}

/// The legend under the speed table.
pub const LEGEND: &str = "\
columns: rays = rays in the set (primary: one per pixel in 4 x 2 blocks; shadow: every primary
  hit towards every light; incoherent: 1,000,000 rays, origins uniform in the scene box,
  directions uniform on the sphere, seed 2026; diffuse: one cosine-distributed bounce from
  every primary hit); best = the fastest coray method on that set and its Mrays/s (casts
  count for primary rays); embree1 / embree8 = rtcIntersect1 / rtcIntersect8 (rtcOccluded1
  / rtcOccluded8 for shadow rays) Mrays/s; x e1, x e8 = best over each; then every method's
  Mrays/s on the same rays (kd-c / kd-c1 / kd-c1-handle: kd through the C ABI, one
  coray_kdtree_intersect call per 4096 rays / one coray_kdtree_tracer_intersect1 call per
  ray on a tracer per thread / one coray_kdtree_intersect1 call per ray with the handle and
  stack; occluded likewise; wide-c1: wide likewise, one coray_wide_tracer_intersect1 call
  per ray on a tracer per thread); slcts2d / hlcts2d / cast-packets: coray_kdtree_cast_image over
  the camera's image, one thread, by SLCTS-2D, HLCTS-2D and 4 x 2 packet tiles, the C cast's
  default); mism = rays of any coray method answering otherwise than the
  kd-tree's hierarchical traversal (Embree: beyond coray::tolerance's tie rules). Best of
  --repeat runs, methods interleaved.";

/// Prints the rows: the summary, then every method's Mrays/s.
pub fn print(rows: &[SpeedRow]) {
    let Some(first) = rows.first() else {
        return;
    };
    let names: Vec<&str> = first.cells.iter().map(|c| c.method.as_str()).collect();
    print!(
        "{:<16} {:<10} {:>3} {:>8} {:>18} {:>8} {:>8} {:>6} {:>6} {:>5}",
        "scene", "set", "thr", "rays", "best (Mr/s)", "embree1", "embree8", "x e1", "x e8", "mism"
    );
    for n in names.iter().filter(|n| !n.starts_with("embree")) {
        print!(" {n:>9}");
    }
    println!();
    for r in rows {
        let Some(b) = r.best() else { continue };
        let e = |m: &str| r.cell(m).map(|c| c.mrays);
        let f = |v: Option<f64>, p: usize| v.map_or("-".into(), |x| format!("{x:.p$}"));
        let mism: usize = r
            .cells
            .iter()
            .filter(|c| !c.method.starts_with("embree"))
            .map(|c| c.mismatches)
            .sum();
        print!(
            "{:<16} {:<10} {:>3} {:>8} {:>18} {:>8} {:>8} {:>6} {:>6} {:>5}",
            r.scene,
            r.set.name(),
            r.threads,
            r.rays,
            format!("{} {:.2}", b.method, b.mrays),
            f(e("embree"), 2),
            f(e("embree8"), 2),
            f(e("embree").map(|x| b.mrays / x), 2),
            f(e("embree8").map(|x| b.mrays / x), 2),
            mism
        );
        for n in names.iter().filter(|n| !n.starts_with("embree")) {
            print!(" {:>9}", f(r.cell(n).map(|c| c.mrays), 2));
        }
        println!();
    }
    println!("{LEGEND}");
}
