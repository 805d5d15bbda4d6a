use super::{Aabb, PreparedRay};
use glam::Vec3;

/// An open truncated cone or cylinder with NFF semantics: a base point and
/// radius, an apex point and radius, no caps. Layout: eight floats.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct Cone {
    /// Centre of the base circle.
    pub base: [f32; 3],
    /// Radius at the base.
    pub base_radius: f32,
    /// Centre of the apex circle.
    pub apex: [f32; 3],
    /// Radius at the apex (0 for a pointed cone).
    pub apex_radius: f32,
}

impl Cone {
    /// True when the cone can be hit: finite, a non-zero axis, radii not
    /// negative and not both zero.
    pub fn is_valid(&self) -> bool {
        let (b, a) = (Vec3::from(self.base), Vec3::from(self.apex));
        b.is_finite()
            && a.is_finite()
            && self.base_radius.is_finite()
            && self.apex_radius.is_finite()
            && self.base_radius >= 0.0
            && self.apex_radius >= 0.0
            && (self.base_radius > 0.0 || self.apex_radius > 0.0)
            && (a - b).length_squared() > 0.0
    }

    /// Bounding box: the boxes of the two end discs (exact per axis).
    pub fn bounds(&self) -> Aabb {
        let (b, a) = (Vec3::from(self.base), Vec3::from(self.apex));
        let w = (a - b).normalize_or_zero();
        // Half-extent of a disc of radius 1 with normal w along each axis.
        let e = (Vec3::ONE - w * w).max(Vec3::ZERO);
        let e = Vec3::new(libm::sqrtf(e.x), libm::sqrtf(e.y), libm::sqrtf(e.z));
        let db = Aabb {
            min: b - e * self.base_radius,
            max: b + e * self.base_radius,
        };
        let da = Aabb {
            min: a - e * self.apex_radius,
            max: a + e * self.apex_radius,
        };
        super::aabb::pad_rounding(&db.union(&da))
    }

    /// Nearest `t` in `[ray.t_min, t_max]` where the ray meets the mantle
    /// (both nappes' sides, caps excluded), and the geometric normal there.
    #[inline]
    pub fn intersect(&self, r: &PreparedRay, t_max: f32) -> Option<(f32, f32, Vec3)> {
        if !(self.base_radius >= 0.0 && self.apex_radius >= 0.0) {
            return None;
        }
        let b = Vec3::from(self.base);
        let axis = Vec3::from(self.apex) - b;
        let len = crate::geom::lanes::sqrt_rn(axis.length_squared());
        if !(len > 0.0) {
            return None;
        }
        let w = axis / len;
        let slope = (self.apex_radius - self.base_radius) / len;
        // Work in units of the axis length along a unit direction, from the
        // point of the ray nearest the cone's centre: the squared terms below
        // then neither underflow nor overflow at any scale, and the
        // discriminant does not cancel for a ray passing far from its origin
        // (the same move as Ray Tracing Gems ch. 7 for spheres).
        let inv_len = 1.0 / len;
        let (dir_len, d) = (r.dir_len, r.unit_dir);
        let center = b + axis * 0.5;
        let shift = (center - r.origin).dot(d);
        let q = (r.origin + d * shift - b) * inv_len;
        let qs = q.dot(w);
        let ds = d.dot(w);
        let qp = q - w * qs;
        let dp = d - w * ds;
        // radius(t) = k + m t along the ray; perpendicular distance = |qp + t dp|.
        let k = self.base_radius * inv_len + slope * qs;
        let m = slope * ds;
        let a = dp.dot(dp) - m * m;
        let bh = qp.dot(dp) - k * m;
        let c = qp.dot(qp) - k * k;
        let disc = bh * bh - a * c;
        if !(disc >= 0.0) {
            return None;
        }
        // Stable roots: q = -(bh + sign(bh) sqrt(disc)); t = q / a and c / q.
        let sq = crate::geom::lanes::sqrt_rn(disc);
        let qq = -(bh + if bh >= 0.0 { sq } else { -sq });
        let (mut t0, mut t1) = (qq / a, c / qq);
        if qq == 0.0 {
            // Only when bh = disc = 0: a double root at t = 0 or a degenerate form.
            t0 = if a != 0.0 { 0.0 } else { f32::NAN };
            t1 = f32::NAN;
        }
        if t0 > t1 {
            core::mem::swap(&mut t0, &mut t1);
        }
        for u in [t0, t1] {
            let t = (shift + u * len) / dir_len;
            if !(t >= r.t_min && t <= t_max) {
                continue;
            }
            let s = qs + u * ds;
            if !(0.0..=1.0).contains(&s) {
                continue;
            }
            let radius = k + m * u;
            if radius < 0.0 {
                continue;
            }
            let perp = qp + dp * u;
            return Some((t, s, (perp - w * (radius * slope)) * len));
        }
        None
    }
}
