//! Wide bounding volume hierarchies: [`WIDTH`] (4) children a node, their
//! boxes stored axis by axis, so a ray tests all four in one pass of
//! vector instructions and descends a tree a quarter as deep as a binary
//! one. This is the structure for incoherent rays (secondary bounces,
//! rays from anywhere in any direction), where a kd-tree's long chain of
//! dependent one-plane steps costs most: the same primitive tests and tie
//! rule give the kd-tree's hits bit for bit.
//!
//! Built in three steps in the caller's memory: the binary SAH hierarchy
//! ([`crate::bvh::Builder::TdbsSah`]'s sweep, pricing a triangle at what
//! its four-lane test costs; small nodes become leaves where the SAH
//! prices a leaf no higher than a split) into scratch,
//! collapsed ([`build`]) into breadth-first wide nodes over the same
//! references, whose leaf runs are then placed (those holding a triangle
//! first, each filling the block of four slots the one before left) and
//! their triangles' corners copied into blocks ([`corners`]) that a leaf
//! tests four triangles at a time from.
//! The caller owns the traversal stack ([`WideBvh::stack_len`]).

mod build;
pub mod corners;
pub mod layout;
mod node;
mod pack;
mod traverse;
mod validate;

pub use node::{WideNode, EMPTY_SLOT, LEAF_BIT, WIDTH};
pub use traverse::{WideStackItem, READ_AHEAD_BYTES};

use crate::bvh::{self, BvhNode, BvhScratch, BvhStorage};
use crate::geom::{Aabb, Corners4, Scene};
use crate::Error;

/// Element counts of the slices a build needs. `nodes` and `refs` are the
/// hierarchy's; the rest is scratch, free once the build returns.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct WideRequirements {
    /// [`WideNode`] slots: one per interior node of the binary hierarchy
    /// at most.
    pub nodes: usize,
    /// Primitive references (`u32`), one per primitive.
    pub refs: usize,
    /// Blocks of four reference slots' triangle corners
    /// ([`corners::blocks_for`] `refs`).
    pub corners: usize,
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
        nodes: prim_count.saturating_sub(1).max(1),
        refs: b.refs,
        corners: corners::blocks_for(b.refs),
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
    /// At least [`WideRequirements::refs`].
    pub refs: &'a mut [u32],
    /// At least [`WideRequirements::corners`].
    pub corners: &'a mut [Corners4],
}

/// Build scratch; free to reuse once the build returns.
pub struct WideScratch<'a> {
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
    /// Leaf entries (runs of references) in the nodes.
    pub leaf_count: u32,
    /// References in leaves (each primitive once).
    pub ref_count: u32,
    /// Level of the deepest node (the root alone: 0).
    pub depth: u32,
    /// Most references in one leaf entry (the build's leaf size).
    pub leaf_size: u32,
    /// [`crate::rng::ref_digest`] of the references in leaves, low and high words.
    pub ref_digest: [u32; 2],
    /// Blocks of triangle corners in use ([`corners`]): they cover the
    /// leaf runs that hold a triangle, which come first.
    pub corner_blocks: u32,
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
    pub(crate) refs: &'a [u32],
    pub(crate) corners: &'a [Corners4],
    pub(crate) info: WideInfo,
    /// Whether walks read ahead (see [`WideBvh::with_read_ahead`]).
    pub(crate) read_ahead: bool,
}

/// A traversal step's cost in primitive tests, for the binary build's
/// leaf rule (see [`build`]); chosen over 0.5 and 2.0 when the rule was
/// written. Leaves of up to 4 by this rule against fixed leaves of 2
/// (`coray bench --table speed spd:X --res 512 --threads 1 --repeat 3`,
/// both alternated, two rounds, wide over `rtcIntersect1`): tetra
/// incoherent 0.62 / 0.54 -> 0.68 / 0.68, diffuse 0.51 / 0.44 -> 0.61 /
/// 0.61; balls, gears, lattice, teapot and tree within the noise.
pub const LEAF_TRAVERSAL_COST: f64 = 1.0;

/// A triangle's test in units of a sphere's or a cone's, for the binary
/// build's SAH (its splits and its leaf rule): a leaf tests its triangles
/// four at a time from a corner block, in about two one-triangle tests'
/// time, while its spheres and cones go one at a time. Against pricing
/// every kind alike (`coray bench --table speed --res 512 --threads 1
/// --repeat 3`, both alternated, two rounds, best; wide over
/// `rtcIntersect1`): incoherent rays random 0.61 -> 0.72, teapot 0.86 ->
/// 0.94; diffuse teapot 0.73 -> 0.76, gears 0.73 -> 0.76, mount 0.79 ->
/// 0.86; tetra, gears incoherent and the scenes without triangles within
/// the noise. Leaves of up to 6 at this cost did no better.
pub const LEAF_TRIANGLE_COST: f64 = 0.5;

/// Builds the binary SAH hierarchy into `scratch`, a node of at most
/// `leaf_size` (1 or more) primitives becoming a leaf where the surface
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
    let req = requirements(scene.prim_count());
    for (slice, needed, got) in [
        ("nodes", req.nodes, storage.nodes.len()),
        ("corners", req.corners, storage.corners.len()),
    ] {
        if got < needed {
            return Err(Error::SliceTooSmall { slice, needed, got });
        }
    }
    let WideStorage {
        nodes,
        refs,
        corners,
    } = storage;
    let (collapsed, binary) = {
        let b = bvh::build_sah_leaves(
            scene,
            leaf_size,
            LEAF_TRAVERSAL_COST,
            LEAF_TRIANGLE_COST,
            BvhStorage {
                nodes: scratch.bvh_nodes,
                refs: &mut *refs,
            },
            BvhScratch {
                boxes: scratch.boxes,
                keys: scratch.keys,
                links: &mut *scratch.links,
                clusters: &mut [],
            },
        )?;
        (build::collapse(&b, nodes)?, *b.info())
    };
    let refs = &mut refs[..binary.ref_count as usize];
    let nt = scene.triangles.len();
    let Some(triangle_slots) =
        pack::pack_leaves(&mut nodes[..collapsed.nodes], refs, scratch.links, nt)
    else {
        return Err(Error::Corrupt {
            what: "leaf entries",
        });
    };
    let refs = &*refs;
    // The requirements hold a block for every four primitives.
    let corners = &mut corners[..corners::blocks_for(triangle_slots)];
    corners::fill(scene, refs, corners);
    let info = WideInfo {
        node_count: collapsed.nodes as u32,
        leaf_count: collapsed.leaves as u32,
        ref_count: binary.ref_count,
        depth: collapsed.depth,
        leaf_size,
        ref_digest: binary.ref_digest,
        corner_blocks: corners.len() as u32,
    };
    let nodes = &nodes[..collapsed.nodes];
    Ok(WideBvh {
        scene: *scene,
        nodes,
        refs,
        corners,
        info,
        read_ahead: traverse::reads_ahead(nodes, corners),
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
        refs: &'a [u32],
        corners: &'a [Corners4],
        info: WideInfo,
    ) -> Result<WideBvh<'a>, Error> {
        let i = &info;
        if i.node_count == 0
            || i.node_count as usize > nodes.len()
            || i.ref_count as usize > refs.len()
            || i.corner_blocks as usize > corners.len()
            || i.corner_blocks as usize > corners::blocks_for(i.ref_count as usize)
            || i.depth >= i.node_count
        {
            return Err(Error::Corrupt { what: "counts" });
        }
        let (nodes, corners) = (
            &nodes[..i.node_count as usize],
            &corners[..i.corner_blocks as usize],
        );
        Ok(WideBvh {
            scene,
            nodes,
            refs: &refs[..i.ref_count as usize],
            corners,
            info,
            read_ahead: traverse::reads_ahead(nodes, corners),
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

    /// The nodes and the references.
    pub fn parts(&self) -> (&'a [WideNode], &'a [u32]) {
        (self.nodes, self.refs)
    }

    /// The root's box: the union of its entries' (empty for an empty scene).
    pub fn bounds(&self) -> Aabb {
        self.nodes.first().map_or(Aabb::EMPTY, |n| n.bounds())
    }

    /// Entries of the traversal stack that [`WideBvh::intersect`] and
    /// [`WideBvh::occluded`] need: a node pushes up to [`WIDTH`] entries
    /// and leaves `WIDTH - 1` waiting a level, so `(WIDTH - 1) * depth +
    /// WIDTH`.
    pub fn stack_len(&self) -> usize {
        (self.info.depth as usize)
            .saturating_mul(WIDTH - 1)
            .saturating_add(WIDTH)
    }
}
