//! Guided ropes: where a ray of a shaft goes on past the shaft's common
//! part, the boundary rays' own leaves predict its next leaf.
//!
//! A rope leads to the smallest node covering a leaf's face; a plain rope
//! walk then descends from that node to the leaf holding the exit point,
//! about two interior steps per leaf on the SPD scenes. A ray between the
//! boundary rays of a narrow shaft mostly crosses the leaves they crossed,
//! in the same order. So each ray keeps, per boundary ray, its place on that
//! ray's path of leaves and first tries the leaf the nearest boundary ray
//! entered next: if that leaf's box holds the exit point (with point
//! location's rule for points on a split plane), it is the leaf point
//! location would find, since the leaves partition the tree's box. A right
//! guess visits one node, the leaf itself; a wrong one costs a step and the
//! ray descends by its rope as usual. The hits are those of a plain rope
//! walk, so exactly those of hierarchical traversal.

use super::history::{HistoryRecord, KIND_LEAF, KIND_UNVISITED};
use crate::geom::PreparedRay;
use crate::kd::traverse::{Closest, LeafVisitor, NoRecord, RopeEnd, Steps};
use crate::kd::{KdRopes, KdStackItem, KdTree, NO_NODE};
use crate::{Hit, TraceStats, Vec3};

/// Most boundary rays that guide a ray: all of a patch shaft's
/// ([`super::hlcts::MAX_RAYS`]); an image window has four.
pub const MAX_GUIDES: usize = super::hlcts::MAX_RAYS;

/// Fills a path's slots past its last leaf: no leaf has this index, so a
/// cursor there never matches and the ray has left that path.
const END: u32 = u32::MAX;

/// Start a path at its history's first record.
pub const FROM_START: u32 = u32::MAX - 1;
/// No path: the boundary ray never reached the end of the common part (it
/// ended before).
pub const NO_PATH: u32 = u32::MAX;

/// The leaves (leaf node indices) each boundary ray crossed past the
/// shaft's common part, in order, in a caller buffer: path `j` in slots
/// `j * cap ..`, closed by two end markers.
#[derive(Debug)]
pub struct Paths<'b> {
    slots: &'b [u32],
    cap: usize,
    count: usize,
    /// Per path, the slot of its first [`END`].
    ends: [u32; MAX_GUIDES],
}

impl Paths<'static> {
    /// No paths: rays walk plain ropes.
    pub fn none() -> Paths<'static> {
        Paths {
            slots: &[],
            cap: 0,
            count: 0,
            ends: [0; MAX_GUIDES],
        }
    }
}

impl<'b> Paths<'b> {
    /// The leaves after record `after[j]` (from the start for
    /// [`FROM_START`], none for [`NO_PATH`]) of each history, up to
    /// [`MAX_GUIDES`] of them, into
    /// `buf` (an equal share each; a path that does not fit is cut short,
    /// which only makes guesses run out sooner). A history that overflowed
    /// gives an empty path.
    pub fn build(
        histories: &[Option<&[HistoryRecord]>],
        after: &[u32],
        buf: &'b mut [u32],
    ) -> Paths<'b> {
        let count = histories.len().min(after.len()).min(MAX_GUIDES);
        let cap = buf.len().checked_div(count).unwrap_or(0);
        if cap < 2 {
            return Paths::none();
        }
        let mut ends = [0; MAX_GUIDES];
        for j in 0..count {
            let out = &mut buf[j * cap..(j + 1) * cap];
            let room = cap - 2;
            let mut n = 0;
            if let Some(h) = histories[j].filter(|_| after[j] != NO_PATH) {
                let start = if after[j] == FROM_START {
                    0
                } else {
                    after[j] as usize + 1
                };
                for r in h.iter().skip(start) {
                    let kind = r.kind();
                    if kind == KIND_UNVISITED || n == room {
                        break;
                    }
                    if kind == KIND_LEAF {
                        out[n] = r.node;
                        n += 1;
                    }
                }
            }
            out[n] = END;
            out[n + 1] = END;
            ends[j] = (j * cap + n) as u32;
        }
        Paths {
            slots: buf,
            cap,
            count,
            ends,
        }
    }
}

/// One ray's place on the paths: the slot of the leaf it would meet next on
/// the path it follows (past every path once it has lost them), and the
/// path it started on, searched first when it leaves the one it follows
/// (the others in index order). Three words: made for every ray.
#[derive(Clone, Copy, Debug)]
pub struct Cursor {
    next: u32,
    first: u8,
    count: u8,
}

impl Cursor {
    /// A ray at the start of path `nearest` (the boundary ray closest to
    /// it).
    #[inline]
    pub fn new(paths: &Paths, nearest: usize) -> Cursor {
        let first = nearest.min(paths.count.max(1) - 1);
        Cursor {
            next: (first * paths.cap) as u32,
            first: first as u8,
            count: paths.count as u8,
        }
    }

    /// The paths in search order: the first one, then the others.
    #[inline]
    fn order(&self) -> impl Iterator<Item = usize> {
        let (first, count) = (self.first as usize, self.count as usize);
        (0..count).map(move |i| match i {
            0 => first,
            i if i <= first => i - 1,
            i => i,
        })
    }

    /// The leaf the followed path enters next, if it holds `p` (a wrong
    /// guess costs a step: its box was read).
    #[inline]
    fn guess(
        &mut self,
        tree: &KdTree,
        paths: &Paths,
        from: u32,
        p: Vec3,
        d: Vec3,
        steps: &mut Steps,
    ) -> Option<u32> {
        let leaf = *paths.slots.get(self.next as usize)?;
        if leaf != END {
            if holds(tree.rope(leaf), p, d) {
                self.next += 1;
                return Some(leaf);
            }
            steps.leaves += 1;
        }
        // The other paths through `from`: where they went next.
        let mut tried = leaf;
        for j in self.order() {
            let (lo, hi) = (j * paths.cap, paths.ends[j] as usize);
            let Some(i) = paths.slots[lo..hi].iter().position(|&l| l == from) else {
                continue;
            };
            let cand = paths.slots[lo + i + 1];
            if cand == END || cand == tried {
                continue;
            }
            if holds(tree.rope(cand), p, d) {
                self.next = (lo + i + 2) as u32;
                return Some(cand);
            }
            steps.leaves += 1;
            tried = cand;
        }
        None
    }

    /// The ray entered `leaf`, the one its rope leads to: on along the
    /// followed path if that is where it went too, else as [`Cursor::resync`].
    #[inline]
    pub(crate) fn follow(&mut self, paths: &Paths, leaf: u32) {
        match paths.slots.get(self.next as usize) {
            Some(&l) if l == leaf => self.next += 1,
            Some(_) => self.resync(paths, leaf),
            None => {}
        }
    }

    /// The ray entered `leaf`, found by its rope: follow the first path (in
    /// search order) that entered it too, from there on; none: stop guessing.
    fn resync(&mut self, paths: &Paths, leaf: u32) {
        for j in self.order() {
            let (from, to) = (j * paths.cap, paths.ends[j] as usize);
            if let Some(i) = paths.slots[from..to].iter().position(|&l| l == leaf) {
                self.next = (from + i + 1) as u32;
                return;
            }
        }
        self.next = u32::MAX;
    }
}

/// Whether leaf box `rp` holds `p` as point location decides: a point on a
/// split plane belongs to the side the ray heads into (direction `d`), and
/// one on a plane parallel to the ray to neither (location then fails, and
/// so does this). The root box's faces count as split planes here.
#[inline]
pub fn holds(rp: &KdRopes, p: Vec3, d: Vec3) -> bool {
    let mut inside = true;
    for a in 0..3 {
        let (lo, hi, x) = (rp.min[a], rp.max[a], p[a]);
        // `&`, not `&&`: six comparisons cost less than their branches.
        inside &= ((lo < x) | ((lo == x) & (d[a] > 0.0))) & ((x < hi) | ((x == hi) & (d[a] < 0.0)));
    }
    inside
}

/// The ray's first leaf, point `p` (where it enters the scene's box) found
/// among the paths' first leaves. The root box's faces are no split: a
/// point just outside one (the traced box is a little wider) is located as
/// if on it.
pub(crate) fn guess_first(
    tree: &KdTree,
    paths: &Paths,
    cur: &mut Cursor,
    p: Vec3,
    d: Vec3,
    steps: &mut Steps,
) -> Option<u32> {
    let b = tree.info.bounds();
    let p = p.clamp(b.min, b.max);
    // Every path's first leaf, nearest first: the ray's first leaf is
    // where its descent parts from theirs, so often one of them.
    let mut tried = [END; MAX_GUIDES];
    for (k, j) in cur.order().enumerate() {
        let from = j * paths.cap;
        let leaf = paths.slots[from];
        if leaf == END || tried[..k].contains(&leaf) {
            continue;
        }
        tried[k] = leaf;
        if holds(tree.rope(leaf), p, d) {
            cur.next = from as u32 + 1;
            return Some(leaf);
        }
        steps.leaves += 1;
    }
    None
}

/// A ray of a shaft without common leaves: its first leaf is one a
/// boundary ray entered first (where the ray meets the scene's box at
/// `t0`), or else `locate` finds it from the shaft's own starting node;
/// then guided ropes to `t1`. False when the ray must be redone
/// hierarchically.
#[allow(clippy::too_many_arguments)]
pub(crate) fn walk_from_first(
    tree: &KdTree,
    v: &mut Closest,
    t0: f32,
    t1: f32,
    paths: &Paths,
    cur: &mut Cursor,
    steps: &mut Steps,
    locate: impl FnOnce(&PreparedRay, Vec3, &mut Steps) -> Option<u32>,
) -> bool {
    let r = v.ray;
    let p = r.at(t0);
    let first = match guess_first(tree, paths, cur, p, r.dir, steps) {
        Some(leaf) => leaf,
        None => match locate(&r, p, steps) {
            Some(leaf) => leaf,
            None => return false,
        },
    };
    walk(tree, v, first, t1, paths, cur, steps) != RopeEnd::Fallback
}

/// The end of every shaft ray's trace: one whose walk could not finish
/// (`done` false: a ray in a split plane it crosses) is redone by
/// hierarchical traversal; the counts go to `stats`.
pub(crate) fn finish(
    tree: &KdTree,
    v: &mut Closest,
    done: bool,
    stack: &mut [KdStackItem],
    mut steps: Steps,
    stats: &mut TraceStats,
) -> Hit {
    if !done && steps.faults == 0 {
        v.best = Hit::MISS;
        tree.walk_hierarchical(v, &mut NoRecord, stack, &mut steps);
    }
    steps.flush(stats);
    stats.prim_tests += v.tests;
    v.best
}

/// Visits a shaft's common leaves (`(node, run)` in order; a run of empty
/// leaves, named by its last leaf, is one step and no test), then goes on
/// by guided ropes from the last of them to `t1`. False when the ray must
/// be redone hierarchically (it lies in a split plane it crosses, or there
/// is no leaf).
pub(crate) fn walk_common(
    tree: &KdTree,
    leaves: impl Iterator<Item = (u32, bool)>,
    v: &mut Closest,
    t1: f32,
    paths: &Paths,
    cur: &mut Cursor,
    steps: &mut Steps,
) -> bool {
    let mut last = None;
    for (node, run) in leaves {
        steps.leaves += 1;
        let nd = tree.node(node);
        last = Some(node);
        if run {
            steps.empty += 1;
            continue;
        }
        let Some(refs) = tree.leaf_refs(nd) else {
            steps.fault();
            return true;
        };
        // The leaf's exit matters only once something is hit: test first.
        v.visit(&tree.scene, refs, f32::NEG_INFINITY);
        if v.best.is_hit() {
            let t_exit = tree.leaf_exit(&v.ray, node).0.min(t1);
            if crate::kd::traverse::inside_leaf(v.best.t, t_exit) {
                return true;
            }
        }
    }
    match last {
        Some(last) => walk_past(tree, v, last, t1, paths, cur, steps),
        None => false,
    }
}

/// Goes on past leaf node `last` (visited, no hit inside it) by guided
/// ropes to `t1`. False when the ray must be redone hierarchically.
pub(crate) fn walk_past(
    tree: &KdTree,
    v: &mut Closest,
    last: u32,
    t1: f32,
    paths: &Paths,
    cur: &mut Cursor,
    steps: &mut Steps,
) -> bool {
    let r = v.ray;
    let (t_exit, face, at_edge) = tree.leaf_exit_at_edge(&r, last);
    if t_exit > t1 {
        return true;
    }
    if at_edge {
        return false;
    }
    match next(tree, &r, last, t_exit, face, paths, cur, steps) {
        Ok(None) => true,
        Ok(Some(n)) => walk(tree, v, n, t1, paths, cur, steps) != RopeEnd::Fallback,
        Err(()) => false,
    }
}

/// Rope walk from leaf node `first` (not yet visited), guided by `paths`,
/// until the visitor stops or the segment ends at `t1`.
pub(crate) fn walk(
    tree: &KdTree,
    v: &mut Closest,
    first: u32,
    t1: f32,
    paths: &Paths,
    cur: &mut Cursor,
    steps: &mut Steps,
) -> RopeEnd {
    let r = v.ray;
    tree.rope_walk_by(v, first, t1, steps, |leaf, t_exit, face, steps| {
        next(tree, &r, leaf, t_exit, face, paths, cur, steps)
    })
}

/// The leaf node beyond face `face` of leaf node `leaf` where the ray goes
/// on after `t_exit`, guessed from the paths or else found down the rope:
/// `Ok(None)` at the scene's boundary, `Err(())` when the ray lies in a
/// split plane there.
#[allow(clippy::too_many_arguments)]
#[inline]
pub(crate) fn next(
    tree: &KdTree,
    r: &PreparedRay,
    leaf: u32,
    t_exit: f32,
    face: usize,
    paths: &Paths,
    cur: &mut Cursor,
    steps: &mut Steps,
) -> Result<Option<u32>, ()> {
    let rp = tree.rope(leaf);
    let rope = rp.neighbor[face];
    if rope == NO_NODE {
        return Ok(None);
    }
    // A rope that leads straight to a leaf needs no guess.
    if tree.node(rope).is_leaf() {
        cur.follow(paths, rope);
        return Ok(Some(rope));
    }
    let p = rp.onto_face(face, r.at(t_exit));
    if let Some(n) = cur.guess(tree, paths, leaf, p, r.dir, steps) {
        return Ok(Some(n));
    }
    match tree.locate(rope, p, steps) {
        Some(leaf) => {
            if cur.next != u32::MAX {
                cur.resync(paths, leaf);
            }
            Ok(Some(leaf))
        }
        None => Err(()),
    }
}
