//! `coray_kdtree_build_jobs`: the kd build's jobs on the caller's threads.
//!
//! coray has no threads. The build hands its jobs to the caller's
//! `run_jobs` callback, which runs them (by `run_job`) on whatever threads
//! it has and returns when they are done; coray then finishes the tree.
//! The tree is byte for byte the one `coray_kdtree_build` makes.

use crate::carve::{self, Regions};
use crate::{guard, CorayStatus};
use coray::kd::{KdJob, KdJobs, KD_MAX_JOBS};
use core::cell::UnsafeCell;
use core::ffi::c_void;
use core::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// Stack below a `run_job` call that its flags may not use: where the
/// call and its job put their frames.
const STACK_BELOW_A_JOB: usize = 256 << 10;

/// Stack above the build's entry that job flags may not use: the entry
/// call's own frame lies there, of a size the code cannot read.
const STACK_ABOVE_THE_ENTRY: usize = 16 << 10;

/// Runs job `job` (0 to `job_count` - 1) of the build that called
/// `run_jobs`, with `flags`: at least `flags_bytes` writable bytes that
/// only this call uses (one buffer per thread, reused from job to job). A
/// job runs at most once: a second call for it fails with
/// `CORAY_STATUS_INVALID_PARAMETER`, as do flags that overlap the scene,
/// the arena, the scratch, `jobs` itself, another running job's flags, or
/// coray's own stack (the 256 KiB below this call, and the build's frames
/// up to 16 KiB above its entry). Call it only while `run_jobs` runs
/// (`jobs` is gone afterwards). A job whose call failed, or that no call
/// ran, runs on the building thread once `run_jobs` returns.
pub type CorayKdRunJob = unsafe extern "C" fn(
    jobs: *mut c_void,
    job: usize,
    flags: *mut u8,
    flags_bytes: usize,
) -> CorayStatus;

/// The caller's job runner for `coray_kdtree_build_jobs`: runs
/// `run_job(jobs, i, flags, flags_bytes)` for each `i` below `job_count`,
/// on any threads, any number at once (each with its own flags), and
/// returns only when every call it made has returned. `ctx` is the
/// caller's, passed through. NULL: the build runs every job itself.
pub type CorayKdRunJobs = Option<
    unsafe extern "C" fn(
        ctx: *mut c_void,
        job_count: usize,
        flags_bytes: usize,
        run_job: CorayKdRunJob,
        jobs: *mut c_void,
    ),
>;

/// The jobs as the callback's calls see them: each slot taken by the one
/// call that claims it first.
struct JobTable<'j> {
    slots: [UnsafeCell<Option<KdJob<'j>>>; KD_MAX_JOBS],
    claimed: [AtomicBool; KD_MAX_JOBS],
    count: usize,
    flags_bytes: usize,
    /// The build's scene, arena and scratch: no job's flags may overlap
    /// them.
    regions: Regions,
    /// The building thread's stack from this table to above the build's
    /// entry: coray's frames, which no job's flags may overlap.
    frames: (usize, usize),
    /// Per job, the flags it runs with (start, end; 0, 0 when it does not
    /// run): no two running jobs may share bytes.
    running: [(AtomicUsize, AtomicUsize); KD_MAX_JOBS],
}

/// Whether the spans `[a.0, a.1)` and `[b.0, b.1)` share a byte.
fn overlap(a: (usize, usize), b: (usize, usize)) -> bool {
    a.0 < b.1 && b.0 < a.1
}

/// Hands `jobs` to `run_jobs` and returns when it does. `regions` holds
/// the call's scene, arena and scratch; `entry` is the address of a local
/// of the build's entry point (the top of coray's frames, but for that
/// frame's own size). Never inlined: the job table's stack (about 7 KiB)
/// is spent only by builds that hand out their jobs.
#[inline(never)]
pub(crate) fn run_with(
    jobs: KdJobs<'_>,
    run_jobs: unsafe extern "C" fn(*mut c_void, usize, usize, CorayKdRunJob, *mut c_void),
    ctx: *mut c_void,
    prim_count: usize,
    regions: Regions,
    entry: usize,
) {
    let mut table = JobTable {
        slots: core::array::from_fn(|_| UnsafeCell::new(None)),
        claimed: core::array::from_fn(|_| AtomicBool::new(false)),
        count: 0,
        flags_bytes: prim_count,
        regions,
        frames: (0, 0),
        running: core::array::from_fn(|_| (AtomicUsize::new(0), AtomicUsize::new(0))),
    };
    // The stack grows down: from the table up to past the entry's frame.
    let at = core::ptr::addr_of!(table) as usize;
    table.frames = (
        at.min(entry),
        entry.max(at + core::mem::size_of::<JobTable>()) + STACK_ABOVE_THE_ENTRY,
    );
    for (slot, job) in table.slots.iter_mut().zip(jobs) {
        *slot.get_mut() = Some(job);
        table.count += 1;
    }
    let ptr = (&table as *const JobTable).cast_mut().cast::<c_void>();
    // SAFETY: `run_jobs` is the caller's callback, called as its contract
    // says; `table` lives until it returns, and by that contract no call
    // of `run_job` outlives it. Calls reach the slots only through
    // `run_job`, which claims each slot once (atomically) before touching
    // it, so no two threads ever use one slot.
    unsafe { run_jobs(ctx, table.count, table.flags_bytes, run_job, ptr) };
    // Jobs left in their slots are dropped here unrun: `finish` runs them.
}

/// The `run_job` coray passes to `run_jobs`.
///
/// # Safety
/// `jobs` is the pointer `run_jobs` received, during that call; `flags` is
/// NULL or writable for `flags_bytes` bytes no one else uses meanwhile.
unsafe extern "C" fn run_job(
    jobs: *mut c_void,
    job: usize,
    flags: *mut u8,
    flags_bytes: usize,
) -> CorayStatus {
    guard(|| {
        if jobs.is_null() {
            return Err(CorayStatus::NullPointer);
        }
        // SAFETY: by the contract, `jobs` is run_with's live table; only
        // shared references to it are made, its mutable parts are behind
        // the claim below.
        let table = unsafe { &*jobs.cast_const().cast::<JobTable>() };
        if job >= table.count || flags_bytes < table.flags_bytes {
            return Err(CorayStatus::InvalidParameter);
        }
        let mut regions = table.regions;
        regions.add(flags, flags_bytes, true).check()?;
        // Flags in coray's own memory: the job table, the build's frames,
        // the stack this call and its job are about to use.
        let span = (flags as usize, (flags as usize).saturating_add(flags_bytes));
        let here = 0u8;
        let sp = core::hint::black_box(&here) as *const u8 as usize;
        let table_span = (
            jobs as usize,
            jobs as usize + core::mem::size_of::<JobTable>(),
        );
        let below = (sp.saturating_sub(STACK_BELOW_A_JOB), sp.saturating_add(1));
        if overlap(span, table_span) || overlap(span, table.frames) || overlap(span, below) {
            return Err(CorayStatus::InvalidParameter);
        }
        // SAFETY: `flags` is writable for `flags_bytes` and this call's
        // alone (the contract); checked above not to overlap the scene,
        // the arena, the scratch or coray's own memory.
        let flags = unsafe { carve::output(flags, flags_bytes)? };
        if table.claimed[job].swap(true, Ordering::AcqRel) {
            return Err(CorayStatus::InvalidParameter);
        }
        // Published before the others are read: of two calls whose flags
        // overlap, at least one sees the other's (sequential consistency),
        // and refuses; its job then runs on the building thread.
        let (start, end) = &table.running[job];
        start.store(span.0, Ordering::SeqCst);
        end.store(span.1, Ordering::SeqCst);
        let shared = (0..table.count).any(|other| {
            let (s, e) = &table.running[other];
            other != job && overlap(span, (s.load(Ordering::SeqCst), e.load(Ordering::SeqCst)))
        });
        let done = if shared {
            Err(CorayStatus::InvalidParameter)
        } else {
            // SAFETY: this call claimed slot `job` above; no other call
            // will, and run_with touches the slots again only after
            // run_jobs returned, when every call has returned.
            let slot = unsafe { &mut *table.slots[job].get() };
            let run = slot.take().ok_or(CorayStatus::InternalError)?;
            run.run(flags).map_err(CorayStatus::from)
        };
        end.store(0, Ordering::SeqCst);
        start.store(0, Ordering::SeqCst);
        done
    })
}
