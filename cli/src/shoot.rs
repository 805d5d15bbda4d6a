//! What the renderer and the benchmark trace rays through: any built
//! structure behind one small trait. Every coray structure comes in through
//! the core's [`Accel`] contract ([`AccelShooter`]); the projection rig and
//! Embree are the two others. The structure, and its traversal, is chosen
//! once: each kind gets its own monomorphised loops.

use crate::method::CCalls;
use coray::{Aabb, Accel, Hit, Ray, TraceStats};
use coray_ffi::through_c::CStructure;

/// A structure rays are shot through, with the per-thread state its
/// traversal needs (its stack).
pub trait Shooter: Sync {
    /// Per-thread state.
    type Ctx;
    /// Fresh state for one thread.
    fn ctx(&self) -> Self::Ctx;
    /// Closest hit.
    fn intersect(&self, ray: &Ray, ctx: &mut Self::Ctx, st: &mut TraceStats) -> Hit;
    /// Any hit. `light`: the light a shadow ray goes to, when known.
    fn occluded(
        &self,
        ray: &Ray,
        light: Option<usize>,
        ctx: &mut Self::Ctx,
        st: &mut TraceStats,
    ) -> bool;
    /// Closest hits of many rays (a packet or stream path where the
    /// structure has one).
    fn intersect_all(
        &self,
        rays: &[Ray],
        out: &mut [Hit],
        ctx: &mut Self::Ctx,
        st: &mut TraceStats,
    ) {
        for (r, h) in rays.iter().zip(out.iter_mut()) {
            *h = self.intersect(r, ctx, st);
        }
    }
    /// Any hits of many rays (`lights[i]` the light of ray `i`, when known).
    fn occluded_all(
        &self,
        rays: &[Ray],
        lights: Option<&[usize]>,
        out: &mut [bool],
        ctx: &mut Self::Ctx,
        st: &mut TraceStats,
    ) {
        for (i, (r, o)) in rays.iter().zip(out.iter_mut()).enumerate() {
            *o = self.occluded(r, lights.map(|l| l[i]), ctx, st);
        }
    }
    /// The scene's box (for the renderer's epsilon).
    fn bounds(&self) -> Aabb;
}

/// Any coray structure with a chosen method.
pub struct AccelShooter<A: Accel> {
    /// The structure.
    pub accel: A,
    /// Its method.
    pub method: A::Method,
    /// Its scene's box.
    pub bounds: Aabb,
}

impl<A: Accel + Sync> Shooter for AccelShooter<A>
where
    A::Method: Sync,
{
    type Ctx = Vec<A::StackItem>;

    fn ctx(&self) -> Self::Ctx {
        vec![A::StackItem::default(); self.accel.stack_len()]
    }

    #[inline]
    fn intersect(&self, ray: &Ray, ctx: &mut Self::Ctx, st: &mut TraceStats) -> Hit {
        self.accel
            .intersect(ray, self.method, ctx, st)
            .expect("a stack of stack_len()")
    }

    #[inline]
    fn occluded(
        &self,
        ray: &Ray,
        _: Option<usize>,
        ctx: &mut Self::Ctx,
        st: &mut TraceStats,
    ) -> bool {
        self.accel
            .occluded(ray, self.method, ctx, st)
            .expect("a stack of stack_len()")
    }

    /// The structure's own array path (packets, for a kd-tree's
    /// `Traversal::Packets`).
    fn intersect_all(
        &self,
        rays: &[Ray],
        out: &mut [Hit],
        ctx: &mut Self::Ctx,
        st: &mut TraceStats,
    ) {
        self.accel
            .intersect_many(rays, out, self.method, ctx, st)
            .expect("a stack of stack_len()");
    }

    fn occluded_all(
        &self,
        rays: &[Ray],
        _: Option<&[usize]>,
        out: &mut [bool],
        ctx: &mut Self::Ctx,
        st: &mut TraceStats,
    ) {
        self.accel
            .occluded_many(rays, out, self.method, ctx, st)
            .expect("a stack of stack_len()");
    }

    fn bounds(&self) -> Aabb {
        self.bounds
    }
}

/// A kd-tree tracing arrays in packets of 8 with the widest kernel the
/// CPU runs (AVX2 or the baseline, chosen by coray-ffi); one ray alone
/// hierarchically.
pub struct KdPacketShooter<'a> {
    /// The tree.
    pub tree: coray::kd::KdTree<'a>,
    /// Its scene's box.
    pub bounds: Aabb,
}

impl Shooter for KdPacketShooter<'_> {
    type Ctx = Vec<coray::kd::KdStackItem>;

    fn ctx(&self) -> Self::Ctx {
        coray::owned::stack(coray::kd::KD_STACK_LEN)
    }

    fn intersect(&self, ray: &Ray, ctx: &mut Self::Ctx, st: &mut TraceStats) -> Hit {
        self.tree
            .intersect(ray, coray::kd::Traversal::Hierarchical, ctx, st)
    }

    fn occluded(
        &self,
        ray: &Ray,
        _: Option<usize>,
        ctx: &mut Self::Ctx,
        st: &mut TraceStats,
    ) -> bool {
        self.tree
            .occluded(ray, coray::kd::Traversal::Hierarchical, ctx, st)
    }

    fn intersect_all(
        &self,
        rays: &[Ray],
        out: &mut [Hit],
        ctx: &mut Self::Ctx,
        st: &mut TraceStats,
    ) {
        coray_ffi::simd::intersect_packets(&self.tree, rays, out, ctx, st);
    }

    fn occluded_all(
        &self,
        rays: &[Ray],
        _: Option<&[usize]>,
        out: &mut [bool],
        ctx: &mut Self::Ctx,
        st: &mut TraceStats,
    ) {
        coray_ffi::simd::occluded_packets(&self.tree, rays, out, ctx, st);
    }

    fn bounds(&self) -> Aabb {
        self.bounds
    }
}

/// The wide hierarchy with the widest kernel the CPU runs (AVX2 or the
/// baseline, chosen by coray-ffi).
pub struct WideShooter<'a> {
    /// The hierarchy.
    pub wide: coray::wide::WideBvh<'a>,
    /// Arrays in packets of eight.
    pub packets: bool,
    /// Its scene's box.
    pub bounds: Aabb,
}

impl Shooter for WideShooter<'_> {
    type Ctx = Vec<coray::wide::WideStackItem>;

    fn ctx(&self) -> Self::Ctx {
        coray::owned::stack(self.wide.stack_len())
    }

    fn intersect(&self, ray: &Ray, ctx: &mut Self::Ctx, st: &mut TraceStats) -> Hit {
        coray_ffi::simd::wide_intersect(&self.wide, ray, ctx, st)
    }

    fn occluded(
        &self,
        ray: &Ray,
        _: Option<usize>,
        ctx: &mut Self::Ctx,
        st: &mut TraceStats,
    ) -> bool {
        coray_ffi::simd::wide_occluded(&self.wide, ray, ctx, st)
    }

    fn intersect_all(
        &self,
        rays: &[Ray],
        out: &mut [Hit],
        ctx: &mut Self::Ctx,
        st: &mut TraceStats,
    ) {
        if self.packets {
            coray_ffi::simd::wide_intersect_packets(&self.wide, rays, out, ctx, st);
            return;
        }
        for (r, o) in rays.iter().zip(out.iter_mut()) {
            *o = coray_ffi::simd::wide_intersect(&self.wide, r, ctx, st);
        }
    }

    fn occluded_all(
        &self,
        rays: &[Ray],
        _: Option<&[usize]>,
        out: &mut [bool],
        ctx: &mut Self::Ctx,
        st: &mut TraceStats,
    ) {
        if self.packets {
            coray_ffi::simd::wide_occluded_packets(&self.wide, rays, out, ctx, st);
            return;
        }
        for (r, o) in rays.iter().zip(out.iter_mut()) {
            *o = coray_ffi::simd::wide_occluded(&self.wide, r, ctx, st);
        }
    }

    fn bounds(&self) -> Aabb {
        self.bounds
    }
}

/// A kd-tree or the wide hierarchy traced through the C ABI: one call per
/// ray (on a tracer per thread, or with the handle and stack), or one
/// array call per chunk of rays (the harness's chunks). Statistics stay 0:
/// the calls get NULL for them, as a renderer's would.
pub struct CShooter<'a, T> {
    /// The opened structure.
    pub structure: &'a T,
    /// How the rays are handed over.
    pub calls: CCalls,
    /// Its scene's box.
    pub bounds: Aabb,
}

/// One thread's state for [`CShooter`]: a traversal stack, the any-hit
/// answers as bytes, and the thread's tracer (for `kd-c1`, `wide-c1`).
pub struct CCtx<'a, F> {
    stack: Vec<u128>,
    bytes: Vec<u8>,
    tracer: Option<coray_ffi::through_c::CTracer<'a, F>>,
}

impl<'a, T: CStructure + Sync> Shooter for CShooter<'a, T> {
    type Ctx = CCtx<'a, T::Calls>;

    fn ctx(&self) -> Self::Ctx {
        let s: &'a T = self.structure;
        CCtx {
            stack: s.stack(),
            bytes: Vec::new(),
            tracer: (self.calls == CCalls::Tracer).then(|| s.tracer().expect("valid tracer")),
        }
    }

    fn intersect(&self, ray: &Ray, ctx: &mut Self::Ctx, _: &mut TraceStats) -> Hit {
        match &mut ctx.tracer {
            Some(t) => t.intersect1(ray),
            None => self.structure.intersect1(ray, &mut ctx.stack),
        }
        .expect("valid call")
    }

    fn occluded(
        &self,
        ray: &Ray,
        _: Option<usize>,
        ctx: &mut Self::Ctx,
        _: &mut TraceStats,
    ) -> bool {
        match &mut ctx.tracer {
            Some(t) => t.occluded1(ray),
            None => self.structure.occluded1(ray, &mut ctx.stack),
        }
        .expect("valid call")
    }

    fn intersect_all(
        &self,
        rays: &[Ray],
        out: &mut [Hit],
        ctx: &mut Self::Ctx,
        _: &mut TraceStats,
    ) {
        if self.calls == CCalls::Arrays {
            self.structure
                .intersect(rays, out, &mut ctx.stack)
                .expect("valid call");
        } else {
            // Each hit written in place, as a C caller's buffer gets it
            // (`CTracer::intersect1_into` says why).
            for (r, h) in rays.iter().zip(out.iter_mut()) {
                match &mut ctx.tracer {
                    Some(t) => t.intersect1_into(r, h),
                    None => self.structure.intersect1_into(r, h, &mut ctx.stack),
                }
                .expect("valid call");
            }
        }
    }

    fn occluded_all(
        &self,
        rays: &[Ray],
        _: Option<&[usize]>,
        out: &mut [bool],
        ctx: &mut Self::Ctx,
        st: &mut TraceStats,
    ) {
        if self.calls == CCalls::Arrays {
            ctx.bytes.resize(rays.len(), 0);
            self.structure
                .occluded(rays, &mut ctx.bytes, &mut ctx.stack)
                .expect("valid call");
            for (o, b) in out.iter_mut().zip(&ctx.bytes) {
                *o = *b != 0;
            }
        } else {
            for (r, o) in rays.iter().zip(out.iter_mut()) {
                *o = self.occluded(r, None, ctx, st);
            }
        }
    }

    fn bounds(&self) -> Aabb {
        self.bounds
    }
}

/// Embree, one ray at a time or in packets of 8.
#[cfg(feature = "embree")]
pub struct EmbreeShooter<'a> {
    /// The scene.
    pub scene: &'a coray_embree::EmbreeScene,
    /// `rtcIntersect8` / `rtcOccluded8` for arrays of rays.
    pub packets: bool,
    /// The scene's box.
    pub bounds: Aabb,
}

#[cfg(feature = "embree")]
impl Shooter for EmbreeShooter<'_> {
    type Ctx = ();

    fn ctx(&self) {}

    fn intersect(&self, ray: &Ray, _: &mut (), st: &mut TraceStats) -> Hit {
        st.rays += 1;
        self.scene.intersect(ray)
    }

    fn occluded(&self, ray: &Ray, _: Option<usize>, _: &mut (), st: &mut TraceStats) -> bool {
        st.rays += 1;
        self.scene.occluded(ray)
    }

    fn intersect_all(&self, rays: &[Ray], out: &mut [Hit], _: &mut (), st: &mut TraceStats) {
        st.rays += rays.len() as u64;
        if self.packets {
            self.scene.intersect8(rays, out);
        } else {
            for (r, h) in rays.iter().zip(out.iter_mut()) {
                *h = self.scene.intersect(r);
            }
        }
    }

    fn occluded_all(
        &self,
        rays: &[Ray],
        _: Option<&[usize]>,
        out: &mut [bool],
        _: &mut (),
        st: &mut TraceStats,
    ) {
        st.rays += rays.len() as u64;
        if self.packets {
            self.scene.occluded8(rays, out);
        } else {
            for (r, o) in rays.iter().zip(out.iter_mut()) {
                *o = self.scene.occluded(r);
            }
        }
    }

    fn bounds(&self) -> Aabb {
        self.bounds
    }
}
