use super::{Aabb, PreparedRay};
use glam::Vec3;

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

/// Bounds of the part of triangle `v` inside `voxel` (Sutherland-Hodgman
/// against the six faces), or `None` when nothing of it is inside. This is
/// the split clipping of the kd build: a straddling triangle's events come
/// from its clipped part, not from its whole box.
pub fn clip_triangle_bounds(v: [Vec3; 3], voxel: &Aabb) -> Option<Aabb> {
    // A convex polygon clipped by 6 planes has at most 3 + 6 vertices; the
    // two buffers take turns as input and output.
    let mut a = [Vec3::ZERO; 9];
    let mut b = [Vec3::ZERO; 9];
    a[..3].copy_from_slice(&v);
    let mut n = 3;
    n = clip_plane::<0, false>(&a, n, &mut b, voxel.min.x)?;
    n = clip_plane::<0, true>(&b, n, &mut a, voxel.max.x)?;
    n = clip_plane::<1, false>(&a, n, &mut b, voxel.min.y)?;
    n = clip_plane::<1, true>(&b, n, &mut a, voxel.max.y)?;
    n = clip_plane::<2, false>(&a, n, &mut b, voxel.min.z)?;
    n = clip_plane::<2, true>(&b, n, &mut a, voxel.max.z)?;
    let mut bounds = Aabb::EMPTY;
    for p in &a[..n] {
        bounds = bounds.grow(*p);
    }
    let bounds = bounds.intersection(voxel);
    if bounds.is_empty() {
        None
    } else {
        Some(bounds)
    }
}

/// One Sutherland-Hodgman step: the polygon `poly[..n]` clipped to the
/// inner side of the plane `p[AXIS] = plane` (below it when `KEEP_BELOW`),
/// written to `out`; returns its vertex count, `None` when nothing is
/// left. A plane with every vertex on its inner side copies the polygon
/// as it is (same vertices, same order). The axis and side are constants
/// so that each of the six steps compiles to straight-line code.
#[inline(always)]
fn clip_plane<const AXIS: usize, const KEEP_BELOW: bool>(
    poly: &[Vec3; 9],
    n: usize,
    out: &mut [Vec3; 9],
    plane: f32,
) -> Option<usize> {
    let inside = |p: Vec3| {
        if KEEP_BELOW {
            p[AXIS] <= plane
        } else {
            p[AXIS] >= plane
        }
    };
    if poly[..n].iter().all(|&p| inside(p)) {
        out[..n].copy_from_slice(&poly[..n]);
        return Some(n);
    }
    let mut m = 0;
    for i in 0..n {
        let p = poly[i];
        let q = poly[if i + 1 == n { 0 } else { i + 1 }];
        let (pin, qin) = (inside(p), inside(q));
        if pin {
            out[m] = p;
            m += 1;
        }
        if pin != qin && m < 9 {
            let s = (plane - p[AXIS]) / (q[AXIS] - p[AXIS]);
            let mut x = p + (q - p) * s;
            x[AXIS] = plane;
            out[m] = x;
            m += 1;
        }
    }
    (m > 0).then_some(m)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

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
        let coord = |rng: &mut SplitMix64| {
            // Coordinates on a coarse grid now and then, so that vertices
            // land exactly on the box's faces.
            let x = rng.next_f32() * 4.0 - 2.0;
            if rng.below(4) == 0 {
                libm::roundf(x * 2.0) / 2.0
            } else {
                x
            }
        };
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
}
