//! Collapsing a binary hierarchy into a wide one: each wide node takes its
//! binary node's children and opens the interior entry of largest surface
//! area until [`WIDTH`] entries are held (or opening any would exceed
//! them), the usual way to derive an 8-wide hierarchy from a binary SAH one
//! without losing its splits. Nodes are numbered breadth first, so a
//! level's nodes and one node's children sit side by side and the order
//! itself proves the tree ([`super::WideBvh::validate`]). Each leaf's
//! primitives are copied into its own blocks as its entry is made, so the
//! blocks follow the leaves in the same breadth-first order.

use super::block::{self, LeafBlock};
use super::node::{leaf_entry, WideNode, LEAF_FIRST_MASK, MAX_LEAF_BLOCKS, WIDTH};
use crate::bvh::{Bvh, BvhNode};
use crate::Error;

/// What a collapse made.
pub(super) struct Collapsed {
    pub nodes: usize,
    pub leaves: usize,
    pub blocks: usize,
    /// Level of the deepest node (root: 0).
    pub depth: u32,
}

/// Wide nodes a collapse makes from a binary hierarchy of `leaves`
/// non-empty leaves, at most: every node holds [`WIDTH`] entries but those
/// whose entries are all leaves (two or more of them), so with `F` full
/// nodes and `B` others, `leaves >= 7F + B + 1` and `B <= 7F + 1`, which
/// gives `F + B <= (4 leaves - 1) / 7` (and one node for a leaf or an
/// empty scene).
pub const fn nodes_bound(leaves: usize) -> usize {
    (leaves.saturating_mul(4) / 7).saturating_add(1)
}

/// Half the surface area of a binary node's box.
fn half_area(n: &BvhNode) -> f32 {
    let e = [
        n.max[0] - n.min[0],
        n.max[1] - n.min[1],
        n.max[2] - n.min[2],
    ];
    e[0] * e[1] + e[1] * e[2] + e[2] * e[0]
}

/// The entries of binary node `src` after opening the largest interior
/// ones (the first of equal areas); returns how many. A leaf stands for
/// itself (only at the root).
fn gather(bn: &[BvhNode], src: u32, out: &mut [u32; WIDTH]) -> Result<usize, Error> {
    let node = |i: u32| {
        bn.get(i as usize).ok_or(Error::Corrupt {
            what: "binary node",
        })
    };
    let s = node(src)?;
    if s.is_leaf() {
        out[0] = src;
        return Ok(1);
    }
    let mut n = 0;
    for c in s.first..s.first + s.len() {
        if n == WIDTH {
            return Err(Error::Corrupt {
                what: "binary node",
            });
        }
        out[n] = c;
        n += 1;
    }
    loop {
        let mut pick = None;
        let mut largest = f32::NEG_INFINITY;
        for (i, &e) in out[..n].iter().enumerate() {
            let en = node(e)?;
            if !en.is_leaf() && n - 1 + en.len() as usize <= WIDTH && half_area(en) > largest {
                largest = half_area(en);
                pick = Some(i);
            }
        }
        let Some(i) = pick else { return Ok(n) };
        let en = *node(out[i])?;
        out[i] = en.first;
        for c in en.first + 1..en.first + en.len() {
            out[n] = c;
            n += 1;
        }
    }
}

/// Collapses the binary `bvh` into `out`, breadth first from node 0, each
/// leaf's primitives copied into the next blocks of `blocks`.
pub(super) fn collapse(
    bvh: &Bvh,
    out: &mut [WideNode],
    blocks: &mut [LeafBlock],
) -> Result<Collapsed, Error> {
    let (bn, refs) = bvh.parts();
    let scene = bvh.scene();
    let got = out.len();
    let room = |needed: usize| Error::SliceTooSmall {
        slice: "nodes",
        needed,
        got,
    };
    if out.is_empty() {
        return Err(room(1));
    }
    // The binary node a wide node stands for waits in its first slot
    // until the node is made.
    out[0] = WideNode::default();
    out[0].child[0] = bvh.info().root;
    let (mut top, mut leaves, mut depth, mut level_end) = (1, 0, 0, 1);
    let mut next_block = 0usize;
    let mut k = 0;
    while k < top {
        if k == level_end {
            depth += 1;
            level_end = top;
        }
        let mut entries = [0u32; WIDTH];
        let n = gather(bn, out[k].child[0], &mut entries)?;
        let mut node = WideNode::default();
        let mut used = 0;
        for &e in &entries[..n] {
            let b = &bn[e as usize];
            if b.is_leaf() {
                if b.is_empty() {
                    continue;
                }
                let run = refs
                    .get(b.first as usize..(b.first + b.len()) as usize)
                    .ok_or(Error::Corrupt {
                        what: "binary leaf",
                    })?;
                let need = block::blocks_for(run.len());
                let end = next_block + need;
                if need > MAX_LEAF_BLOCKS || end > LEAF_FIRST_MASK as usize {
                    return Err(Error::Corrupt {
                        what: "binary leaf",
                    });
                }
                let got = blocks.len();
                let dst = blocks
                    .get_mut(next_block..end)
                    .ok_or(Error::SliceTooSmall {
                        slice: "blocks",
                        needed: end,
                        got,
                    })?;
                for (d, prims) in dst.iter_mut().zip(run.chunks(block::BLOCK_SLOTS)) {
                    *d = block::fill(scene, prims);
                }
                node.child[used] = leaf_entry(next_block as u32, need as u32);
                next_block = end;
                leaves += 1;
            } else {
                if top == out.len() {
                    return Err(room(top + 1));
                }
                out[top] = WideNode::default();
                out[top].child[0] = e;
                node.child[used] = top as u32;
                top += 1;
            }
            node.set_slot_bounds(used, &b.bounds());
            used += 1;
        }
        out[k] = node;
        k += 1;
    }
    Ok(Collapsed {
        nodes: top,
        leaves,
        blocks: next_block,
        depth,
    })
}
