//! Structural checks of a kd-tree, and the figures `coray stats` reports.
//!
//! The builder lays a tree out canonically: node pairs, reference ranges
//! and rope records are all numbered in depth-first preorder, left first.
//! Checking that order proves, with no memory beyond a depth-bounded stack,
//! that the nodes form one tree (no sharing, no cycle, nothing unreachable).
//! Ropes are checked in a second pass, over the tree the first one proved:
//! a rope's walk from the root then visits only vetted nodes and ends
//! within the tree's depth. Both passes read through checked accessors, so
//! no arena, however broken, makes them panic; they take time linear in
//! the arena (times the depth, at most 60, for the ropes).

use super::node::{KdNode, KD_MAX_DEPTH, NO_NODE, SHARED_EMPTY};
use super::KdTree;
use crate::geom::Aabb;
use crate::Error;

/// What a valid tree looks like in numbers.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct KdTreeStats {
    /// Nodes stored, interior and leaf (the shared empty leaf of a tree
    /// without ropes among them).
    pub nodes: u32,
    /// Leaves.
    pub leaves: u32,
    /// Leaves with no primitive.
    pub empty_leaves: u32,
    /// Primitive references in leaves.
    pub refs: u32,
    /// Depth of the deepest leaf.
    pub depth: u32,
    /// SAH cost of the whole tree with the build's constants, relative to
    /// the root's surface area: `sum(K_T * A(interior)) + sum(K_I * n * A(leaf))`, over `A(root)`.
    pub sah_cost: f32,
}

fn corrupt(what: &'static str) -> Error {
    Error::Corrupt { what }
}

/// Closed boxes overlap (touching counts).
fn touches(a: &Aabb, b: &Aabb) -> bool {
    (0..3).all(|i| a.min[i] <= b.max[i] && b.min[i] <= a.max[i])
}

impl<'a> KdTree<'a> {
    /// Checks every structural invariant: one tree in canonical preorder,
    /// splits strictly inside their node's box, depth within the recorded
    /// depth, reference ranges and rope records consecutive, every
    /// reference naming a non-degenerate primitive that touches its leaf's
    /// box, the tree's box the union of its referenced primitives' boxes
    /// (the build's), the references' and the nodes' digests as recorded (a split
    /// moved within its box keeps the references consistent, and only the
    /// nodes' digest, or a tree's rope records, tell), leaf boxes equal to the
    /// ones implied by the splits, and every rope leading to a node whose
    /// box covers that face from outside. Returns the tree's figures.
    /// `cost_traversal` and `cost_intersection` weight the SAH cost in the
    /// figures.
    ///
    /// Never panics, in time linear in the tree. Once it accepts a tree,
    /// every traversal of it gives the hits of a clean build with the same
    /// references (it cannot tell a crafted tree whose references are
    /// consistent from a built one).
    pub fn validate_with_costs(
        &self,
        cost_traversal: f32,
        cost_intersection: f32,
    ) -> Result<KdTreeStats, Error> {
        let info = &self.info;
        let root = info.bounds();
        let area64 = |b: &Aabb| {
            let e = (b.max - b.min).as_dvec3();
            2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
        };
        let root_area = area64(&root);
        let mut st = KdTreeStats {
            nodes: info.node_count,
            ..KdTreeStats::default()
        };
        if self.nodes.len() != info.node_count as usize
            || self.ropes.len() != info.rope_count() as usize
            || self.rope_ids.len() != info.rope_id_count() as usize
            || self.refs.len() != info.ref_count as usize
            || info.depth > KD_MAX_DEPTH
        {
            return Err(corrupt("counts"));
        }
        let mut stack = [(0u32, 0u32, Aabb::EMPTY); KD_MAX_DEPTH as usize + 2];
        stack[0] = (0, 0, root);
        let mut sp = 1;
        // A compact tree's node 1 is the shared empty leaf elided children
        // stand for, and the children start after it; only a tree without
        // ropes may be compact.
        let mut next_pair = 1u32;
        if info.is_compact() {
            if info.has_ropes() {
                return Err(corrupt("compact with ropes"));
            }
            if self.nodes.get(SHARED_EMPTY as usize) != Some(&KdNode::EMPTY) {
                return Err(corrupt("shared empty leaf"));
            }
            next_pair = SHARED_EMPTY + 1;
        }
        let mut next_leaf = 0u32;
        let mut next_ref = 0u32;
        let mut sah = 0.0f64;
        let mut digest = 0u64;
        // The box of every referenced primitive: the build's root box.
        let mut referenced = Aabb::EMPTY;
        let prims = self.scene.prim_count();
        while sp > 0 {
            sp -= 1;
            let (ni, depth, b) = stack[sp];
            if depth > info.depth {
                return Err(corrupt("depth"));
            }
            let nd = *self.nodes.get(ni as usize).ok_or(corrupt("node order"))?;
            let rel_area = if root_area > 0.0 && root_area.is_finite() {
                area64(&b) / root_area
            } else {
                1.0
            };
            if nd.is_leaf() {
                // References lie in leaf preorder, each leaf's after the last's.
                if nd.first_ref() != next_ref {
                    return Err(corrupt("reference range"));
                }
                let refs = self.leaf_refs(nd).ok_or(corrupt("reference range"))?;
                let count = nd.ref_count();
                next_ref += count;
                st.leaves += 1;
                st.empty_leaves += (count == 0) as u32;
                st.refs += count;
                st.depth = st.depth.max(depth);
                sah += cost_intersection as f64 * count as f64 * rel_area;
                if info.has_ropes() {
                    // Rope records in leaf preorder, each with its leaf's box.
                    if self.rope_ids.get(ni as usize) != Some(&next_leaf) {
                        return Err(corrupt("rope index"));
                    }
                    if self.rope(ni).bounds() != b {
                        return Err(corrupt("leaf box"));
                    }
                }
                next_leaf += 1;
                for &p in refs {
                    if p as usize >= prims {
                        return Err(corrupt("reference out of range"));
                    }
                    match self.scene.prim_bounds(p as usize) {
                        Some(pb) if touches(&pb, &b) => referenced = referenced.union(&pb),
                        _ => return Err(corrupt("reference outside its leaf")),
                    }
                    digest = digest.wrapping_add(crate::rng::ref_mix(p));
                }
                continue;
            }
            let (a, s, left) = (nd.axis(), nd.split(), nd.first_stored());
            // Only a compact tree leaves empty leaves out.
            let elided = nd.elided();
            if elided == 3 || (elided != 0 && !info.is_compact()) {
                return Err(corrupt("elided child"));
            }
            let stored = nd.stored_children();
            if left != next_pair || left as u64 + stored as u64 > info.node_count as u64 {
                return Err(corrupt("node order"));
            }
            if info.has_ropes() && self.rope_ids.get(ni as usize) != Some(&NO_NODE) {
                return Err(corrupt("rope index"));
            }
            next_pair += stored;
            if !(s > b.min[a] && s < b.max[a]) {
                return Err(corrupt("split outside its node"));
            }
            if depth >= KD_MAX_DEPTH {
                return Err(corrupt("depth"));
            }
            sah += cost_traversal as f64 * rel_area;
            let mut lb = b;
            lb.max[a] = s;
            let mut rb = b;
            rb.min[a] = s;
            if elided != 0 {
                // The empty leaf left out: counted, nothing to check in it.
                if depth + 1 > info.depth {
                    return Err(corrupt("depth"));
                }
                st.leaves += 1;
                st.empty_leaves += 1;
                st.depth = st.depth.max(depth + 1);
                next_leaf += 1;
                stack[sp] = (left, depth + 1, if elided == 1 { rb } else { lb });
                sp += 1;
                continue;
            }
            stack[sp] = (left + 1, depth + 1, rb);
            stack[sp + 1] = (left, depth + 1, lb);
            sp += 2;
        }
        if next_pair != info.node_count
            || next_leaf != info.leaf_count
            || next_ref != info.ref_count
        {
            return Err(corrupt("unreachable parts"));
        }
        if st.depth != info.depth {
            return Err(corrupt("depth"));
        }
        // The build's box is its primitives' (each valid one is referenced):
        // any other box, larger or smaller, moves the cells' spans along a
        // ray, and with them which rounded hits of grazing rays count (or,
        // smaller, cuts primitives off).
        if referenced != root {
            return Err(corrupt("scene box"));
        }
        if digest != info.ref_digest() {
            return Err(corrupt("reference digest"));
        }
        // Splits moved within their boxes keep the references consistent:
        // the nodes are what the build made.
        let nodes = crate::rng::node_digest(self.nodes.iter().map(|n| (n.word, n.data)));
        if nodes != info.node_digest() {
            return Err(corrupt("node digest"));
        }
        // The scene is the one built on: a vertex or an index changed since
        // may put a primitive into cells whose leaves do not name it.
        if self.scene.digest() != info.scene_digest() {
            return Err(corrupt("scene digest"));
        }
        // The nodes form one tree of the recorded depth, every leaf's box
        // is the one its splits imply: the ropes can be walked.
        for rp in self.ropes {
            let b = rp.bounds();
            for face in 0..6 {
                self.check_rope(rp.neighbor[face], face, &b)?;
            }
        }
        st.sah_cost = sah as f32;
        Ok(st)
    }

    /// [`KdTree::validate_with_costs`] with the default SAH constants.
    pub fn validate(&self) -> Result<KdTreeStats, Error> {
        let p = super::KdParams::auto();
        self.validate_with_costs(p.cost_traversal, p.cost_intersection)
    }

    /// A rope of face `face` of leaf box `b` must be `NO_NODE` exactly when
    /// the face lies on the root's boundary, and otherwise name a node met
    /// on the way from the root towards the region just outside the face,
    /// before any split cuts that face, and whose box covers the face. Runs
    /// on a tree the preorder pass proved, so the walk stays in it.
    fn check_rope(&self, rope: u32, face: usize, b: &Aabb) -> Result<(), Error> {
        let root = self.info.bounds();
        let axis = face / 2;
        let positive = face % 2 == 1;
        let plane = if positive { b.max[axis] } else { b.min[axis] };
        let on_boundary = if positive {
            plane >= root.max[axis]
        } else {
            plane <= root.min[axis]
        };
        if rope == NO_NODE {
            return if on_boundary {
                Ok(())
            } else {
                Err(corrupt("missing rope"))
            };
        }
        if on_boundary || rope >= self.info.node_count {
            return Err(corrupt("rope out of the tree"));
        }
        let mut node = 0u32;
        let mut nb = root;
        for _ in 0..=KD_MAX_DEPTH {
            if node == rope {
                let covers = (0..3).all(|i| {
                    if i == axis {
                        nb.min[i] <= plane && plane <= nb.max[i]
                    } else {
                        nb.min[i] <= b.min[i] && nb.max[i] >= b.max[i]
                    }
                });
                return if covers {
                    Ok(())
                } else {
                    Err(corrupt("rope does not cover its face"))
                };
            }
            let nd: KdNode = self.node(node);
            if nd.is_leaf() {
                return Err(corrupt("rope not beside its face"));
            }
            let (a, s, left) = (nd.axis(), nd.split(), nd.left());
            // Which side holds the region beyond the face (the whole face,
            // or the rope should have stopped above this split).
            let go_right = if a == axis {
                if positive {
                    plane >= s
                } else {
                    plane > s
                }
            } else if b.min[a] >= s {
                true
            } else if b.max[a] <= s {
                false
            } else {
                return Err(corrupt("rope below a split that cuts its face"));
            };
            if go_right {
                nb.min[a] = s;
                node = left + 1;
            } else {
                nb.max[a] = s;
                node = left;
            }
        }
        Err(corrupt("rope deeper than the tree"))
    }
}
