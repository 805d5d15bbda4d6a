//! A kd-tree in owned vectors: the command's one way to build one.

use coray::arena::KdArenaLayout;
use coray::kd::{
    self, KdEvent, KdInfo, KdLeaf, KdNode, KdParams, KdRequirements, KdRopes, KdScratch, KdStorage,
    KdTree,
};
use coray::Scene;
use std::time::Instant;

/// The tree's parts, sized by [`kd::requirements`], and what the build said.
pub struct OwnedKd {
    nodes: Vec<KdNode>,
    leaves: Vec<KdLeaf>,
    ropes: Vec<KdRopes>,
    refs: Vec<u32>,
    pub info: KdInfo,
    pub build_ms: f64,
}

impl OwnedKd {
    /// Builds over `scene` with the ideal room for `params`; scratch is
    /// dropped afterwards. Build time excludes allocation.
    pub fn build(scene: &Scene, params: &KdParams) -> Result<OwnedKd, String> {
        let req = kd::requirements(scene.prim_count(), params);
        let mut nodes = vec![KdNode::default(); req.nodes];
        let mut leaves = vec![KdLeaf::default(); req.leaves];
        let mut ropes = vec![KdRopes::default(); req.ropes];
        let mut refs = vec![0u32; req.refs];
        let mut events = vec![KdEvent::default(); req.events];
        let mut flags = vec![0u8; req.prim_flags];
        let t = Instant::now();
        let info = kd::build_sah(
            scene,
            params,
            KdStorage {
                nodes: &mut nodes,
                leaves: &mut leaves,
                ropes: &mut ropes,
                refs: &mut refs,
            },
            KdScratch {
                events: &mut events,
                prim_flags: &mut flags,
            },
        )
        .map_err(|e| format!("kd build: {e}"))?
        .info;
        let build_ms = t.elapsed().as_secs_f64() * 1e3;
        Ok(OwnedKd {
            nodes,
            leaves,
            ropes,
            refs,
            info,
            build_ms,
        })
    }

    /// The built tree over `scene` (the scene it was built on).
    pub fn tree<'a>(&'a self, scene: Scene<'a>) -> KdTree<'a> {
        KdTree::from_parts(
            scene,
            self.info,
            &self.nodes,
            &self.leaves,
            &self.ropes,
            &self.refs,
        )
        .expect("tree just built")
    }

    /// Bytes of a C arena holding exactly what the tree uses.
    pub fn arena_bytes(&self) -> usize {
        let i = &self.info;
        KdArenaLayout::of(&KdRequirements {
            nodes: i.node_count as usize,
            leaves: i.leaf_count as usize,
            ropes: i.leaf_count as usize,
            refs: i.ref_count as usize,
            events: 0,
            prim_flags: 0,
        })
        .total_bytes
    }
}

/// Parses a preset name.
pub fn preset(name: &str) -> Result<KdParams, String> {
    match name {
        "auto" => Ok(KdParams::auto()),
        "paper" => Ok(KdParams::paper()),
        p => Err(format!("unknown preset `{p}` (auto, paper)")),
    }
}
