//! The wide walk written for AVX2: a node's eight boxes in one pass of
//! 256-bit instructions, a leaf's blocks two at a time (eight triangles a
//! pass), the ray's constants held in registers across the walk. The
//! compiler does not vectorise the portable walk ([`super::traverse`])
//! this well (it splits the eight lanes and spills), so this one names
//! its instructions: `core::arch` intrinsics, safe to call inside a
//! function compiled for AVX2, which callers reach only through
//! [`WideBvh::intersect_avx2`] and [`WideBvh::occluded_avx2`] after
//! checking the CPU (coray-ffi's dispatch).
//!
//! The answers are the portable walk's bit for bit: the triangle test
//! runs the same IEEE operations in the same order per lane (no fused
//! multiply-add), lanes on an edge in single precision go to the scene's
//! one-triangle test as there, hits are kept by the same tie rule, and
//! the box test is the same conservative slab test (only the order in
//! which entries are visited may differ, which changes no answer).

use super::block::{LeafBlock, EMPTY_BLOCK, NO_PRIM};
use super::node::{leaf_run, EMPTY_SLOT, LEAF_BIT, LOWER, UPPER, WIDTH};
use super::traverse::{read_entry_ahead, WideStackItem};
use super::WideBvh;
use crate::geom::leaf::beats;
use crate::geom::{Hit, PreparedRay, Ray, GEOM_TRIANGLES};
use crate::tolerance::BOX_FAR_SLACK;
use crate::TraceStats;
use core::arch::x86_64::*;

/// Eight lanes from an array (one unaligned load).
#[inline(always)]
fn lanes8(a: [f32; 8]) -> __m256 {
    bytemuck::cast(a)
}

/// Rows 0-3 of block `a` and 4-7 of block `b`, of one corner's axis.
#[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
#[inline]
fn pair_row(a: &LeafBlock, b: &LeafBlock, corner: usize, axis: usize) -> __m256 {
    let lo: __m128 = bytemuck::cast(a.corners[corner][axis]);
    let hi: __m128 = bytemuck::cast(b.corners[corner][axis]);
    _mm256_set_m128(hi, lo)
}

/// The watertight test's per-ray constants, broadcast: the origin in the
/// test's axis order (x, y, z = kx, ky, kz), the shear, and the segment's
/// start.
#[derive(Clone, Copy)]
struct TriLanes {
    o: [__m256; 3],
    shear: [__m256; 3],
    t_min: __m256,
    k: [usize; 3],
}

/// What one pass of the triangle test found in its eight slots.
struct Pass {
    /// Slots hit within `[t_min, t_max]`.
    hit: u32,
    /// Slots on an edge in single precision (the scene's test decides).
    edge: u32,
    t: __m256,
    /// The barycentric weights of corners 1 and 2.
    u: __m256,
    v: __m256,
}

/// The watertight test (`crate::geom::intersect_triangles4`) of the eight
/// triangles of blocks `a` and `b` (slots 0-3 and 4-7) within `t_max`,
/// each lane the one-triangle test's operations in its order. Passes
/// where every slot misses the triangle by its barycentric signs (most)
/// skip the division. Generic over its walk's parameters so that each
/// walk has its own copy, which the compiler then inlines (a function
/// compiled for AVX2 cannot be `inline(always)`).
#[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
#[inline]
fn triangles8<const ANY: bool, const OTHERS: bool, const PARALLEL: bool>(
    tl: &TriLanes,
    a: &LeafBlock,
    b: &LeafBlock,
    t_max: f32,
) -> Pass {
    let [kx, ky, kz] = tl.k;
    // Corner `k` relative to the origin, sheared: x, y, and z (unscaled).
    let corner = |k: usize| {
        let az = _mm256_sub_ps(pair_row(a, b, k, kz), tl.o[2]);
        let x = _mm256_sub_ps(
            _mm256_sub_ps(pair_row(a, b, k, kx), tl.o[0]),
            _mm256_mul_ps(tl.shear[0], az),
        );
        let y = _mm256_sub_ps(
            _mm256_sub_ps(pair_row(a, b, k, ky), tl.o[1]),
            _mm256_mul_ps(tl.shear[1], az),
        );
        (x, y, az)
    };
    let ((ax, ay, az), (bx, by, bz), (cx, cy, cz)) = (corner(0), corner(1), corner(2));
    let u = _mm256_sub_ps(_mm256_mul_ps(cx, by), _mm256_mul_ps(cy, bx));
    let v = _mm256_sub_ps(_mm256_mul_ps(ax, cy), _mm256_mul_ps(ay, cx));
    let w = _mm256_sub_ps(_mm256_mul_ps(bx, ay), _mm256_mul_ps(by, ax));
    let zero = _mm256_setzero_ps();
    let on_edge = _mm256_or_ps(
        _mm256_or_ps(
            _mm256_cmp_ps::<_CMP_EQ_OQ>(u, zero),
            _mm256_cmp_ps::<_CMP_EQ_OQ>(v, zero),
        ),
        _mm256_cmp_ps::<_CMP_EQ_OQ>(w, zero),
    );
    let det = _mm256_add_ps(_mm256_add_ps(u, v), w);
    // Inside: the three of one strict sign (no zero, so no lane of
    // `on_edge`), whose sum `det` is then not zero. A NaN among them
    // makes `det` NaN, which `det_ok` drops.
    let det_ok = _mm256_cmp_ps::<_CMP_EQ_OQ>(det, det);
    let low = _mm256_min_ps(_mm256_min_ps(u, v), w);
    let high = _mm256_max_ps(_mm256_max_ps(u, v), w);
    let one_sign = _mm256_or_ps(
        _mm256_cmp_ps::<_CMP_GT_OQ>(low, zero),
        _mm256_cmp_ps::<_CMP_LT_OQ>(high, zero),
    );
    let inside = _mm256_and_ps(one_sign, det_ok);
    let edge = _mm256_movemask_ps(on_edge) as u32;
    if _mm256_movemask_ps(inside) == 0 {
        return Pass {
            hit: 0,
            edge,
            t: zero,
            u: zero,
            v: zero,
        };
    }
    // z scaled after the edge functions, as the one-triangle test does.
    let s = tl.shear[2];
    let t_scaled = _mm256_add_ps(
        _mm256_add_ps(
            _mm256_mul_ps(u, _mm256_mul_ps(s, az)),
            _mm256_mul_ps(v, _mm256_mul_ps(s, bz)),
        ),
        _mm256_mul_ps(w, _mm256_mul_ps(s, cz)),
    );
    let inv_det = _mm256_div_ps(_mm256_set1_ps(1.0), det);
    let t = _mm256_mul_ps(t_scaled, inv_det);
    let within = _mm256_and_ps(
        _mm256_cmp_ps::<_CMP_GE_OQ>(t, tl.t_min),
        _mm256_cmp_ps::<_CMP_LE_OQ>(t, _mm256_set1_ps(t_max)),
    );
    Pass {
        hit: _mm256_movemask_ps(_mm256_and_ps(inside, within)) as u32,
        edge,
        t,
        u: _mm256_mul_ps(v, inv_det),
        v: _mm256_mul_ps(w, inv_det),
    }
}

/// The set bits of `mask`, lowest first.
#[inline(always)]
fn bits(mut mask: u32) -> impl Iterator<Item = usize> {
    core::iter::from_fn(move || {
        (mask != 0).then(|| {
            let i = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            i
        })
    })
}

/// Slots of `b` that hold a sphere or a cone.
#[inline(always)]
fn other_slots(b: &LeafBlock, triangles: usize) -> u32 {
    let mut m = 0;
    for (i, &p) in b.prims.iter().enumerate() {
        m |= ((p != NO_PRIM && p as usize >= triangles) as u32) << i;
    }
    m
}

/// A closest-hit walk's answer so far.
pub(super) struct Best {
    pub(super) hit: Hit,
    /// Block and slot of the best hit when a pass found it: its normal is
    /// made from the block's corners once, at the end.
    pub(super) from_block: Option<(usize, usize)>,
}

/// A valid ray's walk from entry `start` of `w` (a packet's lane walking
/// on alone): a closest hit into `best`, or (`ANY`) whether anything is
/// hit. The ray's inverse direction is finite (a packet's is).
#[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
#[inline]
pub(super) fn walk_from<const ANY: bool>(
    w: &WideBvh,
    ray: &Ray,
    start: u32,
    best: &mut Best,
    stack: &mut [WideStackItem],
    stats: &mut TraceStats,
) -> bool {
    if w.has_others() {
        let r = PreparedRay::new(ray);
        walk::<ANY, true, false, true>(w, &r, start, best, stack, stats)
    } else {
        let r = PreparedRay::for_triangles(ray);
        walk::<ANY, false, false, true>(w, &r, start, best, stack, stats)
    }
}

impl Best {
    /// The best hit, its normal made when a block found it.
    pub(super) fn finish(mut self, w: &WideBvh) -> Hit {
        if let Some((b, slot)) = self.from_block {
            self.hit.ng = w.blocks[b].normal(slot);
        }
        self.hit
    }

    /// Keeps `h` when it beats the best so far; true when it does.
    #[inline(always)]
    fn offer(&mut self, h: Hit, at: Option<(usize, usize)>) -> bool {
        let better = beats(&h, &self.hit);
        if better {
            self.hit = h;
            self.from_block = at;
        }
        better
    }
}

/// What a pass over blocks `pair` and `pair + 1` found (hits and slots to
/// test alone: on an edge, or spheres and cones), kept in `best`; `limit`
/// becomes the best hit's distance. True when an any-hit query (`ANY`) is
/// answered. Out of the walk's loop: most passes find nothing.
#[inline(never)]
#[allow(clippy::too_many_arguments)]
fn settle<const ANY: bool>(
    w: &WideBvh,
    r: &PreparedRay,
    pair: usize,
    blocks: [&LeafBlock; 2],
    (hit, alone): (u32, u32),
    tuv: [[f32; 8]; 3],
    best: &mut Best,
    limit: &mut f32,
) -> bool {
    let prim_of = |lane: usize| blocks[lane / 4].prims[lane % 4];
    if ANY && hit != 0 {
        return true;
    }
    for lane in bits(hit) {
        let h = Hit {
            t: tuv[0][lane],
            u: tuv[1][lane],
            v: tuv[2][lane],
            ng: crate::Vec3::ZERO,
            geom_id: GEOM_TRIANGLES,
            prim_id: prim_of(lane),
        };
        if best.offer(h, Some((pair + lane / 4, lane % 4))) {
            *limit = h.t;
        }
    }
    for lane in bits(alone) {
        let p = prim_of(lane);
        if p == NO_PRIM {
            continue;
        }
        if let Some(h) = w.scene.intersect_prim(p as usize, r, *limit) {
            if ANY {
                return true;
            }
            if best.offer(h, None) {
                *limit = h.t;
            }
        }
    }
    false
}

/// One ray's walk from entry `start` (the root: 0): a closest hit into
/// `best` (or, `ANY`, whether anything is hit: the return value). Every
/// entry taken costs one from a budget of what a valid tree can hold, so
/// corrupt indices end in a fault, never a hang. `OTHERS`: leaves may hold
/// spheres and cones. `PARALLEL`: some axis' inverse direction is
/// infinite. `LANE`: a packet's lane walking on alone (its own copy of the
/// walk, so that each copy is inlined where it is called).
#[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
#[inline]
fn walk<const ANY: bool, const OTHERS: bool, const PARALLEL: bool, const LANE: bool>(
    w: &WideBvh,
    r: &PreparedRay,
    start: u32,
    best: &mut Best,
    stack: &mut [WideStackItem],
    stats: &mut TraceStats,
) -> bool {
    if stack.is_empty() {
        stats.faults += 1;
        return false;
    }
    let origin = r.origin.to_array();
    let inv = r.inv_dir.to_array();
    // Axes whose inverse direction is infinite (a zero component, or one
    // so small that its inverse overflows): `(face - origin) * inf` is NaN
    // on a face, so the origin decides them, as the kd-tree's clip does.
    let parallel = inv.map(f32::is_infinite);
    let o = [
        _mm256_set1_ps(origin[0]),
        _mm256_set1_ps(origin[1]),
        _mm256_set1_ps(origin[2]),
    ];
    let iv = [
        _mm256_set1_ps(inv[0]),
        _mm256_set1_ps(inv[1]),
        _mm256_set1_ps(inv[2]),
    ];
    // Each axis' near and far row, by the direction's sign.
    let row = |a: usize, upper: bool| if upper { UPPER + a } else { LOWER + a };
    let (nx, ny, nz) = (
        row(0, inv[0] < 0.0),
        row(1, inv[1] < 0.0),
        row(2, inv[2] < 0.0),
    );
    let (fx, fy, fz) = (
        row(0, !(inv[0] < 0.0)),
        row(1, !(inv[1] < 0.0)),
        row(2, !(inv[2] < 0.0)),
    );
    let t_min = _mm256_set1_ps(r.t_min);
    let slack = _mm256_set1_ps(BOX_FAR_SLACK);
    let tl = TriLanes {
        o: [
            _mm256_set1_ps(origin[r.kx]),
            _mm256_set1_ps(origin[r.ky]),
            _mm256_set1_ps(origin[r.kz]),
        ],
        shear: [
            _mm256_set1_ps(r.sx),
            _mm256_set1_ps(r.sy),
            _mm256_set1_ps(r.sz),
        ],
        t_min,
        k: [r.kx, r.ky, r.kz],
    };
    let nt = w.scene.triangles.len();
    let (nodes, blocks) = (w.nodes, w.blocks);
    let mut limit = r.t_max;
    let mut sp = 0usize;
    let mut budget = nodes.len().saturating_mul(WIDTH + 1);
    let (mut interior, mut leaves, mut boxes, mut tests) = (0u64, 0u64, 0u64, 0u64);
    let (mut fault, mut stopped) = (false, false);
    // The entry walked now: the nearest one a node sent the ray on to,
    // or the nearest waiting on the stack.
    let mut cur = start;
    // What loads read ahead (where a read-ahead is a load, not a
    // prefetch), kept so that they stay.
    let mut touch = 0u32;
    'walk: loop {
        if budget == 0 {
            fault = true;
            break;
        }
        budget -= 1;
        if cur & LEAF_BIT == 0 {
            let Some(n) = nodes.get(cur as usize) else {
                fault = true;
                break;
            };
            interior += 1;
            let p = &n.planes;
            let near =
                |row: usize, a: usize| _mm256_mul_ps(_mm256_sub_ps(lanes8(p[row]), o[a]), iv[a]);
            let hit = if PARALLEL {
                // Axes the ray runs parallel to are decided by the origin
                // (on a face counts as inside), the others by the slab.
                let (mut tn, mut tf) = (t_min, _mm256_set1_ps(f32::INFINITY));
                let mut inside = _mm256_castsi256_ps(_mm256_set1_epi32(-1));
                for (a, (nr, fr)) in [(nx, fx), (ny, fy), (nz, fz)].into_iter().enumerate() {
                    if parallel[a] {
                        let (lo, hi) = (lanes8(p[LOWER + a]), lanes8(p[UPPER + a]));
                        inside = _mm256_and_ps(
                            inside,
                            _mm256_and_ps(
                                _mm256_cmp_ps::<_CMP_GE_OQ>(o[a], lo),
                                _mm256_cmp_ps::<_CMP_LE_OQ>(o[a], hi),
                            ),
                        );
                    } else {
                        tn = _mm256_max_ps(near(nr, a), tn);
                        tf = _mm256_min_ps(near(fr, a), tf);
                    }
                }
                let tf = _mm256_min_ps(_mm256_mul_ps(tf, slack), _mm256_set1_ps(limit));
                let ok = _mm256_and_ps(inside, _mm256_cmp_ps::<_CMP_LE_OQ>(tn, tf));
                (_mm256_movemask_ps(ok) as u32, tn)
            } else {
                let tn = _mm256_max_ps(
                    _mm256_max_ps(near(nx, 0), near(ny, 1)),
                    _mm256_max_ps(near(nz, 2), t_min),
                );
                let tf = _mm256_min_ps(_mm256_min_ps(near(fx, 0), near(fy, 1)), near(fz, 2));
                let tf = _mm256_min_ps(_mm256_mul_ps(tf, slack), _mm256_set1_ps(limit));
                (
                    _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(tn, tf)) as u32,
                    tn,
                )
            };
            let (hit, tn) = hit;
            let empty = _mm256_cmpeq_epi32(bytemuck::cast(n.child), _mm256_set1_epi32(-1));
            boxes += (WIDTH as u32
                - (_mm256_movemask_ps(_mm256_castsi256_ps(empty)) as u32).count_ones())
                as u64;
            if hit != 0 {
                let i0 = hit.trailing_zeros() as usize;
                let rest = hit & (hit - 1);
                if rest == 0 {
                    // One entry entered: walk it next.
                    cur = n.child[i0];
                    continue;
                }
                if sp + WIDTH > stack.len() {
                    fault = true;
                    break;
                }
                let tn: [f32; WIDTH] = bytemuck::cast(tn);
                let i1 = rest.trailing_zeros() as usize;
                let rest = rest & (rest - 1);
                if rest == 0 {
                    // Two: the farther waits, the nearer is walked.
                    let (c0, c1) = (n.child[i0], n.child[i1]);
                    let swap = !ANY && tn[i1] < tn[i0];
                    let (near, far, far_t) = if swap {
                        (c1, c0, tn[i0])
                    } else {
                        (c0, c1, tn[i1])
                    };
                    if !ANY && w.read_ahead {
                        read_entry_ahead(w, far, &mut touch);
                    }
                    stack[sp] = WideStackItem {
                        child: far,
                        t: far_t,
                    };
                    sp += 1;
                    cur = near;
                    continue;
                }
                // Three or more: all onto the stack (closest hit: sorted
                // far to near), the nearest taken back.
                let base = sp;
                let mut m = hit;
                while m != 0 {
                    let i = m.trailing_zeros() as usize;
                    m &= m - 1;
                    let e = WideStackItem {
                        child: n.child[i],
                        t: tn[i],
                    };
                    if !ANY && w.read_ahead {
                        read_entry_ahead(w, e.child, &mut touch);
                    }
                    let mut k = sp;
                    if !ANY {
                        while k > base && stack[k - 1].t < e.t {
                            stack[k] = stack[k - 1];
                            k -= 1;
                        }
                    }
                    stack[k] = e;
                    sp += 1;
                }
                sp -= 1;
                cur = stack[sp].child;
                continue;
            }
        } else {
            leaves += 1;
            let (first, count) = leaf_run(cur);
            let Some(run) = blocks.get(first..first + count) else {
                fault = true;
                break;
            };
            let mut j = 0;
            while j < count {
                let a = &run[j];
                let b = run.get(j + 1).unwrap_or(&EMPTY_BLOCK);
                let ps = triangles8::<ANY, OTHERS, PARALLEL>(&tl, a, b, limit);
                let mut alone = ps.edge;
                if OTHERS {
                    alone |= other_slots(a, nt) | other_slots(b, nt) << 4;
                }
                if ps.hit | alone != 0 {
                    let tuv = [
                        bytemuck::cast(ps.t),
                        bytemuck::cast(ps.u),
                        bytemuck::cast(ps.v),
                    ];
                    if settle::<ANY>(
                        w,
                        r,
                        first + j,
                        [a, b],
                        (ps.hit, alone),
                        tuv,
                        best,
                        &mut limit,
                    ) {
                        stopped = true;
                        break 'walk;
                    }
                }
                j += 2;
            }
            // Primitives held: every slot but the last block's empty ones.
            let last = &run[count - 1].prims;
            tests += (4 * count) as u64 - last.iter().filter(|&&p| p == NO_PRIM).count() as u64;
        }
        // Back to the nearest entry waiting that still lies within reach.
        while sp > 0 {
            sp -= 1;
            let e = stack[sp];
            if e.t <= limit {
                cur = e.child;
                continue 'walk;
            }
        }
        break;
    }
    let _ = EMPTY_SLOT;
    core::hint::black_box(touch);
    stats.traversal_steps += interior + leaves;
    stats.interior_steps += interior;
    stats.leaf_steps += leaves;
    stats.box_tests += boxes;
    stats.prim_tests += tests;
    stats.faults += fault as u64;
    stopped
}

/// One valid ray's walk with the box test and the leaf test chosen for
/// the ray and the scene.
#[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
#[inline]
fn trace<const ANY: bool>(
    w: &WideBvh,
    ray: &Ray,
    best: &mut Best,
    stack: &mut [WideStackItem],
    stats: &mut TraceStats,
) -> bool {
    let r = if w.has_others() {
        PreparedRay::new(ray)
    } else {
        PreparedRay::for_triangles(ray)
    };
    let parallel = r.inv_dir.to_array().iter().any(|i| i.is_infinite());
    match (w.has_others(), parallel) {
        (false, false) => walk::<ANY, false, false, false>(w, &r, 0, best, stack, stats),
        (false, true) => walk::<ANY, false, true, false>(w, &r, 0, best, stack, stats),
        (true, false) => walk::<ANY, true, false, false>(w, &r, 0, best, stack, stats),
        (true, true) => walk::<ANY, true, true, false>(w, &r, 0, best, stack, stats),
    }
}

impl WideBvh<'_> {
    /// Whether the scene has spheres or cones besides triangles.
    #[inline(always)]
    pub(super) fn has_others(&self) -> bool {
        !(self.scene.spheres.is_empty() && self.scene.cones.is_empty())
    }

    /// [`WideBvh::intersect`] written for AVX2: the same answers.
    ///
    /// # Safety
    /// Call only where the CPU runs AVX2, BMI1, BMI2, LZCNT and POPCNT
    /// (every AVX2 CPU): the function is compiled for them, so calling it
    /// from code that is not takes `unsafe`.
    #[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
    pub fn intersect_avx2(
        &self,
        ray: &Ray,
        stack: &mut [WideStackItem],
        stats: &mut TraceStats,
    ) -> Hit {
        stats.rays += 1;
        if !ray.is_valid() {
            return Hit::MISS;
        }
        let mut best = Best {
            hit: Hit::MISS,
            from_block: None,
        };
        trace::<false>(self, ray, &mut best, stack, stats);
        best.finish(self)
    }

    /// [`WideBvh::occluded`] written for AVX2: the same answers.
    ///
    /// # Safety
    /// As [`WideBvh::intersect_avx2`].
    #[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
    pub fn occluded_avx2(
        &self,
        ray: &Ray,
        stack: &mut [WideStackItem],
        stats: &mut TraceStats,
    ) -> bool {
        stats.rays += 1;
        if !ray.is_valid() {
            return false;
        }
        let mut best = Best {
            hit: Hit::MISS,
            from_block: None,
        };
        trace::<true>(self, ray, &mut best, stack, stats)
    }
}
