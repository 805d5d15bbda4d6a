//! The simple LCTS: the leaves every boundary ray of a shaft visits first,
//! in the same order. A ray inside the shaft visits them too (the shaft and
//! the cells are convex), so it tests their primitives without any descent,
//! and if it finds no hit there goes on by ropes from the last of them.
//!
//! When the boundary rays share no leaf (their first leaves differ, as at
//! the many small leaves of a deep tree's surface), they still share the
//! top of their descent: a ray of the shaft whose entry point lies strictly
//! inside the deepest node all of them passed through ([`EntryNode`])
//! locates its first leaf from there and goes on by ropes. Point location
//! from a node whose split bounds hold the point strictly makes the root's
//! decisions, so the hit is still the hierarchical one.

use super::guide::{self, Cursor, Paths, FROM_START, MAX_GUIDES};
use super::history::{HistoryRecord, KIND_LEAF};
use crate::geom::PreparedRay;
use crate::kd::traverse::{Closest, Steps};
use crate::kd::{KdStackItem, KdTree};
use crate::{Hit, Ray, TraceStats, Vec3};

/// Marks a sequence entry standing for a run of empty leaves (unification
/// of empty leaves, section 4.3.1): the run costs one step and no test.
pub const EMPTY_RUN: u32 = 1 << 31;

/// A shaft's common leaf sequence in a caller buffer.
#[derive(Debug)]
pub struct Slcts<'b> {
    /// Leaf node indices; an entry with [`EMPTY_RUN`] set is the last leaf
    /// of a run of empty leaves.
    pub entries: &'b mut [u32],
    /// Entries used.
    pub len: usize,
    /// The termination object (section 4.3.2): a global primitive index
    /// that every ray of the shaft hits first, if one was established.
    pub termination: Option<u32>,
    /// Leaves the sequence covers (before unification).
    pub leaves: usize,
    /// Only for a sequence without leaves: the deepest node every boundary
    /// ray descended through on its way to its first leaf, where a ray of
    /// the shaft starts looking for its own first leaf.
    pub entry: Option<EntryNode>,
    /// Per boundary ray (the first [`MAX_GUIDES`]), the record of the
    /// sequence's last leaf in its history ([`FROM_START`] without a sequence):
    /// where its path past the sequence starts.
    pub last_record: [u32; MAX_GUIDES],
}

impl Slcts<'_> {
    /// The boundary rays' paths past the sequence, into `buf`.
    pub fn paths<'p>(
        &self,
        histories: &[Option<&[HistoryRecord]>],
        buf: &'p mut [u32],
    ) -> Paths<'p> {
        Paths::build(histories, &self.last_record, buf)
    }
}

/// A node and the open region of space the splits above it bound: a point
/// strictly inside is located from the node exactly as from the root.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EntryNode {
    /// Node index.
    pub node: u32,
    /// Lower split bounds (minus infinity where no split bounds the node).
    pub lo: Vec3,
    /// Upper split bounds (plus infinity where none does).
    pub hi: Vec3,
}

impl EntryNode {
    /// Whether point location of `p` from the root passes through this node
    /// with every decision strict (no tie on a split plane).
    #[inline]
    pub fn holds(&self, p: Vec3) -> bool {
        p.cmpgt(self.lo).all() && p.cmplt(self.hi).all()
    }
}

/// The deepest node on every history's descent to its first leaf (a
/// preorder history starts with that descent: each record before the first
/// leaf is an interior node whose next record is its first child).
pub fn entry_node(tree: &KdTree, histories: &[Option<&[HistoryRecord]>]) -> Option<EntryNode> {
    let first = (*histories.first()?)?;
    if histories.iter().any(|h| h.is_none_or(|h| h.is_empty())) {
        return None;
    }
    let mut e = EntryNode {
        node: first.first()?.node,
        lo: Vec3::splat(f32::NEG_INFINITY),
        hi: Vec3::splat(f32::INFINITY),
    };
    for i in 0.. {
        let r = *first.get(i)?;
        if r.kind() >= 4 {
            return Some(e);
        }
        let next = first.get(i + 1)?.node;
        if histories
            .iter()
            .any(|h| h.and_then(|h| h.get(i + 1)).map(|x| x.node) != Some(next))
        {
            return Some(e);
        }
        let nd = tree.node(r.node);
        let (a, split) = (nd.axis(), nd.split());
        if next == nd.left() {
            e.hi[a] = split;
        } else {
            e.lo[a] = split;
        }
        e.node = next;
    }
    Some(e)
}

/// Builds the SLCTS of boundary rays with histories `histories` (each
/// `None` when its history overflowed: then nothing is shared) into
/// `entries`. `hits` are the boundary rays' hits, for the termination object.
pub fn build<'b>(
    tree: &KdTree,
    histories: &[Option<&[HistoryRecord]>],
    hits: &[Hit],
    entries: &'b mut [u32],
) -> Slcts<'b> {
    let mut s = Slcts {
        entries,
        len: 0,
        termination: None,
        leaves: 0,
        entry: None,
        last_record: [FROM_START; MAX_GUIDES],
    };
    if histories.is_empty() || histories.iter().any(|h| h.is_none()) {
        return s;
    }
    // Walk the leaf entries of every history in lockstep.
    let mut pos = [0usize; 8];
    let k = histories.len().min(pos.len());
    let next_leaf = |h: &[HistoryRecord], p: &mut usize| -> Option<HistoryRecord> {
        while *p < h.len() {
            let r = h[*p];
            *p += 1;
            if r.kind() == KIND_LEAF {
                return Some(r);
            }
        }
        None
    };
    let mut last_empty = false;
    while let Some(rec) = next_leaf(histories[0].unwrap(), &mut pos[0]) {
        let first = rec.node;
        let mut same = true;
        for i in 1..k {
            if next_leaf(histories[i].unwrap(), &mut pos[i]).map(|r| r.node) != Some(first) {
                same = false;
            }
        }
        if !same {
            break;
        }
        let empty = tree.leaf_is_empty(rec.node);
        let unified = empty && last_empty && s.len > 0;
        if !unified && s.len == s.entries.len() {
            break;
        }
        s.leaves += 1;
        for (last, p) in s.last_record.iter_mut().zip(&pos[..k]) {
            *last = *p as u32 - 1;
        }
        if unified {
            // Unification: the run grows; its entry now ends here.
            s.entries[s.len - 1] = first | EMPTY_RUN;
            continue;
        }
        s.entries[s.len] = if empty { first | EMPTY_RUN } else { first };
        s.len += 1;
        last_empty = empty;
    }
    if s.len == 0 {
        s.entry = entry_node(tree, histories);
    }
    s.termination = termination_object(tree, &s, hits, histories);
    s
}

/// The last leaf a history visited.
fn last_leaf(h: &[HistoryRecord]) -> Option<u32> {
    h.iter()
        .rev()
        .find(|r| r.kind() == KIND_LEAF)
        .map(|r| r.node)
}

/// Section 4.3.2: every boundary ray hits the same convex primitive O and
/// ends in the same leaf C, O is the only primitive of C, and C is the
/// first entry of the sequence or the second after a run of empty leaves.
fn termination_object(
    tree: &KdTree,
    s: &Slcts,
    hits: &[Hit],
    histories: &[Option<&[HistoryRecord]>],
) -> Option<u32> {
    let first = hits.first()?;
    if !first.is_hit()
        || hits
            .iter()
            .any(|h| (h.geom_id, h.prim_id) != (first.geom_id, first.prim_id))
    {
        return None;
    }
    let scene = &tree.scene;
    let global = match first.geom_id {
        crate::geom::GEOM_TRIANGLES => first.prim_id,
        crate::geom::GEOM_SPHERES => scene.triangles.len() as u32 + first.prim_id,
        _ => return None, // cones are not convex
    };
    let c = match s.entries[..s.len] {
        [c, ..] if c & EMPTY_RUN == 0 => c,
        [e, c, ..] if e & EMPTY_RUN != 0 && c & EMPTY_RUN == 0 => c,
        _ => return None,
    };
    // Condition 1: every boundary ray ended in C.
    if histories.iter().any(|h| h.and_then(last_leaf) != Some(c)) {
        return None;
    }
    let refs = tree.leaf_refs(tree.node(c))?;
    (refs == [global]).then_some(global)
}

/// The first leaf of a ray of a shaft without common leaves, from the
/// shaft's entry node, `p` where the ray enters the scene's box: one step
/// for the test that `p` lies strictly inside the node; `None` when it does
/// not (the ray is then traced hierarchically).
#[inline]
pub(crate) fn locate_first(tree: &KdTree, s: &Slcts, p: Vec3, steps: &mut Steps) -> Option<u32> {
    let e = s.entry?;
    steps.interior += 1;
    e.holds(p).then_some(())?;
    tree.locate(e.node, p, steps)
}

/// Traces `ray`, which lies inside the shaft of `s`, exactly as
/// hierarchical traversal would answer: the termination object when there
/// is one, else the sequence's leaves, then ropes from the last of them,
/// guided by `paths` ([`Slcts::paths`], or [`Paths::none`]) asked first at
/// path `nearest`. `stack` ([`crate::kd::KD_STACK_LEN`] entries) serves a
/// ray that must be redone hierarchically.
pub fn trace(
    tree: &KdTree,
    s: &Slcts,
    paths: &Paths,
    nearest: usize,
    ray: &Ray,
    stack: &mut [KdStackItem],
    stats: &mut TraceStats,
) -> Hit {
    stats.rays += 1;
    if !ray.is_valid() {
        return Hit::MISS;
    }
    let mut v = Closest::new(ray);
    let mut steps = Steps::default();
    if let Some(o) = s.termination {
        v.tests += 1;
        // Only a hit strictly inside the object's leaf: one on its far
        // boundary may tie with a primitive of the next leaf.
        let inside = |h: &Hit| {
            s.entries[..s.len]
                .iter()
                .find(|&&e| e & EMPTY_RUN == 0)
                .is_some_and(|&e| {
                    let exit = tree.leaf_exit(&v.ray, e).0;
                    crate::kd::traverse::inside_leaf(h.t, exit)
                })
        };
        let hit = tree.scene.intersect_prim(o as usize, &v.ray, ray.t_max);
        if let Some(h) = hit.filter(inside) {
            stats.prim_tests += 1;
            // The leaves before C are empty: one step for them (unified), one for C.
            stats.leaf_steps += s.len.min(2) as u64;
            stats.traversal_steps += s.len.min(2) as u64;
            return h;
        }
        // Rounding, or a hit on the leaf's boundary: the sequence decides.
    }
    let mut cur = Cursor::new(paths, nearest);
    let done = match tree.scene_segment(&v.ray) {
        None => true,
        // No common leaf: the first leaf from the shaft's entry node (one
        // step for the test that the entry point lies strictly inside it).
        Some((t0, t1)) if s.len == 0 => {
            let from_entry =
                |_: &PreparedRay, p: Vec3, steps: &mut Steps| locate_first(tree, s, p, steps);
            guide::walk_from_first(
                tree, &mut v, t0, t1, paths, &mut cur, &mut steps, from_entry,
            )
        }
        Some((_, t1)) => {
            let seq = s.entries[..s.len]
                .iter()
                .map(|&e| (e & !EMPTY_RUN, e & EMPTY_RUN != 0));
            guide::walk_common(tree, seq, &mut v, t1, paths, &mut cur, &mut steps)
        }
    };
    guide::finish(tree, &mut v, done, stack, steps, stats)
}
