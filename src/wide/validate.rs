//! Structural checks of a wide hierarchy, as for the other structures: run
//! after every build in the tests, and by callers on memory they load. One
//! pass over the nodes in index order: the breadth-first numbering the
//! build makes is what proves the nodes a tree, and the blocks following
//! the leaves in the same order is what proves each block one leaf's, so
//! no stack is needed.

use super::block::{self, LeafBlock, BLOCK_SLOTS, NO_PRIM};
use super::node::{leaf_run, EMPTY_SLOT, LEAF_BIT};
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
    /// first, that the leaf entries take blocks 0, 1, 2, ... in the same
    /// order, each block of a leaf but its last full and the last holding
    /// its primitives first, that every slot's box is exactly the union of
    /// what it holds (its child's slots, or its primitives' boxes), that
    /// primitives lie in range and are not degenerate, that the leaves hold
    /// `ref_count` primitives with the recorded digest, leaf and block
    /// counts, and that every block holds the scene's corners of its
    /// triangles (NaN elsewhere). The scene must pass
    /// [`crate::Scene::check`], and the leaves hold exactly its
    /// non-degenerate primitives ([`crate::Scene::built_refs`]).
    ///
    /// Never panics, in time linear in the hierarchy. Once it accepts a
    /// hierarchy, every traversal of it gives the hits of a clean build
    /// with the same leaves.
    pub fn validate(&self) -> Result<Shape, Error> {
        self.scene.check()?;
        let info = &self.info;
        let count = info.node_count as usize;
        if count == 0 || count > self.nodes.len() || info.block_count as usize > self.blocks.len() {
            return Err(corrupt("counts"));
        }
        let mut shape = Shape {
            nodes: info.node_count,
            ..Shape::default()
        };
        let (mut next, mut next_block, mut prims, mut digest) = (1usize, 0usize, 0u64, 0u64);
        let (mut depth, mut level_end) = (0u32, 1usize);
        for (k, n) in self.nodes[..count].iter().enumerate() {
            if k == level_end {
                depth += 1;
                level_end = next;
            }
            let used = n.child.iter().take_while(|&&c| c != EMPTY_SLOT).count();
            if n.child[used..].iter().any(|&c| c != EMPTY_SLOT)
                || (used..super::WIDTH).any(|i| n.slot_bounds(i) != Aabb::EMPTY)
            {
                return Err(corrupt("a used slot after an empty one"));
            }
            if used == 0 && (k != 0 || count != 1 || info.ref_count != 0) {
                return Err(corrupt("node without entries"));
            }
            for i in 0..used {
                let c = n.child[i];
                let b = if c & LEAF_BIT != 0 {
                    shape.leaves += 1;
                    let (first, m) = leaf_run(c);
                    if first != next_block {
                        return Err(corrupt("leaf blocks out of order"));
                    }
                    let run = self
                        .blocks
                        .get(first..first + m)
                        .filter(|_| first + m <= info.block_count as usize)
                        .ok_or(corrupt("leaf blocks out of range"))?;
                    next_block += m;
                    let (b, held) = self.leaf_bounds(run, &mut digest)?;
                    prims += held;
                    b
                } else {
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
        if next_block != info.block_count as usize {
            return Err(corrupt("blocks without a leaf"));
        }
        if prims != info.ref_count as u64 || shape.leaves != info.leaf_count {
            return Err(corrupt("leaves hold a different number of primitives"));
        }
        if depth != info.depth {
            return Err(corrupt("depth differs from the recorded one"));
        }
        if digest != info.ref_digest() {
            return Err(corrupt("reference digest"));
        }
        if self.scene.built_refs() != (prims, digest) {
            return Err(corrupt(
                "leaves differ from the scene's non-degenerate primitives",
            ));
        }
        shape.refs = info.ref_count;
        shape.depth = depth;
        Ok(shape)
    }

    /// The box of one leaf's blocks and how many primitives they hold,
    /// each added to `digest`: every block but the last full, the last
    /// holding its primitives first, each primitive in range and not
    /// degenerate, the corners the scene's.
    fn leaf_bounds(&self, run: &[LeafBlock], digest: &mut u64) -> Result<(Aabb, u64), Error> {
        let (mut b, mut held) = (Aabb::EMPTY, 0u64);
        for (j, blk) in run.iter().enumerate() {
            let filled = blk.prims.iter().take_while(|&&p| p != NO_PRIM).count();
            let last = j + 1 == run.len();
            if filled == 0
                || (!last && filled != BLOCK_SLOTS)
                || blk.prims[filled..].iter().any(|&p| p != NO_PRIM)
            {
                return Err(corrupt("a leaf block's slots out of order"));
            }
            for &p in &blk.prims[..filled] {
                *digest = digest.wrapping_add(crate::rng::ref_mix(p));
                let pb = self
                    .scene
                    .prim_bounds(p as usize)
                    .ok_or(corrupt("reference to a degenerate or missing primitive"))?;
                b = b.union(&pb);
            }
            if !block::matches(&self.scene, blk) {
                return Err(corrupt("corners differ from the scene's triangles"));
            }
            held += filled as u64;
        }
        Ok((b, held))
    }
}
