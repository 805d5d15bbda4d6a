//! Run-time choice of the packet and LCTS window kernels: the core
//! compiles them twice, for the baseline of the target and with AVX2
//! (`KdTree::intersect_packets_avx2`, `lcts::window::trace_avx2`); here
//! the CPU is asked which one may run. The only `unsafe` is the call of an
//! AVX2 clone, after the check. The bare build (no std) has no detection
//! and runs the baseline. `CORAY_NO_AVX2` in the environment (any value)
//! keeps a process on the baseline: for tools that do not decode every
//! AVX instruction (Debian 12's valgrind 3.19 stops at a `vmovq` between
//! registers in the LCTS window kernel).

use coray::kd::{KdStackItem, KdTree};
use coray::lcts::guide::Paths;
use coray::lcts::window::{self, Baseline, Kernel, Shaft};
use coray::lcts::{CastStats, ImageScratch, PixelRect, Scheme};
use coray::wide::{WideBvh, WideStackItem};
use coray::{Camera, Error, Hit, Ray, TraceStats};

/// Whether this CPU runs the AVX2 kernels and the environment lets them
/// (no `CORAY_NO_AVX2`); asked once per process.
#[inline]
pub fn has_avx2() -> bool {
    #[cfg(all(feature = "std", target_arch = "x86_64"))]
    {
        static CHOICE: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
        *CHOICE.get_or_init(|| {
            avx2_allowed(
                std::env::var_os("CORAY_NO_AVX2").is_some(),
                cpu_has_avx2_set(),
            )
        })
    }
    #[cfg(not(all(feature = "std", target_arch = "x86_64")))]
    {
        false
    }
}

/// Whether the CPU runs every feature the AVX2 kernels are compiled for:
/// AVX2 and the bit instructions every AVX2 CPU has (BMI1, BMI2, LZCNT,
/// POPCNT: x86-64-v3's integer part).
#[cfg(all(feature = "std", target_arch = "x86_64"))]
fn cpu_has_avx2_set() -> bool {
    std::is_x86_feature_detected!("avx2")
        && std::is_x86_feature_detected!("bmi1")
        && std::is_x86_feature_detected!("bmi2")
        && std::is_x86_feature_detected!("lzcnt")
        && std::is_x86_feature_detected!("popcnt")
}

/// The AVX2 kernels run when the CPU has AVX2 and the caller did not opt
/// out.
#[cfg_attr(not(all(feature = "std", target_arch = "x86_64")), allow(dead_code))]
fn avx2_allowed(opted_out: bool, cpu_has_avx2: bool) -> bool {
    cpu_has_avx2 && !opted_out
}

/// [`KdTree::intersect_packets`] with the widest kernel this CPU runs.
///
/// # Panics
/// As [`KdTree::intersect_packets`].
pub fn intersect_packets(
    t: &KdTree,
    rays: &[Ray],
    hits: &mut [Hit],
    stack: &mut [KdStackItem],
    stats: &mut TraceStats,
) {
    #[cfg(all(feature = "std", target_arch = "x86_64"))]
    if has_avx2() {
        // SAFETY: the CPU has AVX2 (checked just above), the only feature
        // the clone is compiled for; otherwise it is a safe function.
        unsafe { t.intersect_packets_avx2(rays, hits, stack, stats) };
        return;
    }
    t.intersect_packets(rays, hits, stack, stats);
}

/// [`KdTree::occluded_packets`] with the widest kernel this CPU runs.
///
/// # Panics
/// As [`KdTree::occluded_packets`].
pub fn occluded_packets(
    t: &KdTree,
    rays: &[Ray],
    occluded: &mut [bool],
    stack: &mut [KdStackItem],
    stats: &mut TraceStats,
) {
    #[cfg(all(feature = "std", target_arch = "x86_64"))]
    if has_avx2() {
        // SAFETY: as in intersect_packets.
        unsafe { t.occluded_packets_avx2(rays, occluded, stack, stats) };
        return;
    }
    t.occluded_packets(rays, occluded, stack, stats);
}

/// [`WideBvh::intersect`] with the widest kernel this CPU runs.
#[inline]
pub fn wide_intersect(
    w: &WideBvh,
    ray: &Ray,
    stack: &mut [WideStackItem],
    stats: &mut TraceStats,
) -> Hit {
    #[cfg(all(feature = "std", target_arch = "x86_64"))]
    if has_avx2() {
        // SAFETY: the CPU has AVX2 (checked just above), the only feature
        // the clone is compiled for; otherwise it is a safe function.
        return unsafe { w.intersect_avx2(ray, stack, stats) };
    }
    w.intersect(ray, stack, stats)
}

/// [`WideBvh::occluded`] with the widest kernel this CPU runs.
#[inline]
pub fn wide_occluded(
    w: &WideBvh,
    ray: &Ray,
    stack: &mut [WideStackItem],
    stats: &mut TraceStats,
) -> bool {
    #[cfg(all(feature = "std", target_arch = "x86_64"))]
    if has_avx2() {
        // SAFETY: as in wide_intersect.
        return unsafe { w.occluded_avx2(ray, stack, stats) };
    }
    w.occluded(ray, stack, stats)
}

/// Closest hits of `rays` into `hits` in packets of eight coherent rays
/// where this CPU runs the packet kernel (AVX2), ray by ray otherwise: each
/// hit [`WideBvh::intersect`]'s.
///
/// # Panics
/// When `hits` is shorter than `rays`.
pub fn wide_intersect_packets(
    w: &WideBvh,
    rays: &[Ray],
    hits: &mut [Hit],
    stack: &mut [WideStackItem],
    stats: &mut TraceStats,
) {
    #[cfg(all(feature = "std", target_arch = "x86_64"))]
    if has_avx2() {
        // SAFETY: the CPU runs the kernel's features (checked just above);
        // otherwise it is a safe function.
        unsafe { w.intersect_packets_avx2(rays, hits, stack, stats) };
        return;
    }
    for (r, h) in rays.iter().zip(&mut hits[..rays.len()]) {
        *h = w.intersect(r, stack, stats);
    }
}

/// Any-hit answers of `rays` into `occluded`, in packets as
/// [`wide_intersect_packets`].
///
/// # Panics
/// When `occluded` is shorter than `rays`.
pub fn wide_occluded_packets(
    w: &WideBvh,
    rays: &[Ray],
    occluded: &mut [bool],
    stack: &mut [WideStackItem],
    stats: &mut TraceStats,
) {
    #[cfg(all(feature = "std", target_arch = "x86_64"))]
    if has_avx2() {
        // SAFETY: as in wide_intersect_packets.
        unsafe { w.occluded_packets_avx2(rays, occluded, stack, stats) };
        return;
    }
    for (r, o) in rays.iter().zip(&mut occluded[..rays.len()]) {
        *o = w.occluded(r, stack, stats);
    }
}

/// The LCTS window trace's AVX2 clone (`coray::lcts::window::trace_avx2`)
/// as a cast's kernel. Only [`Avx2Windows::detect`] makes one, on a CPU
/// with AVX2.
#[derive(Clone, Copy, Debug)]
pub struct Avx2Windows(());

impl Avx2Windows {
    /// The kernel, when this CPU runs AVX2.
    pub fn detect() -> Option<Avx2Windows> {
        has_avx2().then_some(Avx2Windows(()))
    }
}

impl Kernel for Avx2Windows {
    #[inline(always)]
    fn trace(
        self,
        tree: &KdTree,
        shaft: Shaft,
        paths: &Paths,
        rays: &[Ray],
        nearest: &[usize],
        hits: &mut [Hit],
        stack: &mut [KdStackItem],
        stats: &mut TraceStats,
    ) {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: an `Avx2Windows` exists only where `detect` found AVX2
        // (its field is private), the only feature the clone is compiled
        // for; otherwise it is a safe function.
        unsafe {
            window::trace_avx2(tree, shaft, paths, rays, nearest, hits, stack, stats)
        };
        #[cfg(not(target_arch = "x86_64"))]
        window::trace(tree, shaft, paths, rays, nearest, hits, stack, stats);
    }

    #[inline(always)]
    fn packets(
        self,
        tree: &KdTree,
        rays: &[Ray],
        hits: &mut [Hit],
        stack: &mut [KdStackItem],
        stats: &mut TraceStats,
    ) {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: as in `trace` just above: an `Avx2Windows` exists only
        // on a CPU with AVX2, the only feature the clone is compiled for.
        unsafe {
            tree.intersect_packets_avx2(rays, hits, stack, stats)
        };
        #[cfg(not(target_arch = "x86_64"))]
        tree.intersect_packets(rays, hits, stack, stats);
    }
}

/// [`coray::lcts::cast_image_with`] with the widest window kernel this CPU
/// runs (chosen once, before the cast).
pub fn cast_image_with(
    tree: &KdTree,
    camera: &Camera,
    scheme: Scheme,
    scratch: ImageScratch,
    put: impl FnMut(u32, u32, &Hit),
) -> Result<CastStats, Error> {
    match Avx2Windows::detect() {
        Some(k) => coray::lcts::cast_image_with_by(k, tree, camera, scheme, scratch, put),
        None => coray::lcts::cast_image_with_by(Baseline, tree, camera, scheme, scratch, put),
    }
}

/// [`coray::lcts::cast_rect_with_by`] with the widest window kernel this
/// CPU runs (chosen once, before the cast).
pub fn cast_rect_with(
    tree: &KdTree,
    camera: &Camera,
    rect: PixelRect,
    scheme: Scheme,
    scratch: ImageScratch,
    put: impl FnMut(u32, u32, &Hit),
) -> Result<CastStats, Error> {
    match Avx2Windows::detect() {
        Some(k) => coray::lcts::cast_rect_with_by(k, tree, camera, rect, scheme, scratch, put),
        None => coray::lcts::cast_rect_with_by(Baseline, tree, camera, rect, scheme, scratch, put),
    }
}

/// [`coray::lcts::cast_image`] with the widest window kernel this CPU runs.
pub fn cast_image(
    tree: &KdTree,
    camera: &Camera,
    scheme: Scheme,
    scratch: ImageScratch,
    hits: &mut [Hit],
) -> Result<CastStats, Error> {
    match Avx2Windows::detect() {
        Some(k) => coray::lcts::cast_image_by(k, tree, camera, scheme, scratch, hits),
        None => coray::lcts::cast_image_by(Baseline, tree, camera, scheme, scratch, hits),
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use coray::kd::{KdParams, Traversal, KD_STACK_LEN};
    use std::{vec, vec::Vec};

    /// A scene of `triangles` over `vertices`.
    fn scene_of<'a>(vertices: &'a [[f32; 3]], triangles: &'a [[u32; 3]]) -> coray::Scene<'a> {
        coray::Scene {
            vertices,
            triangles,
            spheres: &[],
            cones: &[],
        }
    }

    /// 400 random small triangles around the origin.
    fn random_triangles() -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
        let mut g = coray::rng::SplitMix64(5);
        let mut v = Vec::new();
        let mut tris = Vec::new();
        for i in 0..400u32 {
            let c = [
                g.next_f32() * 4.0 - 2.0,
                g.next_f32() * 4.0 - 2.0,
                g.next_f32() * 4.0 - 2.0,
            ];
            for _ in 0..3 {
                v.push([
                    c[0] + g.next_f32() * 0.3,
                    c[1] + g.next_f32() * 0.3,
                    c[2] + g.next_f32() * 0.3,
                ]);
            }
            tris.push([3 * i, 3 * i + 1, 3 * i + 2]);
        }
        (v, tris)
    }

    #[test]
    fn coray_no_avx2_keeps_the_baseline() {
        assert!(avx2_allowed(false, true));
        assert!(!avx2_allowed(true, true));
        assert!(!avx2_allowed(false, false));
        // This process's choice is its environment's and its CPU's.
        #[cfg(target_arch = "x86_64")]
        assert_eq!(
            has_avx2(),
            std::env::var_os("CORAY_NO_AVX2").is_none() && cpu_has_avx2_set()
        );
    }

    /// The AVX2 clone (where this CPU has it) gives the baseline's hits
    /// and answers, bit for bit, on camera rays of a random scene.
    #[test]
    fn dispatched_kernels_agree_with_the_baseline() {
        let (v, tris) = random_triangles();
        let scene = scene_of(&v, &tris);
        let kd = coray::owned::OwnedKd::new(&scene, &KdParams::auto()).unwrap();
        let t = kd.tree(scene).unwrap();
        let rays: Vec<Ray> = (0..64 * 64)
            .map(|k| {
                let (x, y) = ((k % 64) as f32 / 64.0 - 0.5, (k / 64) as f32 / 64.0 - 0.5);
                Ray::new(
                    coray::Vec3::new(0.0, 0.0, 8.0),
                    coray::Vec3::new(x, y, -1.0),
                    0.0,
                    f32::INFINITY,
                )
            })
            .collect();
        let mut stack = vec![KdStackItem::default(); KD_STACK_LEN];
        let mut st = TraceStats::default();
        let (mut a, mut b) = (vec![Hit::MISS; rays.len()], vec![Hit::MISS; rays.len()]);
        t.intersect_packets(&rays, &mut a, &mut stack, &mut st);
        intersect_packets(&t, &rays, &mut b, &mut stack, &mut st);
        assert_eq!(a, b);
        assert!(a.iter().filter(|h| h.is_hit()).count() > 100);
        let (mut oa, mut ob) = (vec![false; rays.len()], vec![false; rays.len()]);
        t.occluded_packets(&rays, &mut oa, &mut stack, &mut st);
        occluded_packets(&t, &rays, &mut ob, &mut stack, &mut st);
        assert_eq!(oa, ob);
        let mut c = vec![Hit::MISS; rays.len()];
        for (r, h) in rays.iter().zip(c.iter_mut()) {
            *h = t.intersect(r, Traversal::Hierarchical, &mut stack, &mut st);
        }
        assert_eq!(a, c);
    }

    /// Every LCTS cast by the AVX2 window kernel (where this CPU has it),
    /// and the packet cast by the AVX2 packet walk, gives the baseline
    /// kernel's hits and counts, bit for bit, and the hierarchical cast's
    /// hits.
    #[test]
    fn avx2_window_kernel_casts_as_the_baseline() {
        use coray::lcts::{cast_image_by, image_requirements};
        let Some(avx2) = Avx2Windows::detect() else {
            return;
        };
        let (v, tris) = random_triangles();
        let scene = scene_of(&v, &tris);
        let kd = coray::owned::OwnedKd::new(&scene, &KdParams::auto_with_ropes()).unwrap();
        let t = kd.tree(scene).unwrap();
        let cam = Camera {
            from: coray::Vec3::new(0.5, 1.0, 4.0),
            at: coray::Vec3::ZERO,
            up: coray::Vec3::Y,
            angle_deg: 50.0,
            width: 96,
            height: 80,
        };
        let n = (cam.width * cam.height) as usize;
        let cast = |scheme: Scheme, by_avx2: bool| {
            let mut room = coray::owned::OwnedCast::new(&image_requirements(
                cam.width, cam.height, scheme, 256,
            ));
            let mut hits = vec![Hit::MISS; n];
            let st = if by_avx2 {
                cast_image_by(avx2, &t, &cam, scheme, room.scratch(), &mut hits)
            } else {
                cast_image_by(Baseline, &t, &cam, scheme, room.scratch(), &mut hits)
            }
            .unwrap();
            (hits, st)
        };
        let (want, _) = cast(Scheme::Hierarchical, false);
        let hit = want.iter().filter(|h| h.is_hit()).count();
        assert!(hit > 500, "{hit} hits");
        for scheme in [
            Scheme::Slcts1d { n: 5 },
            Scheme::Slcts2d { n: 5, m: 5 },
            Scheme::Hlcts1d,
            Scheme::Hlcts2d,
        ] {
            let (a, sa) = cast(scheme, false);
            let (b, sb) = cast(scheme, true);
            assert_eq!(a, b, "{scheme:?}");
            assert_eq!(sa.trace, sb.trace, "{scheme:?}");
            assert_eq!(a, want, "{scheme:?}");
            assert!(sb.windows_shared > 0, "{scheme:?}");
        }
        // The packet tiles, by the AVX2 packet clone: 96 x 80 pixels, all
        // of them in full 4 x 2 tiles.
        let (a, sa) = cast(Scheme::Packets, false);
        let (b, sb) = cast(Scheme::Packets, true);
        assert_eq!(a, b);
        assert_eq!(sa.trace, sb.trace);
        assert_eq!(a, want);
        assert_eq!(sb.trace.rays, n as u64);
    }
}
