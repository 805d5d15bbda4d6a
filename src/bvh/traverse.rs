//! Closest-hit and any-hit traversal of every hierarchy, counting the
//! thesis' metrics: hierarchy objects (boxes) and actual objects
//! (primitives) tested, and their cost in the thesis' units (DESIGN.md:
//! add, multiply, compare 1, divide 5, square root 15).

use super::{Bvh, BvhNode};
use crate::geom::{Hit, PreparedRay, Ray, GEOM_SPHERES, GEOM_TRIANGLES};
use crate::kd::traverse::tie_wins;
use crate::TraceStats;

/// Thesis 4.1.2: a slab costs 15 per axis (2 when the ray is parallel to
/// it), a miss stops at the axis that shows it, a hit adds 6 for the
/// entry point: 51 in all.
pub const BOX_HIT_COST: u64 = 51;
const BOX_AXIS_COST: u64 = 15;
const BOX_PARALLEL_COST: u64 = 2;
const BOX_POINT_COST: u64 = 6;

/// Costs of actual objects by outcome. Spheres are the thesis' (4.1.1:
/// 14 when the ray starts outside and points away, 17 for another miss,
/// 22 for a hit). Triangles are our count of coray's watertight test in
/// the same units: 39 to reject on the edge functions, 61 for a hit.
/// Cones and cylinders are our estimate of their quadric test (frame
/// change, quadratic, rim checks): 50 for a miss, 95 for a hit.
fn prim_cost(geom: u32, hit: bool, sphere_away: bool) -> u64 {
    match (geom, hit) {
        (GEOM_TRIANGLES, true) => 61,
        (GEOM_TRIANGLES, false) => 39,
        (GEOM_SPHERES, true) => 22,
        (GEOM_SPHERES, false) if sphere_away => 14,
        (GEOM_SPHERES, false) => 17,
        (_, true) => 95,
        (_, false) => 50,
    }
}

/// The traversal's counters: the ray counters every structure keeps, and
/// the thesis' box and object costs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[repr(C)]
pub struct BvhStats {
    /// Rays, nodes visited (`traversal_steps`: boxes tested), primitive tests.
    pub trace: TraceStats,
    /// Hierarchy objects (boxes) tested.
    pub box_tests: u64,
    /// Their cost in thesis units.
    pub box_cost: u64,
    /// Cost of the actual objects (primitives) tested, in thesis units.
    pub prim_cost: u64,
}

impl BvhStats {
    /// Adds another call's counts.
    pub fn add(&mut self, o: &BvhStats) {
        self.trace.add(&o.trace);
        self.box_tests += o.box_tests;
        self.box_cost += o.box_cost;
        self.prim_cost += o.prim_cost;
    }
    /// The thesis' average cost per hierarchy object.
    pub fn cost_per_box(&self) -> f64 {
        self.box_cost as f64 / (self.box_tests.max(1)) as f64
    }
    /// The thesis' average cost per actual object.
    pub fn cost_per_prim(&self) -> f64 {
        self.prim_cost as f64 / (self.trace.prim_tests.max(1)) as f64
    }
}

/// Pushes `item` among the entries pushed since `base` (sorted far to near,
/// so the nearest pops first).
#[inline]
pub(crate) fn push_nearest_last(
    stack: &mut [BvhStackItem],
    base: usize,
    sp: &mut usize,
    item: BvhStackItem,
) {
    let mut i = *sp;
    while i > base && stack[i - 1].t < item.t {
        stack[i] = stack[i - 1];
        i -= 1;
    }
    stack[i] = item;
    *sp += 1;
}

/// A traversal stack entry: a node whose box the ray enters at `t`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub struct BvhStackItem {
    /// Node index.
    pub node: u32,
    /// Entry distance into its box.
    pub t: f32,
}

/// Slack on the far distance so that rounding never loses a box the ray
/// touches (Ize 2013: `1 + 2 gamma(3)`).
const FAR_SLACK: f32 = 1.0 + 4.0 * f32::EPSILON;

/// The slab test in the thesis' order (x, y, z, stopping at the first axis
/// that shows a miss), clipped to `[t_min, t_max]`: the entry distance and
/// the cost.
#[inline]
pub(crate) fn box_test(n: &BvhNode, r: &PreparedRay, t_max: f32) -> (Option<f32>, u64) {
    let (mut t0, mut t1) = (r.t_min, t_max);
    let mut cost = 0;
    for a in 0..3 {
        if r.dir[a] == 0.0 {
            cost += BOX_PARALLEL_COST;
            if r.origin[a] < n.min[a] || r.origin[a] > n.max[a] {
                return (None, cost);
            }
            continue;
        }
        cost += BOX_AXIS_COST;
        let lo = (n.min[a] - r.origin[a]) * r.inv_dir[a];
        let hi = (n.max[a] - r.origin[a]) * r.inv_dir[a];
        let (near, far) = if lo <= hi { (lo, hi) } else { (hi, lo) };
        t0 = t0.max(near);
        t1 = t1.min(far * FAR_SLACK);
        if !(t0 <= t1) {
            return (None, cost);
        }
    }
    (Some(t0), cost + BOX_POINT_COST)
}

impl Bvh<'_> {
    /// Tests primitive `p` and charges its cost.
    #[inline]
    pub(crate) fn test_prim(
        &self,
        p: u32,
        r: &PreparedRay,
        t_max: f32,
        st: &mut BvhStats,
    ) -> Option<Hit> {
        st.trace.prim_tests += 1;
        let h = self.scene.intersect_prim(p as usize, r, t_max);
        let geom = self.scene.geom_of(p as usize);
        // Only a sphere's miss cost depends on more than the outcome.
        let away = geom == GEOM_SPHERES && h.is_none() && {
            let s = &self.scene.spheres[p as usize - self.scene.triangles.len()];
            let oc = r.origin - crate::Vec3::from(s.center);
            oc.length_squared() > s.radius * s.radius && oc.dot(r.dir) > 0.0
        };
        st.prim_cost += prim_cost(geom, h.is_some(), away);
        h
    }

    /// In a leaf of several objects (an R-tree's entries), each object's
    /// own box is a hierarchy object too, tested before the object as the
    /// R-tree's search and the thesis do. (A leaf of one object is its box.)
    #[inline]
    fn entry_hit(&self, p: u32, r: &PreparedRay, t_max: f32, st: &mut BvhStats) -> bool {
        let b = self.scene.prim_box(p as usize);
        let node = BvhNode::leaf(&b, 0, 0);
        let (t, cost) = box_test(&node, r, t_max);
        st.box_tests += 1;
        st.box_cost += cost;
        t.is_some()
    }

    /// The root's stack entry when the ray enters its box.
    #[inline]
    fn enter_root(&self, r: &PreparedRay, st: &mut BvhStats) -> Option<BvhStackItem> {
        let root = self.info.root;
        let (t, cost) = box_test(&self.nodes[root as usize], r, r.t_max);
        st.box_tests += 1;
        st.box_cost += cost;
        Some(BvhStackItem { node: root, t: t? })
    }

    /// Closest hit of `ray`, on the caller's `stack` (at least
    /// [`Bvh::stack_len`] entries; a shorter one panics in debug builds and
    /// is never overrun).
    pub fn intersect(&self, ray: &Ray, stack: &mut [BvhStackItem], st: &mut BvhStats) -> Hit {
        st.trace.rays += 1;
        if !ray.is_valid() || self.info.ref_count == 0 {
            return Hit::MISS;
        }
        let r = PreparedRay::new(ray);
        let mut best = Hit::MISS;
        let limit = |best: &Hit| if best.is_hit() { best.t } else { r.t_max };
        let Some(root) = self.enter_root(&r, st) else {
            return best;
        };
        stack[0] = root;
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            let item = stack[sp];
            if item.t > limit(&best) {
                continue;
            }
            let n = self.nodes[item.node as usize];
            st.trace.traversal_steps += 1;
            if n.is_leaf() {
                st.trace.leaf_steps += 1;
                let shared = n.len() > 1;
                for &p in &self.refs[n.first as usize..(n.first + n.len()) as usize] {
                    if shared && !self.entry_hit(p, &r, limit(&best), st) {
                        continue;
                    }
                    if let Some(h) = self.test_prim(p, &r, limit(&best), st) {
                        if !best.is_hit() || h.t < best.t || tie_wins(&h, &best) {
                            best = h;
                        }
                    }
                }
                continue;
            }
            st.trace.interior_steps += 1;
            // Children hit, pushed far to near so the nearest pops first.
            let base = sp;
            for c in n.first..n.first + n.len() {
                let (t, cost) = box_test(&self.nodes[c as usize], &r, limit(&best));
                st.box_tests += 1;
                st.box_cost += cost;
                if let Some(t) = t {
                    push_nearest_last(stack, base, &mut sp, BvhStackItem { node: c, t });
                }
            }
        }
        best
    }

    /// True when anything lies on `ray`'s segment.
    pub fn occluded(&self, ray: &Ray, stack: &mut [BvhStackItem], st: &mut BvhStats) -> bool {
        st.trace.rays += 1;
        if !ray.is_valid() || self.info.ref_count == 0 {
            return false;
        }
        let r = PreparedRay::new(ray);
        let Some(root) = self.enter_root(&r, st) else {
            return false;
        };
        stack[0] = root;
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            let n = self.nodes[stack[sp].node as usize];
            st.trace.traversal_steps += 1;
            if n.is_leaf() {
                st.trace.leaf_steps += 1;
                let shared = n.len() > 1;
                for &p in &self.refs[n.first as usize..(n.first + n.len()) as usize] {
                    if shared && !self.entry_hit(p, &r, r.t_max, st) {
                        continue;
                    }
                    if self.test_prim(p, &r, r.t_max, st).is_some() {
                        return true;
                    }
                }
                continue;
            }
            st.trace.interior_steps += 1;
            for c in n.first..n.first + n.len() {
                let (t, cost) = box_test(&self.nodes[c as usize], &r, r.t_max);
                st.box_tests += 1;
                st.box_cost += cost;
                if let Some(t) = t {
                    stack[sp] = BvhStackItem { node: c, t };
                    sp += 1;
                }
            }
        }
        false
    }
}
