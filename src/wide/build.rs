//! Collapsing a binary hierarchy into a wide one: each wide node takes its
//! binary node's children and opens the interior entry of largest surface
//! area until [`WIDTH`] entries are held (or opening any would exceed
//! them), the usual way to derive a 4-wide hierarchy from a binary SAH one
//! without losing its splits. Nodes are numbered breadth first, so a
//! level's nodes and one node's children sit side by side and the order
//! itself proves the tree ([`super::WideBvh::validate`]).

use super::node::{WideNode, LEAF_BIT, WIDTH};
use crate::bvh::{Bvh, BvhNode};
use crate::Error;

/// What a collapse made.
pub(super) struct Collapsed {
    pub nodes: usize,
    pub leaves: usize,
    /// Level of the deepest node (root: 0).
    pub depth: u32,
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

/// Collapses the binary `bvh` into `out`, breadth first from node 0.
pub(super) fn collapse(bvh: &Bvh, out: &mut [WideNode]) -> Result<Collapsed, Error> {
    let (bn, _) = bvh.parts();
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
                node.child[used] = LEAF_BIT | b.first;
                node.count[used] = b.len();
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
        depth,
    })
}
