//! Run-time choice of the packet kernels: the core compiles them twice,
//! for the baseline of the target and with AVX2
//! (`KdTree::intersect_packets_avx2`); here the CPU is asked once per call
//! which one may run. The only `unsafe` is the call of the AVX2 clone,
//! after the check. The bare build (no std) has no detection and runs the
//! baseline.

use coray::kd::{KdStackItem, KdTree};
use coray::{Hit, Ray, TraceStats};

/// Whether this CPU runs the AVX2 kernels.
#[inline]
pub fn has_avx2() -> bool {
    #[cfg(all(feature = "std", target_arch = "x86_64"))]
    {
        std::is_x86_feature_detected!("avx2")
    }
    #[cfg(not(all(feature = "std", target_arch = "x86_64")))]
    {
        false
    }
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

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use coray::kd::{KdParams, Traversal, KD_STACK_LEN};
    use std::{vec, vec::Vec};

    /// The AVX2 clone (where this CPU has it) gives the baseline's hits
    /// and answers, bit for bit, on camera rays of a random scene.
    #[test]
    fn dispatched_kernels_agree_with_the_baseline() {
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
        let scene = coray::Scene {
            vertices: &v,
            triangles: &tris,
            spheres: &[],
            cones: &[],
        };
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
}
