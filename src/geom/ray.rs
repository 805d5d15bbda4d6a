use glam::Vec3;

/// Marks "no geometry" / "no primitive" in a [`Hit`] (a miss).
pub const INVALID_ID: u32 = u32::MAX;

/// A ray segment `origin + t * dir` for `t` in `[t_min, t_max]`.
///
/// `dir` need not be normalised; `t` is in units of `dir`. A ray with a NaN
/// component or a zero-length direction hits nothing.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct Ray {
    /// Origin.
    pub origin: Vec3,
    /// Start of the segment.
    pub t_min: f32,
    /// Direction (any length but zero).
    pub dir: Vec3,
    /// End of the segment.
    pub t_max: f32,
}

impl Ray {
    /// A ray over `[t_min, t_max]`.
    pub fn new(origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> Ray {
        Ray {
            origin,
            t_min,
            dir,
            t_max,
        }
    }

    /// True when the ray can hit anything: finite origin and direction, a
    /// non-zero direction and a non-empty, non-NaN interval.
    ///
    /// Every traversal asks this of every ray, so it is branch-light: `x *
    /// 0.0` is a zero for finite `x` and NaN for an infinite or NaN one, so
    /// one sum of the six products is zero exactly when all six components
    /// are finite; `t_min <= t_max` is false when either is NaN.
    ///
    /// Inlined into every walk on x86-64, where a call out of line read the
    /// ray back across its stores and stalled (`docs/design.md`, "One ray
    /// per call"); elsewhere left to the compiler: on the Cortex-M4
    /// firmware inlining it and [`crate::Aabb::clip_ray`] everywhere cost
    /// 5.2 KB of flash.
    #[cfg_attr(target_arch = "x86_64", inline(always))]
    #[cfg_attr(not(target_arch = "x86_64"), inline)]
    pub fn is_valid(&self) -> bool {
        let (o, d) = (self.origin, self.dir);
        let zeros = (o.x * 0.0 + o.y * 0.0) + (o.z * 0.0 + d.x * 0.0) + (d.y * 0.0 + d.z * 0.0);
        zeros == 0.0 && (d.x != 0.0) | (d.y != 0.0) | (d.z != 0.0) && self.t_min <= self.t_max
    }
}

/// The closest (or any) intersection found along a ray.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct Hit {
    /// Ray parameter of the hit.
    pub t: f32,
    /// Surface coordinate: for triangles the barycentric weight of vertex 1
    /// (as Embree), for cones the position along the axis in [0, 1].
    pub u: f32,
    /// Surface coordinate: for triangles the barycentric weight of vertex 2.
    pub v: f32,
    /// Geometric normal, not normalised, not flipped towards the ray.
    pub ng: Vec3,
    /// [`crate::geom::GEOM_TRIANGLES`], `GEOM_SPHERES`, `GEOM_CONES`, or [`INVALID_ID`] for a miss.
    pub geom_id: u32,
    /// Index of the primitive inside its geometry, or [`INVALID_ID`].
    pub prim_id: u32,
}

impl Default for Hit {
    fn default() -> Hit {
        Hit::MISS
    }
}

impl Hit {
    /// The value reported for a ray that hits nothing.
    pub const MISS: Hit = Hit {
        t: f32::INFINITY,
        u: 0.0,
        v: 0.0,
        ng: Vec3::ZERO,
        geom_id: INVALID_ID,
        prim_id: INVALID_ID,
    };

    /// True when this records a hit.
    pub fn is_hit(&self) -> bool {
        self.geom_id != INVALID_ID
    }
}

/// A ray with the per-ray constants that every test reuses: reciprocal
/// direction for box and plane tests, and the shear of the watertight
/// triangle test (Woop, Benthin and Wald 2013).
#[derive(Clone, Copy, Debug)]
pub struct PreparedRay {
    /// Origin.
    pub origin: Vec3,
    /// Direction.
    pub dir: Vec3,
    /// `1 / dir` per component (infinite where the component is zero).
    pub inv_dir: Vec3,
    /// Start of the segment.
    pub t_min: f32,
    /// End of the segment.
    pub t_max: f32,
    pub(crate) kx: usize,
    pub(crate) ky: usize,
    pub(crate) kz: usize,
    pub(crate) sx: f32,
    pub(crate) sy: f32,
    pub(crate) sz: f32,
    /// `|dir|` (rounded once, [`crate::geom::lanes::sqrt_rn`]) and `dir /
    /// |dir|`: the frame the sphere and cone tests work in, made once a ray
    /// rather than once a test (the same values, so the same hits).
    pub(crate) dir_len: f32,
    pub(crate) unit_dir: Vec3,
}

impl PreparedRay {
    /// Precomputes the per-ray constants. Call only for a [`Ray::is_valid`] ray.
    ///
    /// The five divisions run as two of four lanes (`1 / d` and the
    /// shear's `(d_kx, d_ky, 1) / d_kz`), each lane the IEEE quotient the
    /// scalar division gives; the axes come from tables, not `% 3`.
    #[inline]
    pub fn new(ray: &Ray) -> PreparedRay {
        PreparedRay::with_inverse(ray, inverse(ray.dir))
    }

    /// [`PreparedRay::new`] without the frame the sphere and cone tests
    /// work in (`dir_len`, `unit_dir`: NaN here), for walks over scenes of
    /// triangles alone: a square root and three divisions fewer a ray.
    /// The triangle test's constants are [`PreparedRay::new`]'s bit for bit.
    #[cfg(all(target_arch = "x86_64", target_feature = "sse2"))]
    #[inline(always)]
    pub(crate) fn for_triangles(ray: &Ray) -> PreparedRay {
        PreparedRay::with_frame::<false>(ray, inverse(ray.dir))
    }

    /// [`PreparedRay::new`] with `inv_dir`, [`inverse`] of the ray's
    /// direction, computed before (by a walk that clipped the ray first).
    #[inline]
    pub(crate) fn with_inverse(ray: &Ray, inv_dir: Vec3) -> PreparedRay {
        PreparedRay::with_frame::<true>(ray, inv_dir)
    }

    /// The constants; the sphere and cone frame only when `FRAME`.
    #[inline(always)]
    fn with_frame<const FRAME: bool>(ray: &Ray, inv_dir: Vec3) -> PreparedRay {
        let d = ray.dir;
        let a = d.abs();
        // The largest component's axis, x before y before z on ties, without
        // branches (incoherent rays would mispredict them): 0 when x wins,
        // else 1 when y wins, else 2.
        let x_wins = (a.x >= a.y) & (a.x >= a.z);
        let y_wins = a.y >= a.z;
        let kz = (!x_wins) as usize * (1 + (!y_wins) as usize);
        const NEXT: [usize; 3] = [1, 2, 0];
        let dk = d.to_array();
        let (mut kx, mut ky) = (NEXT[kz], NEXT[NEXT[kz]]);
        if dk[kz] < 0.0 {
            core::mem::swap(&mut kx, &mut ky);
        }
        let s = div4([dk[kx], dk[ky], 1.0, 1.0], [dk[kz]; 4]);
        let dir_len = if FRAME {
            crate::geom::lanes::sqrt_rn(d.length_squared())
        } else {
            f32::NAN
        };
        PreparedRay {
            origin: ray.origin,
            dir: d,
            inv_dir,
            t_min: ray.t_min,
            t_max: ray.t_max,
            kx,
            ky,
            kz,
            sx: s[0],
            sy: s[1],
            sz: s[2],
            dir_len,
            unit_dir: d / dir_len,
        }
    }

    /// The point at parameter `t`.
    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + self.dir * t
    }
}

/// `1 / d` per component (infinite where the component is zero), as
/// [`PreparedRay::new`] computes it: a walk that clips a ray to the
/// scene's box before preparing it gets the same bits.
#[inline(always)]
pub(crate) fn inverse(d: Vec3) -> Vec3 {
    let inv = div4([1.0; 4], [d.x, d.y, d.z, 1.0]);
    Vec3::new(inv[0], inv[1], inv[2])
}

/// Lane-wise `a / b`: one vector division where the target has one.
#[inline(always)]
fn div4(a: [f32; 4], b: [f32; 4]) -> [f32; 4] {
    [a[0] / b[0], a[1] / b[1], a[2] / b[2], a[3] / b[3]]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    /// The constants as the scalar formulas give them: axes by `% 3`,
    /// each quotient its own division.
    fn reference(d: Vec3) -> ([usize; 3], [f32; 3], [f32; 3]) {
        let a = d.abs();
        let kz = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        if d[kz] < 0.0 {
            core::mem::swap(&mut kx, &mut ky);
        }
        let inv = [1.0 / d.x, 1.0 / d.y, 1.0 / d.z];
        (
            [kx, ky, kz],
            inv,
            [d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]],
        )
    }

    /// `is_valid` answers as its definition, component by component, on
    /// rays whose fields are drawn from the values that decide it
    /// (infinities, NaN, signed zeros, subnormals, huge and plain values).
    #[test]
    fn is_valid_is_its_definition() {
        let definition = |r: &Ray| {
            r.origin.is_finite()
                && r.dir.is_finite()
                && r.dir != Vec3::ZERO
                && r.t_min <= r.t_max
                && !r.t_min.is_nan()
        };
        let values = [
            0.0,
            -0.0,
            1e-40,
            -1e-40,
            1.0,
            -2.5,
            3e38,
            -3e38,
            f32::MAX,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
        ];
        let mut g = SplitMix64(11);
        let (mut valid, mut invalid) = (0, 0);
        for _ in 0..200_000 {
            let mut f = [0.0f32; 8];
            for v in f.iter_mut() {
                // Mostly plain values, so that one special decides.
                *v = if g.next_f32() < 0.15 {
                    values[(g.next_u64() % values.len() as u64) as usize]
                } else {
                    g.next_f32() * 2.0 - 1.0
                };
            }
            let r = Ray::new(
                Vec3::new(f[0], f[1], f[2]),
                Vec3::new(f[3], f[4], f[5]),
                f[6],
                f[7],
            );
            let want = definition(&r);
            assert_eq!(r.is_valid(), want, "{r:?}");
            if want {
                valid += 1;
            } else {
                invalid += 1;
            }
        }
        // Both answers occur often, the zero direction among them.
        assert!(valid > 20_000 && invalid > 20_000, "{valid} {invalid}");
        assert!(!Ray::new(Vec3::ONE, Vec3::ZERO, 0.0, 1.0).is_valid());
        assert!(!Ray::new(Vec3::ONE, -Vec3::ZERO, 0.0, 1.0).is_valid());
        assert!(Ray::new(Vec3::ONE, Vec3::new(0.0, -1e-40, 0.0), 0.0, 0.0).is_valid());
    }

    #[test]
    fn prepared_constants_are_the_scalar_quotients_bit_for_bit() {
        let mut g = SplitMix64(7);
        let specials = [0.0, -0.0, 1e-40, -1e-40, 1e-30, 3e38, -3e38, 1.0, -1.0];
        for i in 0..20_000 {
            let mut c = [0.0f32; 3];
            for v in c.iter_mut() {
                *v = if g.next_f32() < 0.2 {
                    specials[(g.next_u64() % specials.len() as u64) as usize]
                } else {
                    (g.next_f32() * 2.0 - 1.0) * 10f32.powi((g.next_u64() % 7) as i32 - 3)
                };
            }
            let d = Vec3::from(c);
            if d == Vec3::ZERO {
                continue;
            }
            let r = PreparedRay::new(&Ray::new(Vec3::ZERO, d, 0.0, 1.0));
            let (k, inv, s) = reference(d);
            assert_eq!([r.kx, r.ky, r.kz], k, "ray {i}: {d}");
            let bits = |v: [f32; 3]| v.map(f32::to_bits);
            assert_eq!(bits(r.inv_dir.to_array()), bits(inv), "ray {i}: {d}");
            assert_eq!(bits([r.sx, r.sy, r.sz]), bits(s), "ray {i}: {d}");
        }
    }
}
