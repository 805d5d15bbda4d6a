use super::{Aabb, PreparedRay};
use glam::{Vec3, Vec4};

/// Watertight ray-triangle test (Woop, Benthin and Wald, JCGT 2013): no ray
/// slips between two triangles that share an edge. Both sides are hit.
/// Returns `(t, u, v)` with `u`, `v` the weights of `v1` and `v2`, for `t`
/// in `[ray.t_min, t_max]`. A zero-area or NaN triangle is never hit.
#[inline(always)]
pub fn intersect_triangle(
    r: &PreparedRay,
    v0: Vec3,
    v1: Vec3,
    v2: Vec3,
    t_max: f32,
) -> Option<(f32, f32, f32)> {
    // Arrays, not `Vec3`s: they take the ray's run-time axes without a
    // branch per lane.
    let a = (v0 - r.origin).to_array();
    let b = (v1 - r.origin).to_array();
    let c = (v2 - r.origin).to_array();
    let (kx, ky, kz) = (r.kx, r.ky, r.kz);
    let ax = a[kx] - r.sx * a[kz];
    let ay = a[ky] - r.sy * a[kz];
    let bx = b[kx] - r.sx * b[kz];
    let by = b[ky] - r.sy * b[kz];
    let cx = c[kx] - r.sx * c[kz];
    let cy = c[ky] - r.sy * c[kz];
    let mut u = cx * by - cy * bx;
    let mut v = ax * cy - ay * cx;
    let mut w = bx * ay - by * ax;
    if u == 0.0 || v == 0.0 || w == 0.0 {
        // On an edge in single precision: decide it in double, as the paper does.
        u = (cx as f64 * by as f64 - cy as f64 * bx as f64) as f32;
        v = (ax as f64 * cy as f64 - ay as f64 * cx as f64) as f32;
        w = (bx as f64 * ay as f64 - by as f64 * ax as f64) as f32;
    }
    if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
        return None;
    }
    let det = u + v + w;
    if det == 0.0 || det.is_nan() {
        return None;
    }
    let az = r.sz * a[kz];
    let bz = r.sz * b[kz];
    let cz = r.sz * c[kz];
    let t_scaled = u * az + v * bz + w * cz;
    let inv_det = 1.0 / det;
    let t = t_scaled * inv_det;
    if !(t >= r.t_min && t <= t_max) {
        return None;
    }
    Some((t, v * inv_det, w * inv_det))
}

/// Lanes of [`intersect_triangles4`].
pub const TRI_LANES: usize = 4;

/// Four triangles' corners, lane by lane: `v[corner][axis][lane]`.
pub type Corners4 = [[[f32; TRI_LANES]; 3]; 3];

/// What [`intersect_triangles4`] found, lane by lane.
#[derive(Clone, Copy, Debug)]
pub struct Hits4 {
    /// Lanes hit within `[ray.t_min, t_max]` (bit `i` for lane `i`).
    pub hit: u32,
    /// Lanes that lie on an edge in single precision: [`intersect_triangle`]
    /// decides them (in double), never `hit`.
    pub edge: u32,
    /// Per lane: the hit's `t`.
    pub t: [f32; TRI_LANES],
    /// Per lane: the weight of corner 1.
    pub u: [f32; TRI_LANES],
    /// Per lane: the weight of corner 2.
    pub v: [f32; TRI_LANES],
}

/// [`intersect_triangle`] for four triangles at once, each lane the same
/// IEEE operations in the same order (no fused multiply-add), so a lane
/// hits with the same `t`, `u`, `v` as the one-triangle test: one pass of
/// vector instructions and no branch per triangle. Lanes that meet the
/// one-triangle test's double-precision edge case come back in
/// [`Hits4::edge`] for it to decide.
#[inline(always)]
pub fn intersect_triangles4(r: &PreparedRay, c: &Corners4, t_max: f32) -> Hits4 {
    // glam's `Vec4` is four SSE2 lanes (NEON, wasm SIMD, or scalar
    // elsewhere): each step below is one vector instruction, in the
    // one-triangle test's order of operations (no fused multiply-add), so
    // each lane's bits are that test's.
    let o = r.origin.to_array();
    let (kx, ky, kz) = (r.kx, r.ky, r.kz);
    let (ox, oy, oz) = (Vec4::splat(o[kx]), Vec4::splat(o[ky]), Vec4::splat(o[kz]));
    let (sx, sy, sz) = (Vec4::splat(r.sx), Vec4::splat(r.sy), Vec4::splat(r.sz));
    // Corner `k` relative to the origin, sheared: x, y, and z (scaled).
    let corner = |k: usize| {
        let lanes = |axis: usize| Vec4::from_array(c[k][axis]);
        let az = lanes(kz) - oz;
        (
            (lanes(kx) - ox) - sx * az,
            (lanes(ky) - oy) - sy * az,
            sz * az,
        )
    };
    let ((ax, ay, az), (bx, by, bz), (cx, cy, cz)) = (corner(0), corner(1), corner(2));
    let u = cx * by - cy * bx;
    let v = ax * cy - ay * cx;
    let w = bx * ay - by * ax;
    let det = u + v + w;
    let t_scaled = u * az + v * bz + w * cz;
    let inv_det = Vec4::ONE / det;
    let t = t_scaled * inv_det;
    let zero = Vec4::ZERO;
    let on_edge = u.cmpeq(zero) | v.cmpeq(zero) | w.cmpeq(zero);
    let neg = u.cmplt(zero) | v.cmplt(zero) | w.cmplt(zero);
    let pos = u.cmpgt(zero) | v.cmpgt(zero) | w.cmpgt(zero);
    // As the one-triangle test: no zero or NaN determinant.
    let valid = det.cmpne(zero)
        & det.cmpeq(det)
        & t.cmpge(Vec4::splat(r.t_min))
        & t.cmple(Vec4::splat(t_max));
    Hits4 {
        hit: (!on_edge & !(neg & pos) & valid).bitmask(),
        edge: on_edge.bitmask(),
        t: t.to_array(),
        u: (v * inv_det).to_array(),
        v: (w * inv_det).to_array(),
    }
}

/// Bounds of the part of triangle `v` inside `voxel` (Sutherland-Hodgman
/// against the six faces), or `None` when nothing of it is inside. This is
/// the split clipping of the kd build: a straddling triangle's events come
/// from its clipped part, not from its whole box.
pub fn clip_triangle_bounds(v: [Vec3; 3], voxel: &Aabb) -> Option<Aabb> {
    let (mut a, mut b) = (Polygon::of(v), Polygon::EMPTY);
    let (mut p, mut spare) = (&mut a, &mut b);
    clip_faces(&mut p, &mut spare, &faces(voxel), 0, 6)?;
    p.bounds_in(voxel)
}

/// [`clip_triangle_bounds`] of `v` in both children of `voxel` split at
/// `pos` on `axis` (the box below `pos` first), bit for bit the same: the
/// faces both children share with `voxel` that come before the split's in
/// the clipping order are clipped once (none for a split on x, two on y,
/// four on z).
pub fn clip_triangle_bounds_split(
    v: [Vec3; 3],
    voxel: &Aabb,
    axis: usize,
    pos: f32,
) -> [Option<Aabb>; 2] {
    let [below, above] = voxel.split(axis, pos);
    let (mut a, mut b, mut c) = (Polygon::of(v), Polygon::EMPTY, Polygon::EMPTY);
    let (mut p, mut spare) = (&mut a, &mut b);
    let shared = 2 * axis;
    if clip_faces(&mut p, &mut spare, &faces(voxel), 0, shared).is_none() {
        return [None, None];
    }
    c.v[..p.n].copy_from_slice(&p.v[..p.n]);
    c.n = p.n;
    let low = clip_faces(&mut p, &mut spare, &faces(&below), shared, 6)
        .and_then(|()| p.bounds_in(&below));
    let mut q = &mut c;
    let high = clip_faces(&mut q, &mut spare, &faces(&above), shared, 6)
        .and_then(|()| q.bounds_in(&above));
    [low, high]
}

/// A box's six faces in clipping order: min x, max x, min y, max y, min z,
/// max z.
fn faces(b: &Aabb) -> [f32; 6] {
    [b.min.x, b.max.x, b.min.y, b.max.y, b.min.z, b.max.z]
}

/// Clips `*p` by faces `from..to` of `faces`, in order, keeping the inner
/// side of each; `None` when nothing is left. A face with every vertex on
/// its inner side leaves the polygon as it is (not copied): a face that
/// cuts writes to `*spare`, and the two swap. One copy for every caller
/// (inlined into the split's three calls it took 2.8 KB more of a
/// Cortex-M4's flash, for no time measured on the host).
#[inline(never)]
fn clip_faces<'p>(
    p: &mut &'p mut Polygon,
    spare: &mut &'p mut Polygon,
    faces: &[f32; 6],
    from: usize,
    to: usize,
) -> Option<()> {
    macro_rules! face {
        ($i:literal, $axis:literal, $below:literal) => {
            if from <= $i && $i < to && p.cut::<$axis, $below>(spare, faces[$i])? {
                core::mem::swap(p, spare);
            }
        };
    }
    face!(0, 0, false);
    face!(1, 0, true);
    face!(2, 1, false);
    face!(3, 1, true);
    face!(4, 2, false);
    face!(5, 2, true);
    Some(())
}

/// A convex polygon being clipped: at most 3 + 6 vertices (a triangle cut
/// by six planes).
struct Polygon {
    v: [Vec3; 9],
    n: usize,
}

impl Polygon {
    const EMPTY: Polygon = Polygon {
        v: [Vec3::ZERO; 9],
        n: 0,
    };

    fn of(t: [Vec3; 3]) -> Polygon {
        let mut p = Polygon::EMPTY;
        p.v[..3].copy_from_slice(&t);
        p.n = 3;
        p
    }

    /// One Sutherland-Hodgman step: the polygon clipped to the inner side
    /// of the plane `p[AXIS] = plane` (below it when `KEEP_BELOW`), written
    /// to `out`: `Some(true)`. `Some(false)` when every vertex is on the
    /// inner side (nothing written: the polygon stays as it is), `None`
    /// when nothing is left. The axis and side are constants so that each
    /// of the six steps compiles to straight-line code.
    #[inline(always)]
    fn cut<const AXIS: usize, const KEEP_BELOW: bool>(
        &self,
        out: &mut Polygon,
        plane: f32,
    ) -> Option<bool> {
        let inside = |p: Vec3| {
            if KEEP_BELOW {
                p[AXIS] <= plane
            } else {
                p[AXIS] >= plane
            }
        };
        let (poly, n) = (&self.v, self.n);
        if poly[..n].iter().all(|&p| inside(p)) {
            return Some(false);
        }
        let mut m = 0;
        for i in 0..n {
            let p = poly[i];
            let q = poly[if i + 1 == n { 0 } else { i + 1 }];
            let (pin, qin) = (inside(p), inside(q));
            if pin {
                out.v[m] = p;
                m += 1;
            }
            if pin != qin && m < 9 {
                let s = (plane - p[AXIS]) / (q[AXIS] - p[AXIS]);
                let mut x = p + (q - p) * s;
                x[AXIS] = plane;
                out.v[m] = x;
                m += 1;
            }
        }
        out.n = m;
        (m > 0).then_some(true)
    }

    /// The polygon's bounds within `voxel`, `None` when empty.
    fn bounds_in(&self, voxel: &Aabb) -> Option<Aabb> {
        let mut bounds = Aabb::EMPTY;
        for p in &self.v[..self.n] {
            bounds = bounds.grow(*p);
        }
        let bounds = bounds.intersection(voxel);
        if bounds.is_empty() {
            None
        } else {
            Some(bounds)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    /// A coordinate in [-2, 2], on the half-unit grid one time in
    /// `one_in`: so that vertices land on faces and rays pass through edges
    /// and corners.
    fn grid_coord(rng: &mut SplitMix64, one_in: u64) -> f32 {
        let x = rng.next_f32() * 4.0 - 2.0;
        if rng.below(one_in) == 0 {
            libm::roundf(x * 2.0) / 2.0
        } else {
            x
        }
    }

    /// Sutherland-Hodgman against all six planes, no shortcut: the
    /// reference the clipping must equal bit for bit.
    fn clip_every_plane(v: [Vec3; 3], voxel: &Aabb) -> Option<Aabb> {
        let mut poly = [Vec3::ZERO; 9];
        let mut tmp = [Vec3::ZERO; 9];
        poly[..3].copy_from_slice(&v);
        let mut n = 3;
        for axis in 0..3 {
            for (plane, keep_below) in [(voxel.min[axis], false), (voxel.max[axis], true)] {
                let inside = |p: Vec3| {
                    if keep_below {
                        p[axis] <= plane
                    } else {
                        p[axis] >= plane
                    }
                };
                let mut m = 0;
                for i in 0..n {
                    let (p, q) = (poly[i], poly[(i + 1) % n]);
                    if inside(p) {
                        tmp[m] = p;
                        m += 1;
                    }
                    if inside(p) != inside(q) && m < 9 {
                        let s = (plane - p[axis]) / (q[axis] - p[axis]);
                        let mut x = p + (q - p) * s;
                        x[axis] = plane;
                        tmp[m] = x;
                        m += 1;
                    }
                }
                n = m;
                if n == 0 {
                    return None;
                }
                poly[..n].copy_from_slice(&tmp[..n]);
            }
        }
        let b = poly[..n]
            .iter()
            .fold(Aabb::EMPTY, |b, p| b.grow(*p))
            .intersection(voxel);
        (!b.is_empty()).then_some(b)
    }

    /// Skipping the planes no vertex crosses changes no bit of the result,
    /// over triangles inside, across and outside boxes, some on a face.
    #[test]
    fn clipping_equals_clipping_by_every_plane() {
        let mut rng = SplitMix64(77);
        // Coordinates on a coarse grid now and then, so that vertices land
        // exactly on the box's faces.
        let coord = |rng: &mut SplitMix64| grid_coord(rng, 4);
        let (mut clipped, mut whole, mut none) = (0, 0, 0);
        for _ in 0..20_000 {
            let mut p = || Vec3::new(coord(&mut rng), coord(&mut rng), coord(&mut rng));
            let v = [p(), p(), p()];
            let (a, b) = (p(), p());
            let voxel = if rng.below(8) == 0 {
                // A box around the whole triangle.
                Aabb {
                    min: Vec3::splat(-2.0),
                    max: Vec3::splat(2.0),
                }
            } else {
                Aabb {
                    min: a.min(b),
                    max: a.max(b),
                }
            };
            let want = clip_every_plane(v, &voxel);
            let got = clip_triangle_bounds(v, &voxel);
            assert_eq!(
                got.map(|b| (
                    b.min.to_array().map(f32::to_bits),
                    b.max.to_array().map(f32::to_bits)
                )),
                want.map(|b| (
                    b.min.to_array().map(f32::to_bits),
                    b.max.to_array().map(f32::to_bits)
                )),
                "{v:?} in {voxel:?}"
            );
            match got {
                None => none += 1,
                Some(b) if b == Aabb::EMPTY.grow(v[0]).grow(v[1]).grow(v[2]) => whole += 1,
                Some(_) => clipped += 1,
            }
        }
        assert!(
            clipped > 1000 && whole > 100 && none > 1000,
            "{clipped} {whole} {none}"
        );
    }

    /// Clipping into both children of a split at once, sharing the faces
    /// before the split's, gives each child's bounds bit for bit as
    /// clipping by its six faces: splits on every axis, through, beside and
    /// on the triangle's vertices.
    #[test]
    fn split_clipping_equals_clipping_each_child_by_every_plane() {
        let mut rng = SplitMix64(78);
        let coord = |rng: &mut SplitMix64| grid_coord(rng, 4);
        let bits = |b: Option<Aabb>| {
            b.map(|b| {
                (
                    b.min.to_array().map(f32::to_bits),
                    b.max.to_array().map(f32::to_bits),
                )
            })
        };
        let mut seen = [[0; 4]; 3];
        for _ in 0..20_000 {
            let mut p = || Vec3::new(coord(&mut rng), coord(&mut rng), coord(&mut rng));
            let v = [p(), p(), p()];
            let (a, b) = (p(), p());
            let voxel = Aabb {
                min: a.min(b),
                max: a.max(b),
            };
            let axis = rng.below(3) as usize;
            let pos = if rng.below(4) == 0 {
                v[rng.below(3) as usize][axis].clamp(voxel.min[axis], voxel.max[axis])
            } else {
                let f = rng.next_f32();
                voxel.min[axis] + f * (voxel.max[axis] - voxel.min[axis])
            };
            let [below, above] = voxel.split(axis, pos);
            let [low, high] = clip_triangle_bounds_split(v, &voxel, axis, pos);
            assert_eq!(
                bits(low),
                bits(clip_every_plane(v, &below)),
                "{v:?} in {voxel:?} at {pos} on {axis}"
            );
            assert_eq!(
                bits(high),
                bits(clip_every_plane(v, &above)),
                "{v:?} in {voxel:?} at {pos} on {axis}"
            );
            seen[axis][low.is_some() as usize * 2 + high.is_some() as usize] += 1;
        }
        // Each axis saw triangles in neither child, in one, in the other
        // and in both.
        assert!(seen.iter().flatten().all(|&n| n > 100), "{seen:?}");
    }

    /// Each lane of the four-lane test answers as the one-triangle test:
    /// hit or not, and `t`, `u`, `v` bit for bit; a lane it cannot decide
    /// in single precision is flagged `edge` (and never `hit`) exactly when
    /// the one-triangle test falls back to double. Triangles and rays on a
    /// coarse grid now and then, so that rays pass through edges and
    /// corners; degenerate and NaN triangles; segments ending at or near
    /// the hits.
    #[test]
    fn four_lanes_answer_as_one_triangle_tests() {
        use crate::geom::Ray;
        let mut rng = SplitMix64(404);
        let coord = |rng: &mut SplitMix64| grid_coord(rng, 3);
        let (mut hits, mut edges, mut misses) = (0, 0, 0);
        for _ in 0..20_000 {
            let mut c: Corners4 = [[[0.0; TRI_LANES]; 3]; 3];
            let mut tris = [[Vec3::ZERO; 3]; TRI_LANES];
            for (lane, tri) in tris.iter_mut().enumerate() {
                for (k, v) in tri.iter_mut().enumerate() {
                    *v = Vec3::new(coord(&mut rng), coord(&mut rng), coord(&mut rng));
                    match rng.below(40) {
                        0 => *v = Vec3::splat(f32::NAN),
                        1 if k > 0 => *v = Vec3::ZERO, // a corner repeated below
                        _ => {}
                    }
                    for a in 0..3 {
                        c[k][a][lane] = v[a];
                    }
                }
            }
            let o = Vec3::new(coord(&mut rng), coord(&mut rng), coord(&mut rng));
            // Aimed at a lane's triangle: a corner, an edge's midpoint or
            // a point inside, or anywhere.
            let tri = tris[rng.below(TRI_LANES as u64) as usize];
            let (w1, w2) = match rng.below(4) {
                0 => (0.0, 0.0),
                1 => (0.5, 0.0),
                2 => (rng.next_f32() * 0.5, rng.next_f32() * 0.5),
                _ => (f32::NAN, 0.0),
            };
            let aim = tri[0] + (tri[1] - tri[0]) * w1 + (tri[2] - tri[0]) * w2;
            let mut d = if aim.is_finite() {
                aim - o
            } else {
                Vec3::new(coord(&mut rng), coord(&mut rng), coord(&mut rng))
            };
            if rng.below(4) == 0 {
                d[rng.below(3) as usize] = 0.0;
            }
            if d == Vec3::ZERO {
                d = Vec3::X;
            }
            let t_min = if rng.below(2) == 0 {
                0.0
            } else {
                rng.next_f32()
            };
            let ray = Ray::new(o, d, t_min, f32::INFINITY);
            let r = PreparedRay::new(&ray);
            // Segments that end before, at or past the first lane's hit.
            let first = intersect_triangle(&r, tris[0][0], tris[0][1], tris[0][2], f32::INFINITY);
            let t_max = match (first, rng.below(3)) {
                (Some((t, _, _)), 0) => t,
                (Some((t, _, _)), 1) => t * 0.999,
                _ => f32::INFINITY,
            };
            let h4 = intersect_triangles4(&r, &c, t_max);
            for (lane, tri) in tris.iter().enumerate() {
                let bit = 1 << lane;
                let want = intersect_triangle(&r, tri[0], tri[1], tri[2], t_max);
                // The one-triangle test's single-precision edge functions.
                let rel = |v: Vec3| (v - r.origin).to_array();
                let (a, b, cc) = (rel(tri[0]), rel(tri[1]), rel(tri[2]));
                let sh = |p: [f32; 3]| (p[r.kx] - r.sx * p[r.kz], p[r.ky] - r.sy * p[r.kz]);
                let ((ax, ay), (bx, by), (cx, cy)) = (sh(a), sh(b), sh(cc));
                let on_edge = cx * by - cy * bx == 0.0
                    || ax * cy - ay * cx == 0.0
                    || bx * ay - by * ax == 0.0;
                assert_eq!(h4.edge & bit != 0, on_edge, "lane {lane}: {tri:?}");
                if on_edge {
                    assert_eq!(h4.hit & bit, 0);
                    edges += 1;
                    continue;
                }
                match want {
                    Some((t, u, v)) => {
                        assert!(h4.hit & bit != 0, "lane {lane}: {tri:?} {ray:?}");
                        let got = (h4.t[lane], h4.u[lane], h4.v[lane]);
                        assert_eq!(
                            (t.to_bits(), u.to_bits(), v.to_bits()),
                            (got.0.to_bits(), got.1.to_bits(), got.2.to_bits())
                        );
                        hits += 1;
                    }
                    None => {
                        assert_eq!(h4.hit & bit, 0, "lane {lane}: {tri:?} {ray:?}");
                        misses += 1;
                    }
                }
            }
        }
        // Every kind of lane met often.
        assert!(
            hits > 5_000 && edges > 1_000 && misses > 20_000,
            "{hits} {edges} {misses}"
        );
    }
}
