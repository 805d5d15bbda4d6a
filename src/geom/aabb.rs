use glam::Vec3;

/// An axis-aligned box. An empty box has `min > max` on some axis.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct Aabb {
    /// Lower corner.
    pub min: Vec3,
    /// Upper corner.
    pub max: Vec3,
}

impl Aabb {
    /// The box that contains nothing; the identity of [`Aabb::union`].
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    /// Smallest box holding both.
    #[inline]
    pub fn union(&self, o: &Aabb) -> Aabb {
        Aabb {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    /// Smallest box holding `self` and `p`.
    #[inline]
    pub fn grow(&self, p: Vec3) -> Aabb {
        Aabb {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    /// Common part of both boxes (may be empty).
    #[inline]
    pub fn intersection(&self, o: &Aabb) -> Aabb {
        Aabb {
            min: self.min.max(o.min),
            max: self.max.min(o.max),
        }
    }

    /// True when no point lies inside (a flat box is not empty).
    #[inline]
    pub fn is_empty(&self) -> bool {
        !(self.min.x <= self.max.x && self.min.y <= self.max.y && self.min.z <= self.max.z)
    }

    /// Surface area (0 for an empty box).
    #[inline]
    pub fn area(&self) -> f32 {
        if self.is_empty() {
            return 0.0;
        }
        let e = self.max - self.min;
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }

    /// Parameter interval `[t0, t1]` of the ray inside the box, clipped to
    /// `[t_min, t_max]`; `None` when the ray misses. A ray parallel to an
    /// axis is inside that slab when its origin is, faces included.
    #[inline]
    pub fn clip_ray(
        &self,
        origin: Vec3,
        inv_dir: Vec3,
        t_min: f32,
        t_max: f32,
    ) -> Option<(f32, f32)> {
        let mut t0 = t_min;
        let mut t1 = t_max;
        for a in 0..3 {
            if inv_dir[a].is_infinite() {
                if origin[a] < self.min[a] || origin[a] > self.max[a] {
                    return None;
                }
                continue;
            }
            let lo = (self.min[a] - origin[a]) * inv_dir[a];
            let hi = (self.max[a] - origin[a]) * inv_dir[a];
            let (n, f) = if lo <= hi { (lo, hi) } else { (hi, lo) };
            t0 = t0.max(n);
            t1 = t1.min(f);
        }
        if t0 <= t1 {
            Some((t0, t1))
        } else {
            None
        }
    }
}

/// Widens a box computed with rounding (square roots, radii) by a few ulps of
/// its coordinates, so that every point the primitive's own intersection
/// test can report lies inside it. Triangle boxes are exact and need none.
pub(crate) fn pad_rounding(b: &Aabb) -> Aabb {
    let m = b.min.abs().max(b.max.abs()).max_element();
    let e = Vec3::splat(m * 4.0 * f32::EPSILON);
    Aabb {
        min: b.min - e,
        max: b.max + e,
    }
}
