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
        const _: () = assert!(size_of::<KdArenaHeader>() <= KD_HEADER_BYTES);
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

/// The header at the start of a kd-tree arena: the tree's [`KdInfo`] and
/// where its parts lie. Offsets, never pointers: the arena is relocatable.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub struct KdArenaHeader {
    /// Counts, bounds, scene fingerprint, magic and version.
    pub info: KdInfo,
    /// Bytes of the arena the layout covers.
    pub layout_bytes: u32,
    /// Capacity of the node part.
    pub nodes_cap: u32,
    /// Capacity of the leaf and rope parts.
    pub leaves_cap: u32,
    /// Capacity of the reference part.
    pub refs_cap: u32,
    /// Byte offset of the nodes.
    pub nodes_offset: u32,
    /// Byte offset of the leaf records.
    pub leaves_offset: u32,
    /// Byte offset of the ropes.
    pub ropes_offset: u32,
    /// Byte offset of the references.
    pub refs_offset: u32,
}

impl KdArenaHeader {
    /// The header describing `layout` for a tree with `info`.
    pub fn new(info: KdInfo, layout: &KdArenaLayout) -> KdArenaHeader {
        let c = &layout.counts;
        KdArenaHeader {
            info,
            layout_bytes: layout.total_bytes as u32,
            nodes_cap: c.nodes as u32,
            leaves_cap: c.leaves as u32,
            refs_cap: c.refs as u32,
            nodes_offset: layout.nodes_offset as u32,
            leaves_offset: layout.leaves_offset as u32,
            ropes_offset: layout.ropes_offset as u32,
            refs_offset: layout.refs_offset as u32,
        }
    }

    /// The layout this header claims, if it is the one the formulas give
    /// for its capacities, fits in `arena_bytes`, and the counts in its
    /// info fit the capacities. O(1): the tree itself is checked by
    /// [`crate::kd::KdTree::validate`].
    pub fn layout(&self, arena_bytes: usize) -> Result<KdArenaLayout, crate::Error> {
        let corrupt = |what| Err(crate::Error::Corrupt { what });
        if self.info.magic != crate::kd::KD_MAGIC {
            return corrupt("magic");
        }
        if self.info.version != crate::kd::KD_VERSION {
            return corrupt("version");
        }
        let counts = KdRequirements {
            nodes: self.nodes_cap as usize,
            leaves: self.leaves_cap as usize,
            ropes: self.leaves_cap as usize,
            refs: self.refs_cap as usize,
            events: 0,
            prim_flags: 0,
        };
        let layout = KdArenaLayout::of(&counts);
        if KdArenaHeader::new(self.info, &layout) != *self {
            return corrupt("layout");
        }
        if layout.total_bytes > arena_bytes {
            return corrupt("arena shorter than its layout");
        }
        let i = &self.info;
        if i.node_count > self.nodes_cap
            || i.leaf_count > self.leaves_cap
            || i.ref_count > self.refs_cap
        {
            return corrupt("counts");
        }
        Ok(layout)
    }
}

/// Where the parts of an image-casting scratch arena lie:
/// `[records | entries | corners | starts | hlcts]`, each 16-byte aligned.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ImageScratchLayout {
    /// Element counts.
    pub counts: crate::lcts::ImageRequirements,
    /// Byte offsets of the five parts, in the order above.
    pub offsets: [usize; 5],
    /// Bytes the layout covers.
    pub total_bytes: usize,
}

impl ImageScratchLayout {
    /// The layout of `counts`.
    pub fn of(counts: &crate::lcts::ImageRequirements) -> ImageScratchLayout {
        use crate::lcts::hlcts::HlctsEntry;
        use crate::lcts::{CornerInfo, HistoryRecord};
        let sizes = [
            counts.records * size_of::<HistoryRecord>(),
            counts.entries * size_of::<u32>(),
            counts.corners * size_of::<CornerInfo>(),
            counts.starts * size_of::<u32>(),
            counts.hlcts * size_of::<HlctsEntry>(),
        ];
        let mut offsets = [0usize; 5];
        let mut at = 0;
        for (o, s) in offsets.iter_mut().zip(sizes) {
            *o = at;
            at += align_up(s);
        }
        ImageScratchLayout {
            counts: *counts,
            offsets,
            total_bytes: at,
        }
    }
}

/// Bytes reserved for the header at the start of a hierarchy arena.
pub const BVH_HEADER_BYTES: usize = 128;

/// Magic word of a hierarchy arena: "CRBV".
pub const BVH_MAGIC: u32 = u32::from_le_bytes(*b"CRBV");
/// Layout version of [`BvhArenaHeader`] and [`crate::bvh::BvhNode`].
pub const BVH_VERSION: u32 = 1;

/// [`BvhArenaHeader::rtree_flags`]: the R*-tree's rules.
pub const BVH_FLAG_RSTAR: u32 = 1;
/// [`BvhArenaHeader::rtree_flags`]: forced reinsertion.
pub const BVH_FLAG_REINSERT: u32 = 2;

/// Where the parts of a hierarchy arena lie: `[header | nodes | refs]`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BvhArenaLayout {
    /// Node slots.
    pub nodes: usize,
    /// Reference slots.
    pub refs: usize,
    /// Offset of the nodes.
    pub nodes_offset: usize,
    /// Offset of the references.
    pub refs_offset: usize,
    /// Bytes the layout covers.
    pub total_bytes: usize,
}

impl BvhArenaLayout {
    /// The layout holding `nodes` node slots and `refs` references.
    pub fn of(nodes: usize, refs: usize) -> BvhArenaLayout {
        const _: () = assert!(size_of::<BvhArenaHeader>() <= BVH_HEADER_BYTES);
        let nodes_offset = BVH_HEADER_BYTES;
        let refs_offset =
            nodes_offset + align_up(nodes.saturating_mul(size_of::<crate::bvh::BvhNode>()));
        BvhArenaLayout {
            nodes,
            refs,
            nodes_offset,
            refs_offset,
            total_bytes: refs_offset.saturating_add(align_up(refs.saturating_mul(4))),
        }
    }
}

/// Where the parts of a hierarchy build's scratch arena lie:
/// `[boxes | keys | links | clusters]` for the static builders, the
/// insertion order (`links`) alone for R-trees.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BvhScratchLayout {
    /// Element counts.
    pub counts: crate::bvh::BvhRequirements,
    /// Offset of the keys.
    pub keys_offset: usize,
    /// Offset of the links.
    pub links_offset: usize,
    /// Offset of the clusters.
    pub clusters_offset: usize,
    /// Bytes the layout covers.
    pub total_bytes: usize,
}

impl BvhScratchLayout {
    /// The scratch layout of `counts`.
    pub fn of(counts: &crate::bvh::BvhRequirements) -> BvhScratchLayout {
        let keys_offset = align_up(counts.boxes * size_of::<crate::Aabb>());
        let links_offset = keys_offset + align_up(counts.keys * 4);
        let clusters_offset = links_offset + align_up(counts.links * 4);
        let total_bytes = clusters_offset + counts.clusters * size_of::<crate::bvh::BvhNode>();
        BvhScratchLayout {
            counts: *counts,
            keys_offset,
            links_offset,
            clusters_offset,
            total_bytes,
        }
    }
}

/// The header at the start of a hierarchy arena: which builder made it,
/// the scene it was built on, its [`crate::bvh::BvhInfo`], an R-tree's
/// parameters and state, and where the parts lie.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[repr(C)]
pub struct BvhArenaHeader {
    /// [`BVH_MAGIC`].
    pub magic: u32,
    /// [`BVH_VERSION`].
    pub version: u32,
    /// The builder (the C ABI's `CORAY_BVH_*` numbers).
    pub builder: u32,
    /// Triangles, spheres and cones of the scene built on.
    pub scene_counts: [u32; 3],
    /// Shape of the hierarchy.
    pub info: crate::bvh::BvhInfo,
    /// R-trees: M and m (0 for the static builders).
    pub max_children: u32,
    /// See `max_children`.
    pub min_children: u32,
    /// R-trees: [`BVH_FLAG_RSTAR`] and [`BVH_FLAG_REINSERT`].
    pub rtree_flags: u32,
    /// R-trees: free lists and counts.
    pub rtree: crate::bvh::RTreeState,
    /// Bytes of the arena the layout covers.
    pub layout_bytes: u32,
    /// Node slots.
    pub nodes_cap: u32,
    /// Reference slots.
    pub refs_cap: u32,
    /// Most objects the hierarchy may hold: the static builders' object
    /// count; for an R-tree, what its layout holds in the worst case
    /// (inserts beyond it are refused, so deletes' scratch stays bounded).
    pub capacity: u32,
}

impl BvhArenaHeader {
    /// Checks magic, version and that the layout the capacities give fits in
    /// `arena_bytes` and matches `layout_bytes`; O(1). The hierarchy itself
    /// is checked by [`crate::bvh::Bvh::validate`] and [`crate::bvh::RTree::validate`].
    pub fn layout(&self, arena_bytes: usize) -> Result<BvhArenaLayout, crate::Error> {
        let corrupt = |what| Err(crate::Error::Corrupt { what });
        if self.magic != BVH_MAGIC {
            return corrupt("magic");
        }
        if self.version != BVH_VERSION {
            return corrupt("version");
        }
        let l = BvhArenaLayout::of(self.nodes_cap as usize, self.refs_cap as usize);
        if l.total_bytes != self.layout_bytes as usize {
            return corrupt("layout");
        }
        if l.total_bytes > arena_bytes {
            return corrupt("arena shorter than its layout");
        }
        let i = &self.info;
        if i.root >= self.nodes_cap
            || i.node_count > self.nodes_cap
            || i.ref_count > self.refs_cap
            || i.ref_count > self.capacity
        {
            return corrupt("counts");
        }
        Ok(l)
    }
}

/// Bytes reserved for the header at the start of a projection arena.
pub const PROJ_HEADER_BYTES: usize = 128;
/// Magic word of a projection arena: "CRPJ".
pub const PROJ_MAGIC: u32 = u32::from_le_bytes(*b"CRPJ");
/// Layout version of [`ProjArenaHeader`] and [`crate::proj::Rect`].
pub const PROJ_VERSION: u32 = 1;

/// Where the parts of a projection arena lie:
/// `[header | nodes | refs | rects | prim_rects]`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ProjArenaLayout {
    /// Node slots (and node rectangles).
    pub nodes: usize,
    /// Reference slots.
    pub refs: usize,
    /// Primitive rectangles.
    pub prim_rects: usize,
    /// Offset of the nodes.
    pub nodes_offset: usize,
    /// Offset of the references.
    pub refs_offset: usize,
    /// Offset of the node rectangles.
    pub rects_offset: usize,
    /// Offset of the primitive rectangles.
    pub prim_rects_offset: usize,
    /// Bytes the layout covers.
    pub total_bytes: usize,
}

impl ProjArenaLayout {
    /// The layout for these counts.
    pub fn of(nodes: usize, refs: usize, prim_rects: usize) -> ProjArenaLayout {
        const _: () = assert!(size_of::<ProjArenaHeader>() <= PROJ_HEADER_BYTES);
        let rect = size_of::<crate::proj::Rect>();
        let nodes_offset = PROJ_HEADER_BYTES;
        let refs_offset =
            nodes_offset + align_up(nodes.saturating_mul(size_of::<crate::bvh::BvhNode>()));
        let rects_offset = refs_offset + align_up(refs.saturating_mul(4));
        let prim_rects_offset = rects_offset + align_up(nodes.saturating_mul(rect));
        let total_bytes =
            prim_rects_offset.saturating_add(align_up(prim_rects.saturating_mul(rect)));
        ProjArenaLayout {
            nodes,
            refs,
            prim_rects,
            nodes_offset,
            refs_offset,
            rects_offset,
            prim_rects_offset,
            total_bytes,
        }
    }
}

/// The header at the start of a projection arena.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub struct ProjArenaHeader {
    /// [`PROJ_MAGIC`].
    pub magic: u32,
    /// [`PROJ_VERSION`].
    pub version: u32,
    /// The builder (the C ABI's `CORAY_BVH_*` numbers).
    pub builder: u32,
    /// 0: built on the rectangles; 1: dummy (3D structure).
    pub criteria: u32,
    /// Triangles, spheres and cones of the scene built on.
    pub scene_counts: [u32; 3],
    /// Shape of the hierarchy.
    pub info: crate::bvh::BvhInfo,
    /// 0: perspective; 1: orthographic.
    pub plane_kind: u32,
    /// The plane: eye, right, up, forward (eye unused when orthographic).
    pub plane: [f32; 12],
    /// Bytes of the arena the layout covers.
    pub layout_bytes: u32,
    /// Node slots.
    pub nodes_cap: u32,
    /// Reference slots.
    pub refs_cap: u32,
    /// Primitive rectangles.
    pub prim_rects_cap: u32,
}

impl ProjArenaHeader {
    /// The plane the header records.
    pub fn plane(&self) -> crate::proj::ProjPlane {
        let v = |i: usize| crate::Vec3::new(self.plane[i], self.plane[i + 1], self.plane[i + 2]);
        if self.plane_kind == 1 {
            crate::proj::ProjPlane::Orthographic {
                right: v(3),
                up: v(6),
                forward: v(9),
            }
        } else {
            crate::proj::ProjPlane::Perspective {
                eye: v(0),
                right: v(3),
                up: v(6),
                forward: v(9),
            }
        }
    }

    /// Records `p`.
    pub fn set_plane(&mut self, p: &crate::proj::ProjPlane) {
        let (eye, kind) = match *p {
            crate::proj::ProjPlane::Perspective { eye, .. } => (eye, 0),
            crate::proj::ProjPlane::Orthographic { .. } => (crate::Vec3::ZERO, 1),
        };
        let (r, u, f) = p.axes();
        self.plane_kind = kind;
        for (i, v) in [eye, r, u, f].iter().enumerate() {
            self.plane[3 * i..3 * i + 3].copy_from_slice(&v.to_array());
        }
    }

    /// Checks magic, version and layout (O(1)), as [`BvhArenaHeader::layout`].
    pub fn layout(&self, arena_bytes: usize) -> Result<ProjArenaLayout, crate::Error> {
        let corrupt = |what| Err(crate::Error::Corrupt { what });
        if self.magic != PROJ_MAGIC {
            return corrupt("magic");
        }
        if self.version != PROJ_VERSION {
            return corrupt("version");
        }
        if self.plane_kind > 1 || self.criteria > 1 || !self.plane.iter().all(|x| x.is_finite()) {
            return corrupt("plane or criteria");
        }
        let l = ProjArenaLayout::of(
            self.nodes_cap as usize,
            self.refs_cap as usize,
            self.prim_rects_cap as usize,
        );
        if l.total_bytes != self.layout_bytes as usize {
            return corrupt("layout");
        }
        if l.total_bytes > arena_bytes {
            return corrupt("arena shorter than its layout");
        }
        let i = &self.info;
        if i.root >= self.nodes_cap || i.node_count > self.nodes_cap || i.ref_count > self.refs_cap
        {
            return corrupt("counts");
        }
        Ok(l)
    }
}
