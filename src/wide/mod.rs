//! Wide bounding volume hierarchies: [`WIDTH`] (8) children a node, their
//! boxes stored plane by plane, so a ray tests all eight in one pass of
//! vector instructions and descends a tree a third as deep as a binary
//! one. This is the structure for meshes and for incoherent rays
//! (secondary bounces, rays from anywhere in any direction), where a
//! kd-tree's long chain of dependent one-plane steps costs most: the same
//! primitive tests and tie rule give the kd-tree's hits bit for bit.
//!
//! Built in two steps in the caller's memory: the binary SAH hierarchy
//! ([`crate::bvh::Builder::TdbsSah`]'s sweep, pricing a leaf at what its
//! four-lane block tests cost; small nodes become leaves where the SAH
//! prices a leaf no higher than a split) into scratch, then collapsed
//! ([`build`]) into breadth-first wide nodes, each leaf's primitives
//! copied into its own blocks ([`block`]) that a leaf tests four
//! triangles at a time from.
//! The caller owns the traversal stack ([`WideBvh::stack_len`]).

#[cfg(all(target_arch = "x86_64", target_feature = "sse2"))]
mod avx2;
pub mod block;
mod build;
pub mod layout;
mod node;
#[cfg(all(target_arch = "x86_64", target_feature = "sse2"))]
pub mod packet;
mod traverse;
mod validate;

pub use block::{LeafBlock, BLOCK_SLOTS, EMPTY_BLOCK, NO_PRIM};
pub use build::nodes_bound;
pub use node::{
    leaf_entry, leaf_run, WideNode, EMPTY_SLOT, LEAF_BIT, LEAF_BLOCKS_SHIFT, LEAF_FIRST_MASK,
    LOWER, MAX_LEAF_BLOCKS, UPPER, WIDTH,
};
pub use traverse::{WideStackItem, READ_AHEAD_BYTES};

use crate::bvh::{self, BvhNode, BvhScratch, BvhStorage};
use crate::geom::{Aabb, Scene};
use crate::Error;

/// Element counts of the slices a build needs. `nodes` and `blocks` are
/// the hierarchy's; the rest is scratch, free once the build returns.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct WideRequirements {
    /// [`WideNode`] slots: [`nodes_bound`] of one leaf per primitive.
    pub nodes: usize,
    /// [`LeafBlock`]s: one per primitive at most (leaves of one).
    pub blocks: usize,
    /// Scratch: primitive references (`u32`) of the binary hierarchy.
    pub refs: usize,
    /// Scratch: the binary hierarchy's [`BvhNode`]s.
    pub bvh_nodes: usize,
    /// Scratch: primitive boxes.
    pub boxes: usize,
    /// Scratch: `f32` keys of the binary build's sweep.
    pub keys: usize,
    /// Scratch: `u32` links of the binary build.
    pub links: usize,
}

/// Room for a wide hierarchy over `prim_count` primitives.
pub fn requirements(prim_count: usize) -> WideRequirements {
    let b = bvh::requirements(prim_count, bvh::Builder::TdbsSah);
    WideRequirements {
        nodes: nodes_bound(prim_count),
        blocks: prim_count,
        refs: b.refs,
        bvh_nodes: b.nodes,
        boxes: b.boxes,
        keys: b.keys,
        links: b.links,
    }
}

/// The hierarchy's own slices (kept).
pub struct WideStorage<'a> {
    /// At least [`WideRequirements::nodes`].
    pub nodes: &'a mut [WideNode],
    /// At least [`WideRequirements::blocks`].
    pub blocks: &'a mut [LeafBlock],
}

/// Build scratch; free to reuse once the build returns.
pub struct WideScratch<'a> {
    /// At least [`WideRequirements::refs`].
    pub refs: &'a mut [u32],
    /// At least [`WideRequirements::bvh_nodes`].
    pub bvh_nodes: &'a mut [BvhNode],
    /// At least [`WideRequirements::boxes`].
    pub boxes: &'a mut [Aabb],
    /// At least [`WideRequirements::keys`].
    pub keys: &'a mut [f32],
    /// At least [`WideRequirements::links`].
    pub links: &'a mut [u32],
}

/// Shape of a built wide hierarchy: what an arena header records.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[repr(C)]
pub struct WideInfo {
    /// Nodes in use; node 0 is the root.
    pub node_count: u32,
    /// Leaf entries in the nodes.
    pub leaf_count: u32,
    /// Primitives in leaves (each once).
    pub ref_count: u32,
    /// Level of the deepest node (the root alone: 0).
    pub depth: u32,
    /// Most primitives in one leaf entry (the build's leaf size).
    pub leaf_size: u32,
    /// [`crate::rng::ref_digest`] of the primitives in leaves, low and
    /// high words.
    pub ref_digest: [u32; 2],
    /// Leaf blocks in use.
    pub block_count: u32,
}

impl WideInfo {
    /// The recorded reference digest.
    pub fn ref_digest(&self) -> u64 {
        self.ref_digest[0] as u64 | (self.ref_digest[1] as u64) << 32
    }
}

/// A built wide hierarchy over a scene, borrowing the caller's memory.
/// Made only by [`build`] and [`WideBvh::from_parts`].
#[derive(Clone, Copy)]
pub struct WideBvh<'a> {
    pub(crate) scene: Scene<'a>,
    pub(crate) nodes: &'a [WideNode],
    pub(crate) blocks: &'a [LeafBlock],
    pub(crate) info: WideInfo,
    /// Whether walks read ahead (see [`WideBvh::with_read_ahead`]).
    pub(crate) read_ahead: bool,
}

/// A traversal step's cost in primitive tests, for the binary build's
/// leaf rule (see [`build`]).
pub const LEAF_TRAVERSAL_COST: f64 = 1.0;

/// A triangle's test in units of a sphere's or a cone's, for the binary
/// build's SAH (its splits and its leaf rule): a leaf tests its triangles
/// eight at a time ([`LEAF_PASS`]), a pass costing about two one-triangle
/// tests, while its spheres and cones go one at a time. With leaves of up
/// to 8 ([`DEFAULT_LEAF_SIZE`]) and passes priced whole, against 0.5, leaves
/// of up to 4 and passes not priced whole (callgrind, spot.obj, 50,000
/// incoherent rays and 512 x 512 primary rays in packets): 878 -> 853
/// instructions an incoherent ray, 266 -> 286 a primary one; larger
/// leaves (16, 24) cost both more (900-924, 313-328).
pub const LEAF_TRIANGLE_COST: f64 = 0.25;

/// The leaf size a build takes by default (the C parameters' default, the
/// bench's `wide`).
pub const DEFAULT_LEAF_SIZE: u32 = 8;

/// Most primitives a leaf holds: [`MAX_LEAF_BLOCKS`] full blocks.
pub const MAX_LEAF_SIZE: u32 = (MAX_LEAF_BLOCKS * BLOCK_SLOTS) as u32;

/// Triangles a leaf tests at once (the AVX2 walk's eight lanes: two
/// blocks), for the binary build's leaf rule.
pub const LEAF_PASS: usize = 8;

/// Builds the binary SAH hierarchy into `scratch`, a node of at most
/// `leaf_size` (1 to [`MAX_LEAF_SIZE`]) primitives becoming a leaf where the surface
/// area heuristic prices it no higher than its best split (a traversal
/// step at [`LEAF_TRAVERSAL_COST`], a triangle's test at
/// [`LEAF_TRIANGLE_COST`]), then collapses it into `storage`.
/// Fails for bad input or parameters and for slices shorter than
/// [`requirements`].
pub fn build<'a>(
    scene: &Scene<'a>,
    leaf_size: u32,
    storage: WideStorage<'a>,
    scratch: WideScratch,
) -> Result<WideBvh<'a>, Error> {
    if !(1..=MAX_LEAF_SIZE).contains(&leaf_size) {
        return Err(Error::InvalidParameter {
            name: "leaf_size: 1 to 64",
        });
    }
    let req = requirements(scene.prim_count());
    for (slice, needed, got) in [
        ("nodes", req.nodes, storage.nodes.len()),
        ("blocks", req.blocks, storage.blocks.len()),
    ] {
        if got < needed {
            return Err(Error::SliceTooSmall { slice, needed, got });
        }
    }
    let WideStorage { nodes, blocks } = storage;
    let b = bvh::build_sah_leaves(
        scene,
        leaf_size,
        (LEAF_TRAVERSAL_COST, LEAF_TRIANGLE_COST, LEAF_PASS),
        BvhStorage {
            nodes: scratch.bvh_nodes,
            refs: scratch.refs,
        },
        BvhScratch {
            boxes: scratch.boxes,
            keys: scratch.keys,
            links: scratch.links,
            clusters: &mut [],
        },
    )?;
    let c = build::collapse(&b, nodes, blocks)?;
    let binary = b.info();
    let info = WideInfo {
        node_count: c.nodes as u32,
        leaf_count: c.leaves as u32,
        ref_count: binary.ref_count,
        depth: c.depth,
        leaf_size,
        ref_digest: binary.ref_digest,
        block_count: c.blocks as u32,
    };
    let (nodes, blocks) = (&nodes[..c.nodes], &blocks[..c.blocks]);
    Ok(WideBvh {
        scene: *scene,
        nodes,
        blocks,
        info,
        read_ahead: traverse::reads_ahead(nodes, blocks),
    })
}

impl<'a> WideBvh<'a> {
    /// Reassembles a hierarchy from parts read back from memory, with O(1)
    /// checks (counts within the slices). Run [`WideBvh::validate`] on
    /// parts from untrusted storage: until it accepts them, traversal never
    /// panics or hangs on them, but may stop early with
    /// [`crate::TraceStats::faults`] counted.
    #[inline]
    pub fn from_parts(
        scene: Scene<'a>,
        nodes: &'a [WideNode],
        blocks: &'a [LeafBlock],
        info: WideInfo,
    ) -> Result<WideBvh<'a>, Error> {
        let i = &info;
        if i.node_count == 0
            || i.node_count as usize > nodes.len()
            || i.block_count as usize > blocks.len()
            || i.block_count > i.ref_count
            || i.depth >= i.node_count
        {
            return Err(Error::Corrupt { what: "counts" });
        }
        let (nodes, blocks) = (
            &nodes[..i.node_count as usize],
            &blocks[..i.block_count as usize],
        );
        Ok(WideBvh {
            scene,
            nodes,
            blocks,
            info,
            read_ahead: traverse::reads_ahead(nodes, blocks),
        })
    }

    /// This hierarchy with its walks reading ahead (`true`) or not: when a
    /// node sends the ray on to several entries, the farther ones, which
    /// wait on the stack, have each cache line of their node or of their
    /// leaf's first corner block fetched (a prefetch instruction on
    /// x86-64, a load of one word a line elsewhere) so that their memory
    /// is on its way while the nearest is walked. It pays most when the
    /// hierarchy lives beyond the core's own caches; a load costs a few
    /// percent when it does not, a prefetch nothing measured. The default
    /// is on above [`READ_AHEAD_BYTES`] of nodes and corner blocks (on
    /// x86-64: always). The answers are the same either way.
    pub fn with_read_ahead(self, on: bool) -> WideBvh<'a> {
        WideBvh {
            read_ahead: on,
            ..self
        }
    }

    /// Whether walks read ahead (see [`WideBvh::with_read_ahead`]).
    pub fn read_ahead(&self) -> bool {
        self.read_ahead
    }

    /// Shape, counts and digest.
    pub fn info(&self) -> &WideInfo {
        &self.info
    }

    /// The scene the hierarchy was built on.
    pub fn scene(&self) -> &Scene<'a> {
        &self.scene
    }

    /// The nodes and the leaf blocks.
    pub fn parts(&self) -> (&'a [WideNode], &'a [LeafBlock]) {
        (self.nodes, self.blocks)
    }

    /// The root's box: the union of its entries' (empty for an empty scene).
    pub fn bounds(&self) -> Aabb {
        self.nodes.first().map_or(Aabb::EMPTY, |n| n.bounds())
    }

    /// Items of the traversal stack that every walk of this hierarchy
    /// needs ([`stack_len_for_depth`]).
    pub fn stack_len(&self) -> usize {
        stack_len_for_depth(self.info.depth as usize)
    }
}

/// Items of the traversal stack a walk of a hierarchy of `depth` needs: a
/// node pushes up to [`WIDTH`] entries and leaves `WIDTH - 1` waiting a
/// level, and a packet's entry takes two items (the entry and its lanes),
/// so `2 ((WIDTH - 1) depth + WIDTH)`, which covers the single walks too.
pub fn stack_len_for_depth(depth: usize) -> usize {
    depth
        .saturating_mul(WIDTH - 1)
        .saturating_add(WIDTH)
        .saturating_mul(2)
}
