use glam::{Vec3, Vec3A};

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

    /// The two parts of the box cut by the plane at `pos` on `axis`: below
    /// it, then above it (a kd split's children).
    #[inline]
    pub fn split(&self, axis: usize, pos: f32) -> [Aabb; 2] {
        let (mut below, mut above) = (*self, *self);
        below.max[axis] = pos;
        above.min[axis] = pos;
        [below, above]
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
    /// axis (its inverse direction infinite) is inside that slab when its
    /// origin is, faces included; a NaN bound is passed over.
    ///
    /// Every traversal clips every ray to the scene's box, so the three
    /// slabs go at once on SIMD lanes: the same products, the same
    /// comparisons and the same extremes as one axis after the other
    /// (`tests::clip_ray_is_the_slab_test_axis_by_axis`). Inlined as
    /// [`crate::Ray::is_valid`] is, for the same reason.
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    pub fn clip_ray(
        &self,
        origin: Vec3,
        inv_dir: Vec3,
        t_min: f32,
        t_max: f32,
    ) -> Option<(f32, f32)> {
        ClipBox::of(self).clip_ray(origin, inv_dir, t_min, t_max)
    }
}

/// A box with SIMD-width corners ([`Vec3A`]: 16 bytes each, aligned), for
/// a box every ray of a walk is clipped to. [`Aabb`]'s 12-byte corners
/// load as 16 bytes that reach into the next field, and in a view made
/// for each call (a C tracer's) such a load spans two of the stores that
/// made the view, which a store cannot forward: the load waits for both
/// (measured: a tenth of a one-ray call that misses). A `ClipBox`
/// corner is stored and loaded whole.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClipBox {
    /// Lower corner.
    pub min: Vec3A,
    /// Upper corner.
    pub max: Vec3A,
}

impl ClipBox {
    /// `b`'s corners, as they are.
    #[inline(always)]
    pub fn of(b: &Aabb) -> ClipBox {
        ClipBox {
            min: Vec3A::from(b.min),
            max: Vec3A::from(b.max),
        }
    }

    /// The same box as an [`Aabb`].
    #[inline(always)]
    pub fn aabb(&self) -> Aabb {
        Aabb {
            min: Vec3::from(self.min),
            max: Vec3::from(self.max),
        }
    }

    /// [`Aabb::clip_ray`] on this box (inlined as it is).
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    pub fn clip_ray(
        &self,
        origin: Vec3,
        inv_dir: Vec3,
        t_min: f32,
        t_max: f32,
    ) -> Option<(f32, f32)> {
        let (o, inv) = (Vec3A::from(origin), Vec3A::from(inv_dir));
        let (bmin, bmax) = (self.min, self.max);
        let parallel = inv.abs().cmpeq(Vec3A::INFINITY);
        if (parallel & (o.cmplt(bmin) | o.cmpgt(bmax))).any() {
            return None;
        }
        if parallel.all() {
            return (t_min <= t_max).then_some((t_min, t_max));
        }
        let lo = (bmin - o) * inv;
        let hi = (bmax - o) * inv;
        let order = lo.cmple(hi);
        let (n, f) = (Vec3A::select(order, lo, hi), Vec3A::select(order, hi, lo));
        // Parallel axes bound nothing, nor does a NaN bound (`f32::max`
        // and `min` pass over one).
        let n = Vec3A::select(parallel | n.cmpne(n), Vec3A::NEG_INFINITY, n);
        let f = Vec3A::select(parallel | f.cmpne(f), Vec3A::INFINITY, f);
        // The lanes' extremes are never NaN, so one compare gives what
        // `f32::max` / `min` give (a NaN bound yields to them).
        let (far_entry, near_exit) = (n.max_element(), f.min_element());
        let t0 = if t_min > far_entry { t_min } else { far_entry };
        let t1 = if t_max < near_exit { t_max } else { near_exit };
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
    let e = Vec3::splat(m * crate::tolerance::ROUNDED_BOX_PAD);
    Aabb {
        min: b.min - e,
        max: b.max + e,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    /// The slab test one axis after the other, as `clip_ray` once was.
    fn axis_by_axis(b: &Aabb, o: Vec3, inv: Vec3, t_min: f32, t_max: f32) -> Option<(f32, f32)> {
        let (mut t0, mut t1) = (t_min, t_max);
        for a in 0..3 {
            if inv[a].is_infinite() {
                if o[a] < b.min[a] || o[a] > b.max[a] {
                    return None;
                }
                continue;
            }
            let lo = (b.min[a] - o[a]) * inv[a];
            let hi = (b.max[a] - o[a]) * inv[a];
            let (n, f) = if lo <= hi { (lo, hi) } else { (hi, lo) };
            t0 = t0.max(n);
            t1 = t1.min(f);
        }
        (t0 <= t1).then_some((t0, t1))
    }

    #[test]
    fn clip_ray_is_the_slab_test_axis_by_axis() {
        let specials = [
            0.0,
            -0.0,
            1.0,
            -1.0,
            0.5,
            1e-40,
            3e38,
            -3e38,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
        ];
        let mut g = SplitMix64(5);
        let pick = |g: &mut SplitMix64, p: f32| {
            if g.next_f32() < p {
                specials[(g.next_u64() % specials.len() as u64) as usize]
            } else {
                g.next_f32() * 4.0 - 2.0
            }
        };
        let (mut some, mut none) = (0, 0);
        for i in 0..300_000 {
            let mut v = [0.0f32; 14];
            for x in v.iter_mut() {
                *x = pick(&mut g, 0.1);
            }
            let b = Aabb {
                min: Vec3::new(v[0], v[1], v[2]).min(Vec3::new(v[3], v[4], v[5])),
                max: Vec3::new(v[0], v[1], v[2]).max(Vec3::new(v[3], v[4], v[5])),
            };
            let (o, d) = (Vec3::new(v[6], v[7], v[8]), Vec3::new(v[9], v[10], v[11]));
            let inv = Vec3::ONE / d;
            let (t_min, t_max) = (v[12], v[13]);
            let want = axis_by_axis(&b, o, inv, t_min, t_max);
            let got = b.clip_ray(o, inv, t_min, t_max);
            // Equal values (a zero's sign may differ: max of +0 and -0).
            let same = |a: f32, b: f32| a == b || (a.is_nan() && b.is_nan());
            match (want, got) {
                (None, None) => none += 1,
                (Some(w), Some(h)) if same(w.0, h.0) && same(w.1, h.1) => some += 1,
                _ => panic!("case {i}: {b:?} {o} {inv} [{t_min}, {t_max}]: {want:?} {got:?}"),
            }
        }
        assert!(some > 10_000 && none > 10_000, "{some} {none}");
    }
}
