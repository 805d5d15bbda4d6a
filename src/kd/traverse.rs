//! Hierarchical traversal after Havran's TA_B^rec and rope traversal, for
//! closest hit and any hit. The method is chosen once per call, outside the
//! ray loop; each walk is generic over what a leaf visit does, so closest
//! and any hit share one walk without a branch on the query kind.

use super::node::{KdNode, KdStackItem, KD_STACK_LEN, NO_NODE};
use super::KdTree;
use crate::geom::leaf::beats;
use crate::geom::{ClipBox, Hit, PreparedRay, Ray, Scene, Vec3};
use crate::limits::KD_MAX_DEPTH;
use crate::TraceStats;

/// How a ray walks the tree.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Traversal {
    /// Stack traversal with signed entry and exit distances (Havran's
    /// TA_B^rec), on the caller's stack of [`KD_STACK_LEN`] exit points:
    /// enough for any tree.
    Hierarchical,
    /// Leaf to leaf through the six ropes of each leaf; no stack. A ray
    /// that lies exactly in a split plane it must cross falls back to
    /// hierarchical traversal (both sides of the plane hold its hits), and
    /// so does every ray of a tree built without ropes
    /// ([`super::KdParams::ropes`]).
    Ropes,
    /// Arrays of rays in packets of 8 ([`KdTree::intersect_packets`]):
    /// each group of 8 consecutive rays that move alike walks the tree
    /// once, its primitives tested 8 rays at a time; the hits are the
    /// hierarchical traversal's. One ray alone is traced hierarchically.
    Packets,
}

/// What happens at a leaf: test its primitives; return true to stop.
pub(crate) trait LeafVisitor {
    fn ray(&self) -> &PreparedRay;
    fn visit(&mut self, scene: &Scene, refs: &[u32], exit_t: f32) -> bool;
}

/// Closest hit: keeps the nearest hit; stops once it lies within the leaf.
pub(crate) struct Closest {
    pub ray: PreparedRay,
    pub best: Hit,
    pub tests: u64,
}

impl Closest {
    pub fn new(ray: &Ray) -> Closest {
        Closest {
            ray: PreparedRay::new(ray),
            best: Hit::MISS,
            tests: 0,
        }
    }
}

impl LeafVisitor for Closest {
    fn ray(&self) -> &PreparedRay {
        &self.ray
    }
    #[inline]
    fn visit(&mut self, scene: &Scene, refs: &[u32], exit_t: f32) -> bool {
        for &p in refs {
            self.tests += 1;
            let t_max = if self.best.is_hit() {
                self.best.t
            } else {
                self.ray.t_max
            };
            if let Some(h) = scene.intersect_prim(p as usize, &self.ray, t_max) {
                if beats(&h, &self.best) {
                    self.best = h;
                }
            }
        }
        // A hit on (or within rounding of) the leaf's far boundary may tie
        // with one in the next leaf: stop only when it lies clearly inside.
        self.best.is_hit() && inside_leaf(self.best.t, exit_t)
    }
}

/// Whether a hit at `t` lies clearly before a leaf's exit at `exit_t`, by
/// more than the rounding of either ([`crate::tolerance::LEAF_EXIT_MARGIN`]
/// of t): only then can no primitive of a later leaf be hit at the same t.
#[inline]
pub(crate) fn inside_leaf(t: f32, exit_t: f32) -> bool {
    exit_t - t > t.abs() * crate::tolerance::LEAF_EXIT_MARGIN
}

/// Any hit: stops at the first.
pub(crate) struct Any {
    pub ray: PreparedRay,
    pub hit: bool,
    pub tests: u64,
}

impl LeafVisitor for Any {
    fn ray(&self) -> &PreparedRay {
        &self.ray
    }
    #[inline]
    fn visit(&mut self, scene: &Scene, refs: &[u32], _exit_t: f32) -> bool {
        for &p in refs {
            self.tests += 1;
            if scene
                .intersect_prim(p as usize, &self.ray, self.ray.t_max)
                .is_some()
            {
                self.hit = true;
                return true;
            }
        }
        false
    }
}

/// The traversal decision at an interior node, as the LCTS paper names them:
/// which children the ray visits, in which order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Decision {
    /// Only the left child.
    Left = 0,
    /// Only the right child.
    Right = 1,
    /// Left, then right.
    LeftRight = 2,
    /// Right, then left.
    RightLeft = 3,
}

/// Observes a hierarchical traversal: the traversal history of the LCTS
/// paper. Calls come in depth-first preorder of the visited nodes.
pub(crate) trait Recorder {
    /// An interior node was visited and decided `d`.
    fn interior(&mut self, node: u32, d: Decision);
    /// A leaf was visited: its node.
    fn leaf(&mut self, node: u32);
    /// A node was pushed but not visited: the ray ended first.
    fn unvisited(&mut self, node: u32);
}

/// The recorder of an ordinary traversal: records nothing, costs nothing.
pub(crate) struct NoRecord;

impl Recorder for NoRecord {
    #[inline(always)]
    fn interior(&mut self, _: u32, _: Decision) {}
    #[inline(always)]
    fn leaf(&mut self, _: u32) {}
    #[inline(always)]
    fn unvisited(&mut self, _: u32) {}
}

/// Steps counted in registers during a walk, added to [`TraceStats`] after.
#[derive(Clone, Copy, Default)]
pub(crate) struct Steps {
    pub interior: u64,
    pub leaves: u64,
    pub empty: u64,
    /// Walks cut short by a broken invariant of the tree (see
    /// [`TraceStats::faults`]).
    pub faults: u64,
}

impl Steps {
    pub fn flush(&self, stats: &mut TraceStats) {
        stats.interior_steps += self.interior;
        stats.leaf_steps += self.leaves;
        stats.empty_leaf_steps += self.empty;
        stats.traversal_steps += self.interior + self.leaves;
        stats.faults += (self.faults > 0) as u64;
    }

    /// Records a broken invariant; the walk then stops.
    #[cold]
    pub fn fault(&mut self) {
        self.faults += 1;
    }
}

/// How a rope walk ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum RopeEnd {
    /// The visitor stopped it (a hit, for closest hit within its leaf).
    Stopped,
    /// The ray left the scene or its segment ended.
    Exited,
    /// The ray meets a split plane where a walk from leaf to leaf cannot
    /// tell the side (it lies in the plane, starts on it, or leaves a leaf
    /// through an edge or corner): hierarchical traversal must redo it.
    Fallback,
}

/// How far (in multiples of the scene's coordinate scale) a ray's points
/// may lie for rope traversal: see [`KdTree::points_precise`].
pub(crate) const ROPE_REACH: f32 = 256.0;

/// Marks an exit point pushed only to end a segment that is then
/// restarted (a ray lying in a split plane visits both children).
const SKIP: u32 = NO_NODE - 1;

/// Whether `ray` misses, without a walk, a tree whose trace box
/// ([`super::KdInfo::trace_bounds`]) is `trace_box`: an invalid ray, or one
/// that misses the box. [`KdTree::intersect`] answers such a ray with
/// [`Hit::MISS`] and [`KdTree::occluded`] with false, counting only the
/// ray, by this same test (`trace_entry`); a C tracer asks it before it
/// rebuilds the tree's view (most of a missing ray's call).
#[inline(always)]
pub fn misses_trace_box(trace_box: &ClipBox, ray: &Ray) -> bool {
    trace_entry(trace_box, ray).is_none()
}

/// Where a walk of `ray` starts: its direction's [`crate::geom::inverse`]
/// and its segment `[t0, t1]` inside `trace_box` (the same bits as
/// [`KdTree::scene_segment`] of the prepared ray), or `None` for an invalid
/// ray or one that misses the box. Asked before the per-ray constants only
/// primitive tests need are computed: a ray that misses the scene's box
/// (the sky around it) costs its clip only.
#[inline(always)]
fn trace_entry(trace_box: &ClipBox, ray: &Ray) -> Option<(Vec3, f32, f32)> {
    if !ray.is_valid() {
        return None;
    }
    let inv = crate::geom::inverse(ray.dir);
    let (t0, t1) = trace_box.clip_ray(ray.origin, inv, ray.t_min, ray.t_max)?;
    Some((inv, t0, t1))
}

impl<'a> KdTree<'a> {
    /// Closest hit of `ray`, or [`Hit::MISS`], on the caller's `stack` of
    /// at least [`KD_STACK_LEN`] entries (rope traversal uses it only for
    /// rays that lie in a split plane). Adds its work to `stats`.
    ///
    /// # Panics
    /// When `stack` is shorter than [`KD_STACK_LEN`].
    #[inline(always)]
    pub fn intersect(
        &self,
        ray: &Ray,
        method: Traversal,
        stack: &mut [KdStackItem],
        stats: &mut TraceStats,
    ) -> Hit {
        check_stack(stack);
        stats.rays += 1;
        let Some((inv, t0, t1)) = trace_entry(&self.trace_box, ray) else {
            return Hit::MISS;
        };
        let mut v = Closest {
            ray: PreparedRay::with_inverse(ray, inv),
            best: Hit::MISS,
            tests: 0,
        };
        let mut steps = Steps::default();
        self.walk_by(method, &mut v, stack, t0, t1, &mut steps);
        steps.flush(stats);
        stats.prim_tests += v.tests;
        v.best
    }

    /// True when anything lies on `ray` within `[t_min, t_max]`; the stack
    /// as for [`KdTree::intersect`].
    ///
    /// # Panics
    /// When `stack` is shorter than [`KD_STACK_LEN`].
    #[inline(always)]
    pub fn occluded(
        &self,
        ray: &Ray,
        method: Traversal,
        stack: &mut [KdStackItem],
        stats: &mut TraceStats,
    ) -> bool {
        check_stack(stack);
        stats.rays += 1;
        let Some((inv, t0, t1)) = trace_entry(&self.trace_box, ray) else {
            return false;
        };
        let mut v = Any {
            ray: PreparedRay::with_inverse(ray, inv),
            hit: false,
            tests: 0,
        };
        let mut steps = Steps::default();
        self.walk_by(method, &mut v, stack, t0, t1, &mut steps);
        steps.flush(stats);
        stats.prim_tests += v.tests;
        v.hit
    }

    /// Node `i`, or [`KdNode::FAULT`] (a leaf no tree has) when `i` lies
    /// past the nodes: a corrupt tree ends a walk at a fault, never a panic.
    #[inline]
    pub(crate) fn node(&self, i: u32) -> KdNode {
        self.nodes.get(i as usize).copied().unwrap_or(KdNode::FAULT)
    }

    /// The box and ropes of leaf node `leaf` (the FAULT record, a NaN box
    /// no ray enters or leaves and no ropes, for a node without one).
    #[inline]
    pub(crate) fn rope(&self, leaf: u32) -> &super::KdRopes {
        self.rope_ids
            .get(leaf as usize)
            .and_then(|&r| self.ropes.get(r as usize))
            .unwrap_or(&super::node::FAULT_ROPES)
    }

    /// Whether node `leaf` is a leaf that holds no primitive (a missing one
    /// holds none).
    #[inline]
    pub(crate) fn leaf_is_empty(&self, leaf: u32) -> bool {
        self.leaf_refs(self.node(leaf)).is_none_or(|r| r.is_empty())
    }

    /// The primitive references of leaf node `nd`, or `None` when its
    /// reference range lies outside the tree (a fault).
    #[inline]
    pub(crate) fn leaf_refs(&self, nd: KdNode) -> Option<&[u32]> {
        self.refs
            .get(nd.first_ref() as usize..)?
            .get(..nd.ref_count() as usize)
    }

    /// The part of `r`'s segment inside the scene's box
    /// ([`super::KdInfo::trace_bounds`]): where every traversal starts and ends.
    #[inline]
    pub(crate) fn scene_segment(&self, r: &PreparedRay) -> Option<(f32, f32)> {
        self.trace_box
            .clip_ray(r.origin, r.inv_dir, r.t_min, r.t_max)
    }

    /// The walk `method` names for the ray prepared in `v`, over its
    /// segment `[t0, t1]` in the scene's box ([`trace_entry`]); true
    /// when the visitor stopped it.
    #[inline(always)]
    fn walk_by<V: LeafVisitor>(
        &self,
        method: Traversal,
        v: &mut V,
        stack: &mut [KdStackItem],
        t0: f32,
        t1: f32,
        steps: &mut Steps,
    ) -> bool {
        match method {
            Traversal::Hierarchical | Traversal::Packets => self.walk_root(v, stack, t0, t1, steps),
            Traversal::Ropes => self.walk_ropes_from(v, stack, t0, t1, steps),
        }
    }

    /// [`Self::walk_from`] the root over `[t0, t1]`, the ray's segment in
    /// the scene's box: the hierarchical walk of [`Self::intersect`] and
    /// [`Self::occluded`], kept out of their callers' ray loops (inlined
    /// into `intersect_many`, the walk's loop compiled 6% longer).
    #[inline(never)]
    fn walk_root<V: LeafVisitor>(
        &self,
        v: &mut V,
        stack: &mut [KdStackItem],
        t0: f32,
        t1: f32,
        steps: &mut Steps,
    ) -> bool {
        self.walk_from(v, &mut NoRecord, stack, 0, t0, t1, steps)
    }

    /// Hierarchical traversal from the root on the caller's stack; true
    /// when the visitor stopped it (or a fault did).
    pub(crate) fn walk_hierarchical<V: LeafVisitor, R: Recorder>(
        &self,
        v: &mut V,
        rec: &mut R,
        stack: &mut [KdStackItem],
        steps: &mut Steps,
    ) -> bool {
        self.scene_segment(v.ray())
            .is_some_and(|(t0, t1)| self.walk_from(v, rec, stack, 0, t0, t1, steps))
    }

    /// TA_B^rec over the subtree of `start`, for the ray's segment
    /// `[t0, t1]` inside that node's box, on the caller's `stack`. True when
    /// the visitor stopped it. A valid tree is walked visiting each node at
    /// most once and pushing at most two exit points per level; a walk that
    /// would visit more nodes than the tree has, or push past the stack,
    /// meets a broken tree: it stops with a fault.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    pub(crate) fn walk_from<V: LeafVisitor, R: Recorder>(
        &self,
        v: &mut V,
        rec: &mut R,
        stack: &mut [KdStackItem],
        start: u32,
        t0: f32,
        t1: f32,
        steps: &mut Steps,
    ) -> bool {
        // The counters live in registers during the walk; a compact tree's
        // walk is chosen here, once (its nodes need their children decoded).
        let mut counted = *steps;
        let stopped = if self.info.is_compact() {
            self.walk_counted::<V, R, true>(v, rec, stack, start, t0, t1, &mut counted)
        } else {
            self.walk_counted::<V, R, false>(v, rec, stack, start, t0, t1, &mut counted)
        };
        *steps = counted;
        stopped
    }

    /// [`KdTree::walk_from`] on counters it may keep in registers.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn walk_counted<V: LeafVisitor, R: Recorder, const COMPACT: bool>(
        &self,
        v: &mut V,
        rec: &mut R,
        stack: &mut [KdStackItem],
        start: u32,
        t0: f32,
        t1: f32,
        steps: &mut Steps,
    ) -> bool {
        let Some(stack) = stack.get_mut(..KD_STACK_LEN) else {
            steps.fault();
            return true;
        };
        let r = *v.ray();
        // The ray per axis as arrays of 4 (the node's axis, masked to 0..4,
        // indexes them without a bounds check or a branch per axis).
        let origin = r.origin.extend(0.0).to_array();
        let dir = r.dir.extend(0.0).to_array();
        let inv_dir = r.inv_dir.extend(0.0).to_array();
        let heads_up = [dir[0] > 0.0, dir[1] > 0.0, dir[2] > 0.0, false];
        stack[0] = KdStackItem {
            node: NO_NODE,
            t: t1,
        };
        let mut ex = 0usize;
        // The exit of the current segment: `stack[ex].t`, kept in a
        // register (it changes only where the stack does).
        let mut ex_t = t1;
        let mut en_t = t0;
        let mut node = start;
        // Every node visit spends one (interior steps are what leaves did
        // not spend: no counter of their own in the loop).
        let budget0 = self.nodes.len();
        let mut budget = budget0;
        // Leaf visits that spent from the budget.
        let mut leaf_visits = 0usize;
        // Segments lying in a split plane whose right side still waits: it
        // covers the same stretch of the ray as the left side being
        // walked, so a hit inside a left leaf is not the nearest yet.
        let mut in_plane = 0usize;
        let stopped = 'walk: loop {
            let mut nd = self.node(node);
            while !nd.is_leaf() {
                if budget == 0 {
                    steps.fault();
                    break 'walk true;
                }
                budget -= 1;
                let (a, s) = (nd.axis() & 3, nd.split());
                let (left, right) = children::<COMPACT>(nd);
                // Where the ray meets the plane: the segment [en_t, ex_t]
                // lies on one side of it, or crosses it there.
                // A ray parallel to the plane stays on its origin's side
                // (d = inf: the near side only), or lies in it (NaN).
                // `up`: the ray heads to the left child's side first.
                // (Children chosen by selects: computing them as `left +
                // offset` made the next node's load wait on the offset's
                // load, 7-9% slower on primary rays.)
                let (o, da) = (origin[a], dir[a]);
                let (d, up) = if da != 0.0 {
                    ((s - o) * inv_dir[a], heads_up[a])
                } else if o != s {
                    (f32::INFINITY, o < s)
                } else {
                    (f32::NAN, false)
                };
                let (near, far) = if up { (left, right) } else { (right, left) };
                let (near_only, far_only, both) = if up {
                    (Decision::Left, Decision::Right, Decision::LeftRight)
                } else {
                    (Decision::Right, Decision::Left, Decision::RightLeft)
                };
                // A plane met exactly at the segment's entry or exit is a
                // tie: both sides hold the point there (planar primitives
                // in the plane lie on one side only), so both are visited,
                // one of them over a segment of length zero.
                if d > ex_t {
                    rec.interior(node, near_only);
                    node = near;
                } else if d < en_t {
                    rec.interior(node, far_only);
                    node = far;
                } else {
                    // A push: the only place the stack grows, so the only
                    // place its bound is checked.
                    if ex >= KD_STACK_LEN - 2 {
                        steps.fault();
                        break 'walk true;
                    }
                    if d.is_nan() {
                        // The segment lies in the plane (0 * inf): left,
                        // then right again over the same segment.
                        rec.interior(node, Decision::LeftRight);
                        stack[ex + 1] = KdStackItem {
                            node: right,
                            t: en_t,
                        };
                        stack[ex + 2] = KdStackItem {
                            node: SKIP,
                            t: ex_t,
                        };
                        ex += 2;
                        in_plane += 1;
                        node = left;
                    } else {
                        rec.interior(node, both);
                        ex += 1;
                        stack[ex] = KdStackItem { node: far, t: d };
                        ex_t = d;
                        node = near;
                    }
                }
                nd = self.node(node);
            }
            steps.leaves += 1;
            rec.leaf(node);
            // The leaf read again (not `nd`): the descent above then loads a
            // node's second word only where it splits (one load a step less).
            let Some(refs) = self.leaf_refs(self.node(node)).filter(|_| budget > 0) else {
                steps.fault();
                break true;
            };
            budget -= 1;
            leaf_visits += 1;
            steps.empty += refs.is_empty() as u64;
            // No hit is final while a right side of the same segment waits.
            let exit = if in_plane == 0 {
                ex_t
            } else {
                f32::NEG_INFINITY
            };
            if v.visit(&self.scene, refs, exit) {
                // What is still on the stack was pushed and never visited.
                for e in stack[1..=ex].iter().rev() {
                    if e.node != SKIP {
                        rec.unvisited(e.node);
                    }
                }
                break true;
            }
            // Pop: the next segment starts where this one ended.
            loop {
                let e = stack[ex];
                if e.node == NO_NODE {
                    break 'walk false;
                }
                ex -= 1;
                en_t = e.t;
                if e.node != SKIP {
                    node = e.node;
                    ex_t = stack[ex].t;
                    break;
                }
                // The left side of an in-plane segment is done; its right
                // side comes off next.
                in_plane = in_plane.saturating_sub(1);
            }
        };
        steps.interior += (budget0 - budget - leaf_visits) as u64;
        stopped
    }

    /// Descends from `node` to the leaf node holding `p`. `None` when `p`
    /// lies on a split plane: both sides hold it, and a walk from one leaf
    /// could miss a hit at `p` in the other (the caller walks
    /// hierarchically instead, which visits both); [`NO_NODE`] (whose node
    /// is [`KdNode::FAULT`]) when the descent is deeper than any tree.
    #[inline]
    pub(crate) fn locate(&self, mut node: u32, p: Vec3, steps: &mut Steps) -> Option<u32> {
        for _ in 0..=KD_MAX_DEPTH {
            let nd = self.node(node);
            if nd.is_leaf() {
                return Some(node);
            }
            steps.interior += 1;
            // Trees with ropes store both children (never compact).
            let (a, s, (left, right)) = (nd.axis(), nd.split(), children::<false>(nd));
            node = if p[a] < s {
                left
            } else if p[a] > s {
                right
            } else {
                return None;
            };
        }
        Some(NO_NODE)
    }

    /// Descends from `node` to the leaf holding the ray's point at `t`,
    /// deciding each split by the ray parameter where the ray meets it
    /// (the comparison hierarchical traversal makes), not by the point's
    /// rounded coordinates: a point computed at a `t` before the origin
    /// can round onto a plane the ray only reaches later. `None` when the
    /// ray meets a plane exactly at `t` or lies in it (a tie that
    /// hierarchical traversal settles by visiting both sides).
    #[inline]
    pub(crate) fn locate_at(
        &self,
        mut node: u32,
        r: &PreparedRay,
        t: f32,
        steps: &mut Steps,
    ) -> Option<u32> {
        for _ in 0..=KD_MAX_DEPTH {
            let nd = self.node(node);
            if nd.is_leaf() {
                return Some(node);
            }
            steps.interior += 1;
            let (a, s, (left, right)) = (nd.axis(), nd.split(), children::<false>(nd));
            let (o, d) = (r.origin[a], r.dir[a]);
            let below = if d == 0.0 {
                if o == s {
                    return None;
                }
                o < s
            } else {
                let ts = (s - o) * r.inv_dir[a];
                // NaN: on the plane with a direction too small to invert.
                if ts == t || ts.is_nan() {
                    return None;
                }
                (d > 0.0) == (t < ts)
            };
            node = if below { left } else { right };
        }
        Some(NO_NODE)
    }

    /// Where the ray leaves leaf node `leaf`: the signed distance and the face.
    #[inline]
    pub(crate) fn leaf_exit(&self, r: &PreparedRay, leaf: u32) -> (f32, usize) {
        let (t_exit, face, _) = self.leaf_exit_at_edge(r, leaf);
        (t_exit, face)
    }

    /// [`KdTree::leaf_exit`], and whether the ray meets a face of another
    /// axis at the same distance: it leaves through an edge or a corner,
    /// where leaves the face's rope does not lead to hold the exit point
    /// too (hierarchical traversal visits them all, over segments of
    /// length zero; a rope walk cannot, and walks hierarchically instead).
    #[inline]
    pub(crate) fn leaf_exit_at_edge(&self, r: &PreparedRay, leaf: u32) -> (f32, usize, bool) {
        let rp = self.rope(leaf);
        let mut ts = [f32::INFINITY; 3];
        let mut t_exit = f32::INFINITY;
        let mut face = 0;
        for (a, ta) in ts.iter_mut().enumerate() {
            // Selects, not branches: the ray's signs are the same at every leaf.
            let up = r.dir[a] > 0.0;
            let bound = if up { rp.max[a] } else { rp.min[a] };
            let t = (bound - r.origin[a]) * r.inv_dir[a];
            // A ray parallel to the axis never leaves through its faces.
            *ta = if r.dir[a] == 0.0 { f32::INFINITY } else { t };
            if *ta < t_exit {
                t_exit = *ta;
                face = 2 * a + up as usize;
            }
        }
        let [x, y, z] = ts.map(|t| t <= t_exit);
        (t_exit, face, (x & y) | (x & z) | (y & z))
    }

    /// The leaf node beyond face `face` of leaf node `leaf` where the ray
    /// goes on after `t_exit`: `Ok(None)` at the scene's boundary, `Err(())`
    /// when the ray lies in a split plane there.
    #[inline]
    pub(crate) fn rope_next(
        &self,
        r: &PreparedRay,
        leaf: u32,
        t_exit: f32,
        face: usize,
        steps: &mut Steps,
    ) -> Result<Option<u32>, ()> {
        let rp = self.rope(leaf);
        let next = rp.neighbor[face];
        if next == NO_NODE {
            return Ok(None);
        }
        let p = rp.onto_face(face, r.at(t_exit));
        self.locate(next, p, steps).map(Some).ok_or(())
    }

    /// Leaf to leaf by ropes from leaf node `first` (not yet visited) until
    /// the visitor stops or the segment ends at `t1`.
    pub(crate) fn rope_walk<V: LeafVisitor>(
        &self,
        v: &mut V,
        first: u32,
        t1: f32,
        steps: &mut Steps,
    ) -> RopeEnd {
        let r = *v.ray();
        self.rope_walk_by(v, first, t1, steps, |leaf, t_exit, face, steps| {
            self.rope_next(&r, leaf, t_exit, face, steps)
        })
    }

    /// [`KdTree::rope_walk`] with its step across a face given: `next(leaf,
    /// t_exit, face, steps)` is the leaf node beyond, as
    /// [`KdTree::rope_next`] answers (guided ropes guess it first). A walk
    /// crosses each leaf at most once: one that crosses more leaves than the
    /// tree has, or meets a leaf outside the tree, stops with a fault.
    #[inline]
    pub(crate) fn rope_walk_by<V: LeafVisitor>(
        &self,
        v: &mut V,
        first: u32,
        t1: f32,
        steps: &mut Steps,
        mut next: impl FnMut(u32, f32, usize, &mut Steps) -> Result<Option<u32>, ()>,
    ) -> RopeEnd {
        let r = *v.ray();
        let mut leaf = first;
        for _ in 0..self.ropes.len() {
            steps.leaves += 1;
            let Some(refs) = self.leaf_refs(self.node(leaf)) else {
                break;
            };
            steps.empty += refs.is_empty() as u64;
            let (t_exit, face, at_edge) = self.leaf_exit_at_edge(&r, leaf);
            if v.visit(&self.scene, refs, t_exit.min(t1)) {
                return RopeEnd::Stopped;
            }
            if t_exit > t1 {
                return RopeEnd::Exited;
            }
            if at_edge {
                return RopeEnd::Fallback;
            }
            match next(leaf, t_exit, face, steps) {
                Ok(Some(n)) => leaf = n,
                Ok(None) => return RopeEnd::Exited,
                Err(()) => return RopeEnd::Fallback,
            }
        }
        steps.fault();
        RopeEnd::Stopped
    }

    /// Whether points of `r` between `t0` and `t1` are computed precisely
    /// enough for rope steps, which find leaves by points on the ray: the
    /// origin and the distance travelled within [`ROPE_REACH`] times the
    /// scene's coordinate scale keep a point's rounding (a few ulps of
    /// that size) below 2^-15 of the scene, far under the thinnest cells a
    /// build makes ([`crate::tolerance::FACE_CELL`]). A ray from farther
    /// away (found by the C-ABI fuzzer: an origin 10^22 from a scene of
    /// size 8) is traversed hierarchically, by ray parameters alone.
    #[inline]
    fn points_precise(&self, r: &PreparedRay, t0: f32, t1: f32) -> bool {
        let b = self.info.bounds();
        let scale = b
            .min
            .abs()
            .max(b.max.abs())
            .max(b.max - b.min)
            .max_element();
        let reach = r
            .origin
            .abs()
            .max(r.dir.abs() * t0.abs().max(t1.abs()))
            .max_element();
        reach <= scale * ROPE_REACH
    }

    /// Rope traversal of the ray's segment `[t0, t1]` inside the scene's
    /// box ([`Self::scene_segment`]); true when the visitor stopped it.
    fn walk_ropes_from<V: LeafVisitor>(
        &self,
        v: &mut V,
        stack: &mut [KdStackItem],
        t0: f32,
        t1: f32,
        steps: &mut Steps,
    ) -> bool {
        let r = *v.ray();
        // A tree built without ropes, and a ray whose points are too far
        // out for exact exits, walk hierarchically: the same hits.
        if !self.info.has_ropes() || !self.points_precise(&r, t0, t1) {
            return self.walk_from(v, &mut NoRecord, stack, 0, t0, t1, steps);
        }
        let end = match self.locate_at(0, &r, t0, steps) {
            Some(first) => self.rope_walk(v, first, t1, steps),
            None => RopeEnd::Fallback,
        };
        match end {
            RopeEnd::Stopped => true,
            RopeEnd::Exited => false,
            RopeEnd::Fallback => self.walk_hierarchical(v, &mut NoRecord, stack, steps),
        }
    }
}

/// An interior node's children: in a compact tree an elided one as the
/// shared empty leaf ([`KdNode::children`]), elsewhere the stored pair.
#[inline(always)]
pub(crate) fn children<const COMPACT: bool>(nd: KdNode) -> (u32, u32) {
    if COMPACT {
        nd.children()
    } else {
        let left = nd.left();
        (left, left.wrapping_add(1))
    }
}

/// The traversal stack every kd trace takes: at least [`KD_STACK_LEN`].
#[inline]
fn check_stack(stack: &[KdStackItem]) {
    assert!(
        stack.len() >= KD_STACK_LEN,
        "kd traversal stack of {} entries: needs KD_STACK_LEN = {KD_STACK_LEN}",
        stack.len()
    );
}
