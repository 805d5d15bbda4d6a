//! Packets of eight coherent rays through the wide hierarchy, written for
//! AVX2: the packet walks the tree once, each node's eight boxes tested
//! against bounds that hold for every ray of the packet at once (interval
//! arithmetic over the rays' origins and inverse directions, one pass of
//! the eight boxes, as a single ray's test), and each triangle of a leaf
//! tested against the eight rays at once (one ray a lane).
//!
//! Every ray gets exactly its single walk's answer: the bounds are
//! conservative for each ray's own rounded slab test (below), so the
//! packet visits a superset of the leaves each ray would, and each lane
//! tests their triangles with the one-triangle test's operations in its
//! order and keeps hits by the same tie rule. Lanes on an edge in single
//! precision go to the scene's one-triangle test, as there.
//!
//! A packet is traced together when its rays agree on the sign of every
//! direction component (none zero or too small to invert) and on the
//! watertight test's axes: a tile of camera rays, or the shadow rays from
//! one towards a light. Rays of other packets, and rays whose axes differ
//! from the packet's first, are traced alone
//! ([`WideBvh::intersect_avx2`]). A leaf's spheres and cones are tested
//! lane by lane by the scene's own tests.
//!
//! Why the bounds hold: along an axis where every inverse direction is
//! positive, a ray's near distance is `RN(RN(near - o) * inv)` with `o` in
//! `[o_lo, o_hi]` and `inv` in `[inv_lo, inv_hi]`. Rounding is monotone, so
//! `RN(near - o) >= RN(near - o_hi) = x`, and `x * inv` is linear in `inv`,
//! so every ray's near distance is at least `min(RN(x * inv_lo), RN(x *
//! inv_hi))`; the far distance at most `max(..)` of `RN(far - o_lo)` alike.
//! Negative directions swap the faces and the origin bounds. The packet
//! enters a box when the largest near bound is at most the smallest far
//! bound (with the single test's slack) and the largest limit of its rays.

use super::avx2::{walk_from, Best};
use super::block::{LeafBlock, NO_PRIM};
use super::node::{leaf_run, EMPTY_SLOT, LEAF_BIT, LOWER, UPPER, WIDTH};
use super::traverse::{read_entry_ahead, WideStackItem};
use super::WideBvh;
use crate::geom::{Hit, PreparedRay, Ray};
use crate::tolerance::BOX_FAR_SLACK;
use crate::TraceStats;
use core::arch::x86_64::*;

/// Rays a packet holds.
pub const PACKET_LANES: usize = 8;

/// Rays left in a subtree at or below which each walks it alone (the
/// one-ray walk from that entry).
const ALONE: u32 = 1;

/// Eight lanes from an array.
#[inline(always)]
fn lanes8(a: [f32; 8]) -> __m256 {
    bytemuck::cast(a)
}

/// Eight rays prepared together: what [`PreparedRay::new`] computes for
/// each, lane by lane, and the bounds of the packet's frustum test.
struct Packet {
    /// Lanes traced in the packet (valid rays sharing the first valid
    /// lane's watertight axes).
    on: u32,
    /// Lanes holding a valid ray ([`Ray::is_valid`]).
    valid: u32,
    /// Per axis: the rows of the faces every ray meets first and last.
    near: [usize; 3],
    far: [usize; 3],
    /// Per axis: the origin bound the near and the far faces are measured
    /// from (the largest origin for a ray moving up the axis).
    o_near: [__m256; 3],
    o_far: [__m256; 3],
    /// Per axis: the least and the greatest inverse direction.
    inv_lo: [__m256; 3],
    inv_hi: [__m256; 3],
    /// The least segment start.
    t_min_lo: __m256,
    /// Per lane: the origin and the inverse direction, axis by axis (the
    /// single walk's slab test, lane by lane).
    ro: [__m256; 3],
    rinv: [__m256; 3],
    /// Per lane: the watertight test's origin (x, y, z = kx, ky, kz of
    /// the packet), shear and segment.
    o: [__m256; 3],
    shear: [__m256; 3],
    t_min: __m256,
    t_max: __m256,
    /// The watertight test's axes, shared.
    k: [usize; 3],
}

/// `x` in every lane.
#[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
#[inline]
fn splat(x: f32) -> __m256 {
    _mm256_set1_ps(x)
}

/// The least and the greatest of lanes `on` of `v`, each in every lane.
#[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
#[inline]
fn range(v: __m256, on: __m256) -> (__m256, __m256) {
    let lo = _mm256_blendv_ps(splat(f32::INFINITY), v, on);
    let hi = _mm256_blendv_ps(splat(f32::NEG_INFINITY), v, on);
    // Across the halves, then within each: every lane ends with the
    // extreme.
    let lo = _mm256_min_ps(lo, _mm256_permute2f128_ps::<1>(lo, lo));
    let hi = _mm256_max_ps(hi, _mm256_permute2f128_ps::<1>(hi, hi));
    let lo = _mm256_min_ps(lo, _mm256_shuffle_ps::<0b01_00_11_10>(lo, lo));
    let hi = _mm256_max_ps(hi, _mm256_shuffle_ps::<0b01_00_11_10>(hi, hi));
    let lo = _mm256_min_ps(lo, _mm256_shuffle_ps::<0b10_11_00_01>(lo, lo));
    let hi = _mm256_max_ps(hi, _mm256_shuffle_ps::<0b10_11_00_01>(hi, hi));
    (lo, hi)
}

/// An 8 x 8 transpose: lane `j` of row `i` becomes lane `i` of row `j`.
#[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
#[inline]
fn transpose8(r: [__m256; 8]) -> [__m256; 8] {
    let t0 = _mm256_unpacklo_ps(r[0], r[1]);
    let t1 = _mm256_unpackhi_ps(r[0], r[1]);
    let t2 = _mm256_unpacklo_ps(r[2], r[3]);
    let t3 = _mm256_unpackhi_ps(r[2], r[3]);
    let t4 = _mm256_unpacklo_ps(r[4], r[5]);
    let t5 = _mm256_unpackhi_ps(r[4], r[5]);
    let t6 = _mm256_unpacklo_ps(r[6], r[7]);
    let t7 = _mm256_unpackhi_ps(r[6], r[7]);
    let s0 = _mm256_shuffle_ps::<0b01_00_01_00>(t0, t2);
    let s1 = _mm256_shuffle_ps::<0b11_10_11_10>(t0, t2);
    let s2 = _mm256_shuffle_ps::<0b01_00_01_00>(t1, t3);
    let s3 = _mm256_shuffle_ps::<0b11_10_11_10>(t1, t3);
    let s4 = _mm256_shuffle_ps::<0b01_00_01_00>(t4, t6);
    let s5 = _mm256_shuffle_ps::<0b11_10_11_10>(t4, t6);
    let s6 = _mm256_shuffle_ps::<0b01_00_01_00>(t5, t7);
    let s7 = _mm256_shuffle_ps::<0b11_10_11_10>(t5, t7);
    [
        _mm256_permute2f128_ps::<0x20>(s0, s4),
        _mm256_permute2f128_ps::<0x20>(s1, s5),
        _mm256_permute2f128_ps::<0x20>(s2, s6),
        _mm256_permute2f128_ps::<0x20>(s3, s7),
        _mm256_permute2f128_ps::<0x31>(s0, s4),
        _mm256_permute2f128_ps::<0x31>(s1, s5),
        _mm256_permute2f128_ps::<0x31>(s2, s6),
        _mm256_permute2f128_ps::<0x31>(s3, s7),
    ]
}

/// The eight rays' fields, lane by lane: origin x, y, z, `t_min`,
/// direction x, y, z, `t_max` (lanes past `rays` repeat the first ray).
#[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
#[inline]
fn transpose(rays: &[Ray]) -> [__m256; 8] {
    let row = |i: usize| {
        let r = rays.get(i).unwrap_or(&rays[0]);
        let (o, d) = (r.origin, r.dir);
        lanes8([o.x, o.y, o.z, r.t_min, d.x, d.y, d.z, r.t_max])
    };
    transpose8([
        row(0),
        row(1),
        row(2),
        row(3),
        row(4),
        row(5),
        row(6),
        row(7),
    ])
}

impl Packet {
    /// Prepares `rays` (one to eight), or `None` when they are not to be
    /// traced together: fewer than two valid rays, direction signs that
    /// differ or a component too small to invert. Lanes whose watertight
    /// axes differ from the first valid lane's are left out of `on`. Each
    /// lane's constants are [`PreparedRay::new`]'s bit for bit: the same
    /// IEEE operations. Generic over the query so that each has its own
    /// copy to inline.
    #[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
    #[inline]
    fn load<const ANY: bool>(rays: &[Ray]) -> Option<Packet> {
        let [ox, oy, oz, t0, dx, dy, dz, t1] = transpose(rays);
        let present = (1u32 << rays.len().min(PACKET_LANES)) - 1;
        let zero = _mm256_setzero_ps();
        // `Ray::is_valid`, lane by lane: `x * 0` is zero exactly for
        // finite `x`.
        let z = |x: __m256| _mm256_mul_ps(x, zero);
        let zeros = _mm256_add_ps(
            _mm256_add_ps(_mm256_add_ps(z(ox), z(oy)), _mm256_add_ps(z(oz), z(dx))),
            _mm256_add_ps(z(dy), z(dz)),
        );
        let nonzero = _mm256_or_ps(
            _mm256_or_ps(
                _mm256_cmp_ps::<_CMP_NEQ_UQ>(dx, zero),
                _mm256_cmp_ps::<_CMP_NEQ_UQ>(dy, zero),
            ),
            _mm256_cmp_ps::<_CMP_NEQ_UQ>(dz, zero),
        );
        let ok = _mm256_and_ps(
            _mm256_and_ps(_mm256_cmp_ps::<_CMP_EQ_OQ>(zeros, zero), nonzero),
            _mm256_cmp_ps::<_CMP_LE_OQ>(t0, t1),
        );
        let valid = _mm256_movemask_ps(ok) as u32 & present;
        if valid.count_ones() < 2 {
            return None;
        }
        let one = splat(1.0);
        let d = [dx, dy, dz];
        let inv = [
            _mm256_div_ps(one, dx),
            _mm256_div_ps(one, dy),
            _mm256_div_ps(one, dz),
        ];
        // Every valid lane moves the same way along every axis, and every
        // inverse is finite.
        let abs_mask = _mm256_castsi256_ps(_mm256_set1_epi32(i32::MAX));
        let mut down = [false; 3];
        for a in 0..3 {
            let neg = _mm256_movemask_ps(inv[a]) as u32 & valid;
            let finite =
                _mm256_cmp_ps::<_CMP_LT_OQ>(_mm256_and_ps(inv[a], abs_mask), splat(f32::INFINITY));
            if (neg != 0 && neg != valid) || _mm256_movemask_ps(finite) as u32 & valid != valid {
                return None;
            }
            down[a] = neg != 0;
        }
        // The watertight axes, lane by lane (the largest component, x
        // before y before z on ties), as `PreparedRay::new` picks them.
        let (ax, ay, az) = (
            _mm256_and_ps(dx, abs_mask),
            _mm256_and_ps(dy, abs_mask),
            _mm256_and_ps(dz, abs_mask),
        );
        let x_wins = _mm256_movemask_ps(_mm256_and_ps(
            _mm256_cmp_ps::<_CMP_GE_OQ>(ax, ay),
            _mm256_cmp_ps::<_CMP_GE_OQ>(ax, az),
        )) as u32;
        let y_wins = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_GE_OQ>(ay, az)) as u32;
        let lead = valid.trailing_zeros();
        let kz_of = |i: u32| {
            if x_wins >> i & 1 != 0 {
                0
            } else if y_wins >> i & 1 != 0 {
                1
            } else {
                2
            }
        };
        let kz = kz_of(lead);
        let with_kz = match kz {
            0 => x_wins,
            1 => !x_wins & y_wins,
            _ => !x_wins & !y_wins,
        };
        let on = valid & with_kz;
        const NEXT: [usize; 3] = [1, 2, 0];
        let (mut kx, mut ky) = (NEXT[kz], NEXT[NEXT[kz]]);
        if down[kz] {
            core::mem::swap(&mut kx, &mut ky);
        }
        let onv = mask_of(on);
        let o = [ox, oy, oz];
        let mut p = Packet {
            on,
            valid,
            near: [0; 3],
            far: [0; 3],
            o_near: [zero; 3],
            o_far: [zero; 3],
            inv_lo: [zero; 3],
            inv_hi: [zero; 3],
            t_min_lo: range(t0, onv).0,
            ro: o,
            rinv: inv,
            o: [o[kx], o[ky], o[kz]],
            shear: [
                _mm256_div_ps(d[kx], d[kz]),
                _mm256_div_ps(d[ky], d[kz]),
                inv[kz],
            ],
            t_min: t0,
            t_max: t1,
            k: [kx, ky, kz],
        };
        for a in 0..3 {
            let (olo, ohi) = range(o[a], onv);
            let (ilo, ihi) = range(inv[a], onv);
            p.near[a] = if down[a] { UPPER + a } else { LOWER + a };
            p.far[a] = if down[a] { LOWER + a } else { UPPER + a };
            p.o_near[a] = if down[a] { olo } else { ohi };
            p.o_far[a] = if down[a] { ohi } else { olo };
            p.inv_lo[a] = ilo;
            p.inv_hi[a] = ihi;
        }
        Some(p)
    }

    /// The slots of `n` whose boxes some ray of the packet may enter
    /// within `[t_min, limit]`, and a bound below every ray's entry
    /// distance per slot (see the module's reasoning).
    #[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
    #[inline]
    fn enter(&self, n: &super::WideNode, limit: f32) -> (u32, __m256) {
        let p = &n.planes;
        let mut tn = self.t_min_lo;
        let mut tf = splat(f32::INFINITY);
        for a in 0..3 {
            let x = _mm256_sub_ps(lanes8(p[self.near[a]]), self.o_near[a]);
            let near = _mm256_min_ps(
                _mm256_mul_ps(x, self.inv_lo[a]),
                _mm256_mul_ps(x, self.inv_hi[a]),
            );
            let y = _mm256_sub_ps(lanes8(p[self.far[a]]), self.o_far[a]);
            let far = _mm256_max_ps(
                _mm256_mul_ps(y, self.inv_lo[a]),
                _mm256_mul_ps(y, self.inv_hi[a]),
            );
            tn = _mm256_max_ps(near, tn);
            tf = _mm256_min_ps(far, tf);
        }
        let tf = _mm256_min_ps(_mm256_mul_ps(tf, splat(BOX_FAR_SLACK)), splat(limit));
        let hit = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(tn, tf)) as u32;
        (hit, tn)
    }

    /// The lanes whose rays enter slot `slot`'s box of `n` within their
    /// own `[t_min, limits]`: each lane the single walk's slab test of its
    /// ray, so a lane left out is one whose single walk would not enter
    /// the box either.
    #[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
    #[inline]
    fn lanes_in(&self, n: &super::WideNode, slot: usize, limits: __m256) -> u32 {
        let p = &n.planes;
        let mut tn = self.t_min;
        let mut tf = splat(f32::INFINITY);
        for a in 0..3 {
            let near = _mm256_mul_ps(
                _mm256_sub_ps(splat(p[self.near[a]][slot]), self.ro[a]),
                self.rinv[a],
            );
            let far = _mm256_mul_ps(
                _mm256_sub_ps(splat(p[self.far[a]][slot]), self.ro[a]),
                self.rinv[a],
            );
            tn = _mm256_max_ps(near, tn);
            tf = _mm256_min_ps(far, tf);
        }
        let tf = _mm256_min_ps(_mm256_mul_ps(tf, splat(BOX_FAR_SLACK)), limits);
        _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(tn, tf)) as u32
    }
}

/// Per lane: the best hit so far of a closest-hit packet, each field of
/// [`Hit`] but the two indices.
struct Lanes {
    t: __m256,
    u: __m256,
    v: __m256,
    ng: [__m256; 3],
    /// `geom_id << 30 | prim_id`, biased by 2^31 for signed comparison
    /// (`u32::MAX` unbiased for no hit): the tie rule's order.
    key: __m256i,
}

impl Lanes {
    /// No hit in any lane.
    #[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
    #[inline]
    fn none() -> Lanes {
        let zero = _mm256_setzero_ps();
        Lanes {
            t: splat(f32::INFINITY),
            u: zero,
            v: zero,
            ng: [zero; 3],
            key: _mm256_set1_epi32(-1 ^ BIAS),
        }
    }

    /// The hits, lane `i` into `hits[i]` for the lanes of `on`; lanes of
    /// `bad` and lanes with no hit miss ([`Hit::MISS`]). The fields are
    /// made eight lanes at a time, then turned into hits by a transpose:
    /// a [`Hit`] is eight words.
    #[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
    #[inline]
    fn write(&self, on: u32, bad: u32, hits: &mut [Hit]) {
        let key = _mm256_xor_si256(self.key, _mm256_set1_epi32(BIAS));
        let miss = _mm256_or_si256(
            _mm256_cmpeq_epi32(key, _mm256_set1_epi32(-1)),
            _mm256_castps_si256(mask_of(bad)),
        );
        let missf = _mm256_castsi256_ps(miss);
        let keep = |x: __m256| _mm256_andnot_ps(missf, x);
        let geom = _mm256_or_si256(_mm256_srli_epi32::<30>(key), miss);
        let prim = _mm256_or_si256(_mm256_and_si256(key, _mm256_set1_epi32(!(3 << 30))), miss);
        let rows = transpose8([
            _mm256_blendv_ps(self.t, splat(f32::INFINITY), missf),
            keep(self.u),
            keep(self.v),
            keep(self.ng[0]),
            keep(self.ng[1]),
            keep(self.ng[2]),
            _mm256_castsi256_ps(geom),
            _mm256_castsi256_ps(prim),
        ]);
        for (i, h) in hits.iter_mut().enumerate().take(PACKET_LANES) {
            if on >> i & 1 != 0 {
                let r: [f32; 8] = bytemuck::cast(rows[i]);
                *h = Hit {
                    t: r[0],
                    u: r[1],
                    v: r[2],
                    ng: crate::Vec3::new(r[3], r[4], r[5]),
                    geom_id: r[6].to_bits(),
                    prim_id: r[7].to_bits(),
                };
            }
        }
    }
}

/// The bias that makes unsigned order signed.
const BIAS: i32 = i32::MIN;

/// One triangle (slot `slot` of `b`) against the packet's rays `on`,
/// within each lane's `t_max`: the lanes hit (`t`, `u`, `v`), and the lanes
/// on an edge in single precision. The one-triangle test's operations in
/// its order, a ray a lane. Generic over its walk's query so that each
/// walk has its own copy to inline.
#[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
#[inline]
fn triangle<const ANY: bool>(
    p: &Packet,
    b: &LeafBlock,
    slot: usize,
    t_max: __m256,
) -> (u32, u32, [__m256; 3]) {
    let c = &b.corners;
    let [kx, ky, kz] = p.k;
    let corner = |k: usize| {
        let az = _mm256_sub_ps(splat(c[k][kz][slot]), p.o[2]);
        let x = _mm256_sub_ps(
            _mm256_sub_ps(splat(c[k][kx][slot]), p.o[0]),
            _mm256_mul_ps(p.shear[0], az),
        );
        let y = _mm256_sub_ps(
            _mm256_sub_ps(splat(c[k][ky][slot]), p.o[1]),
            _mm256_mul_ps(p.shear[1], az),
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
    if _mm256_movemask_ps(inside) as u32 & p.on == 0 {
        return (0, edge, [zero; 3]);
    }
    let s = p.shear[2];
    let t_scaled = _mm256_add_ps(
        _mm256_add_ps(
            _mm256_mul_ps(u, _mm256_mul_ps(s, az)),
            _mm256_mul_ps(v, _mm256_mul_ps(s, bz)),
        ),
        _mm256_mul_ps(w, _mm256_mul_ps(s, cz)),
    );
    let inv_det = _mm256_div_ps(splat(1.0), det);
    let t = _mm256_mul_ps(t_scaled, inv_det);
    let within = _mm256_and_ps(
        _mm256_cmp_ps::<_CMP_GE_OQ>(t, p.t_min),
        _mm256_cmp_ps::<_CMP_LE_OQ>(t, t_max),
    );
    let hit = _mm256_movemask_ps(_mm256_and_ps(inside, within)) as u32;
    (
        hit,
        edge,
        [t, _mm256_mul_ps(v, inv_det), _mm256_mul_ps(w, inv_det)],
    )
}

/// Lanes of `m` as a vector mask.
#[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
#[inline]
fn mask_of(m: u32) -> __m256 {
    let bitsv = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
    _mm256_castsi256_ps(_mm256_cmpeq_epi32(
        _mm256_and_si256(_mm256_set1_epi32(m as i32), bitsv),
        bitsv,
    ))
}

/// The largest value of lanes `on` of `v` (-inf for none).
#[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
#[inline]
fn max_of(v: __m256, on: u32) -> f32 {
    let (_, hi) = range(v, mask_of(on));
    _mm256_cvtss_f32(hi)
}

/// Lane `i`'s ray prepared as a single walk prepares it (the sphere and
/// cone frame too: the scene's own tests take it).
fn lane_ray(rays: &[Ray], i: usize) -> PreparedRay {
    PreparedRay::new(&rays[i])
}

/// The walk of one packet over a scene of triangles: closest hits into
/// `best` (or, `ANY`, the lanes occluded: the return value). Lanes on an
/// edge in single precision are tested by the scene's one-triangle test.
/// Every entry taken costs one from a budget of what a valid tree can
/// hold, so corrupt indices end in a fault, never a hang.
#[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
#[inline]
fn walk<const ANY: bool>(
    w: &WideBvh,
    p: &Packet,
    rays: &[Ray],
    best: &mut Lanes,
    stack: &mut [WideStackItem],
    stats: &mut TraceStats,
) -> u32 {
    let (nodes, blocks) = (w.nodes, w.blocks);
    let mut sp = 0usize;
    let mut budget = nodes.len().saturating_mul(WIDTH + 1);
    let (mut interior, mut leaves, mut boxes, mut tests) = (0u64, 0u64, 0u64, 0u64);
    let mut fault = false;
    // Lanes still looking (any hit: not yet occluded).
    let mut open = p.on;
    // Each lane's limit: its segment's end, then its best hit's `t`.
    let mut limits = _mm256_min_ps(best.t, p.t_max);
    // The entry walked now and the lanes whose rays enter its box; a
    // waiting entry takes two stack items (the entry, then its lanes).
    let (mut cur, mut lanes) = (0u32, p.on);
    // The largest limit among the lanes of the entry walked now, or more:
    // made when an entry is taken from the stack, kept while the walk
    // goes down (a child's lanes are its parent's or fewer, and limits
    // only shrink).
    let mut reach = max_of(limits, lanes);
    let mut touch = 0u32;
    let nt = w.scene.triangles.len();
    // Each lane's ray as the scene's own tests take it, made when first
    // needed (a sphere or a cone in a leaf).
    let mut lanes_ray = LaneRays::default();
    'walk: loop {
        if budget == 0 {
            fault = true;
            break;
        }
        budget -= 1;
        let here = lanes & open;
        if here.count_ones() <= ALONE && here != 0 {
            // Few rays left in this subtree: each walks it alone, where a
            // node costs a ray one box test, not the packet's.
            let mut m = here;
            while m != 0 {
                let i = m.trailing_zeros() as usize;
                m &= m - 1;
                let lt: [f32; 8] = bytemuck::cast(limits);
                let mut r = rays[i];
                r.t_max = lt[i];
                let mut one = Best {
                    hit: Hit::MISS,
                    from_block: None,
                };
                let hit = walk_from::<ANY>(w, &r, cur, &mut one, &mut stack[sp..], stats);
                if ANY {
                    if hit {
                        open &= !(1 << i);
                    }
                } else if one.hit.is_hit() {
                    settle_lane(best, i, &one.finish(w));
                }
            }
            if ANY && open == 0 {
                break;
            }
            limits = _mm256_min_ps(best.t, p.t_max);
        } else if cur & LEAF_BIT == 0 {
            let Some(n) = nodes.get(cur as usize) else {
                fault = true;
                break;
            };
            interior += 1;
            let (cand, tn) = p.enter(n, reach);
            let empty = _mm256_cmpeq_epi32(bytemuck::cast(n.child), _mm256_set1_epi32(-1));
            boxes += (WIDTH as u32
                - (_mm256_movemask_ps(_mm256_castsi256_ps(empty)) as u32).count_ones())
                as u64;
            if cand != 0 {
                if sp + 2 * WIDTH > stack.len() {
                    fault = true;
                    break;
                }
                let tn: [f32; WIDTH] = bytemuck::cast(tn);
                // Each candidate's lanes, each lane by its own ray's test;
                // the entered ones onto the stack (closest hit: sorted far
                // to near by the packet's bound), the nearest taken back.
                let base = sp;
                let mut m = cand;
                while m != 0 {
                    let i = m.trailing_zeros() as usize;
                    m &= m - 1;
                    let l = p.lanes_in(n, i, limits) & lanes & open;
                    if l == 0 {
                        continue;
                    }
                    let e = WideStackItem {
                        child: n.child[i],
                        t: tn[i],
                    };
                    if w.read_ahead {
                        read_entry_ahead(w, e.child, &mut touch);
                    }
                    let mut k = sp;
                    if !ANY {
                        while k > base && stack[k - 2].t < e.t {
                            stack[k] = stack[k - 2];
                            stack[k + 1] = stack[k - 1];
                            k -= 2;
                        }
                    }
                    stack[k] = e;
                    stack[k + 1] = WideStackItem { child: l, t: 0.0 };
                    sp += 2;
                }
                if sp > base {
                    sp -= 2;
                    cur = stack[sp].child;
                    lanes = stack[sp + 1].child;
                    continue;
                }
            }
        } else {
            leaves += 1;
            let (first, count) = leaf_run(cur);
            let Some(run) = blocks.get(first..first + count) else {
                fault = true;
                break;
            };
            let open_here = lanes & open;
            for b in run {
                for slot in 0..4 {
                    let prim = b.prims[slot];
                    if prim == NO_PRIM {
                        break;
                    }
                    tests += 1;
                    if prim as usize >= nt {
                        // A sphere or a cone: each lane by the scene's test.
                        let mut m = open & open_here;
                        while m != 0 {
                            let i = m.trailing_zeros() as usize;
                            m &= m - 1;
                            let r = lanes_ray.get_or_insert_with(i, || PreparedRay::new(&rays[i]));
                            let lt: [f32; 8] = bytemuck::cast(limits);
                            let Some(h) = w.scene.intersect_prim(prim as usize, r, lt[i]) else {
                                continue;
                            };
                            if ANY {
                                open &= !(1 << i);
                            } else {
                                settle_lane(best, i, &h);
                            }
                        }
                        if ANY {
                            if open == 0 {
                                break 'walk;
                            }
                        } else {
                            limits = _mm256_min_ps(best.t, p.t_max);
                        }
                        continue;
                    }
                    let (hit, edge, tuv) = triangle::<ANY>(p, b, slot, limits);
                    let hit = hit & open & open_here;
                    if ANY && hit != 0 {
                        open &= !hit;
                        if open == 0 {
                            break 'walk;
                        }
                    }
                    if !ANY && hit != 0 {
                        // A hit at the best `t` wins by its key: the
                        // primitive's (triangles come first).
                        let key = _mm256_set1_epi32(prim as i32 ^ BIAS);
                        let t = tuv[0];
                        let nearer = _mm256_cmp_ps::<_CMP_LT_OQ>(t, best.t);
                        let tie = _mm256_and_ps(
                            _mm256_cmp_ps::<_CMP_EQ_OQ>(t, best.t),
                            _mm256_castsi256_ps(_mm256_cmpgt_epi32(best.key, key)),
                        );
                        let take = _mm256_and_ps(_mm256_or_ps(nearer, tie), mask_of(hit));
                        best.t = _mm256_blendv_ps(best.t, t, take);
                        best.u = _mm256_blendv_ps(best.u, tuv[1], take);
                        best.v = _mm256_blendv_ps(best.v, tuv[2], take);
                        let takei = _mm256_castps_si256(take);
                        best.key = _mm256_blendv_epi8(best.key, key, takei);
                        let ng = b.normal(slot);
                        for (a, x) in best.ng.iter_mut().zip(ng.to_array()) {
                            *a = _mm256_blendv_ps(*a, splat(x), take);
                        }
                        limits = _mm256_min_ps(best.t, p.t_max);
                    }
                    let edge = edge & open & open_here;
                    if edge != 0 {
                        // Lanes on an edge: the scene's test, ray by ray.
                        let mut m = edge;
                        while m != 0 {
                            let i = m.trailing_zeros() as usize;
                            m &= m - 1;
                            let r = lane_ray(rays, i);
                            let lt: [f32; 8] = bytemuck::cast(limits);
                            let Some(h) = w.scene.intersect_prim(prim as usize, &r, lt[i]) else {
                                continue;
                            };
                            if ANY {
                                open &= !(1 << i);
                                continue;
                            }
                            settle_lane(best, i, &h);
                        }
                        if ANY {
                            if open == 0 {
                                break 'walk;
                            }
                        } else {
                            limits = _mm256_min_ps(best.t, p.t_max);
                        }
                    }
                }
            }
        }
        // Back to the nearest entry waiting that lies within the reach of
        // one of its lanes still looking.
        while sp >= 2 {
            sp -= 2;
            let (e, l) = (stack[sp], stack[sp + 1].child & open);
            if l == 0 {
                continue;
            }
            reach = max_of(limits, l);
            if e.t <= reach {
                cur = e.child;
                lanes = l;
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
    stats.prim_tests += tests * p.on.count_ones() as u64;
    stats.faults += fault as u64;
    if fault {
        // A corrupt hierarchy: the lanes' answers are not to be used.
        return p.on;
    }
    p.on & !open
}

/// The packet's rays prepared one by one for the scene's own tests,
/// each when first asked for.
#[derive(Default)]
struct LaneRays([Option<PreparedRay>; PACKET_LANES]);

impl LaneRays {
    /// Lane `i`'s ray, made by `make` the first time.
    #[inline(always)]
    fn get_or_insert_with(&mut self, i: usize, make: impl FnOnce() -> PreparedRay) -> &PreparedRay {
        self.0[i].get_or_insert_with(make)
    }
}

/// Lane `i`'s best becomes `h` when it beats it.
#[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
#[inline]
fn settle_lane(best: &mut Lanes, i: usize, h: &Hit) {
    let mut t: [f32; 8] = bytemuck::cast(best.t);
    let mut key: [i32; 8] = bytemuck::cast(best.key);
    let hk = ((h.geom_id << 30 | h.prim_id) as i32) ^ BIAS;
    if h.t < t[i] || (h.t == t[i] && hk < key[i]) {
        t[i] = h.t;
        key[i] = hk;
        let mut u: [f32; 8] = bytemuck::cast(best.u);
        let mut v: [f32; 8] = bytemuck::cast(best.v);
        (u[i], v[i]) = (h.u, h.v);
        best.t = bytemuck::cast(t);
        best.u = bytemuck::cast(u);
        best.v = bytemuck::cast(v);
        best.key = bytemuck::cast(key);
        for (a, x) in best.ng.iter_mut().zip(h.ng.to_array()) {
            let mut n: [f32; 8] = bytemuck::cast(*a);
            n[i] = x;
            *a = bytemuck::cast(n);
        }
    }
}

impl WideBvh<'_> {
    /// Closest hits of `rays` into `hits` (as long), eight rays a packet
    /// where they agree on direction signs ([`crate::wide::packet`]), the
    /// others one by one: each hit [`WideBvh::intersect`]'s bit for bit.
    /// The stack as for [`WideBvh::intersect`].
    ///
    /// # Safety
    /// As [`WideBvh::intersect_avx2`].
    ///
    /// # Panics
    /// When `hits` is shorter than `rays`.
    #[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
    pub fn intersect_packets_avx2(
        &self,
        rays: &[Ray],
        hits: &mut [Hit],
        stack: &mut [WideStackItem],
        stats: &mut TraceStats,
    ) {
        let hits = &mut hits[..rays.len()];
        for (rs, hs) in rays.chunks(PACKET_LANES).zip(hits.chunks_mut(PACKET_LANES)) {
            let alone = self.packet_closest(rs, hs, stack, stats);
            for i in (0..rs.len()).filter(|&i| alone >> i & 1 != 0) {
                hs[i] = self.intersect_avx2(&rs[i], stack, stats);
            }
        }
    }

    /// Whether anything lies on each of `rays`' segments, into `occluded`
    /// (as long), in packets as [`WideBvh::intersect_packets_avx2`]: each
    /// answer [`WideBvh::occluded`]'s.
    ///
    /// # Safety
    /// As [`WideBvh::intersect_avx2`].
    ///
    /// # Panics
    /// When `occluded` is shorter than `rays`.
    #[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
    pub fn occluded_packets_avx2(
        &self,
        rays: &[Ray],
        occluded: &mut [bool],
        stack: &mut [WideStackItem],
        stats: &mut TraceStats,
    ) {
        let occluded = &mut occluded[..rays.len()];
        for (rs, os) in rays
            .chunks(PACKET_LANES)
            .zip(occluded.chunks_mut(PACKET_LANES))
        {
            let alone = self.packet_any(rs, os, stack, stats);
            for i in (0..rs.len()).filter(|&i| alone >> i & 1 != 0) {
                os[i] = self.occluded_avx2(&rs[i], stack, stats);
            }
        }
    }

    /// One packet's closest hits into `hits`; returns the lanes left for
    /// single walks (all of them when the packet is not traced together).
    #[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
    #[inline]
    fn packet_closest(
        &self,
        rays: &[Ray],
        hits: &mut [Hit],
        stack: &mut [WideStackItem],
        stats: &mut TraceStats,
    ) -> u32 {
        let all = (1u32 << rays.len()) - 1;
        let Some(p) = Packet::load::<false>(rays) else {
            return all;
        };
        let valid = p.valid;
        if stack.is_empty() {
            stats.faults += 1;
            return all & !valid;
        }
        let mut best = Lanes::none();
        let bad = walk::<false>(self, &p, rays, &mut best, stack, stats);
        stats.rays += p.on.count_ones() as u64;
        best.write(p.on, bad, hits);
        // Invalid rays miss; lanes left out go alone.
        let mut m = all & !valid;
        while m != 0 {
            hits[m.trailing_zeros() as usize] = Hit::MISS;
            stats.rays += 1;
            m &= m - 1;
        }
        valid & !p.on
    }

    /// One packet's any-hit answers into `out`; returns the lanes left for
    /// single walks, as [`WideBvh::packet_closest`].
    #[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
    #[inline]
    fn packet_any(
        &self,
        rays: &[Ray],
        out: &mut [bool],
        stack: &mut [WideStackItem],
        stats: &mut TraceStats,
    ) -> u32 {
        let all = (1u32 << rays.len()) - 1;
        let Some(p) = Packet::load::<true>(rays) else {
            return all;
        };
        let valid = p.valid;
        if stack.is_empty() {
            stats.faults += 1;
            return all & !valid;
        }
        let mut unused = Lanes::none();
        let occluded = walk::<true>(self, &p, rays, &mut unused, stack, stats);
        stats.rays += p.on.count_ones() as u64;
        for (i, o) in out.iter_mut().enumerate().take(rays.len()) {
            if p.on >> i & 1 != 0 {
                *o = occluded >> i & 1 != 0;
            } else if valid >> i & 1 == 0 {
                *o = false;
                stats.rays += 1;
            }
        }
        valid & !p.on
    }
}
