//! Byte layouts of kd-tree arenas: `[KdArenaHeader | nodes | ropes |
//! rope ids | refs]` for the tree (the two rope parts empty without
//! ropes), `[prim flags | events]` for a build's scratch. Counts in, bytes
//! out, checked ([`crate::arena::Parts`]).

use super::{KdEvent, KdInfo, KdNode, KdRequirements, KdRopes, KD_MAGIC, KD_VERSION};
use crate::arena::Parts;
use crate::Error;
use core::mem::size_of;

/// Bytes reserved for the header at the start of a tree arena.
pub const KD_HEADER_BYTES: usize = 128;

/// Where each part of a kd-tree arena lies, in bytes from its start, and
/// how many elements it holds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct KdArenaLayout {
    /// Element counts.
    pub counts: KdRequirements,
    /// Offset of the nodes.
    pub nodes_offset: usize,
    /// Offset of the rope records.
    pub ropes_offset: usize,
    /// Offset of the rope index (a `u32` per node).
    pub rope_ids_offset: usize,
    /// Offset of the references.
    pub refs_offset: usize,
    /// Bytes the layout covers.
    pub total_bytes: usize,
}

impl KdArenaLayout {
    /// Layout of the tree part (nodes, ropes, rope ids, refs) of `counts`,
    /// or `None` past [`crate::limits::MAX_ARENA_BYTES`].
    pub fn of(counts: &KdRequirements) -> Option<KdArenaLayout> {
        const _: () = assert!(size_of::<KdArenaHeader>() <= KD_HEADER_BYTES);
        let mut p = Parts::after(KD_HEADER_BYTES);
        let nodes_offset = p.push::<KdNode>(counts.nodes)?;
        let ropes_offset = p.push::<KdRopes>(counts.ropes)?;
        let rope_ids_offset = p.push::<u32>(counts.rope_ids)?;
        let refs_offset = p.push::<u32>(counts.refs)?;
        Some(KdArenaLayout {
            counts: *counts,
            nodes_offset,
            ropes_offset,
            rope_ids_offset,
            refs_offset,
            total_bytes: p.total()?,
        })
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
            let lerp = |a: usize, b: usize| {
                a + ((b.saturating_sub(a)) as u128 * k as u128 / 1024) as usize
            };
            let nodes = lerp(min.nodes, ideal.nodes);
            KdArenaLayout::of(&KdRequirements {
                nodes,
                ropes: if ideal.ropes > 0 {
                    nodes.div_ceil(2)
                } else {
                    0
                },
                rope_ids: if ideal.rope_ids > 0 { nodes } else { 0 },
                refs: lerp(min.refs, ideal.refs),
                events: 0,
                prim_flags: 0,
            })
        };
        let fits = |k: usize| at(k).is_some_and(|l| l.total_bytes <= bytes);
        if !fits(0) {
            return None;
        }
        let (mut lo, mut hi) = (0usize, 1024usize);
        while lo < hi {
            let mid = (lo + hi).div_ceil(2);
            if fits(mid) {
                lo = mid;
            } else {
                hi = mid - 1;
            }
        }
        at(lo)
    }

    /// The layout holding exactly what a tree with `info` uses.
    pub fn tight(info: &KdInfo) -> Option<KdArenaLayout> {
        let n = |x: u32| x as usize;
        KdArenaLayout::of(&KdRequirements {
            nodes: n(info.node_count),
            ropes: n(info.rope_count()),
            rope_ids: n(info.rope_id_count()),
            refs: n(info.ref_count),
            events: 0,
            prim_flags: 0,
        })
    }

    /// Bytes of an arena holding exactly what a tree with `info` uses.
    pub fn used_by(info: &KdInfo) -> Option<usize> {
        Some(KdArenaLayout::tight(info)?.total_bytes)
    }

    /// Moves the parts of a tree with `info`, built in `arena` laid out as
    /// `self`, to the [`KdArenaLayout::tight`] layout at the arena's start,
    /// and zeroes the rest of `self`'s bytes: the tree then needs only the
    /// tight layout's bytes (a caller may shrink or copy the arena to them).
    /// The header is left to the caller. `None` (nothing moved) when the
    /// counts exceed this layout's or the arena is shorter than it.
    pub fn pack(&self, info: &KdInfo, arena: &mut [u8]) -> Option<KdArenaLayout> {
        let tight = KdArenaLayout::tight(info)?;
        let (c, t) = (&self.counts, &tight.counts);
        if t.nodes > c.nodes || t.ropes > c.ropes || t.rope_ids > c.rope_ids || t.refs > c.refs {
            return None;
        }
        let arena = arena.get_mut(..self.total_bytes)?;
        // Parts keep their order and shrink, so each one's new place ends
        // before the next one's old place starts: moving them in order
        // never overwrites a part not yet moved.
        let parts = [
            (
                self.nodes_offset,
                tight.nodes_offset,
                t.nodes * size_of::<KdNode>(),
            ),
            (
                self.ropes_offset,
                tight.ropes_offset,
                t.ropes * size_of::<KdRopes>(),
            ),
            (
                self.rope_ids_offset,
                tight.rope_ids_offset,
                t.rope_ids * size_of::<u32>(),
            ),
            (
                self.refs_offset,
                tight.refs_offset,
                t.refs * size_of::<u32>(),
            ),
        ];
        for (from, to, bytes) in parts {
            arena.copy_within(from..from + bytes, to);
        }
        // The padding between parts is zero, whatever the build left there
        // (the job build leaves its shares' spare slots behind): a tree's
        // bytes depend on the tree alone.
        let ends = parts.map(|(_, to, bytes)| to + bytes);
        let starts = [
            tight.ropes_offset,
            tight.rope_ids_offset,
            tight.refs_offset,
            tight.total_bytes,
        ];
        for (end, next) in ends.into_iter().zip(starts) {
            arena[end..next].fill(0);
        }
        arena[tight.total_bytes..].fill(0);
        Some(tight)
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
    /// Bytes the layout covers.
    pub total_bytes: usize,
}

impl KdScratchLayout {
    /// The layout holding `counts.prim_flags` flags and `counts.events` events.
    pub fn of(counts: &KdRequirements) -> Option<KdScratchLayout> {
        let mut p = Parts::after(0);
        p.push::<u8>(counts.prim_flags)?;
        let events_offset = p.push::<KdEvent>(counts.events)?;
        Some(KdScratchLayout {
            prim_flags: counts.prim_flags,
            events_offset,
            events: counts.events,
            total_bytes: p.total()?,
        })
    }

    /// The scratch layout of `bytes` bytes for `prim_count` primitives, or
    /// `None` when it holds fewer than `min_events` events.
    pub fn fit(bytes: usize, prim_count: usize, min_events: usize) -> Option<KdScratchLayout> {
        let events_offset = crate::arena::align_up(prim_count)?;
        let events = bytes.checked_sub(events_offset)? / size_of::<KdEvent>();
        if events < min_events {
            return None;
        }
        KdScratchLayout::of(&KdRequirements {
            prim_flags: prim_count,
            events,
            ..KdRequirements::default()
        })
    }
}

/// The header at the start of a kd-tree arena: the tree's [`KdInfo`] and
/// where its parts lie. Offsets, never pointers: the arena is relocatable.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub struct KdArenaHeader {
    /// Counts, bounds, scene fingerprint, magic and version.
    pub info: KdInfo,
    /// Bytes of the arena the layout covers.
    pub layout_bytes: u32,
    /// Capacity of the node part (and of the rope index when the info's
    /// [`KdInfo::has_ropes`]; else that part is empty).
    pub nodes_cap: u32,
    /// Capacity of the rope part (0 without ropes).
    pub ropes_cap: u32,
    /// Capacity of the reference part.
    pub refs_cap: u32,
    /// Byte offset of the nodes.
    pub nodes_offset: u32,
    /// Byte offset of the ropes.
    pub ropes_offset: u32,
    /// Byte offset of the rope index.
    pub rope_ids_offset: u32,
    /// Byte offset of the references.
    pub refs_offset: u32,
}

impl KdArenaHeader {
    /// The header describing `layout` for a tree with `info`.
    pub fn new(info: KdInfo, layout: &KdArenaLayout) -> KdArenaHeader {
        let c = &layout.counts;
        // Every value below fits: layouts stop at MAX_ARENA_BYTES = u32::MAX.
        KdArenaHeader {
            info,
            layout_bytes: layout.total_bytes as u32,
            nodes_cap: c.nodes as u32,
            ropes_cap: c.ropes as u32,
            refs_cap: c.refs as u32,
            nodes_offset: layout.nodes_offset as u32,
            ropes_offset: layout.ropes_offset as u32,
            rope_ids_offset: layout.rope_ids_offset as u32,
            refs_offset: layout.refs_offset as u32,
        }
    }

    /// The layout this header claims, if it is the one the formulas give
    /// for its capacities, fits in `arena_bytes`, and the counts in its
    /// info fit the capacities. O(1): the tree itself is checked by
    /// [`super::KdTree::validate`].
    pub fn layout(&self, arena_bytes: usize) -> Result<KdArenaLayout, Error> {
        let corrupt = |what| Err(Error::Corrupt { what });
        if self.info.magic != KD_MAGIC {
            return corrupt("magic");
        }
        if self.info.version != KD_VERSION {
            return corrupt("version");
        }
        // With ropes, the rope index has an entry per node slot.
        let ropes = self.info.has_ropes();
        let counts = KdRequirements {
            nodes: self.nodes_cap as usize,
            ropes: self.ropes_cap as usize,
            rope_ids: if ropes { self.nodes_cap as usize } else { 0 },
            refs: self.refs_cap as usize,
            events: 0,
            prim_flags: 0,
        };
        let Some(layout) = KdArenaLayout::of(&counts) else {
            return corrupt("layout");
        };
        if KdArenaHeader::new(self.info, &layout) != *self {
            return corrupt("layout");
        }
        if layout.total_bytes > arena_bytes {
            return corrupt("arena shorter than its layout");
        }
        let i = &self.info;
        if i.node_count > self.nodes_cap
            || i.rope_count() > self.ropes_cap
            || i.ref_count > self.refs_cap
        {
            return corrupt("counts");
        }
        Ok(layout)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A tree with ropes: `ropes` records, one rope index entry per node.
    fn counts(nodes: usize, ropes: usize, refs: usize) -> KdRequirements {
        KdRequirements {
            nodes,
            ropes,
            rope_ids: nodes,
            refs,
            events: 0,
            prim_flags: 0,
        }
    }

    #[test]
    fn parts_follow_the_header_aligned() {
        let l = KdArenaLayout::of(&counts(3, 2, 5)).unwrap();
        assert_eq!(l.nodes_offset, KD_HEADER_BYTES);
        assert_eq!(l.ropes_offset, KD_HEADER_BYTES + 32);
        assert_eq!(l.rope_ids_offset, l.ropes_offset + 96);
        assert_eq!(l.refs_offset, l.rope_ids_offset + 16);
        assert_eq!(l.total_bytes, l.refs_offset + 32);
        assert!([
            l.ropes_offset,
            l.rope_ids_offset,
            l.refs_offset,
            l.total_bytes
        ]
        .iter()
        .all(|o| o % 16 == 0));
    }

    #[test]
    fn counts_near_the_limit_give_no_layout() {
        // Issue 16: 0x2000_0001 node slots wrapped to a 224-byte layout on 32 bits.
        assert!(KdArenaLayout::of(&counts(0x2000_0001, 1, 1)).is_none());
        assert!(KdArenaLayout::of(&counts(1, usize::MAX / 8, 1)).is_none());
        assert!(KdArenaLayout::of(&counts(1, 1, usize::MAX)).is_none());
        let h = KdArenaHeader {
            nodes_cap: 0x2000_0001,
            info: KdInfo {
                magic: KD_MAGIC,
                version: KD_VERSION,
                ..KdInfo::default()
            },
            ..KdArenaHeader::default()
        };
        assert!(h.layout(usize::MAX).is_err());
    }

    #[test]
    fn pack_moves_each_part_to_the_tight_layout_and_zeroes_the_rest() {
        let room = KdArenaLayout::of(&counts(9, 5, 12)).unwrap();
        let info = KdInfo {
            node_count: 5,
            leaf_count: 3,
            ref_count: 7,
            flags: crate::kd::KD_FLAG_ROPES,
            ..KdInfo::default()
        };
        let tight = KdArenaLayout::tight(&info).unwrap();
        // Without ropes both rope parts are empty: the references follow
        // the nodes.
        let plain = KdArenaLayout::tight(&KdInfo { flags: 0, ..info }).unwrap();
        assert_eq!((plain.counts.ropes, plain.counts.rope_ids), (0, 0));
        assert_eq!(plain.ropes_offset, plain.refs_offset);
        assert_eq!(plain.rope_ids_offset, plain.refs_offset);
        // 3 rope records, 5 rope index entries padded to 32 bytes.
        assert_eq!(plain.total_bytes + 3 * 48 + 32, tight.total_bytes);
        // Every used byte of a part holds its part's tag and its index.
        let mut arena = [0xEEu8; 1024];
        assert!(room.total_bytes < arena.len());
        let used = |l: &KdArenaLayout| {
            [
                (l.nodes_offset, 5 * 8),
                (l.ropes_offset, 3 * 48),
                (l.rope_ids_offset, 5 * 4),
                (l.refs_offset, 7 * 4),
            ]
        };
        for (k, (o, n)) in used(&room).into_iter().enumerate() {
            for i in 0..n {
                arena[o + i] = (k * 64 + i % 61) as u8;
            }
        }
        assert_eq!(room.pack(&info, &mut arena), Some(tight));
        for (k, (o, n)) in used(&tight).into_iter().enumerate() {
            for i in 0..n {
                assert_eq!(arena[o + i], (k * 64 + i % 61) as u8, "part {k} byte {i}");
            }
        }
        assert!(arena[tight.total_bytes..room.total_bytes]
            .iter()
            .all(|&b| b == 0));
        assert!(
            arena[room.total_bytes..].iter().all(|&b| b == 0xEE),
            "past the room"
        );
        let too_many = KdInfo {
            node_count: 10,
            ..info
        };
        assert_eq!(room.pack(&too_many, &mut arena), None);
        assert_eq!(room.pack(&info, &mut arena[..room.total_bytes - 1]), None);
    }

    #[test]
    fn fit_never_gives_fewer_elements_for_more_bytes() {
        let (min, ideal) = (counts(1, 1, 100), counts(799, 400, 400));
        let mut last = 0;
        for bytes in (0..12_000).step_by(97) {
            if let Some(l) = KdArenaLayout::fit(bytes, &min, &ideal) {
                assert!(l.total_bytes <= bytes);
                assert!(l.counts.refs >= last);
                last = l.counts.refs;
            }
        }
        assert!(KdArenaLayout::fit(0, &min, &ideal).is_none());
    }
}
