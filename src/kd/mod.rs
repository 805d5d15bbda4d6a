//! SAH kd-trees (rectilinear BSP) over caller memory: build, ropes,
//! hierarchical and rope traversal, validation.
//!
//! ```text
//! let req = kd::requirements(scene.prim_count(), &params);   // element counts
//! // caller provides slices of those lengths
//! let tree = kd::build(&scene, &params, storage, scratch)?;
//! let mut stack = [KdStackItem::default(); KD_STACK_LEN];
//! let hit = tree.intersect(&ray, Traversal::Hierarchical, &mut stack, &mut stats);
//! ```

mod build;
mod build_jobs;
pub mod layout;
mod node;
pub(crate) mod packet;
mod ropes;
pub(crate) mod traverse;
mod validate;

pub use build::{build, build_depth_first, KdEvent};
pub use build_jobs::{
    build_begin, build_begin_for_threads, KdBuild, KdJob, KdJobReport, KdJobs, KD_MAX_JOBS,
};
pub use node::{
    KdInfo, KdNode, KdRopes, KdStackItem, KD_FLAG_COMPACT, KD_FLAG_ROPES, KD_FLAG_TRUNCATED,
    KD_MAGIC, KD_MAX_DEPTH, KD_STACK_LEN, KD_VERSION, MAX_CHILD_INDEX, NO_NODE, SHARED_EMPTY,
};
pub use packet::LANES as PACKET_LANES;
pub use traverse::{misses_trace_box, Decision, Traversal};
pub use validate::KdTreeStats;

use crate::geom::{Aabb, ClipBox};
use crate::{Error, Scene};

/// How a build decides where to stop, and what its SAH costs are.
///
/// Cost constants are those of Wald and Havran (2006): a traversal step costs
/// `cost_traversal` = 15, a ray-primitive test `cost_intersection` = 20, and a
/// split with an empty child is discounted by `empty_bonus` = 0.8.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KdParams {
    /// Deepest leaf allowed; 0 derives it from the primitive count as
    /// `round(8 + 1.3 log2 N)` (capped at [`KD_MAX_DEPTH`]).
    pub max_depth: u32,
    /// A node with at most this many primitives becomes a leaf.
    pub leaf_size: u32,
    /// When true, a node becomes a leaf whenever no split is cheaper than
    /// the leaf by the SAH; when false, split down to `leaf_size` or
    /// `max_depth` (a split that separates nothing still stops).
    pub sah_termination: bool,
    /// SAH cost of one traversal step.
    pub cost_traversal: f32,
    /// SAH cost of one ray-primitive test.
    pub cost_intersection: f32,
    /// Factor (in (0, 1]) applied to the cost of a split with an empty side.
    pub empty_bonus: f32,
    /// What a reference costs, in ray-primitive tests per ray through the
    /// scene's box: a split whose straddling primitives add `k` references
    /// costs `k * cost_reference * cost_intersection` more, scaled from the
    /// scene's box to the node's by their areas, so it must save as many
    /// tests as its references cost. Without it (0, the plain SAH) perfect
    /// splits keep cutting long thin triangles: SPD gears' `auto` tree
    /// wants 26 references per primitive; with `auto`'s 1e-4, 3.9. `auto`'s
    /// trees are up to 70% smaller and build up to 1.7x faster; packet
    /// traversal gains up to 13%, one-ray hierarchical traversal loses up
    /// to 10% on the same walk (`docs/design.md`, the kd build). 0 or
    /// more, finite.
    pub cost_reference: f32,
    /// Ideal room for references, as a multiple of the primitive count
    /// (references are duplicated where primitives straddle splits).
    pub refs_per_prim: u32,
    /// Whether the build makes ropes: a box and six neighbour links per
    /// leaf (48 bytes), which rope traversal and the LCTS casts walk. A tree
    /// without them traces [`Traversal::Ropes`] hierarchically (same hits)
    /// and refuses the casts that need them ([`Error::NoRopes`]).
    pub ropes: bool,
    /// Whether the build leaves out the empty leaves that empty-space cuts
    /// make beside a full child (a tree without ropes only: each leaf with
    /// ropes has a box of its own). Each costs a node of 8 bytes: `auto`'s
    /// trees are 16-25% smaller on most scenes, and the walks decode which
    /// child a node left out at every step (a few percent slower; the
    /// tree's [`KD_FLAG_COMPACT`] picks that walk once per trace). The
    /// leaves, references and every answer and count of a trace are the
    /// tree's without it.
    pub compact: bool,
}

impl KdParams {
    /// The LCTS paper's settings: maximum depth 16, a node with at most 2
    /// objects becomes a leaf, the plain SAH (no reference cost); ropes for
    /// its rope traversal and casts.
    pub const fn paper() -> KdParams {
        KdParams {
            max_depth: 16,
            leaf_size: 2,
            sah_termination: false,
            cost_traversal: 15.0,
            cost_intersection: 20.0,
            empty_bonus: 0.8,
            cost_reference: 0.0,
            refs_per_prim: 4,
            ropes: true,
            compact: false,
        }
    }

    /// SAH-driven termination with a depth bound from N, references costed
    /// ([`KdParams::cost_reference`] 1e-4); no ropes (the
    /// hierarchical and packet traversals need none; set
    /// [`KdParams::ropes`] for rope traversal and the LCTS casts).
    pub const fn auto() -> KdParams {
        KdParams {
            max_depth: 0,
            leaf_size: 1,
            sah_termination: true,
            cost_traversal: 15.0,
            cost_intersection: 20.0,
            empty_bonus: 0.8,
            cost_reference: 1e-4,
            refs_per_prim: 4,
            ropes: false,
            compact: false,
        }
    }

    /// [`KdParams::auto`] with ropes.
    pub const fn auto_with_ropes() -> KdParams {
        KdParams {
            ropes: true,
            ..KdParams::auto()
        }
    }

    /// [`KdParams::auto`] without its empty leaves beside full ones
    /// ([`KdParams::compact`]): the least memory, for small targets.
    pub const fn compact() -> KdParams {
        KdParams {
            compact: true,
            ..KdParams::auto()
        }
    }

    /// Checks every field's range.
    pub fn check(&self) -> Result<(), Error> {
        if self.max_depth > KD_MAX_DEPTH {
            return Err(Error::InvalidParameter { name: "max_depth" });
        }
        if !(self.cost_traversal > 0.0 && self.cost_traversal.is_finite()) {
            return Err(Error::InvalidParameter {
                name: "cost_traversal",
            });
        }
        if !(self.cost_intersection > 0.0 && self.cost_intersection.is_finite()) {
            return Err(Error::InvalidParameter {
                name: "cost_intersection",
            });
        }
        if !(self.empty_bonus > 0.0 && self.empty_bonus <= 1.0) {
            return Err(Error::InvalidParameter {
                name: "empty_bonus",
            });
        }
        if !(self.cost_reference >= 0.0 && self.cost_reference.is_finite()) {
            return Err(Error::InvalidParameter {
                name: "cost_reference",
            });
        }
        if self.refs_per_prim == 0 || self.refs_per_prim > 64 {
            return Err(Error::InvalidParameter {
                name: "refs_per_prim",
            });
        }
        if self.compact && self.ropes {
            return Err(Error::InvalidParameter { name: "compact" });
        }
        Ok(())
    }

    /// The depth bound in force for `prim_count` primitives.
    pub fn depth_limit(&self, prim_count: usize) -> u32 {
        if self.max_depth != 0 {
            return self.max_depth;
        }
        let log2 = if prim_count <= 1 {
            0.0
        } else {
            libm::log2f(prim_count as f32)
        };
        (libm::roundf(8.0 + 1.3 * log2) as u32).min(KD_MAX_DEPTH)
    }
}

impl Default for KdParams {
    fn default() -> Self {
        KdParams::auto()
    }
}

/// Element counts of the slices a build needs. The tree's own slices
/// (`nodes`, `ropes`, `rope_ids`, `refs`) are kept; the scratch slices
/// (`events`, `prim_flags`) may be reused once the build returns.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct KdRequirements {
    /// [`KdNode`] slots.
    pub nodes: usize,
    /// [`KdRopes`] slots, one per leaf a tree of `nodes` nodes can have
    /// (`(nodes + 1) / 2`), for a build with ropes; else 0.
    pub ropes: usize,
    /// Rope index slots (`u32`), one per node, for a build with ropes; else 0.
    pub rope_ids: usize,
    /// Primitive references (`u32`).
    pub refs: usize,
    /// Build scratch: [`KdEvent`] slots.
    pub events: usize,
    /// Build scratch: one byte per primitive.
    pub prim_flags: usize,
}

/// The room for a tree of `prim_count` primitives that does not stop
/// splitting for lack of space in ordinary scenes: `refs_per_prim * N`
/// references and a [`REFS_SLACK`]-th more, [`NODES_PER_REF`] nodes and
/// [`EVENTS_PER_REF`] events of scratch per reference of `refs_per_prim *
/// N`.
///
/// A build given less (down to [`min_requirements`]) still succeeds; it
/// stops splitting where room runs out and sets [`KD_FLAG_TRUNCATED`]. A
/// scene may need more than `refs_per_prim` references per primitive (SPD
/// gears' tree under [`KdParams::auto`] takes 26.5 when given room for 64),
/// or more nodes per reference; it is then truncated too.
pub fn requirements(prim_count: usize, params: &KdParams) -> KdRequirements {
    let n = prim_count.max(1);
    let asked = n * params.refs_per_prim.max(1) as usize;
    let refs = asked + asked / REFS_SLACK;
    let nodes = asked * NODES_PER_REF.0 / NODES_PER_REF.1 + 1;
    let leaves = nodes.div_ceil(2);
    KdRequirements {
        nodes,
        ropes: if params.ropes { leaves } else { 0 },
        rope_ids: if params.ropes { nodes } else { 0 },
        refs,
        events: EVENTS_PER_REF * asked,
        prim_flags: prim_count,
    }
}

/// The references [`requirements`] asks for beyond `refs_per_prim` per
/// primitive, as a fraction of them: a sixteenth (4.25 per primitive at
/// the default 4; one byte per primitive more). A job build shares the
/// references among its jobs in proportion to their primitives, not to
/// what their subtrees need: SPD gears' tree takes 3.9 per primitive, and
/// one of its two jobs more than 4, so it ran out of its share and ran
/// again alone, after the others (`coray bench --table build --threads 2`:
/// gears' two-thread build 1.45x the one-thread one's speed). Nodes and
/// events are not raised with them.
pub const REFS_SLACK: usize = 16;

/// Nodes [`requirements`] asks for per reference, as a fraction: 5/2.
/// Trees take about two nodes per reference they hold (an empty leaf
/// beside most full ones): at most 2.0 on the SPD scenes and `random`
/// under both presets (`tree` 2.0, `rings` 1.85, `random` 1.77, `teapot`
/// 1.69), and fewer references than the room holds. The slack above that
/// keeps each job of a build within its share of the nodes (none ran
/// again at 5/2; the shares are in proportion to primitives, not to
/// what a subtree needs).
pub const NODES_PER_REF: (usize, usize) = (5, 2);

/// Events of scratch [`requirements`] asks for per reference: 6. A
/// depth-first build's events peak at the root's split, about 12 per
/// primitive (its six events, the straddlers' new ones and the merged
/// copies); a job build parks each job's events with an untouched copy
/// (to run it again when it outgrows its shares), about twice that. At
/// `refs_per_prim` 4 this is 24 per primitive: every SPD scene and
/// `random` build the same trees with no job run again.
pub const EVENTS_PER_REF: usize = 6;

/// The least room a build accepts: one leaf holding every primitive (and
/// its ropes, when `params` asks for them; a compact tree's shared empty
/// leaf too), and the six events per primitive of the root's sweep.
pub fn min_requirements(prim_count: usize, params: &KdParams) -> KdRequirements {
    KdRequirements {
        // The root, and a compact tree's shared empty leaf (`SHARED_EMPTY`).
        nodes: build::first_pair(params),
        ropes: params.ropes as usize,
        rope_ids: params.ropes as usize,
        refs: prim_count,
        events: 6 * prim_count,
        prim_flags: prim_count,
    }
}

/// Slices that will hold the tree. Their lengths set the capacities; any
/// length from [`min_requirements`] up is accepted.
pub struct KdStorage<'a> {
    /// Nodes.
    pub nodes: &'a mut [KdNode],
    /// Ropes and boxes, one per leaf, for a build with ropes; ignored (may
    /// be empty) for one without. A build makes at most this many leaves.
    pub ropes: &'a mut [KdRopes],
    /// Each node's rope record (leaves) or [`NO_NODE`] (interior nodes),
    /// for a build with ropes; ignored (may be empty) for one without. A
    /// build makes at most this many nodes.
    pub rope_ids: &'a mut [u32],
    /// Primitive references.
    pub refs: &'a mut [u32],
}

/// Scratch for one build; free again when the build returns.
pub struct KdScratch<'s> {
    /// Split events.
    pub events: &'s mut [KdEvent],
    /// One byte per primitive.
    pub prim_flags: &'s mut [u8],
}

/// A built kd-tree borrowing its parts and the scene it was built on.
/// Immutable: share it between threads. Made only by [`build`] and by
/// [`KdTree::from_parts`].
#[derive(Clone, Copy, Debug)]
pub struct KdTree<'a> {
    pub(crate) scene: Scene<'a>,
    pub(crate) info: KdInfo,
    /// `info.trace_bounds()`, computed once: the box every ray is clipped
    /// to before it walks (with SIMD-width corners: [`ClipBox`] says why).
    pub(crate) trace_box: ClipBox,
    /// `info.node_count` nodes; node 0 is the root.
    pub(crate) nodes: &'a [KdNode],
    /// `info.rope_count()` rope records: one per leaf, or none.
    pub(crate) ropes: &'a [KdRopes],
    /// `info.rope_id_count()` entries: each node's rope record, or none.
    pub(crate) rope_ids: &'a [u32],
    /// `info.ref_count` references (global primitive indices).
    pub(crate) refs: &'a [u32],
}

impl<'a> KdTree<'a> {
    /// Reassembles a tree from parts read back from memory, with O(1) checks
    /// (magic, version, counts within the slices, the scene's counts). Run
    /// [`KdTree::validate`] on parts from untrusted storage: until it
    /// accepts them, traversal never panics or hangs on them, but may stop
    /// early with [`crate::TraceStats::faults`] counted.
    #[inline]
    pub fn from_parts(
        scene: Scene<'a>,
        info: KdInfo,
        nodes: &'a [KdNode],
        ropes: &'a [KdRopes],
        rope_ids: &'a [u32],
        refs: &'a [u32],
    ) -> Result<KdTree<'a>, Error> {
        if info.magic != KD_MAGIC {
            return Err(Error::Corrupt { what: "magic" });
        }
        if info.version != KD_VERSION {
            return Err(Error::Corrupt { what: "version" });
        }
        if info.node_count == 0
            || info.node_count as usize > nodes.len()
            || info.rope_count() as usize > ropes.len()
            || info.rope_id_count() as usize > rope_ids.len()
            || info.ref_count as usize > refs.len()
            || info.depth > KD_MAX_DEPTH
        {
            return Err(Error::Corrupt { what: "counts" });
        }
        let tree = KdTree::from_checked_parts(
            scene,
            &info,
            &nodes[..info.node_count as usize],
            &ropes[..info.rope_count() as usize],
            &rope_ids[..info.rope_id_count() as usize],
            &refs[..info.ref_count as usize],
        );
        tree.check_scene(&scene)?;
        Ok(tree)
    }

    /// [`KdTree::from_parts`] for parts that passed its checks before and
    /// are unchanged since (a C tracer's, checked when it was made): nothing
    /// is checked again. Safe on any parts: the slices are taken as they are,
    /// and traversal of parts that do not match `info` only counts faults.
    #[inline]
    pub fn from_checked_parts(
        scene: Scene<'a>,
        info: &KdInfo,
        nodes: &'a [KdNode],
        ropes: &'a [KdRopes],
        rope_ids: &'a [u32],
        refs: &'a [u32],
    ) -> KdTree<'a> {
        let trace_box = info.trace_bounds();
        KdTree::from_checked_parts_with_trace_box(
            scene, info, trace_box, nodes, ropes, rope_ids, refs,
        )
    }

    /// [`KdTree::from_checked_parts`] with `info.trace_bounds()` computed
    /// once before and passed as `trace_box`, for a caller that views the
    /// same tree once per ray (a C tracer keeps the box in its own words:
    /// about 30 instructions a call). Another box only changes answers:
    /// rays are clipped to it before they walk.
    #[inline]
    pub fn from_checked_parts_with_trace_box(
        scene: Scene<'a>,
        info: &KdInfo,
        trace_box: Aabb,
        nodes: &'a [KdNode],
        ropes: &'a [KdRopes],
        rope_ids: &'a [u32],
        refs: &'a [u32],
    ) -> KdTree<'a> {
        KdTree {
            scene,
            info: *info,
            trace_box: ClipBox::of(&trace_box),
            nodes,
            ropes,
            rope_ids,
            refs,
        }
    }

    /// Errors unless `scene` has the primitive counts this tree was built on.
    #[inline]
    pub fn check_scene(&self, scene: &Scene) -> Result<(), Error> {
        let i = &self.info;
        if scene.triangles.len() != i.triangle_count as usize
            || scene.spheres.len() != i.sphere_count as usize
            || scene.cones.len() != i.cone_count as usize
        {
            return Err(Error::SceneMismatch);
        }
        Ok(())
    }

    /// Counts, bounds, scene fingerprint: what an arena header records.
    pub fn info(&self) -> &KdInfo {
        &self.info
    }

    /// The scene the tree was built on.
    pub fn scene(&self) -> &Scene<'a> {
        &self.scene
    }

    /// The tree's parts: nodes (node 0 the root), the leaves' boxes and
    /// ropes and each node's rope record (both empty without ropes), and
    /// the references (global primitive indices).
    pub fn parts(&self) -> (&'a [KdNode], &'a [KdRopes], &'a [u32], &'a [u32]) {
        (self.nodes, self.ropes, self.rope_ids, self.refs)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cost_reference_is_zero_or_more_and_finite() {
        assert_eq!(KdParams::paper().cost_reference, 0.0);
        assert!(KdParams::auto().cost_reference > 0.0);
        for (cost, ok) in [
            (0.0, true),
            (1e-4, true),
            (f32::MAX, true),
            (-1e-4, false),
            (f32::NAN, false),
            (f32::INFINITY, false),
        ] {
            let p = KdParams {
                cost_reference: cost,
                ..KdParams::auto()
            };
            assert_eq!(p.check().is_ok(), ok, "{cost}");
        }
    }
}
