//! One benchmarked method's figures, and the runners that measure them:
//! ray-by-ray methods on the workload's primary and shadow rays, and LCTS
//! image casts against the hierarchical cast of the same pixels.

use super::harness::{best_of, trace};
use super::rays::{self, Rays};
use crate::built::{Built, Visit};
use crate::method::Method;
use crate::shoot::Shooter;
use coray::lcts::{image_requirements, Scheme};
use coray::owned::OwnedCast;
use coray::tolerance::{classify, same_hit, Agreement};
use coray::{Camera, Hit, Ray, TraceStats};
use coray_ffi::simd::cast_image;
use serde::Serialize;

/// What alpha and eta of an image cast are relative to: the hierarchical
/// cast of the same pixels timed in the same run and harness.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Reference {
    /// Its seconds.
    pub primary_s: f64,
    /// Its traversal steps per ray.
    pub tspr: f64,
}

/// One benchmarked method's figures.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Row {
    /// The method's name.
    pub method: String,
    /// Build time (ms).
    pub build_ms: f64,
    /// Bytes of the structure (None where it is not ours to measure).
    pub arena_bytes: Option<usize>,
    /// Seconds for the primary rays (best run).
    pub primary_s: f64,
    /// Seconds for the shadow rays (best run).
    pub shadow_s: f64,
    /// Primary rays traced.
    pub primary_rays: usize,
    /// Shadow rays traced.
    pub shadow_rays: usize,
    /// Traversal steps per primary ray (None for Embree).
    pub tspr: Option<f64>,
    /// Primitive tests per primary ray.
    pub isect_per_ray: Option<f64>,
    /// Rays whose answer differs from the reference beyond the tie rules.
    pub mismatches: usize,
    /// Rays whose answer differs by a documented tie.
    pub ties: usize,
    /// A kd-tree whose room ran out.
    pub truncated: bool,
    /// LCTS schemes: share of windows whose common sequence holds a leaf.
    pub gamma: Option<f64>,
    /// Hierarchies: the thesis' cost per hierarchy object.
    pub cost_per_box: Option<f64>,
    /// Hierarchies: the thesis' cost per actual object.
    pub cost_per_prim: Option<f64>,
    /// Projection methods: preprocessing of the view, light and global
    /// hierarchies (ms).
    pub build_split: Option<[f64; 3]>,
    /// Projection methods: shadow rays timed in the uniform mode (s).
    pub shadow_uniform_s: Option<f64>,
    /// Image casts: the hierarchical cast they are compared with.
    pub reference: Option<Reference>,
}

impl Row {
    /// Primary rays per second, in millions.
    pub fn primary_mrays(&self) -> f64 {
        self.primary_rays as f64 / self.primary_s / 1e6
    }

    /// Shadow rays per second, in millions; None when none were traced.
    pub fn shadow_mrays(&self) -> Option<f64> {
        (self.shadow_rays > 0).then(|| self.shadow_rays as f64 / self.shadow_s / 1e6)
    }
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
    match rows.iter().find(|r| r.method == "kd") {
        Some(k) => (
            row.tspr.zip(k.tspr).map(|(a, b)| a / b),
            Some(row.primary_s / k.primary_s),
        ),
        None => (None, None),
    }
}

/// The rays every method of a run traces, and the reference's answers
/// (the kd-tree's hierarchical traversal).
pub struct Workload {
    /// Primary rays, one per pixel.
    pub primary: Vec<Ray>,
    /// Shadow rays towards each light from the reference's hits.
    pub shadow: Rays,
    /// The reference's primary hits.
    pub hits: Vec<Hit>,
    /// The reference's shadow answers.
    pub occluded: Vec<bool>,
}

/// What a method gave on the workload: its row, its hits and answers.
pub struct Outcome {
    /// Its figures.
    pub row: Row,
    /// Its primary hits.
    pub hits: Vec<Hit>,
    /// Its shadow answers.
    pub occluded: Vec<bool>,
}

/// Traces the workload through one shooter.
struct RunRays<'w> {
    w: &'w Workload,
    repeat: usize,
    threads: usize,
    uniform: bool,
}

/// (primary seconds, hits, primary stats, shadow seconds, answers, shadow
/// stats, uniform-mode shadow seconds).
type Timings = (
    f64,
    Vec<Hit>,
    TraceStats,
    f64,
    Vec<bool>,
    TraceStats,
    Option<f64>,
);

impl Visit for RunRays<'_> {
    type Out = Timings;
    fn visit<S: Shooter>(self, s: &S) -> Timings {
        let (w, th) = (self.w, self.threads);
        let (ps, (hits, pst)) = best_of(self.repeat, || {
            let (t, h, _, st) = trace(s, &w.primary, None, false, th);
            (t, (h, st))
        });
        let lights = Some(&w.shadow.lights[..]);
        let (ss, (occ, sst)) = best_of(self.repeat, || {
            let (t, _, o, st) = trace(s, &w.shadow.rays, lights, true, th);
            (t, (o, st))
        });
        let uniform = self.uniform.then(|| {
            best_of(self.repeat, || {
                let (t, _, _, _) = trace(s, &w.shadow.rays, None, true, th);
                (t, ())
            })
            .0
        });
        (ps, hits, pst, ss, occ, sst, uniform)
    }
}

/// How a method's answers relate to the reference's, ray by ray: the one
/// judgement `bench` and `compare` share.
pub struct Verdicts {
    /// Per primary ray.
    pub primary: Vec<Agreement>,
    /// Per shadow ray.
    pub shadow: Vec<Agreement>,
}

impl Verdicts {
    /// (mismatches, documented ties) over both sets.
    pub fn counts(&self) -> (usize, usize) {
        let (a, b) = (tally(&self.primary), tally(&self.shadow));
        (a.0 + b.0, a.1 + b.1)
    }
}

/// Judges `built`'s answers (`hits` for the primary rays, `occluded` for
/// the shadow rays) against the workload's reference (`tree`).
pub fn judge(
    built: &Built,
    w: &Workload,
    tree: &coray::kd::KdTree,
    hits: &[Hit],
    occluded: &[bool],
) -> Verdicts {
    Verdicts {
        primary: judge_closest(built, &w.primary, hits, &w.hits),
        shadow: judge_any(built, tree, &w.shadow.rays, occluded, &w.occluded),
    }
}

/// Closest hits of `built` against the reference's, ray by ray. Exact
/// techniques must give the reference's primitive and t (a tie of two
/// primitives at one t allowed); Embree is judged by
/// [`coray::tolerance::classify`].
pub fn judge_closest(
    built: &Built,
    rays: &[Ray],
    hits: &[Hit],
    reference: &[Hit],
) -> Vec<Agreement> {
    let embree = matches!(built.method, Method::Embree(_));
    rays.iter()
        .enumerate()
        .map(|(i, r)| compare_hits(r, &hits[i], &reference[i], embree))
        .collect()
}

/// Any-hit answers of `built` against the reference's: exact techniques
/// must agree; a differing Embree answer is judged by the two closest
/// hits along that ray (ours from `tree`).
pub fn judge_any(
    built: &Built,
    tree: &coray::kd::KdTree,
    rays: &[Ray],
    occluded: &[bool],
    reference: &[bool],
) -> Vec<Agreement> {
    let embree = matches!(built.method, Method::Embree(_));
    let mut stk = coray::owned::stack(coray::kd::KD_STACK_LEN);
    let mut st = TraceStats::default();
    rays.iter()
        .enumerate()
        .map(|(i, r)| {
            if occluded[i] == reference[i] {
                Agreement::Same
            } else if !embree {
                Agreement::Mismatch
            } else {
                let ours = tree.intersect(r, coray::kd::Traversal::Hierarchical, &mut stk, &mut st);
                match classify(r, &ours, &embree_closest(built, r)) {
                    Agreement::Same => Agreement::Mismatch,
                    a => a,
                }
            }
        })
        .collect()
}

/// (mismatches, documented ties) of a list of verdicts.
pub fn tally(v: &[Agreement]) -> (usize, usize) {
    let m = v.iter().filter(|a| **a == Agreement::Mismatch).count();
    let same = v.iter().filter(|a| **a == Agreement::Same).count();
    (m, v.len() - m - same)
}

/// Traces `built` (a ray-by-ray method) through the workload and counts
/// its differences from the reference (`tree`, the kd-tree the workload's
/// answers came from).
pub fn run_rays(
    built: &Built,
    w: &Workload,
    tree: &coray::kd::KdTree,
    repeat: usize,
    threads: usize,
) -> Outcome {
    let uniform = matches!(built.method, Method::Proj(_));
    let (primary_s, hits, pst, shadow_s, occluded, sst, uniform_s) = built.visit(RunRays {
        w,
        repeat,
        threads,
        uniform,
    });
    let n = w.primary.len().max(1) as f64;
    // Embree counts nothing; the C-ABI rows pass NULL statistics.
    let counted = !matches!(
        built.method,
        Method::Embree(_) | Method::KdC { .. } | Method::WideC { .. }
    );
    let (mismatches, ties) = judge(built, w, tree, &hits, &occluded).counts();
    let mut all = pst;
    all.add(&sst);
    let hierarchy = matches!(built.method, Method::Bvh { .. } | Method::Proj(_));
    Outcome {
        row: Row {
            method: built.method.to_string(),
            build_ms: built.build_ms,
            arena_bytes: built.bytes,
            primary_s,
            shadow_s,
            primary_rays: w.primary.len(),
            shadow_rays: w.shadow.rays.len(),
            tspr: counted.then(|| pst.traversal_steps as f64 / n),
            isect_per_ray: counted.then(|| pst.prim_tests as f64 / n),
            mismatches,
            ties,
            truncated: built.truncated,
            cost_per_box: hierarchy.then(|| all.cost_per_box()),
            cost_per_prim: hierarchy.then(|| all.cost_per_prim()),
            build_split: built.rig().map(|r| [r.view_ms, r.light_ms, r.global_ms]),
            shadow_uniform_s: uniform_s,
            ..Row::default()
        },
        hits,
        occluded,
    }
}

/// Two answers for one primary ray: exact techniques must agree up to a
/// tie of two primitives at one t; Embree by the cross-check's rules.
pub fn compare_hits(r: &Ray, a: &Hit, b: &Hit, embree: bool) -> Agreement {
    if embree {
        return classify(r, a, b);
    }
    if (a.geom_id, a.prim_id, a.t.to_bits()) == (b.geom_id, b.prim_id, b.t.to_bits()) {
        Agreement::Same
    } else if same_hit(a, b) {
        Agreement::TieSameDistance
    } else {
        Agreement::Mismatch
    }
}

/// Embree's closest hit of one ray, for judging a differing shadow answer.
fn embree_closest(built: &Built, r: &Ray) -> Hit {
    struct One<'r>(&'r Ray);
    impl Visit for One<'_> {
        type Out = Hit;
        fn visit<S: Shooter>(self, s: &S) -> Hit {
            s.intersect(self.0, &mut s.ctx(), &mut TraceStats::default())
        }
    }
    built.visit(One(r))
}

/// An LCTS image cast on the camera's primary rays, timed in turn with the
/// hierarchical cast of the same pixels (its reference: alpha and eta).
/// Its mismatches are pixels whose primitive or t differ from that cast;
/// ties, pixels where two primitives meet at the same t.
pub fn run_cast(
    tree: &coray::kd::KdTree,
    camera: &Camera,
    scheme: Scheme,
    name: &str,
    build_ms: f64,
    arena_bytes: usize,
    repeat: usize,
) -> Result<Row, String> {
    let n = camera.width as usize * camera.height as usize;
    let req = image_requirements(camera.width, camera.height, scheme, 512);
    let mut scratch = OwnedCast::new(&req);
    let mut hits = vec![Hit::MISS; n];
    let mut reference = vec![Hit::MISS; n];
    let mut cast = |scheme: Scheme, out: &mut [Hit]| {
        cast_image(tree, camera, scheme, scratch.scratch(), out).map_err(|e| e.to_string())
    };
    let (mut reference_s, mut primary_s) = (f64::INFINITY, f64::INFINITY);
    let (mut rs, mut cs) = (None, None);
    for _ in 0..repeat.max(1) {
        let (s, r) = super::harness::timed(|| cast(Scheme::Hierarchical, &mut reference));
        reference_s = reference_s.min(s);
        rs = Some(r?);
        let (s, c) = super::harness::timed(|| cast(scheme, &mut hits));
        primary_s = primary_s.min(s);
        cs = Some(c?);
    }
    let (rs, cs) = (rs.expect("ran"), cs.expect("ran"));
    let (mismatches, ties) = cast_agreement(&hits, &reference);
    let rays = n.max(1) as f64;
    Ok(Row {
        method: name.to_string(),
        build_ms,
        arena_bytes: Some(arena_bytes),
        primary_s,
        primary_rays: n,
        tspr: Some(cs.trace.traversal_steps as f64 / rays),
        isect_per_ray: Some(cs.trace.prim_tests as f64 / rays),
        mismatches,
        ties,
        gamma: (!matches!(scheme, Scheme::Hierarchical | Scheme::Ropes)).then(|| cs.gamma()),
        reference: Some(Reference {
            primary_s: reference_s,
            tspr: rs.trace.traversal_steps as f64 / rays,
        }),
        ..Row::default()
    })
}

/// How an image cast agrees with the hierarchical cast of the same pixels:
/// (mismatches, ties). Any bit of difference counts, except two hits on
/// different primitives at t within rounding of each other
/// ([`coray::tolerance::near_tie`]), which are ties.
pub fn cast_agreement(hits: &[Hit], reference: &[Hit]) -> (usize, usize) {
    let (mut differ, mut ties) = (0, 0);
    for (a, b) in hits.iter().zip(reference) {
        if (a.geom_id, a.prim_id, a.t.to_bits()) != (b.geom_id, b.prim_id, b.t.to_bits()) {
            differ += 1;
            ties += (a.is_hit() && b.is_hit() && coray::tolerance::near_tie(a.t, b.t)) as usize;
        }
    }
    (differ - ties, ties)
}

/// The workload of a scene: its primary rays, the reference's hits, the
/// shadow rays from them, and the reference's shadow answers.
pub fn workload(mesh: &coray_scenes::SceneMesh, reference: &coray::kd::KdTree) -> Workload {
    let primary = rays::primary(mesh);
    let mut stk = coray::owned::stack(coray::kd::KD_STACK_LEN);
    let mut st = TraceStats::default();
    let m = coray::kd::Traversal::Hierarchical;
    let hits: Vec<Hit> = primary
        .iter()
        .map(|r| reference.intersect(r, m, &mut stk, &mut st))
        .collect();
    let shadow = rays::shadow(mesh, &primary, &hits);
    let occluded = shadow
        .rays
        .iter()
        .map(|r| reference.occluded(r, m, &mut stk, &mut st))
        .collect();
    Workload {
        primary,
        shadow,
        hits,
        occluded,
    }
}
