//! Integer sort keys for floats: the builders sort by one `u64` (a float's
//! ordered bits, then a tie-breaking index) instead of chaining float
//! comparisons, which costs fewer mispredicted branches; or, where the
//! items already stand in index order, by the float's bits alone with a
//! stable radix sort.

/// `x`'s bits mapped so that the integers order as `f32::total_cmp` orders
/// the floats (-0.0 before 0.0, NaNs at the ends by sign).
#[inline(always)]
pub(crate) fn ordered_bits(x: f32) -> u32 {
    let bits = x.to_bits();
    if bits >> 31 == 1 {
        !bits
    } else {
        bits | 1 << 31
    }
}

/// The float whose [`ordered_bits`] are `bits`.
#[inline(always)]
pub(crate) fn from_ordered_bits(bits: u32) -> f32 {
    f32::from_bits(if bits >> 31 == 1 {
        bits & !(1 << 31)
    } else {
        !bits
    })
}

/// Sorts `items` by `key`, stably (items with equal keys keep their
/// order): a least-significant-digit radix sort, one byte a pass, that
/// skips the bytes every key shares. `spare` holds at least as many items
/// (fewer than 2^32). O(n) per pass, against the O(n log n) comparisons
/// (each loading two keys) of a comparison sort. One counting pass fills
/// every byte's histogram (5 KiB of stack with the cursors), so each key
/// is read five times, not eight. Each pass moves the front half forwards
/// from each bucket's start and the back half backwards from its end, side
/// by side: two chains of cursor updates overlap, where one would wait on
/// itself whenever neighbouring keys share a byte.
pub(crate) fn radix_sort_by_key(items: &mut [u32], spare: &mut [u32], key: impl Fn(u32) -> u32) {
    let n = items.len();
    let spare = &mut spare[..n];
    let mut counts = [[0u32; 256]; 4];
    for &x in items.iter() {
        let k = key(x);
        for (byte, count) in counts.iter_mut().enumerate() {
            count[(k >> (8 * byte)) as usize & 0xff] += 1;
        }
    }
    // Passes alternate between the two slices; `in_spare` says where the
    // items are now.
    let mut in_spare = false;
    for (byte, start) in counts.iter_mut().enumerate() {
        if start.contains(&(n as u32)) {
            continue;
        }
        let mut end = [0u32; 256];
        let mut sum = 0;
        for (s, e) in start.iter_mut().zip(end.iter_mut()) {
            let c = *s;
            *s = sum;
            sum += c;
            *e = sum;
        }
        let (from, to) = if in_spare {
            (&mut *spare, &mut *items)
        } else {
            (&mut *items, &mut *spare)
        };
        let shift = 8 * byte as u32;
        let digit = |x: u32| (key(x) >> shift) as usize & 0xff;
        // The back half has the odd item, moved last (it is its first).
        let (front, back) = from.split_at(n / 2);
        for (&a, &b) in front.iter().zip(back.iter().rev()) {
            let (da, db) = (digit(a), digit(b));
            to[start[da] as usize] = a;
            start[da] += 1;
            end[db] -= 1;
            to[end[db] as usize] = b;
        }
        if back.len() > front.len() {
            let b = back[0];
            let db = digit(b);
            end[db] -= 1;
            to[end[db] as usize] = b;
        }
        in_spare = !in_spare;
    }
    if in_spare {
        items.copy_from_slice(spare);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every float's ordered bits map back to its own bits (zeros, NaNs
    /// and infinities of both signs, subnormals), and they order as the
    /// floats do.
    #[test]
    fn ordered_bits_round_trip_and_order() {
        let mut rng = crate::rng::SplitMix64(7);
        let special = [
            0.0f32,
            -0.0,
            f32::MIN_POSITIVE,
            -1e-45,
            1.0,
            -1.0,
            f32::MAX,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            -f32::NAN,
        ];
        let mut floats = [0.0f32; 4096];
        for (i, x) in floats.iter_mut().enumerate() {
            *x = special
                .get(i)
                .copied()
                .unwrap_or_else(|| f32::from_bits(rng.next_u64() as u32));
        }
        for &x in &floats {
            assert_eq!(from_ordered_bits(ordered_bits(x)).to_bits(), x.to_bits());
        }
        for &x in &floats[..200] {
            for &y in &floats[..200] {
                assert_eq!(ordered_bits(x).cmp(&ordered_bits(y)), x.total_cmp(&y));
            }
        }
    }

    /// The radix sort orders as a stable comparison sort by the same key:
    /// random keys with many ties (few distinct values), keys that differ
    /// only in one byte, all equal, one item, none.
    #[test]
    fn radix_sort_is_a_stable_sort_by_key() {
        let mut g = crate::rng::SplitMix64(11);
        // (items, key mask): one pass left (an odd count, so the items end
        // in the spare slice and come back), three, all four, none.
        let cases: [(usize, u32); 7] = [
            (1000, 7),
            (1000, u32::MAX),
            (777, 0xff00),
            (999, 0xff00_ffff),
            (50, 0),
            (1, 5),
            (0, 5),
        ];
        for (n, mask) in cases {
            let keys: [u32; 1000] = core::array::from_fn(|_| g.next_u64() as u32 & mask);
            // Items in scrambled order, so stability is visible.
            let mut items: [u32; 1000] = core::array::from_fn(|i| (i as u32 * 7919) % 1000);
            // Stable by construction: the key, then the position.
            let mut at: [usize; 1000] = core::array::from_fn(|i| i);
            at[..n].sort_unstable_by_key(|&i| (keys[items[i] as usize], i));
            let want: [u32; 1000] = core::array::from_fn(|i| items[at[i]]);
            let mut spare = [0u32; 1000];
            radix_sort_by_key(&mut items[..n], &mut spare, |p| keys[p as usize]);
            assert_eq!(items[..n], want[..n], "n {n} mask {mask:x}");
        }
    }

    #[test]
    fn ordered_bits_order_as_total_cmp() {
        let v = [
            f32::NAN,
            -f32::NAN,
            f32::NEG_INFINITY,
            -7e30,
            -1.0,
            -1e-42,
            -0.0,
            0.0,
            1e-42,
            0.25,
            3e30,
            f32::INFINITY,
        ];
        for a in v {
            for b in v {
                assert_eq!(
                    ordered_bits(a).cmp(&ordered_bits(b)),
                    a.total_cmp(&b),
                    "{a} {b}"
                );
            }
        }
    }
}
