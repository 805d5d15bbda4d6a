//! Owned storage for the hierarchies of `coray::bvh`, built by name.

use coray::bvh::{
    self, rtree_requirements, Builder, Bvh, BvhNode, BvhScratch, BvhStorage, RTree, RTreeParams,
};
use coray::{Aabb, Scene};
use std::time::Instant;

/// The hierarchy methods, as `coray bench` names them.
pub const METHODS: [&str; 7] = [
    "tdbs",
    "tdbs-sah",
    "nn",
    "nn-chain",
    "rtree",
    "rstar",
    "rstar-reinsert",
];

/// A built hierarchy's memory and what the build took.
pub struct OwnedBvh {
    nodes: Vec<BvhNode>,
    refs: Vec<u32>,
    info: bvh::BvhInfo,
    pub build_ms: f64,
}

impl OwnedBvh {
    /// Builds `method` over `scene` (scratch is dropped afterwards; the
    /// time excludes allocation).
    pub fn build(scene: &Scene, method: &str) -> Result<OwnedBvh, String> {
        let n = scene.prim_count();
        let rtree = match method {
            "rtree" => Some(RTreeParams::rtree()),
            "rstar" => Some(RTreeParams::rstar()),
            "rstar-reinsert" => Some(RTreeParams {
                forced_reinsert: true,
                ..RTreeParams::rstar()
            }),
            _ => None,
        };
        if let Some(p) = rtree {
            let req = rtree_requirements(n, &p);
            let mut nodes = vec![BvhNode::default(); req.nodes];
            let mut refs = vec![0u32; req.refs];
            let mut order = vec![0u32; req.scratch];
            let t = Instant::now();
            let tree = RTree::build(scene, p, &mut nodes, &mut refs, &mut order)
                .map_err(|e| format!("{method} build: {e}"))?;
            let build_ms = t.elapsed().as_secs_f64() * 1e3;
            let info = tree.bvh().info;
            return Ok(OwnedBvh {
                nodes,
                refs,
                info,
                build_ms,
            });
        }
        let builder = match method {
            "tdbs" => Builder::Tdbs,
            "tdbs-sah" => Builder::TdbsSah,
            "nn" => Builder::Nn,
            "nn-chain" => Builder::NnChain,
            m => return Err(format!("unknown hierarchy `{m}`")),
        };
        let req = bvh::requirements(n, builder);
        let mut nodes = vec![BvhNode::default(); req.nodes];
        let mut refs = vec![0u32; req.refs];
        let mut boxes = vec![Aabb::EMPTY; req.boxes];
        let mut keys = vec![0f32; req.keys];
        let mut links = vec![0u32; req.links];
        let mut clusters = vec![BvhNode::default(); req.clusters];
        let t = Instant::now();
        let storage = BvhStorage {
            nodes: &mut nodes,
            refs: &mut refs,
        };
        let scratch = BvhScratch {
            boxes: &mut boxes,
            keys: &mut keys,
            links: &mut links,
            clusters: &mut clusters,
        };
        let built = bvh::build(scene, builder, 1, storage, scratch)
            .map_err(|e| format!("{method} build: {e}"))?;
        let info = built.info;
        let build_ms = t.elapsed().as_secs_f64() * 1e3;
        Ok(OwnedBvh {
            nodes,
            refs,
            info,
            build_ms,
        })
    }

    /// The hierarchy over `scene` (the scene it was built on).
    pub fn bvh<'a>(&'a self, scene: Scene<'a>) -> Bvh<'a> {
        Bvh {
            scene,
            nodes: &self.nodes,
            refs: &self.refs,
            info: self.info,
        }
    }

    /// Bytes of the nodes in use and the references.
    pub fn bytes(&self) -> usize {
        self.info.node_count as usize * std::mem::size_of::<BvhNode>()
            + self.info.ref_count as usize * 4
    }
}
