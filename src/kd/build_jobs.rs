//! The kd build as jobs that the caller's threads share, without std and
//! without allocating.
//!
//! [`build_begin`] builds the top of the tree on the calling thread, down to
//! nodes of about a quarter of the primitives at most (at most
//! [`KD_MAX_JOBS`] of them), and makes each such node's subtree a job: its
//! events move into a region of the event scratch of its own, and it gets its own shares of
//! the node and reference slices, in proportion to its size.
//! Any thread may run any job ([`KdJob::run`], with a flag slice of its
//! own); a job writes only its shares. [`KdBuild::finish`] runs the jobs
//! nobody ran, moves every share down into the depth-first order of the
//! one-pass build, and makes the ropes.
//!
//! Room is shared before anyone knows what a subtree needs, so a job may
//! run out of its share. Each region keeps an untouched copy of its job's
//! events (when the scratch has room for them), and `finish` runs such a
//! job again on the calling thread, in all the room the others left free.
//! Only when that fails too, or there was no room for the copies, does it
//! build the whole tree again in one pass.
//!
//! Every split is decided by the node's own events, so the tree does not
//! depend on how many threads ran the jobs or which: it is byte for byte
//! [`super::build_depth_first`]'s whenever that one is not truncated (and the
//! untruncated tree when jobs fit where depth-first order ran out).
//!
//! ```text
//! let mut b = kd::build_begin(&scene, &params, storage, scratch)?;
//! for job in b.jobs() { job.run(&mut flags_of_this_thread)?; }  // any threads
//! let tree = b.finish()?;
//! ```

use super::build::{check_build, first_pair, one_pass, Builder, KdEvent, Made, Task};
use super::node::SHARED_EMPTY;
use super::node::{KdNode, KD_MAX_DEPTH};
use super::{KdParams, KdScratch, KdStorage, KdTree};
use crate::geom::{Aabb, Scene};
use crate::Error;

/// Most jobs one build makes.
pub const KD_MAX_JOBS: usize = 32;

/// Most nodes a job build's top holds (the root, the shared empty leaf,
/// and the children of its splits, of which empty-space cuts without ropes
/// store one): past it the top makes jobs of what it has.
const TOP_NODES: usize = 4 * KD_MAX_JOBS;

/// A node becomes a job once it has at most this fraction of the scene's
/// primitives (plus [`JOB_SLACK`]) when the build is not told how many
/// threads will run its jobs: a few top levels, so the part of the build
/// that runs on one thread stays small, and jobs enough to balance two to
/// eight threads. Told `t` threads, the fraction is `t` (1 to
/// [`MAX_JOB_FRACTION`]; one thread, one job): two threads then wait on
/// one top split, not three (`coray bench --table build --threads 2`: SPD
/// mount's two-thread build 3.7 -> 3.5 ms, balls 9.1 -> 8.7, tree 10.2 ->
/// 9.8), and many find jobs enough.
const JOB_FRACTION: usize = 4;

/// The largest fraction a thread count sets (its jobs, with the slack's
/// stragglers, stay within [`KD_MAX_JOBS`]).
const MAX_JOB_FRACTION: usize = 16;

/// The slack on [`JOB_FRACTION`], as a fraction of the primitives, for
/// those that straddle the top splits (SPD rings' third level has 2124 of
/// 8402: without it that level would be split on one thread too).
const JOB_SLACK: usize = 16;

/// Below this many primitives a node is a job whatever the fraction.
const MIN_JOB_PRIMS: usize = 64;

/// A range of one of the build's slices.
#[derive(Clone, Copy, Debug, Default)]
struct Share {
    start: usize,
    len: usize,
}

impl Share {
    fn end(&self) -> usize {
        self.start + self.len
    }
}

/// A job's subtree root and its shares of the slices.
#[derive(Clone, Copy, Debug)]
struct JobSpec {
    /// The subtree's root; its events start its event region (`start` 0)
    /// and its node is the first of its node share (`node` 0).
    task: Task,
    /// Its event region: the working events, then (with `copy`) an
    /// untouched copy of the root's events at the region's end.
    events: Share,
    copy: bool,
    nodes: Share,
    refs: Share,
}

impl JobSpec {
    /// Events the job may work in.
    fn working_events(&self) -> usize {
        self.events.len - if self.copy { self.task.total() } else { 0 }
    }
}

/// What a job made in its shares.
#[derive(Clone, Copy, Debug, Default)]
struct JobDone {
    ran: bool,
    /// False when the job ran out of room in its shares.
    fits: bool,
    nodes: usize,
    leaves: usize,
    refs: usize,
    depth: u32,
    /// The frontier at which a job that ran out of its reference share
    /// stopped (0 otherwise): its untruncated subtree needs at least this.
    refs_short: usize,
}

/// A kd build between [`build_begin`] and [`KdBuild::finish`]: the top of
/// the tree is built, its subtrees wait as jobs.
pub struct KdBuild<'s, 'a> {
    scene: Scene<'a>,
    params: KdParams,
    storage: KdStorage<'a>,
    scratch: KdScratch<'s>,
    specs: [JobSpec; KD_MAX_JOBS],
    done: [JobDone; KD_MAX_JOBS],
    job_count: usize,
    /// Nodes the top of the tree holds at the start of `storage.nodes`
    /// (a job's root is marked there as a leaf whose index is the job's).
    top_nodes: usize,
    /// The top ran out of room: `finish` builds in one pass.
    top_truncated: bool,
    /// The top ran out of references: a greedy one pass would too.
    top_refs_short: bool,
    root_voxel: Aabb,
    root_prims: usize,
}

/// Starts a kd build over `scene` in `storage`, with `scratch`: checks the
/// input as [`super::build`] does, then builds the top of the tree on the
/// calling thread. Run the jobs with [`KdBuild::jobs`] on any threads, then
/// [`KdBuild::finish`]. [`build_begin_for_threads`] when the number of
/// threads is known.
pub fn build_begin<'s, 'a>(
    scene: &Scene<'a>,
    params: &KdParams,
    storage: KdStorage<'a>,
    scratch: KdScratch<'s>,
) -> Result<KdBuild<'s, 'a>, Error> {
    build_begin_for_threads(scene, params, storage, scratch, 0)
}

/// [`build_begin`] for jobs that `threads` threads will run (0: not
/// known): the top is split until each job holds about a `threads`-th of
/// the primitives (a sixteenth at least; a quarter when not known), so
/// that few threads wait less on the top's splits and many find jobs
/// enough. One thread gets one job, the whole tree in all the room: no
/// share to outgrow (SPD gears, whose second of two jobs outgrew its share
/// and ran again: 105 -> 78 ms). The tree does not depend on it.
pub fn build_begin_for_threads<'s, 'a>(
    scene: &Scene<'a>,
    params: &KdParams,
    storage: KdStorage<'a>,
    scratch: KdScratch<'s>,
    threads: usize,
) -> Result<KdBuild<'s, 'a>, Error> {
    check_build(scene, params, &storage, &scratch)?;
    let mut b = Builder::new(*scene, params, storage, scratch.events, scratch.prim_flags);
    b.reserve_shared_empty();
    let root = b.root_task();
    let fraction = match threads {
        0 => JOB_FRACTION,
        t => t.min(MAX_JOB_FRACTION),
    };
    let job_prims = (root.prims / fraction + root.prims / JOB_SLACK).max(MIN_JOB_PRIMS);
    let mut specs = [JobSpec {
        task: root,
        events: Share::default(),
        copy: false,
        nodes: Share::default(),
        refs: Share::default(),
    }; KD_MAX_JOBS];
    let mut stack = [root; KD_MAX_DEPTH as usize + 1];
    let (mut pending, mut count) = (0, 0);
    let mut task = root;
    // Depth first, left first, as the one-pass build: jobs are numbered in
    // the order their subtrees take in the finished tree.
    loop {
        b.pending = count + pending;
        let room = count + pending + 2 <= KD_MAX_JOBS && b.node_top + 2 <= TOP_NODES;
        let split = if task.prims > job_prims && room {
            b.try_split(&task)
        } else {
            None
        };
        match split {
            Some((next, later)) => {
                if let Some(right) = later {
                    stack[pending] = right;
                    pending += 1;
                }
                task = next;
            }
            None => {
                // Park the job's events at the top of the free room; the
                // root as the only job (one thread) keeps them in place.
                if task.depth > 0 {
                    let total = task.total();
                    let at = b.event_limit - total;
                    b.events.copy_within(task.start..task.start + total, at);
                    b.event_limit = at;
                    task.start = at;
                }
                // Marks the job's root: a leaf whose first reference is the job.
                b.nodes[task.node as usize] = KdNode::leaf(count as u32, 0);
                specs[count].task = task;
                count += 1;
                if pending == 0 {
                    break;
                }
                pending -= 1;
                task = stack[pending];
            }
        }
    }
    let top_nodes = b.node_top;
    let top_truncated = b.truncated;
    let top_refs_short = b.refs_short > 0;
    let (mut storage, events, prim_flags) = b.into_parts();
    let specs_made = &mut specs[..count];
    place_events(events, specs_made);
    share_storage(&mut storage, params, top_nodes, specs_made);
    Ok(KdBuild {
        scene: *scene,
        params: *params,
        storage,
        scratch: KdScratch { events, prim_flags },
        specs,
        done: [JobDone::default(); KD_MAX_JOBS],
        job_count: count,
        top_nodes,
        top_truncated,
        top_refs_short,
        root_voxel: root.voxel,
        root_prims: root.prims,
    })
}

/// `total` shared in proportion to `weight(spec)`, rounded down (so the
/// shares never sum past it).
struct Shares {
    total: u128,
    sum: u128,
    weight: fn(&JobSpec) -> usize,
}

impl Shares {
    fn new(total: usize, specs: &[JobSpec], weight: fn(&JobSpec) -> usize) -> Shares {
        let sum = specs.iter().map(|s| weight(s) as u128).sum::<u128>();
        Shares {
            total: total as u128,
            sum: sum.max(1),
            weight,
        }
    }

    fn of(&self, spec: &JobSpec) -> usize {
        (self.total * (self.weight)(spec) as u128 / self.sum) as usize
    }
}

/// Gives each job an event region in proportion to its parked events and
/// moves them to its start, with a copy at its end when every region has
/// room for both. Regions are laid from the top down, job 0 highest; the
/// jobs were parked from the top down too, so moving them in reverse
/// order only ever writes below every event still to move. A build of one
/// job (the root, left in place) gets no copy: a rerun would have no more
/// room than the run (`finish` builds in one pass instead), so its events
/// are not moved at all (three copies of every root event fewer: a
/// one-thread SPD mount build 1.0% fewer instructions, callgrind).
fn place_events(events: &mut [KdEvent], specs: &mut [JobSpec]) {
    let room = events.len();
    let parked: usize = specs.iter().map(|s| s.task.total()).sum();
    // Each region is at least its events (room >= parked), at least twice
    // them when room >= 2 parked.
    let copy = specs.len() > 1 && room >= 2 * parked;
    let shares = Shares::new(room, specs, |s| s.task.total());
    let mut end = room;
    for s in specs.iter_mut() {
        let len = shares.of(s);
        s.events = Share {
            start: end - len,
            len,
        };
        s.copy = copy;
        end -= len;
    }
    for s in specs.iter_mut().rev() {
        let (from, n) = (s.task.start, s.task.total());
        if copy {
            let at = s.events.end() - n;
            events.copy_within(from..from + n, at);
            events.copy_within(at..at + n, s.events.start);
        } else if from != s.events.start {
            events.copy_within(from..from + n, s.events.start);
        }
        s.task.start = 0;
    }
}

/// The most nodes a tree may use of these slices: as the one-pass
/// build's [`Builder::new`] counts them (with ropes, a rope record per leaf
/// and a rope index entry per node).
fn node_limit(storage: &KdStorage, params: &KdParams) -> usize {
    let mut limit = storage.nodes.len().min(crate::limits::KD_MAX_NODES);
    if params.ropes {
        limit = limit
            .min((2 * storage.ropes.len()).saturating_sub(1))
            .min(storage.rope_ids.len());
    }
    limit
}

/// What a job's builder is given: the build's parameters without ropes (a
/// job has no rope slots; the ropes are made over the finished tree).
fn job_params(params: &KdParams) -> KdParams {
    KdParams {
        ropes: false,
        ..*params
    }
}

/// Gives each job shares of the nodes (after the top's) and of the
/// references, in order and in proportion to its primitives; its root
/// becomes node 0 of its share.
fn share_storage(
    storage: &mut KdStorage,
    params: &KdParams,
    top_nodes: usize,
    specs: &mut [JobSpec],
) {
    // Every job needs a node, an empty one too.
    let nodes = Shares::new(
        node_limit(storage, params).saturating_sub(top_nodes),
        specs,
        |s| s.task.prims + 1,
    );
    let refs = Shares::new(storage.refs.len(), specs, |s| s.task.prims);
    let (mut n, mut r) = (top_nodes, 0);
    for s in specs.iter_mut() {
        s.nodes = Share {
            start: n,
            len: nodes.of(s),
        };
        s.refs = Share {
            start: r,
            len: refs.of(s),
        };
        n = s.nodes.end();
        r = s.refs.end();
        s.task.node = 0;
        s.task.ref_budget = s.refs.len;
    }
}

impl<'s, 'a> KdBuild<'s, 'a> {
    /// How many jobs wait (0 when the top already ran out of room).
    pub fn job_count(&self) -> usize {
        if self.top_truncated {
            0
        } else {
            self.job_count
        }
    }

    /// The jobs, each with its own shares of the slices, to hand to any
    /// threads (a job is `Send`). Jobs not run when `finish` is called run
    /// there.
    pub fn jobs(&mut self) -> KdJobs<'_> {
        let count = self.job_count();
        split_jobs(
            self.scene,
            &self.params,
            self.root_voxel,
            &self.specs[..count],
            &mut self.done[..count],
            &mut self.storage,
            &mut *self.scratch.events,
            self.top_nodes,
        )
    }

    /// Runs the jobs nobody ran, on this thread, again those that ran out
    /// of their shares, lays the subtrees out in depth-first order and
    /// makes the ropes. Builds in one pass instead when the top ran out of
    /// room, or a job does again.
    pub fn finish(self) -> Result<KdTree<'a>, Error> {
        Ok(self.finish_with_report()?.0)
    }

    /// [`Self::finish`], and how the tree was made.
    pub fn finish_with_report(self) -> Result<(KdTree<'a>, KdJobReport), Error> {
        let KdBuild {
            scene,
            params,
            mut storage,
            scratch,
            mut specs,
            mut done,
            job_count,
            top_nodes,
            top_truncated,
            top_refs_short,
            root_voxel,
            root_prims,
        } = self;
        let KdScratch { events, prim_flags } = scratch;
        let mut report = KdJobReport {
            jobs: job_count,
            reruns: 0,
            one_pass: true,
            fair_pass_only: top_truncated && top_refs_short,
        };
        if top_truncated {
            let scratch = KdScratch { events, prim_flags };
            let greedy_first = !report.fair_pass_only;
            let tree = one_pass(&scene, &params, storage, scratch, greedy_first);
            return Ok((tree?, report));
        }
        let (specs, done) = (&mut specs[..job_count], &mut done[..job_count]);
        let jobs = split_jobs(
            scene,
            &params,
            root_voxel,
            specs,
            done,
            &mut storage,
            &mut *events,
            top_nodes,
        );
        for job in jobs {
            if !job.done.ran {
                job.run(&mut *prim_flags)?;
            }
        }
        // When most jobs outgrew their shares the tree is unlikely to fit
        // at all (SPD gears): build in one pass rather than run them again
        // one by one first.
        let failed = done.iter().filter(|d| !d.fits).count();
        report.reruns = failed;
        let reruns = if 2 * failed > job_count {
            None
        } else {
            Reruns::park(events, specs, done)
        };
        let made = reruns.and_then(|reruns| {
            let mut layout = Layout {
                scene,
                params,
                storage: &mut storage,
                specs,
                done,
                reruns,
                prim_flags: &mut *prim_flags,
                root_voxel,
            };
            layout.assemble(top_nodes, root_prims)
        });
        match made {
            Some(made) => {
                report.one_pass = false;
                Ok((made.into_tree(&scene, storage, &params), report))
            }
            None => {
                report.fair_pass_only = greedy_runs_out(specs, done, storage.refs.len());
                let scratch = KdScratch { events, prim_flags };
                let greedy_first = !report.fair_pass_only;
                Ok((
                    one_pass(&scene, &params, storage, scratch, greedy_first)?,
                    report,
                ))
            }
        }
    }
}

/// How [`KdBuild::finish_with_report`] made the tree.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct KdJobReport {
    /// Jobs the top of the tree was cut into.
    pub jobs: usize,
    /// Jobs that outgrew their shares (run again in `finish` unless
    /// `one_pass`).
    pub reruns: usize,
    /// The tree was built again in one pass ([`super::build_depth_first`]): the
    /// top or a job ran out of room even in its second run, or most jobs
    /// outgrew their shares.
    pub one_pass: bool,
    /// That pass shared the room fairly from the start, without the
    /// greedy pass [`super::build_depth_first`] tries first: the top or the jobs
    /// showed that the greedy pass would run out of references (the same
    /// tree, one pass less).
    pub fair_pass_only: bool,
}

/// Whether a greedy one-pass build must run out of references, judged by
/// what the jobs met. The subtrees it would build are the jobs' untruncated
/// ones, and each needs at least: what a job that fitted used, the frontier
/// at which one ran out of its share, its own primitives otherwise (the
/// frontier never shrinks). Their sum past the room cannot fit.
fn greedy_runs_out(specs: &[JobSpec], done: &[JobDone], refs: usize) -> bool {
    let need: usize = specs
        .iter()
        .zip(done)
        .map(|(s, d)| match (d.fits, d.refs_short) {
            (true, _) => d.refs,
            (false, 0) => s.task.prims,
            (false, short) => short,
        })
        .sum();
    need > refs
}

/// The event scratch once the jobs ran: free below `limit`, the copies of
/// the jobs to run again parked above it.
struct Reruns<'e> {
    events: &'e mut [KdEvent],
    limit: usize,
    /// Where each job's parked copy starts (for the jobs that failed).
    copy_at: [usize; KD_MAX_JOBS],
}

impl<'e> Reruns<'e> {
    /// Moves the copies of the jobs that ran out of room to the top of the
    /// scratch, highest region first (each moves up, past nothing still
    /// needed). None when a job failed and there are no copies.
    fn park(events: &'e mut [KdEvent], specs: &[JobSpec], done: &[JobDone]) -> Option<Reruns<'e>> {
        let mut r = Reruns {
            limit: events.len(),
            events,
            copy_at: [0; KD_MAX_JOBS],
        };
        for (k, (s, d)) in specs.iter().zip(done).enumerate() {
            if d.fits {
                continue;
            }
            if !s.copy {
                return None;
            }
            let n = s.task.total();
            let from = s.events.end() - n;
            r.limit -= n;
            r.events.copy_within(from..from + n, r.limit);
            r.copy_at[k] = r.limit;
        }
        Some(r)
    }
}

/// What [`Layout::assemble`] works on: the storage with the jobs' shares,
/// and what it needs to run a failed job again.
struct Layout<'l, 'a, 'e> {
    scene: Scene<'a>,
    params: KdParams,
    storage: &'l mut KdStorage<'a>,
    specs: &'l mut [JobSpec],
    done: &'l mut [JobDone],
    reruns: Reruns<'e>,
    prim_flags: &'l mut [u8],
    /// The scene's box: the tree's bounds, and what prices references (as
    /// the jobs did).
    root_voxel: Aabb,
}

/// Where the finished tree stands: the next node pair and reference, and
/// the leaves so far.
#[derive(Clone, Copy)]
struct Tops {
    node: usize,
    leaf: usize,
    re: usize,
}

impl Layout<'_, '_, '_> {
    /// Moves the top's nodes and every job's shares into the one-pass
    /// build's layout: node pairs, leaves and references in depth-first
    /// preorder, left first. Everything moves down (a share starts at or
    /// after where its contents end up), so each copy runs forward in
    /// place. None when a job fails again. `prims` are the root's.
    fn assemble(&mut self, top_nodes: usize, prims: usize) -> Option<Made> {
        let mut top = [KdNode::default(); TOP_NODES];
        top[..top_nodes].copy_from_slice(&self.storage.nodes[..top_nodes]);
        // (top node, its slot in the finished tree)
        let mut stack = [(0usize, 0usize); TOP_NODES];
        let mut sp = 1;
        let first = first_pair(&self.params);
        if first > SHARED_EMPTY as usize {
            self.storage.nodes[SHARED_EMPTY as usize] = KdNode::EMPTY;
        }
        let mut at = Tops {
            node: first,
            leaf: 0,
            re: 0,
        };
        let mut depth = 0;
        while sp > 0 {
            sp -= 1;
            let (t, slot) = stack[sp];
            let n = top[t];
            if !n.is_leaf() {
                let c = at.node;
                at.node += n.stored_children() as usize;
                self.storage.nodes[slot] = n.with_first_stored(c as u32);
                let l = n.first_stored() as usize;
                if n.elided() == 0 {
                    stack[sp] = (l + 1, c + 1);
                    sp += 1;
                }
                stack[sp] = (l, c);
                sp += 1;
                continue;
            }
            let j = n.first_ref() as usize;
            if !self.done[j].fits {
                self.rerun(j, at)?;
            }
            self.place(j, slot, at);
            let d = self.done[j];
            at.node += d.nodes - 1;
            at.leaf += d.leaves;
            at.re += d.refs;
            depth = depth.max(d.depth);
        }
        Some(Made {
            node_count: at.node,
            leaf_count: at.leaf,
            ref_count: at.re,
            depth,
            truncated: false,
            bounds: self.root_voxel,
            prims,
        })
    }

    /// Moves job `j`'s subtree to its place: its root to `slot`, its other
    /// nodes and its references to `at`, renumbered.
    fn place(&mut self, j: usize, slot: usize, at: Tops) {
        let KdStorage { nodes, refs, .. } = &mut *self.storage;
        let (s, d) = (&self.specs[j], &self.done[j]);
        let (nb, rb) = (at.node as u32, at.re as u32);
        let moved = |r: KdNode| {
            if r.is_leaf() {
                KdNode::leaf(r.first_ref() + rb, r.ref_count())
            } else {
                r.with_first_stored(r.first_stored() - 1 + nb)
            }
        };
        nodes[slot] = moved(nodes[s.nodes.start]);
        for i in 1..d.nodes {
            nodes[at.node + i - 1] = moved(nodes[s.nodes.start + i]);
        }
        refs.copy_within(s.refs.start..s.refs.start + d.refs, at.re);
    }

    /// Runs job `j` again from its copy, in all the room between `at` and
    /// the jobs after it (moved to the slices' ends first). None when it
    /// runs out of room again.
    fn rerun(&mut self, j: usize, at: Tops) -> Option<()> {
        let mut end = Tops {
            node: node_limit(self.storage, &self.params),
            leaf: 0,
            re: self.storage.refs.len(),
        };
        // Later jobs that made their subtrees, to the ends, last first.
        for k in (j + 1..self.specs.len()).rev() {
            let d = self.done[k];
            if !d.fits {
                continue;
            }
            let KdStorage { nodes, refs, .. } = &mut *self.storage;
            let s = &mut self.specs[k];
            end.node -= d.nodes;
            end.re -= d.refs;
            nodes.copy_within(s.nodes.start..s.nodes.start + d.nodes, end.node);
            refs.copy_within(s.refs.start..s.refs.start + d.refs, end.re);
            s.nodes.start = end.node;
            s.refs.start = end.re;
        }
        if at.node >= end.node || at.re > end.re {
            return None;
        }
        let s = &mut self.specs[j];
        let n = s.task.total();
        let (work, parked) = self.reruns.events.split_at_mut(self.reruns.limit);
        let from = self.reruns.copy_at[j] - self.reruns.limit;
        work.get_mut(..n)?.copy_from_slice(&parked[from..from + n]);
        let KdStorage { nodes, refs, .. } = &mut *self.storage;
        let storage = KdStorage {
            nodes: &mut nodes[at.node..end.node],
            ropes: &mut [],
            rope_ids: &mut [],
            refs: &mut refs[at.re..end.re],
        };
        if storage.refs.len() < s.task.prims {
            return None;
        }
        let mut b = Builder::new(
            self.scene,
            &job_params(&self.params),
            storage,
            work,
            &mut *self.prim_flags,
        );
        b.as_job(s.task.prims, &self.root_voxel);
        b.run(s.task);
        if b.truncated {
            return None;
        }
        self.done[j] = JobDone {
            ran: true,
            fits: true,
            nodes: b.node_top,
            leaves: b.leaf_top,
            refs: b.ref_top,
            depth: b.depth,
            refs_short: 0,
        };
        s.nodes.start = at.node;
        s.refs.start = at.re;
        Some(())
    }
}

/// One job's subtree: its root, its shares of the slices, where it reports.
pub struct KdJob<'j> {
    scene: Scene<'j>,
    params: KdParams,
    root_voxel: Aabb,
    task: Task,
    nodes: &'j mut [KdNode],
    refs: &'j mut [u32],
    events: &'j mut [KdEvent],
    done: &'j mut JobDone,
}

impl KdJob<'_> {
    /// The job's size in split events: run the largest first.
    pub fn weight(&self) -> usize {
        self.task.total()
    }

    /// Builds the job's subtree in its shares. `prim_flags` is this
    /// thread's: at least one byte per primitive of the scene, its contents
    /// anything (two threads never share one at the same time).
    pub fn run(self, prim_flags: &mut [u8]) -> Result<(), Error> {
        let n = self.scene.prim_count();
        if prim_flags.len() < n {
            return Err(Error::SliceTooSmall {
                slice: "prim_flags",
                needed: n,
                got: prim_flags.len(),
            });
        }
        let task = self.task;
        *self.done = JobDone {
            ran: true,
            ..JobDone::default()
        };
        if self.nodes.is_empty() || self.refs.len() < task.prims {
            return Ok(());
        }
        let storage = KdStorage {
            nodes: self.nodes,
            ropes: &mut [],
            rope_ids: &mut [],
            refs: self.refs,
        };
        let params = job_params(&self.params);
        let mut b = Builder::new(self.scene, &params, storage, self.events, prim_flags);
        b.as_job(task.prims, &self.root_voxel);
        b.run(task);
        *self.done = JobDone {
            ran: true,
            fits: !b.truncated,
            nodes: b.node_top,
            leaves: b.leaf_top,
            refs: b.ref_top,
            depth: b.depth,
            refs_short: b.refs_short,
        };
        Ok(())
    }
}

/// The jobs of a build, in order, each split off the slices' fronts (events:
/// their backs).
pub struct KdJobs<'j> {
    scene: Scene<'j>,
    params: KdParams,
    root_voxel: Aabb,
    specs: &'j [JobSpec],
    done: core::slice::IterMut<'j, JobDone>,
    nodes: &'j mut [KdNode],
    refs: &'j mut [u32],
    events: &'j mut [KdEvent],
}

#[allow(clippy::too_many_arguments)]
fn split_jobs<'j>(
    scene: Scene<'j>,
    params: &KdParams,
    root_voxel: Aabb,
    specs: &'j [JobSpec],
    done: &'j mut [JobDone],
    storage: &'j mut KdStorage,
    events: &'j mut [KdEvent],
    top_nodes: usize,
) -> KdJobs<'j> {
    KdJobs {
        scene,
        params: *params,
        root_voxel,
        specs,
        done: done.iter_mut(),
        nodes: &mut storage.nodes[top_nodes..],
        refs: &mut storage.refs[..],
        events,
    }
}

fn take_front<'j, T>(s: &mut &'j mut [T], n: usize) -> &'j mut [T] {
    let (a, b) = core::mem::take(s).split_at_mut(n);
    *s = b;
    a
}

fn take_back<'j, T>(s: &mut &'j mut [T], n: usize) -> &'j mut [T] {
    let rest = core::mem::take(s);
    let at = rest.len() - n;
    let (a, b) = rest.split_at_mut(at);
    *s = a;
    b
}

impl<'j> Iterator for KdJobs<'j> {
    type Item = KdJob<'j>;

    fn next(&mut self) -> Option<KdJob<'j>> {
        let (s, rest) = self.specs.split_first()?;
        self.specs = rest;
        let region = take_back(&mut self.events, s.events.len);
        Some(KdJob {
            scene: self.scene,
            params: self.params,
            root_voxel: self.root_voxel,
            task: s.task,
            nodes: take_front(&mut self.nodes, s.nodes.len),
            refs: take_front(&mut self.refs, s.refs.len),
            events: &mut region[..s.working_events()],
            done: self.done.next()?,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The greedy pass is skipped only when what the jobs need at least
    /// (a fitted job's references, a short job's frontier, else its
    /// primitives) exceeds the room; at the room exactly it may fit.
    #[test]
    fn greedy_runs_out_when_the_jobs_need_more_than_the_room() {
        let spec = |prims: usize| JobSpec {
            task: Task {
                node: 0,
                depth: 0,
                voxel: Aabb::EMPTY,
                start: 0,
                counts: [0; 3],
                prims,
                ref_budget: 0,
            },
            events: Share::default(),
            copy: false,
            nodes: Share::default(),
            refs: Share::default(),
        };
        let fitted = |refs: usize| JobDone {
            ran: true,
            fits: true,
            refs,
            ..JobDone::default()
        };
        let short = |refs_short: usize| JobDone {
            ran: true,
            refs_short,
            ..JobDone::default()
        };
        let specs = [spec(10), spec(20), spec(30)];
        // 15 used + frontier 40 + 30 primitives (out of nodes or events).
        let done = [fitted(15), short(40), short(0)];
        assert!(greedy_runs_out(&specs, &done, 84));
        assert!(!greedy_runs_out(&specs, &done, 85));
        // Every job fitted: what they used.
        let done = [fitted(15), fitted(25), fitted(35)];
        assert!(greedy_runs_out(&specs, &done, 74));
        assert!(!greedy_runs_out(&specs, &done, 75));
    }
}
