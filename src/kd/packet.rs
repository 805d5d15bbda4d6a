//! Packets of 8 coherent rays through a kd-tree (Wald, Slusallek, Benthin
//! and Wagner 2001): the packet walks the tree once, deciding each split
//! for all its rays at once, and each triangle is tested against all of
//! them at once, on the lane arrays of [`crate::geom::lanes`].
//!
//! The rays of a packet must agree on the sign of each direction
//! component (true of a tile of camera rays, or of shadow rays from a
//! tile towards one light); other groups are traced ray by ray. Lanes
//! whose watertight test would order the axes unlike the packet's first
//! ray (its dominant axis differs) stay in the packet for traversal and
//! take their triangle tests alone, as the single ray does. Every ray
//! gets exactly the hit of
//! [`Traversal::Hierarchical`](super::Traversal::Hierarchical): each lane
//! takes the same decisions at the nodes it needs, tests the primitives
//! of a superset of the same leaves with the same arithmetic, keeps its
//! best hit by the same rule, and stops where the single ray stops.
//!
//! A lane that does not visit a node carries the empty interval
//! (+inf, -inf) there, so masks are never stored: a lane is active where
//! its entry distance is at most its exit distance.
//!
//! The packet's stack lives in the caller's [`KdStackItem`]s: one entry
//! takes [`ITEMS_PER_ENTRY`] of them (the node, and the entry and exit
//! distance of each lane).

// Index loops over the lanes, on purpose (see crate::geom::lanes).
#![allow(clippy::needless_range_loop)]

use super::node::{KdRopes, KdStackItem, KD_STACK_LEN};
use super::traverse::{children, inside_leaf, Steps};
use super::KdTree;
use crate::geom::lanes::{F8, M8};
use crate::geom::leaf::beats;
use crate::geom::{intersect_triangle, Aabb, Hit, PreparedRay, Ray, Vec3, GEOM_TRIANGLES};
use crate::limits::KD_MAX_DEPTH;
use crate::TraceStats;

pub use crate::geom::lanes::LANES;

/// Stack items one packet entry takes: the node and 8 entry and 8 exit
/// distances (2 words per item).
pub const ITEMS_PER_ENTRY: usize = (2 + 2 * LANES) / 2;

/// Packet entries the stack must hold: one per level of the deepest tree,
/// and a few to spare.
const ENTRIES: usize = KD_MAX_DEPTH as usize + 4;

const _: () = assert!(ITEMS_PER_ENTRY * ENTRIES <= KD_STACK_LEN);

const INF: F8 = F8::splat(f32::INFINITY);
const NEG_INF: F8 = F8::splat(f32::NEG_INFINITY);

/// Eight rays prepared together: each lane holds what
/// [`PreparedRay::new`] computes for its ray.
pub(crate) struct Packet {
    /// Lanes holding a valid ray.
    valid: [bool; LANES],
    o: [F8; 3],
    d: [F8; 3],
    inv: [F8; 3],
    sx: F8,
    sy: F8,
    sz: F8,
    t_min: F8,
    t_max: F8,
    /// Each direction's length and the unit direction (what the sphere
    /// and cone tests normalise by), once per packet; set only when the
    /// scene has spheres or cones.
    dir_len: F8,
    unit: [F8; 3],
    /// Valid lanes whose watertight axes differ from `k` (their dominant
    /// direction component is another): their triangle tests run alone.
    odd_k: M8,
    /// Whether the rays move towards +axis, per axis (shared).
    up: [bool; 3],
    /// The watertight test's axes (shared).
    k: [usize; 3],
}

impl Packet {
    pub(crate) const EMPTY: Packet = Packet {
        valid: [false; LANES],
        o: [F8::splat(0.0); 3],
        d: [F8::splat(1.0); 3],
        inv: [F8::splat(1.0); 3],
        sx: F8::splat(0.0),
        sy: F8::splat(0.0),
        sz: F8::splat(0.0),
        t_min: F8::splat(0.0),
        t_max: F8::splat(0.0),
        dir_len: F8::splat(1.0),
        unit: [F8::splat(1.0); 3],
        odd_k: M8::NONE,
        up: [true; 3],
        k: [0, 1, 2],
    };

    /// Lane `i` holds ray `r`.
    #[inline(always)]
    fn set_lane(&mut self, i: usize, r: &Ray) {
        for a in 0..3 {
            self.o[a].0[i] = r.origin[a];
            self.d[a].0[i] = r.dir[a];
        }
        self.t_min.0[i] = r.t_min;
        self.t_max.0[i] = r.t_max;
    }

    /// Loads `rays` (at most 8; missing and invalid lanes are off), with
    /// the unit directions when the scene is `curved` (has spheres or
    /// cones). False when they do not move alike: a direction component
    /// of zero or too small to invert, or signs that differ (the packet is
    /// then unusable).
    #[inline(always)]
    pub(crate) fn load(&mut self, rays: &[Ray], curved: bool) -> bool {
        let rays = &rays[..rays.len().min(LANES)];
        let Some(last) = rays.last() else {
            return false;
        };
        // Every lane first (missing ones repeat the last ray), then which
        // are valid, by [`Ray::is_valid`]'s arithmetic on the lanes: one
        // vector test for the packet, not a scalar one per ray.
        for i in 0..LANES {
            self.set_lane(i, rays.get(i).unwrap_or(last));
        }
        let zero = F8::splat(0.0);
        let (o, d) = (self.o, self.d);
        let zeros =
            (o[0] * zero + o[1] * zero) + (o[2] * zero + d[0] * zero) + (d[1] * zero + d[2] * zero);
        let valid = zeros.eq(zero)
            & (d[0].ne(zero) | d[1].ne(zero) | d[2].ne(zero))
            & self.t_min.le(self.t_max);
        let bits = valid.bits() & (u16::MAX >> (16 - rays.len())) as u8;
        if bits == 0 {
            return false;
        }
        // Missing and invalid lanes (rare) take the first valid ray.
        let first = &rays[bits.trailing_zeros() as usize];
        for i in 0..LANES {
            self.valid[i] = bits >> i & 1 != 0;
            if !self.valid[i] {
                self.set_lane(i, first);
            }
        }
        let p0 = PreparedRay::new(first);
        self.up = [p0.dir.x > 0.0, p0.dir.y > 0.0, p0.dir.z > 0.0];
        self.k = [p0.kx, p0.ky, p0.kz];
        // Lane by lane what PreparedRay::new computes, checked alike.
        let one = F8::splat(1.0);
        let mut alike = M8([u32::MAX; LANES]);
        for a in 0..3 {
            self.inv[a] = one / self.d[a];
            let same_sign = if self.up[a] {
                self.d[a].gt(zero)
            } else {
                self.d[a].lt(zero)
            };
            alike = alike & same_sign & self.inv[a].lt(INF) & self.inv[a].gt(NEG_INF);
        }
        let [kx, ky, kz] = self.k;
        let abs = |v: F8| v.max(zero - v);
        let (ax, ay, az) = (abs(self.d[0]), abs(self.d[1]), abs(self.d[2]));
        // PreparedRay::new's choice of kz: x on ties with y and z, then y.
        let is_x = ax.ge(ay) & ax.ge(az);
        let is_y = !is_x & ay.ge(az);
        let is_z = !is_x & !is_y;
        self.odd_k = !([is_x, is_y, is_z][kz]);
        self.sx = self.d[kx] / self.d[kz];
        self.sy = self.d[ky] / self.d[kz];
        self.sz = one / self.d[kz];
        if curved {
            let d = self.d;
            self.dir_len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            self.unit = [
                d[0] / self.dir_len,
                d[1] / self.dir_len,
                d[2] / self.dir_len,
            ];
        }
        alike.count() == LANES as u32
    }

    /// Each valid lane's segment inside box `b` (the scene's trace box):
    /// [`KdTree::scene_segment`]'s arithmetic lane by lane (every lane's
    /// 1/dir is finite). Lanes that miss it, or hold no valid ray, get the
    /// empty interval (+inf, -inf) and are clear in the mask.
    #[inline(always)]
    pub(crate) fn segment(&self, b: &Aabb) -> (F8, F8, M8) {
        let (tn, tf) = self.clip(b, self.t_min, self.t_max);
        let mut valid = M8::NONE;
        for i in 0..LANES {
            valid.0[i] = if self.valid[i] { u32::MAX } else { 0 };
        }
        let hit_box = valid & tn.le(tf);
        (
            hit_box.select(tn, INF),
            hit_box.select(tf, NEG_INF),
            hit_box,
        )
    }

    /// Each lane's interval `[t0, t1]` clipped to box `b` by the slab test
    /// (`Aabb::clip_ray`'s arithmetic on finite 1/dir; NaN keeps a bound).
    #[inline(always)]
    fn clip(&self, b: &Aabb, mut t0: F8, mut t1: F8) -> (F8, F8) {
        for a in 0..3 {
            let lo = (F8::splat(b.min[a]) - self.o[a]) * self.inv[a];
            let hi = (F8::splat(b.max[a]) - self.o[a]) * self.inv[a];
            let order = lo.le(hi);
            t0 = t0.max(order.select(lo, hi));
            t1 = t1.min(order.select(hi, lo));
        }
        (t0, t1)
    }

    /// Where each lane leaves the leaf box of `rp`, through which face, and
    /// the lanes that leave through an edge or corner:
    /// [`KdTree::leaf_exit_at_edge`]'s arithmetic and tie rule lane by lane
    /// (the packet's lanes share their direction signs, none of them zero).
    #[inline(always)]
    pub(crate) fn leaf_exit(&self, rp: &KdRopes) -> (F8, [u8; LANES], M8) {
        let mut exit = INF;
        let mut faces = [0u32; LANES];
        let mut ts = [INF; 3];
        for (a, ta) in ts.iter_mut().enumerate() {
            let bound = if self.up[a] { rp.max[a] } else { rp.min[a] };
            *ta = (F8::splat(bound) - self.o[a]) * self.inv[a];
            let nearer = ta.lt(exit);
            exit = nearer.select(*ta, exit);
            // Selects on the lanes' masks, not branches.
            let f = (2 * a + self.up[a] as usize) as u32;
            for (fi, m) in faces.iter_mut().zip(nearer.0) {
                *fi = (f & m) | (*fi & !m);
            }
        }
        let [x, y, z] = ts.map(|t| t.le(exit));
        (exit, faces.map(|f| f as u8), (x & y) | (x & z) | (y & z))
    }

    /// Lane `i` as the single ray's prepared form (for the cases a lane
    /// decides alone: spheres, cones, triangle edges).
    #[inline(always)]
    pub(crate) fn ray(&self, i: usize) -> PreparedRay {
        if self.odd_k.get(i) {
            let o = Vec3::new(self.o[0].0[i], self.o[1].0[i], self.o[2].0[i]);
            let d = Vec3::new(self.d[0].0[i], self.d[1].0[i], self.d[2].0[i]);
            return PreparedRay::new(&Ray::new(o, d, self.t_min.0[i], self.t_max.0[i]));
        }
        PreparedRay {
            origin: Vec3::new(self.o[0].0[i], self.o[1].0[i], self.o[2].0[i]),
            dir: Vec3::new(self.d[0].0[i], self.d[1].0[i], self.d[2].0[i]),
            inv_dir: Vec3::new(self.inv[0].0[i], self.inv[1].0[i], self.inv[2].0[i]),
            t_min: self.t_min.0[i],
            t_max: self.t_max.0[i],
            kx: self.k[0],
            ky: self.k[1],
            kz: self.k[2],
            sx: self.sx.0[i],
            sy: self.sy.0[i],
            sz: self.sz.0[i],
            // The packet's (made alike: `sqrt` and a division a lane) where
            // the scene has spheres or cones; no test reads them elsewhere.
            dir_len: self.dir_len.0[i],
            unit_dir: Vec3::new(self.unit[0].0[i], self.unit[1].0[i], self.unit[2].0[i]),
        }
    }
}

/// What a packet does at its leaves: closest hit or any hit.
pub(crate) trait PacketVisitor {
    /// One answer per ray: a [`Hit`] or an occlusion flag.
    type Answer;
    /// A fresh visitor for packet `p`.
    fn new(p: &Packet) -> Self;
    /// Tests `refs` for the lanes `on` (their segments end at `exit`);
    /// returns the lanes that are done.
    fn visit(&mut self, tree: &KdTree, p: &Packet, refs: &[u32], on: M8, exit: F8) -> M8;
    /// Primitive tests done.
    fn tests(&self) -> u64;
    /// Writes the lanes' answers to `out` (one per ray of the packet).
    fn answers(&self, out: &mut [Self::Answer]);
    /// The answer for a ray that cannot join a packet: hierarchical traversal.
    fn single(
        tree: &KdTree,
        ray: &Ray,
        stack: &mut [KdStackItem],
        stats: &mut TraceStats,
    ) -> Self::Answer;
}

/// Closest hits, one per lane: the best distance of each lane in a lane
/// array (the range every later test takes), the hit records beside it.
pub(crate) struct ClosestLanes {
    pub best: [Hit; LANES],
    /// `best[i].t`, or the ray's `t_max` while lane i has no hit.
    t_max: F8,
    /// Lanes with a hit.
    found: M8,
    pub tests: u64,
}

impl ClosestLanes {
    /// Keeps `h` for lane `i` by the single ray's rule.
    #[inline(always)]
    fn offer(&mut self, i: usize, h: Hit) {
        let b = &self.best[i];
        if beats(&h, b) {
            self.best[i] = h;
            self.t_max.0[i] = h.t;
            self.found.0[i] = u32::MAX;
        }
    }
}

/// Any hit, one answer per lane.
pub(crate) struct AnyLanes {
    pub hit: M8,
    t_max: F8,
    pub tests: u64,
}

/// Vertex `q` relative to the lanes' origins `o`, both in the watertight
/// test's axis order `k`. A function, not a closure: a closure is compiled
/// apart from the AVX2 kernels that call it (without their features) and
/// was not inlined (a call with SSE2 code, a quarter of a shadow packet's
/// instructions on spd:tetra).
#[inline(always)]
fn relative(q: Vec3, k: [usize; 3], o: &[F8; 3]) -> [F8; 3] {
    [
        F8::splat(q[k[0]]) - o[0],
        F8::splat(q[k[1]]) - o[1],
        F8::splat(q[k[2]]) - o[2],
    ]
}

/// Woop's watertight test of one triangle against eight rays, lane by
/// lane the arithmetic of [`intersect_triangle`], for the lanes `on`.
/// Returns the lanes hit in `[t_min, t_max]` with their (t, u, v), and
/// the lanes the caller tests alone: those the single test would settle
/// in double precision (a barycentric of exactly 0), and those whose
/// watertight axes are not the packet's.
#[inline(always)]
fn triangle8(p: &Packet, v: [Vec3; 3], on: M8, t_max: F8) -> (M8, M8, F8, F8, F8) {
    let [kx, ky, kz] = p.k;
    let o = [p.o[kx], p.o[ky], p.o[kz]];
    let [a_x, a_y, a_z] = relative(v[0], p.k, &o);
    let [b_x, b_y, b_z] = relative(v[1], p.k, &o);
    let [c_x, c_y, c_z] = relative(v[2], p.k, &o);
    let ax = a_x - p.sx * a_z;
    let ay = a_y - p.sy * a_z;
    let bx = b_x - p.sx * b_z;
    let by = b_y - p.sy * b_z;
    let cx = c_x - p.sx * c_z;
    let cy = c_y - p.sy * c_z;
    let u = cx * by - cy * bx;
    let vv = ax * cy - ay * cx;
    let w = bx * ay - by * ax;
    let zero = F8::splat(0.0);
    let edge = u.eq(zero) | vv.eq(zero) | w.eq(zero);
    let mixed = (u.lt(zero) | vv.lt(zero) | w.lt(zero)) & (u.gt(zero) | vv.gt(zero) | w.gt(zero));
    let det = u + vv + w;
    let inv_det = F8::splat(1.0) / det;
    let t = (u * (p.sz * a_z) + vv * (p.sz * b_z) + w * (p.sz * c_z)) * inv_det;
    // det not 0 nor NaN (ne is true for NaN: eq excludes it); t in range.
    let ok = !mixed & det.ne(zero) & det.eq(det) & t.ge(p.t_min) & t.le(t_max);
    let (shared, odd) = (on & !p.odd_k, on & p.odd_k);
    (
        shared & !edge & ok,
        (shared & edge) | odd,
        t,
        vv * inv_det,
        w * inv_det,
    )
}

/// The lanes of `on` whose segments may pass within `radius` of `center`
/// (squared distances, no square root): a cheap filter before an exact
/// test, widened by 1/64 of the radius so that no rounding can drop a
/// lane the exact test would hit.
#[inline(always)]
fn near_sphere(p: &Packet, center: Vec3, radius: f32, on: M8, t_max: F8) -> M8 {
    let s8 = F8::splat;
    let r = radius * (1.0 + 1.0 / 64.0);
    let oc = [
        p.o[0] - s8(center.x),
        p.o[1] - s8(center.y),
        p.o[2] - s8(center.z),
    ];
    let dd = p.d[0] * p.d[0] + p.d[1] * p.d[1] + p.d[2] * p.d[2];
    let cx = oc[1] * p.d[2] - oc[2] * p.d[1];
    let cy = oc[2] * p.d[0] - oc[0] * p.d[2];
    let cz = oc[0] * p.d[1] - oc[1] * p.d[0];
    let r2dd = s8(r * r) * dd;
    let close = (cx * cx + cy * cy + cz * cz).le(r2dd);
    // The closest approach's t, and the sphere's half-width in t (squared).
    let tc = (s8(0.0) - (oc[0] * p.d[0] + oc[1] * p.d[1] + oc[2] * p.d[2])) / dd;
    let w2 = s8(r * r) / dd;
    let before = p.t_min - tc;
    let after = tc - t_max;
    let reach_min = before.le(s8(0.0)) | (before * before).le(w2);
    let reach_max = after.le(s8(0.0)) | (after * after).le(w2);
    // A NaN anywhere (huge values) keeps the lane: the exact test decides.
    let unsure = !(close | !close) | tc.ne(tc);
    on & ((close & reach_min & reach_max) | unsure)
}

/// The box of a cone's two end discs (normal `w`, the axis direction),
/// widened by 1/64 of its size: what [`crate::Cone::bounds`] gives, with
/// room for rounding, without a library square root.
#[inline(always)]
fn cone_box(cone: &crate::Cone, w: Vec3, len: f32) -> crate::geom::Aabb {
    let (b, a) = (Vec3::from(cone.base), Vec3::from(cone.apex));
    let e = (Vec3::ONE - w * w).max(Vec3::ZERO);
    let sq = crate::geom::lanes::sqrt_rn;
    let e = Vec3::new(sq(e.x), sq(e.y), sq(e.z));
    let (rb, ra) = (cone.base_radius, cone.apex_radius);
    let lo = (b - e * rb).min(a - e * ra);
    let hi = (b + e * rb).max(a + e * ra);
    let pad = Vec3::splat((len + rb.max(ra)) / 64.0);
    crate::geom::Aabb {
        min: lo - pad,
        max: hi + pad,
    }
}

/// The lanes of `on` whose segments meet `bx` (a slab test, on every
/// lane's finite 1/dir); NaN keeps a lane.
#[inline(always)]
fn near_box(p: &Packet, bx: crate::geom::Aabb, on: M8, t_max: F8) -> M8 {
    let (t0, t1) = p.clip(&bx, p.t_min, t_max);
    on & !t0.gt(t1)
}

/// The sphere test of [`crate::Sphere::intersect`] against eight rays,
/// lane by lane the same arithmetic (the square roots correctly rounded
/// in both). Returns the lanes of `on` hit in `[t_min, t_max]` and t.
#[inline(always)]
fn sphere8(p: &Packet, sp: &crate::Sphere, on: M8, t_max: F8) -> (M8, F8) {
    if !(sp.radius > 0.0) {
        return (M8::NONE, F8::splat(0.0));
    }
    let on = near_sphere(p, Vec3::from(sp.center), sp.radius, on, t_max);
    if !on.any() {
        return (M8::NONE, F8::splat(0.0));
    }
    let inv_r = F8::splat(1.0 / sp.radius);
    let dot = |a: [F8; 3], b: [F8; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let to_t = F8::splat(sp.radius) / p.dir_len;
    let c = sp.center;
    let oc = [
        (p.o[0] - F8::splat(c[0])) * inv_r,
        (p.o[1] - F8::splat(c[1])) * inv_r,
        (p.o[2] - F8::splat(c[2])) * inv_r,
    ];
    let d = p.unit;
    let uc = F8::splat(0.0) - dot(oc, d);
    let h = [oc[0] + d[0] * uc, oc[1] + d[1] * uc, oc[2] + d[2] * uc];
    let disc = F8::splat(1.0) - dot(h, h);
    let real = disc.ge(F8::splat(0.0));
    let root = disc.sqrt();
    let t0 = (uc - root) * to_t;
    let t1 = (uc + root) * to_t;
    let in0 = real & t0.ge(p.t_min) & t0.le(t_max);
    let in1 = real & t1.ge(p.t_min) & t1.le(t_max);
    (on & (in0 | in1), in0.select(t0, t1))
}

/// The cone test of [`crate::Cone::intersect`] against eight rays, lane
/// by lane the same arithmetic. Returns the lanes of `on` hit in
/// `[t_min, t_max]` with t, the axis parameter and the normal.
#[inline(always)]
fn cone8(p: &Packet, cone: &crate::Cone, on: M8, t_max: F8) -> (M8, F8, F8, [F8; 3]) {
    let none = (
        M8::NONE,
        F8::splat(0.0),
        F8::splat(0.0),
        [F8::splat(0.0); 3],
    );
    if !(cone.base_radius >= 0.0 && cone.apex_radius >= 0.0) {
        return none;
    }
    let b = Vec3::from(cone.base);
    let axis = Vec3::from(cone.apex) - b;
    // Vec3::length's sum, with the same rounding.
    let len = crate::geom::lanes::sqrt_rn(axis.dot(axis));
    if !(len > 0.0) {
        return none;
    }
    let w = axis / len;
    let slope = (cone.apex_radius - cone.base_radius) / len;
    let inv_len = 1.0 / len;
    let center = b + axis * 0.5;
    // The cone lies within the boxes of its end discs; lanes whose
    // segments miss that box (widened by 1/64 of the cone's size) are done.
    let on = near_box(p, cone_box(cone, w, len), on, t_max);
    if !on.any() {
        return none;
    }
    let s8 = F8::splat;
    let dot = |a: [F8; 3], b: [F8; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let (dir_len, d) = (p.dir_len, p.unit);
    let co = [
        s8(center.x) - p.o[0],
        s8(center.y) - p.o[1],
        s8(center.z) - p.o[2],
    ];
    let shift = dot(co, d);
    let q = [
        (p.o[0] + d[0] * shift - s8(b.x)) * s8(inv_len),
        (p.o[1] + d[1] * shift - s8(b.y)) * s8(inv_len),
        (p.o[2] + d[2] * shift - s8(b.z)) * s8(inv_len),
    ];
    let w8 = [s8(w.x), s8(w.y), s8(w.z)];
    let qs = dot(q, w8);
    let ds = dot(d, w8);
    let qp = [q[0] - w8[0] * qs, q[1] - w8[1] * qs, q[2] - w8[2] * qs];
    let dp = [d[0] - w8[0] * ds, d[1] - w8[1] * ds, d[2] - w8[2] * ds];
    let k = s8(cone.base_radius * inv_len) + s8(slope) * qs;
    let m = s8(slope) * ds;
    let a = dot(dp, dp) - m * m;
    let bh = dot(qp, dp) - k * m;
    let c = dot(qp, qp) - k * k;
    let disc = bh * bh - a * c;
    let real = on & disc.ge(s8(0.0));
    if !real.any() {
        return none;
    }
    let sq = disc.sqrt();
    let zero = s8(0.0);
    let qq = zero - (bh + bh.ge(zero).select(sq, zero - sq));
    let degenerate = qq.eq(zero);
    let t0 = degenerate.select(a.ne(zero).select(zero, s8(f32::NAN)), qq / a);
    let t1 = degenerate.select(s8(f32::NAN), c / qq);
    let swap = t0.gt(t1);
    let (u0, u1) = (swap.select(t1, t0), swap.select(t0, t1));
    // The first root that passes, as the single test's loop takes them.
    let mut hit = M8::NONE;
    let (mut t_hit, mut s_hit, mut u_hit) = (zero, zero, zero);
    for u in [u0, u1] {
        let t = (shift + u * s8(len)) / dir_len;
        let sv = qs + u * ds;
        let radius = k + m * u;
        let ok =
            !hit & t.ge(p.t_min) & t.le(t_max) & sv.ge(zero) & sv.le(s8(1.0)) & !radius.lt(zero);
        t_hit = ok.select(t, t_hit);
        s_hit = ok.select(sv, s_hit);
        u_hit = ok.select(u, u_hit);
        hit = hit | ok;
    }
    let hit = real & hit;
    let radius = k + m * u_hit;
    let rs = radius * s8(slope);
    let ng = [
        (qp[0] + dp[0] * u_hit - w8[0] * rs) * s8(len),
        (qp[1] + dp[1] * u_hit - w8[1] * rs) * s8(len),
        (qp[2] + dp[2] * u_hit - w8[2] * rs) * s8(len),
    ];
    (hit, t_hit, s_hit, ng)
}

impl PacketVisitor for ClosestLanes {
    type Answer = Hit;

    fn new(p: &Packet) -> ClosestLanes {
        ClosestLanes {
            best: [Hit::MISS; LANES],
            t_max: p.t_max,
            found: M8::NONE,
            tests: 0,
        }
    }

    fn tests(&self) -> u64 {
        self.tests
    }

    fn answers(&self, out: &mut [Hit]) {
        out.copy_from_slice(&self.best[..out.len()]);
    }

    fn single(tree: &KdTree, ray: &Ray, stack: &mut [KdStackItem], stats: &mut TraceStats) -> Hit {
        tree.intersect(ray, super::Traversal::Hierarchical, stack, stats)
    }

    #[inline(always)]
    fn visit(&mut self, tree: &KdTree, p: &Packet, refs: &[u32], on: M8, exit: F8) -> M8 {
        let scene = &tree.scene;
        let nt = scene.triangles.len();
        let lanes = on.count() as u64;
        for &r in refs {
            self.tests += lanes;
            let prim = r as usize;
            if prim < nt {
                let tri = scene.triangle(prim);
                let (hit, edge, t, u, v) = triangle8(p, tri, on, self.t_max);
                if !(hit | edge).any() {
                    continue;
                }
                let [a, b, c] = tri;
                let ng = (a - b).cross(c - a);
                for i in 0..LANES {
                    let found = if hit.get(i) {
                        Some((t.0[i], u.0[i], v.0[i]))
                    } else if edge.get(i) {
                        intersect_triangle(&p.ray(i), a, b, c, self.t_max.0[i])
                    } else {
                        None
                    };
                    if let Some((t, u, v)) = found {
                        let h = Hit {
                            t,
                            u,
                            v,
                            ng,
                            geom_id: GEOM_TRIANGLES,
                            prim_id: r,
                        };
                        self.offer(i, h);
                    }
                }
            } else if let Some(sp) = scene.spheres.get(prim - nt) {
                let (hit, t) = sphere8(p, sp, on, self.t_max);
                if !hit.any() {
                    continue;
                }
                let c = Vec3::from(sp.center);
                for i in 0..LANES {
                    if hit.get(i) {
                        let t = t.0[i];
                        let h = Hit {
                            t,
                            u: 0.0,
                            v: 0.0,
                            ng: p.ray(i).at(t) - c,
                            geom_id: crate::geom::GEOM_SPHERES,
                            prim_id: (prim - nt) as u32,
                        };
                        self.offer(i, h);
                    }
                }
            } else if let Some(cone) = scene.cones.get(prim - nt - scene.spheres.len()) {
                let (hit, t, u, ng) = cone8(p, cone, on, self.t_max);
                for i in 0..LANES {
                    if hit.get(i) {
                        let h = Hit {
                            t: t.0[i],
                            u: u.0[i],
                            v: 0.0,
                            ng: Vec3::new(ng[0].0[i], ng[1].0[i], ng[2].0[i]),
                            geom_id: crate::geom::GEOM_CONES,
                            prim_id: (prim - nt - scene.spheres.len()) as u32,
                        };
                        self.offer(i, h);
                    }
                }
            }
        }
        // inside_leaf, lane by lane: clearly before the leaf's exit.
        let mut inside = M8::NONE;
        for i in 0..LANES {
            inside.0[i] = if inside_leaf(self.t_max.0[i], exit.0[i]) {
                u32::MAX
            } else {
                0
            };
        }
        on & self.found & inside
    }
}

impl PacketVisitor for AnyLanes {
    type Answer = bool;

    fn new(p: &Packet) -> AnyLanes {
        AnyLanes {
            hit: M8::NONE,
            t_max: p.t_max,
            tests: 0,
        }
    }

    fn tests(&self) -> u64 {
        self.tests
    }

    fn answers(&self, out: &mut [bool]) {
        for (i, o) in out.iter_mut().enumerate() {
            *o = self.hit.get(i);
        }
    }

    fn single(tree: &KdTree, ray: &Ray, stack: &mut [KdStackItem], stats: &mut TraceStats) -> bool {
        tree.occluded(ray, super::Traversal::Hierarchical, stack, stats)
    }

    #[inline(always)]
    fn visit(&mut self, tree: &KdTree, p: &Packet, refs: &[u32], on: M8, _: F8) -> M8 {
        let scene = &tree.scene;
        let nt = scene.triangles.len();
        let mut live = on & !self.hit;
        for &r in refs {
            if !live.any() {
                break;
            }
            self.tests += live.count() as u64;
            let prim = r as usize;
            if prim < nt {
                let tri = scene.triangle(prim);
                let (hit, edge, ..) = triangle8(p, tri, live, self.t_max);
                let mut got = hit;
                if edge.any() {
                    let [a, b, c] = tri;
                    for i in 0..LANES {
                        if edge.get(i)
                            && intersect_triangle(&p.ray(i), a, b, c, self.t_max.0[i]).is_some()
                        {
                            got.0[i] = u32::MAX;
                        }
                    }
                }
                self.hit = self.hit | got;
                live = live & !got;
            } else if let Some(sp) = scene.spheres.get(prim - nt) {
                let (hit, _) = sphere8(p, sp, live, self.t_max);
                self.hit = self.hit | hit;
                live = live & !hit;
            } else if let Some(cone) = scene.cones.get(prim - nt - scene.spheres.len()) {
                let (hit, ..) = cone8(p, cone, live, self.t_max);
                self.hit = self.hit | hit;
                live = live & !hit;
            }
        }
        on & self.hit
    }
}

/// Writes packet entry `e` (node, entry and exit distances) into the stack.
#[inline(always)]
fn push(stack: &mut [KdStackItem], e: usize, node: u32, tn: F8, tf: F8) {
    let s = &mut stack[e * ITEMS_PER_ENTRY..(e + 1) * ITEMS_PER_ENTRY];
    s[0] = KdStackItem { node, t: 0.0 };
    for i in 0..LANES / 2 {
        s[1 + i] = KdStackItem {
            node: tn.0[2 * i].to_bits(),
            t: tn.0[2 * i + 1],
        };
        s[1 + LANES / 2 + i] = KdStackItem {
            node: tf.0[2 * i].to_bits(),
            t: tf.0[2 * i + 1],
        };
    }
}

/// Reads packet entry `e` back: (node, entry and exit distances).
#[inline(always)]
fn pop(stack: &[KdStackItem], e: usize) -> (u32, F8, F8) {
    let s = &stack[e * ITEMS_PER_ENTRY..(e + 1) * ITEMS_PER_ENTRY];
    let mut tn = F8::splat(0.0);
    let mut tf = F8::splat(0.0);
    for i in 0..LANES / 2 {
        tn.0[2 * i] = f32::from_bits(s[1 + i].node);
        tn.0[2 * i + 1] = s[1 + i].t;
        tf.0[2 * i] = f32::from_bits(s[1 + LANES / 2 + i].node);
        tf.0[2 * i + 1] = s[1 + LANES / 2 + i].t;
    }
    (s[0].node, tn, tf)
}

impl KdTree<'_> {
    /// Walks packet `p` from the root; the visitor keeps the answers.
    /// `stack` holds at least [`KD_STACK_LEN`] items. Counts lane steps
    /// (a node visited for 5 lanes is 5 steps, as 5 rays would take).
    #[inline(always)]
    pub(crate) fn walk_packet<V: PacketVisitor>(
        &self,
        p: &Packet,
        v: &mut V,
        stack: &mut [KdStackItem],
        steps: &mut Steps,
    ) {
        // Interior lane steps summed per lane in a vector (one add a
        // step), counted once at the end: a per-step count of the mask's
        // lanes cost some thirty instructions of every step.
        let mut lane_steps = [0u32; LANES];
        // A compact tree's walk chosen once (its nodes' children decoded).
        if self.info.is_compact() {
            self.walk_packet_counted::<V, true>(p, v, stack, steps, &mut lane_steps);
        } else {
            self.walk_packet_counted::<V, false>(p, v, stack, steps, &mut lane_steps);
        }
        steps.interior += lane_steps.iter().map(|&n| n as u64).sum::<u64>();
    }

    /// [`KdTree::walk_packet`], adding each interior node's active lanes
    /// to `lane_steps`.
    #[inline(always)]
    fn walk_packet_counted<V: PacketVisitor, const COMPACT: bool>(
        &self,
        p: &Packet,
        v: &mut V,
        stack: &mut [KdStackItem],
        steps: &mut Steps,
        lane_steps: &mut [u32; LANES],
    ) {
        let (mut tn, mut tf, hit_box) = p.segment(&self.trace_box.aabb());
        let mut alive = hit_box.count();
        if alive == 0 {
            return;
        }
        let Some(stack) = stack.get_mut(..KD_STACK_LEN) else {
            steps.fault();
            return;
        };
        // -inf / +inf for live lanes (max and min leave intervals alone),
        // +inf / -inf for done ones (they empty them).
        let (mut dead_tn, mut dead_tf) = (NEG_INF, INF);
        let mut sp = 0usize;
        let mut node = 0u32;
        let mut budget = self.nodes.len();
        loop {
            let mut nd = self.node(node);
            while !nd.is_leaf() {
                if budget == 0 || sp + 1 >= ENTRIES {
                    steps.fault();
                    return;
                }
                budget -= 1;
                let on = tn.le(tf);
                for (n, &m) in lane_steps.iter_mut().zip(on.0.iter()) {
                    *n += m & 1;
                }
                let (a, s) = (nd.axis(), nd.split());
                let (left, right) = children::<COMPACT>(nd);
                let (near, far) = if p.up[a] {
                    (left, right)
                } else {
                    (right, left)
                };
                // Per lane, as the single ray decides: the near side is
                // needed unless the plane lies before the entry, the far
                // side unless it lies past the exit (a plane met exactly
                // there is a tie: both); a lane that needs both splits its
                // segment at the plane. (A lane that does not visit the
                // node needs neither.)
                let d = (F8::splat(s) - p.o[a]) * p.inv[a];
                let n = d.ge(tn);
                let f = d.le(tf);
                let both = n & f;
                if n.any() {
                    if f.any() {
                        let far_tn = both.select(d, f.select(tn, INF));
                        let far_tf = f.select(tf, NEG_INF);
                        push(stack, sp, far, far_tn, far_tf);
                        sp += 1;
                    }
                    node = near;
                    tf = both.select(d, n.select(tf, NEG_INF));
                    tn = n.select(tn, INF);
                } else {
                    node = far;
                    tn = f.select(tn, INF);
                    tf = f.select(tf, NEG_INF);
                }
                nd = self.node(node);
            }
            let on = tn.le(tf);
            let lanes = on.count() as u64;
            steps.leaves += lanes;
            let Some(refs) = self.leaf_refs(nd).filter(|_| budget > 0) else {
                steps.fault();
                return;
            };
            budget -= 1;
            if refs.is_empty() {
                steps.empty += lanes;
            } else {
                let done = v.visit(self, p, refs, on, tf);
                // A lane that is done visits nothing more: its intervals
                // on the stack are emptied as they come off.
                dead_tn = done.select(INF, dead_tn);
                dead_tf = done.select(NEG_INF, dead_tf);
                alive -= done.count();
            }
            loop {
                if sp == 0 || alive == 0 {
                    return;
                }
                sp -= 1;
                let (n, en, ex) = pop(stack, sp);
                tn = en.max(dead_tn);
                tf = ex.min(dead_tf);
                if tn.le(tf).any() {
                    node = n;
                    break;
                }
            }
        }
    }

    /// Closest hits of `rays` into `hits` (as many): packets of 8 where
    /// the rays move alike, ray by ray hierarchically elsewhere. Each hit
    /// equals [`KdTree::intersect`]'s with hierarchical traversal. `stack`
    /// holds at least [`KD_STACK_LEN`] items.
    ///
    /// # Panics
    /// When `hits` is shorter than `rays` or `stack` than [`KD_STACK_LEN`].
    pub fn intersect_packets(
        &self,
        rays: &[Ray],
        hits: &mut [Hit],
        stack: &mut [KdStackItem],
        stats: &mut TraceStats,
    ) {
        self.packets::<ClosestLanes>(rays, hits, stack, stats);
    }

    /// [`KdTree::intersect_packets`] compiled for AVX2: the same hits, bit
    /// for bit (the same IEEE operations; no fused multiply-add is formed).
    ///
    /// # Safety
    /// Call only on a CPU with AVX2 (`coray_ffi::simd` checks and chooses).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    pub fn intersect_packets_avx2(
        &self,
        rays: &[Ray],
        hits: &mut [Hit],
        stack: &mut [KdStackItem],
        stats: &mut TraceStats,
    ) {
        self.packets::<ClosestLanes>(rays, hits, stack, stats);
    }

    /// Any-hit answers of `rays` into `occluded`, packets as
    /// [`KdTree::intersect_packets`].
    ///
    /// # Panics
    /// As [`KdTree::intersect_packets`].
    pub fn occluded_packets(
        &self,
        rays: &[Ray],
        occluded: &mut [bool],
        stack: &mut [KdStackItem],
        stats: &mut TraceStats,
    ) {
        self.packets::<AnyLanes>(rays, occluded, stack, stats);
    }

    /// [`KdTree::occluded_packets`] compiled for AVX2.
    ///
    /// # Safety
    /// As [`KdTree::intersect_packets_avx2`].
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    pub fn occluded_packets_avx2(
        &self,
        rays: &[Ray],
        occluded: &mut [bool],
        stack: &mut [KdStackItem],
        stats: &mut TraceStats,
    ) {
        self.packets::<AnyLanes>(rays, occluded, stack, stats);
    }

    /// Answers of `rays` into `out` (as many): packets of 8 where the rays
    /// move alike, ray by ray hierarchically elsewhere.
    #[inline(always)]
    fn packets<V: PacketVisitor>(
        &self,
        rays: &[Ray],
        out: &mut [V::Answer],
        stack: &mut [KdStackItem],
        stats: &mut TraceStats,
    ) {
        assert!(out.len() >= rays.len() && stack.len() >= KD_STACK_LEN);
        let mut p = Packet::EMPTY;
        let curved = !(self.scene.spheres.is_empty() && self.scene.cones.is_empty());
        for (rs, os) in rays.chunks(LANES).zip(out.chunks_mut(LANES)) {
            if p.load(rs, curved) {
                let mut v = V::new(&p);
                let mut steps = Steps::default();
                self.walk_packet(&p, &mut v, stack, &mut steps);
                steps.flush(stats);
                stats.rays += rs.len() as u64;
                stats.prim_tests += v.tests();
                v.answers(&mut os[..rs.len()]);
            } else {
                for (r, o) in rs.iter().zip(os.iter_mut()) {
                    *o = V::single(self, r, stack, stats);
                }
            }
        }
    }
}
