//! Owned storage for every structure (feature `alloc`): the slices a build
//! needs, sized by the family's requirements, in `Vec`s. For std users, the
//! CLI and the tests; the core itself never allocates.
//!
//! Each owner is made in two steps, so a caller can time the build alone:
//! `with_room` allocates, `build` fills. `view` (or `tree`) lends the built
//! structure over the scene it was built on.

use crate::bvh::{self, Builder, Bvh, BvhInfo, BvhNode, BvhStackItem, RTree, RTreeParams};
use crate::kd::{self, KdEvent, KdInfo, KdNode, KdParams, KdRequirements, KdRopes, KdTree};
use crate::lcts::hlcts::HlctsEntry;
use crate::lcts::{CornerInfo, HistoryRecord, ImageRequirements, ImageScratch};
use crate::proj::{self, Criteria, ProjBuilder, ProjHierarchy, ProjPlane, Rect};
use crate::wide::{self, WideBvh, WideInfo, WideNode};
use crate::{Aabb, Error, Scene};
use alloc::vec;
use alloc::vec::Vec;

/// A stack of `n` default entries, for any structure's traces.
pub fn stack<T: Copy + Default>(n: usize) -> Vec<T> {
    vec![T::default(); n]
}

/// A kd-tree's parts and its build scratch.
pub struct OwnedKd {
    nodes: Vec<KdNode>,
    ropes: Vec<KdRopes>,
    rope_ids: Vec<u32>,
    refs: Vec<u32>,
    events: Vec<KdEvent>,
    flags: Vec<u8>,
    info: KdInfo,
}

impl OwnedKd {
    /// Room for `req` (from [`kd::requirements`] or [`kd::min_requirements`]).
    pub fn with_room(req: &KdRequirements) -> OwnedKd {
        OwnedKd {
            nodes: vec![KdNode::default(); req.nodes],
            ropes: vec![KdRopes::default(); req.ropes],
            rope_ids: vec![0; req.rope_ids],
            refs: vec![0; req.refs],
            events: vec![KdEvent::default(); req.events],
            flags: vec![0; req.prim_flags],
            info: KdInfo::default(),
        }
    }

    /// Builds into this room; the scratch is freed afterwards.
    pub fn build(&mut self, scene: &Scene, params: &KdParams) -> Result<(), Error> {
        self.build_with_jobs(scene, params, 1, |_| {})
    }

    /// Builds into this room as [`Self::build`] does, handing the build's
    /// jobs, made for `threads` threads (0: not known), to `run_jobs`
    /// (which may run them on other threads: see
    /// [`kd::build_begin_for_threads`]); jobs it leaves run on this thread.
    pub fn build_with_jobs(
        &mut self,
        scene: &Scene,
        params: &KdParams,
        threads: usize,
        run_jobs: impl FnOnce(kd::KdJobs<'_>),
    ) -> Result<(), Error> {
        let mut b = kd::build_begin_for_threads(
            scene,
            params,
            kd::KdStorage {
                nodes: &mut self.nodes,
                ropes: &mut self.ropes,
                rope_ids: &mut self.rope_ids,
                refs: &mut self.refs,
            },
            kd::KdScratch {
                events: &mut self.events,
                prim_flags: &mut self.flags,
            },
            threads,
        )?;
        run_jobs(b.jobs());
        self.info = *b.finish()?.info();
        self.events = Vec::new();
        self.flags = Vec::new();
        Ok(())
    }

    /// A tree over `scene` with the ideal room for `params`.
    pub fn new(scene: &Scene, params: &KdParams) -> Result<OwnedKd, Error> {
        let mut o = OwnedKd::with_room(&kd::requirements(scene.prim_count(), params));
        o.build(scene, params)?;
        Ok(o)
    }

    /// The built tree over `scene` (the scene it was built on).
    pub fn tree<'a>(&'a self, scene: Scene<'a>) -> Result<KdTree<'a>, Error> {
        KdTree::from_parts(
            scene,
            self.info,
            &self.nodes,
            &self.ropes,
            &self.rope_ids,
            &self.refs,
        )
    }

    /// What the build made.
    pub fn info(&self) -> &KdInfo {
        &self.info
    }

    /// Bytes of a C arena holding exactly what the tree uses.
    pub fn arena_bytes(&self) -> usize {
        kd::layout::KdArenaLayout::used_by(&self.info).unwrap_or(usize::MAX)
    }

    /// The parts the tree uses, to corrupt in tests or copy elsewhere.
    pub fn parts_mut(&mut self) -> (&mut [KdNode], &mut [KdRopes], &mut [u32], &mut [u32]) {
        let i = self.info;
        (
            &mut self.nodes[..i.node_count as usize],
            &mut self.ropes[..i.rope_count() as usize],
            &mut self.rope_ids[..i.rope_id_count() as usize],
            &mut self.refs[..i.ref_count as usize],
        )
    }
}

/// How an [`OwnedBvh`] is built: a static builder with its leaf size, or
/// an R-tree.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BvhBuild {
    /// TDBS, TDBS-SAH, NN or NN chain, with at most this many per leaf.
    Static(Builder, u32),
    /// An R-tree or R*-tree.
    RTree(RTreeParams),
}

/// A hierarchy's parts (for an R-tree, also its parameters and state).
pub struct OwnedBvh {
    nodes: Vec<BvhNode>,
    refs: Vec<u32>,
    boxes: Vec<Aabb>,
    keys: Vec<f32>,
    links: Vec<u32>,
    clusters: Vec<BvhNode>,
    how: BvhBuild,
    info: BvhInfo,
    rtree: bvh::RTreeState,
}

impl OwnedBvh {
    /// Room for `how` over `prim_count` primitives (an R-tree's capacity).
    pub fn with_room(prim_count: usize, how: BvhBuild) -> OwnedBvh {
        let (nodes, refs, scratch) = match how {
            BvhBuild::Static(b, _) => {
                let r = bvh::requirements(prim_count, b);
                (r.nodes, r.refs, r)
            }
            BvhBuild::RTree(p) => {
                let r = bvh::RTree::requirements(prim_count, &p);
                let s = bvh::BvhRequirements {
                    links: r.scratch,
                    ..Default::default()
                };
                (r.nodes, r.refs, s)
            }
        };
        OwnedBvh {
            nodes: vec![BvhNode::default(); nodes],
            refs: vec![0; refs],
            boxes: vec![Aabb::EMPTY; scratch.boxes],
            keys: vec![0.0; scratch.keys],
            links: vec![0; scratch.links],
            clusters: vec![BvhNode::default(); scratch.clusters],
            how,
            info: BvhInfo::default(),
            rtree: bvh::RTreeState::default(),
        }
    }

    /// Builds into this room. The static builders' scratch is freed; an
    /// R-tree keeps its order buffer as the orphans scratch of deletes.
    pub fn build(&mut self, scene: &Scene) -> Result<(), Error> {
        match self.how {
            BvhBuild::Static(b, leaf_size) => {
                let t = bvh::build(
                    scene,
                    b,
                    leaf_size,
                    bvh::BvhStorage {
                        nodes: &mut self.nodes,
                        refs: &mut self.refs,
                    },
                    bvh::BvhScratch {
                        boxes: &mut self.boxes,
                        keys: &mut self.keys,
                        links: &mut self.links,
                        clusters: &mut self.clusters,
                    },
                )?;
                self.info = *t.info();
                self.boxes = Vec::new();
                self.keys = Vec::new();
                self.links = Vec::new();
                self.clusters = Vec::new();
            }
            BvhBuild::RTree(p) => {
                let t = RTree::build(scene, p, &mut self.nodes, &mut self.refs, &mut self.links)?;
                self.info = *t.bvh().info();
                self.rtree = t.state();
            }
        }
        Ok(())
    }

    /// A hierarchy over `scene` built with `how`.
    pub fn new(scene: &Scene, how: BvhBuild) -> Result<OwnedBvh, Error> {
        let mut o = OwnedBvh::with_room(scene.prim_count(), how);
        o.build(scene)?;
        Ok(o)
    }

    /// The built hierarchy over `scene` (the scene it was built on).
    pub fn view<'a>(&'a self, scene: Scene<'a>) -> Result<Bvh<'a>, Error> {
        Bvh::from_parts(scene, &self.nodes, &self.refs, self.info)
    }

    /// An R-tree's validation with its fill rules, or the plain one.
    pub fn validate(&self, scene: Scene) -> Result<bvh::BvhTreeStats, Error> {
        let b = self.view(scene)?;
        let mut st = stack::<BvhStackItem>(b.stack_len());
        match self.how {
            BvhBuild::RTree(p) => bvh::validate_rtree(&b, &p, &self.rtree, &mut st),
            BvhBuild::Static(..) => b.validate(None, &mut st),
        }
    }

    /// Inserts (`true`) or deletes primitive `prim` of an R-tree; false
    /// from a delete when it was not there.
    pub fn update(&mut self, scene: &Scene, prim: u32, insert: bool) -> Result<bool, Error> {
        let BvhBuild::RTree(p) = self.how else {
            return Err(Error::InvalidParameter { name: "builder" });
        };
        let mut t = RTree::resume(scene, p, &mut self.nodes, &mut self.refs, self.rtree)?;
        let r = if insert {
            t.insert(prim).map(|_| true)
        } else {
            t.delete(prim, &mut self.links)
        };
        self.info = *t.bvh().info();
        self.rtree = t.state();
        r
    }

    /// What the build made.
    pub fn info(&self) -> &BvhInfo {
        &self.info
    }

    /// Bytes of the nodes in use and the references.
    pub fn bytes(&self) -> usize {
        self.info.node_count as usize * core::mem::size_of::<BvhNode>()
            + self.info.ref_count as usize * 4
    }

    /// The parts, to corrupt in tests.
    pub fn parts_mut(&mut self) -> (&mut [BvhNode], &mut [u32], &mut BvhInfo) {
        (&mut self.nodes, &mut self.refs, &mut self.info)
    }

    /// An R-tree's state (free lists, counts, digest), to corrupt in tests.
    pub fn rtree_state_mut(&mut self) -> &mut bvh::RTreeState {
        &mut self.rtree
    }
}

/// A wide hierarchy's parts and its build scratch.
pub struct OwnedWide {
    nodes: Vec<WideNode>,
    blocks: Vec<wide::LeafBlock>,
    refs: Vec<u32>,
    bvh_nodes: Vec<BvhNode>,
    boxes: Vec<Aabb>,
    keys: Vec<f32>,
    links: Vec<u32>,
    info: WideInfo,
}

impl OwnedWide {
    /// Room for a wide hierarchy over `prim_count` primitives.
    pub fn with_room(prim_count: usize) -> OwnedWide {
        let r = wide::requirements(prim_count);
        OwnedWide {
            nodes: vec![WideNode::default(); r.nodes],
            blocks: vec![wide::EMPTY_BLOCK; r.blocks],
            refs: vec![0; r.refs],
            bvh_nodes: vec![BvhNode::default(); r.bvh_nodes],
            boxes: vec![Aabb::EMPTY; r.boxes],
            keys: vec![0.0; r.keys],
            links: vec![0; r.links],
            info: WideInfo::default(),
        }
    }

    /// Builds into this room with leaves of at most `leaf_size`; the
    /// scratch is freed afterwards, and the parts shrunk to what the
    /// hierarchy uses.
    pub fn build(&mut self, scene: &Scene, leaf_size: u32) -> Result<(), Error> {
        let t = wide::build(
            scene,
            leaf_size,
            wide::WideStorage {
                nodes: &mut self.nodes,
                blocks: &mut self.blocks,
            },
            wide::WideScratch {
                refs: &mut self.refs,
                bvh_nodes: &mut self.bvh_nodes,
                boxes: &mut self.boxes,
                keys: &mut self.keys,
                links: &mut self.links,
            },
        )?;
        self.info = *t.info();
        self.nodes.truncate(self.info.node_count as usize);
        self.nodes.shrink_to_fit();
        self.blocks.truncate(self.info.block_count as usize);
        self.blocks.shrink_to_fit();
        self.refs = Vec::new();
        self.bvh_nodes = Vec::new();
        self.boxes = Vec::new();
        self.keys = Vec::new();
        self.links = Vec::new();
        Ok(())
    }

    /// A wide hierarchy over `scene` with leaves of at most `leaf_size`.
    pub fn new(scene: &Scene, leaf_size: u32) -> Result<OwnedWide, Error> {
        let mut o = OwnedWide::with_room(scene.prim_count());
        o.build(scene, leaf_size)?;
        Ok(o)
    }

    /// The built hierarchy over `scene` (the scene it was built on).
    pub fn view<'a>(&'a self, scene: Scene<'a>) -> Result<WideBvh<'a>, Error> {
        WideBvh::from_parts(scene, &self.nodes, &self.blocks, self.info)
    }

    /// What the build made.
    pub fn info(&self) -> &WideInfo {
        &self.info
    }

    /// Bytes of the nodes and leaf blocks in use.
    pub fn bytes(&self) -> usize {
        let i = &self.info;
        i.node_count as usize * core::mem::size_of::<WideNode>()
            + i.block_count as usize * core::mem::size_of::<wide::LeafBlock>()
    }

    /// The parts, to corrupt in tests.
    pub fn parts_mut(&mut self) -> (&mut [WideNode], &mut [wide::LeafBlock], &mut WideInfo) {
        (&mut self.nodes, &mut self.blocks, &mut self.info)
    }
}

/// A projection build's scratch: the builder's boxes, keys, links and
/// clusters, the source boxes and the refit's stack.
type ProjBuildScratch = (
    Vec<Aabb>,
    Vec<f32>,
    Vec<u32>,
    Vec<BvhNode>,
    Vec<Aabb>,
    Vec<u32>,
);

/// A projection hierarchy's parts and build scratch.
pub struct OwnedProj {
    nodes: Vec<BvhNode>,
    refs: Vec<u32>,
    rects: Vec<Rect>,
    prim_rects: Vec<Rect>,
    scratch: ProjBuildScratch,
    info: BvhInfo,
    plane: ProjPlane,
}

impl OwnedProj {
    /// Room for a hierarchy by `builder` over `prim_count` primitives.
    pub fn with_room(prim_count: usize, builder: &ProjBuilder, plane: ProjPlane) -> OwnedProj {
        let req = proj::requirements(prim_count, builder);
        let s = &req.bvh_scratch;
        OwnedProj {
            nodes: vec![BvhNode::default(); req.nodes],
            refs: vec![0; req.refs],
            rects: vec![Rect::EMPTY; req.rects],
            prim_rects: vec![Rect::EMPTY; req.prim_rects],
            scratch: (
                vec![Aabb::EMPTY; s.boxes],
                vec![0.0; s.keys],
                vec![0; s.links],
                vec![BvhNode::default(); s.clusters],
                vec![Aabb::EMPTY; req.source],
                vec![0; req.stack],
            ),
            info: BvhInfo::default(),
            plane,
        }
    }

    /// Builds into this room; the scratch is freed afterwards.
    pub fn build(
        &mut self,
        scene: &Scene,
        builder: ProjBuilder,
        criteria: Criteria,
    ) -> Result<(), Error> {
        let (boxes, keys, links, clusters, source, stack) = &mut self.scratch;
        let h = proj::build(
            scene,
            self.plane,
            builder,
            criteria,
            proj::ProjStorage {
                nodes: &mut self.nodes,
                refs: &mut self.refs,
                rects: &mut self.rects,
                prim_rects: &mut self.prim_rects,
            },
            proj::ProjScratch {
                bvh: bvh::BvhScratch {
                    boxes,
                    keys,
                    links,
                    clusters,
                },
                source,
                stack,
            },
        )?;
        self.info = *h.bvh().info();
        self.scratch = Default::default();
        Ok(())
    }

    /// A hierarchy of `scene` on `plane`.
    pub fn new(
        scene: &Scene,
        plane: ProjPlane,
        builder: ProjBuilder,
        criteria: Criteria,
    ) -> Result<OwnedProj, Error> {
        let mut o = OwnedProj::with_room(scene.prim_count(), &builder, plane);
        o.build(scene, builder, criteria)?;
        Ok(o)
    }

    /// The built hierarchy over `scene` (the scene it was built on).
    pub fn view<'a>(&'a self, scene: Scene<'a>) -> Result<ProjHierarchy<'a>, Error> {
        let b = Bvh::from_parts(scene, &self.nodes, &self.refs, self.info)?;
        ProjHierarchy::from_parts(b, &self.rects, &self.prim_rects, self.plane)
    }

    /// What the build made.
    pub fn info(&self) -> &BvhInfo {
        &self.info
    }

    /// The parts, to corrupt in tests.
    pub fn parts_mut(&mut self) -> (&mut [BvhNode], &mut [u32], &mut [Rect], &mut [Rect]) {
        (
            &mut self.nodes,
            &mut self.refs,
            &mut self.rects,
            &mut self.prim_rects,
        )
    }
}

/// Scratch for [`crate::lcts::cast_image`].
pub struct OwnedCast {
    records: Vec<HistoryRecord>,
    entries: Vec<u32>,
    corners: Vec<CornerInfo>,
    starts: Vec<u32>,
    hlcts: Vec<HlctsEntry>,
    stack: Vec<kd::KdStackItem>,
}

impl OwnedCast {
    /// Room for `req` (from [`crate::lcts::image_requirements`]).
    pub fn new(req: &ImageRequirements) -> OwnedCast {
        OwnedCast {
            records: vec![HistoryRecord::default(); req.records],
            entries: vec![0; req.entries],
            corners: vec![CornerInfo::default(); req.corners],
            starts: vec![0; req.starts],
            hlcts: vec![HlctsEntry::default(); req.hlcts],
            stack: vec![kd::KdStackItem::default(); req.stack],
        }
    }

    /// The scratch to lend a cast.
    pub fn scratch(&mut self) -> ImageScratch<'_> {
        ImageScratch {
            records: &mut self.records,
            entries: &mut self.entries,
            corners: &mut self.corners,
            starts: &mut self.starts,
            hlcts: &mut self.hlcts,
            stack: &mut self.stack,
        }
    }
}

/// Scratch for [`crate::lcts::patch::patch_visibility`], histories of up
/// to `capacity` records.
pub struct OwnedPatch {
    records: Vec<HistoryRecord>,
    hlcts: Vec<HlctsEntry>,
    paths: Vec<u32>,
    stack: Vec<kd::KdStackItem>,
}

impl OwnedPatch {
    /// Room for histories of `capacity` records.
    pub fn new(capacity: usize) -> OwnedPatch {
        let k = crate::lcts::hlcts::MAX_RAYS * capacity.max(1);
        OwnedPatch {
            records: vec![HistoryRecord::default(); k],
            hlcts: vec![HlctsEntry::default(); k],
            paths: vec![0; k],
            stack: vec![kd::KdStackItem::default(); kd::KD_STACK_LEN],
        }
    }

    /// The scratch to lend a query.
    pub fn scratch(&mut self) -> crate::lcts::patch::PatchScratch<'_> {
        crate::lcts::patch::PatchScratch {
            records: &mut self.records,
            hlcts: &mut self.hlcts,
            paths: &mut self.paths,
            stack: &mut self.stack,
        }
    }
}
