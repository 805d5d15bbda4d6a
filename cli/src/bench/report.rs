//! How benchmark rows are shown: the method table, the thesis' hierarchy
//! and projection tables, each with a legend of its columns, and JSON
//! (serde) for all of them.

use super::row::{ratios, Row};
use crate::scene::SceneData;
use serde::Serialize;

/// The line above a table: the scene and the rays traced.
fn print_workload(s: &SceneData, rows: &[Row], threads: usize, note: &str) {
    println!(
        "scene {}: {} objects ({} primitives), {}x{} primary rays, {} shadow rays, {threads} thread{}{note}",
        s.name,
        s.mesh.counts.objects(),
        s.prim_count(),
        s.mesh.camera.width,
        s.mesh.camera.height,
        rows.iter().map(|r| r.shadow_rays).max().unwrap_or(0),
        if threads == 1 { "" } else { "s" }
    );
}

fn opt(v: Option<f64>, p: usize) -> String {
    v.map_or("-".to_string(), |x| format!("{x:.p$}"))
}

/// The legend under the method table.
pub const LEGEND: &str = "\
columns: build ms = build time (Embree: rtcCommitScene alone); arena B = bytes of the
  structure (a C arena's for coray); B/prim = arena B per primitive; prim/shad Mr/s =
  millions of primary / shadow rays per second (best of --repeat runs); TSPR = traversal
  steps (nodes visited) per primary ray; isect/r = ray-primitive tests per primary ray;
  alpha = TSPR and eta = time relative to the kd-tree's hierarchical traversal (for LCTS
  casts: to the hierarchical cast of the same pixels, timed in turn); vs embree = primary
  speed over Embree's rtcIntersect1; mismatch = rays whose answer differs from the
  reference beyond the tie rules (coray::tolerance); ties = differences the rules
  explain; trunc = the kd build ran out of room. docs/design.md defines every metric.";

/// Prints the method table.
pub fn print_table(s: &SceneData, rows: &[Row], threads: usize) {
    let embree = rows.iter().find(|r| r.method == "embree");
    print_workload(s, rows, threads, "");
    println!(
        "{:<16} {:>9} {:>11} {:>7} {:>9} {:>9} {:>7} {:>8} {:>6} {:>6} {:>9} {:>8} {:>6} {:>5}",
        "method",
        "build ms",
        "arena B",
        "B/prim",
        "prim Mr/s",
        "shad Mr/s",
        "TSPR",
        "isect/r",
        "alpha",
        "eta",
        "vs embree",
        "mismatch",
        "ties",
        "trunc"
    );
    for r in rows {
        let (alpha, eta) = ratios(r, rows);
        let vs_embree = embree.map(|e| r.primary_mrays() / e.primary_mrays());
        println!(
            "{:<16} {:>9.1} {:>11} {:>7} {:>9.3} {:>9} {:>7} {:>8} {:>6} {:>6} {:>9} {:>8} {:>6} {:>5}",
            r.method,
            r.build_ms,
            r.arena_bytes.map_or("-".into(), |b| b.to_string()),
            r.arena_bytes.map_or("-".into(), |b| format!(
                "{:.1}",
                b as f64 / s.prim_count().max(1) as f64
            )),
            r.primary_mrays(),
            opt(r.shadow_mrays(), 3),
            opt(r.tspr, 2),
            opt(r.isect_per_ray, 2),
            opt(alpha, 3),
            opt(eta, 3),
            opt(vs_embree, 3),
            r.mismatches,
            r.ties,
            if r.truncated { "yes" } else { "no" }
        );
    }
    if let Some(e) = embree {
        println!(
            "ratios to Embree, shadow rays: {}",
            rows.iter()
                .filter(|r| r.method != "embree")
                .filter_map(|r| Some(format!(
                    "{} {:.3}",
                    r.method,
                    r.shadow_mrays()? / e.shadow_mrays()?
                )))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    println!("{LEGEND}");
}

/// The rows as one JSON object.
pub fn to_json(s: &SceneData, rows: &[Row], threads: usize) -> serde_json::Value {
    #[derive(Serialize)]
    struct Out<'a> {
        scene: &'a str,
        objects: usize,
        primitives: usize,
        res: [u32; 2],
        threads: usize,
        rows: Vec<serde_json::Value>,
    }
    let rows = rows
        .iter()
        .map(|r| {
            let (alpha, eta) = ratios(r, rows);
            let mut v = serde_json::to_value(r).expect("rows serialise");
            let o = v.as_object_mut().expect("an object");
            o.insert("primary_mrays".into(), r.primary_mrays().into());
            o.insert("shadow_mrays".into(), r.shadow_mrays().into());
            o.insert("alpha".into(), alpha.into());
            o.insert("eta".into(), eta.into());
            v
        })
        .collect();
    serde_json::to_value(Out {
        scene: &s.name,
        objects: s.mesh.counts.objects(),
        primitives: s.prim_count(),
        res: [s.mesh.camera.width, s.mesh.camera.height],
        threads,
        rows,
    })
    .expect("serialises")
}

/// `--table bvh`: the thesis' metrics per hierarchy builder (6.3.1):
/// preprocessing time, ray-tracing time (primary and shadow rays), objects
/// tested per primary ray, cost per hierarchy object and per actual object.
pub fn print_bvh_table(s: &SceneData, rows: &[Row]) {
    print_workload(s, rows, 1, "; costs in the thesis' units");
    println!(
        "{:<14} {:>12} {:>12} {:>14} {:>13} {:>13} {:>9}",
        "builder",
        "preproc ms",
        "trace s",
        "objects/prim",
        "cost/hier obj",
        "cost/act obj",
        "mismatch"
    );
    for r in rows {
        println!(
            "{:<14} {:>12.1} {:>12.3} {:>14} {:>13} {:>13} {:>9}",
            r.method,
            r.build_ms,
            r.primary_s + r.shadow_s,
            opt(r.isect_per_ray, 2),
            opt(r.cost_per_box, 2),
            opt(r.cost_per_prim, 2),
            r.mismatches
        );
    }
    println!(
        "columns: preproc ms = build time; trace s = primary and shadow rays; objects/prim = \
         primitives tested per primary ray;\n  cost/hier obj, cost/act obj = the thesis' cost units \
         (add, multiply, compare 1, divide 5, square root 15) per box and per primitive tested"
    );
}

/// `--table proj`: per projection hierarchy x build criterion x scheme,
/// the thesis' chapter 6 metrics, with the 3D hierarchies and the kd-tree
/// of the same run above them.
pub fn print_proj_table(s: &SceneData, rows: &[Row]) {
    print_workload(
        s,
        rows,
        1,
        "; shadow rays by their light's plane (known) and by asking every light (uniform)",
    );
    println!(
        "{:<24} {:>8} {:>8} {:>8} {:>9} {:>9} {:>9} {:>8} {:>9} {:>9} {:>8}",
        "method",
        "view ms",
        "light ms",
        "glob ms",
        "prim s",
        "shad s",
        "unif s",
        "obj/ray",
        "cost/hobj",
        "cost/aobj",
        "mismatch"
    );
    for r in rows {
        let [v, l, g] = r.build_split.unwrap_or([r.build_ms, 0.0, 0.0]);
        println!(
            "{:<24} {:>8.1} {:>8.1} {:>8.1} {:>9.4} {:>9.4} {:>9} {:>8} {:>9} {:>9} {:>8}",
            r.method,
            v,
            l,
            g,
            r.primary_s,
            r.shadow_s,
            opt(r.shadow_uniform_s, 4),
            opt(r.isect_per_ray, 2),
            opt(r.cost_per_box, 2),
            opt(r.cost_per_prim, 2),
            r.mismatches
        );
    }
    println!(
        "columns: view, light, glob ms = preprocessing of the camera's, the lights' and the global \
         3D hierarchy;\n  prim s, shad s = primary and shadow rays (their light known); unif s = \
         shadow rays asking every light; obj/ray = primitives per primary ray;\n  cost/hobj, \
         cost/aobj = the thesis' cost units per hierarchy object and per actual object"
    );
}
