//! The one contract every acceleration structure keeps once built, so the
//! CLI, the tests and the C ABI drive a kd-tree, a hierarchy and a
//! projection hierarchy the same way: trace one ray or an array of rays,
//! closest or any hit, on the caller's stack, with one statistics type;
//! validate; say how long a stack it needs.

use crate::bvh::{Bvh, BvhStackItem};
use crate::kd::{KdStackItem, KdTree, Traversal, KD_STACK_LEN};
use crate::proj::{ProjHierarchy, ProjScheme};
use crate::wide::{WideBvh, WideStackItem};
use crate::{Error, Hit, Ray, TraceStats};

/// What `validate` found: the structure's shape.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Shape {
    /// Nodes, interior and leaf.
    pub nodes: u32,
    /// Leaves.
    pub leaves: u32,
    /// Leaves holding no primitive.
    pub empty_leaves: u32,
    /// Primitive references in leaves.
    pub refs: u32,
    /// Depth of the deepest leaf (root: 0).
    pub depth: u32,
}

/// An acceleration structure, built.
pub trait Accel {
    /// How a ray walks it, chosen once per call ([`Traversal`] for a
    /// kd-tree, [`ProjScheme`] for a projection hierarchy, `()` otherwise).
    type Method: Copy;
    /// One entry of the caller's traversal stack.
    type StackItem: Copy + Default;

    /// Entries of stack every trace and `validate` needs.
    fn stack_len(&self) -> usize;

    /// Closest hit of `ray`, or [`Hit::MISS`]. `Err` only for a ray the
    /// structure cannot take (a projection hierarchy's, off its plane's
    /// lines) or a stack shorter than [`Accel::stack_len`].
    fn intersect(
        &self,
        ray: &Ray,
        method: Self::Method,
        stack: &mut [Self::StackItem],
        stats: &mut TraceStats,
    ) -> Result<Hit, Error>;

    /// Whether anything lies on `ray`'s segment; errors as [`Accel::intersect`].
    fn occluded(
        &self,
        ray: &Ray,
        method: Self::Method,
        stack: &mut [Self::StackItem],
        stats: &mut TraceStats,
    ) -> Result<bool, Error>;

    /// Every structural invariant; never panics, linear time.
    fn validate(&self, stack: &mut [Self::StackItem]) -> Result<Shape, Error>;

    /// Why this structure cannot take `rays` (checked for a whole array
    /// before any answer is written), or `Ok`. Every ray by default.
    fn check_rays(&self, rays: &[Ray]) -> Result<(), Error> {
        let _ = rays;
        Ok(())
    }

    /// Closest hits of `rays` into `hits` (as long). Nothing is written
    /// unless every ray can be taken.
    fn intersect_many(
        &self,
        rays: &[Ray],
        hits: &mut [Hit],
        method: Self::Method,
        stack: &mut [Self::StackItem],
        stats: &mut TraceStats,
    ) -> Result<(), Error> {
        check_lengths(rays.len(), hits.len(), stack.len(), self.stack_len())?;
        self.check_rays(rays)?;
        // Counted in a local the loop can keep in registers, added once
        // (also when a ray stops the loop).
        let mut counts = TraceStats::default();
        let done = rays.iter().zip(hits.iter_mut()).try_for_each(|(r, h)| {
            *h = self.intersect(r, method, stack, &mut counts)?;
            Ok(())
        });
        stats.add(&counts);
        done
    }

    /// Any-hit answers of `rays` into `out` (as long).
    fn occluded_many(
        &self,
        rays: &[Ray],
        out: &mut [bool],
        method: Self::Method,
        stack: &mut [Self::StackItem],
        stats: &mut TraceStats,
    ) -> Result<(), Error> {
        check_lengths(rays.len(), out.len(), stack.len(), self.stack_len())?;
        self.check_rays(rays)?;
        // As in `intersect_many`.
        let mut counts = TraceStats::default();
        let done = rays.iter().zip(out.iter_mut()).try_for_each(|(r, o)| {
            *o = self.occluded(r, method, stack, &mut counts)?;
            Ok(())
        });
        stats.add(&counts);
        done
    }
}

fn check_lengths(rays: usize, out: usize, stack: usize, need: usize) -> Result<(), Error> {
    if out < rays {
        return Err(Error::SliceTooSmall {
            slice: "hits",
            needed: rays,
            got: out,
        });
    }
    if stack < need {
        return Err(Error::SliceTooSmall {
            slice: "stack",
            needed: need,
            got: stack,
        });
    }
    Ok(())
}

fn stack_ok(len: usize, need: usize) -> Result<(), Error> {
    check_lengths(0, 0, len, need)
}

impl Accel for KdTree<'_> {
    type Method = Traversal;
    type StackItem = KdStackItem;

    fn stack_len(&self) -> usize {
        KD_STACK_LEN
    }

    #[inline]
    fn intersect(
        &self,
        ray: &Ray,
        method: Traversal,
        stack: &mut [KdStackItem],
        stats: &mut TraceStats,
    ) -> Result<Hit, Error> {
        stack_ok(stack.len(), KD_STACK_LEN)?;
        Ok(KdTree::intersect(self, ray, method, stack, stats))
    }

    #[inline]
    fn occluded(
        &self,
        ray: &Ray,
        method: Traversal,
        stack: &mut [KdStackItem],
        stats: &mut TraceStats,
    ) -> Result<bool, Error> {
        stack_ok(stack.len(), KD_STACK_LEN)?;
        Ok(KdTree::occluded(self, ray, method, stack, stats))
    }

    fn validate(&self, _: &mut [KdStackItem]) -> Result<Shape, Error> {
        let s = KdTree::validate(self)?;
        Ok(Shape {
            nodes: s.nodes,
            leaves: s.leaves,
            empty_leaves: s.empty_leaves,
            refs: s.refs,
            depth: s.depth,
        })
    }

    /// With [`Traversal::Packets`], packets of 8 where the rays move alike
    /// (feature `packets`; without it, ray by ray, the same hits).
    fn intersect_many(
        &self,
        rays: &[Ray],
        hits: &mut [Hit],
        method: Traversal,
        stack: &mut [KdStackItem],
        stats: &mut TraceStats,
    ) -> Result<(), Error> {
        check_lengths(rays.len(), hits.len(), stack.len(), KD_STACK_LEN)?;
        if cfg!(feature = "packets") && method == Traversal::Packets {
            self.intersect_packets(rays, hits, stack, stats);
        } else {
            // Counted in a local the loop can keep in registers, added
            // once.
            let mut counts = TraceStats::default();
            for (r, h) in rays.iter().zip(hits.iter_mut()) {
                *h = KdTree::intersect(self, r, method, stack, &mut counts);
            }
            stats.add(&counts);
        }
        Ok(())
    }

    /// With [`Traversal::Packets`], packets of 8 where the rays move alike
    /// (feature `packets`; without it, ray by ray, the same hits).
    fn occluded_many(
        &self,
        rays: &[Ray],
        out: &mut [bool],
        method: Traversal,
        stack: &mut [KdStackItem],
        stats: &mut TraceStats,
    ) -> Result<(), Error> {
        check_lengths(rays.len(), out.len(), stack.len(), KD_STACK_LEN)?;
        if cfg!(feature = "packets") && method == Traversal::Packets {
            self.occluded_packets(rays, out, stack, stats);
        } else {
            // As in `intersect_many`.
            let mut counts = TraceStats::default();
            for (r, o) in rays.iter().zip(out.iter_mut()) {
                *o = KdTree::occluded(self, r, method, stack, &mut counts);
            }
            stats.add(&counts);
        }
        Ok(())
    }
}

fn bvh_shape(s: crate::bvh::BvhTreeStats) -> Shape {
    Shape {
        nodes: s.nodes,
        leaves: s.leaves,
        empty_leaves: 0,
        refs: s.refs,
        depth: s.depth,
    }
}

impl Accel for Bvh<'_> {
    type Method = ();
    type StackItem = BvhStackItem;

    fn stack_len(&self) -> usize {
        Bvh::stack_len(self)
    }

    #[inline]
    fn intersect(
        &self,
        ray: &Ray,
        _: (),
        stack: &mut [BvhStackItem],
        stats: &mut TraceStats,
    ) -> Result<Hit, Error> {
        stack_ok(stack.len(), Bvh::stack_len(self))?;
        Ok(Bvh::intersect(self, ray, stack, stats))
    }

    #[inline]
    fn occluded(
        &self,
        ray: &Ray,
        _: (),
        stack: &mut [BvhStackItem],
        stats: &mut TraceStats,
    ) -> Result<bool, Error> {
        stack_ok(stack.len(), Bvh::stack_len(self))?;
        Ok(Bvh::occluded(self, ray, stack, stats))
    }

    /// [`Bvh::validate`] without an R-tree's fill rules (see
    /// [`crate::bvh::validate_rtree`] for those).
    fn validate(&self, stack: &mut [BvhStackItem]) -> Result<Shape, Error> {
        Bvh::validate(self, None, stack).map(bvh_shape)
    }
}

impl Accel for WideBvh<'_> {
    type Method = ();
    type StackItem = WideStackItem;

    fn stack_len(&self) -> usize {
        WideBvh::stack_len(self)
    }

    #[inline]
    fn intersect(
        &self,
        ray: &Ray,
        _: (),
        stack: &mut [WideStackItem],
        stats: &mut TraceStats,
    ) -> Result<Hit, Error> {
        stack_ok(stack.len(), WideBvh::stack_len(self))?;
        Ok(WideBvh::intersect(self, ray, stack, stats))
    }

    #[inline]
    fn occluded(
        &self,
        ray: &Ray,
        _: (),
        stack: &mut [WideStackItem],
        stats: &mut TraceStats,
    ) -> Result<bool, Error> {
        stack_ok(stack.len(), WideBvh::stack_len(self))?;
        Ok(WideBvh::occluded(self, ray, stack, stats))
    }

    /// [`WideBvh::validate`] (one pass over the nodes: no stack needed).
    fn validate(&self, _: &mut [WideStackItem]) -> Result<Shape, Error> {
        WideBvh::validate(self)
    }
}

/// A ray a projection plane cannot take.
const OFF_PLANE: Error = Error::InvalidParameter {
    name: "ray: not on a line through the plane's eye",
};

impl Accel for ProjHierarchy<'_> {
    type Method = ProjScheme;
    type StackItem = BvhStackItem;

    fn stack_len(&self) -> usize {
        ProjHierarchy::stack_len(self)
    }

    #[inline]
    fn intersect(
        &self,
        ray: &Ray,
        method: ProjScheme,
        stack: &mut [BvhStackItem],
        stats: &mut TraceStats,
    ) -> Result<Hit, Error> {
        stack_ok(stack.len(), ProjHierarchy::stack_len(self))?;
        ProjHierarchy::intersect(self, ray, method, stack, stats).ok_or(OFF_PLANE)
    }

    #[inline]
    fn occluded(
        &self,
        ray: &Ray,
        method: ProjScheme,
        stack: &mut [BvhStackItem],
        stats: &mut TraceStats,
    ) -> Result<bool, Error> {
        stack_ok(stack.len(), ProjHierarchy::stack_len(self))?;
        ProjHierarchy::occluded(self, ray, method, stack, stats).ok_or(OFF_PLANE)
    }

    fn validate(&self, stack: &mut [BvhStackItem]) -> Result<Shape, Error> {
        ProjHierarchy::validate(self, None, stack).map(bvh_shape)
    }

    /// Every ray must lie on a line through the plane's eye: all are
    /// checked before any answer is written.
    fn check_rays(&self, rays: &[Ray]) -> Result<(), Error> {
        if rays.iter().any(|r| self.project(r).is_none()) {
            return Err(OFF_PLANE);
        }
        Ok(())
    }
}
