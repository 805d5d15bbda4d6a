//! The thesis' scene ladders (`coray bench --table bvh-series|proj-series`):
//! every method of a study on every size of every ladder, a whole render
//! timed per method, the metrics printed per ladder and drawn as charts,
//! and the thesis' observations checked against the numbers. A study is
//! data ([`Study`]): its ladders, its methods, its metrics and its claims
//! ([`claims`]); this module runs and prints any of them.

pub mod bvh;
pub mod claims;
pub mod proj;

use crate::bench::{self, Settings};
use crate::built::{Built, Visit};
use crate::method::Method;
use crate::plot::{self, Curve, Panel};
use crate::render::{self, Tracer};
use crate::scene::{self, SceneData};
use crate::shoot::Shooter;
use coray::Vec3;
use coray_scenes::spd::Options;
use serde::Serialize;
use std::time::Instant;

/// One ladder of scenes: an SPD scene at a range of sizes.
pub struct Ladder {
    /// Its name in tables and claims.
    pub name: &'static str,
    /// The SPD scene.
    pub scene: &'static str,
    /// Its sizes.
    pub sizes: std::ops::RangeInclusive<u32>,
    /// Floor cut into k x k pieces (thesis 6.3.6); 1 keeps it whole.
    pub floor_split: u32,
    /// Replace the scene's lights by this many inside its box (0: keep).
    pub lights: usize,
}

/// What is shown of a point, per ladder, method and size.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Metric {
    /// A whole one-thread render (s).
    RenderS,
    /// Preprocessing, all of it (ms).
    BuildMs,
    /// Preprocessing of the camera's projection hierarchy (ms).
    ViewMs,
    /// Preprocessing of the lights' projection hierarchies (ms).
    LightMs,
    /// Preprocessing of the global 3D hierarchy (ms).
    GlobalMs,
    /// View and light preprocessing (ms).
    ProjectionMs,
    /// Primitives tested per primary ray.
    ObjectsPerRay,
    /// The thesis' cost per hierarchy object.
    CostPerBox,
    /// The thesis' cost per actual object.
    CostPerPrim,
    /// Shadow rays asking every light over shadow rays knowing theirs.
    UniformOverKnown,
    /// Reflection and refraction rays per primary ray.
    SecondaryPerPrimary,
}

impl Metric {
    /// Its name in tables and charts.
    pub fn name(self) -> &'static str {
        match self {
            Metric::RenderS => "ray tracing s",
            Metric::BuildMs => "preprocessing ms",
            Metric::ViewMs => "view preprocessing ms",
            Metric::LightMs => "light preprocessing ms",
            Metric::GlobalMs => "global preprocessing ms",
            Metric::ProjectionMs => "projection preprocessing ms",
            Metric::ObjectsPerRay => "objects per primary ray",
            Metric::CostPerBox => "cost per hierarchy object",
            Metric::CostPerPrim => "cost per actual object",
            Metric::UniformOverKnown => "uniform / known shadow time",
            Metric::SecondaryPerPrimary => "secondary per primary ray",
        }
    }

    /// Its value at a point.
    pub fn of(self, p: &Point) -> Option<f64> {
        match self {
            Metric::RenderS => Some(p.render_s),
            Metric::BuildMs => Some(p.build_ms),
            Metric::ViewMs => p.split.map(|s| s[0]),
            Metric::LightMs => p.split.map(|s| s[1]),
            Metric::GlobalMs => Some(p.split.map_or(p.build_ms, |s| s[2])),
            Metric::ProjectionMs => p.split.map(|s| s[0] + s[1]),
            Metric::ObjectsPerRay => p.objects_per_ray,
            Metric::CostPerBox => p.cost_per_box,
            Metric::CostPerPrim => p.cost_per_prim,
            Metric::UniformOverKnown => Some(p.shadow_uniform_s? / p.shadow_s),
            Metric::SecondaryPerPrimary => Some(p.secondary_per_primary),
        }
    }
}

/// A study: what the thesis measured over which ladders, and what it
/// concluded.
pub struct Study {
    /// `--table` name.
    pub table: &'static str,
    /// The line above the tables.
    pub title: &'static str,
    /// The ladders.
    pub ladders: &'static [Ladder],
    /// The methods, in table order.
    pub methods: fn() -> Vec<Method>,
    /// Rows per ladder.
    pub metrics: &'static [Metric],
    /// The charts' metrics.
    pub plot_metrics: &'static [Metric],
    /// The charts' methods (names).
    pub plot_methods: fn() -> Vec<String>,
    /// The observations checked.
    pub claims: &'static [claims::Claim],
    /// Which section of the thesis.
    pub section: &'static str,
}

/// Every study.
pub const STUDIES: [&Study; 2] = [&bvh::STUDY, &proj::STUDY];

/// One method on one scene of a ladder.
#[derive(Clone, Debug, Serialize)]
pub struct Point {
    /// The ladder.
    pub ladder: &'static str,
    /// The size factor.
    pub size: u32,
    /// Objects as the SPD counts them.
    pub objects: usize,
    /// The method's name.
    pub method: String,
    /// Preprocessing (ms).
    pub build_ms: f64,
    /// Projection methods: view, light and global preprocessing (ms).
    pub split: Option<[f64; 3]>,
    /// Whole render, one thread, best of `repeat` (s).
    pub render_s: f64,
    /// Rays of that render.
    pub render_rays: u64,
    /// Primitives tested per primary ray.
    pub objects_per_ray: Option<f64>,
    /// The thesis' cost per hierarchy object.
    pub cost_per_box: Option<f64>,
    /// The thesis' cost per actual object.
    pub cost_per_prim: Option<f64>,
    /// Shadow rays knowing their light (s).
    pub shadow_s: f64,
    /// Shadow rays asking every light (projection methods; s).
    pub shadow_uniform_s: Option<f64>,
    /// Rays answering otherwise than the kd-tree.
    pub mismatches: usize,
    /// Of the image plane's covered area, how often it is covered: the sum
    /// of the primitives' rectangle areas over their union's bounding
    /// rectangle (the 2D overlap the thesis' conclusions speak of).
    pub overlap: f64,
    /// Reflection and refraction rays per primary ray.
    pub secondary_per_primary: f64,
}

/// Reflection and refraction depth of the timed renders.
pub const RENDER_DEPTH: u32 = 5;

/// A one-thread render through a built method: (best seconds, rays,
/// secondary rays).
struct TimeRender<'a> {
    s: &'a SceneData,
    repeat: usize,
}

impl Visit for TimeRender<'_> {
    type Out = Result<(f64, u64, u64), String>;
    fn visit<S: Shooter>(self, shooter: &S) -> Self::Out {
        let (mut best, mut rays, mut secondary) = (f64::INFINITY, 0, 0);
        for _ in 0..self.repeat.max(1) {
            let tracer = Tracer {
                mesh: &self.s.mesh,
                shooter,
                max_depth: RENDER_DEPTH,
                rules: render::Rules::WHITTED,
            };
            let t = Instant::now();
            let (_, st, counts) = render::render(&tracer, 1, false)?;
            best = best.min(t.elapsed().as_secs_f64());
            rays = st.rays;
            secondary = counts.secondary_rays();
        }
        Ok((best, rays, secondary))
    }
}

/// `count` light positions inside `b`: spread over the upper half of the
/// box (where a tree's lights hang), deterministic.
fn lights_inside(b: &coray::Aabb, count: usize) -> Vec<(Vec3, Vec3)> {
    const AT: [[f32; 3]; 7] = [
        [0.5, 0.5, 0.8],
        [0.2, 0.3, 0.6],
        [0.8, 0.3, 0.7],
        [0.3, 0.8, 0.65],
        [0.75, 0.75, 0.9],
        [0.5, 0.15, 0.55],
        [0.15, 0.6, 0.85],
    ];
    AT.iter()
        .take(count)
        .map(|f| (b.min + (b.max - b.min) * Vec3::from(*f), Vec3::splat(1.0)))
        .collect()
}

/// The image plane's 2D overlap: summed rectangle areas of the primitives
/// (clipped to the view) over the area of the view they cover.
fn overlap(s: &SceneData) -> f64 {
    let scene = s.mesh.scene();
    let plane = coray::proj::ProjPlane::camera(&s.mesh.camera);
    let (_, r, u) = s.mesh.camera.basis();
    // The view spans [-|r|, |r|] x [-|u|, |u|] on the plane (unit axes).
    let (w, h) = (r.length(), u.length());
    let mut sum = 0.0f64;
    let mut cover = coray::proj::Rect::EMPTY;
    for p in 0..scene.prim_count() {
        let Some(b) = scene.prim_bounds(p) else {
            continue;
        };
        let q = plane.project_box(&b);
        let lo = [q.min[0].max(-w), q.min[1].max(-h)];
        let hi = [q.max[0].min(w), q.max[1].min(h)];
        if lo[0] < hi[0] && lo[1] < hi[1] {
            sum += ((hi[0] - lo[0]) * (hi[1] - lo[1])) as f64;
            cover = cover.union(&coray::proj::Rect {
                min: lo,
                max: hi,
                near: 0.0,
            });
        }
    }
    if cover.is_empty() {
        return 0.0;
    }
    sum / ((cover.max[0] - cover.min[0]) * (cover.max[1] - cover.min[1])) as f64
}

/// Runs `study` on every ladder (sizes above `max_size` left out) at
/// `res` x `res`, one thread.
pub fn run(
    study: &Study,
    res: u32,
    max_size: Option<u32>,
    set: &Settings,
) -> Result<Vec<Point>, String> {
    let methods = (study.methods)();
    let one = Settings {
        repeat: 1,
        threads: 1,
        ..*set
    };
    let mut out = Vec::new();
    for l in study.ladders {
        for size in l.sizes.clone() {
            if max_size.is_some_and(|m| size > m) {
                continue;
            }
            let opts = Options {
                floor_split: l.floor_split,
            };
            let mut s = scene::load(&format!("spd:{}:{size}", l.scene), &opts)?;
            s.set_resolution(res as u64, res as u64)?;
            if l.lights > 0 {
                s.mesh.lights = lights_inside(&s.mesh.scene().bounds(), l.lights);
            }
            let overlap = overlap(&s);
            let rows = bench::bench(&s, &methods, &one)?;
            let primary = (res as f64) * (res as f64);
            // bench() puts the kd reference first when it is not listed.
            let reference = usize::from(rows.len() > methods.len());
            for (m, row) in methods.iter().zip(&rows[reference..]) {
                let built = Built::new(*m, &s.mesh, set.preset, 1)?;
                let (render_s, render_rays, secondary) = built.visit(TimeRender {
                    s: &s,
                    repeat: set.repeat,
                })?;
                out.push(Point {
                    ladder: l.name,
                    size,
                    objects: s.mesh.counts.objects(),
                    method: row.method.clone(),
                    build_ms: row.build_ms,
                    split: row.build_split,
                    render_s,
                    render_rays,
                    objects_per_ray: row.isect_per_ray,
                    cost_per_box: row.cost_per_box,
                    cost_per_prim: row.cost_per_prim,
                    shadow_s: row.shadow_s,
                    shadow_uniform_s: row.shadow_uniform_s,
                    mismatches: row.mismatches,
                    overlap,
                    secondary_per_primary: secondary as f64 / primary,
                });
            }
        }
    }
    Ok(out)
}

/// The sizes of a ladder present in `pts`, ascending.
pub fn sizes(pts: &[Point], ladder: &str) -> Vec<u32> {
    let mut v: Vec<u32> = pts
        .iter()
        .filter(|p| p.ladder == ladder)
        .map(|p| p.size)
        .collect();
    v.sort_unstable();
    v.dedup();
    v
}

/// The point of one method on one scene.
pub fn find<'a>(pts: &'a [Point], ladder: &str, size: u32, method: &str) -> Option<&'a Point> {
    pts.iter()
        .find(|p| p.ladder == ladder && p.size == size && p.method == method)
}

/// The methods of `pts` in table order.
pub fn methods(pts: &[Point]) -> Vec<String> {
    let mut v: Vec<String> = Vec::new();
    for p in pts {
        if !v.contains(&p.method) {
            v.push(p.method.clone());
        }
    }
    v
}

/// One block per ladder: the scene's figures, then a row per metric and
/// method, a column per size; the claims checked; the legend.
pub fn print(study: &Study, pts: &[Point], res: u32) {
    println!(
        "{}: {res}x{res}, one thread. {}",
        study.section, study.title
    );
    let all = methods(pts);
    for l in study.ladders {
        let sz = sizes(pts, l.name);
        let Some(first) = all.first() else {
            continue;
        };
        if sz.is_empty() {
            continue;
        }
        println!("\n{}", l.name);
        let scene_row = |name: &str, get: &dyn Fn(&Point) -> String| {
            print!("{name:<34}");
            for s in &sz {
                print!(
                    "{:>10}",
                    find(pts, l.name, *s, first).map_or("-".into(), get)
                );
            }
            println!();
        };
        scene_row("size", &|p| p.size.to_string());
        scene_row("objects", &|p| p.objects.to_string());
        scene_row("2D overlap", &|p| format!("{:.2}", p.overlap));
        scene_row("secondary per primary", &|p| {
            format!("{:.2}", p.secondary_per_primary)
        });
        for metric in study.metrics {
            println!("  {}", metric.name());
            for m in &all {
                print!("    {m:<30}");
                for s in &sz {
                    match find(pts, l.name, *s, m).and_then(|p| metric.of(p)) {
                        Some(v) if v >= 100.0 => print!("{v:>10.0}"),
                        Some(v) => print!("{v:>10.3}"),
                        None => print!("{:>10}", "-"),
                    }
                }
                println!();
            }
        }
        let total: usize = pts
            .iter()
            .filter(|p| p.ladder == l.name)
            .map(|p| p.mismatches)
            .sum();
        println!("  rays answering otherwise than the kd-tree, all methods and sizes: {total}");
    }
    println!(
        "\nthe thesis' observations, checked (claims in cli/src/series/{}.rs):",
        study.table.trim_end_matches("-series")
    );
    for c in claims::check_all(study, pts) {
        println!("{c}");
    }
    println!("{}", LEGEND);
}

/// The legend under the series tables.
pub const LEGEND: &str = "\
rows: ray tracing s = a whole render (primary, shadow, reflection and refraction rays, depth 5),
  one thread, best of --repeat; preprocessing ms = build time (projection methods: view =
  the camera's projection hierarchy, light = every light plane's, global = the 3D hierarchy
  for other rays); objects per primary ray = ray-primitive tests; cost per hierarchy / actual
  object = the thesis' cost units (add, multiply, compare 1, divide 5, square root 15) per box
  and per primitive tested, primary and shadow rays; 2D overlap = summed image-plane rectangle
  areas of the primitives over the area they cover. docs/design.md defines every metric.";

/// The points as JSON, with the claims' verdicts.
pub fn to_json(study: &Study, pts: &[Point]) -> serde_json::Value {
    serde_json::json!({
        "table": study.table,
        "points": pts,
        "claims": claims::check_all(study, pts),
    })
}

/// The ladders as charts: one row per ladder, one column per metric.
pub fn write_plot(
    study: &Study,
    pts: &[Point],
    path: &std::path::Path,
    res: u32,
) -> Result<(), String> {
    let shown = (study.plot_methods)();
    let mut panels = Vec::new();
    for l in study.ladders {
        if sizes(pts, l.name).is_empty() {
            continue;
        }
        for &metric in study.plot_metrics {
            panels.push(Panel {
                title: format!("{}: {}", l.name, metric.name()),
                x_label: "objects".into(),
                y_label: metric.name().into(),
                curves: shown
                    .iter()
                    .map(|m| Curve {
                        name: m.clone(),
                        points: pts
                            .iter()
                            .filter(|p| p.ladder == l.name && &p.method == m)
                            .filter_map(|p| Some((p.objects as f64, metric.of(p)?)))
                            .collect(),
                    })
                    .collect(),
            });
        }
    }
    plot::write(
        path,
        &format!("{} ({}), {res}x{res}, log-log", study.title, study.section),
        &panels,
        study.plot_metrics.len(),
        420,
        300,
    )
}
