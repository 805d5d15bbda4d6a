//! The body of coray's C-ABI fuzz target (`fuzz/`), and of `cargo test`'s
//! replay of its regression corpus (`fuzz/regressions/`).
//!
//! One input drives one structure family through every entry point it
//! has: a small fixed scene (perturbed by the input when it asks) is built
//! into an arena, the arena is then corrupted by the input (bytes flipped,
//! replaced wholesale, or cut short), and the corrupted arena is opened,
//! validated, traced, cast, queried for patch visibility, and for R-trees
//! updated. What must hold, whatever the bytes:
//!
//! - no entry point panics (the std build would turn a panic into
//!   `CORAY_STATUS_INTERNAL_ERROR`, which this harness treats as a crash);
//! - nothing returns late (the fuzzer's timeout);
//! - when validate says OK, every trace on that arena answers as the
//!   clean build does (the same primitive and t, or a tie of two
//!   primitives at one t), and an R-tree update on it keeps it valid;
//! - a kd build whose jobs a runner drives from the input (flag bit 3:
//!   indices out of range, short flags, repeats, jobs never run) writes the
//!   clean build's arena, byte for byte, and refuses each misuse with a
//!   status.
//!
//! The first byte picks the family (kd-tree, hierarchy, projection
//! hierarchy, by its remainder mod 3); flag bits 4 to 7 equal to 5 pick the
//! wide hierarchy instead (a value no corpus input had when it came, so
//! the corpus kept its meaning). Two more values leave the arenas intact
//! and damage something else:
//!
//! - 6: one to three words of the scene changed by the input, then the
//!   kd-tree, wide and TDBS arenas built over the original opened over the
//!   changed scene: when `validate` accepts, every answer is a fresh
//!   build's over the changed scene; the kd-tree accepts only an unchanged
//!   scene (its scene digest);
//! - 7: a saved file (`coray build -o`) damaged like an arena and given to
//!   `coray_saved_open`: when it opens, the tree answers as the clean
//!   file's.

use coray::tolerance::near_tie;
use coray_ffi::*;
use core::ffi::c_void;
use core::mem::size_of;

/// Memory aligned for every arena, scratch and stack the ABI takes.
#[repr(C, align(16))]
#[derive(Clone, Copy)]
struct Block([u8; 16]);

fn blocks(bytes: usize) -> Vec<Block> {
    vec![Block([0; 16]); bytes.div_ceil(16).max(1)]
}

fn as_bytes(b: &[Block]) -> Vec<u8> {
    b.iter().flat_map(|x| x.0).collect()
}

fn from_bytes(bytes: &[u8]) -> Vec<Block> {
    let mut b = blocks(bytes.len());
    for (i, v) in bytes.iter().enumerate() {
        b[i / 16].0[i % 16] = *v;
    }
    b
}

/// Reads the input front to back; past its end, zeros.
struct Input<'a> {
    d: &'a [u8],
    at: usize,
}

impl Input<'_> {
    fn u8(&mut self) -> u8 {
        let v = self.d.get(self.at).copied().unwrap_or(0);
        self.at += 1;
        v
    }
    fn u32(&mut self) -> u32 {
        u32::from_le_bytes([self.u8(), self.u8(), self.u8(), self.u8()])
    }
    fn f32(&mut self) -> f32 {
        f32::from_bits(self.u32())
    }
    fn rest(&self) -> &[u8] {
        self.d.get(self.at..).unwrap_or(&[])
    }
}

/// The scene's arrays: a floor, a few triangles, spheres and cones.
#[derive(Clone)]
struct SceneData {
    vertices: Vec<f32>,
    indices: Vec<u32>,
    spheres: Vec<f32>,
    cones: Vec<f32>,
}

impl SceneData {
    fn new(inp: &mut Input, perturb: bool) -> SceneData {
        let mut s = SceneData {
            vertices: vec![
                -4., 0., -4., 4., 0., -4., 4., 0., 4., -4., 0., 4., // floor
                -1., 1., -1., 1., 1., -1., 0., 2.5, 0., // a tent
                1.5, 0.5, 1.5, 2.5, 0.5, 1.5, 2., 1.5, 2., // another
            ],
            indices: vec![0, 1, 2, 0, 2, 3, 4, 5, 6, 7, 8, 9, 4, 6, 9],
            spheres: vec![0., 1., 2., 0.7, -2., 0.5, -2., 0.5, 2.5, 2., -1., 0.4],
            cones: vec![
                -2.5, 0., 2., 0.4, -2.5, 2., 2., 0.1, // cone
                2.5, 0., -2.5, 0.3, 2.5, 1.5, -2.5, 0.3, // cylinder
            ],
        };
        if perturb {
            // One value of each array from the input (NaN, infinities and
            // huge numbers included).
            let n = s.vertices.len();
            s.vertices[inp.u8() as usize % n] = inp.f32();
            let n = s.spheres.len();
            s.spheres[inp.u8() as usize % n] = inp.f32();
            let n = s.cones.len();
            s.cones[inp.u8() as usize % n] = inp.f32();
        }
        s
    }

    /// Every word the same, bit for bit (NaN equals its own bits).
    fn same_bits(&self, o: &SceneData) -> bool {
        let f = |a: &[f32], b: &[f32]| {
            a.iter()
                .map(|x| x.to_bits())
                .eq(b.iter().map(|x| x.to_bits()))
        };
        f(&self.vertices, &o.vertices)
            && self.indices == o.indices
            && f(&self.spheres, &o.spheres)
            && f(&self.cones, &o.cones)
    }

    fn prims(&self) -> usize {
        self.indices.len() / 3 + self.spheres.len() / 4 + self.cones.len() / 8
    }

    fn scene(&self) -> CorayScene {
        let mut s = coray_scene_default();
        s.vertices = self.vertices.as_ptr();
        s.vertex_count = self.vertices.len() / 3;
        s.indices = self.indices.as_ptr();
        s.triangle_count = self.indices.len() / 3;
        s.spheres = self.spheres.as_ptr();
        s.sphere_count = self.spheres.len() / 4;
        s.cones = self.cones.as_ptr();
        s.cone_count = self.cones.len() / 8;
        s
    }
}

/// Rays: a fixed fan through the scene, then a few from the input.
fn rays(inp: &mut Input) -> Vec<CorayRay> {
    let mut v = Vec::new();
    for k in 0..12 {
        let a = k as f32 * 0.5;
        v.push(CorayRay {
            org: [6.0 * a.cos(), 3.0, 6.0 * a.sin()],
            tnear: 0.0,
            dir: [-a.cos(), -0.45, -a.sin()],
            tfar: if k % 3 == 0 { 5.0 } else { f32::INFINITY },
        });
    }
    for _ in 0..inp.u8() % 6 {
        v.push(CorayRay {
            org: [inp.f32(), inp.f32(), inp.f32()],
            tnear: inp.f32(),
            dir: [inp.f32(), inp.f32(), inp.f32()],
            tfar: inp.f32(),
        });
    }
    v
}

/// Status codes there are (`CORAY_STATUS_OK` = 0 to `_DAMAGED_FILE` = 11).
pub const STATUS_COUNT: usize = CorayStatus::DamagedFile as usize + 1;

/// What a run saw: how many calls ended with each status.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Report {
    /// Calls per status code.
    pub statuses: [u32; STATUS_COUNT],
    /// Whether the corrupted arena validated.
    pub validated: bool,
    /// `run_job` calls of a hostile kd job runner, per status code.
    pub run_job: [u32; STATUS_COUNT],
}

impl Report {
    fn note(&mut self, what: &str, s: CorayStatus) -> CorayStatus {
        assert!(
            s != CorayStatus::InternalError,
            "{what}: CORAY_STATUS_INTERNAL_ERROR (a panic caught)"
        );
        self.statuses[s as usize] += 1;
        s
    }
}

/// How the input corrupts the arena.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Damage {
    /// Bytes at input-chosen offsets XORed with input-chosen values.
    Flips,
    /// The arena replaced by the input's remaining bytes.
    Raw,
    /// The arena cut to an input-chosen length, then flipped.
    Short,
}

fn damage(arena: &mut Vec<u8>, inp: &mut Input, how: Damage) {
    match how {
        Damage::Raw => *arena = inp.rest().to_vec(),
        Damage::Short => {
            let len = inp.u32() as usize % (arena.len() + 1);
            arena.truncate(len);
            flips(arena, inp);
        }
        Damage::Flips => flips(arena, inp),
    }
}

fn flips(arena: &mut [u8], inp: &mut Input) {
    if arena.is_empty() {
        return;
    }
    for _ in 0..inp.u8() % 16 {
        let at = inp.u32() as usize % arena.len();
        arena[at] ^= inp.u8();
    }
}

/// Same answer for one ray from the clean and the damaged arena.
fn same(a: &CorayHit, b: &CorayHit) -> bool {
    let miss = |h: &CorayHit| h.geom_id == u32::MAX;
    match (miss(a), miss(b)) {
        (true, true) => true,
        (false, false) => {
            (a.geom_id, a.prim_id, a.t.to_bits()) == (b.geom_id, b.prim_id, b.t.to_bits())
                || near_tie(a.t, b.t)
        }
        _ => false,
    }
}

/// The trace answers of one arena for `rays`: closest hits by the array
/// call, by the one-ray call, any-hit answers, the statuses of the two
/// array calls, and which rays the one-ray call took (an answer it
/// refused is the zeroed default, not a miss).
type Answers = (
    Vec<CorayHit>,
    Vec<CorayHit>,
    Vec<u8>,
    [CorayStatus; 2],
    Vec<bool>,
);

/// Runs one input. Panics when a property above fails.
pub fn run(data: &[u8]) -> Report {
    let mut inp = Input { d: data, at: 0 };
    let family = inp.u8();
    let flags = inp.u8();
    let how = match flags & 3 {
        0 | 3 => Damage::Flips,
        1 => Damage::Raw,
        _ => Damage::Short,
    };
    let sd = SceneData::new(&mut inp, flags & 4 != 0);
    let rays = rays(&mut inp);
    let mut rep = Report::default();
    match flags >> 4 {
        WIDE_FLAGS => wide(&sd, &rays, &mut inp, how, &mut rep),
        SCENE_FLAGS => scene_changed(&sd, &rays, &mut inp, &mut rep),
        SAVED_FLAGS => saved_damaged(&sd, &rays, &mut inp, how, &mut rep),
        _ => {}
    }
    if matches!(flags >> 4, WIDE_FLAGS | SCENE_FLAGS | SAVED_FLAGS) {
        return rep;
    }
    match family % 3 {
        0 => kd(
            &sd,
            &rays,
            &mut inp,
            how,
            (family / 3 % 2 == 1, flags & 8 != 0),
            &mut rep,
        ),
        1 => bvh(&sd, &rays, &mut inp, how, family / 3, &mut rep),
        _ => proj(&sd, &rays, &mut inp, how, family / 3, &mut rep),
    }
    rep
}

/// A runner for `coray_kdtree_build_jobs` that does what the input says:
/// job indices (out of range too), flags one byte short, the same job
/// twice, jobs left to the build.
struct HostileRunner<'a> {
    inp: Input<'a>,
    report: Report,
}

/// The `run_jobs` of [`HostileRunner`].
///
/// # Safety
/// `ctx` is a live `HostileRunner`; the rest as `CorayKdRunJobs` says.
unsafe extern "C" fn hostile_run_jobs(
    ctx: *mut c_void,
    job_count: usize,
    flags_bytes: usize,
    run_job: CorayKdRunJob,
    jobs: *mut c_void,
) {
    // SAFETY: the harness passes its HostileRunner as ctx.
    let r = unsafe { &mut *ctx.cast::<HostileRunner>() };
    let mut flags = vec![0u8; flags_bytes + 1];
    for _ in 0..r.inp.u8() % 48 {
        let job = r.inp.u8() as usize % (job_count + 2);
        let len = if r.inp.u8() % 4 == 0 {
            flags_bytes.saturating_sub(1)
        } else {
            flags_bytes
        };
        // SAFETY: `jobs` and `run_job` are this call's; flags holds len bytes.
        let s = unsafe { run_job(jobs, job, flags.as_mut_ptr(), len) };
        assert!(
            matches!(s, CorayStatus::Ok | CorayStatus::InvalidParameter),
            "run_job {job} of {job_count} with {len} flag bytes: {s:?}"
        );
        r.report.note("kd run_job", s);
    }
}

/// The kd build again with its jobs run as the input says: the arena must
/// be the clean build's, byte for byte.
fn kd_jobs(
    scene: &CorayScene,
    params: &CorayKdParams,
    (clean, arena_bytes): (&[Block], usize),
    scratch_bytes: usize,
    inp: &Input,
    rep: &mut Report,
) {
    let mut arena = blocks(arena_bytes);
    let mut scratch = blocks(scratch_bytes);
    // The runner reads a copy of the input: the damage that follows sees
    // the same bytes with or without this build.
    let mut runner = HostileRunner {
        inp: Input {
            d: inp.d,
            at: inp.at,
        },
        report: Report::default(),
    };
    // SAFETY: as the clean build; the runner keeps CorayKdRunJobs' contract
    // (one thread, returns when its calls have) and lives through the call.
    let s = unsafe {
        coray_kdtree_build_jobs(
            scene,
            params,
            arena.as_mut_ptr().cast(),
            arena_bytes,
            scratch.as_mut_ptr().cast(),
            scratch_bytes,
            core::ptr::null_mut(),
            Some(hostile_run_jobs),
            (&mut runner as *mut HostileRunner).cast(),
        )
    };
    assert_eq!(rep.note("kd build jobs", s), CorayStatus::Ok);
    rep.run_job = runner.report.statuses;
    assert!(
        as_bytes(&arena)[..arena_bytes] == as_bytes(clean)[..arena_bytes],
        "the job build's arena differs from coray_kdtree_build's"
    );
}

/// Checks the damaged arena's answers against the clean one's.
fn compare(what: &str, clean: &Answers, got: &Answers, rays: &[CorayRay]) {
    // A validated arena may differ from the clean one in a value that only
    // changes which rays it takes (a projection plane's eye moved by a
    // rounding): the documented refusal, nothing else, and then no answers.
    if clean.3 != got.3 {
        for s in got.3 {
            assert!(
                matches!(s, CorayStatus::Ok | CorayStatus::InvalidParameter),
                "{what}: a validated arena's trace gives {s:?}"
            );
        }
        return;
    }
    for (i, ray) in rays.iter().enumerate() {
        assert!(
            same(&clean.0[i], &got.0[i]),
            "{what}: a validated arena answers ray {i} ({ray:?}) otherwise: {:?} against {:?}",
            got.0[i],
            clean.0[i]
        );
        match (clean.4[i], got.4[i]) {
            (true, true) => assert!(
                same(&clean.1[i], &got.1[i]),
                "{what}: a validated arena's one-ray call answers ray {i} ({ray:?}) otherwise: \
                 {:?} against {:?}",
                got.1[i],
                clean.1[i]
            ),
            // Taken by one arena and refused by the other: only a
            // projection plane's eye, moved by a rounding, changes which
            // rays a call takes (the array calls' rule above, ray by ray:
            // both array calls may refuse the batch for another ray).
            (a, b) if a != b => assert_eq!(
                what, "proj",
                "{what}: a validated arena's one-ray call takes ray {i} ({ray:?}): {b}, \
                 the clean one's: {a}"
            ),
            _ => {}
        }
        assert_eq!(
            clean.2[i] != 0,
            got.2[i] != 0,
            "{what}: a validated arena's any-hit answer for ray {i} differs"
        );
    }
}

fn requirements() -> CorayRequirements {
    coray_requirements_default()
}

fn kd(
    sd: &SceneData,
    rays: &[CorayRay],
    inp: &mut Input,
    how: Damage,
    (paper, jobs): (bool, bool),
    rep: &mut Report,
) {
    let scene = sd.scene();
    let preset = if paper {
        CORAY_KD_PRESET_PAPER
    } else {
        CORAY_KD_PRESET_AUTO
    };
    let mut params = coray_kdtree_params_default(preset);
    // Auto trees with ropes, without (their casts then return NO_ROPES),
    // and compact (without, and without the empty leaves beside full ones).
    if !paper {
        params.omit_ropes = (inp.u8() % 3) as u32;
    }
    let mut req = requirements();
    // SAFETY: params and req are live locals with struct_size set.
    let s = unsafe { coray_kdtree_requirements(sd.prims(), &params, &mut req) };
    if rep.note("kd requirements", s) != CorayStatus::Ok {
        return;
    }
    let mut arena = blocks(req.arena_bytes);
    let mut scratch = blocks(req.scratch_bytes);
    // SAFETY: the scene's arrays outlive the call; arena and scratch are
    // 16-byte aligned buffers of at least the sizes passed.
    let s = unsafe {
        coray_kdtree_build(
            &scene,
            &params,
            arena.as_mut_ptr().cast(),
            req.arena_bytes,
            scratch.as_mut_ptr().cast(),
            req.scratch_bytes,
            core::ptr::null_mut(),
        )
    };
    if rep.note("kd build", s) != CorayStatus::Ok {
        return;
    }
    if jobs {
        kd_jobs(
            &scene,
            &params,
            (&arena, req.arena_bytes),
            req.scratch_bytes,
            inp,
            rep,
        );
    }
    let clean = open_kd(&arena, req.arena_bytes, &scene).expect("a clean build opens");
    // Each traversal against its own clean answers: the two agree on
    // ordinary rays (tests/kd_oracle.rs), but on grazing rays with
    // sub-normal directions either may see a hit the other does not.
    let traversals = [
        (CORAY_TRAVERSAL_HIERARCHICAL, "kd hierarchical"),
        (CORAY_TRAVERSAL_ROPES, "kd ropes"),
    ];
    let clean_answers = traversals.map(|(t, _)| kd_trace(&clean, rays, t, rep));
    let mut bytes = as_bytes(&arena);
    bytes.truncate(req.arena_bytes);
    damage(&mut bytes, inp, how);
    let bad = from_bytes(&bytes);
    let Some(tree) = open_kd(&bad, bytes.len(), &scene)
        .map_err(|s| rep.note("kd open", s))
        .ok()
    else {
        return;
    };
    let mut shape = coray_shape_default();
    // SAFETY: tree and shape are live locals; the stack argument is ignored by kd validate.
    let v = unsafe { coray_kdtree_validate(&tree, core::ptr::null_mut(), 0, &mut shape) };
    rep.validated = rep.note("kd validate", v) == CorayStatus::Ok;
    for (k, (traversal, what)) in traversals.into_iter().enumerate() {
        let got = kd_trace(&tree, rays, traversal, rep);
        if rep.validated {
            compare(what, &clean_answers[k], &got, rays);
        }
    }
    kd_cast(&tree, inp, rep);
    kd_patch(&tree, inp, rep);
}

fn open_kd(arena: &[Block], bytes: usize, scene: &CorayScene) -> Result<CorayKdTree, CorayStatus> {
    let mut h = CorayKdTree { opaque: [0; 32] };
    // SAFETY: arena holds at least `bytes` bytes; scene's arrays are live.
    let s = unsafe { coray_kdtree_open(arena.as_ptr().cast(), bytes, scene, &mut h) };
    if s == CorayStatus::Ok {
        Ok(h)
    } else {
        Err(s)
    }
}

/// A family's one-ray calls on a tracer: tracer, ray, answer.
type TracerCall<O> = unsafe extern "C" fn(*mut CorayTracer, *const CorayRay, *mut O) -> CorayStatus;

/// One-ray calls through a tracer made by `make` on a stack of its own
/// (`calls`: the family's intersect1 and occluded1 on a tracer): where its
/// make call and a ray's call succeed, the answer must be the handle's
/// one-ray call's (`ones`, `one_ok`), bit for bit.
#[allow(clippy::too_many_arguments)]
fn traced(
    family: &str,
    rays: &[CorayRay],
    ones: &[CorayHit],
    one_ok: &[bool],
    stack_bytes: usize,
    rep: &mut Report,
    make: impl FnOnce(*mut c_void, usize, *mut CorayTracer) -> CorayStatus,
    calls: (TracerCall<CorayHit>, TracerCall<u8>),
) {
    let mut stack = blocks(stack_bytes);
    let mut tracer = Box::new(CorayTracer { opaque: [0; 32] });
    let made = rep.note(
        &format!("{family} tracer"),
        make(stack.as_mut_ptr().cast(), stack_bytes, &mut *tracer),
    );
    if made != CorayStatus::Ok {
        return;
    }
    for (i, r) in rays.iter().enumerate() {
        let mut h = CorayHit::default();
        let mut o = 0u8;
        // SAFETY: the tracer was made on a live handle and this stack;
        // the ray and the answers are locals.
        let (s, so) = unsafe {
            (
                (calls.0)(&mut *tracer, r, &mut h),
                (calls.1)(&mut *tracer, r, &mut o),
            )
        };
        rep.note(&format!("{family} tracer intersect1"), s);
        rep.note(&format!("{family} tracer occluded1"), so);
        if s == CorayStatus::Ok && one_ok[i] {
            let w = &ones[i];
            assert!(
                (h.geom_id, h.prim_id, h.t.to_bits()) == (w.geom_id, w.prim_id, w.t.to_bits()),
                "{family}: the tracer answers ray {i} otherwise than intersect1: {h:?} against {w:?}"
            );
        }
    }
}

fn kd_trace(
    t: &CorayKdTree,
    rays: &[CorayRay],
    traversal: CorayTraversal,
    rep: &mut Report,
) -> Answers {
    let n = rays.len();
    let mut stack = blocks(CORAY_KDTREE_STACK_BYTES);
    let sp: *mut c_void = stack.as_mut_ptr().cast();
    let mut hits = vec![CorayHit::default(); n];
    let mut ones = vec![CorayHit::default(); n];
    let mut occ = vec![0u8; n];
    let mut stats = coray_trace_stats_default();
    let mut statuses = [CorayStatus::Ok; 2];
    let mut one_ok = vec![false; n];
    // SAFETY: every buffer is live and as long as the count passed; the
    // stack has CORAY_KDTREE_STACK_BYTES aligned bytes.
    unsafe {
        let s = coray_kdtree_intersect(
            t,
            traversal,
            rays.as_ptr(),
            hits.as_mut_ptr(),
            n,
            sp,
            CORAY_KDTREE_STACK_BYTES,
            &mut stats,
        );
        statuses[0] = rep.note("kd intersect", s);
        let s = coray_kdtree_occluded(
            t,
            traversal,
            rays.as_ptr(),
            occ.as_mut_ptr(),
            n,
            sp,
            CORAY_KDTREE_STACK_BYTES,
            &mut stats,
        );
        statuses[1] = rep.note("kd occluded", s);
        for ((r, h), ok) in rays.iter().zip(ones.iter_mut()).zip(one_ok.iter_mut()) {
            let s = coray_kdtree_intersect1(
                t,
                traversal,
                r,
                h,
                sp,
                CORAY_KDTREE_STACK_BYTES,
                &mut stats,
            );
            *ok = rep.note("kd intersect1", s) == CorayStatus::Ok;
            let mut o = 0u8;
            let s = coray_kdtree_occluded1(
                t,
                traversal,
                r,
                &mut o,
                sp,
                CORAY_KDTREE_STACK_BYTES,
                core::ptr::null_mut(),
            );
            rep.note("kd occluded1", s);
        }
    }
    let make = |sp, sb, tr| unsafe {
        // SAFETY: the handle is live; the stack and tracer are the helper's.
        coray_kdtree_tracer(t, traversal, sp, sb, tr)
    };
    let on_tracer = (
        coray_kdtree_tracer_intersect1 as TracerCall<CorayHit>,
        coray_kdtree_tracer_occluded1 as TracerCall<u8>,
    );
    traced(
        "kd",
        rays,
        &ones,
        &one_ok,
        CORAY_KDTREE_STACK_BYTES,
        rep,
        make,
        on_tracer,
    );
    (hits, ones, occ, statuses, one_ok)
}

fn kd_cast(t: &CorayKdTree, inp: &mut Input, rep: &mut Report) {
    let mut cam = coray_camera_default();
    cam.from = [0.0, 3.0, 7.0];
    cam.at = [0.0, 0.5, 0.0];
    cam.up = [0.0, 1.0, 0.0];
    cam.angle_deg = 50.0;
    cam.width = 1 + inp.u8() as u32 % 12;
    cam.height = 1 + inp.u8() as u32 % 12;
    let mut p = coray_cast_params_default();
    p.scheme = inp.u8() as u32 % 7;
    p.window_width = inp.u8() as u32 % 8;
    p.window_height = inp.u8() as u32 % 8;
    p.history_capacity = 1 + inp.u8() as u32 % 64;
    // Half the casts a rectangle of the image (since 1.6), some of them
    // empty or leaving it.
    let rect = inp.u8();
    if rect & 1 == 1 {
        p.rect_x = inp.u8() as u32 % 14;
        p.rect_y = inp.u8() as u32 % 14;
        p.rect_width = inp.u8() as u32 % 14;
        p.rect_height = inp.u8() as u32 % 14;
    }
    let mut req = requirements();
    // SAFETY: live locals with struct_size set.
    let s = unsafe { coray_kdtree_cast_requirements(&cam, &p, &mut req) };
    if rep.note("kd cast requirements", s) != CorayStatus::Ok {
        return;
    }
    let mut scratch = blocks(req.scratch_bytes);
    let mut stack = blocks(req.stack_bytes);
    // The hits of the pixels cast: a rectangle's, else the image's.
    let pixels = if p.rect_width > 0 {
        p.rect_width * p.rect_height
    } else {
        cam.width * cam.height
    };
    let mut hits = vec![CorayHit::default(); pixels as usize];
    let mut stats = coray_trace_stats_default();
    // SAFETY: scratch, stack and hits are as large as the requirements
    // and the pixels cast ask.
    let s = unsafe {
        coray_kdtree_cast_image(
            t,
            &cam,
            &p,
            scratch.as_mut_ptr().cast(),
            req.scratch_bytes,
            stack.as_mut_ptr().cast(),
            req.stack_bytes,
            hits.as_mut_ptr(),
            &mut stats,
        )
    };
    rep.note("kd cast image", s);
}

fn kd_patch(t: &CorayKdTree, inp: &mut Input, rep: &mut Report) {
    let a = [
        -2.0f32, 3.0, -2.0, 2.0, 3.0, -2.0, 2.0, 3.0, 2.0, -2.0, 3.0, 2.0,
    ];
    let mut b = [
        -3.0f32, -1.0, -3.0, 3.0, -1.0, -3.0, 3.0, -1.0, 3.0, -3.0, -1.0, 3.0,
    ];
    if inp.u8() & 1 == 1 {
        b[inp.u8() as usize % 12] = inp.f32();
    }
    let cap = 1 + inp.u8() as u32 % 64;
    let samples = inp.u8() as u32 % 6;
    let mut req = requirements();
    // SAFETY: a live local with struct_size set.
    let s = unsafe { coray_kdtree_patch_requirements(cap, &mut req) };
    if rep.note("kd patch requirements", s) != CorayStatus::Ok {
        return;
    }
    let mut scratch = blocks(req.scratch_bytes);
    let mut stack = blocks(req.stack_bytes);
    let mut out = coray_patch_result_default();
    // SAFETY: both patches hold 4 vertices; scratch and stack are as
    // large as asked.
    let s = unsafe {
        coray_kdtree_patch_visibility(
            t,
            a.as_ptr(),
            4,
            b.as_ptr(),
            4,
            samples,
            1e-4,
            scratch.as_mut_ptr().cast(),
            req.scratch_bytes,
            stack.as_mut_ptr().cast(),
            req.stack_bytes,
            &mut out,
            core::ptr::null_mut(),
        )
    };
    rep.note("kd patch visibility", s);
}

/// The BVH builders the families cycle through.
const BUILDERS: [CorayBvhBuilder; 6] = [
    CORAY_BVH_BUILDER_TDBS,
    CORAY_BVH_BUILDER_TDBS_SAH,
    CORAY_BVH_BUILDER_NN,
    CORAY_BVH_BUILDER_NN_CHAIN,
    CORAY_BVH_BUILDER_RTREE,
    CORAY_BVH_BUILDER_RSTAR,
];

fn bvh(
    sd: &SceneData,
    rays: &[CorayRay],
    inp: &mut Input,
    how: Damage,
    which: u8,
    rep: &mut Report,
) {
    let scene = sd.scene();
    let builder = BUILDERS[which as usize % BUILDERS.len()];
    let params = coray_bvh_params_default(builder);
    let mut req = requirements();
    // SAFETY: live locals with struct_size set.
    let s = unsafe { coray_bvh_requirements(sd.prims(), &params, &mut req) };
    if rep.note("bvh requirements", s) != CorayStatus::Ok {
        return;
    }
    let mut arena = blocks(req.arena_bytes);
    let mut scratch = blocks(req.scratch_bytes);
    // SAFETY: as for the kd build.
    let s = unsafe {
        coray_bvh_build(
            &scene,
            &params,
            arena.as_mut_ptr().cast(),
            req.arena_bytes,
            scratch.as_mut_ptr().cast(),
            req.scratch_bytes,
            core::ptr::null_mut(),
        )
    };
    if rep.note("bvh build", s) != CorayStatus::Ok {
        return;
    }
    let clean = open_bvh(&arena, req.arena_bytes, &scene).expect("a clean build opens");
    let clean_answers = bvh_trace(&clean, rays, req.stack_bytes, rep);
    let mut bytes = as_bytes(&arena);
    bytes.truncate(req.arena_bytes);
    damage(&mut bytes, inp, how);
    let mut bad = from_bytes(&bytes);
    let Some(h) = open_bvh(&bad, bytes.len(), &scene)
        .map_err(|s| rep.note("bvh open", s))
        .ok()
    else {
        return;
    };
    rep.validated = bvh_validate(&h, req.stack_bytes, rep) == CorayStatus::Ok;
    let got = bvh_trace(&h, rays, req.stack_bytes, rep);
    if rep.validated {
        compare("bvh", &clean_answers, &got, rays);
    }
    if builder == CORAY_BVH_BUILDER_RTREE || builder == CORAY_BVH_BUILDER_RSTAR {
        // Delete then insert a primitive chosen by the input: all or
        // nothing, and a valid tree stays valid.
        let geom = inp.u8() as u32 % 4;
        let prim = inp.u8() as u32 % 8;
        let mut deleted = 0u8;
        let len = bytes.len();
        // SAFETY: bad holds `len` aligned bytes; scratch is the build's.
        let s = unsafe {
            coray_bvh_delete(
                bad.as_mut_ptr().cast(),
                len,
                &scene,
                geom,
                prim,
                scratch.as_mut_ptr().cast(),
                req.scratch_bytes,
                &mut deleted,
            )
        };
        let deleted_ok = rep.note("bvh delete", s) == CorayStatus::Ok;
        // SAFETY: as above.
        let s = unsafe { coray_bvh_insert(bad.as_mut_ptr().cast(), len, &scene, geom, prim) };
        let inserted_ok = rep.note("bvh insert", s) == CorayStatus::Ok;
        if rep.validated && deleted_ok && inserted_ok {
            let h = open_bvh(&bad, len, &scene).expect("an updated valid tree opens");
            let v = bvh_validate(&h, req.stack_bytes, rep);
            if v != CorayStatus::Ok {
                // The same updates on the clean arena, for the report.
                let mut c = arena.clone();
                let mut d2 = 0u8;
                // SAFETY: as above, on the clean copy.
                let (s1, s2) = unsafe {
                    (
                        coray_bvh_delete(
                            c.as_mut_ptr().cast(),
                            len,
                            &scene,
                            geom,
                            prim,
                            scratch.as_mut_ptr().cast(),
                            req.scratch_bytes,
                            &mut d2,
                        ),
                        coray_bvh_insert(c.as_mut_ptr().cast(), len, &scene, geom, prim),
                    )
                };
                let hc = open_bvh(&c, len, &scene).expect("opens");
                let vc = bvh_validate(&hc, req.stack_bytes, rep);
                panic!("an update left a valid R-tree invalid ({v:?}; deleted {deleted}, geom {geom} prim {prim}; the clean arena: delete {s1:?} deleted {d2}, insert {s2:?}, validate {vc:?})");
            }
        }
    }
}

fn open_bvh(arena: &[Block], bytes: usize, scene: &CorayScene) -> Result<CorayBvh, CorayStatus> {
    let mut h = CorayBvh { opaque: [0; 32] };
    // SAFETY: arena holds at least `bytes` bytes; scene's arrays are live.
    let s = unsafe { coray_bvh_open(arena.as_ptr().cast(), bytes, scene, &mut h) };
    if s == CorayStatus::Ok {
        Ok(h)
    } else {
        Err(s)
    }
}

fn bvh_validate(h: &CorayBvh, stack_bytes: usize, rep: &mut Report) -> CorayStatus {
    let mut stack = blocks(stack_bytes);
    let mut shape = coray_shape_default();
    // SAFETY: the stack holds stack_bytes aligned bytes.
    let s = unsafe { coray_bvh_validate(h, stack.as_mut_ptr().cast(), stack_bytes, &mut shape) };
    rep.note("bvh validate", s)
}

/// The entry points one trace of a family makes on a handle `H`.
struct TraceCalls<H> {
    intersect: ArrayCall<H, CorayHit>,
    occluded: ArrayCall<H, u8>,
    intersect1: OneCall<H, CorayHit>,
    occluded1: OneCall<H, u8>,
    tracer: MakeTracer<H>,
    tracer_intersect1: TracerCall<CorayHit>,
    tracer_occluded1: TracerCall<u8>,
}

/// A tracer's make call: handle, stack, its bytes, the tracer.
type MakeTracer<H> =
    unsafe extern "C" fn(*const H, *mut c_void, usize, *mut CorayTracer) -> CorayStatus;

/// An array trace call: handle, rays, answers, count, stack, its bytes, stats.
type ArrayCall<H, O> = unsafe extern "C" fn(
    *const H,
    *const CorayRay,
    *mut O,
    usize,
    *mut c_void,
    usize,
    *mut CorayTraceStats,
) -> CorayStatus;

/// A one-ray trace call: handle, ray, answer, stack, its bytes, stats.
type OneCall<H, O> = unsafe extern "C" fn(
    *const H,
    *const CorayRay,
    *mut O,
    *mut c_void,
    usize,
    *mut CorayTraceStats,
) -> CorayStatus;

/// [`Answers`] of every trace call of a family on `rays`, with a stack of
/// `stack_bytes`.
fn trace_answers<H>(
    family: &str,
    h: &H,
    rays: &[CorayRay],
    stack_bytes: usize,
    rep: &mut Report,
    calls: TraceCalls<H>,
) -> Answers {
    let n = rays.len();
    let mut stack = blocks(stack_bytes);
    let (sp, sb): (*mut c_void, usize) = (stack.as_mut_ptr().cast(), stack_bytes);
    let mut hits = vec![CorayHit::default(); n];
    let mut ones = vec![CorayHit::default(); n];
    let mut occ = vec![0u8; n];
    let mut stats = coray_trace_stats_default();
    let mut statuses = [CorayStatus::Ok; 2];
    let mut one_ok = vec![false; n];
    let what = |call: &str| format!("{family} {call}");
    // SAFETY: every buffer is live and as long as the count passed.
    unsafe {
        statuses[0] = rep.note(
            &what("intersect"),
            (calls.intersect)(h, rays.as_ptr(), hits.as_mut_ptr(), n, sp, sb, &mut stats),
        );
        statuses[1] = rep.note(
            &what("occluded"),
            (calls.occluded)(h, rays.as_ptr(), occ.as_mut_ptr(), n, sp, sb, &mut stats),
        );
        for ((r, one), ok) in rays.iter().zip(ones.iter_mut()).zip(one_ok.iter_mut()) {
            *ok = rep.note(
                &what("intersect1"),
                (calls.intersect1)(h, r, one, sp, sb, &mut stats),
            ) == CorayStatus::Ok;
            let mut o = 0u8;
            rep.note(
                &what("occluded1"),
                (calls.occluded1)(h, r, &mut o, sp, sb, core::ptr::null_mut()),
            );
        }
    }
    let make = |sp, sb, tr| unsafe {
        // SAFETY: the handle is live; the stack and tracer are the helper's.
        (calls.tracer)(h, sp, sb, tr)
    };
    let on_tracer = (calls.tracer_intersect1, calls.tracer_occluded1);
    traced(
        family,
        rays,
        &ones,
        &one_ok,
        stack_bytes,
        rep,
        make,
        on_tracer,
    );
    (hits, ones, occ, statuses, one_ok)
}

fn bvh_trace(h: &CorayBvh, rays: &[CorayRay], stack_bytes: usize, rep: &mut Report) -> Answers {
    let calls = TraceCalls {
        intersect: coray_bvh_intersect,
        occluded: coray_bvh_occluded,
        intersect1: coray_bvh_intersect1,
        occluded1: coray_bvh_occluded1,
        tracer: coray_bvh_tracer,
        tracer_intersect1: coray_bvh_tracer_intersect1,
        tracer_occluded1: coray_bvh_tracer_occluded1,
    };
    trace_answers("bvh", h, rays, stack_bytes, rep, calls)
}

/// Flag bits 4 to 7 that pick the wide hierarchy.
pub const WIDE_FLAGS: u8 = 5;
/// Flag bits 4 to 7 that pick a scene changed under intact arenas.
pub const SCENE_FLAGS: u8 = 6;
/// Flag bits 4 to 7 that pick a damaged saved file.
pub const SAVED_FLAGS: u8 = 7;

/// A family's requirements call.
type RequirementsFn<P> =
    unsafe extern "C" fn(usize, *const P, *mut CorayRequirements) -> CorayStatus;
/// A family's build call.
type BuildFn<P> = unsafe extern "C" fn(
    *const CorayScene,
    *const P,
    *mut c_void,
    usize,
    *mut c_void,
    usize,
    *mut usize,
) -> CorayStatus;

/// An arena built over `sd` by a family's calls, and its requirements;
/// `None` when a call refused (noted).
fn built<P>(
    what: &str,
    sd: &SceneData,
    params: &P,
    (requirements_of, build): (RequirementsFn<P>, BuildFn<P>),
    rep: &mut Report,
) -> Option<(Vec<Block>, CorayRequirements)> {
    let mut req = requirements();
    // SAFETY: params and req are live locals with struct_size set.
    let s = unsafe { requirements_of(sd.prims(), params, &mut req) };
    if rep.note(&format!("{what} requirements"), s) != CorayStatus::Ok {
        return None;
    }
    let mut arena = blocks(req.arena_bytes);
    let mut scratch = blocks(req.scratch_bytes);
    let scene = sd.scene();
    // SAFETY: the scene's arrays outlive the call; arena and scratch are
    // 16-byte aligned buffers of at least the sizes passed.
    let s = unsafe {
        build(
            &scene,
            params,
            arena.as_mut_ptr().cast(),
            req.arena_bytes,
            scratch.as_mut_ptr().cast(),
            req.scratch_bytes,
            core::ptr::null_mut(),
        )
    };
    (rep.note(&format!("{what} build"), s) == CorayStatus::Ok).then_some((arena, req))
}

/// The kd-tree (auto, ropes), wide and TDBS arenas built over `sd`, then
/// opened over `sd` with one to three words changed by the input.
fn scene_changed(sd: &SceneData, rays: &[CorayRay], inp: &mut Input, rep: &mut Report) {
    let mut changed = sd.clone();
    for _ in 0..1 + inp.u8() % 3 {
        let bits = inp.u32();
        let at = inp.u8() as usize;
        let c = &mut changed;
        match inp.u8() % 4 {
            0 => c.vertices[at % sd.vertices.len()] = f32::from_bits(bits),
            // Mostly another vertex, sometimes any index.
            1 => c.indices[at % sd.indices.len()] = if bits >> 31 == 0 { bits % 10 } else { bits },
            2 => c.spheres[at % sd.spheres.len()] = f32::from_bits(bits),
            _ => c.cones[at % sd.cones.len()] = f32::from_bits(bits),
        }
    }
    let scene = changed.scene();
    let kd_params = CorayKdParams {
        omit_ropes: 0,
        ..coray_kdtree_params_default(CORAY_KD_PRESET_AUTO)
    };
    let kd_calls = (
        coray_kdtree_requirements as RequirementsFn<CorayKdParams>,
        coray_kdtree_build as BuildFn<CorayKdParams>,
    );
    if let Some((arena, req)) = built("kd", sd, &kd_params, kd_calls, rep) {
        if let Ok(t) = open_kd(&arena, req.arena_bytes, &scene).map_err(|s| rep.note("kd open", s))
        {
            // SAFETY: a handle just opened; the stack is ignored by kd.
            let v = unsafe {
                coray_kdtree_validate(&t, core::ptr::null_mut(), 0, core::ptr::null_mut())
            };
            if rep.note("kd validate", v) == CorayStatus::Ok {
                assert!(
                    changed.same_bits(sd),
                    "kd: validate accepted a tree over a changed scene"
                );
            }
            kd_trace(&t, rays, CORAY_TRAVERSAL_HIERARCHICAL, rep);
        }
    }
    let wide_params = coray_wide_params_default();
    let wide_calls = (
        coray_wide_requirements as RequirementsFn<CorayWideParams>,
        coray_wide_build as BuildFn<CorayWideParams>,
    );
    if let Some((arena, req)) = built("wide", sd, &wide_params, wide_calls, rep) {
        if let Ok(h) =
            open_wide(&arena, req.arena_bytes, &scene).map_err(|s| rep.note("wide open", s))
        {
            // SAFETY: a handle just opened.
            let v = unsafe { coray_wide_validate(&h, core::ptr::null_mut()) };
            let got = wide_trace(&h, rays, req.stack_bytes, rep);
            if rep.note("wide validate", v) == CorayStatus::Ok {
                let (fresh, freq) = built("wide", &changed, &wide_params, wide_calls, rep)
                    .expect("a scene a tree validates over builds");
                let f = open_wide(&fresh, freq.arena_bytes, &scene).expect("a fresh build opens");
                compare(
                    "wide over a changed scene",
                    &wide_trace(&f, rays, freq.stack_bytes, rep),
                    &got,
                    rays,
                );
            }
        }
    }
    let bvh_params = coray_bvh_params_default(CORAY_BVH_BUILDER_TDBS);
    let bvh_calls = (
        coray_bvh_requirements as RequirementsFn<CorayBvhParams>,
        coray_bvh_build as BuildFn<CorayBvhParams>,
    );
    if let Some((arena, req)) = built("bvh", sd, &bvh_params, bvh_calls, rep) {
        if let Ok(h) =
            open_bvh(&arena, req.arena_bytes, &scene).map_err(|s| rep.note("bvh open", s))
        {
            let v = bvh_validate(&h, req.stack_bytes, rep);
            let got = bvh_trace(&h, rays, req.stack_bytes, rep);
            if v == CorayStatus::Ok {
                let (fresh, freq) = built("bvh", &changed, &bvh_params, bvh_calls, rep)
                    .expect("a scene a tree validates over builds");
                let f = open_bvh(&fresh, freq.arena_bytes, &scene).expect("a fresh build opens");
                compare(
                    "bvh over a changed scene",
                    &bvh_trace(&f, rays, freq.stack_bytes, rep),
                    &got,
                    rays,
                );
            }
        }
    }
}

/// A saved file of a kd-tree over `sd`, damaged as the input says, then
/// opened by `coray_saved_open`.
fn saved_damaged(
    sd: &SceneData,
    rays: &[CorayRay],
    inp: &mut Input,
    how: Damage,
    rep: &mut Report,
) {
    let v: Vec<[f32; 3]> = sd
        .vertices
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect();
    let t: Vec<[u32; 3]> = sd
        .indices
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect();
    let sp: Vec<coray::Sphere> = sd
        .spheres
        .chunks_exact(4)
        .map(|c| coray::Sphere {
            center: [c[0], c[1], c[2]],
            radius: c[3],
        })
        .collect();
    let co: Vec<coray::Cone> = sd
        .cones
        .chunks_exact(8)
        .map(|c| coray::Cone {
            base: [c[0], c[1], c[2]],
            base_radius: c[3],
            apex: [c[4], c[5], c[6]],
            apex_radius: c[7],
        })
        .collect();
    let scene = coray::Scene {
        vertices: &v,
        triangles: &t,
        spheres: &sp,
        cones: &co,
    };
    let preset = (inp.u8() % 2) as CorayKdPreset;
    let omit = (inp.u8() % 3) as u32;
    // A view in every file, so that damage reaches its record too.
    let view = coray::Camera {
        from: coray::Vec3::new(0.0, 1.0, 5.0),
        at: coray::Vec3::ZERO,
        up: coray::Vec3::Y,
        angle_deg: 45.0,
        width: 32,
        height: 24,
    };
    let file = match coray_ffi::saved::kdtree_file(&scene, Some(&view), preset, omit) {
        Ok(f) => f,
        Err(s) => {
            rep.note("saved write", s);
            return;
        }
    };
    let open = |bytes: &[u8], rep: &mut Report| {
        let b = from_bytes(bytes);
        let mut out = coray_saved_default();
        // SAFETY: b is 16-byte aligned and holds bytes.len() bytes.
        let s = unsafe { coray_saved_open(b.as_ptr().cast(), bytes.len(), &mut out) };
        (rep.note("saved open", s) == CorayStatus::Ok).then_some((b, out))
    };
    let (_keep, clean) = open(&file, rep).expect("a clean file opens");
    let want = kd_trace(&clean.tree, rays, CORAY_TRAVERSAL_HIERARCHICAL, rep);
    let mut bytes = file.clone();
    damage(&mut bytes, inp, how);
    if let Some((_keep, got)) = open(&bytes, rep) {
        rep.validated = true;
        assert!(
            bytes == file,
            "coray_saved_open accepted a damaged file ({} bytes, {} written)",
            bytes.len(),
            file.len()
        );
        compare(
            "saved",
            &want,
            &kd_trace(&got.tree, rays, CORAY_TRAVERSAL_HIERARCHICAL, rep),
            rays,
        );
    }
}

fn wide(sd: &SceneData, rays: &[CorayRay], inp: &mut Input, how: Damage, rep: &mut Report) {
    let scene = sd.scene();
    let params = CorayWideParams {
        leaf_size: 1 + inp.u8() as u32 % 4,
        ..coray_wide_params_default()
    };
    let mut req = requirements();
    // SAFETY: live locals with struct_size set.
    let s = unsafe { coray_wide_requirements(sd.prims(), &params, &mut req) };
    if rep.note("wide requirements", s) != CorayStatus::Ok {
        return;
    }
    let mut arena = blocks(req.arena_bytes);
    let mut scratch = blocks(req.scratch_bytes);
    // SAFETY: as for the kd build.
    let s = unsafe {
        coray_wide_build(
            &scene,
            &params,
            arena.as_mut_ptr().cast(),
            req.arena_bytes,
            scratch.as_mut_ptr().cast(),
            req.scratch_bytes,
            core::ptr::null_mut(),
        )
    };
    if rep.note("wide build", s) != CorayStatus::Ok {
        return;
    }
    let clean = open_wide(&arena, req.arena_bytes, &scene).expect("a clean build opens");
    let clean_answers = wide_trace(&clean, rays, req.stack_bytes, rep);
    let mut bytes = as_bytes(&arena);
    bytes.truncate(req.arena_bytes);
    damage(&mut bytes, inp, how);
    let bad = from_bytes(&bytes);
    let Some(h) = open_wide(&bad, bytes.len(), &scene)
        .map_err(|s| rep.note("wide open", s))
        .ok()
    else {
        return;
    };
    let mut shape = coray_shape_default();
    // SAFETY: a handle just opened, a live shape.
    let v = unsafe { coray_wide_validate(&h, &mut shape) };
    rep.validated = rep.note("wide validate", v) == CorayStatus::Ok;
    let got = wide_trace(&h, rays, req.stack_bytes, rep);
    if rep.validated {
        compare("wide", &clean_answers, &got, rays);
    }
}

fn open_wide(arena: &[Block], bytes: usize, scene: &CorayScene) -> Result<CorayWide, CorayStatus> {
    let mut h = CorayWide { opaque: [0; 32] };
    // SAFETY: arena holds at least `bytes` bytes; scene's arrays are live.
    let s = unsafe { coray_wide_open(arena.as_ptr().cast(), bytes, scene, &mut h) };
    if s == CorayStatus::Ok {
        Ok(h)
    } else {
        Err(s)
    }
}

fn wide_trace(h: &CorayWide, rays: &[CorayRay], stack_bytes: usize, rep: &mut Report) -> Answers {
    let calls = TraceCalls {
        intersect: coray_wide_intersect,
        occluded: coray_wide_occluded,
        intersect1: coray_wide_intersect1,
        occluded1: coray_wide_occluded1,
        tracer: coray_wide_tracer,
        tracer_intersect1: coray_wide_tracer_intersect1,
        tracer_occluded1: coray_wide_tracer_occluded1,
    };
    trace_answers("wide", h, rays, stack_bytes, rep, calls)
}

fn proj(
    sd: &SceneData,
    rays: &[CorayRay],
    inp: &mut Input,
    how: Damage,
    which: u8,
    rep: &mut Report,
) {
    let scene = sd.scene();
    let criteria = if which.is_multiple_of(2) {
        CORAY_PROJ_CRITERIA_2D
    } else {
        CORAY_PROJ_CRITERIA_DUMMY
    };
    let builder = BUILDERS[(which / 2) as usize % BUILDERS.len()];
    let params = coray_proj_params_default(criteria, builder);
    // The plane of a point light above the scene, looking down (rays
    // from it are the ones the hierarchy takes).
    let mut light = coray_light_default();
    light.kind = CORAY_LIGHT_POINT;
    light.v = [0.3, 6.0, 0.2];
    let (lo, hi) = ([-5.0f32, -1.0, -5.0], [5.0f32, 4.0, 5.0]);
    let mut planes = [coray_proj_plane_default(); 6];
    let mut count = 0u32;
    // SAFETY: six planes as the call documents, live locals.
    let s = unsafe { coray_proj_light_planes(&light, &lo, &hi, planes.as_mut_ptr(), &mut count) };
    if rep.note("proj light planes", s) != CorayStatus::Ok || count == 0 {
        return;
    }
    let plane = planes[inp.u8() as usize % count as usize];
    let mut req = requirements();
    // SAFETY: live locals with struct_size set.
    let s = unsafe { coray_proj_requirements(sd.prims(), &params, &mut req) };
    if rep.note("proj requirements", s) != CorayStatus::Ok {
        return;
    }
    let mut arena = blocks(req.arena_bytes);
    let mut scratch = blocks(req.scratch_bytes);
    // SAFETY: as for the kd build.
    let s = unsafe {
        coray_proj_build(
            &scene,
            &params,
            &plane,
            arena.as_mut_ptr().cast(),
            req.arena_bytes,
            scratch.as_mut_ptr().cast(),
            req.scratch_bytes,
            core::ptr::null_mut(),
        )
    };
    if rep.note("proj build", s) != CorayStatus::Ok {
        return;
    }
    // Rays from the light: the plane takes these.
    let from_light: Vec<CorayRay> = rays
        .iter()
        .map(|r| {
            let to = [
                r.org[0] + 2.0 * r.dir[0],
                r.org[1] + 2.0 * r.dir[1],
                r.org[2] + 2.0 * r.dir[2],
            ];
            let d = [to[0] - light.v[0], to[1] - light.v[1], to[2] - light.v[2]];
            CorayRay {
                org: light.v,
                tnear: 0.0,
                dir: d,
                tfar: 1.0,
            }
        })
        .collect();
    let clean = open_proj(&arena, req.arena_bytes, &scene).expect("a clean build opens");
    let scheme = inp.u8() as u32 % 4;
    let clean_answers = proj_trace(&clean, scheme, &from_light, req.stack_bytes, rep);
    let mut bytes = as_bytes(&arena);
    bytes.truncate(req.arena_bytes);
    damage(&mut bytes, inp, how);
    let bad = from_bytes(&bytes);
    let Some(h) = open_proj(&bad, bytes.len(), &scene)
        .map_err(|s| rep.note("proj open", s))
        .ok()
    else {
        return;
    };
    let mut stack = blocks(req.stack_bytes);
    let mut shape = coray_shape_default();
    // SAFETY: the stack holds stack_bytes aligned bytes.
    let v =
        unsafe { coray_proj_validate(&h, stack.as_mut_ptr().cast(), req.stack_bytes, &mut shape) };
    rep.validated = rep.note("proj validate", v) == CorayStatus::Ok;
    let got = proj_trace(&h, scheme, &from_light, req.stack_bytes, rep);
    if rep.validated && scheme < 3 {
        compare("proj", &clean_answers, &got, &from_light);
    }
    // Rays the plane does not take, and hostile ones: statuses only.
    proj_trace(&h, scheme, rays, req.stack_bytes, rep);
}

fn open_proj(arena: &[Block], bytes: usize, scene: &CorayScene) -> Result<CorayProj, CorayStatus> {
    let mut h = CorayProj { opaque: [0; 32] };
    // SAFETY: arena holds at least `bytes` bytes; scene's arrays are live.
    let s = unsafe { coray_proj_open(arena.as_ptr().cast(), bytes, scene, &mut h) };
    if s == CorayStatus::Ok {
        Ok(h)
    } else {
        Err(s)
    }
}

fn proj_trace(
    h: &CorayProj,
    scheme: u32,
    rays: &[CorayRay],
    stack_bytes: usize,
    rep: &mut Report,
) -> Answers {
    let n = rays.len();
    let mut stack = blocks(stack_bytes);
    let (sp, sb): (*mut c_void, usize) = (stack.as_mut_ptr().cast(), stack_bytes);
    let mut hits = vec![CorayHit::default(); n];
    let mut ones = vec![CorayHit::default(); n];
    let mut occ = vec![0u8; n];
    let mut stats = coray_trace_stats_default();
    let mut statuses = [CorayStatus::Ok; 2];
    let mut one_ok = vec![false; n];
    // SAFETY: every buffer is live and as long as the count passed.
    unsafe {
        statuses[0] = rep.note(
            "proj intersect",
            coray_proj_intersect(
                h,
                scheme,
                rays.as_ptr(),
                hits.as_mut_ptr(),
                n,
                sp,
                sb,
                &mut stats,
            ),
        );
        statuses[1] = rep.note(
            "proj occluded",
            coray_proj_occluded(
                h,
                scheme,
                rays.as_ptr(),
                occ.as_mut_ptr(),
                n,
                sp,
                sb,
                &mut stats,
            ),
        );
        for ((r, one), ok) in rays.iter().zip(ones.iter_mut()).zip(one_ok.iter_mut()) {
            *ok = rep.note(
                "proj intersect1",
                coray_proj_intersect1(h, scheme, r, one, sp, sb, &mut stats),
            ) == CorayStatus::Ok;
            let mut o = 0u8;
            rep.note(
                "proj occluded1",
                coray_proj_occluded1(h, scheme, r, &mut o, sp, sb, core::ptr::null_mut()),
            );
        }
    }
    let make = |sp, sb, tr| unsafe {
        // SAFETY: the handle is live; the stack and tracer are the helper's.
        coray_proj_tracer(h, scheme, sp, sb, tr)
    };
    let on_tracer = (
        coray_proj_tracer_intersect1 as TracerCall<CorayHit>,
        coray_proj_tracer_occluded1 as TracerCall<u8>,
    );
    traced(
        "proj",
        rays,
        &ones,
        &one_ok,
        stack_bytes,
        rep,
        make,
        on_tracer,
    );
    (hits, ones, occ, statuses, one_ok)
}

/// Sizes of the ABI structs the harness builds by hand, checked so that a
/// changed struct is noticed here first.
const _: () = assert!(size_of::<CorayRay>() == 32 && size_of::<CorayHit>() == 32);
