//! Closest-hit and any-hit traversal of every hierarchy, counting the
//! thesis' metrics: hierarchy objects (boxes) and actual objects
//! (primitives) tested, and their cost in the thesis' units (docs/design.md, Metrics:
//! add, multiply, compare 1, divide 5, square root 15).

use super::{Bvh, BvhNode};
use crate::geom::leaf::beats;
use crate::geom::{Hit, PreparedRay, Ray, GEOM_SPHERES, GEOM_TRIANGLES};
use crate::tolerance::BOX_FAR_SLACK;
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

/// A traversal stack entry with its entry distance.
pub(crate) trait Entered: Copy {
    /// Where the ray enters the entry's volume.
    fn t(&self) -> f32;
}

impl Entered for BvhStackItem {
    #[inline(always)]
    fn t(&self) -> f32 {
        self.t
    }
}

/// Pushes `item` among the entries pushed since `base` (sorted far to near,
/// so the nearest pops first): every hierarchy's closest-hit walk.
#[inline(always)]
pub(crate) fn push_nearest_last<T: Entered>(stack: &mut [T], base: usize, sp: &mut usize, item: T) {
    let mut i = *sp;
    while i > base && stack[i - 1].t() < item.t() {
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

/// The slab test in the thesis' order (x, y, z, stopping at the first axis
/// that shows a miss), clipped to `[t_min, t_max]`: the entry distance and
/// the cost.
#[inline]
pub(crate) fn box_test(n: &BvhNode, r: &PreparedRay, t_max: f32) -> (Option<f32>, u64) {
    let (mut t0, mut t1) = (r.t_min, t_max);
    let mut cost = 0;
    for a in 0..3 {
        // Zero or so small that its inverse overflows: parallel, as the
        // kd-tree's clip takes it (`(face - origin) * inf` is NaN on a face).
        if r.inv_dir[a].is_infinite() {
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
        t1 = t1.min(far * BOX_FAR_SLACK);
        if !(t0 <= t1) {
            return (None, cost);
        }
    }
    (Some(t0), cost + BOX_POINT_COST)
}

/// How a hierarchy's walk tests its entries: a node's volume (a 3D box,
/// a 2D rectangle, or both) and, in a leaf of several objects, each
/// object's own volume. The walk is the same for every hierarchy.
pub(crate) trait EntryTest {
    /// Entry distance into node `i` (whose 3D side is `node`) within
    /// `t_max`, or `None`; charges the test to `st`. `None` too for a node
    /// whose data lies outside the structure.
    fn node(&self, i: u32, node: &BvhNode, t_max: f32, st: &mut TraceStats) -> Option<f32>;
    /// Whether primitive `p`'s own entry in a leaf of several is met.
    fn entry(&self, p: u32, t_max: f32, st: &mut TraceStats) -> bool;
}

/// The 3D hierarchies' test: the slab test on boxes.
pub(crate) struct BoxTest<'r> {
    pub scene: crate::Scene<'r>,
    pub ray: &'r PreparedRay,
}

impl EntryTest for BoxTest<'_> {
    #[inline(always)]
    fn node(&self, _: u32, node: &BvhNode, t_max: f32, st: &mut TraceStats) -> Option<f32> {
        let (t, cost) = box_test(node, self.ray, t_max);
        st.box_tests += 1;
        st.box_cost += cost;
        t
    }
    #[inline(always)]
    fn entry(&self, p: u32, t_max: f32, st: &mut TraceStats) -> bool {
        let b = self.scene.prim_box(p as usize);
        self.node(p, &BvhNode::leaf(&b, 0, 0), t_max, st).is_some()
    }
}

impl<'a> Bvh<'a> {
    /// Tests primitive `p` and charges its cost.
    #[inline]
    pub(crate) fn test_prim(
        &self,
        p: u32,
        r: &PreparedRay,
        t_max: f32,
        st: &mut TraceStats,
    ) -> Option<Hit> {
        st.prim_tests += 1;
        let h = self.scene.intersect_prim(p as usize, r, t_max);
        let geom = self.scene.geom_of(p as usize);
        // Only a sphere's miss cost depends on more than the outcome.
        let away = geom == GEOM_SPHERES
            && h.is_none()
            && self
                .scene
                .spheres
                .get((p as usize).wrapping_sub(self.scene.triangles.len()))
                .is_some_and(|s| {
                    let oc = r.origin - crate::Vec3::from(s.center);
                    oc.length_squared() > s.radius * s.radius && oc.dot(r.dir) > 0.0
                });
        st.prim_cost += prim_cost(geom, h.is_some(), away);
        h
    }

    /// The references of leaf `n`, or `None` when they lie outside the refs.
    #[inline]
    pub(crate) fn leaf_refs(&self, n: &BvhNode) -> Option<&'a [u32]> {
        self.refs.get(n.first as usize..)?.get(..n.len() as usize)
    }

    /// The children of interior node `n`, or `None` outside the nodes.
    #[inline]
    pub(crate) fn children(&self, n: &BvhNode) -> Option<core::ops::Range<u32>> {
        let end = n.first.checked_add(n.len())?;
        (end as usize <= self.nodes.len()).then_some(n.first..end)
    }

    /// Closest hit of `ray`, on the caller's `stack` of at least
    /// [`Bvh::stack_len`] entries.
    ///
    /// # Panics
    /// When `stack` is shorter than [`Bvh::stack_len`].
    pub fn intersect(&self, ray: &Ray, stack: &mut [BvhStackItem], st: &mut TraceStats) -> Hit {
        self.check_stack(stack);
        st.rays += 1;
        if !ray.is_valid() || self.info.ref_count == 0 {
            return Hit::MISS;
        }
        let r = PreparedRay::new(ray);
        let test = BoxTest {
            scene: self.scene,
            ray: &r,
        };
        self.closest(&r, &test, stack, st)
    }

    /// True when anything lies on `ray`'s segment; the stack as for
    /// [`Bvh::intersect`].
    ///
    /// # Panics
    /// When `stack` is shorter than [`Bvh::stack_len`].
    pub fn occluded(&self, ray: &Ray, stack: &mut [BvhStackItem], st: &mut TraceStats) -> bool {
        self.check_stack(stack);
        st.rays += 1;
        if !ray.is_valid() || self.info.ref_count == 0 {
            return false;
        }
        let r = PreparedRay::new(ray);
        let test = BoxTest {
            scene: self.scene,
            ray: &r,
        };
        self.any(&r, &test, stack, st)
    }

    fn check_stack(&self, stack: &[BvhStackItem]) {
        assert!(
            stack.len() >= self.stack_len(),
            "hierarchy traversal stack of {} entries: needs stack_len() = {}",
            stack.len(),
            self.stack_len()
        );
    }

    /// The closest-hit walk of every hierarchy, nearest child first. It
    /// visits each node at most once and never pushes past a stack of
    /// [`Bvh::stack_len`] on a valid hierarchy; a walk that would, or that
    /// meets an index outside the structure, stops with a fault.
    #[inline(always)]
    pub(crate) fn closest<T: EntryTest>(
        &self,
        r: &PreparedRay,
        test: &T,
        stack: &mut [BvhStackItem],
        st: &mut TraceStats,
    ) -> Hit {
        let mut best = Hit::MISS;
        let limit = |best: &Hit| if best.is_hit() { best.t } else { r.t_max };
        let root = self.info.root;
        let Some(t) = self
            .nodes
            .get(root as usize)
            .and_then(|n| test.node(root, n, r.t_max, st))
        else {
            return best;
        };
        let Some(first) = stack.first_mut() else {
            st.faults += 1;
            return best;
        };
        *first = BvhStackItem { node: root, t };
        let mut sp = 1;
        let mut budget = self.nodes.len();
        while sp > 0 {
            sp -= 1;
            let item = stack[sp];
            if item.t > limit(&best) {
                continue;
            }
            let Some(n) = self.nodes.get(item.node as usize).filter(|_| budget > 0) else {
                st.faults += 1;
                return best;
            };
            budget -= 1;
            st.traversal_steps += 1;
            if n.is_leaf() {
                st.leaf_steps += 1;
                let Some(refs) = self.leaf_refs(n) else {
                    st.faults += 1;
                    return best;
                };
                let shared = refs.len() > 1;
                for &p in refs {
                    if shared && !test.entry(p, limit(&best), st) {
                        continue;
                    }
                    if let Some(h) = self.test_prim(p, r, limit(&best), st) {
                        if beats(&h, &best) {
                            best = h;
                        }
                    }
                }
                continue;
            }
            st.interior_steps += 1;
            let Some(kids) = self.children(n) else {
                st.faults += 1;
                return best;
            };
            // Children hit, pushed far to near so the nearest pops first.
            let base = sp;
            for c in kids {
                if let Some(t) = test.node(c, &self.nodes[c as usize], limit(&best), st) {
                    if sp == stack.len() {
                        st.faults += 1;
                        return best;
                    }
                    push_nearest_last(stack, base, &mut sp, BvhStackItem { node: c, t });
                }
            }
        }
        best
    }

    /// The any-hit walk of every hierarchy, with the same bounds as
    /// [`Bvh::closest`].
    #[inline(always)]
    pub(crate) fn any<T: EntryTest>(
        &self,
        r: &PreparedRay,
        test: &T,
        stack: &mut [BvhStackItem],
        st: &mut TraceStats,
    ) -> bool {
        let root = self.info.root;
        let Some(t) = self
            .nodes
            .get(root as usize)
            .and_then(|n| test.node(root, n, r.t_max, st))
        else {
            return false;
        };
        let Some(first) = stack.first_mut() else {
            st.faults += 1;
            return false;
        };
        *first = BvhStackItem { node: root, t };
        let mut sp = 1;
        let mut budget = self.nodes.len();
        while sp > 0 {
            sp -= 1;
            let Some(n) = self
                .nodes
                .get(stack[sp].node as usize)
                .filter(|_| budget > 0)
            else {
                st.faults += 1;
                return false;
            };
            budget -= 1;
            st.traversal_steps += 1;
            if n.is_leaf() {
                st.leaf_steps += 1;
                let Some(refs) = self.leaf_refs(n) else {
                    st.faults += 1;
                    return false;
                };
                let shared = refs.len() > 1;
                for &p in refs {
                    if shared && !test.entry(p, r.t_max, st) {
                        continue;
                    }
                    if self.test_prim(p, r, r.t_max, st).is_some() {
                        return true;
                    }
                }
                continue;
            }
            st.interior_steps += 1;
            let Some(kids) = self.children(n) else {
                st.faults += 1;
                return false;
            };
            for c in kids {
                if let Some(t) = test.node(c, &self.nodes[c as usize], r.t_max, st) {
                    if sp == stack.len() {
                        st.faults += 1;
                        return false;
                    }
                    stack[sp] = BvhStackItem { node: c, t };
                    sp += 1;
                }
            }
        }
        false
    }
}
