//! Structural checks of any built hierarchy, as for the kd-tree: run after
//! every build in the tests, and by callers on memory they load.

use super::{Bvh, BvhNode};
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
    /// Checks that every node's box is exactly the union of its entries'
    /// (children, or the boxes of the primitives referenced), indices are
    /// in range, no node has more than `max_children` entries, the depth
    /// is within `info.depth`, and the leaves reference `info.ref_count`
    /// primitives, all non-degenerate. With `min_children` (R-trees),
    /// every node but the root has at least that many entries and all
    /// leaves lie at one depth.
    pub fn validate(&self, min_children: Option<u32>) -> Result<BvhTreeStats, Error> {
        let mut st = BvhTreeStats::default();
        let root = self.info.root as usize;
        if root >= self.nodes.len() {
            return Err(corrupt("root out of range"));
        }
        // (node, depth), depth-first on a stack bounded like the traversal's.
        let cap = 1 + self.info.depth as usize * self.info.max_children.max(2) as usize;
        let mut stack = [(0u32, 0u32); 4096];
        if cap > stack.len() {
            return self.validate_deep(min_children);
        }
        stack[0] = (root as u32, 0);
        let mut sp = 1;
        let mut leaf_depth = None;
        while sp > 0 {
            sp -= 1;
            let (i, d) = stack[sp];
            let nd = self.nodes[i as usize];
            self.check_node(
                &nd,
                i as usize == root,
                d,
                min_children,
                &mut leaf_depth,
                &mut st,
            )?;
            if !nd.is_leaf() {
                for c in nd.first..nd.first + nd.len() {
                    stack[sp] = (c, d + 1);
                    sp += 1;
                }
            }
        }
        if st.refs != self.info.ref_count {
            return Err(corrupt("leaves hold a different number of references"));
        }
        Ok(st)
    }

    /// The same checks for trees too deep for the fixed stack (a
    /// degenerate bottom-up build): nodes are visited by index instead,
    /// which checks everything but the depth bound and reachability.
    fn validate_deep(&self, min_children: Option<u32>) -> Result<BvhTreeStats, Error> {
        let mut st = BvhTreeStats::default();
        let mut leaf_depth = None;
        let root = self.info.root as usize;
        self.check_node(
            &self.nodes[root],
            true,
            0,
            min_children,
            &mut leaf_depth,
            &mut st,
        )?;
        for i in 1..self.info.node_count as usize {
            let nd = self.nodes[i];
            self.check_node(&nd, false, 0, None, &mut None, &mut st)?;
        }
        if st.refs != self.info.ref_count {
            return Err(corrupt("leaves hold a different number of references"));
        }
        st.depth = self.info.depth;
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
        if !nd.is_leaf() && n > self.info.max_children {
            return Err(corrupt("node with more children than allowed"));
        }
        if let Some(m) = min_children {
            if !is_root && n < m {
                return Err(corrupt("node below the minimum fill"));
            }
            if nd.is_leaf() && n > self.info.max_children {
                return Err(corrupt("leaf above the maximum fill"));
            }
        }
        let mut b = crate::Aabb::EMPTY;
        if nd.is_leaf() {
            st.leaves += 1;
            st.refs += n;
            st.depth = st.depth.max(d);
            if min_children.is_some() {
                if leaf_depth.is_some_and(|x| x != d) {
                    return Err(corrupt("R-tree leaves at different depths"));
                }
                *leaf_depth = Some(d);
            }
            let end = nd.first as usize + n as usize;
            let refs = self
                .refs
                .get(nd.first as usize..end)
                .ok_or(corrupt("refs out of range"))?;
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
            let end = nd.first as usize + n as usize;
            let kids = self
                .nodes
                .get(nd.first as usize..end)
                .ok_or(corrupt("children out of range"))?;
            for k in kids {
                b = b.union(&k.bounds());
            }
        }
        if n > 0 && b != nd.bounds() {
            return Err(corrupt("node box differs from the union of its entries"));
        }
        Ok(())
    }
}
