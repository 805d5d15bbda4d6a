//! SplitMix64 (Steele, Lea and Flood 2014): the one generator of the
//! project (R-tree shuffles here; scenes, tests and benchmarks through this
//! module), and the mix that digests a structure's references.

/// A small, seedable generator: the same sequence on every machine.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SplitMix64(pub u64);

impl SplitMix64 {
    /// The next 64 random bits.
    #[inline]
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        mix64(self.0)
    }

    /// Uniform in [0, 1), 24 bits.
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }

    /// Uniform in `0..n` (0 when `n` is 0); the modulo bias is below 2^-32
    /// for every `n` under 2^32.
    #[inline]
    pub fn below(&mut self, n: u64) -> u64 {
        self.next_u64() % n.max(1)
    }
}

/// SplitMix64's finaliser: a bijection of 64-bit words that spreads every
/// input bit over the output.
#[inline]
pub const fn mix64(x: u64) -> u64 {
    let mut z = x;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// One primitive reference's share of a reference digest.
#[inline]
pub const fn ref_mix(p: u32) -> u64 {
    mix64((p as u64) ^ 0xC0DE_5EED_0000_0000)
}

/// The digest of a multiset of primitive references: the wrapping sum of
/// [`ref_mix`] over them, so insert and delete update it in O(1). Builds
/// record it; `validate` recomputes it, which catches a corrupted
/// reference with probability 1 - 2^-64 (not a crafted arena).
pub fn ref_digest(refs: impl Iterator<Item = u32>) -> u64 {
    refs.fold(0u64, |d, p| d.wrapping_add(ref_mix(p)))
}

/// The digest of a kd-tree's nodes, in order: each node's two words mixed
/// into the running value. Builds record it; `validate` recomputes it,
/// which catches a corrupted node with probability 1 - 2^-64 (not a
/// crafted arena). Its splits need it in a tree without ropes: a split
/// moved within its node's box keeps every reference touching its leaf's
/// box, yet leaves primitives out of the cells it moves over, and no rope
/// record pins the leaf boxes there.
pub fn node_digest(nodes: impl Iterator<Item = (u32, u32)>) -> u64 {
    nodes.fold(0x6B64_4E4F_4445_5331, |d, (word, data)| {
        mix64(d ^ (((word as u64) << 32) | data as u64))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splitmix64_reference_values() {
        // The first outputs for seed 0 (Vigna's splitmix64.c).
        let mut r = SplitMix64(0);
        assert_eq!(r.next_u64(), 0xE220_A839_7B1D_CDAF);
        assert_eq!(r.next_u64(), 0x6E78_9E6A_A1B9_65F4);
        let f = SplitMix64(3).next_f32();
        assert!((0.0..1.0).contains(&f));
        assert_eq!(SplitMix64(9).below(0), 0);
    }

    #[test]
    fn digest_is_order_free_and_sees_a_changed_reference() {
        let a = ref_digest([1u32, 5, 9].into_iter());
        assert_eq!(a, ref_digest([9u32, 1, 5].into_iter()));
        assert_ne!(a, ref_digest([1u32, 5, 8].into_iter()));
        assert_ne!(a, ref_digest([1u32, 5].into_iter()));
        assert_eq!(
            a.wrapping_sub(ref_mix(5)).wrapping_add(ref_mix(6)),
            ref_digest([1u32, 6, 9].into_iter())
        );
    }
}
