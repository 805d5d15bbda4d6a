//! The rays of one LCTS window (an SLCTS window, or a small interval or
//! rectangle of an HLCTS cast) traced together, eight at a time (the
//! packet's lanes, `kd::packet`): each primitive of the shaft's
//! common leaves is tested against all of them at once; past the common
//! leaves the packet goes on by ropes while every ray still in it leaves
//! its leaf through the same face into a leaf. Where the rays part (other
//! faces, or a rope to an interior node), each goes on alone from that
//! leaf, exactly as [`slcts::trace`] and [`hlcts::trace_guided`] go on
//! from the last common leaf.
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
use crate::kd::packet::{ClosestLanes, Packet, PacketVisitor};
use crate::kd::traverse::{Closest, Steps};
use crate::kd::{KdStackItem, KdTree, NO_NODE};
use crate::{Hit, Ray, TraceStats};

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
    /// already answers most rays with one test) and some common leaf.
    fn shared(&self) -> bool {
        match self {
            Shaft::Slcts(s) => s.termination.is_none() && s.len > 0,
            Shaft::Hlcts(h) => h.termination.is_none() && h.leading_leaves > 0,
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
/// share a packet (directions of different signs, a termination object,
/// no common leaf), and every ray in a build without the `packets`
/// feature, are traced one by one by that single-ray trace.
#[allow(clippy::too_many_arguments)]
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
                trace_packet(tree, leaves, paths, &p, rays, nearest, hits, stack, stats)
            }
            Shaft::Hlcts(h) => {
                let leaves = h.entries[..h.leading_leaves]
                    .iter()
                    .map(|e| (e.node, e.flags & ENTRY_EMPTY_RUN != 0));
                trace_packet(tree, leaves, paths, &p, rays, nearest, hits, stack, stats)
            }
        }
        .is_some();
    if !packed {
        for i in 0..n {
            hits[i] = shaft.single(tree, paths, nearest[i], &rays[i], stack, stats);
        }
    }
}

/// The packet's walk; `None` (nothing counted, nothing written) when the
/// tree breaks an invariant, so that the single rays meet the fault and
/// count it as they do.
#[allow(clippy::too_many_arguments)]
fn trace_packet(
    tree: &KdTree,
    leaves: impl Iterator<Item = (u32, bool)>,
    paths: &Paths,
    p: &Packet,
    rays: &[Ray],
    nearest: &[usize],
    hits: &mut [Hit],
    stack: &mut [KdStackItem],
    stats: &mut TraceStats,
) -> Option<()> {
    let (_, t1, mut on) = p.segment(&tree.trace_box);
    let mut v = ClosestLanes::new(p);
    let mut steps = Steps::default();
    // One leaf for the lanes `on`: a step each, its primitives tested; the
    // lanes with a hit clearly inside it are done. Returns where each lane
    // leaves it; `None` for a leaf whose references lie outside the tree.
    let mut test = |leaf: u32, on: &mut M8, steps: &mut Steps| -> Option<(F8, [u8; LANES], M8)> {
        steps.leaves += on.count() as u64;
        let refs = tree.leaf_refs(tree.node(leaf))?;
        let exits = p.leaf_exit(tree.rope(leaf));
        let done = v.visit(tree, p, refs, *on, exits.0.min(t1));
        *on = *on & !done;
        Some(exits)
    };
    // The common leaves, as walk_common visits them: a run of empty leaves
    // is one step and no test.
    let mut leaf = 0;
    let mut exits = None;
    for (node, run) in leaves {
        leaf = node;
        exits = None;
        if run {
            let lanes = on.count() as u64;
            steps.leaves += lanes;
            steps.empty += lanes;
        } else {
            exits = Some(test(leaf, &mut on, &mut steps)?);
        }
    }
    let (mut t_exit, mut faces, mut at_edge) =
        exits.unwrap_or_else(|| p.leaf_exit(tree.rope(leaf)));
    let mut cursors = [Cursor::new(paths, 0); LANES];
    for (c, &near) in cursors.iter_mut().zip(nearest) {
        *c = Cursor::new(paths, near);
    }
    // By ropes, together while the lanes leave alike into a leaf.
    for _ in 0..tree.ropes.len() {
        // A lane whose segment ends in this leaf is done, hit or not.
        on = on & !t_exit.gt(t1);
        let Some(first) = (0..LANES).find(|&i| on.get(i)) else {
            break;
        };
        // A lane through an edge or corner goes on alone (and so
        // hierarchically, as its single ray).
        let face = faces[first];
        if (0..LANES).any(|i| on.get(i) && faces[i] != face) || (on & at_edge).any() {
            break;
        }
        let rope = tree.rope(leaf).neighbor[face as usize];
        if rope == NO_NODE {
            // Out of the scene: the lanes keep what they found.
            on = M8::NONE;
            break;
        }
        // A rope to an interior node: each lane finds its leaf alone.
        if !tree.node(rope).is_leaf() {
            break;
        }
        for (i, c) in cursors.iter_mut().enumerate() {
            if on.get(i) {
                c.follow(paths, rope);
            }
        }
        leaf = rope;
        if tree.leaf_is_empty(leaf) {
            steps.empty += on.count() as u64;
        }
        (t_exit, faces, at_edge) = test(leaf, &mut on, &mut steps)?;
    }
    steps.flush(stats);
    stats.rays += hits.len() as u64;
    stats.prim_tests += v.tests();
    for (i, hit) in hits.iter_mut().enumerate() {
        *hit = v.best[i];
        if !on.get(i) {
            continue;
        }
        // Alone from `leaf` on, as the single ray goes on from there.
        let mut c = Closest::new(&rays[i]);
        c.best = v.best[i];
        let mut own = Steps::default();
        let done = guide::walk_past(
            tree,
            &mut c,
            leaf,
            t1.0[i],
            paths,
            &mut cursors[i],
            &mut own,
        );
        *hit = guide::finish(tree, &mut c, done, stack, own, stats);
    }
    Some(())
}
