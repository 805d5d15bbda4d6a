//! The hierarchical LCTS: the cut of the kd-tree where the boundary rays of
//! a shaft stop deciding alike. Above the cut every ray of the shaft would
//! make the same decisions, so it starts at the cut's nodes, in order, and
//! traverses each subtree hierarchically.
//!
//! Each entry keeps, per boundary ray, where that node's subtree lies in the
//! ray's history, so a sub-shaft's HLCTS is built from its parent's entries
//! without retracing from the root (section 4.2.3).
//!
//! Two ways through a cut. [`trace`] walks its entries in order, each
//! subtree hierarchically, and can record the ray's history relative to the
//! cut (the rays that split a shaft need that, for their halves' cuts).
//! [`trace_guided`] is for the other rays: the cut's leading leaves are the
//! shaft's common leaf sequence (section 4.3.3), so a ray visits them, then
//! goes on by ropes guided by the boundary rays' leaves ([`super::guide`]),
//! as an SLCTS ray does; a cut that starts at an interior node (the boundary
//! rays share no leaf) starts the ray at its first leaf, found from there.
//! Walking the cut's interior entries one by one costs more steps than the
//! guided ropes (at 1024^2, HLCTS-2D alpha 0.33-0.56 before, 0.24-0.33 after).

use super::guide::{self, Cursor, Paths, FROM_START, MAX_GUIDES, NO_PATH};
use super::history::{fill_lengths, History, HistoryRecord, KIND_LEAF};
use crate::geom::{Aabb, PreparedRay};
use crate::kd::traverse::{Closest, NoRecord, Steps};
use crate::kd::{KdNode, KdStackItem, KdTree};
use crate::{Hit, Ray, TraceStats, Vec3};

/// "No record": the ray never reached this node (it ended before it).
pub const NONE: u32 = u32::MAX;
/// Most boundary rays a shaft may have: the 4 x 4 vertex pairs of two quads.
pub const MAX_RAYS: usize = 16;

/// Flag of an entry standing for a run of empty leaves (section 4.3.1).
pub const ENTRY_EMPTY_RUN: u32 = 1;

/// One node of the cut, its box, and per boundary ray the index of its
/// record in that ray's history (or [`NONE`]). Plain data.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub struct HlctsEntry {
    /// Node index.
    pub node: u32,
    /// [`ENTRY_EMPTY_RUN`].
    pub flags: u32,
    /// Lower corner of the node's box.
    pub min: [f32; 3],
    /// Upper corner of the node's box.
    pub max: [f32; 3],
    /// Record index per boundary ray.
    pub ptr: [u32; MAX_RAYS],
}

/// An HLCTS in a caller buffer.
#[derive(Debug)]
pub struct Hlcts<'b> {
    /// Entries, in the order every ray of the shaft meets them.
    pub entries: &'b mut [HlctsEntry],
    /// Entries used.
    pub len: usize,
    /// Leading entries that are leaves (section 4.3.3).
    pub leading_leaves: usize,
    /// Termination object (section 4.3.2), a global primitive index.
    pub termination: Option<u32>,
}

impl Hlcts<'_> {
    /// The used entries.
    pub fn as_slice(&self) -> &[HlctsEntry] {
        &self.entries[..self.len]
    }

    /// The paths of the boundary rays `histories` (those the cut was built
    /// from, in the same order) past the leading leaves, into `buf`.
    pub fn paths<'p>(
        &self,
        histories: &[Option<&[HistoryRecord]>],
        buf: &'p mut [u32],
    ) -> Paths<'p> {
        let after: [u32; MAX_GUIDES] = core::array::from_fn(|j| match self.leading_leaves {
            0 => FROM_START,
            k => match self.entries[k - 1].ptr[j] {
                NONE => NO_PATH,
                at => at,
            },
        });
        Paths::build(histories, &after, buf)
    }
}

/// The entry that starts every traversal: the root, whose record is the
/// first of every history traced from the root.
pub fn root_entry(tree: &KdTree) -> HlctsEntry {
    let b = tree.trace_box.aabb();
    HlctsEntry {
        node: 0,
        flags: 0,
        min: b.min.into(),
        max: b.max.into(),
        ptr: [0; MAX_RAYS],
    }
}

/// Where a boundary ray's record for a parent entry is found.
#[derive(Clone, Copy)]
pub enum Source<'a> {
    /// A boundary ray of the parent shaft: slot `j` of each parent entry's `ptr`.
    Parent(usize),
    /// A ray traced through the parent HLCTS: its record index per parent entry.
    Starts(&'a [u32]),
}

/// One boundary ray of a shaft: the ray, its history, where its records
/// are, its hit.
#[derive(Clone, Copy)]
pub struct Boundary<'a> {
    /// The ray.
    pub ray: Ray,
    /// The history (`None` when it overflowed: the ray then shares nothing).
    pub records: Option<&'a [HistoryRecord]>,
    /// How its record for each parent entry is found.
    pub source: Source<'a>,
    /// Its hit.
    pub hit: Hit,
}

struct Builder<'t, 'b, 'r> {
    tree: &'t KdTree<'t>,
    rays: &'r [Boundary<'r>],
    out: Hlcts<'b>,
    last_empty: bool,
    /// An entry did not fit: the cut is incomplete and must not be used.
    full: bool,
    /// Nodes visited by the walks.
    walks: u64,
    /// The first record of the first ray that the current parent entry's
    /// walk has not read: a walk reads the records in preorder, so a
    /// position below it is read a second time, which only histories that
    /// do not match the tree (a corrupt tree's, or lengths left partial)
    /// lead to. Such a node is emitted instead of refined: without this,
    /// two children sent to overlapping records doubled the visits at
    /// every level (2^depth on a tree that is its own child).
    unread: u32,
}

/// Builds the HLCTS of a shaft whose boundary rays are `rays` (at most
/// [`MAX_RAYS`]) under the parent cut `parent` (for the first shaft,
/// `[root_entry(tree)]` with every ray sourced as `Parent(j)`). When the
/// refined cut does not fit `entries`, the parent's cut is kept unrefined
/// (it is valid for every sub-shaft), so an entry buffer at least as long as
/// the parent cut always gives a usable cut.
pub fn build<'b>(
    tree: &KdTree,
    parent: &[HlctsEntry],
    rays: &[Boundary],
    entries: &'b mut [HlctsEntry],
) -> Hlcts<'b> {
    build_counted(tree, parent, rays, entries).0
}

/// [`build`], and how many nodes its walks visited.
fn build_counted<'b>(
    tree: &KdTree,
    parent: &[HlctsEntry],
    rays: &[Boundary],
    entries: &'b mut [HlctsEntry],
) -> (Hlcts<'b>, u64) {
    let mut b = Builder {
        tree,
        rays: &rays[..rays.len().min(MAX_RAYS)],
        out: Hlcts {
            entries,
            len: 0,
            leading_leaves: 0,
            termination: None,
        },
        last_empty: false,
        full: false,
        walks: 0,
        unread: 0,
    };
    for refine in [true, false] {
        b.out.len = 0;
        b.last_empty = false;
        b.full = false;
        for (e, pe) in parent.iter().enumerate() {
            let mut pos = [NONE; MAX_RAYS];
            for (j, r) in b.rays.iter().enumerate() {
                pos[j] = match (r.records, r.source) {
                    (None, _) => NONE,
                    (Some(_), Source::Parent(slot)) => pe.ptr[slot],
                    (Some(_), Source::Starts(s)) => s.get(e).copied().unwrap_or(NONE),
                };
            }
            let bx = Aabb {
                min: Vec3::from(pe.min),
                max: Vec3::from(pe.max),
            };
            if pe.flags & ENTRY_EMPTY_RUN != 0 || !refine {
                b.push(pe.node, pe.flags, &bx, pos);
            } else {
                b.unread = 0;
                b.walk(pe.node, bx, pos, 0);
            }
        }
        if !b.full {
            break;
        }
    }
    if b.full {
        // Not even the parent's cut fits: share nothing below the root.
        b.out.len = 0;
        b.full = false;
        b.push(0, 0, &tree.trace_box.aabb(), [NONE; MAX_RAYS]);
    }
    let n = b.out.len;
    b.out.leading_leaves = b.out.entries[..n]
        .iter()
        .take_while(|e| tree.node(e.node).is_leaf())
        .count();
    b.out.termination = termination_object(tree, &b.out, rays);
    (b.out, b.walks)
}

impl Builder<'_, '_, '_> {
    fn kind(&self, j: usize, pos: u32) -> u32 {
        match self.rays[j].records {
            Some(r) if (pos as usize) < r.len() => r[pos as usize].kind(),
            _ => 6, // missing: differs from everything recorded
        }
    }

    fn walk(&mut self, node: u32, bx: Aabb, pos: [u32; MAX_RAYS], depth: u32) {
        self.walks += 1;
        let k = self.rays.len();
        let kind = self.kind(0, pos[0]);
        // Equal decisions carry over to the rays between only when the
        // boundary rays also enter and leave the node through the same
        // faces: then every ray of the shaft enters (and leaves) within the
        // convex hull of their entry (exit) points on that face, on the same
        // side of the split. (Equal decisions alone do not suffice: two rays
        // leaving through opposite faces before the split can straddle one
        // that crosses it.)
        let alike = kind < 4
            && pos[0] >= self.unread
            && depth <= crate::kd::KD_MAX_DEPTH
            && (1..k).all(|j| self.kind(j, pos[j]) == kind)
            && {
                let f = faces(&self.rays[0].ray, &bx);
                (1..k).all(|j| faces(&self.rays[j].ray, &bx) == f)
            };
        if !alike {
            self.emit(node, &bx, pos);
            return;
        }
        let nd: KdNode = self.tree.node(node);
        if nd.is_leaf() {
            // Decisions recorded for a leaf: only a corrupt tree does that.
            self.emit(node, &bx, pos);
            return;
        }
        // `kind < 4`: the record lies in the history, below `u32::MAX`.
        self.unread = pos[0] + 1;
        let (a, s, left) = (nd.axis(), nd.split(), nd.left());
        let mut lb = bx;
        lb.max[a] = s;
        let mut rb = bx;
        rb.min[a] = s;
        let mut first = [NONE; MAX_RAYS];
        let mut second = [NONE; MAX_RAYS];
        for j in 0..k {
            let r = self.rays[j].records.unwrap_or(&[]);
            let p1 = pos[j] as usize + 1;
            first[j] = p1 as u32;
            second[j] = r
                .get(p1)
                .map_or(NONE, |rec| (p1 + rec.subtree_len()) as u32);
        }
        match kind {
            0 => self.walk(left, lb, first, depth + 1),
            1 => self.walk(left + 1, rb, first, depth + 1),
            2 => {
                self.walk(left, lb, first, depth + 1);
                self.walk(left + 1, rb, second, depth + 1);
            }
            _ => {
                self.walk(left + 1, rb, first, depth + 1);
                self.walk(left, lb, second, depth + 1);
            }
        }
    }

    fn emit(&mut self, node: u32, bx: &Aabb, pos: [u32; MAX_RAYS]) {
        let nd = self.tree.node(node);
        let empty = nd.is_leaf() && self.tree.leaf_refs(nd).is_none_or(|r| r.is_empty());
        if empty && self.last_empty {
            // Unified into the run already in the sequence, which now ends
            // here: a ray that goes on by ropes leaves the run from this leaf.
            if let Some(run) = self.out.entries[..self.out.len].last_mut() {
                run.node = node;
                run.min = bx.min.into();
                run.max = bx.max.into();
                run.ptr = pos;
            }
            return;
        }
        self.last_empty = empty;
        self.push(node, if empty { ENTRY_EMPTY_RUN } else { 0 }, bx, pos);
    }

    fn push(&mut self, node: u32, flags: u32, bx: &Aabb, pos: [u32; MAX_RAYS]) {
        if self.out.len == self.out.entries.len() {
            self.full = true;
            return;
        }
        self.out.entries[self.out.len] = HlctsEntry {
            node,
            flags,
            min: bx.min.into(),
            max: bx.max.into(),
            ptr: pos,
        };
        self.out.len += 1;
    }
}

/// The faces (0 to 5: -x, +x, -y, +y, -z, +z) through which `ray` enters
/// and leaves `bx`; 6 where its segment starts or ends inside, 7 when it misses.
pub(crate) fn faces(ray: &Ray, bx: &Aabb) -> (u8, u8) {
    let mut t0 = ray.t_min;
    let mut t1 = ray.t_max;
    let (mut f0, mut f1) = (6u8, 6u8);
    for a in 0..3 {
        let d = ray.dir[a];
        if d == 0.0 {
            if ray.origin[a] < bx.min[a] || ray.origin[a] > bx.max[a] {
                return (7, 7);
            }
            continue;
        }
        let inv = 1.0 / d;
        let (lo, hi) = (
            (bx.min[a] - ray.origin[a]) * inv,
            (bx.max[a] - ray.origin[a]) * inv,
        );
        let (near, far, fn_, ff) = if d > 0.0 {
            (lo, hi, 2 * a, 2 * a + 1)
        } else {
            (hi, lo, 2 * a + 1, 2 * a)
        };
        if near > t0 {
            t0 = near;
            f0 = fn_ as u8;
        }
        if far < t1 {
            t1 = far;
            f1 = ff as u8;
        }
    }
    if t0 > t1 {
        (7, 7)
    } else {
        (f0, f1)
    }
}

/// Section 4.3.2 over the cut: every boundary ray hits the same convex
/// primitive and ends in the first non-empty entry, a leaf holding only it.
fn termination_object(tree: &KdTree, h: &Hlcts, rays: &[Boundary]) -> Option<u32> {
    let first = rays.first()?.hit;
    if !first.is_hit()
        || rays
            .iter()
            .any(|r| (r.hit.geom_id, r.hit.prim_id) != (first.geom_id, first.prim_id))
    {
        return None;
    }
    let global = match first.geom_id {
        crate::geom::GEOM_TRIANGLES => first.prim_id,
        crate::geom::GEOM_SPHERES => tree.scene.triangles.len() as u32 + first.prim_id,
        _ => return None,
    };
    let c = match h.as_slice() {
        [c, ..] if c.flags & ENTRY_EMPTY_RUN == 0 => c.node,
        [e, c, ..] if e.flags & ENTRY_EMPTY_RUN != 0 && c.flags & ENTRY_EMPTY_RUN == 0 => c.node,
        _ => return None,
    };
    let nd = tree.node(c);
    if !nd.is_leaf() || tree.leaf_refs(nd) != Some(&[global]) {
        return None;
    }
    let ends_in_c = |r: &Boundary| {
        r.records
            .and_then(|recs| recs.iter().rev().find(|x| x.kind() == KIND_LEAF))
            .map(|x| x.node)
            == Some(c)
    };
    rays.iter().all(ends_in_c).then_some(global)
}

/// Traces `ray` (inside the shaft of `h`) from the cut: the termination
/// object if any, else each entry's subtree in order. With `record`, also
/// writes the ray's history (records of each entry's subtree, in order)
/// and `starts[e]`, where entry `e`'s records begin ([`NONE`] where the ray
/// ended before it). The hit is exactly the hierarchical traversal's.
/// `stack`: [`crate::kd::KD_STACK_LEN`] entries.
pub fn trace(
    tree: &KdTree,
    h: &Hlcts,
    ray: &Ray,
    mut record: Option<(&mut History, &mut [u32])>,
    stack: &mut [KdStackItem],
    stats: &mut TraceStats,
) -> Hit {
    stats.rays += 1;
    if let Some((hist, starts)) = record.as_mut() {
        hist.len = 0;
        hist.overflow = false;
        hist.hit = Hit::MISS;
        for s in starts.iter_mut() {
            *s = NONE;
        }
    }
    if !ray.is_valid() {
        return Hit::MISS;
    }
    let mut v = Closest::new(ray);
    let mut steps = Steps::default();
    let r = v.ray;
    if tree.scene_segment(&r).is_none() {
        // Outside the scene's box: no step, as in every traversal (the
        // history is already empty).
        return Hit::MISS;
    }
    let hit_via_termination = record.is_none() && terminated(tree, h, &mut v, &mut steps);
    if !hit_via_termination {
        for (e, entry) in h.as_slice().iter().enumerate() {
            if entry.flags & ENTRY_EMPTY_RUN != 0 {
                // Nothing to test; one step for the whole run.
                steps.leaves += 1;
                steps.empty += 1;
                if let Some((hist, starts)) = record.as_mut() {
                    starts[e] = hist.len as u32;
                    crate::kd::traverse::Recorder::leaf(&mut **hist, entry.node);
                }
                continue;
            }
            let bx = Aabb {
                min: Vec3::from(entry.min),
                max: Vec3::from(entry.max),
            };
            let Some((t0, t1)) = bx.clip_ray(r.origin, r.inv_dir, r.t_min, r.t_max) else {
                // Testing an entry the ray misses is a step too.
                steps.interior += 1;
                continue;
            };
            let stopped = match record.as_mut() {
                Some((hist, starts)) => {
                    starts[e] = hist.len as u32;
                    tree.walk_from(&mut v, &mut **hist, stack, entry.node, t0, t1, &mut steps)
                }
                None => {
                    tree.walk_from(&mut v, &mut NoRecord, stack, entry.node, t0, t1, &mut steps)
                }
            };
            if stopped {
                break;
            }
        }
    }
    if let Some((hist, _)) = record.as_mut() {
        hist.hit = v.best;
        if !hist.overflow {
            let n = hist.len;
            fill_lengths(&mut hist.records[..n]);
        }
    }
    steps.flush(stats);
    stats.prim_tests += v.tests;
    v.best
}

/// Section 4.3.2: the ray hits the termination object, strictly inside its
/// leaf (a hit on the leaf's far boundary may tie with a primitive of the
/// next leaf): then that is its hit, after one step per entry up to the
/// object's leaf. False when there is no termination object or this ray
/// needs the cut after all (rounding, or such a boundary hit).
fn terminated(tree: &KdTree, h: &Hlcts, v: &mut Closest, steps: &mut Steps) -> bool {
    let Some(o) = h.termination else {
        return false;
    };
    let r = v.ray;
    v.tests += 1;
    let leaf_exit = h
        .as_slice()
        .iter()
        .take(2)
        .find(|e| e.flags & ENTRY_EMPTY_RUN == 0)
        .and_then(|e| {
            let bx = Aabb {
                min: Vec3::from(e.min),
                max: Vec3::from(e.max),
            };
            bx.clip_ray(r.origin, r.inv_dir, r.t_min, r.t_max)
        })
        .map_or(f32::NEG_INFINITY, |(_, t1)| t1);
    match tree.scene.intersect_prim(o as usize, &r, r.t_max) {
        Some(hit) if crate::kd::traverse::inside_leaf(hit.t, leaf_exit) => {
            v.best = hit;
            steps.leaves += h.as_slice().iter().take(2).count() as u64;
            true
        }
        _ => false,
    }
}

/// The first leaf of ray `r` of a cut without leading leaves, located
/// from the cut's first entry (an interior node every ray of the shaft
/// enters first) where `r` enters its box; `None` when it misses the box
/// or lies in a split plane (the ray is then traced hierarchically).
#[inline]
pub(crate) fn locate_first(
    tree: &KdTree,
    h: &Hlcts,
    r: &PreparedRay,
    steps: &mut Steps,
) -> Option<u32> {
    let e = h.as_slice().first()?;
    let bx = Aabb {
        min: Vec3::from(e.min),
        max: Vec3::from(e.max),
    };
    let (te, _) = bx.clip_ray(r.origin, r.inv_dir, r.t_min, r.t_max)?;
    tree.locate(e.node, r.at(te), steps)
}

/// Traces `ray` (inside the shaft of `h`) without a history: the
/// termination object if any; else the leading leaves (the shaft's common
/// leaf sequence, section 4.3.3), then ropes guided by `paths`
/// ([`Hlcts::paths`] of the boundary rays, asked first at `nearest`, or
/// [`Paths::none`]). A cut without leading leaves starts the ray at its
/// first leaf, guessed from the paths or located from the first entry.
/// The hit is exactly the hierarchical traversal's. `stack` serves a ray
/// that must be redone hierarchically.
pub fn trace_guided(
    tree: &KdTree,
    h: &Hlcts,
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
    let Some((t0, t1)) = tree.scene_segment(&v.ray) else {
        return Hit::MISS;
    };
    let done = terminated(tree, h, &mut v, &mut steps) || {
        let mut cur = Cursor::new(paths, nearest);
        match h.leading_leaves {
            // No leading leaf: the first leaf from the cut's first entry, an
            // interior node every ray of the shaft enters first.
            0 => {
                let from_entry =
                    |r: &PreparedRay, _: Vec3, steps: &mut Steps| locate_first(tree, h, r, steps);
                guide::walk_from_first(
                    tree, &mut v, t0, t1, paths, &mut cur, &mut steps, from_entry,
                )
            }
            k => {
                let leaves = h.entries[..k]
                    .iter()
                    .map(|e| (e.node, e.flags & ENTRY_EMPTY_RUN != 0));
                guide::walk_common(tree, leaves, &mut v, t1, paths, &mut cur, &mut steps)
            }
        }
    };
    guide::finish(tree, &mut v, done, stack, steps, stats)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kd::KdInfo;

    /// A corrupt tree whose interior nodes are their own children, under
    /// histories that say "both children" at every record with no subtree
    /// lengths filled in (what a ray's traversal of such a tree records
    /// when its history runs out): the walks must read each record of the
    /// first ray once, so that their visits stay linear in the history.
    #[test]
    fn a_cut_over_a_cyclic_tree_reads_each_record_once() {
        let nodes = [KdNode::interior(0, 0.0, 1); 3];
        let info = KdInfo {
            node_count: 3,
            bounds_min: [-1.0; 3],
            bounds_max: [1.0; 3],
            ..KdInfo::default()
        };
        let tree =
            KdTree::from_checked_parts(crate::Scene::default(), &info, &nodes, &[], &[], &[]);
        const N: usize = 30;
        let mut records = [HistoryRecord::default(); N];
        for (i, r) in records.iter_mut().enumerate() {
            // Decision 2 (both children), subtree length 1.
            *r = HistoryRecord {
                node: if i == 0 { 0 } else { 1 + (i % 2) as u32 },
                word: 2 | 1 << 3,
            };
        }
        let ray = Ray::new(Vec3::new(-2.0, 0.5, 0.5), Vec3::X, 0.0, f32::INFINITY);
        let rays: [Boundary; 4] = core::array::from_fn(|j| Boundary {
            ray,
            records: Some(&records),
            source: Source::Parent(j),
            hit: Hit::MISS,
        });
        let parent = [root_entry(&tree)];
        let mut entries = [HlctsEntry::default(); 64];
        let (_, walks) = build_counted(&tree, &parent, &rays, &mut entries);
        assert!(walks <= 2 * N as u64 + 2, "{walks} visits over {N} records");
    }
}
