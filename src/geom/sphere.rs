use super::{Aabb, PreparedRay};
use glam::Vec3;

/// A sphere; layout `x y z r` as four floats (Embree's sphere points).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct Sphere {
    /// Centre.
    pub center: [f32; 3],
    /// Radius; zero, negative or NaN makes the sphere degenerate (never hit).
    pub radius: f32,
}

impl Sphere {
    /// True when the sphere can be hit.
    pub fn is_valid(&self) -> bool {
        Vec3::from(self.center).is_finite() && self.radius.is_finite() && self.radius > 0.0
    }

    /// Bounding box.
    pub fn bounds(&self) -> Aabb {
        let c = Vec3::from(self.center);
        let r = Vec3::splat(self.radius);
        super::aabb::pad_rounding(&Aabb {
            min: c - r,
            max: c + r,
        })
    }

    /// Nearest `t` in `[ray.t_min, t_max]` where the ray meets the surface
    /// (from outside or from inside), and the geometric normal there.
    #[inline]
    pub fn intersect(&self, r: &PreparedRay, t_max: f32) -> Option<(f32, Vec3)> {
        if !(self.radius > 0.0) {
            return None;
        }
        let c = Vec3::from(self.center);
        // In units of the radius along a unit direction: the squares below
        // neither underflow nor overflow at any scale; `to_t` maps back.
        let inv_r = 1.0 / self.radius;
        let (dir_len, d) = (r.dir_len, r.unit_dir);
        let to_t = self.radius / dir_len;
        let oc = (r.origin - c) * inv_r;
        // Closest approach, then the discriminant from the perpendicular
        // distance: robust for far origins (Haines et al., Ray Tracing Gems 7).
        let uc = -oc.dot(d);
        let h = oc + d * uc;
        let disc = 1.0 - h.dot(h);
        if !(disc >= 0.0) {
            return None;
        }
        let s = crate::geom::lanes::sqrt_rn(disc);
        for u in [uc - s, uc + s] {
            let t = u * to_t;
            if t >= r.t_min && t <= t_max {
                return Some((t, r.at(t) - c));
            }
        }
        None
    }
}
