//! Traversal histories: what a ray's hierarchical traversal visited, in
//! depth-first preorder, each interior node with its decision (the LCTS
//! paper's traversal tree, flattened), leaves, and nodes pushed but never
//! visited because the ray ended first.

use crate::kd::traverse::{Closest, Recorder, Steps};
use crate::kd::{Decision, KdStackItem, KdTree};
use crate::{Hit, Ray, TraceStats};

/// Kind of a [`HistoryRecord`] beyond the four decisions (0 to 3).
pub const KIND_LEAF: u32 = 4;
/// The node was pushed on the traversal stack but never visited.
pub const KIND_UNVISITED: u32 = 5;

/// One visited (or pushed) node. Plain data: `word` holds the kind in the
/// low 3 bits ([`Decision`] as 0 to 3, [`KIND_LEAF`], [`KIND_UNVISITED`])
/// and above them, for an interior node, once [`fill_lengths`] ran, the
/// number of records of its subtree (so a subtree can be skipped in O(1)).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[repr(C)]
pub struct HistoryRecord {
    /// Node index in the tree.
    pub node: u32,
    /// Kind in bits 0 to 2; subtree length above.
    pub word: u32,
}

impl HistoryRecord {
    /// The record's kind.
    #[inline]
    pub fn kind(&self) -> u32 {
        self.word & 7
    }

    /// Records in this node's subtree, itself included (1 for a leaf or an
    /// unvisited node).
    #[inline]
    pub fn subtree_len(&self) -> usize {
        if self.kind() >= KIND_LEAF {
            1
        } else {
            (self.word >> 3) as usize
        }
    }
}

/// Children recorded after a record of `kind` (preorder).
fn arity(kind: u32) -> usize {
    match kind {
        0 | 1 => 1,
        2 | 3 => 2,
        _ => 0,
    }
}

/// Stores each record's subtree length in its word. `records` must be a
/// sequence of whole subtrees in preorder (what a traversal records); a
/// truncated subtree at the end is left with partial lengths.
pub fn fill_lengths(records: &mut [HistoryRecord]) {
    // Open ancestors and how many children each still waits for: at most
    // one per level of the tree.
    let mut open = [(0usize, 0usize); crate::kd::KD_MAX_DEPTH as usize + 2];
    let mut sp = 0usize;
    for i in 0..records.len() {
        let kind = records[i].kind();
        if kind < KIND_LEAF {
            records[i].word = kind | (1 << 3);
        }
        let a = arity(kind);
        if a > 0 && sp < open.len() {
            open[sp] = (i, a);
            sp += 1;
            continue;
        }
        // Record i is a whole subtree: add it to its ancestors.
        let mut done = i;
        while sp > 0 {
            let (p, rem) = open[sp - 1];
            let add = records[done].subtree_len() as u32;
            records[p].word += add << 3;
            if rem > 1 {
                open[sp - 1].1 = rem - 1;
                break;
            }
            sp -= 1;
            done = p;
        }
    }
}

/// A ray's history in a caller buffer, and the ray's hit.
#[derive(Debug)]
pub struct History<'b> {
    /// The buffer; `len` records are used.
    pub records: &'b mut [HistoryRecord],
    /// Records written.
    pub len: usize,
    /// The traversal did not fit: the history is unusable for sharing.
    pub overflow: bool,
    /// The ray's closest hit.
    pub hit: Hit,
}

impl<'b> History<'b> {
    /// An empty history over `records`.
    pub fn new(records: &'b mut [HistoryRecord]) -> History<'b> {
        History {
            records,
            len: 0,
            overflow: false,
            hit: Hit::MISS,
        }
    }

    /// The records, or `None` when they did not fit.
    pub fn get(&self) -> Option<&[HistoryRecord]> {
        (!self.overflow).then(|| &self.records[..self.len])
    }

    fn push(&mut self, node: u32, word: u32) {
        if self.len < self.records.len() {
            self.records[self.len] = HistoryRecord { node, word };
            self.len += 1;
        } else {
            self.overflow = true;
        }
    }
}

impl Recorder for History<'_> {
    #[inline]
    fn interior(&mut self, node: u32, d: Decision) {
        self.push(node, d as u32);
    }
    #[inline]
    fn leaf(&mut self, node: u32) {
        self.push(node, KIND_LEAF);
    }
    #[inline]
    fn unvisited(&mut self, node: u32) {
        self.push(node, KIND_UNVISITED);
    }
}

/// Traces `ray` hierarchically from the root on the caller's `stack`
/// ([`crate::kd::KD_STACK_LEN`] entries), recording its history into `h`
/// (cleared first). The hit is exactly that of [`KdTree::intersect`] with
/// hierarchical traversal.
pub fn trace_recorded(
    tree: &KdTree,
    ray: &Ray,
    h: &mut History,
    stack: &mut [KdStackItem],
    stats: &mut TraceStats,
) {
    trace_recorded_on(tree, ray, h, stack, stats, true);
}

/// [`trace_recorded`], with subtree lengths only with `lengths` (the SLCTS
/// does not use them).
pub(crate) fn trace_recorded_on(
    tree: &KdTree,
    ray: &Ray,
    h: &mut History,
    stack: &mut [KdStackItem],
    stats: &mut TraceStats,
    lengths: bool,
) {
    h.len = 0;
    h.overflow = false;
    h.hit = Hit::MISS;
    stats.rays += 1;
    if !ray.is_valid() {
        return;
    }
    let mut v = Closest::new(ray);
    let mut steps = Steps::default();
    tree.walk_hierarchical(&mut v, h, stack, &mut steps);
    steps.flush(stats);
    stats.prim_tests += v.tests;
    h.hit = v.best;
    if lengths && !h.overflow {
        let n = h.len;
        fill_lengths(&mut h.records[..n]);
    }
}
