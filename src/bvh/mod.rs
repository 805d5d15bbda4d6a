//! Bounding volume hierarchies of axis-aligned boxes, built four ways as
//! Bezerianos' thesis compares them (sections 2.2.2, 3.3.3, chapter 5):
//! top-down binary splitting ([`Builder::Tdbs`], balanced children, or
//! [`Builder::TdbsSah`]),
//! bottom-up matching of the pair with the smallest joint surface area
//! ([`Builder::Nn`], [`Builder::NnChain`]), all through [`build`], and the R-tree and R*-tree ([`RTree`]: dynamic insert
//! and delete in caller memory).
//!
//! Every builder writes the same [`BvhNode`] layout, so one traversal
//! ([`Bvh::intersect`], [`Bvh::occluded`]) and one [`Bvh::validate`] serve
//! all; the caller owns the traversal stack ([`Bvh::stack_len`]).

mod build_nn;
mod build_nn_chain;
mod build_tdbs;
pub mod layout;
mod node;
mod rtree;
pub(crate) mod traverse;
mod validate;

pub use node::BvhNode;
pub use rtree::{
    validate_rtree, InsertOrder, RTree, RTreeParams, RTreeRequirements, RTreeState, Split,
    MAX_CHILDREN,
};
pub use traverse::{BvhStackItem, BOX_HIT_COST};
pub use validate::BvhTreeStats;

use crate::geom::{Aabb, Scene};
use crate::Error;

/// How a top-down or bottom-up hierarchy is built.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Builder {
    /// TDBS: at each node the linear partition (objects sorted by box centre
    /// on each axis) whose two children have the most nearly equal surface
    /// areas, as the thesis defines it.
    Tdbs,
    /// The same sweep minimising the surface area heuristic
    /// `A_L * n_L + A_R * n_R` instead.
    TdbsSah,
    /// Bottom-up: repeatedly join the two clusters whose joint box has the
    /// smallest surface area (the thesis' algorithm, O(n^2)).
    Nn,
    /// The same joins found by a nearest-neighbour chain over a kd-tree of
    /// cluster boxes: sub-quadratic; exact ties may be broken differently.
    NnChain,
}

/// The TDBS-SAH hierarchy whose nodes of `leaf_size` primitives or fewer
/// become leaves only where the surface area heuristic prices a leaf at
/// most as the best split (a traversal step costing `traversal` sphere
/// tests, a triangle's test `triangle` of one, triangles tested `block`
/// at a time; both the splits and the leaf rule price each primitive at
/// its kind's cost): the binary hierarchy the wide one is collapsed from. Storage and scratch as
/// [`build`] with [`Builder::TdbsSah`].
pub(crate) fn build_sah_leaves<'a>(
    scene: &Scene<'a>,
    leaf_size: u32,
    (traversal, triangle, block): (f64, f64, usize),
    storage: BvhStorage<'a>,
    scratch: BvhScratch,
) -> Result<Bvh<'a>, Error> {
    build_tdbs::build(
        scene,
        None,
        Builder::TdbsSah,
        leaf_size,
        build_tdbs::LeafRule::Sah {
            traversal,
            triangle,
            block,
        },
        storage,
        scratch,
    )
}

/// Storage of a static hierarchy over `n` primitives: `2n - 1` nodes,
/// `n` references, and build scratch of `n` of each scratch kind it uses
/// (the chain build: `3n - 1` boxes, for its kd-tree of clusters).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BvhRequirements {
    /// [`BvhNode`] slots of the hierarchy.
    pub nodes: usize,
    /// Primitive references (`u32`).
    pub refs: usize,
    /// Scratch: primitive boxes.
    pub boxes: usize,
    /// Scratch: `f32` keys (areas, costs).
    pub keys: usize,
    /// Scratch: `u32` links (NN partners).
    pub links: usize,
    /// Scratch: [`BvhNode`] cluster roots (NN only).
    pub clusters: usize,
}

/// Room for a static hierarchy over `prim_count` primitives built by `builder`.
pub fn requirements(prim_count: usize, builder: Builder) -> BvhRequirements {
    let n = prim_count;
    if builder == Builder::NnChain {
        return build_nn_chain::chain_requirements(n);
    }
    let top_down = matches!(builder, Builder::Tdbs | Builder::TdbsSah);
    BvhRequirements {
        nodes: (2 * n).saturating_sub(1).max(1),
        refs: n,
        boxes: n,
        keys: n,
        links: if top_down {
            build_tdbs::links_needed(n).max(1)
        } else {
            n
        },
        clusters: if builder == Builder::Nn { n } else { 0 },
    }
}

/// Builds a static hierarchy with `builder`; `leaf_size` (at least 1) bounds
/// the TDBS builders' leaves; bottom-up matching makes leaves of one.
pub fn build<'a>(
    scene: &Scene<'a>,
    builder: Builder,
    leaf_size: u32,
    storage: BvhStorage<'a>,
    scratch: BvhScratch,
) -> Result<Bvh<'a>, Error> {
    build_over(scene, None, builder, leaf_size, storage, scratch)
}

/// [`build`] on `source` boxes (one per primitive; an empty box leaves the
/// primitive out) instead of the primitives' own: the projection
/// hierarchies build on 2D boxes this way. The nodes get the source's
/// boxes; the caller refits them when it wants others.
pub fn build_over<'a>(
    scene: &Scene<'a>,
    source: Option<&[Aabb]>,
    builder: Builder,
    leaf_size: u32,
    storage: BvhStorage<'a>,
    scratch: BvhScratch,
) -> Result<Bvh<'a>, Error> {
    match builder {
        Builder::Nn => build_nn::build(scene, source, storage, scratch),
        Builder::NnChain => build_nn_chain::build(scene, source, storage, scratch),
        b => build_tdbs::build(
            scene,
            source,
            b,
            leaf_size,
            build_tdbs::LeafRule::Size,
            storage,
            scratch,
        ),
    }
}

/// Where a static build writes the hierarchy.
pub struct BvhStorage<'a> {
    /// At least [`BvhRequirements::nodes`].
    pub nodes: &'a mut [BvhNode],
    /// At least [`BvhRequirements::refs`].
    pub refs: &'a mut [u32],
}

/// Build scratch; free to reuse once the build returns.
pub struct BvhScratch<'a> {
    /// At least [`BvhRequirements::boxes`].
    pub boxes: &'a mut [Aabb],
    /// At least [`BvhRequirements::keys`].
    pub keys: &'a mut [f32],
    /// At least [`BvhRequirements::links`].
    pub links: &'a mut [u32],
    /// At least [`BvhRequirements::clusters`].
    pub clusters: &'a mut [BvhNode],
}

/// Shape of a built hierarchy.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[repr(C)]
pub struct BvhInfo {
    /// Index of the root node.
    pub root: u32,
    /// Nodes in use (interior and leaf).
    pub node_count: u32,
    /// Leaves in use.
    pub leaf_count: u32,
    /// References in leaves (each primitive once).
    pub ref_count: u32,
    /// Levels below the root (a lone leaf has depth 0).
    pub depth: u32,
    /// Most children a node may have (2, or the R-tree's M).
    pub max_children: u32,
    /// [`crate::rng::ref_digest`] of the references in leaves, low and high words.
    pub ref_digest: [u32; 2],
}

impl BvhInfo {
    /// The recorded reference digest.
    pub fn ref_digest(&self) -> u64 {
        self.ref_digest[0] as u64 | (self.ref_digest[1] as u64) << 32
    }

    pub(crate) fn set_ref_digest(&mut self, d: u64) {
        self.ref_digest = [d as u32, (d >> 32) as u32];
    }
}

/// A built hierarchy over a scene, borrowing the caller's memory. Made
/// only by the builders, [`RTree::bvh`] and [`Bvh::from_parts`].
#[derive(Clone, Copy)]
pub struct Bvh<'a> {
    pub(crate) scene: Scene<'a>,
    /// Nodes (the R-tree's may include free blocks).
    pub(crate) nodes: &'a [BvhNode],
    /// References from leaves to global primitive indices.
    pub(crate) refs: &'a [u32],
    pub(crate) info: BvhInfo,
}

impl<'a> Bvh<'a> {
    /// Reassembles a hierarchy from parts read back from memory, with O(1)
    /// checks (root and counts within the slices, fan-out, depth below the
    /// node count). Run [`Bvh::validate`] on parts from untrusted storage:
    /// until it accepts them, traversal never panics or hangs on them, but
    /// may stop early with [`crate::TraceStats::faults`] counted.
    #[inline]
    pub fn from_parts(
        scene: Scene<'a>,
        nodes: &'a [BvhNode],
        refs: &'a [u32],
        info: BvhInfo,
    ) -> Result<Bvh<'a>, Error> {
        let i = &info;
        if i.root as usize >= nodes.len()
            || i.node_count as usize > nodes.len()
            || i.ref_count as usize > refs.len()
            || !(2..=crate::limits::RTREE_MAX_CHILDREN).contains(&i.max_children)
            || i.depth >= i.node_count.max(1)
        {
            return Err(Error::Corrupt { what: "counts" });
        }
        Ok(Bvh {
            scene,
            nodes,
            refs,
            info,
        })
    }

    /// Shape, counts and digest: what an arena header records.
    pub fn info(&self) -> &BvhInfo {
        &self.info
    }

    /// The scene the hierarchy was built on.
    pub fn scene(&self) -> &Scene<'a> {
        &self.scene
    }

    /// The nodes and the references.
    pub fn parts(&self) -> (&'a [BvhNode], &'a [u32]) {
        (self.nodes, self.refs)
    }

    /// Entries of the traversal stack that [`Bvh::intersect`] and
    /// [`Bvh::occluded`] need: a node's children are pushed together, so
    /// `depth * (max_children - 1) + 1`.
    pub fn stack_len(&self) -> usize {
        (self.info.depth as usize)
            .saturating_mul(self.info.max_children.max(2) as usize - 1)
            .saturating_add(1)
    }
}

/// A binary hierarchy rooted at node 0 over `nodes[..node_count]`: every
/// node is a leaf or has two children, so half of them (rounded up) are leaves.
pub(crate) fn binary<'a>(
    scene: &Scene<'a>,
    nodes: &'a [BvhNode],
    refs: &'a [u32],
    node_count: usize,
    ref_count: usize,
    depth: u32,
) -> Bvh<'a> {
    let mut info = BvhInfo {
        root: 0,
        node_count: node_count as u32,
        leaf_count: node_count.div_ceil(2) as u32,
        ref_count: ref_count as u32,
        depth,
        max_children: 2,
        ref_digest: [0; 2],
    };
    info.set_ref_digest(crate::rng::ref_digest(refs[..ref_count].iter().copied()));
    Bvh {
        scene: *scene,
        nodes,
        refs,
        info,
    }
}

pub(crate) fn check_storage(
    req: &BvhRequirements,
    s: &BvhStorage,
    k: &BvhScratch,
) -> Result<(), Error> {
    let checks = [
        ("nodes", req.nodes, s.nodes.len()),
        ("refs", req.refs, s.refs.len()),
        ("boxes", req.boxes, k.boxes.len()),
        ("keys", req.keys, k.keys.len()),
        ("links", req.links, k.links.len()),
        ("clusters", req.clusters, k.clusters.len()),
    ];
    for (slice, needed, got) in checks {
        if got < needed {
            return Err(Error::SliceTooSmall { slice, needed, got });
        }
    }
    Ok(())
}

/// Boxes of the scene's non-degenerate primitives into `boxes`, their
/// indices into `refs`; returns how many (degenerate ones are never hit
/// and stay out of the hierarchy). With `source`, its boxes stand in for
/// the primitives' (an empty one leaves the primitive out). No box it
/// keeps is empty.
pub(crate) fn gather(
    scene: &Scene,
    source: Option<&[Aabb]>,
    boxes: &mut [Aabb],
    refs: &mut [u32],
) -> Result<usize, Error> {
    if scene.prim_count() > u32::MAX as usize / 2 {
        return Err(Error::TooManyPrimitives {
            count: scene.prim_count(),
        });
    }
    if let Some(src) = source {
        if src.len() < scene.prim_count() {
            return Err(Error::SliceTooSmall {
                slice: "source boxes",
                needed: scene.prim_count(),
                got: src.len(),
            });
        }
    }
    let mut n = 0;
    for (p, slot) in boxes.iter_mut().enumerate().take(scene.prim_count()) {
        // Never an empty box (the TDBS sweep's areas rely on it).
        let b = match source {
            Some(src) => Some(src[p]),
            None => scene.prim_bounds(p),
        }
        .filter(|b| !b.is_empty());
        if let Some(b) = b {
            *slot = b;
            refs[n] = p as u32;
            n += 1;
        }
    }
    Ok(n)
}
