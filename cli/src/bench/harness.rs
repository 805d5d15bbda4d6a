//! Timing: a workload traced through a shooter on N threads, best of
//! repeated runs, runs of different methods interleaved by the caller (this
//! machine is shared and noisy: the minimum is the least disturbed run).

use crate::shoot::Shooter;
use coray::{Hit, Ray, TraceStats};
use std::time::Instant;

/// Rays per work unit a thread takes at a time: large enough to amortise
/// the handing out, a multiple of 8 (packets).
const CHUNK: usize = 4096;

/// Traces `rays` once through `s` on `threads` threads (each its own
/// traversal state), closest hit or any hit.
pub fn trace<S: Shooter>(
    s: &S,
    rays: &[Ray],
    lights: Option<&[usize]>,
    any_hit: bool,
    threads: usize,
) -> (f64, Vec<Hit>, Vec<bool>, TraceStats) {
    let n = rays.len();
    let mut hits = if any_hit {
        Vec::new()
    } else {
        vec![Hit::MISS; n]
    };
    let mut occ = if any_hit { vec![false; n] } else { Vec::new() };
    let t = Instant::now();
    let stats = if threads <= 1 {
        let mut ctx = s.ctx();
        let mut st = TraceStats::default();
        if any_hit {
            s.occluded_all(rays, lights, &mut occ, &mut ctx, &mut st);
        } else {
            s.intersect_all(rays, &mut hits, &mut ctx, &mut st);
        }
        st
    } else {
        let next = std::sync::atomic::AtomicUsize::new(0);
        let hit_chunks: Vec<std::sync::Mutex<&mut [Hit]>> =
            hits.chunks_mut(CHUNK).map(std::sync::Mutex::new).collect();
        let occ_chunks: Vec<std::sync::Mutex<&mut [bool]>> =
            occ.chunks_mut(CHUNK).map(std::sync::Mutex::new).collect();
        let chunks = n.div_ceil(CHUNK);
        std::thread::scope(|sc| {
            let handles: Vec<_> = (0..threads)
                .map(|_| {
                    sc.spawn(|| {
                        let mut ctx = s.ctx();
                        let mut st = TraceStats::default();
                        loop {
                            let c = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                            if c >= chunks {
                                break st;
                            }
                            let (lo, hi) = (c * CHUNK, ((c + 1) * CHUNK).min(n));
                            let l = lights.map(|l| &l[lo..hi]);
                            if any_hit {
                                let mut out = occ_chunks[c].lock().unwrap();
                                s.occluded_all(&rays[lo..hi], l, &mut out, &mut ctx, &mut st);
                            } else {
                                let mut out = hit_chunks[c].lock().unwrap();
                                s.intersect_all(&rays[lo..hi], &mut out, &mut ctx, &mut st);
                            }
                        }
                    })
                })
                .collect();
            let mut total = TraceStats::default();
            for h in handles {
                total.add(&h.join().unwrap());
            }
            total
        })
    };
    (t.elapsed().as_secs_f64(), hits, occ, stats)
}

/// Best of `repeat` runs of `f`, each returning (seconds, value); the value
/// of the last run.
pub fn best_of<T>(repeat: usize, mut f: impl FnMut() -> (f64, T)) -> (f64, T) {
    let mut best = f64::INFINITY;
    let mut out = None;
    for _ in 0..repeat.max(1) {
        let (s, v) = f();
        best = best.min(s);
        out = Some(v);
    }
    (best, out.expect("at least one run"))
}

/// Times `f`: (seconds, value).
pub fn timed<T>(f: impl FnOnce() -> T) -> (f64, T) {
    let t = Instant::now();
    let v = f();
    (t.elapsed().as_secs_f64(), v)
}
