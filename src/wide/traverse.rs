//! Closest-hit and any-hit traversal: one slab test of a node's four boxes
//! at once, entries hit pushed nearest last (closest hit) so the nearest
//! is visited first, each leaf's triangles tested four at a time from its
//! corner blocks and its spheres and cones one at a time, with the
//! kd-tree's tests and tie rule, so the hits are the kd-tree's bit for bit.
//!
//! The box test is chosen once per ray: rays whose inverse direction is
//! finite take the plain slab test; the others (a zero component, or a
//! subnormal one whose inverse overflows) take one that decides those
//! axes by the origin (on a face counts as inside), as the kd-tree's clip
//! does, since `0 * inf` would be NaN on a face. Whether a walk reads
//! ahead the entries it leaves on the stack is the hierarchy's
//! ([`WideBvh::with_read_ahead`]), also chosen once per ray.

use super::node::{WideNode, EMPTY_SLOT, LEAF_BIT, WIDTH};
use super::WideBvh;
use crate::bvh::traverse::{push_nearest_last, Entered};
use crate::geom::{leaf, Corners4, Hit, PreparedRay, Ray, TRI_LANES};
use crate::TraceStats;

/// A traversal stack entry: a node's entry (an interior child, or a leaf's
/// run of references) whose box the ray enters at `t`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub struct WideStackItem {
    /// [`WideNode::child`] of the entry.
    pub child: u32,
    /// [`WideNode::count`] of the entry.
    pub count: u32,
    /// Entry distance into its box.
    pub t: f32,
}

/// Slack on the far distance so that rounding never loses a box the ray
/// touches (Ize 2013: `1 + 2 gamma(3)`), as the binary hierarchies use.
const FAR_SLACK: f32 = 1.0 + 4.0 * f32::EPSILON;

/// What a walk does at a leaf and how far a box may lie.
trait Query {
    /// Entries are pushed nearest last when true (closest hit).
    const SORTED: bool;
    /// Boxes entered beyond this are skipped.
    fn limit(&self) -> f32;
    /// Tests the primitives of reference slots `[first, first + count)`
    /// of `w` (`others`: the scene has spheres or cones); `Some(true)`
    /// stops the walk, `None` is a slot past the hierarchy's slices.
    fn visit(
        &mut self,
        w: &WideBvh,
        r: &PreparedRay,
        run: (usize, usize),
        others: bool,
    ) -> Option<bool>;
}

struct Closest {
    best: Hit,
    /// The ray's end until something is hit, then the best hit's `t`
    /// (kept, not chosen at every box and test).
    limit: f32,
    tests: u64,
}

impl Query for Closest {
    const SORTED: bool = true;
    #[inline(always)]
    fn limit(&self) -> f32 {
        self.limit
    }
    #[inline(always)]
    fn visit(
        &mut self,
        w: &WideBvh,
        r: &PreparedRay,
        run: (usize, usize),
        others: bool,
    ) -> Option<bool> {
        self.tests += run.1 as u64;
        let (scene, refs, blocks) = (&w.scene, w.refs, w.corners);
        let whole = leaf::closest_in_blocks(scene, r, refs, blocks, run, others, &mut self.best);
        if self.best.is_hit() {
            self.limit = self.best.t;
        }
        whole.then_some(false)
    }
}

struct Any {
    hit: bool,
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
    fn visit(
        &mut self,
        w: &WideBvh,
        r: &PreparedRay,
        run: (usize, usize),
        others: bool,
    ) -> Option<bool> {
        self.tests += run.1 as u64;
        let (scene, refs, blocks) = (&w.scene, w.refs, w.corners);
        self.hit = leaf::any_in_blocks(scene, r, refs, blocks, run, others, self.t_max)?;
        Some(self.hit)
    }
}

/// The ray as the slab test reads it.
struct Slabs {
    origin: [f32; 3],
    inv_dir: [f32; 3],
    /// Axes the ray is taken as parallel to: those whose inverse direction
    /// is infinite, as the kd-tree's clip takes them (`Aabb::clip_ray`).
    parallel: [bool; 3],
}

impl Slabs {
    fn new(r: &PreparedRay) -> Slabs {
        Slabs {
            origin: r.origin.to_array(),
            inv_dir: r.inv_dir.to_array(),
            // A zero component, or one so small that its inverse
            // overflows: `(face - origin) * inf` is NaN on a face.
            parallel: r.inv_dir.to_array().map(f32::is_infinite),
        }
    }

    /// Entry and exit distances of the four boxes of `n`, clipped to
    /// `[t0, t1]`: a box is hit when entry <= exit. `PARALLEL`: some axis
    /// has a zero direction.
    #[inline(always)]
    fn test<const PARALLEL: bool>(
        &self,
        n: &WideNode,
        t0: f32,
        t1: f32,
    ) -> ([f32; WIDTH], [f32; WIDTH]) {
        let (mut tn, mut tf) = ([t0; WIDTH], [t1; WIDTH]);
        for a in 0..3 {
            let (o, inv) = (self.origin[a], self.inv_dir[a]);
            for i in 0..WIDTH {
                let (near, far) = if PARALLEL && self.parallel[a] {
                    if o >= n.min[a][i] && o <= n.max[a][i] {
                        (f32::NEG_INFINITY, f32::INFINITY)
                    } else {
                        (f32::INFINITY, f32::NEG_INFINITY)
                    }
                } else {
                    let l = (n.min[a][i] - o) * inv;
                    let h = (n.max[a][i] - o) * inv;
                    (fmin(l, h), fmax(l, h))
                };
                tn[i] = fmax(near, tn[i]);
                tf[i] = fmin(far * FAR_SLACK, tf[i]);
            }
        }
        (tn, tf)
    }
}

impl Entered for WideStackItem {
    #[inline(always)]
    fn t(&self) -> f32 {
        self.t
    }
}

impl WideBvh<'_> {
    /// Closest hit of `ray`, on the caller's `stack` of at least
    /// [`WideBvh::stack_len`] entries (a shorter one stops the walk with
    /// a fault counted in `stats`).
    pub fn intersect(&self, ray: &Ray, stack: &mut [WideStackItem], stats: &mut TraceStats) -> Hit {
        stats.rays += 1;
        if !ray.is_valid() {
            return Hit::MISS;
        }
        let r = PreparedRay::new(ray);
        let mut q = Closest {
            best: Hit::MISS,
            limit: r.t_max,
            tests: 0,
        };
        self.walk(&r, &mut q, stack, stats);
        stats.prim_tests += q.tests;
        q.best
    }

    /// Whether anything lies on `ray`'s segment; the stack as for
    /// [`WideBvh::intersect`].
    pub fn occluded(&self, ray: &Ray, stack: &mut [WideStackItem], stats: &mut TraceStats) -> bool {
        stats.rays += 1;
        if !ray.is_valid() {
            return false;
        }
        let r = PreparedRay::new(ray);
        let mut q = Any {
            hit: false,
            t_max: r.t_max,
            tests: 0,
        };
        self.walk(&r, &mut q, stack, stats);
        stats.prim_tests += q.tests;
        q.hit
    }

    /// The box test and the read-ahead chosen once for the ray, then the
    /// walk.
    #[inline(always)]
    fn walk<Q: Query>(
        &self,
        r: &PreparedRay,
        q: &mut Q,
        stack: &mut [WideStackItem],
        stats: &mut TraceStats,
    ) {
        let slabs = Slabs::new(r);
        // Rays with a parallel axis are rare: they walk without reading
        // ahead (one copy of the walk fewer).
        match (slabs.parallel.iter().any(|&p| p), self.read_ahead) {
            (true, _) => self.walk_with::<Q, true, false>(r, &slabs, q, stack, stats),
            (false, false) => self.walk_with::<Q, false, false>(r, &slabs, q, stack, stats),
            (false, true) => self.walk_with::<Q, false, true>(r, &slabs, q, stack, stats),
        }
    }

    /// Every entry popped costs one from a budget of what a valid tree
    /// can hold, so corrupt indices end in a fault, never a hang. `READ_AHEAD`:
    /// the entries pushed are read ahead ([`read_entry_ahead`]).
    #[inline(always)]
    fn walk_with<Q: Query, const PARALLEL: bool, const READ_AHEAD: bool>(
        &self,
        r: &PreparedRay,
        slabs: &Slabs,
        q: &mut Q,
        stack: &mut [WideStackItem],
        stats: &mut TraceStats,
    ) {
        let Some(first) = stack.first_mut() else {
            stats.faults += 1;
            return;
        };
        *first = WideStackItem {
            child: 0,
            count: 0,
            t: r.t_min,
        };
        let mut sp = 1;
        let mut budget = self.nodes.len().saturating_mul(WIDTH + 1);
        let (mut interior, mut leaves, mut boxes, mut faults) = (0u64, 0u64, 0u64, 0u64);
        // The nearest entry a node pushed is visited next without going
        // through the stack (and a lone one is never written to it).
        let mut next: Option<WideStackItem> = None;
        let mut touch = 0u32;
        let others = !(self.scene.spheres.is_empty() && self.scene.cones.is_empty());
        loop {
            let it = match next.take() {
                Some(it) => it,
                None => {
                    if sp == 0 {
                        break;
                    }
                    sp -= 1;
                    let it = stack[sp];
                    if it.t > q.limit() {
                        continue;
                    }
                    it
                }
            };
            if budget == 0 {
                faults += 1;
                break;
            }
            budget -= 1;
            if it.child & LEAF_BIT != 0 {
                leaves += 1;
                let run = ((it.child & !LEAF_BIT) as usize, it.count as usize);
                match q.visit(self, r, run, others) {
                    Some(false) => continue,
                    Some(true) => break,
                    None => {
                        faults += 1;
                        break;
                    }
                }
            }
            let Some(n) = self.nodes.get(it.child as usize) else {
                faults += 1;
                break;
            };
            interior += 1;
            let (tn, tf) = slabs.test::<PARALLEL>(n, r.t_min, q.limit());
            let (mut hit, mut used) = (0u32, 0u32);
            for i in 0..WIDTH {
                hit |= ((tn[i] <= tf[i]) as u32) << i;
                used |= ((n.child[i] != EMPTY_SLOT) as u32) << i;
            }
            hit &= used;
            boxes += used.count_ones() as u64;
            let item = |i: usize| WideStackItem {
                child: n.child[i],
                count: n.count[i],
                t: tn[i],
            };
            if hit == 0 {
                continue;
            }
            if hit & (hit - 1) == 0 {
                next = Some(item(hit.trailing_zeros() as usize));
                continue;
            }
            if sp + WIDTH > stack.len() {
                faults += 1;
                break;
            }
            let base = sp;
            while hit != 0 {
                let i = hit.trailing_zeros() as usize;
                hit &= hit - 1;
                if READ_AHEAD {
                    read_entry_ahead(self, n.child[i], &mut touch);
                }
                if Q::SORTED {
                    push_nearest_last(stack, base, &mut sp, item(i));
                } else {
                    stack[sp] = item(i);
                    sp += 1;
                }
            }
            sp -= 1;
            next = Some(stack[sp]);
        }
        core::hint::black_box(touch);
        stats.traversal_steps += interior + leaves;
        stats.interior_steps += interior;
        stats.leaf_steps += leaves;
        stats.box_tests += boxes;
        stats.faults += (faults > 0) as u64;
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

/// Bytes of nodes and corner blocks above which a hierarchy's walks read
/// ahead by default ([`WideBvh::with_read_ahead`]).
///
/// On x86-64 (with SSE: all but the soft-float targets) a read-ahead is a
/// prefetch instruction, which costs a small hierarchy nothing measured,
/// and every hierarchy reads ahead. Against
/// loads above 2 MiB (below), incoherent rays, wide over `rtcIntersect1`
/// (`coray bench --table speed --res 256`, the two builds alternated,
/// two rounds): `random` (6.4 MiB) 0.60 / 0.57 -> 1.08 / 0.69, through
/// the wide tracer 0.63 / 0.62 -> 0.70 / 0.69; `spd:gears` (2.1 MiB)
/// 0.81 / 0.78 -> 0.84 / 0.83; the other SPD scenes, which read nothing
/// ahead before, within the noise on every ray set.
#[cfg(all(target_arch = "x86_64", target_feature = "sse"))]
pub const READ_AHEAD_BYTES: usize = 0;

/// Bytes of nodes and corner blocks above which a hierarchy's walks read
/// ahead by default ([`WideBvh::with_read_ahead`]).
///
/// Elsewhere a read-ahead is a load (below), which pays beyond a typical
/// per-core L2 cache (2 MiB on the machine the figures come from) and not
/// within it: reading ahead over not, incoherent rays, one process
/// alternating the two (x86-64, when it read ahead by loads too): `random`
/// (6.4 MiB) 1.04-1.19x, `spd:gears` (2.1 MiB) 1.02-1.18x, `spd:teapot`
/// (0.5 MiB) 0.95x, `spd:balls` (0.4 MiB) 0.92x.
#[cfg(not(all(target_arch = "x86_64", target_feature = "sse")))]
pub const READ_AHEAD_BYTES: usize = 2 << 20;

/// Whether walks over `nodes` and `corners` read ahead by default: they
/// span more than [`READ_AHEAD_BYTES`].
pub(crate) fn reads_ahead(nodes: &[WideNode], corners: &[Corners4]) -> bool {
    size_of_val(nodes) + size_of_val(corners) > READ_AHEAD_BYTES
}

/// Starts loading every cache line of what an entry names (an interior
/// child's node, a leaf's first corner block) when the entry goes to the
/// stack, so that its lines are on their way while the nearest entry is
/// walked. A hint: what it reads changes no answer, and an index past its
/// slice reads nothing. Three words a record, whose lines are all of a
/// 16-aligned node's (128 bytes) or block's (144) wherever it starts: a
/// node spans two or three lines, a block always three.
#[inline(always)]
fn read_entry_ahead(w: &WideBvh, child: u32, touch: &mut u32) {
    if child & LEAF_BIT == 0 {
        if let Some(n) = w.nodes.get(child as usize) {
            // Bytes 0, 64 and 124 of the node's 128.
            line_ahead(n.min[0][0].to_bits(), &n.min[0][0], touch);
            line_ahead(n.max[1][0].to_bits(), &n.max[1][0], touch);
            line_ahead(n.count[WIDTH - 1], &n.count[WIDTH - 1], touch);
        }
    } else if let Some(b) = w.corners.get((child & !LEAF_BIT) as usize / TRI_LANES) {
        // Bytes 0, 64 and 140 of the block's 144.
        line_ahead(b[0][0][0].to_bits(), &b[0][0][0], touch);
        line_ahead(b[1][1][0].to_bits(), &b[1][1][0], touch);
        line_ahead(b[2][2][3].to_bits(), &b[2][2][3], touch);
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
