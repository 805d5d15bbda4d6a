//! Closest-hit and any-hit traversal: one slab test of a node's eight
//! boxes at once, entries hit pushed nearest last (closest hit) so the
//! nearest is visited first, each leaf's triangles tested four at a time
//! from its blocks and its spheres and cones one at a time, with the
//! kd-tree's tests and tie rule, so the hits are the kd-tree's bit for bit.
//!
//! What a walk does is chosen once per ray, outside the loop: the box
//! test (rays whose inverse direction is finite read each axis' near and
//! far face by the direction's sign; the others, a zero component or a
//! subnormal one whose inverse overflows, decide those axes by the origin,
//! on a face counting as inside, as the kd-tree's clip does, since `0 *
//! inf` would be NaN on a face), whether leaves may hold spheres and
//! cones, and whether the walk reads ahead the entries it leaves on the
//! stack ([`WideBvh::with_read_ahead`]).
//!
//! Every kernel is compiled for the target's baseline and, on x86-64, once
//! more with AVX2 ([`WideBvh::intersect_avx2`]): the same operations in
//! the same order, so the same answers, one vector instruction per node
//! plane.

use super::block::{LeafBlock, BLOCK_SLOTS, NO_PRIM};
use super::node::{leaf_run, WideNode, EMPTY_SLOT, LEAF_BIT, LOWER, UPPER, WIDTH};
use super::WideBvh;
use crate::geom::leaf::beats;
use crate::geom::{intersect_triangles4, Hit, PreparedRay, Ray, GEOM_TRIANGLES};
use crate::tolerance::BOX_FAR_SLACK;
use crate::TraceStats;

/// A traversal stack entry: a node's entry (an interior child, or a leaf's
/// run of blocks) whose box the ray enters at `t`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub struct WideStackItem {
    /// [`WideNode::child`] of the entry.
    pub child: u32,
    /// Entry distance into its box.
    pub t: f32,
}

/// What a walk does at a leaf and how far a box may lie.
trait Query {
    /// Entries are pushed nearest last when true (closest hit).
    const SORTED: bool;
    /// Boxes entered beyond this are skipped.
    fn limit(&self) -> f32;
    /// Tests the primitives of blocks `[first, first + count)` of `w`
    /// (`OTHERS`: the scene has spheres or cones); `Some(true)` stops the
    /// walk, `None` is a block past the hierarchy's.
    fn visit<const OTHERS: bool>(
        &mut self,
        w: &WideBvh,
        r: &PreparedRay,
        first: usize,
        count: usize,
    ) -> Option<bool>;
}

/// The blocks `[first, first + count)` of `w`, or `None` past them.
#[inline(always)]
fn blocks_of<'a>(w: &WideBvh<'a>, first: usize, count: usize) -> Option<&'a [LeafBlock]> {
    w.blocks.get(first..first.checked_add(count)?)
}

/// Slots of `b` that hold a sphere or a cone (a primitive past the
/// scene's `triangles`).
#[inline(always)]
fn other_slots(b: &LeafBlock, triangles: usize) -> u32 {
    let mut m = 0;
    for (i, &p) in b.prims.iter().enumerate() {
        m |= ((p != NO_PRIM && p as usize >= triangles) as u32) << i;
    }
    m
}

/// The set bits of `mask`, lowest first.
#[inline(always)]
fn bits(mut mask: u32) -> impl Iterator<Item = usize> {
    core::iter::from_fn(move || {
        (mask != 0).then(|| {
            let i = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            i
        })
    })
}

struct Closest {
    best: Hit,
    /// Block and slot of the best hit when a block's four-lane test found
    /// it: its normal is made from the block's corners once, at the end.
    from_block: Option<(usize, usize)>,
    /// The ray's end until something is hit, then the best hit's `t`.
    limit: f32,
    tests: u64,
}

impl Closest {
    /// Keeps `h` when it beats the best so far.
    #[inline(always)]
    fn offer(&mut self, h: Hit, at: Option<(usize, usize)>) {
        if beats(&h, &self.best) {
            self.best = h;
            self.from_block = at;
            self.limit = h.t;
        }
    }

    /// The best hit, its normal made when a block found it.
    fn finish(mut self, w: &WideBvh) -> Hit {
        if let Some((b, slot)) = self.from_block {
            self.best.ng = w.blocks[b].normal(slot);
        }
        self.best
    }
}

impl Query for Closest {
    const SORTED: bool = true;
    #[inline(always)]
    fn limit(&self) -> f32 {
        self.limit
    }
    #[inline(always)]
    fn visit<const OTHERS: bool>(
        &mut self,
        w: &WideBvh,
        r: &PreparedRay,
        first: usize,
        count: usize,
    ) -> Option<bool> {
        let blocks = blocks_of(w, first, count)?;
        let nt = w.scene.triangles.len();
        for (j, b) in blocks.iter().enumerate() {
            self.tests += b.prims.iter().filter(|&&p| p != NO_PRIM).count() as u64;
            let h4 = intersect_triangles4(r, &b.corners, self.limit);
            for slot in bits(h4.hit) {
                let h = Hit {
                    t: h4.t[slot],
                    u: h4.u[slot],
                    v: h4.v[slot],
                    ng: crate::Vec3::ZERO,
                    geom_id: GEOM_TRIANGLES,
                    prim_id: b.prims[slot],
                };
                self.offer(h, Some((first + j, slot)));
            }
            // Slots on an edge in single precision, and spheres and cones:
            // one at a time by the scene's own test.
            let mut alone = h4.edge;
            if OTHERS {
                alone |= other_slots(b, nt);
            }
            for slot in bits(alone) {
                let p = b.prims[slot];
                if p == NO_PRIM {
                    continue;
                }
                if let Some(h) = w.scene.intersect_prim(p as usize, r, self.limit) {
                    self.offer(h, None);
                }
            }
        }
        Some(false)
    }
}

struct Any {
    t_max: f32,
    tests: u64,
}

impl Query for Any {
    const SORTED: bool = false;
    #[inline(always)]
    fn limit(&self) -> f32 {
        self.t_max
    }
    #[inline(always)]
    fn visit<const OTHERS: bool>(
        &mut self,
        w: &WideBvh,
        r: &PreparedRay,
        first: usize,
        count: usize,
    ) -> Option<bool> {
        let blocks = blocks_of(w, first, count)?;
        let nt = w.scene.triangles.len();
        for b in blocks {
            self.tests += b.prims.iter().filter(|&&p| p != NO_PRIM).count() as u64;
            let h4 = intersect_triangles4(r, &b.corners, self.t_max);
            if h4.hit != 0 {
                return Some(true);
            }
            let mut alone = h4.edge;
            if OTHERS {
                alone |= other_slots(b, nt);
            }
            for slot in bits(alone) {
                let p = b.prims[slot];
                if p != NO_PRIM && w.scene.intersect_prim(p as usize, r, self.t_max).is_some() {
                    return Some(true);
                }
            }
        }
        Some(false)
    }
}

/// The ray as the slab test reads it.
struct Slabs {
    origin: [f32; 3],
    inv_dir: [f32; 3],
    /// Per axis, the row of [`WideNode::planes`] the ray meets first (the
    /// lower face when it moves up the axis) and last.
    near: [usize; 3],
    far: [usize; 3],
    /// Axes the ray is taken as parallel to: those whose inverse direction
    /// is infinite, as the kd-tree's clip takes them (`Aabb::clip_ray`).
    parallel: [bool; 3],
}

impl Slabs {
    fn new(r: &PreparedRay) -> Slabs {
        let inv_dir = r.inv_dir.to_array();
        let down = inv_dir.map(|i| i < 0.0);
        Slabs {
            origin: r.origin.to_array(),
            inv_dir,
            near: [0, 1, 2].map(|a| if down[a] { UPPER + a } else { LOWER + a }),
            far: [0, 1, 2].map(|a| if down[a] { LOWER + a } else { UPPER + a }),
            // A zero component, or one so small that its inverse
            // overflows: `(face - origin) * inf` is NaN on a face.
            parallel: inv_dir.map(f32::is_infinite),
        }
    }

    /// The slots of `n` whose boxes the ray enters within `[t0, t1]`, and
    /// each slot's entry distance. `PARALLEL`: some axis' inverse
    /// direction is infinite. An empty slot's box (+inf lower, -inf upper)
    /// is never entered.
    #[inline(always)]
    fn test<const PARALLEL: bool>(&self, n: &WideNode, t0: f32, t1: f32) -> (u32, [f32; WIDTH]) {
        let mut tn = [t0; WIDTH];
        let mut tf = [f32::INFINITY; WIDTH];
        for a in 0..3 {
            let (o, inv) = (self.origin[a], self.inv_dir[a]);
            if PARALLEL && self.parallel[a] {
                let (lo, hi) = (&n.planes[LOWER + a], &n.planes[UPPER + a]);
                for i in 0..WIDTH {
                    if !(o >= lo[i] && o <= hi[i]) {
                        tn[i] = f32::INFINITY;
                        tf[i] = f32::NEG_INFINITY;
                    }
                }
                continue;
            }
            let (near, far) = (&n.planes[self.near[a]], &n.planes[self.far[a]]);
            for i in 0..WIDTH {
                tn[i] = fmax((near[i] - o) * inv, tn[i]);
                tf[i] = fmin((far[i] - o) * inv, tf[i]);
            }
        }
        let mut hit = 0u32;
        for i in 0..WIDTH {
            hit |= ((tn[i] <= fmin(tf[i] * BOX_FAR_SLACK, t1)) as u32) << i;
        }
        (hit, tn)
    }
}

/// `a < b ? a : b`: one `minps` lane (the second operand when either is NaN).
#[inline(always)]
fn fmin(a: f32, b: f32) -> f32 {
    if a < b {
        a
    } else {
        b
    }
}

/// `a > b ? a : b`: one `maxps` lane (the second operand when either is NaN).
#[inline(always)]
fn fmax(a: f32, b: f32) -> f32 {
    if a > b {
        a
    } else {
        b
    }
}

impl WideBvh<'_> {
    /// Closest hit of `ray`, on the caller's `stack` of at least
    /// [`WideBvh::stack_len`] entries (a shorter one stops the walk with
    /// a fault counted in `stats`).
    #[inline]
    pub fn intersect(&self, ray: &Ray, stack: &mut [WideStackItem], stats: &mut TraceStats) -> Hit {
        self.closest(ray, stack, stats)
    }

    /// Whether anything lies on `ray`'s segment; the stack as for
    /// [`WideBvh::intersect`].
    #[inline]
    pub fn occluded(&self, ray: &Ray, stack: &mut [WideStackItem], stats: &mut TraceStats) -> bool {
        self.any(ray, stack, stats)
    }

    #[inline(always)]
    fn closest(&self, ray: &Ray, stack: &mut [WideStackItem], stats: &mut TraceStats) -> Hit {
        stats.rays += 1;
        if !ray.is_valid() {
            return Hit::MISS;
        }
        let r = PreparedRay::new(ray);
        let mut q = Closest {
            best: Hit::MISS,
            from_block: None,
            limit: r.t_max,
            tests: 0,
        };
        self.walk(&r, &mut q, stack, stats);
        stats.prim_tests += q.tests;
        q.finish(self)
    }

    #[inline(always)]
    fn any(&self, ray: &Ray, stack: &mut [WideStackItem], stats: &mut TraceStats) -> bool {
        stats.rays += 1;
        if !ray.is_valid() {
            return false;
        }
        let r = PreparedRay::new(ray);
        let mut q = Any {
            t_max: r.t_max,
            tests: 0,
        };
        let hit = self.walk(&r, &mut q, stack, stats);
        stats.prim_tests += q.tests;
        hit
    }

    /// The box test, the leaf test and the read-ahead chosen once for the
    /// ray, then the walk; true when a leaf stopped it.
    #[inline(always)]
    fn walk<Q: Query>(
        &self,
        r: &PreparedRay,
        q: &mut Q,
        stack: &mut [WideStackItem],
        stats: &mut TraceStats,
    ) -> bool {
        let slabs = Slabs::new(r);
        let others = !(self.scene.spheres.is_empty() && self.scene.cones.is_empty());
        // Rays with a parallel axis are rare, and so are scenes of
        // spheres and cones among meshes: those walks do not read ahead
        // (fewer copies of the walk).
        match (slabs.parallel.iter().any(|&p| p), others, self.read_ahead) {
            (true, _, _) => self.walk_with::<Q, true, true, false>(r, &slabs, q, stack, stats),
            (false, true, _) => self.walk_with::<Q, false, true, false>(r, &slabs, q, stack, stats),
            (false, false, false) => {
                self.walk_with::<Q, false, false, false>(r, &slabs, q, stack, stats)
            }
            (false, false, true) => {
                self.walk_with::<Q, false, false, true>(r, &slabs, q, stack, stats)
            }
        }
    }

    /// Every entry popped costs one from a budget of what a valid tree can
    /// hold, so corrupt indices end in a fault, never a hang. `OTHERS`:
    /// leaves may hold spheres and cones. `READ_AHEAD`: the entries
    /// pushed are read ahead ([`read_entry_ahead`]). True when a leaf
    /// stopped the walk.
    #[inline(always)]
    fn walk_with<Q: Query, const PARALLEL: bool, const OTHERS: bool, const READ_AHEAD: bool>(
        &self,
        r: &PreparedRay,
        slabs: &Slabs,
        q: &mut Q,
        stack: &mut [WideStackItem],
        stats: &mut TraceStats,
    ) -> bool {
        if stack.is_empty() {
            stats.faults += 1;
            return false;
        }
        let mut sp = 0usize;
        let mut budget = self.nodes.len().saturating_mul(WIDTH + 1);
        let (mut interior, mut leaves, mut boxes, mut faults) = (0u64, 0u64, 0u64, 0u64);
        let mut stopped = false;
        let mut touch = 0u32;
        // The entry walked now: the nearest one a node sent the ray on
        // to, or the top of the stack.
        let mut it = WideStackItem {
            child: 0,
            t: r.t_min,
        };
        'walk: loop {
            if budget == 0 {
                faults += 1;
                break;
            }
            budget -= 1;
            if it.child & LEAF_BIT != 0 {
                leaves += 1;
                let (first, count) = leaf_run(it.child);
                match q.visit::<OTHERS>(self, r, first, count) {
                    Some(false) => {}
                    Some(true) => {
                        stopped = true;
                        break;
                    }
                    None => {
                        faults += 1;
                        break;
                    }
                }
            } else {
                let Some(n) = self.nodes.get(it.child as usize) else {
                    faults += 1;
                    break;
                };
                interior += 1;
                let (mut hit, tn) = slabs.test::<PARALLEL>(n, r.t_min, q.limit());
                let mut used = 0u32;
                for i in 0..WIDTH {
                    used |= ((n.child[i] != EMPTY_SLOT) as u32) << i;
                }
                boxes += used.count_ones() as u64;
                hit &= used;
                let item = |i: usize| WideStackItem {
                    child: n.child[i],
                    t: tn[i],
                };
                if hit != 0 {
                    let first = hit.trailing_zeros() as usize;
                    hit &= hit - 1;
                    if hit == 0 {
                        // One entry entered: walk it next.
                        it = item(first);
                        continue;
                    }
                    if sp + WIDTH > stack.len() {
                        faults += 1;
                        break;
                    }
                    // Every entry entered onto the stack (closest hit:
                    // sorted far to near), then the nearest taken back.
                    let base = sp;
                    for i in core::iter::once(first).chain(bits(hit)) {
                        if READ_AHEAD {
                            read_entry_ahead(self, n.child[i], &mut touch);
                        }
                        let e = item(i);
                        let mut k = sp;
                        if Q::SORTED {
                            while k > base && stack[k - 1].t < e.t {
                                stack[k] = stack[k - 1];
                                k -= 1;
                            }
                        }
                        stack[k] = e;
                        sp += 1;
                    }
                    sp -= 1;
                    it = stack[sp];
                    continue;
                }
            }
            // Back to the nearest entry waiting that still lies within
            // reach.
            while sp > 0 {
                sp -= 1;
                if stack[sp].t <= q.limit() {
                    it = stack[sp];
                    continue 'walk;
                }
            }
            break;
        }
        core::hint::black_box(touch);
        stats.traversal_steps += interior + leaves;
        stats.interior_steps += interior;
        stats.leaf_steps += leaves;
        stats.box_tests += boxes;
        stats.faults += (faults > 0) as u64;
        stopped
    }
}

/// Bytes of nodes and blocks above which a hierarchy's walks read ahead by
/// default ([`WideBvh::with_read_ahead`]).
///
/// On x86-64 (with SSE: all but the soft-float targets) a read-ahead is a
/// prefetch instruction, which costs a small hierarchy nothing measured,
/// and every hierarchy reads ahead.
#[cfg(all(target_arch = "x86_64", target_feature = "sse"))]
pub const READ_AHEAD_BYTES: usize = 0;

/// Bytes of nodes and blocks above which a hierarchy's walks read ahead by
/// default ([`WideBvh::with_read_ahead`]).
///
/// Elsewhere a read-ahead is a load (below), which pays beyond a typical
/// per-core L2 cache (2 MiB) and not within it.
#[cfg(not(all(target_arch = "x86_64", target_feature = "sse")))]
pub const READ_AHEAD_BYTES: usize = 2 << 20;

/// Whether walks over `nodes` and `blocks` read ahead by default: they
/// span more than [`READ_AHEAD_BYTES`].
pub(crate) fn reads_ahead(nodes: &[WideNode], blocks: &[LeafBlock]) -> bool {
    size_of_val(nodes) + size_of_val(blocks) > READ_AHEAD_BYTES
}

/// Starts loading every cache line of what an entry names (an interior
/// child's node, a leaf's first block) when the entry goes to the stack,
/// so that its lines are on their way while the nearest entry is walked.
/// A hint: what it reads changes no answer, and an index past its slice
/// reads nothing. A 16-aligned node (224 bytes) spans four or five lines,
/// a block (160 bytes) three or four: one word at bytes 0, 64, 128 and
/// the last of each.
#[inline(always)]
pub(super) fn read_entry_ahead(w: &WideBvh, child: u32, touch: &mut u32) {
    if child & LEAF_BIT == 0 {
        if let Some(n) = w.nodes.get(child as usize) {
            for row in [0, 2, 4] {
                line_ahead(n.planes[row][0].to_bits(), &n.planes[row][0], touch);
            }
            line_ahead(n.child[WIDTH - 1], &n.child[WIDTH - 1], touch);
        }
    } else if let Some(b) = w.blocks.get(leaf_run(child).0) {
        line_ahead(b.corners[0][0][0].to_bits(), &b.corners[0][0][0], touch);
        line_ahead(b.corners[1][1][0].to_bits(), &b.corners[1][1][0], touch);
        line_ahead(b.corners[2][2][0].to_bits(), &b.corners[2][2][0], touch);
        line_ahead(b.prims[BLOCK_SLOTS - 1], &b.prims[BLOCK_SLOTS - 1], touch);
    }
}

/// Starts loading the cache line that holds `word`: on x86-64 a
/// `prefetcht0` (`safe_arch`'s safe wrapper of `_mm_prefetch`; the core
/// itself holds no `unsafe`), which waits for nothing and leaves `bits`
/// unread; elsewhere the load of `bits`, folded into `touch`, which the walk
/// hands to `black_box` so that the load stays.
#[inline(always)]
fn line_ahead<T>(bits: u32, word: &T, touch: &mut u32) {
    #[cfg(all(target_arch = "x86_64", target_feature = "sse"))]
    {
        let _ = (bits, touch);
        safe_arch::prefetch_t0(word);
    }
    #[cfg(not(all(target_arch = "x86_64", target_feature = "sse")))]
    {
        let _ = word;
        *touch ^= bits;
    }
}
