//! A kd-tree and a wide hierarchy built, opened and traced through the C
//! entry points, for Rust code that must pay exactly what a C caller pays
//! per call: `coray bench` times `kd-c` (one `coray_kdtree_intersect` /
//! `_occluded` call per array of rays) against `kd-c1` (one
//! `coray_kdtree_tracer_intersect1` / `_occluded1` call per ray on a tracer
//! per thread) and `kd-c1-handle` (one `coray_kdtree_intersect1` /
//! `_occluded1` call per ray with the handle and stack) with it, and
//! `wide-c` / `wide-c1` alike on the wide hierarchy. Safe to use: each
//! owns its arena and handle and hands the entry points only pointers it
//! made from live borrows.

use crate::saved::{aligned, build_arena, c_scene};
use crate::*;
use coray::{Hit, Ray, Scene};
use core::marker::PhantomData;
use std::vec::Vec;

/// A kd-tree in a C arena, opened: its handle points into the arena and
/// into the scene's arrays, which `'s` keeps alive and unchanged.
pub struct CKdTree<'s> {
    /// The arena (its heap buffer never moves while the tree lives).
    _arena: Vec<u128>,
    /// Its bytes, as `coray_kdtree_requirements` asked.
    arena_bytes: usize,
    handle: CorayKdTree,
    traversal: CorayTraversal,
    _scene: PhantomData<&'s Scene<'s>>,
}

/// A family's one-ray calls on its tracers, called directly (as a C
/// caller calls them).
pub trait TracerCalls {
    /// `coray_<family>_tracer_intersect1`.
    ///
    /// # Safety
    /// As that entry point.
    unsafe fn intersect1(t: *mut CorayTracer, r: *const CorayRay, h: *mut CorayHit) -> CorayStatus;
    /// `coray_<family>_tracer_occluded1`.
    ///
    /// # Safety
    /// As that entry point.
    unsafe fn occluded1(t: *mut CorayTracer, r: *const CorayRay, o: *mut u8) -> CorayStatus;
}

/// The kd-tree's tracer calls.
pub struct KdCalls;

impl TracerCalls for KdCalls {
    #[inline(always)]
    unsafe fn intersect1(t: *mut CorayTracer, r: *const CorayRay, h: *mut CorayHit) -> CorayStatus {
        // SAFETY: forwarded contract.
        unsafe { coray_kdtree_tracer_intersect1(t, r, h) }
    }
    #[inline(always)]
    unsafe fn occluded1(t: *mut CorayTracer, r: *const CorayRay, o: *mut u8) -> CorayStatus {
        // SAFETY: forwarded contract.
        unsafe { coray_kdtree_tracer_occluded1(t, r, o) }
    }
}

/// The wide hierarchy's tracer calls.
pub struct WideCalls;

impl TracerCalls for WideCalls {
    #[inline(always)]
    unsafe fn intersect1(t: *mut CorayTracer, r: *const CorayRay, h: *mut CorayHit) -> CorayStatus {
        // SAFETY: forwarded contract.
        unsafe { coray_wide_tracer_intersect1(t, r, h) }
    }
    #[inline(always)]
    unsafe fn occluded1(t: *mut CorayTracer, r: *const CorayRay, o: *mut u8) -> CorayStatus {
        // SAFETY: forwarded contract.
        unsafe { coray_wide_tracer_occluded1(t, r, o) }
    }
}

/// One thread's tracer on a [`CKdTree`] (`coray_kdtree_tracer`) or a
/// [`CWide`] (`coray_wide_tracer`) with its own stack: the family's
/// (`F`) `_tracer_intersect1` / `_occluded1` per ray. Both live on the
/// heap, so that moving this value moves neither (a tracer's address is
/// part of its check).
pub struct CTracer<'t, F> {
    tracer: std::boxed::Box<CorayTracer>,
    _stack: Vec<u128>,
    _structure: PhantomData<(&'t (), F)>,
}

impl<F: TracerCalls> CTracer<'_, F> {
    /// Makes a tracer with `make` (given the stack and its bytes, and the
    /// tracer to fill).
    fn new(
        stack_bytes: usize,
        make: impl FnOnce(*mut u128, usize, &mut CorayTracer) -> CorayStatus,
    ) -> Result<Self, CorayStatus> {
        let mut t = CTracer {
            tracer: std::boxed::Box::new(CorayTracer { opaque: [0; 32] }),
            _stack: aligned(stack_bytes),
            _structure: PhantomData,
        };
        let s = make(t._stack.as_mut_ptr(), stack_bytes, &mut t.tracer);
        status(s).map(|()| t)
    }

    /// The closest hit of `ray` by one `_tracer_intersect1` call.
    pub fn intersect1(&mut self, ray: &Ray) -> Result<Hit, CorayStatus> {
        let mut hit = Hit::MISS;
        self.intersect1_into(ray, &mut hit).map(|()| hit)
    }

    /// The closest hit of `ray` by one `_tracer_intersect1` call, written
    /// into `hit`, as a C caller traces into its own hit buffer (on an
    /// error `hit` is unchanged). A caller that reads the hit back whole
    /// right after the call waits on the store (its loads span the call's
    /// stores): about a third of a missing ray's call on x86-64, so `coray
    /// bench` writes in place, as the array calls do.
    pub fn intersect1_into(&mut self, ray: &Ray, hit: &mut Hit) -> Result<(), CorayStatus> {
        // SAFETY: the tracer was made on a structure borrowed for 't (its
        // handle, arena and scene in place) with the stack owned here, by
        // the family whose call this is; Ray and CorayRay, Hit and
        // CorayHit share their layout (abi.rs); `hit` is a unique borrow,
        // written whole when the call succeeds.
        let s = unsafe {
            F::intersect1(
                &mut *self.tracer,
                (ray as *const Ray).cast(),
                (hit as *mut Hit).cast(),
            )
        };
        status(s)
    }

    /// Whether something blocks `ray`, by one `_tracer_occluded1` call.
    pub fn occluded1(&mut self, ray: &Ray) -> Result<bool, CorayStatus> {
        let mut o = 0u8;
        // SAFETY: as in `intersect1`, with one byte.
        let s = unsafe { F::occluded1(&mut *self.tracer, (ray as *const Ray).cast(), &mut o) };
        status(s).map(|()| o != 0)
    }

    /// The tracer's statistics so far (`coray_tracer_stats`).
    pub fn stats(&self) -> Result<CorayTraceStats, CorayStatus> {
        let mut st = CorayTraceStats {
            struct_size: core::mem::size_of::<CorayTraceStats>(),
            ..Default::default()
        };
        // SAFETY: the tracer is live; st is a local with its size set.
        let s = unsafe { coray_tracer_stats(&*self.tracer, &mut st) };
        status(s).map(|()| st)
    }
}

impl<'s> CKdTree<'s> {
    /// Builds a tree on `scene` with `preset` (`CORAY_KD_PRESET_*`) and
    /// `omit_ropes` (`CorayKdParams::omit_ropes`) and opens it, to be
    /// traced by `traversal` (`CORAY_TRAVERSAL_*`).
    pub fn new(
        scene: &Scene<'s>,
        preset: CorayKdPreset,
        omit_ropes: u32,
        traversal: CorayTraversal,
    ) -> Result<CKdTree<'s>, CorayStatus> {
        let (arena, bytes) = build_arena(scene, preset, omit_ropes)?;
        let c = c_scene(scene);
        let mut handle = CorayKdTree { opaque: [0; 32] };
        // SAFETY: the arena was just built (16-byte aligned, `bytes` long)
        // and is kept with the handle; c points to `scene`'s arrays, which
        // outlive 's; handle is a live local.
        let s = unsafe { coray_kdtree_open(arena.as_ptr().cast(), bytes, &c, &mut handle) };
        if s != CorayStatus::Ok {
            return Err(s);
        }
        Ok(CKdTree {
            _arena: arena,
            arena_bytes: bytes,
            handle,
            traversal,
            _scene: PhantomData,
        })
    }

    /// The arena's bytes.
    pub fn arena_bytes(&self) -> usize {
        self.arena_bytes
    }
}

/// A wide hierarchy in a C arena (`coray_wide_build`, default
/// parameters), opened: its handle points into the arena and into the
/// scene's arrays, which `'s` keeps alive and unchanged.
pub struct CWide<'s> {
    /// The arena (its heap buffer never moves while the hierarchy lives).
    _arena: Vec<u128>,
    handle: CorayWide,
    /// Bytes of the arena the hierarchy uses (`arena_bytes_used`).
    arena_bytes: usize,
    /// Stack bytes a trace call needs (`CorayWideInfo::stack_bytes`).
    stack_bytes: usize,
    _scene: PhantomData<&'s Scene<'s>>,
}

impl<'s> CWide<'s> {
    /// Builds the hierarchy on `scene` with `coray_wide_params_default()`
    /// and opens it.
    pub fn new(scene: &Scene<'s>) -> Result<CWide<'s>, CorayStatus> {
        let params = coray_wide_params_default();
        let c = c_scene(scene);
        let mut req = coray_requirements_default();
        // SAFETY: params and req are live locals with struct_size set.
        status(unsafe { coray_wide_requirements(scene.prim_count(), &params, &mut req) })?;
        let mut arena = aligned(req.arena_bytes);
        let mut scratch = aligned(req.scratch_bytes);
        // SAFETY: c's arrays are `scene`'s, live for the call; arena and
        // scratch are 16-byte aligned and at least as long as passed.
        status(unsafe {
            coray_wide_build(
                &c,
                &params,
                arena.as_mut_ptr().cast(),
                req.arena_bytes,
                scratch.as_mut_ptr().cast(),
                req.scratch_bytes,
                core::ptr::null_mut(),
            )
        })?;
        let mut handle = CorayWide { opaque: [0; 32] };
        // SAFETY: the arena was just built and is kept with the handle; c
        // points to `scene`'s arrays, which outlive 's; handle is a local.
        status(unsafe {
            coray_wide_open(arena.as_ptr().cast(), req.arena_bytes, &c, &mut handle)
        })?;
        let mut info = coray_wide_info_default();
        // SAFETY: the handle was just opened; info is a local, size set.
        status(unsafe { coray_wide_info(&handle, &mut info) })?;
        Ok(CWide {
            _arena: arena,
            handle,
            arena_bytes: info.arena_bytes_used,
            stack_bytes: info.stack_bytes,
            _scene: PhantomData,
        })
    }

    /// The arena's bytes the hierarchy uses.
    pub fn arena_bytes(&self) -> usize {
        self.arena_bytes
    }
}

/// What `coray bench`'s C methods call on a structure opened through the
/// C ABI ([`CKdTree`], [`CWide`]): array calls, one-ray calls with the
/// handle (on a stack from [`CStructure::stack`]), and tracers.
pub trait CStructure {
    /// The family's tracer calls.
    type Calls: TracerCalls;
    /// One thread's traversal stack for the handle's calls, 16-byte
    /// aligned.
    fn stack(&self) -> Vec<u128>;
    /// A tracer with a stack of its own.
    fn tracer(&self) -> Result<CTracer<'_, Self::Calls>, CorayStatus>;
    /// Closest hits of `rays`, one array call.
    fn intersect(
        &self,
        rays: &[Ray],
        hits: &mut [Hit],
        stack: &mut [u128],
    ) -> Result<(), CorayStatus>;
    /// Any-hit answers (1 blocked, 0 free), one array call.
    fn occluded(&self, rays: &[Ray], out: &mut [u8], stack: &mut [u128])
        -> Result<(), CorayStatus>;
    /// The closest hit of one ray, one call with the handle.
    fn intersect1(&self, ray: &Ray, stack: &mut [u128]) -> Result<Hit, CorayStatus> {
        let mut hit = Hit::MISS;
        self.intersect1_into(ray, &mut hit, stack).map(|()| hit)
    }
    /// The closest hit of one ray, one call with the handle, written into
    /// `hit` (unchanged on an error; see [`CTracer::intersect1_into`]).
    fn intersect1_into(
        &self,
        ray: &Ray,
        hit: &mut Hit,
        stack: &mut [u128],
    ) -> Result<(), CorayStatus>;
    /// Whether something blocks one ray, one call with the handle.
    fn occluded1(&self, ray: &Ray, stack: &mut [u128]) -> Result<bool, CorayStatus>;
}

impl CStructure for CKdTree<'_> {
    type Calls = KdCalls;

    fn stack(&self) -> Vec<u128> {
        aligned(CORAY_KDTREE_STACK_BYTES)
    }

    /// A tracer on this tree by its traversal.
    fn tracer(&self) -> Result<CTracer<'_, KdCalls>, CorayStatus> {
        CTracer::new(CORAY_KDTREE_STACK_BYTES, |stack, bytes, tracer| {
            // SAFETY: the handle is this tree's (its arena and scene
            // alive for the borrow the tracer keeps); the stack is
            // 16-byte aligned and as long as passed; the tracer is a
            // live heap value.
            unsafe {
                coray_kdtree_tracer(&self.handle, self.traversal, stack.cast(), bytes, tracer)
            }
        })
    }

    /// By one `coray_kdtree_intersect` call.
    fn intersect(
        &self,
        rays: &[Ray],
        hits: &mut [Hit],
        stack: &mut [u128],
    ) -> Result<(), CorayStatus> {
        let n = rays.len().min(hits.len());
        // SAFETY: Ray and CorayRay, Hit and CorayHit share their layout
        // (asserted in abi.rs); both arrays hold at least n elements and
        // are disjoint borrows; the handle is this tree's, its arena and
        // scene alive ('s); the stack is 16-byte aligned, its bytes
        // passed.
        status(unsafe {
            coray_kdtree_intersect(
                &self.handle,
                self.traversal,
                rays.as_ptr().cast(),
                hits.as_mut_ptr().cast(),
                n,
                stack.as_mut_ptr().cast(),
                size_of_val(stack),
                core::ptr::null_mut(),
            )
        })
    }

    /// By one `coray_kdtree_occluded` call.
    fn occluded(
        &self,
        rays: &[Ray],
        out: &mut [u8],
        stack: &mut [u128],
    ) -> Result<(), CorayStatus> {
        let n = rays.len().min(out.len());
        // SAFETY: as in `intersect`, with `out` holding at least n bytes.
        status(unsafe {
            coray_kdtree_occluded(
                &self.handle,
                self.traversal,
                rays.as_ptr().cast(),
                out.as_mut_ptr(),
                n,
                stack.as_mut_ptr().cast(),
                size_of_val(stack),
                core::ptr::null_mut(),
            )
        })
    }

    /// By one `coray_kdtree_intersect1` call.
    fn intersect1_into(
        &self,
        ray: &Ray,
        hit: &mut Hit,
        stack: &mut [u128],
    ) -> Result<(), CorayStatus> {
        // SAFETY: as in `intersect`, for one ray and one hit (a unique
        // borrow).
        status(unsafe {
            coray_kdtree_intersect1(
                &self.handle,
                self.traversal,
                (ray as *const Ray).cast(),
                (hit as *mut Hit).cast(),
                stack.as_mut_ptr().cast(),
                size_of_val(stack),
                core::ptr::null_mut(),
            )
        })
    }

    /// By one `coray_kdtree_occluded1` call.
    fn occluded1(&self, ray: &Ray, stack: &mut [u128]) -> Result<bool, CorayStatus> {
        let mut out = 0u8;
        // SAFETY: as in `intersect`, for one ray and one byte (a local).
        let s = unsafe {
            coray_kdtree_occluded1(
                &self.handle,
                self.traversal,
                (ray as *const Ray).cast(),
                &mut out,
                stack.as_mut_ptr().cast(),
                size_of_val(stack),
                core::ptr::null_mut(),
            )
        };
        status(s).map(|()| out != 0)
    }
}

impl CStructure for CWide<'_> {
    type Calls = WideCalls;

    /// Its `stack_bytes`.
    fn stack(&self) -> Vec<u128> {
        aligned(self.stack_bytes)
    }

    fn tracer(&self) -> Result<CTracer<'_, WideCalls>, CorayStatus> {
        CTracer::new(self.stack_bytes, |stack, bytes, tracer| {
            // SAFETY: the handle is this hierarchy's (its arena and scene
            // alive for the borrow the tracer keeps); the stack is 16-byte
            // aligned and as long as passed; the tracer is a live heap
            // value.
            unsafe { coray_wide_tracer(&self.handle, stack.cast(), bytes, tracer) }
        })
    }

    /// By one `coray_wide_intersect` call.
    fn intersect(
        &self,
        rays: &[Ray],
        hits: &mut [Hit],
        stack: &mut [u128],
    ) -> Result<(), CorayStatus> {
        let n = rays.len().min(hits.len());
        // SAFETY: as CKdTree's, on this hierarchy's handle.
        status(unsafe {
            coray_wide_intersect(
                &self.handle,
                rays.as_ptr().cast(),
                hits.as_mut_ptr().cast(),
                n,
                stack.as_mut_ptr().cast(),
                size_of_val(stack),
                core::ptr::null_mut(),
            )
        })
    }

    /// By one `coray_wide_occluded` call.
    fn occluded(
        &self,
        rays: &[Ray],
        out: &mut [u8],
        stack: &mut [u128],
    ) -> Result<(), CorayStatus> {
        let n = rays.len().min(out.len());
        // SAFETY: as in `intersect`, with `out` holding at least n bytes.
        status(unsafe {
            coray_wide_occluded(
                &self.handle,
                rays.as_ptr().cast(),
                out.as_mut_ptr(),
                n,
                stack.as_mut_ptr().cast(),
                size_of_val(stack),
                core::ptr::null_mut(),
            )
        })
    }

    /// By one `coray_wide_intersect1` call.
    fn intersect1_into(
        &self,
        ray: &Ray,
        hit: &mut Hit,
        stack: &mut [u128],
    ) -> Result<(), CorayStatus> {
        // SAFETY: as in `intersect`, for one ray and one hit (a unique
        // borrow).
        status(unsafe {
            coray_wide_intersect1(
                &self.handle,
                (ray as *const Ray).cast(),
                (hit as *mut Hit).cast(),
                stack.as_mut_ptr().cast(),
                size_of_val(stack),
                core::ptr::null_mut(),
            )
        })
    }

    /// By one `coray_wide_occluded1` call.
    fn occluded1(&self, ray: &Ray, stack: &mut [u128]) -> Result<bool, CorayStatus> {
        let mut out = 0u8;
        // SAFETY: as in `intersect`, for one ray and one byte (a local).
        let s = unsafe {
            coray_wide_occluded1(
                &self.handle,
                (ray as *const Ray).cast(),
                &mut out,
                stack.as_mut_ptr().cast(),
                size_of_val(stack),
                core::ptr::null_mut(),
            )
        };
        status(s).map(|()| out != 0)
    }
}

fn status(s: CorayStatus) -> Result<(), CorayStatus> {
    match s {
        CorayStatus::Ok => Ok(()),
        e => Err(e),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use coray::kd::{KdParams, Traversal};
    use coray::owned::OwnedKd;
    use coray::{Sphere, Vec3};

    /// Every call of the wrappers answers as the core's kd-tree does on the
    /// same scene, for closest and any hits, arrays and single rays, on the
    /// kd-tree and on the wide hierarchy.
    #[test]
    fn the_c_calls_answer_as_the_core() {
        let vertices = [
            [0.0, 0.0, 5.0],
            [4.0, 0.0, 5.0],
            [0.0, 4.0, 5.0],
            [4.0, 4.0, 6.0],
        ];
        let triangles = [[0, 1, 2], [1, 3, 2]];
        let spheres = [Sphere {
            center: [1.0, 1.0, 2.0],
            radius: 0.5,
        }];
        let scene = Scene {
            vertices: &vertices,
            triangles: &triangles,
            spheres: &spheres,
            cones: &[],
        };
        let rays: Vec<Ray> = (0..40)
            .map(|i| {
                let (x, y) = ((i % 8) as f32 * 0.6 - 0.5, (i / 8) as f32 * 0.9 - 0.5);
                Ray::new(Vec3::new(x, y, 0.0), Vec3::new(0.0, 0.0, 1.0), 0.0, 1e30)
            })
            .collect();
        let owned = OwnedKd::new(&scene, &KdParams::auto()).expect("build");
        let core = owned.tree(scene).expect("tree");
        let mut st = coray::TraceStats::default();
        let mut core_stack = coray::owned::stack(coray::kd::KD_STACK_LEN);
        let want: Vec<Hit> = rays
            .iter()
            .map(|r| core.intersect(r, Traversal::Hierarchical, &mut core_stack, &mut st))
            .collect();
        assert!(want.iter().any(|h| h.is_hit()) && want.iter().any(|h| !h.is_hit()));
        // With ropes for rope traversal, without for the others, and compact.
        for (traversal, omit_ropes) in [
            (CORAY_TRAVERSAL_HIERARCHICAL, 1),
            (CORAY_TRAVERSAL_ROPES, 0),
            (CORAY_TRAVERSAL_PACKETS, 1),
            (CORAY_TRAVERSAL_HIERARCHICAL, 2),
            (CORAY_TRAVERSAL_PACKETS, 2),
        ] {
            let t =
                CKdTree::new(&scene, CORAY_KD_PRESET_AUTO, omit_ropes, traversal).expect("open");
            let mut stack = t.stack();
            let mut hits = std::vec![Hit::MISS; rays.len()];
            t.intersect(&rays, &mut hits, &mut stack)
                .expect("array call");
            let mut occ = std::vec![0u8; rays.len()];
            t.occluded(&rays, &mut occ, &mut stack).expect("array call");
            for (i, r) in rays.iter().enumerate() {
                let one = t.intersect1(r, &mut stack).expect("one-ray call");
                assert_eq!((hits[i].prim_id, hits[i].t), (want[i].prim_id, want[i].t));
                assert_eq!((one.prim_id, one.t), (want[i].prim_id, want[i].t));
                assert_eq!(occ[i] != 0, want[i].is_hit());
                assert_eq!(t.occluded1(r, &mut stack), Ok(want[i].is_hit()));
            }
            let mut tr = t.tracer().expect("tracer");
            for (i, r) in rays.iter().enumerate() {
                let one = tr.intersect1(r).expect("tracer call");
                assert_eq!((one.prim_id, one.t), (want[i].prim_id, want[i].t));
                assert_eq!(tr.occluded1(r), Ok(want[i].is_hit()));
            }
            assert_eq!(tr.stats().expect("statistics").rays, 2 * rays.len() as u64);
        }
        // The wide hierarchy: arrays and its tracer.
        let w = CWide::new(&scene).expect("wide build and open");
        let mut stack = w.stack();
        let mut hits = std::vec![Hit::MISS; rays.len()];
        w.intersect(&rays, &mut hits, &mut stack)
            .expect("array call");
        let mut occ = std::vec![0u8; rays.len()];
        w.occluded(&rays, &mut occ, &mut stack).expect("array call");
        let mut tr = w.tracer().expect("tracer");
        for (i, r) in rays.iter().enumerate() {
            assert_eq!((hits[i].prim_id, hits[i].t), (want[i].prim_id, want[i].t));
            assert_eq!(occ[i] != 0, want[i].is_hit());
            let one = w.intersect1(r, &mut stack).expect("one-ray call");
            assert_eq!((one.prim_id, one.t), (want[i].prim_id, want[i].t));
            assert_eq!(w.occluded1(r, &mut stack), Ok(want[i].is_hit()));
            let one = tr.intersect1(r).expect("tracer call");
            assert_eq!((one.prim_id, one.t), (want[i].prim_id, want[i].t));
            assert_eq!(tr.occluded1(r), Ok(want[i].is_hit()));
        }
        assert_eq!(tr.stats().expect("statistics").rays, 2 * rays.len() as u64);
    }
}
