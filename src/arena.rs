//! Byte layouts of caller arenas: the formulas written once that turn element
//! counts into bytes and a byte budget back into counts. The C ABI carves
//! arenas with these; the core itself only ever sees typed slices.
//!
//! A kd-tree arena is `[KdInfo | nodes | leaves | ropes | refs]`, each part
//! starting on a multiple of [`ARENA_ALIGN`] from the arena's start, found
//! from offsets in the header: the arena can be copied anywhere aligned.

use crate::kd::{KdEvent, KdInfo, KdLeaf, KdNode, KdRequirements, KdRopes};
use core::mem::size_of;

/// Alignment every arena's start must have, and that every part keeps.
pub const ARENA_ALIGN: usize = 16;

/// Bytes reserved for the header at the start of a tree arena.
pub const KD_HEADER_BYTES: usize = 128;

/// Rounds `n` up to a multiple of [`ARENA_ALIGN`].
pub const fn align_up(n: usize) -> usize {
    (n + ARENA_ALIGN - 1) & !(ARENA_ALIGN - 1)
}

/// Where each part of a kd-tree arena lies, in bytes from its start, and how
/// many elements it holds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct KdArenaLayout {
    /// Element counts.
    pub counts: KdRequirements,
    /// Offset of the nodes.
    pub nodes_offset: usize,
    /// Offset of the leaf records.
    pub leaves_offset: usize,
    /// Offset of the ropes.
    pub ropes_offset: usize,
    /// Offset of the references.
    pub refs_offset: usize,
    /// Bytes the layout covers.
    pub total_bytes: usize,
}

impl KdArenaLayout {
    /// Layout of the tree part (nodes, leaves, ropes, refs) of `counts`.
    pub fn of(counts: &KdRequirements) -> KdArenaLayout {
        const _: () = assert!(size_of::<KdInfo>() <= KD_HEADER_BYTES);
        let nodes_offset = KD_HEADER_BYTES;
        let leaves_offset = nodes_offset + align_up(counts.nodes * size_of::<KdNode>());
        let ropes_offset = leaves_offset + align_up(counts.leaves * size_of::<KdLeaf>());
        let refs_offset = ropes_offset + align_up(counts.ropes * size_of::<KdRopes>());
        let total_bytes = refs_offset + align_up(counts.refs * size_of::<u32>());
        KdArenaLayout {
            counts: *counts,
            nodes_offset,
            leaves_offset,
            ropes_offset,
            refs_offset,
            total_bytes,
        }
    }

    /// The largest layout between `min` and `ideal` that fits in `bytes`, or
    /// `None` when even `min` does not. Counts grow together, in 1024 steps
    /// from `min` to `ideal`, so more bytes never give fewer elements.
    pub fn fit(
        bytes: usize,
        min: &KdRequirements,
        ideal: &KdRequirements,
    ) -> Option<KdArenaLayout> {
        let at = |k: usize| {
            let lerp = |a: usize, b: usize| a + (b.saturating_sub(a)) * k / 1024;
            let leaves = lerp(min.leaves, ideal.leaves);
            KdArenaLayout::of(&KdRequirements {
                nodes: lerp(min.nodes, ideal.nodes).min(2 * leaves - 1),
                leaves,
                ropes: leaves,
                refs: lerp(min.refs, ideal.refs),
                events: 0,
                prim_flags: 0,
            })
        };
        if at(0).total_bytes > bytes {
            return None;
        }
        let (mut lo, mut hi) = (0usize, 1024usize);
        while lo < hi {
            let mid = (lo + hi).div_ceil(2);
            if at(mid).total_bytes <= bytes {
                lo = mid;
            } else {
                hi = mid - 1;
            }
        }
        Some(at(lo))
    }
}

/// Where the parts of a kd build's scratch arena lie: `[prim flags | events]`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct KdScratchLayout {
    /// Bytes of primitive flags at offset 0.
    pub prim_flags: usize,
    /// Offset of the events.
    pub events_offset: usize,
    /// Events that fit.
    pub events: usize,
}

impl KdScratchLayout {
    /// Bytes of scratch holding `counts.events` events.
    pub fn bytes_for(counts: &KdRequirements) -> usize {
        align_up(counts.prim_flags) + counts.events * size_of::<KdEvent>()
    }

    /// The scratch layout of `bytes` bytes for `prim_count` primitives, or
    /// `None` when it holds fewer than `min_events` events.
    pub fn fit(bytes: usize, prim_count: usize, min_events: usize) -> Option<KdScratchLayout> {
        let events_offset = align_up(prim_count);
        let events = bytes.checked_sub(events_offset)? / size_of::<KdEvent>();
        (events >= min_events).then_some(KdScratchLayout {
            prim_flags: prim_count,
            events_offset,
            events,
        })
    }
}
