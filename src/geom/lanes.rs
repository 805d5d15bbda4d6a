//! Eight-lane arrays for packets of rays: `F8` (f32) and `M8` (lane masks,
//! all bits set or clear), each operation a loop over the lanes that the
//! compiler turns into one SIMD instruction (two on SSE2, one with AVX).
//! Plain safe code: no intrinsics, no `unsafe`, the same IEEE results in
//! every lane as the scalar code (no fused multiply-add is ever formed).

// Index loops over the lanes, on purpose: they are what the vectoriser maps
// one-to-one onto SIMD lanes.
#![allow(clippy::needless_range_loop)]

use core::ops::{Add, BitAnd, BitOr, Div, Mul, Not, Sub};

/// Lanes per packet.
pub const LANES: usize = 8;

/// Eight `f32`s.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(32))]
pub struct F8(pub [f32; LANES]);

/// Eight lane flags: `u32::MAX` (set) or 0.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(C, align(32))]
pub struct M8(pub [u32; LANES]);

macro_rules! lanewise {
    ($t:ident, $tr:ident, $f:ident, $op:tt) => {
        impl $tr for $t {
            type Output = $t;
            #[inline(always)]
            fn $f(self, o: $t) -> $t {
                let mut r = self.0;
                for i in 0..LANES {
                    r[i] = self.0[i] $op o.0[i];
                }
                $t(r)
            }
        }
    };
}

lanewise!(F8, Add, add, +);
lanewise!(F8, Sub, sub, -);
lanewise!(F8, Mul, mul, *);
lanewise!(F8, Div, div, /);
lanewise!(M8, BitAnd, bitand, &);
lanewise!(M8, BitOr, bitor, |);

impl Not for M8 {
    type Output = M8;
    #[inline(always)]
    fn not(self) -> M8 {
        let mut r = self.0;
        for v in r.iter_mut() {
            *v = !*v;
        }
        M8(r)
    }
}

macro_rules! compare {
    ($f:ident, $op:tt) => {
        /// Lane-wise comparison (false for NaN but `ne`).
        #[inline(always)]
        pub fn $f(self, o: F8) -> M8 {
            let mut r = [0u32; LANES];
            for i in 0..LANES {
                r[i] = if self.0[i] $op o.0[i] { u32::MAX } else { 0 };
            }
            M8(r)
        }
    };
}

impl F8 {
    /// Every lane `v`.
    #[inline(always)]
    pub const fn splat(v: f32) -> F8 {
        F8([v; LANES])
    }

    compare!(lt, <);
    compare!(le, <=);
    compare!(gt, >);
    compare!(ge, >=);
    compare!(eq, ==);
    compare!(ne, !=);

    /// Lane-wise minimum (`f32::min`: a NaN lane takes the other value).
    #[inline(always)]
    pub fn min(self, o: F8) -> F8 {
        let mut r = self.0;
        for i in 0..LANES {
            r[i] = self.0[i].min(o.0[i]);
        }
        F8(r)
    }

    /// Lane-wise maximum (`f32::max`).
    #[inline(always)]
    pub fn max(self, o: F8) -> F8 {
        let mut r = self.0;
        for i in 0..LANES {
            r[i] = self.0[i].max(o.0[i]);
        }
        F8(r)
    }
}

/// The correctly rounded square root of `x`, as IEEE 754 gives it (so
/// bit for bit what every path of it returns): with feature `std`, the
/// compiler's intrinsic (`f32::sqrt`), which takes the encoding of the
/// code around it and vectorises over lanes (one `vsqrtps` for 8 in the
/// AVX2 packet kernels); without it, on x86 libm's `sqrtf` (one `sqrtss`
/// in inline assembly), elsewhere [`sqrt_newton`] (libm's portable square
/// root loops over the bits).
///
/// Measured: `sqrtss` doubled the packets' shadow rays over the Newton
/// iteration on an AMD EPYC (`coray bench spd:lattice --methods
/// kd-packet`), whose twenty dependent f64 operations per root were most
/// of a cone test. On an Intel Xeon (AVX-512) the same legacy-encoded
/// `sqrtss` inside the AVX2 kernels stalled them on the upper register
/// state: `coray bench spd:balls --res 512 --methods kd,kd-packet`, two
/// rounds alternated, kd-packet primary 2.22 / 3.36 Mr/s with libm against
/// 11.67 / 11.67 with the intrinsic (hierarchical traversal 3.9-4.5).
#[inline(always)]
pub fn sqrt_rn(x: f32) -> f32 {
    #[cfg(feature = "std")]
    {
        x.sqrt()
    }
    #[cfg(all(not(feature = "std"), any(target_arch = "x86", target_arch = "x86_64")))]
    {
        libm::sqrtf(x)
    }
    #[cfg(all(
        not(feature = "std"),
        not(any(target_arch = "x86", target_arch = "x86_64"))
    ))]
    {
        sqrt_newton(x)
    }
}

/// The correctly rounded square root of `x` (as [`sqrt_rn`]), computed with
/// multiplies only: a reciprocal square root refined by Newton's method
/// in f64, then the f32 result chosen by exact comparisons at the
/// midpoints of its neighbours (a 25-bit midpoint squares exactly in f64,
/// and never equals a float). Plain arithmetic, for targets without a
/// square root instruction that libm would use.
#[inline(always)]
pub fn sqrt_newton(x: f32) -> f32 {
    let xd = x as f64;
    // 1/sqrt(x) to about 3.5%, then four Newton steps: below 1e-20.
    let mut r = f64::from_bits(0x5fe6_eb50_c7b5_37a9u64.wrapping_sub(xd.to_bits() >> 1));
    for _ in 0..4 {
        r = r * (1.5 - 0.5 * xd * r * r);
    }
    let mut y = (xd * r) as f32;
    // The nearest float to sqrt(x): move y by one ulp when the true root
    // lies past a midpoint.
    let up = f32::from_bits(y.to_bits().wrapping_add(1));
    let mid_up = (y as f64 + up as f64) * 0.5;
    if mid_up * mid_up < xd {
        y = up;
    }
    let down = f32::from_bits(y.to_bits().wrapping_sub(1));
    let mid_down = (down as f64 + y as f64) * 0.5;
    if mid_down * mid_down > xd {
        y = down;
    }
    // Zero (either sign), +inf and NaN return themselves; below zero, NaN.
    if x == 0.0 || x == f32::INFINITY || x.is_nan() {
        x
    } else if x < 0.0 {
        f32::NAN
    } else {
        y
    }
}

impl F8 {
    /// Lane-wise [`sqrt_rn`].
    #[inline(always)]
    pub fn sqrt(self) -> F8 {
        let mut r = self.0;
        for v in r.iter_mut() {
            *v = sqrt_rn(*v);
        }
        F8(r)
    }
}

impl M8 {
    /// No lane set.
    pub const NONE: M8 = M8([0; LANES]);

    /// Lane `i`.
    #[inline(always)]
    pub fn get(self, i: usize) -> bool {
        self.0[i] != 0
    }

    /// Whether any lane is set.
    #[inline(always)]
    pub fn any(self) -> bool {
        self.0.iter().fold(0, |a, &b| a | b) != 0
    }

    /// Lanes set.
    #[inline(always)]
    pub fn count(self) -> u32 {
        self.0.iter().map(|&b| b & 1).sum()
    }

    /// `a` where set, `b` elsewhere.
    #[inline(always)]
    pub fn select(self, a: F8, b: F8) -> F8 {
        let mut r = b.0;
        for i in 0..LANES {
            r[i] = if self.0[i] != 0 { a.0[i] } else { b.0[i] };
        }
        F8(r)
    }

    /// The flags as bits (lane i in bit i).
    #[inline(always)]
    pub fn bits(self) -> u8 {
        let mut b = 0u8;
        for i in 0..LANES {
            b |= ((self.0[i] & 1) as u8) << i;
        }
        b
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Bit for bit libm's (the hardware's) square root: special values,
    /// every float of several whole binades (subnormal, around 1, near
    /// the top), and a million random ones.
    #[test]
    fn sqrt_is_correctly_rounded() {
        let check = |x: f32| {
            let b = libm::sqrtf(x);
            for a in [sqrt_rn(x), sqrt_newton(x)] {
                assert!(
                    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()),
                    "{x:e}: {a:e} vs {b:e}"
                );
            }
        };
        for x in [
            0.0,
            -0.0,
            1.0,
            4.0,
            2.0,
            f32::MIN_POSITIVE,
            1e-45,
            f32::MAX,
            f32::INFINITY,
            -1.0,
            f32::NAN,
            -f32::INFINITY,
        ] {
            check(x);
        }
        for lo in [0x0000_0001u32, 0x3f00_0000, 0x3f80_0000, 0x7e80_0000] {
            for bits in lo..lo + (1 << 23) {
                check(f32::from_bits(bits));
            }
        }
        let mut g = crate::rng::SplitMix64(3);
        for _ in 0..1_000_000 {
            check(f32::from_bits(g.next_u64() as u32 & 0x7fff_ffff));
        }
        let v = F8([1.0, 2.0, 3.0, 0.0, 9.0, 1e-40, 5e30, 7.0]).sqrt();
        assert_eq!(v.0[4], 3.0);
        assert_eq!(v.0[1], libm::sqrtf(2.0));
    }

    #[test]
    fn lanes_follow_ieee_per_lane() {
        let a = F8([1.0, -2.0, f32::NAN, 0.0, -0.0, 3.5, f32::INFINITY, 1e-40]);
        let b = F8::splat(2.0);
        assert_eq!((a * b).0[0], 2.0);
        assert!((a + b).0[2].is_nan());
        assert_eq!((a / b).0[7], 1e-40 / 2.0);
        let m = a.lt(b);
        assert_eq!(m.bits(), 0b1001_1011);
        assert_eq!(m.count(), 5);
        assert!(m.any() && !M8::NONE.any());
        assert_eq!(m.select(a, b).0[5], 2.0);
        assert_eq!(a.min(b).0[2], 2.0);
        assert_eq!((!m & m), M8::NONE);
    }
}
