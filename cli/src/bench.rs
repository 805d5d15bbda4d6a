//! `coray bench`: every method on the same primary and shadow rays, one
//! thread, side by side in one run. Figures are ratios to the kd-tree's
//! hierarchical traversal (alpha for traversal steps, eta for time) and to
//! Embree when it is in the run. LCTS schemes cast the image themselves, so
//! their reference is the hierarchical image cast timed in the same harness
//! (the kd row traces pre-generated rays into a vector: more time for the
//! same traversal).

use crate::kdbuild::OwnedKd;
use crate::scene::SceneData;
use coray::kd::{KdParams, Traversal};
use coray::lcts::hlcts::HlctsEntry;
use coray::lcts::{
    cast_image, image_requirements, CornerInfo, HistoryRecord, ImageScratch, Scheme,
};
use coray::{Hit, Ray, TraceStats};
use std::time::Instant;

/// One benchmarked method's figures.
#[derive(Clone, Debug, Default)]
pub struct Row {
    pub method: String,
    pub build_ms: f64,
    /// Bytes of the structure (None where it is not ours to measure).
    pub arena_bytes: Option<usize>,
    pub primary_s: f64,
    pub shadow_s: f64,
    pub primary_rays: usize,
    pub shadow_rays: usize,
    /// Traversal steps per primary ray (None for Embree).
    pub tspr: Option<f64>,
    pub isect_per_ray: Option<f64>,
    pub mismatches: usize,
    pub truncated: bool,
    /// LCTS schemes: share of windows whose common sequence holds a leaf.
    pub gamma: Option<f64>,
    /// Hierarchies: the thesis' cost per hierarchy object and per actual
    /// object (primary and shadow rays), and the trace time of both.
    pub cost_per_box: Option<f64>,
    pub cost_per_prim: Option<f64>,
    /// Projection methods: preprocessing of the view, light and global
    /// hierarchies (ms), and shadow rays timed in the uniform mode (s).
    pub build_split: Option<[f64; 3]>,
    pub shadow_uniform_s: Option<f64>,
    /// LCTS schemes: pixels whose primitive differs from hierarchical
    /// casting's only by a tie (same t, both primitives met there).
    pub ties: usize,
    /// Image casts: the hierarchical cast of the same pixels, timed in the
    /// same run and harness; alpha and eta are relative to it.
    pub reference: Option<Reference>,
}

/// What alpha and eta of an image cast are relative to.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Reference {
    pub primary_s: f64,
    pub tspr: f64,
}

/// (alpha, eta) of `row`: against its own cast reference when it has one,
/// else against the kd row of `rows`.
pub fn ratios(row: &Row, rows: &[Row]) -> (Option<f64>, Option<f64>) {
    if let Some(k) = row.reference {
        return (
            row.tspr.map(|t| t / k.tspr),
            Some(row.primary_s / k.primary_s),
        );
    }
    match reference(rows) {
        Some(k) => (
            row.tspr.zip(k.tspr).map(|(a, b)| a / b),
            Some(row.primary_s / k.primary_s),
        ),
        None => (None, None),
    }
}

impl Row {
    pub fn primary_mrays(&self) -> f64 {
        self.primary_rays as f64 / self.primary_s / 1e6
    }
    /// None when the method traced no shadow rays (LCTS casts primary rays only).
    pub fn shadow_mrays_opt(&self) -> Option<f64> {
        (self.shadow_rays > 0).then(|| self.shadow_mrays())
    }
    pub fn shadow_mrays(&self) -> f64 {
        self.shadow_rays as f64 / self.shadow_s / 1e6
    }
}

/// Camera rays through every pixel (and, by [`lit_shadow_rays`], one
/// shadow ray per hit per light), all with unit directions (Embree's cones
/// need them, see coray-embree).
/// Shadow rays of the workload, each with the index of its light.
pub fn lit_shadow_rays(s: &SceneData, reference: &[Hit]) -> Vec<(usize, Ray)> {
    let mut shadow = Vec::new();
    let primary = primary_rays(s);
    for (r, h) in primary.iter().zip(reference) {
        if !h.is_hit() {
            continue;
        }
        let p = r.origin + r.dir * h.t;
        for (i, (l, _)) in s.mesh.lights.iter().enumerate() {
            let d = *l - p;
            let len = d.length();
            if len > 0.0 {
                shadow.push((i, Ray::new(p, d / len, 1e-4 * len.max(1.0), len)));
            }
        }
    }
    shadow
}

pub fn primary_rays(s: &SceneData) -> Vec<Ray> {
    let c = &s.mesh.camera;
    let (f, r, u) = c.basis();
    let mut rays = Vec::with_capacity((c.width * c.height) as usize);
    for y in 0..c.height {
        for x in 0..c.width {
            let ray = c.ray_in(f, r, u, x as f32 + 0.5, y as f32 + 0.5);
            rays.push(Ray::new(
                ray.origin,
                ray.dir.normalize(),
                0.0,
                f32::INFINITY,
            ));
        }
    }
    rays
}

/// Best of `repeat` timed runs of `f` (the machine is shared: the minimum
/// is the least disturbed run).
fn best_of<T>(repeat: usize, mut f: impl FnMut() -> T) -> (f64, T) {
    let mut best = f64::INFINITY;
    let mut out = None;
    for _ in 0..repeat.max(1) {
        let t = Instant::now();
        let v = f();
        best = best.min(t.elapsed().as_secs_f64());
        out = Some(v);
    }
    (best, out.unwrap())
}

/// Two real hits of one ray on different primitives whose t agree within
/// rounding (2^-20 relative): both are the closest, a tie.
fn near_tie(a: f32, b: f32) -> bool {
    (a - b).abs() <= a.abs().max(b.abs()) * (1.0 / 1_048_576.0)
}

fn same_hit(a: &Hit, b: &Hit) -> bool {
    a.is_hit() == b.is_hit()
        && (!a.is_hit()
            || ((a.geom_id, a.prim_id) == (b.geom_id, b.prim_id) || near_tie(a.t, b.t))
                && (a.t - b.t).abs() <= 1e-4 * a.t.abs().max(1.0))
}

/// Results of one method on the workload, for comparison.
pub struct Traced {
    pub row: Row,
    pub hits: Vec<Hit>,
    pub shadowed: Vec<bool>,
}

/// Builds a kd-tree with `params` and traces the workload with `method`.
pub fn run_kd(
    s: &SceneData,
    params: &KdParams,
    method: Traversal,
    name: &str,
    primary: &[Ray],
    shadow: &[Ray],
    repeat: usize,
) -> Traced {
    let owned = OwnedKd::build(&s.mesh.scene(), params).expect("kd build");
    let tree = owned.tree(s.mesh.scene());
    let mut stats = TraceStats::default();
    let (primary_s, hits) = best_of(repeat, || {
        stats = TraceStats::default();
        primary
            .iter()
            .map(|r| tree.intersect(r, method, &mut stats))
            .collect::<Vec<_>>()
    });
    let (shadow_s, shadowed) = best_of(repeat, || {
        let mut st = TraceStats::default();
        shadow
            .iter()
            .map(|r| tree.occluded(r, method, &mut st))
            .collect::<Vec<_>>()
    });
    let n = primary.len().max(1) as f64;
    Traced {
        row: Row {
            method: name.to_string(),
            build_ms: owned.build_ms,
            arena_bytes: Some(owned.arena_bytes()),
            primary_s,
            shadow_s,
            primary_rays: primary.len(),
            shadow_rays: shadow.len(),
            tspr: Some(stats.traversal_steps as f64 / n),
            isect_per_ray: Some(stats.prim_tests as f64 / n),
            mismatches: 0,
            truncated: owned.info.truncated(),
            gamma: None,
            ..Row::default()
        },
        hits,
        shadowed,
    }
}

#[cfg(feature = "embree")]
pub fn run_embree(s: &SceneData, primary: &[Ray], shadow: &[Ray], repeat: usize) -> Traced {
    let t = Instant::now();
    let e = coray_embree::EmbreeScene::new(&s.mesh.scene(), Some(1));
    let build_ms = t.elapsed().as_secs_f64() * 1e3;
    let (primary_s, hits) = best_of(repeat, || {
        primary.iter().map(|r| e.intersect(r)).collect::<Vec<_>>()
    });
    let (shadow_s, shadowed) = best_of(repeat, || {
        shadow.iter().map(|r| e.occluded(r)).collect::<Vec<_>>()
    });
    Traced {
        row: Row {
            method: "embree".into(),
            build_ms,
            arena_bytes: None,
            primary_s,
            shadow_s,
            primary_rays: primary.len(),
            shadow_rays: shadow.len(),
            ..Row::default()
        },
        hits,
        shadowed,
    }
}

/// Builds hierarchy `method` and traces the workload through it.
pub fn run_bvh(
    s: &SceneData,
    method: &str,
    primary: &[Ray],
    shadow: &[Ray],
    repeat: usize,
) -> Result<Traced, String> {
    use coray::bvh::{BvhStackItem, BvhStats};
    let owned = crate::bvhbuild::OwnedBvh::build(&s.mesh.scene(), method)?;
    let bvh = owned.bvh(s.mesh.scene());
    let mut stack = vec![BvhStackItem::default(); bvh.stack_len()];
    let mut prim_stats = BvhStats::default();
    let (primary_s, hits) = best_of(repeat, || {
        prim_stats = BvhStats::default();
        primary
            .iter()
            .map(|r| bvh.intersect(r, &mut stack, &mut prim_stats))
            .collect::<Vec<_>>()
    });
    let mut shadow_stats = BvhStats::default();
    let (shadow_s, shadowed) = best_of(repeat, || {
        shadow_stats = BvhStats::default();
        shadow
            .iter()
            .map(|r| bvh.occluded(r, &mut stack, &mut shadow_stats))
            .collect::<Vec<_>>()
    });
    let mut all = prim_stats;
    all.add(&shadow_stats);
    let n = primary.len().max(1) as f64;
    Ok(Traced {
        row: Row {
            method: method.to_string(),
            build_ms: owned.build_ms,
            arena_bytes: Some(owned.bytes()),
            primary_s,
            shadow_s,
            primary_rays: primary.len(),
            shadow_rays: shadow.len(),
            tspr: Some(prim_stats.trace.traversal_steps as f64 / n),
            isect_per_ray: Some(prim_stats.trace.prim_tests as f64 / n),
            cost_per_box: Some(all.cost_per_box()),
            cost_per_prim: Some(all.cost_per_prim()),
            ..Row::default()
        },
        hits,
        shadowed,
    })
}

/// Builds projection method `name` (camera, light planes, global 3D
/// hierarchy) and traces the workload: primary rays through the camera's
/// hierarchy, shadow rays through their light's planes (known origin; the
/// uniform mode timed beside it).
pub fn run_proj(
    s: &SceneData,
    name: &str,
    primary: &[Ray],
    shadow: &[(usize, Ray)],
    repeat: usize,
) -> Result<Traced, String> {
    use crate::projbuild::{parse, ProjRig};
    use coray::bvh::BvhStackItem;
    use coray::proj::ProjStats;
    let m = parse(name).ok_or(format!("unknown projection method `{name}`"))?;
    let scene = s.mesh.scene();
    let rig = ProjRig::for_scene(s, m)?;
    let mut stack = vec![BvhStackItem::default(); rig.stack_len(scene)];
    let mut pst = ProjStats::default();
    let (primary_s, hits) = best_of(repeat, || {
        pst = ProjStats::default();
        primary
            .iter()
            .map(|r| rig.intersect(scene, r, &mut stack, &mut pst))
            .collect::<Vec<_>>()
    });
    let mut sst = ProjStats::default();
    let (shadow_s, shadowed) = best_of(repeat, || {
        sst = ProjStats::default();
        shadow
            .iter()
            .map(|(l, r)| rig.occluded(scene, r, Some(*l), &mut stack, &mut sst))
            .collect::<Vec<_>>()
    });
    let (uniform_s, uniform) = best_of(repeat, || {
        let mut st = ProjStats::default();
        shadow
            .iter()
            .map(|(_, r)| rig.occluded(scene, r, None, &mut stack, &mut st))
            .collect::<Vec<_>>()
    });
    let mut all = pst.bvh;
    all.add(&sst.bvh);
    let n = primary.len().max(1) as f64;
    let uniform_diff = uniform
        .iter()
        .zip(&shadowed)
        .filter(|(a, b)| a != b)
        .count();
    Ok(Traced {
        row: Row {
            method: name.to_string(),
            build_ms: rig.view_ms + rig.light_ms + rig.global_ms,
            primary_s,
            shadow_s,
            primary_rays: primary.len(),
            shadow_rays: shadow.len(),
            tspr: Some(pst.bvh.trace.traversal_steps as f64 / n),
            isect_per_ray: Some(pst.bvh.trace.prim_tests as f64 / n),
            cost_per_box: Some(all.cost_per_box()),
            cost_per_prim: Some(all.cost_per_prim()),
            build_split: Some([rig.view_ms, rig.light_ms, rig.global_ms]),
            shadow_uniform_s: Some(uniform_s),
            // Counted with the known-origin answers' below.
            mismatches: uniform_diff,
            ..Row::default()
        },
        hits,
        shadowed,
    })
}

/// Every method coray has (and Embree when built with it).
pub fn all_methods() -> Vec<&'static str> {
    let mut m = vec!["kd", "kd-rope", "slcts1d", "slcts2d", "hlcts1d", "hlcts2d"];
    m.extend(crate::bvhbuild::METHODS);
    if cfg!(feature = "embree") {
        m.push("embree");
    }
    m
}

/// Runs the named methods on the same rays. The reference for mismatches,
/// alpha and eta is the kd-tree's hierarchical traversal, traced in the same
/// run whether or not `kd` is listed (for LCTS rows: its image cast).
pub fn bench(
    s: &SceneData,
    methods: &[String],
    params: &KdParams,
    repeat: usize,
    with_shadow: bool,
) -> Result<Vec<Row>, String> {
    let projection = crate::projbuild::methods();
    for m in methods {
        if !all_methods().contains(&m.as_str()) && !projection.contains(m) && !is_lcts(m) {
            return Err(format!(
                "unknown method `{m}` (have: {}, slcts1d:N, slcts2d:NxM, and proj-BUILDER-CRITERIA-SCHEME: {})",
                all_methods().join(", "),
                projection.join(", ")
            ));
        }
    }
    let primary = primary_rays(s);
    let lit = if with_shadow {
        let first = run_kd(s, params, Traversal::Hierarchical, "kd", &primary, &[], 1);
        lit_shadow_rays(s, &first.hits)
    } else {
        Vec::new()
    };
    let shadow: Vec<Ray> = lit.iter().map(|(_, r)| *r).collect();
    let reference = run_kd(
        s,
        params,
        Traversal::Hierarchical,
        "kd",
        &primary,
        &shadow,
        repeat,
    );
    let mut rows = Vec::new();
    if !methods.iter().any(|m| m == "kd") {
        rows.push(reference.row.clone());
    }
    for m in methods {
        let traced = match m.as_str() {
            "kd" => Traced {
                row: reference.row.clone(),
                hits: reference.hits.clone(),
                shadowed: reference.shadowed.clone(),
            },
            l if is_lcts(l) => run_lcts(s, params, lcts_scheme(l).unwrap(), l, repeat)?,
            "kd-rope" => run_kd(
                s,
                params,
                Traversal::Ropes,
                "kd-rope",
                &primary,
                &shadow,
                repeat,
            ),
            #[cfg(feature = "embree")]
            "embree" => run_embree(s, &primary, &shadow, repeat),
            b if crate::bvhbuild::METHODS.contains(&b) => run_bvh(s, b, &primary, &shadow, repeat)?,
            p if p.starts_with("proj-") => run_proj(s, p, &primary, &lit, repeat)?,
            _ => unreachable!("checked above"),
        };
        let mismatches = total_mismatches(&traced, &reference, m == "embree", &primary);
        let mut row = traced.row;
        row.mismatches = mismatches;
        rows.push(row);
    }
    Ok(rows)
}

/// A method's mismatches: those it counted itself (an LCTS scheme's
/// pixels against hierarchical casting, a projection method's uniform
/// against known-origin shadow answers), plus its hits and shadow answers
/// that differ from the reference's.
fn total_mismatches(traced: &Traced, reference: &Traced, embree: bool, primary: &[Ray]) -> usize {
    let shadow = traced
        .shadowed
        .iter()
        .zip(&reference.shadowed)
        .filter(|(a, b)| a != b)
        .count();
    let hits = if embree {
        embree_mismatches(primary, &traced.hits, &reference.hits)
    } else {
        traced
            .hits
            .iter()
            .zip(&reference.hits)
            .filter(|(a, b)| !same_hit(a, b))
            .count()
    };
    traced.row.mismatches + shadow + hits
}

/// The image-casting scheme of a method name: the four LCTS schemes
/// (paper windows, or `slcts1d:N` and `slcts2d:NxM` for others), and `kd` /
/// `kd-rope` as hierarchical and rope casts.
pub fn lcts_scheme(method: &str) -> Option<Scheme> {
    let size = |s: &str| s.parse::<u32>().ok();
    if let Some(n) = method.strip_prefix("slcts1d:") {
        return Some(Scheme::Slcts1d { n: size(n)? });
    }
    if let Some(nm) = method.strip_prefix("slcts2d:") {
        let (n, m) = nm.split_once('x')?;
        return Some(Scheme::Slcts2d {
            n: size(n)?,
            m: size(m)?,
        });
    }
    Some(match method {
        "kd" => Scheme::Hierarchical,
        "kd-rope" => Scheme::Ropes,
        "slcts1d" => Scheme::Slcts1d { n: 5 },
        "slcts2d" => Scheme::Slcts2d { n: 5, m: 5 },
        "hlcts1d" => Scheme::Hlcts1d,
        "hlcts2d" => Scheme::Hlcts2d,
        _ => return None,
    })
}

/// Whether `method` casts an image by an LCTS scheme.
fn is_lcts(method: &str) -> bool {
    lcts_scheme(method).is_some_and(|s| !matches!(s, Scheme::Hierarchical | Scheme::Ropes))
}

/// An LCTS image-casting scheme on the camera's primary rays. Its
/// mismatches are pixels whose primitive or t differ from hierarchical
/// casting of the same rays (the scheme's exactness).
pub fn run_lcts(
    s: &SceneData,
    params: &KdParams,
    scheme: Scheme,
    name: &str,
    repeat: usize,
) -> Result<Traced, String> {
    let owned = OwnedKd::build(&s.mesh.scene(), params)?;
    let tree = owned.tree(s.mesh.scene());
    let cam = &s.mesh.camera;
    let n = (cam.width * cam.height) as usize;
    let req = image_requirements(cam.width, cam.height, scheme, 512);
    let mut records = vec![HistoryRecord::default(); req.records];
    let mut entries = vec![0u32; req.entries];
    let mut corners = vec![CornerInfo::default(); req.corners];
    let mut starts = vec![0u32; req.starts];
    let mut hlcts = vec![HlctsEntry::default(); req.hlcts];
    let (mut t, mut p) = (vec![0.0f32; n], vec![0u32; n]);
    let (mut t_ref, mut p_ref) = (vec![0.0f32; n], vec![0u32; n]);
    let mut cast = |scheme: Scheme, t: &mut [f32], p: &mut [u32]| {
        let scratch = ImageScratch {
            records: &mut records,
            entries: &mut entries,
            corners: &mut corners,
            starts: &mut starts,
            hlcts: &mut hlcts,
        };
        cast_image(&tree, cam, scheme, scratch, t, p).map_err(|e| e.to_string())
    };
    // The reference: the same pixels cast hierarchically through the same
    // harness (ray generation, output writes), in turn with the scheme so
    // that both see the machine alike; the best of each.
    let (mut reference_s, mut primary_s) = (f64::INFINITY, f64::INFINITY);
    let (mut rs, mut cs) = (None, None);
    for _ in 0..repeat.max(1) {
        let (s, r) = best_of(1, || cast(Scheme::Hierarchical, &mut t_ref, &mut p_ref));
        reference_s = reference_s.min(s);
        rs = Some(r?);
        let (s, c) = best_of(1, || cast(scheme, &mut t, &mut p));
        primary_s = primary_s.min(s);
        cs = Some(c?);
    }
    let (rs, cs) = (rs.unwrap(), cs.unwrap());
    // A pixel agrees when its primitive and t are the hierarchical cast's,
    // bit for bit; one whose primitive differs but whose t is within
    // rounding of it (a few ulps) is a tie: two primitives through one point
    // (a shared edge), each really hit, found in another order.
    let differ: Vec<usize> = (0..n)
        .filter(|&i| p[i] != p_ref[i] || t[i].to_bits() != t_ref[i].to_bits())
        .collect();
    let ties = differ
        .iter()
        .filter(|&&i| p[i] != u32::MAX && p_ref[i] != u32::MAX && p[i] != p_ref[i])
        .filter(|&&i| near_tie(t[i], t_ref[i]))
        .count();
    let mismatches = differ.len() - ties;
    // Per pixel: the 2D bisection traces some rays twice, and that work counts.
    let rays = n.max(1) as f64;
    Ok(Traced {
        row: Row {
            method: name.to_string(),
            build_ms: owned.build_ms,
            arena_bytes: Some(owned.arena_bytes()),
            primary_s,
            shadow_s: 0.0,
            primary_rays: n,
            shadow_rays: 0,
            tspr: Some(cs.trace.traversal_steps as f64 / rays),
            isect_per_ray: Some(cs.trace.prim_tests as f64 / rays),
            mismatches,
            ties,
            truncated: owned.info.truncated(),
            gamma: (!matches!(scheme, Scheme::Hierarchical | Scheme::Ropes)).then(|| cs.gamma()),
            reference: Some(Reference {
                primary_s: reference_s,
                tspr: rs.trace.traversal_steps as f64 / rays,
            }),
            ..Row::default()
        },
        hits: Vec::new(),
        shadowed: Vec::new(),
    })
}

/// Rays where Embree's hit differs from coray's beyond a documented tie.
fn embree_mismatches(rays: &[Ray], theirs: &[Hit], ours: &[Hit]) -> usize {
    #[cfg(feature = "embree")]
    {
        use coray_embree::{classify, Agreement};
        rays.iter()
            .zip(ours.iter().zip(theirs))
            .filter(|(r, (a, b))| classify(r, a, b) == Agreement::Mismatch)
            .count()
    }
    #[cfg(not(feature = "embree"))]
    {
        let _ = (rays, theirs, ours);
        0
    }
}

/// The reference row (kd hierarchical) of a set of rows, if present.
pub fn reference(rows: &[Row]) -> Option<&Row> {
    rows.iter().find(|r| r.method == "kd")
}

/// The line above a table: the scene and the rays traced.
fn print_workload(s: &SceneData, rows: &[Row], note: &str) {
    println!(
        "scene {}: {} objects ({} primitives), {}x{} primary rays, {} shadow rays, 1 thread{note}",
        s.name,
        s.mesh.counts.objects(),
        s.prim_count(),
        s.mesh.camera.width,
        s.mesh.camera.height,
        rows.first().map_or(0, |r| r.shadow_rays)
    );
}

/// Prints the rows as a table.
pub fn print_table(s: &SceneData, rows: &[Row]) {
    let embree = rows.iter().find(|r| r.method == "embree");
    print_workload(s, rows, "");
    println!(
        "{:<14} {:>9} {:>11} {:>7} {:>9} {:>9} {:>7} {:>8} {:>6} {:>6} {:>9} {:>9} {:>5}",
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
        "trunc"
    );
    let opt = |v: Option<f64>, p: usize| v.map_or("-".to_string(), |x| format!("{x:.p$}"));
    for r in rows {
        let (alpha, eta) = ratios(r, rows);
        let vs_embree = embree.map(|e| r.primary_mrays() / e.primary_mrays());
        println!(
            "{:<14} {:>9.1} {:>11} {:>7} {:>9.3} {:>9} {:>7} {:>8} {:>6} {:>6} {:>9} {:>9} {:>5}",
            r.method,
            r.build_ms,
            r.arena_bytes.map_or("-".into(), |b| b.to_string()),
            r.arena_bytes.map_or("-".into(), |b| format!(
                "{:.1}",
                b as f64 / s.prim_count().max(1) as f64
            )),
            r.primary_mrays(),
            opt(r.shadow_mrays_opt(), 3),
            opt(r.tspr, 2),
            opt(r.isect_per_ray, 2),
            opt(alpha, 3),
            opt(eta, 3),
            opt(vs_embree, 3),
            r.mismatches,
            if r.truncated { "yes" } else { "no" }
        );
    }
    if let Some(e) = embree {
        println!(
            "ratios to Embree, shadow rays: {}",
            rows.iter()
                .filter(|r| r.method != "embree" && r.shadow_rays > 0)
                .map(|r| format!("{} {:.3}", r.method, r.shadow_mrays() / e.shadow_mrays()))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
}

fn json_num(v: Option<f64>) -> String {
    match v {
        Some(x) if x.is_finite() => format!("{x}"),
        _ => "null".into(),
    }
}

/// The rows as one JSON object.
pub fn to_json(s: &SceneData, rows: &[Row]) -> String {
    let items: Vec<String> = rows
        .iter()
        .map(|r| {
            let (alpha, eta) = ratios(r, rows);
            format!(
                "{{\"method\": \"{}\", \"build_ms\": {}, \"arena_bytes\": {}, \"primary_mrays\": {}, \"shadow_mrays\": {}, \
                 \"tspr\": {}, \"isect_per_ray\": {}, \"alpha\": {}, \"eta\": {}, \"mismatches\": {}, \"truncated\": {}, \"gamma\": {}, \"cost_per_box\": {}, \"cost_per_prim\": {}}}",
                r.method,
                json_num(Some(r.build_ms)),
                r.arena_bytes.map_or("null".into(), |b| b.to_string()),
                json_num(Some(r.primary_mrays())),
                json_num(r.shadow_mrays_opt()),
                json_num(r.tspr),
                json_num(r.isect_per_ray),
                json_num(alpha),
                json_num(eta),
                r.mismatches,
                r.truncated,
                json_num(r.gamma),
                json_num(r.cost_per_box),
                json_num(r.cost_per_prim)
            )
        })
        .collect();
    format!(
        "{{\"scene\": \"{}\", \"objects\": {}, \"primitives\": {}, \"res\": [{}, {}], \"rows\": [{}]}}",
        s.name,
        s.mesh.counts.objects(),
        s.prim_count(),
        s.mesh.camera.width,
        s.mesh.camera.height,
        items.join(", ")
    )
}

/// `--table bvh`: the thesis' metrics per hierarchy builder (6.3.1):
/// preprocessing time, ray-tracing time (primary and shadow rays), objects
/// tested per primary ray, cost per hierarchy object and per actual object.
pub fn print_bvh_table(s: &SceneData, rows: &[Row]) {
    print_workload(s, rows, "; costs in the thesis' units");
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
        let opt = |v: Option<f64>| v.map_or("-".to_string(), |x| format!("{x:.2}"));
        println!(
            "{:<14} {:>12.1} {:>12.3} {:>14} {:>13} {:>13} {:>9}",
            r.method,
            r.build_ms,
            r.primary_s + r.shadow_s,
            opt(r.isect_per_ray),
            opt(r.cost_per_box),
            opt(r.cost_per_prim),
            r.mismatches
        );
    }
}

/// `--table proj`: per projection hierarchy x build criterion x scheme,
/// the thesis' chapter 6 metrics, with the 3D hierarchies and the kd-tree
/// of the same run above them.
pub fn print_proj_table(s: &SceneData, rows: &[Row]) {
    print_workload(
        s,
        rows,
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
    let opt = |v: Option<f64>, p: usize| v.map_or("-".to_string(), |x| format!("{x:.p$}"));
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
}

#[cfg(test)]
mod tests {
    use super::*;

    fn traced(mismatches: usize, hits: Vec<Hit>, shadowed: Vec<bool>) -> Traced {
        Traced {
            row: Row {
                mismatches,
                ..Row::default()
            },
            hits,
            shadowed,
        }
    }

    /// Different primitives hit within rounding of one t are a tie (a ray
    /// through a shared edge); farther apart, a mismatch.
    #[test]
    fn near_ties_agree_and_real_differences_do_not() {
        let h = |prim_id: u32, t: f32| Hit {
            t,
            geom_id: 0,
            prim_id,
            ..Hit::MISS
        };
        let t = 9.417824f32;
        let next = f32::from_bits(t.to_bits() + 1);
        assert!(same_hit(&h(173, t), &h(30, next)));
        assert!(same_hit(&h(30, t), &h(30, t)));
        assert!(!same_hit(&h(173, t), &h(30, t * (1.0 + 1e-5))));
        assert!(!same_hit(&h(173, t), &Hit::MISS));
    }

    /// An image-casting row is compared with the hierarchical cast of the
    /// same pixels timed in its own run, not with the kd row, which traces
    /// pre-generated rays into a vector of hits (about 25% more time for
    /// the same traversal: eta was once flattered by that much).
    #[test]
    fn cast_rows_are_compared_with_the_hierarchical_cast() {
        let kd = Row {
            method: "kd".into(),
            primary_s: 2.0,
            tspr: Some(40.0),
            ..Row::default()
        };
        let slcts = Row {
            method: "slcts2d".into(),
            primary_s: 1.0,
            tspr: Some(10.0),
            reference: Some(Reference {
                primary_s: 0.8,
                tspr: 20.0,
            }),
            ..Row::default()
        };
        let rows = [kd.clone(), slcts.clone()];
        assert_eq!(ratios(&slcts, &rows), (Some(0.5), Some(1.25)));
        // Rows without a cast reference (BVHs, ropes from vectors) use kd's.
        let rtree = Row {
            method: "rtree".into(),
            primary_s: 3.0,
            tspr: Some(20.0),
            ..Row::default()
        };
        assert_eq!(ratios(&rtree, &rows), (Some(0.5), Some(1.5)));
        assert_eq!(ratios(&kd, &rows), (Some(1.0), Some(1.0)));
    }

    /// Window sizes other than the paper's are methods too; a malformed or
    /// non-LCTS name is none.
    #[test]
    fn lcts_window_sizes_are_method_names() {
        assert_eq!(
            lcts_scheme("slcts2d:7x3"),
            Some(Scheme::Slcts2d { n: 7, m: 3 })
        );
        assert_eq!(lcts_scheme("slcts1d:9"), Some(Scheme::Slcts1d { n: 9 }));
        assert_eq!(lcts_scheme("slcts2d"), Some(Scheme::Slcts2d { n: 5, m: 5 }));
        for bad in [
            "slcts2d:7",
            "slcts2d:7x",
            "slcts1d:",
            "slcts1d:-2",
            "hlcts2d:4x4",
        ] {
            assert_eq!(lcts_scheme(bad), None, "{bad}");
        }
        assert!(is_lcts("slcts2d:9x9") && is_lcts("hlcts1d"));
        assert!(!is_lcts("kd") && !is_lcts("kd-rope") && !is_lcts("rtree"));
    }

    /// A method's own count (LCTS pixels, which come without per-ray hits)
    /// survives; differing hits and shadow answers add to it. (It was once
    /// overwritten, so LCTS rows showed 0 whatever their pixels said.)
    #[test]
    fn own_mismatches_are_kept_and_differences_added() {
        let hit = |t: f32| Hit {
            t,
            geom_id: 0,
            prim_id: 0,
            ..Hit::MISS
        };
        let reference = traced(0, vec![hit(1.0), Hit::MISS], vec![true, false]);
        let lcts = traced(3, Vec::new(), Vec::new());
        assert_eq!(total_mismatches(&lcts, &reference, false, &[]), 3);
        // Own 1, the second hit where the reference misses, the second shadow answer.
        let bvh = traced(1, vec![hit(1.0), hit(2.0)], vec![true, true]);
        assert_eq!(total_mismatches(&bvh, &reference, false, &[]), 1 + 1 + 1);
    }
}
