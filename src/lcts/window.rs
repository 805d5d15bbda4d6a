//! The rays of one LCTS window (an SLCTS window, or a small interval or
//! rectangle of an HLCTS cast) traced together, eight at a time (the
//! packet's lanes, `kd::packet`): each primitive of the shaft's common
//! leaves is tested against all of them at once. Past the common leaves
//! (and in a shaft without common leaves, from each ray's first leaf)
//! each lane walks on as [`slcts::trace`] and [`hlcts::trace_guided`]
//! walk its single ray, and the lanes that stand in the same leaf test it
//! together.
//!
//! Every ray gets the single-ray trace's hit, and so the hierarchical one: each
//! lane tests the same primitives of the same leaves in the same order
//! with the single ray's arithmetic, keeps its best hit by the same rule,
//! computes each leaf's exit as `KdTree::leaf_exit` does, and stops
//! where the single ray stops. Steps and tests are counted per ray as the
//! single rays count them.

use super::guide::{self, Cursor, Paths};
use super::hlcts::{self, Hlcts, ENTRY_EMPTY_RUN};
use super::slcts::{self, Slcts, EMPTY_RUN};
use crate::geom::lanes::{F8, LANES, M8};
use crate::geom::PreparedRay;
use crate::kd::packet::{ClosestLanes, Packet, PacketVisitor};
use crate::kd::traverse::{Closest, Steps};
use crate::kd::{KdStackItem, KdTree, NO_NODE};
use crate::{Hit, Ray, TraceStats, Vec3};

/// The shaft a window's rays share: an SLCTS sequence or an HLCTS cut
/// (whose leading leaves are its common sequence).
#[derive(Clone, Copy)]
pub enum Shaft<'a, 'b> {
    /// A window of an SLCTS cast.
    Slcts(&'a Slcts<'b>),
    /// A small interval or rectangle of an HLCTS cast.
    Hlcts(&'a Hlcts<'b>),
}

impl Shaft<'_, '_> {
    /// Whether the rays can share a packet: no termination object (it
    /// already answers most rays with one test).
    fn shared(&self) -> bool {
        match self {
            Shaft::Slcts(s) => s.termination.is_none(),
            Shaft::Hlcts(h) => h.termination.is_none(),
        }
    }

    /// The first leaf of ray `r` of a shaft without common leaves, where
    /// it enters the scene's box at `p`, as its single ray locates it
    /// when no boundary ray's first leaf holds `p`.
    #[inline]
    fn locate_first(
        &self,
        tree: &KdTree,
        r: &PreparedRay,
        p: Vec3,
        steps: &mut Steps,
    ) -> Option<u32> {
        match self {
            Shaft::Slcts(s) => slcts::locate_first(tree, s, p, steps),
            Shaft::Hlcts(h) => hlcts::locate_first(tree, h, r, steps),
        }
    }

    /// One ray alone, as the cast traces it without packets.
    #[allow(clippy::too_many_arguments)]
    fn single(
        &self,
        tree: &KdTree,
        paths: &Paths,
        nearest: usize,
        ray: &Ray,
        stack: &mut [KdStackItem],
        stats: &mut TraceStats,
    ) -> Hit {
        match self {
            Shaft::Slcts(s) => slcts::trace(tree, s, paths, nearest, ray, stack, stats),
            Shaft::Hlcts(h) => hlcts::trace_guided(tree, h, paths, nearest, ray, stack, stats),
        }
    }
}

/// Traces `rays` (at most [`LANES`], all inside `shaft`) into `hits`, ray
/// `i` with its nearest boundary ray `nearest[i]` as the single-ray trace
/// ([`slcts::trace`], [`hlcts::trace_guided`]) takes it. Rays that cannot
/// share a packet (directions of different signs, a termination object),
/// and every ray in a build without the `packets` feature, are traced one
/// by one by that single-ray trace.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub fn trace(
    tree: &KdTree,
    shaft: Shaft,
    paths: &Paths,
    rays: &[Ray],
    nearest: &[usize],
    hits: &mut [Hit],
    stack: &mut [KdStackItem],
    stats: &mut TraceStats,
) {
    let n = rays.len().min(LANES).min(nearest.len()).min(hits.len());
    let (rays, nearest, hits) = (&rays[..n], &nearest[..n], &mut hits[..n]);
    let scene = &tree.scene;
    let curved = !(scene.spheres.is_empty() && scene.cones.is_empty());
    let mut p = Packet::EMPTY;
    // Without the `packets` feature (small targets) every ray goes alone.
    let shared = cfg!(feature = "packets") && n > 1 && shaft.shared() && p.load(rays, curved);
    let packed = shared
        && match shaft {
            Shaft::Slcts(s) => {
                let leaves = s.entries[..s.len]
                    .iter()
                    .map(|&e| (e & !EMPTY_RUN, e & EMPTY_RUN != 0));
                trace_packet(
                    tree, shaft, leaves, paths, &p, rays, nearest, hits, stack, stats,
                )
            }
            Shaft::Hlcts(h) => {
                let leaves = h.entries[..h.leading_leaves]
                    .iter()
                    .map(|e| (e.node, e.flags & ENTRY_EMPTY_RUN != 0));
                trace_packet(
                    tree, shaft, leaves, paths, &p, rays, nearest, hits, stack, stats,
                )
            }
        }
        .is_some();
    if !packed {
        for i in 0..n {
            hits[i] = shaft.single(tree, paths, nearest[i], &rays[i], stack, stats);
        }
    }
}

/// How a cast traces its windows' rays: [`trace`] compiled for the
/// target's baseline ([`Baseline`]), or a clone compiled for more of the
/// CPU, which only a caller that checked the CPU can make
/// (`coray_ffi::simd`). Chosen once per cast, outside its loops; every
/// kernel gives the same hits and counts.
pub trait Kernel: Copy {
    /// [`trace`], as this kernel compiles it.
    #[allow(clippy::too_many_arguments)]
    fn trace(
        self,
        tree: &KdTree,
        shaft: Shaft,
        paths: &Paths,
        rays: &[Ray],
        nearest: &[usize],
        hits: &mut [Hit],
        stack: &mut [KdStackItem],
        stats: &mut TraceStats,
    );

    /// [`KdTree::intersect_packets`], as this kernel compiles it: the
    /// tiles of a [`super::Scheme::Packets`] cast.
    #[inline(always)]
    fn packets(
        self,
        tree: &KdTree,
        rays: &[Ray],
        hits: &mut [Hit],
        stack: &mut [KdStackItem],
        stats: &mut TraceStats,
    ) {
        tree.intersect_packets(rays, hits, stack, stats);
    }
}

/// [`trace`] for the target's baseline (SSE2 on x86-64).
#[derive(Clone, Copy, Debug, Default)]
pub struct Baseline;

impl Kernel for Baseline {
    #[inline(always)]
    fn trace(
        self,
        tree: &KdTree,
        shaft: Shaft,
        paths: &Paths,
        rays: &[Ray],
        nearest: &[usize],
        hits: &mut [Hit],
        stack: &mut [KdStackItem],
        stats: &mut TraceStats,
    ) {
        trace(tree, shaft, paths, rays, nearest, hits, stack, stats);
    }
}

/// [`trace`] compiled for AVX2: the same hits and counts, bit for bit (the
/// same IEEE operations; no fused multiply-add is formed).
///
/// # Safety
/// Call only on a CPU with AVX2 (`coray_ffi::simd` checks and makes the
/// kernel).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[allow(clippy::too_many_arguments)]
pub fn trace_avx2(
    tree: &KdTree,
    shaft: Shaft,
    paths: &Paths,
    rays: &[Ray],
    nearest: &[usize],
    hits: &mut [Hit],
    stack: &mut [KdStackItem],
    stats: &mut TraceStats,
) {
    trace(tree, shaft, paths, rays, nearest, hits, stack, stats);
}

/// The packet's walk; `None` (nothing counted, nothing written) when the
/// tree breaks an invariant, so that the single rays meet the fault and
/// count it as they do.
///
/// The lanes visit the common leaves together; past them, or without a
/// common leaf, each lane walks its single ray's leaves ([`Lanes`]), and
/// the lanes that stand in one leaf test it together.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn trace_packet(
    tree: &KdTree,
    shaft: Shaft,
    leaves: impl Iterator<Item = (u32, bool)>,
    paths: &Paths,
    p: &Packet,
    rays: &[Ray],
    nearest: &[usize],
    hits: &mut [Hit],
    stack: &mut [KdStackItem],
    stats: &mut TraceStats,
) -> Option<()> {
    let (_, t1, mut on) = p.segment(&tree.trace_box.aabb());
    let mut v = ClosestLanes::new(p);
    let mut steps = Steps::default();
    let mut cursors = [Cursor::new(paths, 0); LANES];
    for (c, &near) in cursors.iter_mut().zip(nearest) {
        *c = Cursor::new(paths, near);
    }
    let mut lanes = Lanes::new(p, t1);
    // The common leaves, as walk_common visits them: a run of empty leaves
    // is one step and no test.
    let mut last = None;
    let mut exits = None;
    for (node, run) in leaves {
        last = Some(node);
        exits = None;
        if run {
            let lanes = on.count() as u64;
            steps.leaves += lanes;
            steps.empty += lanes;
        } else {
            exits = Some(test_leaf(tree, p, &mut v, node, t1, &mut on, &mut steps)?);
        }
    }
    match last {
        Some(leaf) => {
            let exits = exits.unwrap_or_else(|| p.leaf_exit(tree.rope(leaf)));
            lanes.on = on;
            lanes.leave(tree, leaf, on, &exits, paths, &mut cursors, &mut steps);
        }
        None => {
            lanes.on = on;
            lanes.enter(tree, shaft, paths, &mut cursors, &mut steps);
        }
    }
    lanes.walk(tree, p, &mut v, paths, &mut cursors, &mut steps)?;
    steps.flush(stats);
    stats.rays += hits.len() as u64;
    stats.prim_tests += v.tests();
    for (i, hit) in hits.iter_mut().enumerate() {
        *hit = v.best[i];
        if lanes.redo.get(i) {
            // A lane in a split plane it crosses: redone hierarchically,
            // as its single ray is.
            let mut c = Closest::new(&rays[i]);
            *hit = guide::finish(tree, &mut c, false, stack, Steps::default(), stats);
        }
    }
    Some(())
}

/// One leaf for the lanes `on`: a step each, its primitives tested; the
/// lanes with a hit clearly inside it are done. Returns where each lane
/// leaves it; `None` for a leaf whose references lie outside the tree.
#[inline(always)]
fn test_leaf(
    tree: &KdTree,
    p: &Packet,
    v: &mut ClosestLanes,
    leaf: u32,
    t1: F8,
    on: &mut M8,
    steps: &mut Steps,
) -> Option<(F8, [u8; LANES], M8)> {
    steps.leaves += on.count() as u64;
    let refs = tree.leaf_refs(tree.node(leaf))?;
    let exits = p.leaf_exit(tree.rope(leaf));
    let done = v.visit(tree, p, refs, *on, exits.0.min(t1));
    *on = *on & !done;
    Some(exits)
}

/// Lanes that walk apart, each along its single ray's leaves by guided
/// ropes ([`guide::walk`]): per lane the same leaves, guesses and steps as
/// its single ray, so the same hit. The lanes that stand in the same leaf
/// test its primitives together, the leaf entered nearest the eye first:
/// lanes that part for a leaf or two meet again behind it.
struct Lanes<'r> {
    /// The packet.
    packet: &'r Packet,
    /// Where each lane's segment ends.
    t1: F8,
    /// Lanes still walking.
    on: M8,
    /// Lanes to redo hierarchically (in a split plane they cross, as the
    /// single ray's walk says).
    redo: M8,
    /// Each walking lane's next leaf node.
    at: [u32; LANES],
    /// Where each walking lane enters it.
    t_in: F8,
    /// Each lane's single prepared ray, made when its point location
    /// needs it.
    prepared: [Option<PreparedRay>; LANES],
}

impl<'r> Lanes<'r> {
    fn new(packet: &'r Packet, t1: F8) -> Self {
        Lanes {
            packet,
            t1,
            on: M8::NONE,
            redo: M8::NONE,
            at: [NO_NODE; LANES],
            t_in: F8::splat(f32::INFINITY),
            prepared: [None; LANES],
        }
    }

    /// Lane `i`'s single prepared ray: the packet's lane, which holds
    /// what [`PreparedRay::new`] computes for the ray (no division made
    /// again).
    #[inline(always)]
    fn prepared(&mut self, i: usize) -> &PreparedRay {
        let p = self.packet;
        self.prepared[i].get_or_insert_with(|| p.ray(i))
    }

    /// Lane `i` goes on to `next` (its next leaf, entered at `t`), ends
    /// (`None`) or is redone hierarchically (`Err`).
    #[inline(always)]
    fn go(&mut self, i: usize, next: Result<Option<u32>, ()>, t: f32) {
        match next {
            Ok(Some(n)) => {
                self.at[i] = n;
                self.t_in.0[i] = t;
                return;
            }
            Ok(None) => {}
            Err(()) => self.redo.0[i] = u32::MAX,
        }
        self.on.0[i] = 0;
    }

    /// The walking lanes of a shaft without common leaves find their first
    /// leaves as [`guide::walk_from_first`] does: one a boundary ray
    /// entered first, or else the shaft's own point location.
    #[inline(always)]
    fn enter(
        &mut self,
        tree: &KdTree,
        shaft: Shaft,
        paths: &Paths,
        cursors: &mut [Cursor; LANES],
        steps: &mut Steps,
    ) {
        for (i, cursor) in cursors.iter_mut().enumerate() {
            if !self.on.get(i) {
                continue;
            }
            let r = self.prepared(i);
            let (next, t0) = match tree.scene_segment(r) {
                None => (Ok(None), 0.0),
                Some((t0, _)) => {
                    let q = r.at(t0);
                    let first = guide::guess_first(tree, paths, cursor, q, r.dir, steps)
                        .or_else(|| shaft.locate_first(tree, r, q, steps));
                    (first.ok_or(()).map(Some), t0)
                }
            };
            self.go(i, next, t0);
        }
    }

    /// The lanes `leaving` leave leaf node `from` at `exits`: each on to
    /// its next leaf as [`guide::walk`] goes (a rope straight to a leaf
    /// taken here; else [`guide::next`]), or done (out of its segment or
    /// the scene), or to be redone (an edge or corner, a split plane).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn leave(
        &mut self,
        tree: &KdTree,
        from: u32,
        leaving: M8,
        (t_exit, faces, at_edge): &(F8, [u8; LANES], M8),
        paths: &Paths,
        cursors: &mut [Cursor; LANES],
        steps: &mut Steps,
    ) {
        let ropes = &tree.rope(from).neighbor;
        for i in 0..LANES {
            if !leaving.get(i) {
                continue;
            }
            let t = t_exit.0[i];
            let next = if t > self.t1.0[i] {
                Ok(None)
            } else if at_edge.get(i) {
                Err(())
            } else {
                let face = faces[i] as usize;
                let rope = ropes[face];
                if rope == NO_NODE {
                    Ok(None)
                } else if tree.node(rope).is_leaf() {
                    cursors[i].follow(paths, rope);
                    Ok(Some(rope))
                } else {
                    let r = self.prepared(i);
                    guide::next(tree, r, from, t, face, paths, &mut cursors[i], steps)
                }
            };
            self.go(i, next, t);
        }
    }

    /// Walks every lane to its end: the leaf entered first, with every lane
    /// that stands in it, at a time. `None` on a broken tree.
    #[inline(always)]
    fn walk(
        &mut self,
        tree: &KdTree,
        p: &Packet,
        v: &mut ClosestLanes,
        paths: &Paths,
        cursors: &mut [Cursor; LANES],
        steps: &mut Steps,
    ) -> Option<()> {
        // Every lane's walk is at most one pass over the leaves (as a
        // single rope walk's); past that the tree is broken.
        let mut budget = LANES * tree.ropes.len();
        while self.on.any() {
            budget = budget.checked_sub(1)?;
            // The first walking lane that enters its leaf first (branch
            // free: the lanes' order is data).
            let t_in = self.on.select(self.t_in, F8::splat(f32::INFINITY));
            let nearest = t_in.0.iter().fold(f32::INFINITY, |a, &b| a.min(b));
            let mut first = LANES - 1;
            for i in (0..LANES).rev() {
                first = if self.on.get(i) && t_in.0[i] == nearest {
                    i
                } else {
                    first
                };
            }
            if !self.on.get(first) {
                // (No walking lane entered at `nearest`: a NaN.)
                first = (0..LANES).find(|&i| self.on.get(i))?;
            }
            let node = self.at[first];
            let mut group = M8::NONE;
            for i in 0..LANES {
                group.0[i] = self.on.0[i] & 0u32.wrapping_sub((self.at[i] == node) as u32);
            }
            let count = group.count() as u64;
            steps.leaves += count;
            let refs = tree.leaf_refs(tree.node(node))?;
            if refs.is_empty() {
                steps.empty += count;
            }
            let exits = p.leaf_exit(tree.rope(node));
            let done = v.visit(tree, p, refs, group, exits.0.min(self.t1));
            self.on = self.on & !done;
            self.leave(tree, node, group & !done, &exits, paths, cursors, steps);
        }
        Some(())
    }
}
