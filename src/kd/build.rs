//! SAH kd-tree build in O(N log N) from sorted split events (Wald and
//! Havran 2006), with split clipping, entirely inside caller slices.
//!
//! Events of a node sit contiguously in the scratch slice, grouped by axis and
//! sorted by (position, kind). A split classifies primitives from the split
//! axis' events, clips the straddling ones into both children, sorts only
//! those new events and merges them with the filtered old ones: no node
//! sorts its whole list again. Depth-first order keeps the live events to the
//! pending right children plus one split's temporaries.

use super::node::{
    KdInfo, KdNode, KD_FLAG_COMPACT, KD_FLAG_ROPES, KD_FLAG_TRUNCATED, KD_MAGIC, KD_MAX_DEPTH,
    KD_VERSION, SHARED_EMPTY,
};
use super::{min_requirements, ropes, KdParams, KdScratch, KdStorage, KdTree};
use crate::geom::{Aabb, ClipBox, Scene};
use crate::limits::KD_MAX_NODES;
use crate::Error;

/// One split event: a primitive's clipped box starts, ends or lies flat at
/// some position on some axis, stored as its sweep key: the position's
/// ordered bits (high 32 bits), the kind (bits 30 and 31: end < planar <
/// start), the primitive (low 30 bits). Events sort by this one integer
/// (position, then kind, then primitive, which makes the build
/// deterministic), and a sweep finds the events of one position and kind
/// by one compare of `key >> 30`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord)]
#[repr(C)]
pub struct KdEvent {
    key: u64,
}

const END: u32 = 0;
const PLANAR: u32 = 1;
const START: u32 = 2;

/// What an event of each kind adds to a sweep's count of a position's
/// ends (low 32 bits) and starts (high 32 bits): one load and one add.
const ENDS_STARTS: [u64; 4] = {
    let mut c = [0u64; 4];
    c[END as usize] = 1;
    c[START as usize] = 1 << 32;
    c
};

const BOTH: u8 = 0;
const LEFT: u8 = 1;
const RIGHT: u8 = 2;
// `merge` steps its cursors by these bits.
const _: () = assert!(BOTH == 0 && LEFT == 1 && RIGHT == 2);

impl KdEvent {
    /// Primitives fit in 30 bits (the scene limit is below).
    fn new(pos: f32, prim: usize, kind: u32) -> KdEvent {
        // `+ 0.0` turns -0.0 into 0.0, so equal positions have equal bits.
        let bits = crate::sort_key::ordered_bits(pos + 0.0);
        KdEvent {
            key: (bits as u64) << 32 | (kind as u64) << 30 | (prim as u64 & PRIM_MASK),
        }
    }
    /// The position's ordered bits: they order as the positions compare.
    #[inline(always)]
    fn pos_bits(&self) -> u32 {
        (self.key >> 32) as u32
    }
    #[inline(always)]
    fn pos(&self) -> f32 {
        crate::sort_key::from_ordered_bits(self.pos_bits())
    }
    #[inline(always)]
    fn prim(&self) -> usize {
        (self.key & PRIM_MASK) as usize
    }
    #[inline(always)]
    fn kind(&self) -> u32 {
        (self.key >> 30) as u32 & 3
    }
}

const PRIM_MASK: u64 = (1 << 30) - 1;

/// A node waiting to be built: its events are `events[start..]`, `counts[a]`
/// of them on axis `a`, in axis order.
#[derive(Clone, Copy, Debug)]
pub(super) struct Task {
    pub(super) node: u32,
    pub(super) depth: u32,
    pub(super) voxel: Aabb,
    pub(super) start: usize,
    pub(super) counts: [usize; 3],
    pub(super) prims: usize,
    /// References this subtree may use. The root has the whole `refs`
    /// slice; a split gives each child its own references plus a share of
    /// the spare in proportion to them, so budgets never sum past the
    /// slice and room runs out evenly across the tree, not in whichever
    /// subtree depth-first order reaches first.
    pub(super) ref_budget: usize,
}

impl Task {
    pub(super) fn total(&self) -> usize {
        self.counts[0] + self.counts[1] + self.counts[2]
    }
    fn axis_range(&self, axis: usize) -> (usize, usize) {
        let s = self.start + self.counts[..axis].iter().sum::<usize>();
        (s, s + self.counts[axis])
    }
}

/// Thickness of the cell that cuts planar primitives off a node's face,
/// relative to the node's extent or coordinates (see `find_split`).
use crate::tolerance::FACE_CELL;

/// What every candidate plane of one node's sweep shares.
struct SweepNode {
    voxel: Aabb,
    /// The voxel's extent, in f64 for the areas.
    extent: [f64; 3],
    inv_area: f64,
    prims: usize,
    /// What one reference more costs a split of this node, in the node's
    /// SAH terms (0 for the plain SAH).
    ref_cost: f32,
}

/// The best plane of a node's sweep.
#[derive(Clone, Copy, Debug)]
struct Split {
    axis: usize,
    pos: f32,
    planar_left: bool,
    cost: f32,
    /// Primitives on each side as the cost counted them: 0 when that side
    /// is empty space (no primitive classifies into it).
    left: usize,
    right: usize,
}

/// Appends the events of box `b` on `axis` at `events[*at..]`.
fn push_events(events: &mut [KdEvent], at: &mut usize, prim: usize, b: &Aabb, axis: usize) {
    if b.min[axis] == b.max[axis] {
        events[*at] = KdEvent::new(b.min[axis], prim, PLANAR);
        *at += 1;
    } else {
        events[*at] = KdEvent::new(b.min[axis], prim, START);
        events[*at + 1] = KdEvent::new(b.max[axis], prim, END);
        *at += 2;
    }
}

/// Regions shorter than this are left to `sort_unstable`: the radix
/// sort's fixed cost (its counts, a pass per digit) pays from about here.
const RADIX_MIN_EVENTS: usize = 1024;

/// Counters the root's radix sort needs: one per value of its widest
/// digit.
const RADIX_COUNTS: usize = 4096;

/// Sorts `events`, which hold each primitive's events in increasing
/// primitive order (as the root's bounds pass makes them), by their keys,
/// with `buf` (as long) as scratch: a stable LSD radix sort in three
/// passes (11, 11 and 12 bits) on the key's position and kind only (bits
/// 30 to 63), whose ties keep the input's primitive order, the key's low
/// bits. The result is `sort_unstable`'s: no two events share a key. A
/// pass whose digit is the same for every event (the sign and exponent
/// bits of a scene within one octave) is skipped. Its counters are the
/// keys of `counts` ([`RADIX_COUNTS`] of them, the build's scratch): on
/// the stack they took 16 KiB, which put the kd build's stack past 32 KiB
/// (a microcontroller's is small).
fn sort_in_prim_order(events: &mut [KdEvent], buf: &mut [KdEvent], counts: &mut [KdEvent]) {
    // Bits 30..41, 41..52, 52..64 (the last digit 12 bits).
    const DIGITS: [(u32, usize); 3] = [(30, 2048), (41, 2048), (52, RADIX_COUNTS)];
    let n = events.len() as u64;
    // Passes alternate between the two slices; `in_buf` says where the
    // keys are.
    let mut in_buf = false;
    for (shift, size) in DIGITS {
        let digit = |e: &KdEvent| (e.key >> shift) as usize & (size - 1);
        let (from, to): (&[KdEvent], &mut [KdEvent]) = if in_buf {
            (&*buf, &mut *events)
        } else {
            (&*events, &mut *buf)
        };
        let start = &mut counts[..size];
        start.fill(KdEvent { key: 0 });
        for e in from {
            start[digit(e)].key += 1;
        }
        if start.iter().any(|k| k.key == n) {
            continue;
        }
        let mut sum = 0;
        for s in start.iter_mut() {
            let k = s.key;
            s.key = sum;
            sum += k;
        }
        for e in from {
            let d = digit(e);
            to[start[d].key as usize] = *e;
            start[d].key += 1;
        }
        in_buf = !in_buf;
    }
    if in_buf {
        events.copy_from_slice(buf);
    }
}

fn area64(b: &Aabb) -> f64 {
    area_of_extent((b.max - b.min).as_dvec3().to_array())
}

/// Surface area of a box of extent `e`, in f64 (in this one order of
/// operations: the sweep's candidates must round as the node's own area).
#[inline]
fn area_of_extent(e: [f64; 3]) -> f64 {
    2.0 * (e[0] * e[1] + e[1] * e[2] + e[2] * e[0])
}

/// Area of the node's box with its extent on `AXIS` replaced by `along`
/// (the extent of a candidate child): as `area64` of that child's box,
/// bit for bit, without building it. `AXIS` is a constant so the extent
/// stays in registers (an indexed store then a vector load of the same
/// array stalls on store forwarding, twice per candidate).
#[inline(always)]
fn area_along<const AXIS: usize>(extent: [f64; 3], along: f32) -> f64 {
    let mut e = extent;
    e[AXIS] = along as f64;
    area_of_extent(e)
}

/// Where a tree's first pair of children goes: after the root, and after
/// the shared empty leaf ([`SHARED_EMPTY`]) in a compact tree.
pub(super) fn first_pair(params: &KdParams) -> usize {
    1 + params.compact as usize
}

pub(super) struct Builder<'s, 'a> {
    scene: Scene<'a>,
    params: KdParams,
    depth_limit: u32,
    pub(super) nodes: &'a mut [KdNode],
    /// Kept for the caller (ropes are made after the build).
    ropes: &'a mut [super::KdRopes],
    /// Kept for the caller, as `ropes`.
    rope_ids: &'a mut [u32],
    refs: &'a mut [u32],
    pub(super) events: &'s mut [KdEvent],
    flags: &'s mut [u8],
    /// Events at and above this index are not the build's to use (the job
    /// build parks its jobs' events there).
    pub(super) event_limit: usize,
    node_cap: usize,
    leaf_cap: usize,
    pub(super) node_top: usize,
    /// Empty children of empty-space cuts are left out (a compact tree).
    elide: bool,
    pub(super) leaf_top: usize,
    pub(super) ref_top: usize,
    pub(super) pending: usize,
    pub(super) depth: u32,
    pub(super) truncated: bool,
    /// References of the leaves made so far plus every pending node: what
    /// the tree needs at least if nothing more is split. It never shrinks
    /// (no split leaves its children fewer references than it had), so
    /// the tree a greedy build would finish with needs at least every
    /// value it takes.
    frontier_refs: usize,
    /// The frontier a greedy build first found past its reference room (0
    /// while it has not): a lower bound on what the untruncated tree needs.
    pub(super) refs_short: usize,
    /// How the reference room is shared: greedily (any split that fits the
    /// whole slice) or fairly (each subtree within its [`Task::ref_budget`]).
    fair: bool,
    /// [`KdParams::cost_reference`] times the cost of a test, in the root's
    /// SAH terms (times the root's area); a node's share is this over its
    /// area. Set with the root: [`Self::root_task`], [`Self::as_job`].
    ref_cost_root: f64,
}

/// Checks what every build checks first: the scene, the parameters, and
/// that each slice holds at least [`min_requirements`].
pub(super) fn check_build(
    scene: &Scene,
    params: &KdParams,
    storage: &KdStorage,
    scratch: &KdScratch,
) -> Result<(), Error> {
    scene.check()?;
    params.check()?;
    let min = min_requirements(scene.prim_count(), params);
    let have = [
        ("nodes", min.nodes, storage.nodes.len()),
        ("ropes", min.ropes, storage.ropes.len()),
        ("rope_ids", min.rope_ids, storage.rope_ids.len()),
        ("refs", min.refs, storage.refs.len()),
        ("events", min.events, scratch.events.len()),
        ("prim_flags", min.prim_flags, scratch.prim_flags.len()),
    ];
    for (slice, needed, got) in have {
        if got < needed {
            return Err(Error::SliceTooSmall { slice, needed, got });
        }
    }
    Ok(())
}

/// Builds an SAH kd-tree over `scene` into `storage`, using `scratch`, on
/// the calling thread: [`super::build_begin_for_threads`] for one thread
/// (one job), then [`super::KdBuild::finish`] running it.
///
/// Fails only for bad input (indices out of range, bad parameters) or for
/// slices shorter than [`min_requirements`]. With less room than
/// [`super::requirements`] it stops splitting where room runs out, stays
/// correct, and sets [`KD_FLAG_TRUNCATED`] in the tree's info.
pub fn build<'a>(
    scene: &Scene<'a>,
    params: &KdParams,
    storage: KdStorage<'a>,
    scratch: KdScratch<'_>,
) -> Result<KdTree<'a>, Error> {
    super::build_begin_for_threads(scene, params, storage, scratch, 1)?.finish()
}

/// The same tree as [`build`], built depth first in one pass over the whole
/// arena: what the job build falls back to when a job runs out of its
/// share of the room, and the reference the tests hold it to.
pub fn build_depth_first<'a>(
    scene: &Scene<'a>,
    params: &KdParams,
    storage: KdStorage<'a>,
    scratch: KdScratch<'_>,
) -> Result<KdTree<'a>, Error> {
    one_pass(scene, params, storage, scratch, true)
}

/// [`build_depth_first`], greedy first when `greedy_first`; without it,
/// the fair pass alone: the same tree whenever the greedy pass would run
/// out of room (the job build knows so from its jobs).
pub(super) fn one_pass<'a>(
    scene: &Scene<'a>,
    params: &KdParams,
    storage: KdStorage<'a>,
    scratch: KdScratch<'_>,
    greedy_first: bool,
) -> Result<KdTree<'a>, Error> {
    check_build(scene, params, &storage, &scratch)?;
    let mut b = Builder::new(*scene, params, storage, scratch.events, scratch.prim_flags);
    b.reserve_shared_empty();
    // Greedy first: the best tree whenever the room suffices. When it ran
    // out, the greedy tree has spent the room on whatever subtrees depth
    // first order reached first; build again sharing it fairly.
    let mut root = b.root_task();
    if greedy_first {
        b.run(root);
    }
    if b.truncated || !greedy_first {
        b.restart_fair();
        root = b.root_task();
        b.run(root);
    }
    let made = Made {
        node_count: b.node_top,
        leaf_count: b.leaf_top,
        ref_count: b.ref_top,
        depth: b.depth,
        truncated: b.truncated,
        bounds: root.voxel,
        prims: root.prims,
    };
    let (storage, _, _) = b.into_parts();
    Ok(made.into_tree(scene, storage, params))
}

/// What a build laid out at the start of its storage, before the ropes.
pub(super) struct Made {
    pub(super) node_count: usize,
    pub(super) leaf_count: usize,
    pub(super) ref_count: usize,
    pub(super) depth: u32,
    pub(super) truncated: bool,
    /// The root's box.
    pub(super) bounds: Aabb,
    /// Primitives that are not degenerate.
    pub(super) prims: usize,
}

impl Made {
    /// Ropes (when `params` asks for them), info and the tree over the
    /// first counts of `storage`.
    pub(super) fn into_tree<'a>(
        self,
        scene: &Scene<'a>,
        storage: KdStorage<'a>,
        params: &KdParams,
    ) -> KdTree<'a> {
        let (with_ropes, compact) = (params.ropes, params.compact);
        let KdStorage {
            nodes,
            ropes,
            rope_ids,
            refs,
        } = storage;
        let (nodes, refs) = (&nodes[..self.node_count], &refs[..self.ref_count]);
        let (ropes, rope_ids) = if with_ropes {
            let ropes = &mut ropes[..self.leaf_count];
            let rope_ids = &mut rope_ids[..self.node_count];
            ropes::build_ropes(nodes, ropes, rope_ids, &self.bounds);
            (&*ropes, &*rope_ids)
        } else {
            (&[][..], &[][..])
        };
        let mut flags = 0;
        if self.truncated {
            flags |= KD_FLAG_TRUNCATED;
        }
        if with_ropes {
            flags |= KD_FLAG_ROPES;
        }
        if compact {
            flags |= KD_FLAG_COMPACT;
        }
        let info = KdInfo {
            magic: KD_MAGIC,
            version: KD_VERSION,
            triangle_count: scene.triangles.len() as u32,
            sphere_count: scene.spheres.len() as u32,
            cone_count: scene.cones.len() as u32,
            valid_prim_count: self.prims as u32,
            node_count: self.node_count as u32,
            leaf_count: self.leaf_count as u32,
            ref_count: self.ref_count as u32,
            depth: self.depth,
            flags,
            bounds_min: self.bounds.min.into(),
            bounds_max: self.bounds.max.into(),
            ref_digest: {
                let d = crate::rng::ref_digest(refs.iter().copied());
                [d as u32, (d >> 32) as u32]
            },
            node_digest: {
                let d = crate::rng::node_digest(nodes.iter().map(|n| (n.word, n.data)));
                [d as u32, (d >> 32) as u32]
            },
            scene_digest: {
                let d = scene.digest();
                [d as u32, (d >> 32) as u32]
            },
        };
        KdTree {
            scene: *scene,
            info,
            trace_box: ClipBox::of(&info.trace_bounds()),
            nodes,
            ropes,
            rope_ids,
            refs,
        }
    }
}

impl<'s, 'a> Builder<'s, 'a> {
    /// A greedy builder over these slices, its capacities theirs, nothing
    /// made yet (node 0 is the root's slot).
    pub(super) fn new(
        scene: Scene<'a>,
        params: &KdParams,
        storage: KdStorage<'a>,
        events: &'s mut [KdEvent],
        flags: &'s mut [u8],
    ) -> Builder<'s, 'a> {
        let mut node_cap = storage.nodes.len().min(KD_MAX_NODES);
        if params.ropes {
            // A rope record per leaf, a rope index entry per node.
            node_cap = node_cap
                .min((2 * storage.ropes.len()).saturating_sub(1))
                .min(storage.rope_ids.len());
        }
        let leaf_cap = node_cap.div_ceil(2);
        Builder {
            scene,
            params: *params,
            depth_limit: params.depth_limit(scene.prim_count()),
            nodes: storage.nodes,
            ropes: storage.ropes,
            rope_ids: storage.rope_ids,
            refs: storage.refs,
            event_limit: events.len(),
            events,
            flags,
            node_cap,
            leaf_cap,
            node_top: 1,
            elide: params.compact,
            leaf_top: 0,
            ref_top: 0,
            pending: 0,
            depth: 0,
            truncated: false,
            frontier_refs: 0,
            refs_short: 0,
            fair: false,
            ref_cost_root: 0.0,
        }
    }

    /// Keeps node [`SHARED_EMPTY`] for the empty leaf that elided children
    /// stand for, in a compact tree: the one-pass build and a job build's
    /// top do; a job does not (its nodes join the tree's after it).
    pub(super) fn reserve_shared_empty(&mut self) {
        if self.elide {
            self.nodes[SHARED_EMPTY as usize] = KdNode::EMPTY;
            self.node_top = first_pair(&self.params);
        }
    }

    /// Makes this builder one job of a job build: it starts with `prims`
    /// references pending, as [`Self::root_task`] starts the whole scene,
    /// and prices references against the scene's box `root_voxel`.
    pub(super) fn as_job(&mut self, prims: usize, root_voxel: &Aabb) {
        self.frontier_refs = prims;
        self.set_root(root_voxel);
    }

    fn set_root(&mut self, root_voxel: &Aabb) {
        let p = &self.params;
        // Zero for the plain SAH even where the root's area overflows
        // (0 * infinity would be NaN).
        self.ref_cost_root = if p.cost_reference > 0.0 {
            p.cost_reference as f64 * p.cost_intersection as f64 * area64(root_voxel)
        } else {
            0.0
        };
    }

    /// The storage, the events and the flags the builder was given back.
    pub(super) fn into_parts(self) -> (KdStorage<'a>, &'s mut [KdEvent], &'s mut [u8]) {
        let storage = KdStorage {
            nodes: self.nodes,
            ropes: self.ropes,
            rope_ids: self.rope_ids,
            refs: self.refs,
        };
        (storage, self.events, self.flags)
    }

    fn restart_fair(&mut self) {
        self.node_top = first_pair(&self.params);
        self.leaf_top = 0;
        self.ref_top = 0;
        self.pending = 0;
        self.depth = 0;
        self.truncated = false;
        self.fair = true;
    }

    /// Events of every non-degenerate primitive, sorted once per axis.
    pub(super) fn root_task(&mut self) -> Task {
        let n = self.scene.prim_count();
        let mut voxel = Aabb::EMPTY;
        let mut valid = 0;
        // One bounds pass: axis `a`'s events go to their own region of 2n
        // slots from 2n * a (the scratch holds at least 6n events), each
        // region is sorted, then the three are closed up.
        let mut at = [0, 2 * n, 4 * n];
        for p in 0..n {
            if let Some(b) = self.scene.prim_bounds(p) {
                voxel = voxel.union(&b);
                valid += 1;
                for (axis, at) in at.iter_mut().enumerate() {
                    push_events(self.events, at, p, &b, axis);
                }
            }
        }
        self.frontier_refs = valid;
        self.set_root(&voxel);
        // Each region sorted; the scratch beyond the three, when the
        // requirements gave it (they do but for the smallest arenas), is
        // the radix sort's buffer and counters.
        let (regions, spare) = self.events.split_at_mut(6 * n);
        for (axis, &top) in at.iter().enumerate() {
            let region = &mut regions[2 * n * axis..top];
            if region.len() >= RADIX_MIN_EVENTS && spare.len() >= region.len() + RADIX_COUNTS {
                let (buf, counts) = spare.split_at_mut(region.len());
                sort_in_prim_order(region, buf, counts);
            } else {
                region.sort_unstable();
            }
        }
        let mut counts = [0; 3];
        let mut end = 0;
        for (axis, count) in counts.iter_mut().enumerate() {
            let region = 2 * n * axis..at[axis];
            self.events.copy_within(region.clone(), end);
            *count = region.len();
            end += *count;
        }
        Task {
            node: 0,
            depth: 0,
            voxel,
            start: 0,
            counts,
            prims: valid,
            ref_budget: self.refs.len(),
        }
    }

    /// Depth-first: split the current node while it pays, keep right
    /// children on a stack bounded by the depth limit. What a leaf leaves of
    /// its reference budget passes to the next node built.
    pub(super) fn run(&mut self, root: Task) {
        let mut stack = [root; KD_MAX_DEPTH as usize + 1];
        let mut task = root;
        loop {
            match self.try_split(&task) {
                Some((next, later)) => {
                    if let Some(right) = later {
                        stack[self.pending] = right;
                        self.pending += 1;
                    }
                    task = next;
                }
                None => {
                    self.make_leaf(&task);
                    if self.pending == 0 {
                        return;
                    }
                    let spare = task.ref_budget.saturating_sub(task.prims);
                    self.pending -= 1;
                    task = stack[self.pending];
                    task.ref_budget += spare;
                }
            }
        }
    }

    fn make_leaf(&mut self, task: &Task) {
        self.leaf_top += 1;
        let first = self.ref_top;
        let (s, e) = task.axis_range(0);
        for i in s..e {
            let ev = self.events[i];
            if ev.kind() != END {
                self.refs[self.ref_top] = ev.prim() as u32;
                self.ref_top += 1;
            }
        }
        self.nodes[task.node as usize] = KdNode::leaf(first as u32, (self.ref_top - first) as u32);
        self.depth = self.depth.max(task.depth);
    }

    /// The SAH sweep over the three axes' sorted events.
    fn find_split(&self, task: &Task) -> Option<Split> {
        let v = &task.voxel;
        // Areas in f64: boxes of huge scenes overflow f32 areas.
        let area = area64(v);
        if !(area > 0.0 && area.is_finite()) {
            return None;
        }
        let node = SweepNode {
            voxel: *v,
            extent: (v.max - v.min).as_dvec3().to_array(),
            inv_area: 1.0 / area,
            prims: task.prims,
            // At most f32::MAX, so that a split adding no reference costs
            // its SAH exactly (0 * infinity would be NaN).
            ref_cost: (self.ref_cost_root / area).min(f32::MAX as f64) as f32,
        };
        let mut best: Option<Split> = None;
        self.sweep::<0>(&node, task.axis_range(0), &mut best);
        self.sweep::<1>(&node, task.axis_range(1), &mut best);
        self.sweep::<2>(&node, task.axis_range(2), &mut best);
        best
    }

    /// One axis of [`Self::find_split`]: every candidate plane among the
    /// axis' events `[s, e)`, kept in `best` when it is cheaper (ties keep
    /// the earlier axis and position).
    #[inline(always)]
    fn sweep<const AXIS: usize>(
        &self,
        node: &SweepNode,
        (s, e): (usize, usize),
        best: &mut Option<Split>,
    ) {
        let v = &node.voxel;
        let (lo, hi) = (v.min[AXIS], v.max[AXIS]);
        if !(lo < hi) {
            return;
        }
        let (kt, ki, bonus) = (
            self.params.cost_traversal,
            self.params.cost_intersection,
            self.params.empty_bonus,
        );
        // Counts convert through i32 (they are below 2^30): one
        // instruction, where an unsigned 64-bit one takes a branch and
        // several; the same value, so the same rounding.
        let (ref_cost, n) = (node.ref_cost, node.prims as i32);
        // A straddling primitive is counted on both sides: `nl + nr - n`
        // references more. With no reference cost the sum is the plain
        // SAH's bit for bit (`x + 0.0 == x`).
        let cost = |pl: f32, pr: f32, nl: usize, nr: usize| {
            let (nl, nr) = (nl as i32, nr as i32);
            let added = (nl + nr - n).max(0) as f32;
            let c = kt + ki * (pl * nl as f32 + pr * nr as f32) + ref_cost * added;
            if nl == 0 || nr == 0 {
                c * bonus
            } else {
                c
            }
        };
        let (extent, inv_area) = (node.extent, node.inv_area);
        let mut consider = |pos: f32, nl: usize, nr: usize, planars: usize| {
            let pl = (area_along::<AXIS>(extent, pos - lo) * inv_area) as f32;
            let pr = (area_along::<AXIS>(extent, hi - pos) * inv_area) as f32;
            // Planar primitives go to the cheaper side; with none, both
            // sides cost the same: one evaluation (`cl <= cr` is then
            // `!c.is_nan()`).
            let (c, planar_left) = if planars == 0 {
                let c = cost(pl, pr, nl, nr);
                (c, !c.is_nan())
            } else {
                let cl = cost(pl, pr, nl + planars, nr);
                let cr = cost(pl, pr, nl, nr + planars);
                if cl <= cr {
                    (cl, true)
                } else {
                    (cr, false)
                }
            };
            if best.is_none_or(|b| c < b.cost) {
                let planars_left = if planar_left { planars } else { 0 };
                *best = Some(Split {
                    axis: AXIS,
                    pos,
                    planar_left,
                    cost: c,
                    left: nl + planars_left,
                    right: nr + planars - planars_left,
                });
            }
        };
        let ev = &self.events[s..e];
        let (mut nl, mut nr) = (0usize, node.prims);
        let mut i = 0;
        while i < ev.len() {
            // Every event at this position: its ends, planars and starts.
            let (p, bits) = (ev[i].pos(), ev[i].pos_bits());
            // Ends and starts counted in one register, 32 bits each (a
            // count in an array would chain its increments through memory);
            // the rest are planar.
            let (first, mut ends_starts) = (i, 0u64);
            while i < ev.len() && ev[i].pos_bits() == bits {
                ends_starts += ENDS_STARTS[ev[i].kind() as usize & 3];
                i += 1;
            }
            let (ends, starts) = (ends_starts as u32 as usize, (ends_starts >> 32) as usize);
            let planars = i - first - ends - starts;
            nr -= planars + ends;
            if p > lo && p < hi {
                consider(p, nl, nr, planars);
            } else if planars > 0 {
                // Planar primitives on a face of the node (a floor under
                // the scene): a split just inside cuts them off into a
                // thin cell, so the cells above stop referencing them.
                // Primitives starting on the face straddle the split.
                // The cell is 2^-12 of the node's extent or of its
                // coordinates' magnitude, whichever is larger: thousands
                // of ulps, far above the rounding of a ray's points on
                // that face, so no traversal (from the root or from an
                // LCTS entry) can classify a point across it
                // differently. Nodes thinner than that keep their faces.
                let thick = (hi - lo).max(lo.abs()).max(hi.abs()) * FACE_CELL;
                let inside = if p == lo { p + thick } else { p - thick };
                // Strictly inside: in a node of subnormal thickness the
                // cell rounds to nothing and would put the plane on the
                // face (which `validate` refuses).
                if 2.0 * thick < hi - lo && inside > lo && inside < hi {
                    if p == lo {
                        consider(inside, planars + starts, nr, 0);
                    } else {
                        consider(inside, nl, planars + ends, 0);
                    }
                }
            }
            nl += starts + planars;
        }
    }

    /// Splits `task`'s node when the termination rule and the room allow:
    /// the child to build next and the one to build after it (none when
    /// the other child is an elided empty leaf), their events in place.
    pub(super) fn try_split(&mut self, task: &Task) -> Option<(Task, Option<Task>)> {
        let n = task.prims;
        if n <= self.params.leaf_size as usize || task.depth >= self.depth_limit {
            return None;
        }
        let split = self.find_split(task)?;
        if self.params.sah_termination && split.cost >= self.params.cost_intersection * n as f32 {
            return None;
        }
        if self.node_top + 2 > self.node_cap || self.leaf_top + self.pending + 2 > self.leaf_cap {
            self.truncated = true;
            return None;
        }
        let (k, p) = (split.axis, split.pos);
        if split.left == 0 || split.right == 0 {
            return self.cut_empty_space(task, &split);
        }

        // Classify and count from the split axis' events, in one pass: a
        // primitive's start comes before its end (it lies below it), so a
        // start below the plane marks it straddling until an end at or
        // below the plane makes it left only. Positions compare as their
        // ordered bits (events hold no -0.0).
        let (ks, ke) = task.axis_range(k);
        let pb = crate::sort_key::ordered_bits(p + 0.0);
        let mut straddling = 0;
        let (mut left_only, mut right_only) = (0, 0);
        // A primitive whose end lies beyond the plane while its start was
        // marked straddling does straddle: its end event is listed at the
        // top of the free events, downwards (stored for every end beyond
        // the plane, the count advanced only for those), so the clipping
        // below need not scan the axis again. The list fits below the
        // limit and above this node's events whenever the room check
        // below passes; when it might not, the axis is scanned instead.
        let top = task.start + task.total();
        let list_top = self.event_limit;
        let listing = list_top >= top + (ke - ks);
        let mut listed = 0;
        for i in ks..ke {
            let ev = self.events[i];
            let at = ev.pos_bits();
            let side = match ev.kind() {
                START if at >= pb => RIGHT,
                START => BOTH,
                END if at <= pb => {
                    straddling -= 1;
                    LEFT
                }
                END => {
                    if listing {
                        self.events[list_top - 1 - listed] = ev;
                        listed += (self.flags[ev.prim()] == BOTH) as usize;
                    }
                    continue;
                }
                _ if at < pb || (at == pb && split.planar_left) => LEFT,
                _ => RIGHT,
            };
            match side {
                LEFT => left_only += 1,
                RIGHT => right_only += 1,
                _ => straddling += 1,
            }
            self.flags[ev.prim()] = side;
        }

        // New events of the straddling primitives, clipped into each child.
        let s2 = 2 * straddling;
        let dest = top + 12 * straddling;
        // The children's events are written at `dest` (left) and after
        // room for the most the left side can have (right): at most six
        // old events per primitive on one side, plus its new ones. No pass
        // counts them first.
        if dest + 6 * (left_only + right_only) + 12 * straddling > self.event_limit {
            self.truncated = true;
            return None;
        }
        let [lv, rv] = task.voxel.split(k, p);
        let mut tl = [0usize; 3];
        let mut tr = [0usize; 3];
        let (mut nl_new, mut nr_new) = (0, 0);
        // The order the straddlers come in does not matter: their new
        // events are sorted below, and no two events share a key.
        let mut clip = |b: &mut Self, prim: usize| {
            let [left, right] = b.scene.clipped_bounds_split(prim, &task.voxel, k, p);
            if let Some(c) = left {
                nl_new += 1;
                for (axis, n) in tl.iter_mut().enumerate() {
                    let mut at = top + axis * s2 + *n;
                    push_events(b.events, &mut at, prim, &c, axis);
                    *n = at - top - axis * s2;
                }
            }
            if let Some(c) = right {
                nr_new += 1;
                for (axis, n) in tr.iter_mut().enumerate() {
                    let base = top + 6 * straddling + axis * s2;
                    let mut at = base + *n;
                    push_events(b.events, &mut at, prim, &c, axis);
                    *n = at - base;
                }
            }
        };
        if listing {
            for j in 0..listed {
                let prim = self.events[list_top - 1 - j].prim();
                clip(self, prim);
            }
        } else {
            for i in ks..ke {
                let ev = self.events[i];
                if ev.kind() == START && self.flags[ev.prim()] == BOTH {
                    clip(self, ev.prim());
                }
            }
        }
        let nl = left_only + nl_new;
        let nr = right_only + nr_new;
        if !self.params.sah_termination && nl == n && nr == n {
            return None;
        }
        // A straddler that rounding clips out of both children would
        // shrink the frontier; such a node stays a leaf, so that the
        // frontier never shrinks (see `frontier_refs`).
        if nl + nr < n {
            return None;
        }
        let frontier = self.frontier_refs + nl + nr - n;
        let fits = if self.fair {
            nl + nr <= task.ref_budget
        } else {
            frontier <= self.refs.len()
        };
        if !fits {
            if !self.fair && self.refs_short == 0 {
                self.refs_short = frontier;
            }
            self.truncated = true;
            return None;
        }
        // Merge old and new events per axis into the two destinations.
        let right_dest = dest + 6 * left_only + tl.iter().sum::<usize>();
        let mut lcounts = [0usize; 3];
        let mut rcounts = [0usize; 3];
        let (mut lat, mut rat) = (dest, right_dest);
        for axis in 0..3 {
            let (s, e) = task.axis_range(axis);
            let lnew = top + axis * s2;
            let rnew = top + 6 * straddling + axis * s2;
            self.events[lnew..lnew + tl[axis]].sort_unstable();
            self.events[rnew..rnew + tr[axis]].sort_unstable();
            let (l0, r0) = (lat, rat);
            self.merge(
                (s, e),
                (lnew, lnew + tl[axis]),
                (rnew, rnew + tr[axis]),
                (&mut lat, &mut rat),
            );
            lcounts[axis] = lat - l0;
            rcounts[axis] = rat - r0;
        }
        let er = rat - right_dest;
        // Right child first at the node's base (it waits), left on top.
        let base = task.start;
        self.events.copy_within(right_dest..rat, base);
        self.events.copy_within(dest..lat, base + er);

        let c = self.node_top as u32;
        self.node_top += 2;
        self.nodes[task.node as usize] = KdNode::interior(k, p, c);
        self.frontier_refs = frontier;
        let spare = task.ref_budget.saturating_sub(nl + nr);
        let left_budget = nl + (spare as u128 * nl as u128 / (nl + nr).max(1) as u128) as usize;
        let left = Task {
            node: c,
            depth: task.depth + 1,
            voxel: lv,
            start: base + er,
            counts: lcounts,
            prims: nl,
            ref_budget: left_budget,
        };
        let right = Task {
            node: c + 1,
            depth: task.depth + 1,
            voxel: rv,
            start: base,
            counts: rcounts,
            prims: nr,
            ref_budget: task.ref_budget.saturating_sub(left_budget),
        };
        Some((left, Some(right)))
    }

    /// [`Self::try_split`] for a plane with no primitive on one side: the
    /// other child keeps the node's events as they lie (nothing straddles,
    /// nothing is classified, clipped or merged), so only the node and the
    /// children are written. Same children, same checks and the same tree
    /// as the general path; a top of empty-space cuts (each over all the
    /// events) stays cheap.
    ///
    /// In a compact tree the empty child is not stored: the node names the
    /// full child alone ([`KdNode::interior_elided`]), and the empty leaf
    /// is counted as made.
    fn cut_empty_space(&mut self, task: &Task, split: &Split) -> Option<(Task, Option<Task>)> {
        let n = task.prims;
        let total = task.total();
        // The general path's room check, for no straddling primitive.
        if task.start + total + 6 * n > self.event_limit {
            self.truncated = true;
            return None;
        }
        let fits = if self.fair {
            n <= task.ref_budget
        } else {
            self.frontier_refs <= self.refs.len()
        };
        if !fits {
            self.truncated = true;
            return None;
        }
        let (k, p) = (split.axis, split.pos);
        let c = self.node_top as u32;
        let elide = self.elide;
        self.node_top += 2 - elide as usize;
        self.nodes[task.node as usize] = if elide {
            KdNode::interior_elided(k, p, c, split.left == 0)
        } else {
            KdNode::interior(k, p, c)
        };
        // The general path's budgets: a left child gets its references and
        // all the spare, a right one what the left leaves.
        let full_budget = if split.left == 0 {
            task.ref_budget
        } else {
            task.ref_budget.max(n)
        };
        let full = |node: u32, voxel: Aabb| Task {
            node,
            depth: task.depth + 1,
            voxel,
            ref_budget: full_budget,
            ..*task
        };
        let empty = |node: u32, voxel: Aabb| Task {
            node,
            depth: task.depth + 1,
            voxel,
            start: task.start + if split.left == 0 { total } else { 0 },
            counts: [0; 3],
            prims: 0,
            ref_budget: 0,
        };
        let [lv, rv] = task.voxel.split(k, p);
        if elide {
            // The empty leaf, made where it stands: a leaf of the tree's
            // count and depth.
            self.leaf_top += 1;
            self.depth = self.depth.max(task.depth + 1);
            let full_voxel = if split.left == 0 { rv } else { lv };
            return Some((full(c, full_voxel), None));
        }
        Some(if split.left == 0 {
            (empty(c, lv), Some(full(c + 1, rv)))
        } else {
            (full(c, lv), Some(empty(c + 1, rv)))
        })
    }

    /// Splits the old events in `[s, e)` by their primitive's side and
    /// merges each side with its sorted new events (`left_new`,
    /// `right_new`), writing at `*at.0` and `*at.1` (a straddling
    /// primitive's old events are dropped: its clipped ones are among the
    /// new). The outputs lie after every input.
    ///
    /// The old events are partitioned first, without a branch on their
    /// side (whose outcome is a coin toss a predictor cannot learn): each
    /// is stored at its side's cursor, a dropped one (a straddler's) at the
    /// right cursor without moving it. The new events then go in from the
    /// back ([`merge_from_back`]).
    fn merge(
        &mut self,
        (s, e): (usize, usize),
        left_new: (usize, usize),
        right_new: (usize, usize),
        at: (&mut usize, &mut usize),
    ) {
        let (lat, rat) = at;
        let (l0, r0) = (*lat, *rat);
        // The outputs lie after every input: read below `e`, write above,
        // and below the limit only (the room past it may hold a job's copy
        // of its events).
        let (inputs, outputs) = self.events.split_at_mut(e);
        let outputs = &mut outputs[..self.event_limit - e];
        let (mut l, mut r) = (l0 - e, r0 - e);
        for &ev in &inputs[s..] {
            // The side's bits are the cursors' steps (classification wrote
            // every flag this node's events name: LEFT, RIGHT or BOTH).
            let side = self.flags[ev.prim()] as usize;
            let (to_left, to_right) = (side & LEFT as usize, side >> 1);
            // A dropped event is stored at the right cursor, which does not
            // move: the next right event, or the merge, writes over it.
            let dst = if to_left != 0 { l } else { r };
            debug_assert!(dst < outputs.len() || side == BOTH as usize);
            if let Some(slot) = outputs.get_mut(dst) {
                *slot = ev;
            }
            l += to_left;
            r += to_right;
        }
        *lat = merge_from_back(self.events, l0, l + e, left_new);
        *rat = merge_from_back(self.events, r0, r + e, right_new);
    }
}

/// Merges the sorted events `new` into the sorted events `[start, end)`,
/// which have room after them for as many; returns the merged run's end.
/// An old event goes before a new one it ties with. `new` lies outside
/// `[start, end + new's length)`. Few new events (a split's straddlers,
/// mostly) go in each after a binary search, moving the old ones above it
/// in one block; many, one step per event.
fn merge_from_back(
    events: &mut [KdEvent],
    start: usize,
    end: usize,
    (ns, ne): (usize, usize),
) -> usize {
    let mut hi = end;
    if (ne - ns) * 16 >= end - start {
        // Many new events: one step per event, from the back, until the
        // new ones run out (the old ones below them are in place).
        let mut out = end + (ne - ns);
        let mut j = ne;
        while j > ns {
            let ev = events[j - 1];
            out -= 1;
            if hi > start && events[hi - 1] > ev {
                hi -= 1;
                events[out] = events[hi];
            } else {
                j -= 1;
                events[out] = ev;
            }
        }
        return end + (ne - ns);
    }
    for m in (0..ne - ns).rev() {
        let ev = events[ns + m];
        let p = start + events[start..hi].partition_point(|old| *old <= ev);
        events.copy_within(p..hi, p + m + 1);
        events[p + m] = ev;
        hi = p;
    }
    end + (ne - ns)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Merging new events in from the back gives the sorted union, old
    /// before new where they tie, whether few new events go in (a binary
    /// search and a block move each) or many (one step per event), at
    /// either end, none, or only new ones.
    #[test]
    fn merge_from_back_is_the_sorted_union() {
        let mut g = crate::rng::SplitMix64(5);
        const N: usize = 200;
        for case in 0..400 {
            let olds = g.below(N as u64) as usize;
            let news = match case % 4 {
                0 => g.below(4) as usize,
                1 => g.below(N as u64) as usize,
                2 => 0,
                _ => g.below(40) as usize,
            };
            // Few distinct positions, so old and new events tie often.
            let event = |g: &mut crate::rng::SplitMix64| {
                KdEvent::new(g.below(16) as f32, g.below(8) as usize, g.below(3) as u32)
            };
            let mut events = [KdEvent::default(); 3 * N];
            // New events first, the old ones after them with room behind.
            for e in &mut events[..news] {
                *e = event(&mut g);
            }
            for e in &mut events[N..N + olds] {
                *e = event(&mut g);
            }
            events[..news].sort_unstable();
            events[N..N + olds].sort_unstable();
            // The reference: a stable merge, old first on ties.
            let mut want = [KdEvent::default(); 2 * N];
            let (mut i, mut j) = (N, 0);
            for w in &mut want[..olds + news] {
                if j == news || (i < N + olds && events[i] <= events[j]) {
                    *w = events[i];
                    i += 1;
                } else {
                    *w = events[j];
                    j += 1;
                }
            }
            let end = merge_from_back(&mut events, N, N + olds, (0, news));
            assert_eq!(end, N + olds + news, "case {case}");
            assert_eq!(events[N..end], want[..olds + news], "case {case}");
        }
    }

    /// The root's radix sort gives `sort_unstable`'s order on events made
    /// in primitive order: positions of every sign and size, many ties (so
    /// the primitive order decides), planars, and scenes in one octave
    /// (whose constant digits are skipped).
    #[test]
    fn radix_sort_in_prim_order_is_the_key_order() {
        let mut g = crate::rng::SplitMix64(11);
        const N: usize = 3000;
        for case in 0..60 {
            let n = 1 + g.below(N as u64) as usize;
            let pos = |g: &mut crate::rng::SplitMix64| -> f32 {
                match case % 4 {
                    // Few distinct positions: ties everywhere.
                    0 => g.below(8) as f32 - 4.0,
                    // One octave: the sign and exponent digits constant.
                    1 => 1.0 + g.below(1 << 23) as f32 / (1 << 23) as f32,
                    // Any finite float, and the infinities.
                    2 => match g.below(50) {
                        0 => f32::INFINITY,
                        1 => f32::NEG_INFINITY,
                        _ => f32::from_bits(g.below(u32::MAX as u64) as u32 & 0xFF7F_FFFF),
                    },
                    _ => (g.below(2000) as f32 - 1000.0) * 1e-3,
                }
            };
            let mut events = [KdEvent::default(); 2 * N];
            let mut at = 0;
            for prim in 0..n {
                let (a, b) = (pos(&mut g), pos(&mut g));
                let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
                let flat = g.below(5) == 0;
                let hi = if flat { lo } else { hi };
                let b = Aabb {
                    min: crate::Vec3::splat(lo),
                    max: crate::Vec3::splat(hi),
                };
                push_events(&mut events, &mut at, prim, &b, 0);
            }
            let mut want = events;
            want[..at].sort_unstable();
            let mut buf = [KdEvent::default(); 2 * N];
            let mut counts = [KdEvent::default(); RADIX_COUNTS];
            sort_in_prim_order(&mut events[..at], &mut buf[..at], &mut counts);
            assert_eq!(events[..at], want[..at], "case {case}");
        }
    }

    /// The integer key orders as position, then kind, then primitive.
    #[test]
    fn key_orders_by_position_kind_and_primitive() {
        let positions = [
            f32::NEG_INFINITY,
            -3.5e30,
            -2.0,
            -1e-40,
            -0.0,
            0.0,
            1e-40,
            0.5,
            2.0,
            7.25e30,
            f32::INFINITY,
        ];
        let mut events = [KdEvent::default(); 11 * 3 * 3];
        let mut i = 0;
        for &pos in &positions {
            for kind in [END, PLANAR, START] {
                for prim in [0, 5, (1 << 30) - 1] {
                    events[i] = KdEvent::new(pos, prim, kind);
                    i += 1;
                }
            }
        }
        let reference = |a: &KdEvent, b: &KdEvent| {
            a.pos()
                .partial_cmp(&b.pos())
                .unwrap()
                .then(a.kind().cmp(&b.kind()))
                .then(a.prim().cmp(&b.prim()))
        };
        for a in &events {
            for b in &events {
                assert_eq!(a.cmp(b), reference(a, b), "{a:?} {b:?}");
            }
        }
    }
}
