//! Traversal of a projection hierarchy by one of the thesis' three
//! intersection schemes, closest hit and any hit. The scheme is chosen
//! once per ray; each has its own loop.

use super::{ProjHierarchy, Rect};
use crate::bvh::traverse::{box_test, push_nearest_last};
use crate::bvh::{BvhNode, BvhStackItem, BvhStats};
use crate::geom::{Hit, PreparedRay, Ray};
use crate::kd::traverse::tie_wins;

/// How a ray is tested against the hierarchy's nodes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ProjScheme {
    /// The ray's 2D point in the node's rectangle (4 comparisons).
    TwoD,
    /// The ray against the node's 3D box (2 to 51 units).
    ThreeD,
    /// 2D first; the 3D box only when the rectangle holds the point.
    Combination,
}

/// The thesis' units of a point-in-rectangle test.
pub const RECT_COST: u64 = 4;

/// A projection traversal's counters: those of [`BvhStats`] (hierarchy
/// objects tested, counting 2D and 3D tests, and their cost; primitives)
/// and how many of the tests were 2D.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ProjStats {
    /// Rays, nodes, primitive tests and the thesis' costs.
    pub bvh: BvhStats,
    /// Point-in-rectangle tests among `bvh.box_tests` (a combination test
    /// that goes on to the 3D box counts once there, with both costs).
    pub rect_tests: u64,
}

impl ProjStats {
    /// Adds another call's counts.
    pub fn add(&mut self, o: &ProjStats) {
        self.bvh.add(&o.bvh);
        self.rect_tests += o.rect_tests;
    }
}

const TWO_D: u8 = 0;
const THREE_D: u8 = 1;
const COMBINED: u8 = 2;

/// A ray in a plane's terms: its 2D point and, for ordering, the factor
/// from a depth along the plane's forward axis to the ray's t.
pub struct Projected {
    /// Where the ray's line crosses the plane (plane coordinates).
    pub point: [f32; 2],
    /// t per unit of depth along the plane's forward axis (0: unknown).
    pub t_per_depth: f32,
}

impl ProjHierarchy<'_> {
    /// One entry test of scheme `S`: the lower bound of t inside it, or None.
    #[inline(always)]
    fn test<const S: u8>(
        rect: &Rect,
        node: &BvhNode,
        r: &PreparedRay,
        q: &Projected,
        t_max: f32,
        st: &mut ProjStats,
    ) -> Option<f32> {
        st.bvh.box_tests += 1;
        if S != THREE_D {
            st.rect_tests += 1;
            st.bvh.box_cost += RECT_COST;
            if !rect.contains(q.point) {
                return None;
            }
            if S == TWO_D {
                let t = (rect.near * q.t_per_depth).max(r.t_min);
                return (t <= t_max).then_some(t);
            }
        }
        let (t, cost) = box_test(node, r, t_max);
        st.bvh.box_cost += cost;
        t
    }

    /// Primitive `p`'s entry in a leaf of several: its rectangle and box.
    #[inline(always)]
    fn entry<const S: u8>(
        &self,
        p: u32,
        r: &PreparedRay,
        q: &Projected,
        t_max: f32,
        st: &mut ProjStats,
    ) -> bool {
        let b = self.bvh.scene.prim_box(p as usize);
        let node = BvhNode::leaf(&b, 0, 0);
        Self::test::<S>(&self.prim_rects[p as usize], &node, r, q, t_max, st).is_some()
    }

    fn closest<const S: u8>(
        &self,
        r: &PreparedRay,
        q: &Projected,
        stack: &mut [BvhStackItem],
        st: &mut ProjStats,
    ) -> Hit {
        let mut best = Hit::MISS;
        let limit = |best: &Hit| if best.is_hit() { best.t } else { r.t_max };
        let root = self.bvh.info.root as usize;
        let Some(t) = Self::test::<S>(&self.rects[root], &self.bvh.nodes[root], r, q, r.t_max, st)
        else {
            return best;
        };
        stack[0] = BvhStackItem {
            node: root as u32,
            t,
        };
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            let item = stack[sp];
            if item.t > limit(&best) {
                continue;
            }
            let n = self.bvh.nodes[item.node as usize];
            st.bvh.trace.traversal_steps += 1;
            if n.is_leaf() {
                st.bvh.trace.leaf_steps += 1;
                let shared = n.len() > 1;
                for &p in &self.bvh.refs[n.first as usize..(n.first + n.len()) as usize] {
                    if shared && !self.entry::<S>(p, r, q, limit(&best), st) {
                        continue;
                    }
                    if let Some(h) = self.bvh.test_prim(p, r, limit(&best), &mut st.bvh) {
                        if !best.is_hit() || h.t < best.t || tie_wins(&h, &best) {
                            best = h;
                        }
                    }
                }
                continue;
            }
            st.bvh.trace.interior_steps += 1;
            let base = sp;
            for c in n.first..n.first + n.len() {
                let ci = c as usize;
                let hit =
                    Self::test::<S>(&self.rects[ci], &self.bvh.nodes[ci], r, q, limit(&best), st);
                if let Some(t) = hit {
                    push_nearest_last(stack, base, &mut sp, BvhStackItem { node: c, t });
                }
            }
        }
        best
    }

    fn any<const S: u8>(
        &self,
        r: &PreparedRay,
        q: &Projected,
        stack: &mut [BvhStackItem],
        st: &mut ProjStats,
    ) -> bool {
        let root = self.bvh.info.root as usize;
        let t_max = r.t_max;
        if Self::test::<S>(&self.rects[root], &self.bvh.nodes[root], r, q, t_max, st).is_none() {
            return false;
        }
        stack[0] = BvhStackItem {
            node: root as u32,
            t: 0.0,
        };
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            let n = self.bvh.nodes[stack[sp].node as usize];
            st.bvh.trace.traversal_steps += 1;
            if n.is_leaf() {
                st.bvh.trace.leaf_steps += 1;
                let shared = n.len() > 1;
                for &p in &self.bvh.refs[n.first as usize..(n.first + n.len()) as usize] {
                    if shared && !self.entry::<S>(p, r, q, t_max, st) {
                        continue;
                    }
                    if self.bvh.test_prim(p, r, t_max, &mut st.bvh).is_some() {
                        return true;
                    }
                }
                continue;
            }
            st.bvh.trace.interior_steps += 1;
            for c in n.first..n.first + n.len() {
                let ci = c as usize;
                if Self::test::<S>(&self.rects[ci], &self.bvh.nodes[ci], r, q, t_max, st).is_some()
                {
                    stack[sp] = BvhStackItem { node: c, t: 0.0 };
                    sp += 1;
                }
            }
        }
        false
    }

    /// The ray's point on the plane, when it lies on a line through the
    /// plane's eye, in front of it: a primary ray from the eye, or a ray
    /// towards the eye (a shadow ray to a light) that ends at it or
    /// before; for an orthographic plane, a ray against its direction.
    /// Only such rays can hit only what projects onto their point.
    pub fn project(&self, ray: &Ray) -> Option<Projected> {
        use super::ProjPlane::*;
        match self.plane {
            Perspective { eye, forward, .. } => {
                if ray.origin == eye {
                    let df = ray.dir.dot(forward);
                    let point = self.plane.point_of_direction(ray.dir)?;
                    return Some(Projected {
                        point,
                        t_per_depth: 1.0 / df,
                    });
                }
                if !super::plane::runs_towards(ray, eye) {
                    return None;
                }
                let point = self.plane.point_of_direction(ray.origin - eye)?;
                Some(Projected {
                    point,
                    t_per_depth: 0.0,
                })
            }
            Orthographic { forward, .. } => {
                if !super::plane::runs_against(ray, forward) {
                    return None;
                }
                Some(Projected {
                    point: self.plane.point_of_position(ray.origin),
                    t_per_depth: 0.0,
                })
            }
        }
    }

    /// Closest hit of `ray` by `scheme`, or `None` when the plane cannot
    /// take the ray (not on a line through its eye; see
    /// [`ProjHierarchy::project`]): trace such a ray, as every secondary
    /// ray, through a 3D hierarchy. `stack` holds at least
    /// `bvh.stack_len()` entries.
    pub fn intersect(
        &self,
        ray: &Ray,
        scheme: ProjScheme,
        stack: &mut [BvhStackItem],
        st: &mut ProjStats,
    ) -> Option<Hit> {
        let q = self.project(ray)?;
        st.bvh.trace.rays += 1;
        if !ray.is_valid() || self.bvh.info.ref_count == 0 {
            return Some(Hit::MISS);
        }
        let r = PreparedRay::new(ray);
        Some(match scheme {
            ProjScheme::TwoD if q.t_per_depth > 0.0 => self.closest::<TWO_D>(&r, &q, stack, st),
            // Without a depth factor 2D tests cannot order: combination.
            ProjScheme::TwoD | ProjScheme::Combination => {
                self.closest::<COMBINED>(&r, &q, stack, st)
            }
            ProjScheme::ThreeD => self.closest::<THREE_D>(&r, &q, stack, st),
        })
    }

    /// True when anything lies on `ray`'s segment, by `scheme`; `None`
    /// as for [`ProjHierarchy::intersect`].
    pub fn occluded(
        &self,
        ray: &Ray,
        scheme: ProjScheme,
        stack: &mut [BvhStackItem],
        st: &mut ProjStats,
    ) -> Option<bool> {
        let q = self.project(ray)?;
        st.bvh.trace.rays += 1;
        if !ray.is_valid() || self.bvh.info.ref_count == 0 {
            return Some(false);
        }
        let r = PreparedRay::new(ray);
        Some(match scheme {
            ProjScheme::TwoD => self.any::<TWO_D>(&r, &q, stack, st),
            ProjScheme::ThreeD => self.any::<THREE_D>(&r, &q, stack, st),
            ProjScheme::Combination => self.any::<COMBINED>(&r, &q, stack, st),
        })
    }
}
