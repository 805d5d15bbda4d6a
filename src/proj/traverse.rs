//! Traversal of a projection hierarchy by one of the thesis' three
//! intersection schemes, closest hit and any hit. The scheme is chosen
//! once per ray; each has its own loop.

use super::ProjHierarchy;
use crate::bvh::traverse::{box_test, EntryTest};
use crate::bvh::{BvhNode, BvhStackItem};
use crate::geom::{Hit, PreparedRay, Ray};
use crate::TraceStats;

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

/// Entry tests of scheme `S` on a projection hierarchy: its rectangles,
/// its 3D boxes, or both.
struct ProjTest<'h, 'r, const S: u8> {
    h: &'h ProjHierarchy<'h>,
    r: &'r PreparedRay,
    q: &'r Projected,
}

impl<const S: u8> ProjTest<'_, '_, S> {
    /// One entry test against `rect` and `node`.
    #[inline(always)]
    fn test(
        &self,
        rect: &super::Rect,
        node: &BvhNode,
        t_max: f32,
        st: &mut TraceStats,
    ) -> Option<f32> {
        st.box_tests += 1;
        if S != THREE_D {
            st.rect_tests += 1;
            st.box_cost += RECT_COST;
            if !rect.contains(self.q.point) {
                return None;
            }
            if S == TWO_D {
                let t = (rect.near * self.q.t_per_depth).max(self.r.t_min);
                return (t <= t_max).then_some(t);
            }
        }
        let (t, cost) = box_test(node, self.r, t_max);
        st.box_cost += cost;
        t
    }
}

impl<const S: u8> EntryTest for ProjTest<'_, '_, S> {
    #[inline(always)]
    fn node(&self, i: u32, node: &BvhNode, t_max: f32, st: &mut TraceStats) -> Option<f32> {
        self.test(self.h.rects.get(i as usize)?, node, t_max, st)
    }
    #[inline(always)]
    fn entry(&self, p: u32, t_max: f32, st: &mut TraceStats) -> bool {
        let b = self.h.bvh.scene.prim_box(p as usize);
        let node = BvhNode::leaf(&b, 0, 0);
        self.h
            .prim_rects
            .get(p as usize)
            .and_then(|rect| self.test(rect, &node, t_max, st))
            .is_some()
    }
}

impl ProjHierarchy<'_> {
    fn closest<const S: u8>(
        &self,
        r: &PreparedRay,
        q: &Projected,
        stack: &mut [BvhStackItem],
        st: &mut TraceStats,
    ) -> Hit {
        let test = ProjTest::<S> { h: self, r, q };
        self.bvh.closest(r, &test, stack, st)
    }

    fn any<const S: u8>(
        &self,
        r: &PreparedRay,
        q: &Projected,
        stack: &mut [BvhStackItem],
        st: &mut TraceStats,
    ) -> bool {
        let test = ProjTest::<S> { h: self, r, q };
        self.bvh.any(r, &test, stack, st)
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

    fn check_stack(&self, stack: &[BvhStackItem]) {
        assert!(
            stack.len() >= self.bvh.stack_len(),
            "projection traversal stack of {} entries: needs stack_len() = {}",
            stack.len(),
            self.bvh.stack_len()
        );
    }

    /// Closest hit of `ray` by `scheme`, or `None` when the plane cannot
    /// take the ray (not on a line through its eye; see
    /// [`ProjHierarchy::project`]): trace such a ray, as every secondary
    /// ray, through a 3D hierarchy. `stack` holds at least
    /// [`ProjHierarchy::stack_len`] entries.
    ///
    /// # Panics
    /// When `stack` is shorter than that.
    pub fn intersect(
        &self,
        ray: &Ray,
        scheme: ProjScheme,
        stack: &mut [BvhStackItem],
        st: &mut TraceStats,
    ) -> Option<Hit> {
        let q = self.project(ray)?;
        self.check_stack(stack);
        st.rays += 1;
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
        st: &mut TraceStats,
    ) -> Option<bool> {
        let q = self.project(ray)?;
        self.check_stack(stack);
        st.rays += 1;
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
