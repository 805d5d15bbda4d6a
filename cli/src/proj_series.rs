//! `coray bench --table proj-series`: the thesis' chapter 6 over its scene
//! ladders: tree 1 to 11 (floor whole and split, 7 lights; floor whole, 1
//! light), balls 1 to 4, gears 1 to 4. Per method (3D hierarchies, and
//! projection hierarchy x criterion x scheme): preprocessing split into
//! view, light and global parts, ray-tracing time (a whole render, one
//! thread), cost per hierarchy object and per actual object, objects per
//! primary ray; then each conclusion of section 6.4 checked against the
//! numbers, and the ladders as charts.

use crate::bench;
use crate::plot::{self, Curve, Panel};
use crate::projbuild::{self, ProjRig};
use crate::render::{BvhShooter, ProjShooter};
use crate::scene::{self, SceneData};
use crate::series::{time_render, verdict, Series};
use coray::kd::KdParams;
use coray::Vec3;
use coray_scenes::spd::Options;

/// The thesis' ladders. Its tree has 7 lights inside the scene volume; ours
/// places 7 in the scene box (and 1 for the one-light ladder), as below.
pub const LADDERS: [Series; 5] = [
    Series {
        name: "tree, 7 lights",
        scene: "tree",
        sizes: 1..=11,
        floor_split: 1,
        lights: 7,
    },
    Series {
        name: "tree, floor split, 7 lights",
        scene: "tree",
        sizes: 1..=11,
        floor_split: 16,
        lights: 7,
    },
    Series {
        name: "tree, 1 light",
        scene: "tree",
        sizes: 1..=11,
        floor_split: 1,
        lights: 1,
    },
    Series {
        name: "balls",
        scene: "balls",
        sizes: 1..=4,
        floor_split: 1,
        lights: 0,
    },
    Series {
        name: "gears",
        scene: "gears",
        sizes: 1..=4,
        floor_split: 1,
        lights: 0,
    },
];

/// The 3D (view independent) hierarchies compared with the projections.
pub const GLOBAL: [&str; 4] = ["tdbs", "nn-chain", "rtree", "rstar"];

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

/// One method on one scene.
#[derive(Clone, Debug)]
pub struct Point {
    pub ladder: &'static str,
    pub size: u32,
    pub objects: usize,
    pub method: String,
    pub view_ms: f64,
    pub light_ms: f64,
    pub global_ms: f64,
    pub render_s: f64,
    pub objects_per_ray: f64,
    pub cost_per_box: f64,
    pub cost_per_prim: f64,
    pub shadow_s: f64,
    pub shadow_uniform_s: Option<f64>,
    pub mismatches: usize,
    /// Of the image plane's covered area, how often it is covered: the sum
    /// of the primitives' rectangle areas over their union's bounding
    /// rectangle (the 2D overlap the thesis' conclusions speak of).
    pub overlap: f64,
    /// Secondary (reflection and refraction) rays per primary ray.
    pub secondary_per_primary: f64,
}

/// All projection methods and the 3D hierarchies, at `res` x `res`.
pub fn run(
    res: u32,
    max_size: Option<u32>,
    params: &KdParams,
    repeat: usize,
) -> Result<Vec<Point>, String> {
    let mut out = Vec::new();
    let mut methods: Vec<String> = GLOBAL.iter().map(|m| m.to_string()).collect();
    methods.extend(projbuild::methods());
    for l in &LADDERS {
        for size in l.sizes.clone() {
            if max_size.is_some_and(|m| size > m) {
                continue;
            }
            let opts = Options {
                floor_split: l.floor_split,
            };
            let mut s = scene::load(&format!("spd:{}:{size}", l.scene), &opts)?;
            s.mesh.camera.width = res;
            s.mesh.camera.height = res;
            if l.lights > 0 {
                s.mesh.lights = lights_inside(&s.mesh.scene().bounds(), l.lights);
            }
            let overlap = overlap(&s);
            let rows = bench::bench(&s, &methods, params, 1, true)?;
            let primary = (res * res) as f64;
            for row in rows {
                if row.method == "kd" {
                    continue;
                }
                let (render_s, _, secondary) = render_time(&s, &row.method, repeat)?;
                let [view_ms, light_ms, global_ms] =
                    row.build_split.unwrap_or([0.0, 0.0, row.build_ms]);
                out.push(Point {
                    ladder: l.name,
                    size,
                    objects: s.mesh.counts.objects(),
                    method: row.method.clone(),
                    view_ms,
                    light_ms,
                    global_ms,
                    render_s,
                    objects_per_ray: row.isect_per_ray.unwrap_or(f64::NAN),
                    cost_per_box: row.cost_per_box.unwrap_or(f64::NAN),
                    cost_per_prim: row.cost_per_prim.unwrap_or(f64::NAN),
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

/// A whole one-thread render through `method`: (best seconds, rays,
/// secondary rays).
fn render_time(s: &SceneData, method: &str, repeat: usize) -> Result<(f64, u64, u64), String> {
    let scene = s.mesh.scene();
    if let Some(m) = projbuild::parse(method) {
        let rig = ProjRig::for_scene(s, m)?;
        Ok(time_render(s, &ProjShooter { rig: &rig, scene }, repeat))
    } else {
        let owned = crate::bvhbuild::OwnedBvh::build(&scene, method)?;
        let shooter = BvhShooter {
            bvh: owned.bvh(scene),
        };
        Ok(time_render(s, &shooter, repeat))
    }
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

fn find<'a>(pts: &'a [Point], ladder: &str, size: u32, method: &str) -> Option<&'a Point> {
    pts.iter()
        .find(|p| p.ladder == ladder && p.size == size && p.method == method)
}

fn sizes(pts: &[Point], ladder: &str) -> Vec<u32> {
    let mut v: Vec<u32> = pts
        .iter()
        .filter(|p| p.ladder == ladder)
        .map(|p| p.size)
        .collect();
    v.dedup();
    v
}

/// The methods in table order.
fn methods(pts: &[Point]) -> Vec<String> {
    let mut v: Vec<String> = Vec::new();
    for p in pts {
        if !v.contains(&p.method) {
            v.push(p.method.clone());
        }
    }
    v
}

type Metric = (&'static str, fn(&Point) -> f64);
const METRICS: [Metric; 7] = [
    ("ray tracing s", |p| p.render_s),
    ("view preprocessing ms", |p| p.view_ms),
    ("light preprocessing ms", |p| p.light_ms),
    ("global preprocessing ms", |p| p.global_ms),
    ("objects per primary ray", |p| p.objects_per_ray),
    ("cost per hierarchy object", |p| p.cost_per_box),
    ("cost per actual object", |p| p.cost_per_prim),
];

/// One block per ladder and metric: a row per method, a column per size.
pub fn print(pts: &[Point], res: u32) {
    println!(
        "thesis chapter 6, projection hierarchies: {res}x{res}, one thread; ray tracing = whole \
         render (shadow rays choose their light plane uniformly); preprocessing split into view \
         (camera), light (every light plane) and global (3D hierarchy for secondary rays); costs \
         in thesis units over primary and shadow rays. Methods: 3D hierarchies by name, \
         proj-BUILDER-CRITERIA-SCHEME"
    );
    let all = methods(pts);
    for l in &LADDERS {
        let sz = sizes(pts, l.name);
        if sz.is_empty() {
            continue;
        }
        println!("\n{}", l.name);
        print!("{:<30}", "size");
        for s in &sz {
            print!("{s:>10}");
        }
        print!("\n{:<30}", "objects");
        for s in &sz {
            print!(
                "{:>10}",
                find(pts, l.name, *s, &all[0]).map_or(0, |p| p.objects)
            );
        }
        print!("\n{:<30}", "2D overlap");
        for s in &sz {
            print!(
                "{:>10.2}",
                find(pts, l.name, *s, &all[0]).map_or(0.0, |p| p.overlap)
            );
        }
        print!("\n{:<30}", "secondary per primary");
        for s in &sz {
            let v = find(pts, l.name, *s, &all[0]).map_or(0.0, |p| p.secondary_per_primary);
            print!("{v:>10.2}");
        }
        println!();
        for (metric, get) in METRICS {
            println!("  {metric}");
            for m in &all {
                print!("    {m:<26}");
                for s in &sz {
                    match find(pts, l.name, *s, m).map(get) {
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
        println!("  mismatches against the kd-tree, all methods and sizes: {total}");
    }
}

/// Best render time among methods matching `keep` at one scene.
fn best(
    pts: &[Point],
    ladder: &str,
    size: u32,
    keep: impl Fn(&str) -> bool,
) -> Option<(f64, String)> {
    pts.iter()
        .filter(|p| p.ladder == ladder && p.size == size && keep(&p.method))
        .map(|p| (p.render_s, p.method.clone()))
        .min_by(|a, b| a.0.total_cmp(&b.0))
}

fn is_proj(m: &str) -> bool {
    m.starts_with("proj-")
}

/// Each conclusion of the thesis' section 6.4, checked against `pts`.
pub fn conclusions(pts: &[Point]) -> Vec<String> {
    let mut out = Vec::new();
    let largest = |ladder: &str| sizes(pts, ladder).last().copied();
    // 1. Sorting first (TDBS) gives better hierarchies than inserting (R-trees).
    let (mut wins, mut total) = (0, 0);
    for p in pts
        .iter()
        .filter(|p| p.method == "tdbs" || p.method.starts_with("proj-tdbs-"))
    {
        let other = |b: &str| {
            let name = p.method.replacen("tdbs", b, 1);
            find(pts, p.ladder, p.size, &name).map(|q| q.render_s)
        };
        if let (Some(r), Some(s)) = (other("rtree"), other("rstar")) {
            total += 1;
            wins += (p.render_s < r.min(s)) as usize;
        }
    }
    out.push(format!(
        "1. Sorting the objects first (TDBS) yields more efficient hierarchies than inserting \
         them (R-tree, R*-tree): {} (TDBS faster than both R-tree variants in {wins} of {total} \
         method x scene pairs)",
        verdict(wins * 2 > total)
    ));
    // 2. A tight 3D hierarchy beats the cheap traversal of a loose 2D one.
    let (mut tight, mut n2) = (0, 0);
    for l in &LADDERS {
        for s in sizes(pts, l.name) {
            let (Some(g), Some(p2)) = (
                best(pts, l.name, s, |m| !is_proj(m)),
                best(pts, l.name, s, |m| is_proj(m) && m.ends_with("-2d")),
            ) else {
                continue;
            };
            n2 += 1;
            tight += (g.0 < p2.0) as usize;
        }
    }
    out.push(format!(
        "2. The traversal cost of a 2D hierarchy is insignificant beside a hierarchy that models \
         the scene closely (the best 3D hierarchy beats the best pure-2D projection): {} ({tight} \
         of {n2} scenes)",
        verdict(tight * 2 > n2)
    ));
    // 3-6. By 2D overlap: the most and least overlapped scenes at their largest size.
    let mut by_overlap: Vec<(f64, &str, u32)> = LADDERS
        .iter()
        .filter_map(|l| {
            let s = largest(l.name)?;
            Some((find(pts, l.name, s, "tdbs")?.overlap, l.name, s))
        })
        .collect();
    by_overlap.sort_by(|a, b| a.0.total_cmp(&b.0));
    if let (Some(lo), Some(hi)) = (by_overlap.first().copied(), by_overlap.last().copied()) {
        let t = |l: &str, s: u32, m: &str| find(pts, l, s, m).map_or(f64::NAN, |p| p.render_s);
        let (r_lo, s_lo) = (
            t(lo.1, lo.2, "proj-rtree-2d-2d"),
            t(lo.1, lo.2, "proj-rstar-2d-2d"),
        );
        let (r_hi, s_hi) = (
            t(hi.1, hi.2, "proj-rtree-2d-2d"),
            t(hi.1, hi.2, "proj-rstar-2d-2d"),
        );
        out.push(format!(
            "3. Area criteria (R-tree) are better with limited overlap: {} (least overlapped scene, \
             {} {} at overlap {:.1}: R-tree {r_lo:.3} s, R*-tree {s_lo:.3} s; 2D criteria, 2D scheme)",
            verdict(r_lo < s_lo),
            lo.1,
            lo.2,
            lo.0
        ));
        out.push(format!(
            "4. Overlap criteria (R*-tree) are better with large overlap: {} (most overlapped \
             scene, {} {} at overlap {:.1}: R*-tree {s_hi:.3} s, R-tree {r_hi:.3} s)",
            verdict(s_hi < r_hi),
            hi.1,
            hi.2,
            hi.0
        ));
        let scheme_wins = |l: &str, s: u32, a: &str, b: &str| {
            let mut w = 0;
            for bld in projbuild::BUILDERS {
                let ta = t(l, s, &format!("proj-{bld}-2d-{a}"));
                let tb = t(l, s, &format!("proj-{bld}-2d-{b}"));
                w += (ta < tb) as usize;
            }
            w
        };
        let comb_hi = scheme_wins(hi.1, hi.2, "comb", "2d");
        let twod_lo = scheme_wins(lo.1, lo.2, "2d", "comb");
        out.push(format!(
            "5. With large 2D overlap combination intersections are preferred: {} (in {} {}, \
             combination beats the 2D scheme for {comb_hi} of 4 builders)",
            verdict(comb_hi >= 3),
            hi.1,
            hi.2
        ));
        out.push(format!(
            "6. With small 2D overlap a 2D intersection hierarchy is faster: {} (in {} {}, the 2D \
             scheme beats combination for {twod_lo} of 4 builders)",
            verdict(twod_lo >= 3),
            lo.1,
            lo.2
        ));
    }
    // 7. Choosing a hierarchy costs more where secondary rays abound: the
    // uniform mode's extra time over known origin, per ladder (largest size).
    let extra = |ladder: &str| {
        let s = largest(ladder)?;
        let v: Vec<f64> = pts
            .iter()
            .filter(|p| p.ladder == ladder && p.size == s && is_proj(&p.method))
            .filter_map(|p| Some(p.shadow_uniform_s? / p.shadow_s))
            .collect();
        let sec = find(pts, ladder, s, "tdbs")?.secondary_per_primary;
        Some((v.iter().sum::<f64>() / v.len().max(1) as f64, sec))
    };
    let ratios: Vec<(String, f64, f64)> = LADDERS
        .iter()
        .filter_map(|l| {
            let (e, sec) = extra(l.name)?;
            Some((l.name.to_string(), e, sec))
        })
        .collect();
    let most_secondary = ratios.iter().max_by(|a, b| a.2.total_cmp(&b.2));
    let dearest = ratios.iter().max_by(|a, b| a.1.total_cmp(&b.1));
    let rows: Vec<String> = ratios
        .iter()
        .map(|(n, e, sec)| format!("{n}: uniform/known {e:.3}, {sec:.2} secondary per primary"))
        .collect();
    out.push(format!(
        "7. The cost of choosing a hierarchy becomes significant with many secondary rays (the \
         uniform mode's extra shadow-ray time is largest where secondary rays are most): {} ({})",
        verdict(matches!((most_secondary, dearest), (Some(a), Some(b)) if a.0 == b.0)),
        rows.join("; ")
    ));
    // 8. Large objects: splitting the tree's floor speeds every method up.
    let whole = "tree, 7 lights";
    let split = "tree, floor split, 7 lights";
    if let Some(s) = largest(whole).filter(|s| sizes(pts, split).contains(s)) {
        let ms = methods(pts);
        let faster = ms
            .iter()
            .filter(|m| {
                let (a, b) = (find(pts, whole, s, m), find(pts, split, s, m));
                matches!((a, b), (Some(a), Some(b)) if b.render_s < a.render_s)
            })
            .count();
        out.push(format!(
            "8. Objects much larger than the rest (the tree's floor) slow ray tracing: {} (tree {s}: \
             splitting the floor into 16 x 16 makes {faster} of {} methods faster)",
            verdict(faster * 2 > ms.len()),
            ms.len()
        ));
    }
    // 9. Projected hierarchies win in large scenes with few secondary rays.
    let judge = |ladder: &str| {
        let s = largest(ladder)?;
        let g = best(pts, ladder, s, |m| !is_proj(m))?;
        let p = best(pts, ladder, s, is_proj)?;
        Some((s, g, p))
    };
    let mut parts = Vec::new();
    let mut ok = true;
    for (ladder, want_proj) in [("tree, 1 light", true), ("balls", false)] {
        if let Some((s, g, p)) = judge(ladder) {
            let proj_wins = p.0 < g.0;
            ok &= proj_wins == want_proj;
            parts.push(format!(
                "{ladder} {s}: best projection {} {:.3} s, best 3D {} {:.3} s",
                p.1, p.0, g.1, g.0
            ));
        }
    }
    out.push(format!(
        "9. Projected hierarchies are faster in large scenes with few secondary rays (tree, \
         matte) and not where secondary rays abound (balls): {} ({})",
        verdict(ok && !parts.is_empty()),
        parts.join("; ")
    ));
    out
}

/// Charts like the thesis' figures 6.4 to 6.21: per ladder, ray-tracing
/// time, preprocessing (view + light), objects per primary ray and cost per
/// hierarchy object, for the 3D hierarchies and the 2D-criteria
/// projections with the combination scheme (one chart per ladder and
/// metric; the table has every method).
pub fn write_plot(pts: &[Point], path: &std::path::Path, res: u32) -> Result<(), String> {
    let shown: Vec<String> = GLOBAL
        .iter()
        .map(|m| m.to_string())
        .chain(
            projbuild::BUILDERS
                .iter()
                .map(|b| format!("proj-{b}-2d-2d")),
        )
        .collect();
    let metrics: [Metric; 4] = [
        METRICS[0],
        ("projection preprocessing ms", |p| p.view_ms + p.light_ms),
        METRICS[4],
        METRICS[5],
    ];
    let mut panels = Vec::new();
    for l in &LADDERS {
        if sizes(pts, l.name).is_empty() {
            continue;
        }
        for (metric, get) in metrics {
            panels.push(Panel {
                title: format!("{}: {metric}", l.name),
                x_label: "objects".into(),
                y_label: metric.into(),
                curves: shown
                    .iter()
                    .map(|m| Curve {
                        name: m.clone(),
                        points: pts
                            .iter()
                            .filter(|p| p.ladder == l.name && &p.method == m)
                            .map(|p| (p.objects as f64, get(p)))
                            .collect(),
                    })
                    .collect(),
            });
        }
    }
    plot::write(
        path,
        &format!("projection hierarchies (thesis ch. 6), {res}x{res}, log-log"),
        &panels,
        metrics.len(),
        420,
        300,
    )
}
