//! The kd-tree's stored parts. Every type is plain data (`u32` and `f32`
//! fields, `repr(C)`, no padding), so any bit pattern is a value: the C ABI
//! may view a byte arena as these slices, and [`super::KdTree::validate`]
//! decides whether the values make a tree.

use crate::geom::Aabb;
use glam::{Vec3, Vec3A};

/// "No node": a rope that leads out of the scene, an exit point with no node.
pub const NO_NODE: u32 = u32::MAX;

pub use crate::limits::KD_MAX_DEPTH;

/// Entries of the stack every kd traversal takes ([`KdStackItem`]s): for a
/// packet of 8 rays, one entry of 9 items (node, lanes, 8 entry and 8
/// exit distances) per level of the deepest tree and a few to spare; a
/// single ray uses the first 2 per level.
pub const KD_STACK_LEN: usize = 9 * (KD_MAX_DEPTH as usize + 4);

/// One entry of a kd traversal stack: an exit point of TA_B^rec, the node
/// to visit after the current segment and the ray parameter where that
/// segment ends (and the next node's begins). Plain data: the caller owns
/// the stack.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub struct KdStackItem {
    /// Node to visit next.
    pub node: u32,
    /// Ray parameter where the current segment ends.
    pub t: f32,
}

/// One node in 8 bytes. `word & 3` is the split axis (0, 1, 2) or 3 for a
/// leaf. An interior node's `word >> 4` is the index of its left child
/// (the right one follows it), bit 2 or 3 set says that the left or the
/// right child is an empty leaf not stored (the right child, stored alone,
/// then still lies at `(word >> 4) + 1`: [`KdNode::children`]), and `data`
/// is the split position's bits; a leaf's `word >> 2` is its number of
/// references and `data` the first of them: a leaf is whole in its node,
/// so a traversal reads the references next.
///
/// A compact tree ([`KD_FLAG_COMPACT`]) stores no empty leaf beside a full
/// child (on `random` they are 46% of `auto`'s leaves): its interior node
/// names the full child alone, and the walks read the empty side as node
/// [`SHARED_EMPTY`], one empty leaf the tree keeps at index 1 (statistics
/// count it as the leaf it stands for). Other trees store every child.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[repr(C)]
pub struct KdNode {
    /// Axis or leaf tag in the low two bits; an interior node's elided
    /// child and first child, or a leaf's reference count, above.
    pub word: u32,
    /// `f32::to_bits` of the split position, or a leaf's first reference.
    pub data: u32,
}

/// Node 1 of a compact tree: the empty leaf every elided child stands for
/// ([`KdNode::children`]).
pub const SHARED_EMPTY: u32 = 1;

/// Interior nodes' child indices are below this: 28 bits of `word`
/// ([`crate::limits::KD_MAX_NODES`]).
pub const MAX_CHILD_INDEX: u32 = crate::limits::KD_MAX_NODES as u32;

/// Bit of an interior node's word: its left child is elided.
const ELIDED_LEFT: u32 = 4;
/// Bit of an interior node's word: its right child is elided.
const ELIDED_RIGHT: u32 = 8;

impl KdNode {
    /// What a traversal reads for a node index past the tree: a leaf of
    /// 2^30 - 1 references from the 2^32 - 1st, past any tree's (an arena
    /// stops at 4 GiB), so the walk stops there with a fault.
    pub const FAULT: KdNode = KdNode {
        word: u32::MAX,
        data: u32::MAX,
    };

    /// An empty leaf (what [`SHARED_EMPTY`] holds).
    pub const EMPTY: KdNode = KdNode { word: 3, data: 0 };

    /// An interior node splitting `axis` at `split`, children at `left` and
    /// `left + 1` (`left` below [`MAX_CHILD_INDEX`]).
    pub fn interior(axis: usize, split: f32, left: u32) -> KdNode {
        KdNode {
            word: (left << 4) | axis as u32,
            data: split.to_bits(),
        }
    }

    /// An interior node with one child stored, at `child`, and the other
    /// (the left one when `empty_left`) an empty leaf left out.
    pub fn interior_elided(axis: usize, split: f32, child: u32, empty_left: bool) -> KdNode {
        let elided = if empty_left {
            ELIDED_LEFT
        } else {
            ELIDED_RIGHT
        };
        KdNode {
            word: elided | axis as u32,
            data: split.to_bits(),
        }
        .with_first_stored(child)
    }

    /// A leaf holding references `first_ref..first_ref + ref_count`
    /// (`ref_count` below 2^30).
    pub fn leaf(first_ref: u32, ref_count: u32) -> KdNode {
        KdNode {
            word: (ref_count << 2) | 3,
            data: first_ref,
        }
    }

    /// True for a leaf.
    #[inline]
    pub fn is_leaf(&self) -> bool {
        self.word & 3 == 3
    }

    /// Split axis of an interior node.
    #[inline]
    pub fn axis(&self) -> usize {
        (self.word & 3) as usize
    }

    /// Left child of an interior node that stores both (as every node of
    /// a tree with ropes does); the right one is `left() + 1`.
    #[inline]
    pub fn left(&self) -> u32 {
        self.word >> 4
    }

    /// Which child of an interior node is an elided empty leaf: 0 none,
    /// 1 the left, 2 the right (3 makes no tree; validation refuses it).
    #[inline]
    pub fn elided(&self) -> u32 {
        (self.word >> 2) & 3
    }

    /// Index of an interior node's first stored child.
    #[inline]
    pub fn first_stored(&self) -> u32 {
        self.left()
            .wrapping_add((self.word & ELIDED_LEFT != 0) as u32)
    }

    /// The same interior node with its first stored child at `child`.
    #[inline]
    pub fn with_first_stored(&self, child: u32) -> KdNode {
        let bits = self.word & 15;
        let left = child.wrapping_sub((bits & ELIDED_LEFT != 0) as u32);
        KdNode {
            word: (left << 4) | bits,
            data: self.data,
        }
    }

    /// Number of children an interior node stores (2, or 1 with one elided).
    #[inline]
    pub fn stored_children(&self) -> u32 {
        2 - (self.elided() != 0) as u32
    }

    /// The left and right children of an interior node, an elided one as
    /// [`SHARED_EMPTY`]: two selects on the node's own bits beside the
    /// shift and the add of a node that stores both (no branch, no load).
    #[inline]
    pub fn children(&self) -> (u32, u32) {
        let left = self.left();
        let l = if self.word & ELIDED_LEFT != 0 {
            SHARED_EMPTY
        } else {
            left
        };
        let r = if self.word & ELIDED_RIGHT != 0 {
            SHARED_EMPTY
        } else {
            left.wrapping_add(1)
        };
        (l, r)
    }

    /// A leaf's number of references.
    #[inline]
    pub fn ref_count(&self) -> u32 {
        self.word >> 2
    }

    /// A leaf's first reference.
    #[inline]
    pub fn first_ref(&self) -> u32 {
        self.data
    }

    /// Split position of an interior node.
    #[inline]
    pub fn split(&self) -> f32 {
        f32::from_bits(self.data)
    }
}

/// A leaf's box and its six ropes (Havran; Popov et al. 2007): for each face
/// (order -x, +x, -y, +y, -z, +z) the smallest node whose region covers the
/// whole face from outside, or [`NO_NODE`] on the scene's boundary.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub struct KdRopes {
    /// Neighbour node per face.
    pub neighbor: [u32; 6],
    /// Lower corner of the leaf.
    pub min: [f32; 3],
    /// Upper corner of the leaf.
    pub max: [f32; 3],
}

/// What a traversal reads for a rope record past the tree: no ropes and a
/// NaN box, which no ray enters or leaves.
pub(crate) static FAULT_ROPES: KdRopes = KdRopes {
    neighbor: [NO_NODE; 6],
    min: [f32::NAN; 3],
    max: [f32::NAN; 3],
};

impl KdRopes {
    /// `p`, where a ray leaves the leaf through face `face`, put on that
    /// face exactly: located beyond the face, it cannot round back into
    /// this leaf. Each lane is selected, not written at a run-time index:
    /// an array written there and read back whole is a store the load
    /// spans with another, which waits for both (perf: an eighth of
    /// `guide::next`'s time on SPD lattice).
    #[inline]
    pub(crate) fn onto_face(&self, face: usize, p: Vec3) -> Vec3 {
        let a = face / 2;
        let on = if face % 2 == 1 {
            self.max[a]
        } else {
            self.min[a]
        };
        let lane = |i: usize, x: f32| if a == i { on } else { x };
        Vec3::new(lane(0, p.x), lane(1, p.y), lane(2, p.z))
    }

    /// The leaf's box.
    #[inline]
    pub fn bounds(&self) -> Aabb {
        Aabb {
            min: Vec3::from(self.min),
            max: Vec3::from(self.max),
        }
    }
}

/// Magic word of a kd-tree's [`KdInfo`]: "CRKD".
pub const KD_MAGIC: u32 = u32::from_le_bytes(*b"CRKD");
/// Layout version of [`KdInfo`] and the node types.
pub const KD_VERSION: u32 = 7;

/// Flag in [`KdInfo::flags`]: a capacity stopped splitting somewhere.
pub const KD_FLAG_TRUNCATED: u32 = 1;

/// Flag in [`KdInfo::flags`]: every leaf has a [`KdRopes`] record (the
/// build was asked for ropes, [`crate::kd::KdParams::ropes`]).
pub const KD_FLAG_ROPES: u32 = 2;

/// Flag in [`KdInfo::flags`]: empty leaves beside full ones are left out,
/// node 1 stands for them ([`crate::kd::KdParams::compact`], [`KdNode`]).
pub const KD_FLAG_COMPACT: u32 = 4;

/// Everything about a built tree except its arrays: counts, bounds, the scene
/// fingerprint. Plain data, so a byte arena can carry it as its header.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub struct KdInfo {
    /// [`KD_MAGIC`].
    pub magic: u32,
    /// [`KD_VERSION`].
    pub version: u32,
    /// Triangles in the scene built on.
    pub triangle_count: u32,
    /// Spheres in the scene built on.
    pub sphere_count: u32,
    /// Cones in the scene built on.
    pub cone_count: u32,
    /// Primitives that are not degenerate (the ones in the tree).
    pub valid_prim_count: u32,
    /// Nodes used.
    pub node_count: u32,
    /// Leaves (each has a [`KdRopes`] record when [`KdInfo::has_ropes`]).
    pub leaf_count: u32,
    /// References used.
    pub ref_count: u32,
    /// Depth of the deepest leaf (root has depth 0).
    pub depth: u32,
    /// [`KD_FLAG_TRUNCATED`], [`KD_FLAG_ROPES`], [`KD_FLAG_COMPACT`] and
    /// future flags.
    pub flags: u32,
    /// Lower corner of the root box.
    pub bounds_min: [f32; 3],
    /// Upper corner of the root box.
    pub bounds_max: [f32; 3],
    /// [`crate::rng::ref_digest`] of the references, low and high words.
    pub ref_digest: [u32; 2],
    /// [`crate::rng::node_digest`] of the nodes, low and high words.
    pub node_digest: [u32; 2],
    /// [`Scene::digest`](crate::Scene::digest) of the scene built on, low
    /// and high words.
    pub scene_digest: [u32; 2],
}

impl KdInfo {
    /// The recorded reference digest.
    pub fn ref_digest(&self) -> u64 {
        self.ref_digest[0] as u64 | (self.ref_digest[1] as u64) << 32
    }

    /// The recorded node digest.
    pub fn node_digest(&self) -> u64 {
        self.node_digest[0] as u64 | (self.node_digest[1] as u64) << 32
    }

    /// The recorded scene digest.
    pub fn scene_digest(&self) -> u64 {
        self.scene_digest[0] as u64 | (self.scene_digest[1] as u64) << 32
    }

    /// Root box.
    #[inline]
    pub fn bounds(&self) -> Aabb {
        Aabb {
            min: Vec3::from(self.bounds_min),
            max: Vec3::from(self.bounds_max),
        }
    }

    /// The box every traversal clips rays to: the root box widened by
    /// [`crate::tolerance::LEAF_EXIT_MARGIN`] of its largest coordinate or extent. A primitive's own test
    /// may report a hit point a few ulps outside the root box (a triangle
    /// on the box's face, met at a slant); clipped to the exact box, the
    /// ray's exit point can round onto the wrong side of a split near it,
    /// and a traversal that classifies points would skip the leaf that
    /// holds the hit. All traversals use this one box, so they still agree.
    ///
    /// In SIMD lanes: every one-ray C call builds its view of the tree, and
    /// this box with it.
    #[inline(always)]
    pub fn trace_bounds(&self) -> Aabb {
        let (lo, hi) = (Vec3A::from(self.bounds_min), Vec3A::from(self.bounds_max));
        if !lo.cmple(hi).all() {
            return self.bounds();
        }
        let m = lo.abs().max(hi.abs()).max(hi - lo).max_element();
        let e = Vec3A::splat(m * crate::tolerance::LEAF_EXIT_MARGIN);
        Aabb {
            min: (lo - e).into(),
            max: (hi + e).into(),
        }
    }

    /// True when a capacity made the build stop splitting early.
    pub fn truncated(&self) -> bool {
        self.flags & KD_FLAG_TRUNCATED != 0
    }

    /// True when the tree has ropes (one [`KdRopes`] record per leaf).
    pub fn has_ropes(&self) -> bool {
        self.flags & KD_FLAG_ROPES != 0
    }

    /// True when the tree leaves empty leaves out ([`KD_FLAG_COMPACT`]).
    pub fn is_compact(&self) -> bool {
        self.flags & KD_FLAG_COMPACT != 0
    }

    /// Rope records the tree holds: one per leaf, or none.
    pub fn rope_count(&self) -> u32 {
        if self.has_ropes() {
            self.leaf_count
        } else {
            0
        }
    }

    /// Entries of the tree's rope index (node to rope record): one per
    /// node when it has ropes, else none.
    pub fn rope_id_count(&self) -> u32 {
        if self.has_ropes() {
            self.node_count
        } else {
            0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The trace box in SIMD lanes is the scalar formula's, bit for bit:
    /// boxes tiny and huge, off the origin, flat, a point, and empty.
    #[test]
    fn trace_bounds_are_the_scalar_formula() {
        let scalar = |i: &KdInfo| {
            let b = i.bounds();
            if b.is_empty() {
                return b;
            }
            let m = b
                .min
                .abs()
                .max(b.max.abs())
                .max(b.max - b.min)
                .max_element();
            let e = Vec3::splat(m * crate::tolerance::LEAF_EXIT_MARGIN);
            Aabb {
                min: b.min - e,
                max: b.max + e,
            }
        };
        let mut g = crate::rng::SplitMix64(7);
        let fixed = [
            ([0.0; 3], [0.0; 3]),
            ([1.0, 2.0, 3.0], [1.0, 2.0, 3.0]),
            ([-1e30, 5.0, -2.0], [1e30, 5.0, 4.0]),
            ([1.0, 0.0, 0.0], [0.0, 1.0, 1.0]),
            ([1e-30, -1e-30, 0.0], [2e-30, 1e-30, 1e-38]),
        ];
        let drawn = (0..2000).map(|_| {
            let s = 10f32.powi((g.next_f32() * 40.0) as i32 - 20);
            let o = (g.next_f32() - 0.5) * 1e4 * s;
            let lo = [0; 3].map(|_| o + (g.next_f32() - 0.5) * s);
            let hi = lo.map(|x| x + g.next_f32() * s);
            (lo, hi)
        });
        for (lo, hi) in fixed.into_iter().chain(drawn) {
            let i = KdInfo {
                bounds_min: lo,
                bounds_max: hi,
                ..KdInfo::default()
            };
            let (a, b) = (i.trace_bounds(), scalar(&i));
            let bits = |x: Aabb| {
                (
                    x.min.to_array().map(f32::to_bits),
                    x.max.to_array().map(f32::to_bits),
                )
            };
            assert_eq!(bits(a), bits(b), "{lo:?} {hi:?}");
        }
    }

    /// Interior and leaf words keep axis, split bits and index apart, for
    /// every axis and up to the largest index a build makes (2^30 - 1).
    #[test]
    fn node_words_round_trip() {
        for axis in 0..3 {
            for (split, left) in [(0.5f32, 2u32), (-0.0, 7), (f32::MAX, MAX_CHILD_INDEX - 2)] {
                let n = KdNode::interior(axis, split, left);
                assert!(!n.is_leaf());
                assert_eq!(
                    (n.axis(), n.split().to_bits(), n.left(), n.elided()),
                    (axis, split.to_bits(), left, 0)
                );
                assert_eq!((n.children(), n.stored_children()), ((left, left + 1), 2));
                for empty_left in [false, true] {
                    let e = KdNode::interior_elided(axis, split, left, empty_left);
                    assert!(!e.is_leaf());
                    assert_eq!((e.axis(), e.split(), e.first_stored()), (axis, split, left));
                    let want = if empty_left {
                        (SHARED_EMPTY, left)
                    } else {
                        (left, SHARED_EMPTY)
                    };
                    assert_eq!((e.children(), e.stored_children()), (want, 1));
                    let moved = e.with_first_stored(left + 1);
                    let moved_want = if empty_left {
                        (SHARED_EMPTY, left + 1)
                    } else {
                        (left + 1, SHARED_EMPTY)
                    };
                    assert_eq!((moved.children(), moved.elided()), (moved_want, e.elided()));
                }
                assert_eq!(
                    n.with_first_stored(left + 1).children(),
                    (left + 1, left + 2)
                );
            }
        }
        for (first, count) in [(0u32, 0u32), (u32::MAX, (1 << 30) - 1), (77, 3)] {
            let l = KdNode::leaf(first, count);
            assert!(l.is_leaf() && (l.first_ref(), l.ref_count()) == (first, count));
        }
        // FAULT is a leaf with more references than any tree holds.
        assert!(KdNode::FAULT.is_leaf() && KdNode::FAULT.ref_count() == (1 << 30) - 1);
        assert_eq!(core::mem::size_of::<KdNode>(), 8);
        assert_eq!(core::mem::size_of::<KdStackItem>(), 8);
    }
}
