//! R-tree (Guttman 1984) and R*-tree (Beckmann, Kriegel, Schneider and
//! Seeger 1990) over the scene's primitive boxes, in caller memory, with
//! dynamic insert and delete.
//!
//! Layout: slot 0 of `nodes` holds the root; every node owns a block of
//! `max_children` slots for its entries, in `nodes` (interior) or `refs`
//! (leaf). Blocks all have one size, so freed ones go on a free list and
//! never fragment. "Area" is surface area throughout (the thesis' measure;
//! flat primitives would make every volume 0), "margin" the sum of a box's
//! edge lengths.

use super::{Bvh, BvhInfo, BvhNode};
use crate::geom::{Aabb, Scene};
use crate::Error;

/// Most entries a node may have (the R-tree's M).
pub const MAX_CHILDREN: u32 = crate::limits::RTREE_MAX_CHILDREN;
/// Height limit: with at least 2 entries per node, 2^40 objects.
const MAX_HEIGHT: usize = 40;
const NONE: u32 = u32::MAX;

/// How a full node is split and where an object goes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Split {
    /// Guttman: least area enlargement (ties: smallest area), quadratic split.
    Quadratic,
    /// R*: least overlap enlargement just above the leaves, split axis by
    /// margin, split index by overlap then area; forced reinsertion when
    /// [`RTreeParams::forced_reinsert`] is set (the thesis ran without it).
    RStar,
}

/// The order in which [`RTree::build`] inserts the primitives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InsertOrder {
    /// Scene order.
    Scene,
    /// A Fisher-Yates shuffle seeded with this value (SplitMix64).
    Shuffled(u64),
    /// Sorted by the Morton code of the box centre (10 bits per axis).
    Sorted,
}

/// R-tree parameters.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RTreeParams {
    /// Split and choose-subtree rules.
    pub split: Split,
    /// M: most entries per node, 4 to [`MAX_CHILDREN`].
    pub max_children: u32,
    /// m: fewest entries per node but the root, 2 to M / 2.
    pub min_children: u32,
    /// Insertion order of [`RTree::build`].
    pub order: InsertOrder,
    /// Beckmann et al.'s forced reinsertion: the first time a node other
    /// than the root overflows at a level during one insert, its 30% of
    /// entries farthest from its centre are taken out and inserted again
    /// (nearest first) instead of splitting it. Off by default, as in the
    /// thesis; it applies to either split rule.
    pub forced_reinsert: bool,
}

impl RTreeParams {
    /// Guttman's R-tree, M = 8, m = 3 (m about 40% of M), scene order.
    pub const fn rtree() -> RTreeParams {
        RTreeParams {
            split: Split::Quadratic,
            max_children: 8,
            min_children: 3,
            order: InsertOrder::Scene,
            forced_reinsert: false,
        }
    }
    /// The R*-tree with the same M and m.
    pub const fn rstar() -> RTreeParams {
        RTreeParams {
            split: Split::RStar,
            ..RTreeParams::rtree()
        }
    }

    /// Checks M and m: 4 <= M <= [`MAX_CHILDREN`], 2 <= m <= M / 2.
    pub fn check(&self) -> Result<(), Error> {
        let (big, small) = (self.max_children, self.min_children);
        if !(4..=MAX_CHILDREN).contains(&big) {
            return Err(Error::InvalidParameter {
                name: "max_children",
            });
        }
        if small < 2 || small > big / 2 {
            return Err(Error::InvalidParameter {
                name: "min_children",
            });
        }
        Ok(())
    }
}

/// Room for an R-tree of up to `capacity` primitives: every node but the
/// root holds at least m entries, so leaves and interior nodes are bounded.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RTreeRequirements {
    /// [`BvhNode`] slots: the root slot and one block per interior node.
    pub nodes: usize,
    /// Reference slots: one block per leaf.
    pub refs: usize,
    /// Scratch `u32`s: the insertion order of a build, the orphans of a delete.
    pub scratch: usize,
}

/// [`Bvh::validate`] with the R-tree's fill rules, and the parts only an
/// R-tree has: each free list names blocks that were handed out, as many as
/// its count says, none twice; blocks in use and free blocks add up to the
/// blocks handed out; `bvh.info` agrees with `state`. For memory a caller
/// loaded: a tree that passes can be traced, and resumed and changed.
/// `stack` as for [`Bvh::validate`]. Never panics; linear time.
pub fn validate_rtree(
    bvh: &Bvh,
    params: &RTreeParams,
    state: &RTreeState,
    stack: &mut [super::BvhStackItem],
) -> Result<super::BvhTreeStats, Error> {
    let corrupt = |what| Err(Error::Corrupt { what });
    if params.check().is_err() {
        return corrupt("R-tree parameters");
    }
    let big = params.max_children;
    let st = state;
    if bvh.info.max_children != big || bvh.info.root != 0 || st.height as usize > MAX_HEIGHT {
        return corrupt("R-tree shape");
    }
    if 1 + st.node_blocks as usize * big as usize > bvh.nodes.len()
        || st.ref_blocks as usize * big as usize > bvh.refs.len()
    {
        return corrupt("blocks beyond the slices");
    }
    // Walk each free list no further than its count: a list that ends
    // after exactly that many steps has no repeats.
    let mut b = st.free_nodes;
    for _ in 0..st.free_node_blocks {
        if b == NONE || b == 0 || !(b - 1).is_multiple_of(big) || (b - 1) / big >= st.node_blocks {
            return corrupt("free node list");
        }
        b = bvh.nodes.get(b as usize).map_or(0, |n| n.first);
    }
    if b != NONE {
        return corrupt("free node list longer than its count");
    }
    let mut b = st.free_refs;
    for _ in 0..st.free_ref_blocks {
        if b == NONE || !b.is_multiple_of(big) || b / big >= st.ref_blocks {
            return corrupt("free reference list");
        }
        b = bvh.refs.get(b as usize).copied().unwrap_or(0);
    }
    if b != NONE {
        return corrupt("free reference list longer than its count");
    }
    let stats = bvh.validate(Some(params.min_children), stack)?;
    // Every interior node owns one node block and every leaf one
    // reference block.
    let interior = stats.nodes - stats.leaves;
    if interior.checked_add(st.free_node_blocks) != Some(st.node_blocks)
        || stats.leaves.checked_add(st.free_ref_blocks) != Some(st.ref_blocks)
    {
        return corrupt("blocks in use and free blocks do not add up");
    }
    let i = &bvh.info;
    if stats.refs != st.len
        || stats.depth != st.height
        || i.node_count != stats.nodes
        || i.leaf_count != stats.leaves
    {
        return corrupt("counts disagree with the state");
    }
    // The digest updates carry on: it must be the one validate just
    // checked against the references.
    if st.ref_digest != i.ref_digest {
        return corrupt("the state's reference digest");
    }
    Ok(stats)
}

/// A dynamic R-tree or R*-tree borrowing the caller's memory.
pub struct RTree<'a> {
    scene: Scene<'a>,
    nodes: &'a mut [BvhNode],
    refs: &'a mut [u32],
    params: RTreeParams,
    state: RTreeState,
    /// Boxes standing in for the primitives' own (see [`RTree::build_over`]).
    source: Option<&'a [Aabb]>,
}

/// Everything of an [`RTree`] besides its two slices and parameters: what a
/// caller stores beside the slices to take the tree up again later
/// ([`RTree::state`], [`RTree::resume`]). Plain data for an arena header.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[repr(C)]
pub struct RTreeState {
    /// Levels below the root.
    pub height: u32,
    /// Blocks ever taken from `nodes` (after the root slot) and `refs`.
    pub node_blocks: u32,
    /// See `node_blocks`.
    pub ref_blocks: u32,
    /// Heads of the free lists (a freed block's first slot links on), or `u32::MAX`.
    pub free_nodes: u32,
    /// See `free_nodes`.
    pub free_refs: u32,
    /// Blocks on each free list.
    pub free_node_blocks: u32,
    /// See `free_node_blocks`.
    pub free_ref_blocks: u32,
    /// Objects in the tree.
    pub len: u32,
    /// [`crate::rng::ref_digest`] of the objects, low and high words.
    pub ref_digest: [u32; 2],
}

/// One entry while a node is being split: a child node, or (at leaf
/// level) a primitive carried in `first`.
type Entry = BvhNode;

fn margin(b: &Aabb) -> f32 {
    let e = b.max - b.min;
    e.x + e.y + e.z
}

fn enlarged(b: &Aabb, add: &Aabb) -> f32 {
    finite_area(&b.union(add)) - finite_area(b)
}

/// A box's area, f32::MAX where it overflows: boxes near f32::MAX keep
/// comparable (finite) enlargements instead of `inf - inf`.
fn finite_area(b: &Aabb) -> f32 {
    b.area().min(f32::MAX)
}

fn morton(c: crate::Vec3, lo: crate::Vec3, hi: crate::Vec3) -> u32 {
    let spread = |v: u32| {
        let mut x = v & 0x3ff;
        x = (x | (x << 16)) & 0x030000ff;
        x = (x | (x << 8)) & 0x0300f00f;
        x = (x | (x << 4)) & 0x030c30c3;
        (x | (x << 2)) & 0x09249249
    };
    let q = |a: usize| {
        let w = hi[a] - lo[a];
        let t = if w > 0.0 { (c[a] - lo[a]) / w } else { 0.0 };
        (t.clamp(0.0, 1.0) * 1023.0) as u32
    };
    spread(q(0)) | (spread(q(1)) << 1) | (spread(q(2)) << 2)
}

impl<'a> RTree<'a> {
    /// Room for an R-tree of up to `capacity` objects with `params`.
    pub fn requirements(capacity: usize, params: &RTreeParams) -> RTreeRequirements {
        let big = params.max_children.clamp(4, MAX_CHILDREN) as usize;
        let small = params.min_children.clamp(2, big as u32 / 2) as usize;
        let leaves = (capacity / small).max(1);
        let (mut x, mut interior) = (leaves, 0usize);
        while x > 1 {
            x = x.div_ceil(small);
            interior += x;
        }
        RTreeRequirements {
            nodes: 1 + big * (interior + 1),
            refs: big * (leaves + 1),
            scratch: capacity,
        }
    }

    /// An empty tree over `scene` (objects enter with [`RTree::insert`]).
    pub fn new(
        scene: &Scene<'a>,
        params: RTreeParams,
        nodes: &'a mut [BvhNode],
        refs: &'a mut [u32],
    ) -> Result<RTree<'a>, Error> {
        params.check()?;
        let big = params.max_children as usize;
        if nodes.is_empty() {
            return Err(Error::SliceTooSmall {
                slice: "nodes",
                needed: 1,
                got: 0,
            });
        }
        if refs.len() < big {
            return Err(Error::SliceTooSmall {
                slice: "refs",
                needed: big,
                got: refs.len(),
            });
        }
        let mut t = RTree {
            scene: *scene,
            nodes,
            refs,
            params,
            state: RTreeState {
                free_nodes: NONE,
                free_refs: NONE,
                ..RTreeState::default()
            },
            source: None,
        };
        let b = t.alloc_refs()?.ok_or(BROKEN)?;
        t.nodes[0] = BvhNode::leaf(&Aabb::EMPTY, b, 0);
        Ok(t)
    }

    /// A tree holding every non-degenerate primitive of `scene`, inserted
    /// one at a time in `params.order`; `order` is scratch of
    /// [`RTreeRequirements::scratch`] entries.
    pub fn build(
        scene: &Scene<'a>,
        params: RTreeParams,
        nodes: &'a mut [BvhNode],
        refs: &'a mut [u32],
        order: &mut [u32],
    ) -> Result<RTree<'a>, Error> {
        RTree::build_over(scene, None, params, nodes, refs, order)
    }

    /// [`RTree::build`] on `source` boxes (one per primitive; empty leaves
    /// it out) instead of the primitives' own; later inserts and deletes
    /// use them too. The projection hierarchies build on 2D boxes this way.
    pub fn build_over(
        scene: &Scene<'a>,
        source: Option<&'a [Aabb]>,
        params: RTreeParams,
        nodes: &'a mut [BvhNode],
        refs: &'a mut [u32],
        order: &mut [u32],
    ) -> Result<RTree<'a>, Error> {
        let mut t = RTree::new(scene, params, nodes, refs)?;
        if let Some(src) = source {
            if src.len() < scene.prim_count() {
                return Err(Error::SliceTooSmall {
                    slice: "source boxes",
                    needed: scene.prim_count(),
                    got: src.len(),
                });
            }
        }
        t.source = source;
        let mut n = 0;
        let mut bounds = Aabb::EMPTY;
        for p in 0..scene.prim_count() {
            if let Some(b) = t.prim_box(p) {
                if n == order.len() {
                    return Err(Error::SliceTooSmall {
                        slice: "order",
                        needed: scene.prim_count(),
                        got: order.len(),
                    });
                }
                order[n] = p as u32;
                bounds = bounds.union(&b);
                n += 1;
            }
        }
        let order = &mut order[..n];
        match params.order {
            InsertOrder::Scene => {}
            InsertOrder::Shuffled(seed) => {
                let mut rng = crate::rng::SplitMix64(seed);
                for i in (1..n).rev() {
                    order.swap(i, rng.below(i as u64 + 1) as usize);
                }
            }
            InsertOrder::Sorted => {
                let key = |p: u32| {
                    let b = t.prim_box(p as usize).unwrap_or(Aabb::EMPTY);
                    (morton(0.5 * (b.min + b.max), bounds.min, bounds.max), p)
                };
                order.sort_unstable_by_key(|&p| key(p));
            }
        }
        for &p in order.iter() {
            t.insert(p)?;
        }
        Ok(t)
    }

    /// Takes up a tree whose slices and [`RTree::state`] a caller kept
    /// (an arena from the C ABI). Checks, in O(1), that the state fits the
    /// slices; [`RTree::validate`] checks the rest on untrusted memory.
    /// Insert and delete never panic on a tree that fails it: they stop at
    /// the first broken invariant with [`Error::Corrupt`].
    pub fn resume(
        scene: &Scene<'a>,
        params: RTreeParams,
        nodes: &'a mut [BvhNode],
        refs: &'a mut [u32],
        state: RTreeState,
    ) -> Result<RTree<'a>, Error> {
        let corrupt = |what| Err(Error::Corrupt { what });
        if params.check().is_err() {
            return corrupt("R-tree parameters");
        }
        let big = params.max_children as usize;
        let st = &state;
        if nodes.is_empty() || 1 + st.node_blocks as usize * big > nodes.len() {
            return corrupt("node blocks beyond the nodes slice");
        }
        if st.ref_blocks == 0 || st.ref_blocks as usize * big > refs.len() {
            return corrupt("reference blocks beyond the refs slice");
        }
        if st.free_node_blocks > st.node_blocks || st.free_ref_blocks > st.ref_blocks {
            return corrupt("free block counts");
        }
        if st.height as usize > MAX_HEIGHT || st.len as usize > st.ref_blocks as usize * big {
            return corrupt("height or length");
        }
        Ok(RTree {
            scene: *scene,
            nodes,
            refs,
            params,
            state,
            source: None,
        })
    }

    /// What [`RTree::resume`] needs besides the slices and parameters.
    pub fn state(&self) -> RTreeState {
        self.state
    }

    /// [`validate_rtree`] of this tree, on a stack of [`Bvh::stack_len`].
    pub fn validate(
        &self,
        stack: &mut [super::BvhStackItem],
    ) -> Result<super::BvhTreeStats, Error> {
        validate_rtree(&self.bvh(), &self.params, &self.state, stack)
    }

    /// The box a primitive enters with, or `None` when it stays out.
    fn prim_box(&self, p: usize) -> Option<Aabb> {
        match self.source {
            Some(src) => src.get(p).copied().filter(|b| !b.is_empty()),
            None => self.scene.prim_bounds(p),
        }
    }

    /// Objects in the tree.
    pub fn len(&self) -> u32 {
        self.state.len
    }

    /// True when the tree holds nothing.
    pub fn is_empty(&self) -> bool {
        self.state.len == 0
    }

    /// The tree for tracing (and [`Bvh::validate`]).
    pub fn bvh(&self) -> Bvh<'_> {
        let big = self.params.max_children;
        Bvh {
            scene: self.scene,
            nodes: self.nodes,
            refs: self.refs,
            info: BvhInfo {
                root: 0,
                node_count: self.live_nodes(),
                leaf_count: self
                    .state
                    .ref_blocks
                    .saturating_sub(self.state.free_ref_blocks),
                ref_count: self.state.len,
                depth: self.state.height,
                max_children: big,
                ref_digest: self.state.ref_digest,
            },
        }
    }

    /// The parameters it was made with.
    pub fn params(&self) -> RTreeParams {
        self.params
    }

    /// Nodes in use: every interior node owns one node block and every
    /// leaf one reference block, so this is O(1).
    fn live_nodes(&self) -> u32 {
        let st = &self.state;
        (st.node_blocks.saturating_sub(st.free_node_blocks))
            .saturating_add(st.ref_blocks.saturating_sub(st.free_ref_blocks))
    }

    /// Node slot `slot`, or [`BROKEN`] outside the slice.
    #[inline]
    fn node(&self, slot: u32) -> Result<BvhNode, Error> {
        self.nodes.get(slot as usize).copied().ok_or(BROKEN)
    }

    #[inline]
    fn node_mut(&mut self, slot: u32) -> Result<&mut BvhNode, Error> {
        self.nodes.get_mut(slot as usize).ok_or(BROKEN)
    }

    #[inline]
    fn reference(&self, i: u32) -> Result<u32, Error> {
        self.refs.get(i as usize).copied().ok_or(BROKEN)
    }

    #[inline]
    fn reference_mut(&mut self, i: u32) -> Result<&mut u32, Error> {
        self.refs.get_mut(i as usize).ok_or(BROKEN)
    }

    /// Entries of `nd`, checked against M: a node never holds more.
    #[inline]
    fn entries(&self, nd: &BvhNode) -> Result<u32, Error> {
        let n = nd.len();
        if n > self.params.max_children {
            return Err(BROKEN);
        }
        Ok(n)
    }

    /// Adds or removes object `p` from the digest.
    fn digest(&mut self, p: u32, add: bool) {
        let d = self.state.ref_digest[0] as u64 | (self.state.ref_digest[1] as u64) << 32;
        let m = crate::rng::ref_mix(p);
        let d = if add {
            d.wrapping_add(m)
        } else {
            d.wrapping_sub(m)
        };
        self.state.ref_digest = [d as u32, (d >> 32) as u32];
    }

    /// A node block: from the free list, else fresh; `None` when full.
    fn alloc_nodes(&mut self) -> Result<Option<u32>, Error> {
        let big = self.params.max_children as usize;
        if self.state.free_nodes != NONE {
            let b = self.state.free_nodes;
            let next = self.node(b)?.first;
            self.state.free_nodes = next;
            self.state.free_node_blocks =
                self.state.free_node_blocks.checked_sub(1).ok_or(BROKEN)?;
            return Ok(Some(b));
        }
        let start = 1 + self.state.node_blocks as usize * big;
        if start + big > self.nodes.len() {
            return Ok(None);
        }
        self.state.node_blocks += 1;
        Ok(Some(start as u32))
    }

    /// A reference block, as [`RTree::alloc_nodes`].
    fn alloc_refs(&mut self) -> Result<Option<u32>, Error> {
        let big = self.params.max_children as usize;
        if self.state.free_refs != NONE {
            let b = self.state.free_refs;
            let next = self.reference(b)?;
            self.state.free_refs = next;
            self.state.free_ref_blocks = self.state.free_ref_blocks.checked_sub(1).ok_or(BROKEN)?;
            return Ok(Some(b));
        }
        let start = self.state.ref_blocks as usize * big;
        if start + big > self.refs.len() {
            return Ok(None);
        }
        self.state.ref_blocks += 1;
        Ok(Some(start as u32))
    }

    fn free_block(&mut self, leaf: bool, b: u32) -> Result<(), Error> {
        if leaf {
            let head = self.state.free_refs;
            *self.reference_mut(b)? = head;
            self.state.free_refs = b;
            self.state.free_ref_blocks += 1;
        } else {
            let head = self.state.free_nodes;
            self.node_mut(b)?.first = head;
            self.state.free_nodes = b;
            self.state.free_node_blocks += 1;
        }
        Ok(())
    }

    /// Blocks still obtainable: free lists plus untouched room.
    fn room(&self) -> (usize, usize) {
        let big = self.params.max_children as usize;
        let nodes = (self.state.free_node_blocks as usize + (self.nodes.len() - 1) / big)
            .saturating_sub(self.state.node_blocks as usize);
        let refs = (self.state.free_ref_blocks as usize + self.refs.len() / big)
            .saturating_sub(self.state.ref_blocks as usize);
        (nodes, refs)
    }

    fn entry_box(&self, leaf: bool, block: u32, i: u32) -> Result<Aabb, Error> {
        let at = block.checked_add(i).ok_or(BROKEN)?;
        Ok(if leaf {
            let p = self.reference(at)? as usize;
            self.prim_box(p).unwrap_or(Aabb::EMPTY)
        } else {
            self.node(at)?.bounds()
        })
    }

    /// Recomputes the box of the node in `slot` from its entries.
    fn refit(&mut self, slot: u32) -> Result<(), Error> {
        let nd = self.node(slot)?;
        let mut b = Aabb::EMPTY;
        for i in 0..self.entries(&nd)? {
            b = b.union(&self.entry_box(nd.is_leaf(), nd.first, i)?);
        }
        self.node_mut(slot)?.set_bounds(&b);
        Ok(())
    }

    /// The entry of interior node `nd` that `add` should go into.
    fn choose_subtree(&self, nd: &BvhNode, add: &Aabb) -> Result<u32, Error> {
        let n = self.entries(nd)?;
        let kids = self
            .nodes
            .get(nd.first as usize..)
            .and_then(|k| k.get(..n as usize))
            .filter(|k| !k.is_empty())
            .ok_or(BROKEN)?;
        let above_leaves = kids[0].is_leaf();
        let mut best = (0u32, f32::INFINITY, f32::INFINITY, f32::INFINITY);
        for (i, k) in kids.iter().enumerate() {
            let b = k.bounds();
            let grow = enlarged(&b, add);
            let overlap = if self.params.split == Split::RStar && above_leaves {
                let bigger = b.union(add);
                kids.iter()
                    .enumerate()
                    .filter(|(j, _)| *j != i)
                    .map(|(_, o)| {
                        let ob = o.bounds();
                        bigger.intersection(&ob).area() - b.intersection(&ob).area()
                    })
                    .sum()
            } else {
                0.0
            };
            let key = (overlap, grow, b.area());
            if key < (best.1, best.2, best.3) {
                best = (i as u32, key.0, key.1, key.2);
            }
        }
        Ok(best.0)
    }

    /// Inserts primitive `prim`. A degenerate primitive is not stored (it
    /// is never hit). Without room for the splits this insert needs, the
    /// tree is left as it was and `SliceTooSmall` names the slice.
    pub fn insert(&mut self, prim: u32) -> Result<(), Error> {
        if prim as usize >= self.scene.prim_count() {
            return Err(Error::InvalidParameter { name: "prim" });
        }
        let Some(pb) = self.prim_box(prim as usize) else {
            return Ok(());
        };
        if self.params.forced_reinsert && self.room_for_reinsertion() {
            self.insert_reinserting(BvhNode::leaf(&pb, prim, 1))?;
            self.state.len = self.state.len.checked_add(1).ok_or(BROKEN)?;
            self.digest(prim, true);
            return Ok(());
        }
        let big = self.params.max_children;
        // Path from the root to the leaf, as slots.
        let mut path = [0u32; MAX_HEIGHT + 1];
        let depth = self.path_to(&pb, 0, &mut path)?;
        // Splits needed: full nodes from the leaf up; one more block when the root splits.
        let mut splits = 0;
        while splits <= depth && self.node(path[depth - splits])?.len() == big {
            splits += 1;
        }
        let (node_room, ref_room) = self.room();
        let need_nodes = splits.saturating_sub(1) + (splits == depth + 1) as usize;
        if splits > 0 && ref_room < 1 {
            return Err(Error::SliceTooSmall {
                slice: "refs",
                needed: self.refs.len() + big as usize,
                got: self.refs.len(),
            });
        }
        if need_nodes > node_room || (splits == depth + 1 && depth + 1 > MAX_HEIGHT) {
            return Err(Error::SliceTooSmall {
                slice: "nodes",
                needed: self.nodes.len() + (need_nodes - node_room) * big as usize,
                got: self.nodes.len(),
            });
        }
        // Every level counts as reinserted already: overflow splits.
        let mut out = [BvhNode::default(); MAX_CHILDREN as usize];
        let entry = BvhNode::leaf(&pb, prim, 1);
        self.place_on_path(entry, &path, depth, &mut [true; MAX_HEIGHT + 1], &mut out)?;
        self.state.len = self.state.len.checked_add(1).ok_or(BROKEN)?;
        self.digest(prim, true);
        Ok(())
    }

    /// Entries one forced reinsertion takes out: 30% of M (at least one).
    fn reinsert_count(&self) -> usize {
        (self.params.max_children as usize * 3 / 10).max(1)
    }

    /// Whether the free room covers the worst an insert with forced
    /// reinsertion can need: every level but the root reinserts once, and
    /// each entry placed may split nodes up to a new root. Without it the
    /// insert splits plainly (and checks its exact needs), so an arena sized
    /// by [`RTree::requirements`] still holds its capacity.
    fn room_for_reinsertion(&self) -> bool {
        let h = self.state.height as usize;
        if h + 2 > MAX_HEIGHT {
            return false;
        }
        let worst = (1 + self.reinsert_count() * h) * (h + 2);
        let (nodes, refs) = self.room();
        nodes >= worst && refs >= worst
    }

    /// Inserts `first` (an object entry) with forced reinsertion; entries
    /// taken out wait on a stack with the height of the node they go in.
    fn insert_reinserting(&mut self, first: Entry) -> Result<(), Error> {
        // Each level but the root reinserts once, at most 30% of 32 entries.
        const MAX_PENDING: usize = 1 + 9 * MAX_HEIGHT;
        let mut pending = [(BvhNode::default(), 0u32); MAX_PENDING];
        pending[0] = (first, 0);
        let mut sp = 1;
        let mut reinserted = [false; MAX_HEIGHT + 1];
        while sp > 0 {
            sp -= 1;
            let (entry, height) = pending[sp];
            let mut out = [BvhNode::default(); MAX_CHILDREN as usize];
            let (n, at) = self.place(entry, height, &mut reinserted, &mut out)?;
            // Farthest first onto the stack: the nearest is placed first.
            for e in &out[..n] {
                *pending.get_mut(sp).ok_or(BROKEN)? = (*e, at);
                sp += 1;
            }
        }
        Ok(())
    }

    /// The slots from the root down to the node `height` levels above the
    /// leaves that an entry with box `b` goes into; returns its depth.
    fn path_to(
        &self,
        b: &Aabb,
        height: u32,
        path: &mut [u32; MAX_HEIGHT + 1],
    ) -> Result<usize, Error> {
        let top = self.state.height;
        let mut depth = 0usize;
        let mut slot = 0u32;
        while top.checked_sub(depth as u32).ok_or(BROKEN)? > height {
            let nd = self.node(slot)?;
            if nd.is_leaf() || depth >= MAX_HEIGHT {
                return Err(BROKEN);
            }
            path[depth] = slot;
            depth += 1;
            slot = nd
                .first
                .checked_add(self.choose_subtree(&nd, b)?)
                .ok_or(BROKEN)?;
        }
        path[depth] = slot;
        Ok(depth)
    }

    /// Puts `entry` into a node `height` levels above the leaves (0: a
    /// leaf) by [`RTree::place_on_path`].
    fn place(
        &mut self,
        entry: Entry,
        height: u32,
        reinserted: &mut [bool; MAX_HEIGHT + 1],
        out: &mut [Entry; MAX_CHILDREN as usize],
    ) -> Result<(usize, u32), Error> {
        let mut path = [0u32; MAX_HEIGHT + 1];
        let depth = self.path_to(&entry.bounds(), height, &mut path)?;
        self.place_on_path(entry, &path, depth, reinserted, out)
    }

    /// Adds `entry` to the node `path[depth]`, treating overflow the R* way
    /// at levels not yet `reinserted` (the taken entries go to `out`,
    /// farthest first; returns their count and height), else by a split,
    /// climbing while parents overflow, and refits the path above.
    fn place_on_path(
        &mut self,
        entry: Entry,
        path: &[u32; MAX_HEIGHT + 1],
        depth: usize,
        reinserted: &mut [bool; MAX_HEIGHT + 1],
        out: &mut [Entry; MAX_CHILDREN as usize],
    ) -> Result<(usize, u32), Error> {
        let big = self.params.max_children;
        let top = self.state.height;
        let mut entry = entry;
        let mut level = depth;
        let mut taken = (0usize, 0u32);
        loop {
            let s = path[level];
            let nd = self.node(s)?;
            let n = self.entries(&nd)?;
            if n < big {
                self.put(nd.is_leaf(), nd.first.checked_add(n).ok_or(BROKEN)?, &entry)?;
                self.node_mut(s)?.set_len(n + 1);
                self.refit(s)?;
                break;
            }
            let h = (top as usize).checked_sub(level).ok_or(BROKEN)? as u32;
            if level > 0 && !reinserted[h as usize] {
                reinserted[h as usize] = true;
                taken = (self.take_farthest(s, &entry, out)?, h);
                break;
            }
            let sibling = self.split(s, &entry)?;
            if level == 0 {
                // The root split: a new root over the old one and its sibling.
                let b = self.alloc_nodes()?.ok_or(BROKEN)?;
                let old = self.node(0)?;
                *self.node_mut(b)? = old;
                *self.node_mut(b.wrapping_add(1))? = sibling;
                let joint = old.bounds().union(&sibling.bounds());
                self.nodes[0] = BvhNode::interior(&joint, b, 2);
                self.state.height += 1;
                break;
            }
            entry = sibling;
            level -= 1;
        }
        for l in (0..level).rev() {
            self.refit(path[l])?;
        }
        Ok(taken)
    }

    /// The full node in `slot` plus `extra`: keeps the entries nearest the
    /// centre of their joint box, writes the [`RTree::reinsert_count`]
    /// farthest to `out` (farthest first) and returns how many.
    fn take_farthest(
        &mut self,
        slot: u32,
        extra: &Entry,
        out: &mut [Entry],
    ) -> Result<usize, Error> {
        let nd = self.node(slot)?;
        let leaf = nd.is_leaf();
        let (mut e, n) = self.overfull(slot, extra)?;
        let all = e[..n].iter().fold(Aabb::EMPTY, |b, x| b.union(&x.bounds()));
        let c = 0.5 * (all.min + all.max);
        let dist = |x: &Entry| {
            let b = x.bounds();
            (0.5 * (b.min + b.max) - c).length_squared()
        };
        // Farthest first; ties by box, then by reference, for one order everywhere.
        e[..n].sort_unstable_by(|a, b| {
            dist(b)
                .total_cmp(&dist(a))
                .then(a.first.cmp(&b.first))
                .then(a.count.cmp(&b.count))
        });
        let k = self.reinsert_count().min(n);
        out[..k].copy_from_slice(&e[..k]);
        for (i, x) in e[k..n].iter().enumerate() {
            self.put(leaf, nd.first.wrapping_add(i as u32), x)?;
        }
        self.node_mut(slot)?.set_len((n - k) as u32);
        self.refit(slot)?;
        Ok(k)
    }

    /// The entries of the full node in `slot`, then `extra`, and how many.
    fn overfull(
        &self,
        slot: u32,
        extra: &Entry,
    ) -> Result<([Entry; MAX_CHILDREN as usize + 1], usize), Error> {
        let nd = self.node(slot)?;
        let n = self.entries(&nd)? as usize + 1;
        let mut e = [BvhNode::default(); MAX_CHILDREN as usize + 1];
        for (i, x) in e.iter_mut().enumerate().take(n - 1) {
            let at = nd.first.checked_add(i as u32).ok_or(BROKEN)?;
            *x = if nd.is_leaf() {
                let p = self.reference(at)?;
                BvhNode::leaf(&self.entry_box(true, nd.first, i as u32)?, p, 1)
            } else {
                self.node(at)?
            };
        }
        e[n - 1] = *extra;
        Ok((e, n))
    }

    fn put(&mut self, leaf: bool, at: u32, e: &Entry) -> Result<(), Error> {
        if leaf {
            *self.reference_mut(at)? = e.first;
        } else {
            *self.node_mut(at)? = *e;
        }
        Ok(())
    }

    /// Splits the full node in `slot` plus `extra` into two groups: the
    /// first stays in the node's block, the second goes to a new block,
    /// returned as the node's new sibling.
    fn split(&mut self, slot: u32, extra: &Entry) -> Result<Entry, Error> {
        let nd = self.node(slot)?;
        let leaf = nd.is_leaf();
        let (mut e, n) = self.overfull(slot, extra)?;
        let m = self.params.min_children as usize;
        if n < 2 * m {
            return Err(BROKEN);
        }
        let second = match self.params.split {
            Split::Quadratic => quadratic_split(&e[..n], m),
            Split::RStar => rstar_split(&mut e[..n], m),
        };
        let block = if leaf {
            self.alloc_refs()?
        } else {
            self.alloc_nodes()?
        }
        .ok_or(BROKEN)?;
        let (mut k1, mut k2) = (0u32, 0u32);
        let (mut b1, mut b2) = (Aabb::EMPTY, Aabb::EMPTY);
        for (i, x) in e[..n].iter().enumerate() {
            if second[i] {
                self.put(leaf, block.wrapping_add(k2), x)?;
                k2 += 1;
                b2 = b2.union(&x.bounds());
            } else {
                self.put(leaf, nd.first.wrapping_add(k1), x)?;
                k1 += 1;
                b1 = b1.union(&x.bounds());
            }
        }
        let kind = |b: &Aabb, first: u32, k: u32| {
            if leaf {
                BvhNode::leaf(b, first, k)
            } else {
                BvhNode::interior(b, first, k)
            }
        };
        *self.node_mut(slot)? = kind(&b1, nd.first, k1);
        Ok(kind(&b2, block, k2))
    }

    /// Removes primitive `prim`; false when the tree does not hold it.
    /// Nodes left with fewer than m entries are dissolved and their
    /// objects inserted again (Guttman's CondenseTree, reinserting objects
    /// rather than whole subtrees); `orphans` is scratch of
    /// [`RTreeRequirements::scratch`] entries.
    pub fn delete(&mut self, prim: u32, orphans: &mut [u32]) -> Result<bool, Error> {
        if orphans.len() < self.state.len as usize {
            return Err(Error::SliceTooSmall {
                slice: "orphans",
                needed: self.state.len as usize,
                got: orphans.len(),
            });
        }
        let Some(pb) = (prim as usize)
            .lt(&self.scene.prim_count())
            .then(|| self.prim_box(prim as usize))
            .flatten()
        else {
            return Ok(false);
        };
        // Depth-first search for the leaf holding it: (slot, next entry).
        let mut path = [(0u32, 0u32); MAX_HEIGHT + 1];
        let mut depth = 0usize;
        // A search visits each node once: more visits means a broken tree.
        let mut budget = self.nodes.len();
        let found = loop {
            budget = budget.checked_sub(1).ok_or(BROKEN)?;
            let (slot, next) = path[depth];
            let nd = self.node(slot)?;
            let n = self.entries(&nd)?;
            if nd.is_leaf() {
                let mut hit = None;
                for i in 0..n {
                    if self.reference(nd.first.wrapping_add(i))? == prim {
                        hit = Some(i);
                        break;
                    }
                }
                if let Some(i) = hit {
                    break Some(i);
                }
            } else if next < n {
                path[depth].1 += 1;
                let child = nd.first.wrapping_add(next);
                let cb = self.node(child)?.bounds();
                if cb.union(&pb) == cb {
                    if depth == MAX_HEIGHT {
                        return Err(BROKEN);
                    }
                    depth += 1;
                    path[depth] = (child, 0);
                }
                continue;
            }
            if depth == 0 {
                break None;
            }
            depth -= 1;
        };
        let Some(i) = found else { return Ok(false) };
        let leaf = path[depth].0;
        let nd = self.node(leaf)?;
        let last = self.reference(nd.first.wrapping_add(nd.len() - 1))?;
        *self.reference_mut(nd.first.wrapping_add(i))? = last;
        self.node_mut(leaf)?.set_len(nd.len() - 1);
        self.state.len = self.state.len.checked_sub(1).ok_or(BROKEN)?;
        self.digest(prim, false);
        // CondenseTree: dissolve underfull nodes on the path, bottom up.
        let mut orphan_count = 0usize;
        for l in (1..=depth).rev() {
            let s = path[l].0;
            if self.node(s)?.len() >= self.params.min_children {
                self.refit(s)?;
                continue;
            }
            self.dissolve(s, orphans, &mut orphan_count)?;
            let parent = path[l - 1].0;
            let pn = self.node(parent)?;
            let last = pn
                .first
                .checked_add(pn.len())
                .and_then(|e| e.checked_sub(1))
                .ok_or(BROKEN)?;
            let moved = self.node(last)?;
            *self.node_mut(s)? = moved;
            self.node_mut(parent)?.set_len(pn.len() - 1);
        }
        self.refit(0)?;
        // Shorten: a root with one child is replaced by it.
        while !self.nodes[0].is_leaf() && self.nodes[0].len() <= 1 {
            let root = self.nodes[0];
            if root.is_empty() {
                self.free_block(false, root.first)?;
                let b = self.alloc_refs()?.ok_or(BROKEN)?;
                self.nodes[0] = BvhNode::leaf(&Aabb::EMPTY, b, 0);
                self.state.height = 0;
                break;
            }
            self.nodes[0] = self.node(root.first)?;
            self.free_block(false, root.first)?;
            self.state.height = self.state.height.checked_sub(1).ok_or(BROKEN)?;
        }
        self.state.len = self
            .state
            .len
            .checked_sub(orphan_count as u32)
            .ok_or(BROKEN)?;
        for &p in &orphans[..orphan_count] {
            self.digest(p, false);
        }
        for &p in &orphans[..orphan_count] {
            self.insert(p)?;
        }
        Ok(true)
    }

    /// Frees the subtree in `slot`, collecting its objects into `orphans`.
    fn dissolve(&mut self, slot: u32, orphans: &mut [u32], n: &mut usize) -> Result<(), Error> {
        let nd = self.node(slot)?;
        let mut take = |orphans: &mut [u32], p: u32| -> Result<(), Error> {
            *orphans.get_mut(*n).ok_or(BROKEN)? = p;
            *n += 1;
            Ok(())
        };
        if nd.is_leaf() {
            for i in 0..self.entries(&nd)? {
                take(orphans, self.reference(nd.first.wrapping_add(i))?)?;
            }
            return self.free_block(true, nd.first);
        }
        // Depth-first over the subtree's blocks: a block is freed only
        // after its entries are read (freeing overwrites its first slot).
        let mut stack = [(0u32, 0u32); MAX_HEIGHT * MAX_CHILDREN as usize];
        stack[0] = (nd.first, self.entries(&nd)?);
        let mut sp = 1;
        let mut budget = self.nodes.len();
        while sp > 0 {
            budget = budget.checked_sub(1).ok_or(BROKEN)?;
            sp -= 1;
            let (block, len) = stack[sp];
            for i in 0..len {
                let c = self.node(block.wrapping_add(i))?;
                if c.is_leaf() {
                    for k in 0..self.entries(&c)? {
                        take(orphans, self.reference(c.first.wrapping_add(k))?)?;
                    }
                    self.free_block(true, c.first)?;
                } else {
                    *stack.get_mut(sp).ok_or(BROKEN)? = (c.first, self.entries(&c)?);
                    sp += 1;
                }
            }
            self.free_block(false, block)?;
        }
        Ok(())
    }
}

/// What insert and delete return on a tree that breaks an invariant they
/// rely on (an index past its slices, a node over M, a free list that
/// runs dry): they never panic on memory a caller loaded.
const BROKEN: Error = Error::Corrupt {
    what: "R-tree invariant",
};

/// Guttman's quadratic split of `e` (M + 1 entries): true for entries of
/// the second group. Each group gets at least `m`.
fn quadratic_split(e: &[Entry], m: usize) -> [bool; MAX_CHILDREN as usize + 1] {
    let n = e.len();
    let mut second = [false; MAX_CHILDREN as usize + 1];
    let mut done = [false; MAX_CHILDREN as usize + 1];
    // PickSeeds: the pair wasting the most area together.
    let (mut s1, mut s2, mut worst) = (0, 1, f32::NEG_INFINITY);
    for i in 0..n {
        for j in i + 1..n {
            let (a, b) = (e[i].bounds(), e[j].bounds());
            let d = a.union(&b).area() - a.area() - b.area();
            if d > worst {
                (s1, s2, worst) = (i, j, d);
            }
        }
    }
    let (mut g1, mut g2) = (e[s1].bounds(), e[s2].bounds());
    let (mut n1, mut n2) = (1usize, 1usize);
    done[s1] = true;
    done[s2] = true;
    second[s2] = true;
    let mut left = n - 2;
    while left > 0 {
        // One group must take the rest to reach m.
        if n1 + left == m || n2 + left == m {
            let to_second = n2 + left == m;
            for i in 0..n {
                if !done[i] {
                    second[i] = to_second;
                    done[i] = true;
                }
            }
            break;
        }
        // PickNext: the entry with the strongest preference.
        let (mut pick, mut pref) = (usize::MAX, f32::NEG_INFINITY);
        for i in 0..n {
            if !done[i] {
                let b = e[i].bounds();
                let p = (enlarged(&g1, &b) - enlarged(&g2, &b)).abs();
                if p > pref || pick == usize::MAX {
                    (pick, pref) = (i, p);
                }
            }
        }
        let b = e[pick].bounds();
        let (d1, d2) = (enlarged(&g1, &b), enlarged(&g2, &b));
        let to_second = (d2, g2.area(), n2) < (d1, g1.area(), n1);
        done[pick] = true;
        second[pick] = to_second;
        if to_second {
            g2 = g2.union(&b);
            n2 += 1;
        } else {
            g1 = g1.union(&b);
            n1 += 1;
        }
        left -= 1;
    }
    second
}

/// The R* split: the axis with the smallest margin sum over all
/// distributions of the entries sorted by lower then by upper bound; on
/// it, the distribution with the least overlap, then the least area.
/// Reorders `e`; true for entries of the second group.
fn rstar_split(e: &mut [Entry], m: usize) -> [bool; MAX_CHILDREN as usize + 1] {
    let n = e.len();
    let sort = |e: &mut [Entry], axis: usize, upper: bool| {
        e.sort_unstable_by(|a, b| {
            let (ka, kb) = if upper {
                ((a.max[axis], a.min[axis]), (b.max[axis], b.min[axis]))
            } else {
                ((a.min[axis], a.max[axis]), (b.min[axis], b.max[axis]))
            };
            ka.0.total_cmp(&kb.0)
                .then(ka.1.total_cmp(&kb.1))
                .then(a.first.cmp(&b.first))
        })
    };
    // Boxes of the first k and of the rest, for every k.
    let groups = |e: &[Entry], k: usize| {
        let mut a = Aabb::EMPTY;
        let mut b = Aabb::EMPTY;
        for x in &e[..k] {
            a = a.union(&x.bounds());
        }
        for x in &e[k..] {
            b = b.union(&x.bounds());
        }
        (a, b)
    };
    let mut best_axis = (0usize, f32::INFINITY);
    for axis in 0..3 {
        let mut s = 0.0;
        for upper in [false, true] {
            sort(e, axis, upper);
            for k in m..=n - m {
                let (a, b) = groups(e, k);
                s += margin(&a) + margin(&b);
            }
        }
        if s < best_axis.1 {
            best_axis = (axis, s);
        }
    }
    let axis = best_axis.0;
    let mut best = (false, m, f32::INFINITY, f32::INFINITY);
    for upper in [false, true] {
        sort(e, axis, upper);
        for k in m..=n - m {
            let (a, b) = groups(e, k);
            let key = (a.intersection(&b).area(), a.area() + b.area());
            if key < (best.2, best.3) {
                best = (upper, k, key.0, key.1);
            }
        }
    }
    sort(e, axis, best.0);
    let mut second = [false; MAX_CHILDREN as usize + 1];
    for s in second.iter_mut().take(n).skip(best.1) {
        *s = true;
    }
    second
}
