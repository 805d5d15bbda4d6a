//! Ropes: six neighbour links per leaf, pushed down to the smallest node
//! that still covers the whole face (Popov, Günther, Seidel and Slusallek
//! 2007), so rope traversal descends little after crossing a face.

use super::node::{KdNode, KdRopes, KD_MAX_DEPTH, NO_NODE};
use crate::geom::Aabb;

/// Moves rope `r` of face `face` of box `b` down while one child of the
/// rope's node still covers the whole face.
fn push_down(nodes: &[KdNode], mut r: u32, face: usize, b: &Aabb) -> u32 {
    let face_axis = face / 2;
    let positive = face % 2 == 1;
    while r != NO_NODE {
        let node = nodes[r as usize];
        if node.is_leaf() {
            break;
        }
        let (axis, split, left) = (node.axis(), node.split(), node.left());
        r = if axis == face_axis {
            // The neighbour lies beyond the face: its child on our side touches it.
            if positive {
                left
            } else {
                left + 1
            }
        } else if split <= b.min[axis] {
            left + 1
        } else if split >= b.max[axis] {
            left
        } else {
            break;
        };
    }
    r
}

/// Makes the rope records of a built tree: one per leaf, numbered in
/// preorder (left first), each with the leaf's box and its six links, and
/// `rope_ids[node]` = the record of each leaf node ([`NO_NODE`] for an
/// interior node). `ropes` holds a slot per leaf, `rope_ids` per node.
pub(super) fn build_ropes(
    nodes: &[KdNode],
    ropes: &mut [KdRopes],
    rope_ids: &mut [u32],
    root: &Aabb,
) {
    #[derive(Clone, Copy)]
    struct Frame {
        node: u32,
        bounds: Aabb,
        links: [u32; 6],
    }
    let mut stack = [Frame {
        node: 0,
        bounds: *root,
        links: [NO_NODE; 6],
    }; KD_MAX_DEPTH as usize + 2];
    let mut sp = 1;
    let mut next_rope = 0u32;
    while sp > 0 {
        sp -= 1;
        let Frame {
            node,
            bounds,
            mut links,
        } = stack[sp];
        for (face, l) in links.iter_mut().enumerate() {
            *l = push_down(nodes, *l, face, &bounds);
        }
        let n = nodes[node as usize];
        if n.is_leaf() {
            ropes[next_rope as usize] = KdRopes {
                neighbor: links,
                min: bounds.min.into(),
                max: bounds.max.into(),
            };
            rope_ids[node as usize] = next_rope;
            next_rope += 1;
            continue;
        }
        rope_ids[node as usize] = NO_NODE;
        let (axis, split, left) = (n.axis(), n.split(), n.left());
        let [lb, rb] = bounds.split(axis, split);
        let mut ll = links;
        ll[2 * axis + 1] = left + 1;
        let mut rl = links;
        rl[2 * axis] = left;
        stack[sp] = Frame {
            node: left + 1,
            bounds: rb,
            links: rl,
        };
        stack[sp + 1] = Frame {
            node: left,
            bounds: lb,
            links: ll,
        };
        sp += 2;
    }
}
