//! Structural checks of a wide hierarchy, as for the other structures: run
//! after every build in the tests, and by callers on memory they load. One
//! pass over the nodes in index order: the breadth-first numbering the
//! build makes is what proves the nodes a tree, so no stack is needed.

use super::node::{EMPTY_SLOT, LEAF_BIT};
use super::WideBvh;
use crate::accel::Shape;
use crate::{Aabb, Error};

fn corrupt(what: &'static str) -> Error {
    Error::Corrupt { what }
}

impl WideBvh<'_> {
    /// Checks that the interior children of nodes 0, 1, 2, ... are nodes
    /// 1, 2, 3, ... in slot order up to the node count (so every node but
    /// the root has one parent, numbered below it: a tree, walked in
    /// breadth-first levels of the recorded depth), that used slots come
    /// first, every slot's box is exactly the union of what it holds (its
    /// child's slots, or its references' primitive boxes), references lie
    /// in range and name non-degenerate primitives, the leaves hold
    /// `ref_count` references with the recorded digest and leaf count, the
    /// corner blocks hold the scene's triangles of the slots they cover,
    /// and every run with a triangle lies within them.
    ///
    /// Never panics, in time linear in the hierarchy. Once it accepts a
    /// hierarchy, every traversal of it gives the hits of a clean build
    /// with the same references.
    pub fn validate(&self) -> Result<Shape, Error> {
        let info = &self.info;
        let count = info.node_count as usize;
        if count == 0 || count > self.nodes.len() || info.ref_count as usize > self.refs.len() {
            return Err(corrupt("counts"));
        }
        let mut shape = Shape {
            nodes: info.node_count,
            ..Shape::default()
        };
        let (mut next, mut refs, mut digest) = (1usize, 0u64, 0u64);
        // Reference slots the corner blocks cover.
        let covered = self.corners.len() * crate::geom::TRI_LANES;
        let (mut depth, mut level_end) = (0u32, 1usize);
        for (k, n) in self.nodes[..count].iter().enumerate() {
            if k == level_end {
                depth += 1;
                level_end = next;
            }
            let used = n.child.iter().take_while(|&&c| c != EMPTY_SLOT).count();
            if n.child[used..].iter().any(|&c| c != EMPTY_SLOT)
                || n.count[used..].iter().any(|&c| c != 0)
            {
                return Err(corrupt("a used slot after an empty one"));
            }
            if used == 0 && (k != 0 || count != 1 || info.ref_count != 0) {
                return Err(corrupt("node without entries"));
            }
            for i in 0..used {
                let (c, m) = (n.child[i], n.count[i]);
                let b = if c & LEAF_BIT != 0 {
                    if m == 0 {
                        return Err(corrupt("leaf without references"));
                    }
                    shape.leaves += 1;
                    refs += m as u64;
                    let first = (c & !LEAF_BIT) as usize;
                    let run = first
                        .checked_add(m as usize)
                        .filter(|&end| end <= info.ref_count as usize)
                        .map(|end| &self.refs[first..end])
                        .ok_or(corrupt("references out of range"))?;
                    if first + m as usize > covered
                        && run
                            .iter()
                            .any(|&p| (p as usize) < self.scene.triangles.len())
                    {
                        return Err(corrupt("a run with a triangle past the corner blocks"));
                    }
                    let mut b = Aabb::EMPTY;
                    for &p in run {
                        digest = digest.wrapping_add(crate::rng::ref_mix(p));
                        let pb = self
                            .scene
                            .prim_bounds(p as usize)
                            .ok_or(corrupt("reference to a degenerate or missing primitive"))?;
                        b = b.union(&pb);
                    }
                    b
                } else {
                    if m != 0 {
                        return Err(corrupt("interior entry with a reference count"));
                    }
                    if c as usize != next || next >= count {
                        return Err(corrupt("children out of breadth-first order"));
                    }
                    next += 1;
                    self.nodes[c as usize].bounds()
                };
                if b != n.slot_bounds(i) {
                    return Err(corrupt("entry box differs from the union of what it holds"));
                }
            }
        }
        if next != count {
            return Err(corrupt("nodes without a parent"));
        }
        if refs != info.ref_count as u64 || shape.leaves != info.leaf_count {
            return Err(corrupt("leaves hold a different number of references"));
        }
        if depth != info.depth {
            return Err(corrupt("depth differs from the recorded one"));
        }
        if digest != info.ref_digest() {
            return Err(corrupt("reference digest"));
        }
        let refs = &self.refs[..info.ref_count as usize];
        if self.corners.len() != info.corner_blocks as usize
            || !super::corners::matches(&self.scene, refs, self.corners)
        {
            return Err(corrupt("corners differ from the scene's triangles"));
        }
        shape.refs = info.ref_count;
        shape.depth = depth;
        Ok(shape)
    }
}
