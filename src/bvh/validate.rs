//! Structural checks of any built hierarchy, as for the kd-tree: run after
//! every build in the tests, and by callers on memory they load. One
//! depth-first walk on the caller's traversal stack, visiting no more nodes
//! than the hierarchy has: linear time, whatever the arena holds, and no
//! panic on any of it.

use super::{Bvh, BvhNode, BvhStackItem};
use crate::Error;

fn corrupt(what: &'static str) -> Error {
    Error::Corrupt { what }
}

/// What [`Bvh::validate`] counted.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BvhTreeStats {
    /// Nodes reached from the root.
    pub nodes: u32,
    /// Leaves reached.
    pub leaves: u32,
    /// References in them.
    pub refs: u32,
    /// Deepest leaf.
    pub depth: u32,
}

impl Bvh<'_> {
    /// Checks that the nodes reached from the root form a tree of the
    /// recorded depth and node count, every node's box is exactly the union
    /// of its entries' (children, or the boxes of the primitives
    /// referenced), indices are in range, no node has more than
    /// `max_children` entries, and the leaves hold `info.ref_count`
    /// references to non-degenerate primitives with the recorded digest.
    /// With `min_children` (R-trees), every node but the root has at least
    /// that many entries and all leaves lie at one depth. `stack` is the
    /// traversal stack ([`Bvh::stack_len`] entries).
    ///
    /// Never panics, in time linear in the hierarchy. Once it accepts a
    /// hierarchy, every traversal of it gives the hits of a clean build
    /// with the same references.
    pub fn validate(
        &self,
        min_children: Option<u32>,
        stack: &mut [BvhStackItem],
    ) -> Result<BvhTreeStats, Error> {
        let st = self.validate_with(min_children, stack, |_, _| Ok(()))?;
        if min_children.is_none()
            && self.scene.built_refs() != (self.info.ref_count as u64, self.info.ref_digest())
        {
            return Err(corrupt(
                "leaves differ from the scene's non-degenerate primitives",
            ));
        }
        Ok(st)
    }

    /// [`Bvh::validate`], calling `extra(index, node)` on every node it
    /// reaches (the projection hierarchies check their rectangles there).
    pub(crate) fn validate_with(
        &self,
        min_children: Option<u32>,
        stack: &mut [BvhStackItem],
        mut extra: impl FnMut(u32, &BvhNode) -> Result<(), Error>,
    ) -> Result<BvhTreeStats, Error> {
        self.scene.check()?;
        let info = &self.info;
        if info.depth >= info.node_count.max(1)
            || info.node_count as usize > self.nodes.len()
            || info.ref_count as usize > self.refs.len()
            || !(2..=crate::limits::RTREE_MAX_CHILDREN).contains(&info.max_children)
        {
            return Err(corrupt("counts"));
        }
        let need = self.stack_len();
        if stack.len() < need {
            return Err(Error::SliceTooSmall {
                slice: "stack",
                needed: need,
                got: stack.len(),
            });
        }
        let mut st = BvhTreeStats::default();
        let mut digest = 0u64;
        // (node, depth), depth-first; the depth rides in the t field.
        let item = |node: u32, d: u32| BvhStackItem {
            node,
            t: f32::from_bits(d),
        };
        stack[0] = item(info.root, 0);
        let mut sp = 1;
        let mut leaf_depth = None;
        while sp > 0 {
            sp -= 1;
            let (i, d) = (stack[sp].node, stack[sp].t.to_bits());
            if st.nodes == info.node_count {
                return Err(corrupt("more nodes reached than the hierarchy has"));
            }
            let nd = *self
                .nodes
                .get(i as usize)
                .ok_or(corrupt("node out of range"))?;
            self.check_node(
                &nd,
                i == info.root,
                d,
                min_children,
                &mut leaf_depth,
                &mut st,
            )?;
            extra(i, &nd)?;
            if nd.is_leaf() {
                for &p in self.leaf_refs(&nd).unwrap_or(&[]) {
                    digest = digest.wrapping_add(crate::rng::ref_mix(p));
                }
                continue;
            }
            for c in self.children(&nd).ok_or(corrupt("children out of range"))? {
                if sp == stack.len() {
                    return Err(corrupt("node deeper than the recorded depth"));
                }
                stack[sp] = item(c, d + 1);
                sp += 1;
            }
        }
        if st.refs != info.ref_count {
            return Err(corrupt("leaves hold a different number of references"));
        }
        if st.nodes != info.node_count {
            return Err(corrupt("nodes reached differ from the node count"));
        }
        if digest != info.ref_digest() {
            return Err(corrupt("reference digest"));
        }
        Ok(st)
    }

    fn check_node(
        &self,
        nd: &BvhNode,
        is_root: bool,
        d: u32,
        min_children: Option<u32>,
        leaf_depth: &mut Option<u32>,
        st: &mut BvhTreeStats,
    ) -> Result<(), Error> {
        st.nodes += 1;
        if d > self.info.depth {
            return Err(corrupt("node deeper than the recorded depth"));
        }
        let n = nd.len();
        if n > self.info.max_children && (!nd.is_leaf() || min_children.is_some()) {
            return Err(corrupt("node with more entries than allowed"));
        }
        if let Some(m) = min_children {
            if !is_root && n < m {
                return Err(corrupt("node below the minimum fill"));
            }
        }
        let mut b = crate::Aabb::EMPTY;
        if nd.is_leaf() {
            st.leaves += 1;
            st.refs = st
                .refs
                .checked_add(n)
                .ok_or(corrupt("references out of range"))?;
            st.depth = st.depth.max(d);
            if min_children.is_some() {
                if leaf_depth.is_some_and(|x| x != d) {
                    return Err(corrupt("R-tree leaves at different depths"));
                }
                *leaf_depth = Some(d);
            }
            let refs = self.leaf_refs(nd).ok_or(corrupt("refs out of range"))?;
            for &p in refs {
                let pb = self
                    .scene
                    .prim_bounds(p as usize)
                    .ok_or(corrupt("reference to a degenerate or missing primitive"))?;
                b = b.union(&pb);
            }
        } else {
            if n == 0 {
                return Err(corrupt("interior node without children"));
            }
            let kids = self.children(nd).ok_or(corrupt("children out of range"))?;
            for k in kids {
                b = b.union(&self.nodes[k as usize].bounds());
            }
        }
        if n > 0 && b != nd.bounds() {
            return Err(corrupt("node box differs from the union of its entries"));
        }
        Ok(())
    }
}
