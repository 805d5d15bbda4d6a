//! Top-down binary splitting (thesis 2.2.2, "Top-Down Binary Axis
//! Partitioning"): at each node the objects are sorted by box centre on
//! each axis and the `n - 1` linear partitions are swept; the best one by
//! the builder's criterion splits the node.
//!
//! Nodes are processed in index order: a node waits as a leaf over its run
//! of references until its turn, and its two children are appended at the
//! end, so the build needs no stack and the root is node 0.

use super::{binary, check_storage, gather, requirements, Builder, Bvh, BvhNode};
use super::{BvhScratch, BvhStorage};
use crate::geom::{Aabb, Scene};
use crate::Error;
use glam::Vec3A;

fn centre(b: &Aabb, axis: usize) -> f32 {
    0.5 * (b.min[axis] + b.max[axis])
}

/// Half the surface area, in f64, of a box that is not empty: every box
/// [`gather`] yields is not, and so no union of them is, so the sweeps'
/// loops skip the emptiness test (a tenth of a build's instructions).
/// Halving every area scales every criterion by one half exactly, so it
/// chooses as the whole areas would, one multiplication sooner.
#[inline(always)]
fn half_area(b: &Aabb) -> f64 {
    debug_assert!(!b.is_empty());
    half_area_of((b.max - b.min).as_dvec3())
}

/// Half the surface area of a box of extent `e` (products exact in f64).
#[inline(always)]
fn half_area_of(e: glam::DVec3) -> f64 {
    e.x * e.y + e.y * e.z + e.z * e.x
}

/// A box that a sweep grows one primitive box at a time, in SIMD lanes
/// (glam's `Vec3A`: one `minps` and one `maxps` a join).
#[derive(Clone, Copy)]
struct Grown {
    min: Vec3A,
    max: Vec3A,
}

impl Grown {
    const EMPTY: Grown = Grown {
        min: Vec3A::INFINITY,
        max: Vec3A::NEG_INFINITY,
    };

    #[inline(always)]
    fn join(&mut self, b: &Aabb) {
        self.min = self.min.min(Vec3A::from(b.min));
        self.max = self.max.max(Vec3A::from(b.max));
    }

    /// [`half_area`] of the box, to the bit.
    #[inline(always)]
    fn half_area(&self) -> f64 {
        half_area_of((self.max - self.min).as_dvec3())
    }

    fn aabb(&self) -> Aabb {
        Aabb {
            min: self.min.into(),
            max: self.max.into(),
        }
    }
}

/// The box centre on `axis` as a `u32` that orders as `f32::total_cmp`
/// orders the centres.
#[inline(always)]
fn ordered_centre(b: &Aabb, axis: usize) -> u32 {
    crate::sort_key::ordered_bits(centre(b, axis))
}

/// Sweep order as one integer: the ordered centre (from `ordered_centre`,
/// cached per primitive), then the primitive index (so the build is the
/// same on every machine).
#[inline(always)]
fn centre_key(ordered: &[u32], prim: u32) -> u64 {
    (ordered[prim as usize] as u64) << 32 | prim as u64
}

/// `links` a TDBS build needs for `n` primitives: a depth per pair of
/// siblings, the references in centre order on each axis, one run's right
/// side while it is partitioned, and each primitive's ordered centre on
/// each axis.
pub(crate) fn links_needed(n: usize) -> usize {
    n.saturating_mul(8)
}

/// When a node becomes a leaf.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum LeafRule {
    /// At `leaf_size` primitives or fewer (the thesis' builders).
    Size,
    /// At `leaf_size` or fewer, when the surface area heuristic prices the
    /// leaf at most as the best split: a split costs `traversal` (in
    /// primitive tests) over the node's area, plus its children's tests.
    Sah {
        /// A traversal step's cost in primitive tests.
        traversal: f64,
        /// What a triangle's test costs against a sphere's or a cone's
        /// (1: all alike): the SAH counts each primitive at its kind's
        /// cost, so splits and leaves weigh what testing them costs.
        triangle: f64,
        /// Triangles a leaf tests at once (1: one at a time): the leaf
        /// rule prices a leaf's triangles, and those of the two leaves
        /// its best split would make, rounded up to whole passes.
        block: usize,
    },
}

/// What a node's sweeps minimise, chosen once per build (never per
/// partition).
#[derive(Clone, Copy)]
enum Criterion {
    /// TDBS: children of most nearly equal area, `|A_L - A_R|`.
    Balanced,
    /// The SAH, `A_L n_L + A_R n_R`, every primitive one test.
    Sah,
    /// The SAH with each side's primitives priced by kind.
    SahWeighted(Weights),
}

/// The cost of testing primitive `p` in units of a sphere's test: `tw`
/// for the scene's first `nt` (its triangles), 1 for the rest.
#[derive(Clone, Copy)]
struct Weights {
    nt: usize,
    tw: f64,
}

impl Weights {
    #[inline(always)]
    fn of(&self, p: u32) -> f64 {
        if (p as usize) < self.nt {
            self.tw
        } else {
            1.0
        }
    }
}

pub(crate) fn build<'a>(
    scene: &Scene<'a>,
    source: Option<&[Aabb]>,
    builder: Builder,
    leaf_size: u32,
    rule: LeafRule,
    storage: BvhStorage<'a>,
    scratch: BvhScratch,
) -> Result<Bvh<'a>, Error> {
    if matches!(builder, Builder::Nn | Builder::NnChain) {
        return Err(Error::InvalidParameter { name: "builder" });
    }
    if leaf_size == 0 {
        return Err(Error::InvalidParameter { name: "leaf_size" });
    }
    let req = requirements(scene.prim_count(), builder);
    check_storage(&req, &storage, &scratch)?;
    let BvhStorage { nodes, refs } = storage;
    let boxes = &mut scratch.boxes[..];
    let suffix = &mut scratch.keys[..];
    let n = gather(scene, source, boxes, refs)?;
    let boxes = &*boxes;
    // Every node's box is written when its turn comes: a node that is
    // split gets it from its sweeps, which join its boxes anyway.
    nodes[0] = BvhNode::leaf(&Aabb::EMPTY, 0, n as u32);
    // Depth per pair of siblings (root: pair 0; nodes 2p - 1 and 2p: pair
    // p), then the references sorted by centre on each axis, once: a
    // node's run in each order is its part of the parent's, partitioned
    // stably, so no node sorts again (the sweeps see the same sequences
    // as sorting each run would give, hence the same tree).
    let (level, rest) = scratch.links.split_at_mut(n.max(1));
    let (by_x, rest) = rest.split_at_mut(n);
    let (by_y, rest) = rest.split_at_mut(n);
    let (by_z, rest) = rest.split_at_mut(n);
    let (right_side, rest) = rest.split_at_mut(n);
    let prims = scene.prim_count();
    let (cx, rest) = rest.split_at_mut(prims);
    let (cy, rest) = rest.split_at_mut(prims);
    let cz = &mut rest[..prims];
    let mut centres = [cx, cy, cz];
    for (axis, c) in centres.iter_mut().enumerate() {
        for &p in &refs[..n] {
            c[p as usize] = ordered_centre(&boxes[p as usize], axis);
        }
    }
    // `refs` stands in index order (gather's), so a stable sort by the
    // centre alone orders by `centre_key`.
    let mut order = [by_x, by_y, by_z];
    for (o, c) in order.iter_mut().zip(&centres) {
        o.copy_from_slice(&refs[..n]);
        crate::sort_key::radix_sort_by_key(o, right_side, |p| c[p as usize]);
    }
    let criterion = match (builder, rule) {
        (Builder::Tdbs, _) => Criterion::Balanced,
        (_, LeafRule::Sah { triangle, .. }) if triangle != 1.0 => Criterion::SahWeighted(Weights {
            nt: scene.triangles.len(),
            tw: triangle,
        }),
        _ => Criterion::Sah,
    };
    let pair = |i: usize| i.div_ceil(2);
    level[0] = 0;
    let (mut top, mut i, mut depth) = (1usize, 0usize, 0u32);
    while i < top {
        let nd = nodes[i];
        let (first, count) = (nd.first as usize, nd.len() as usize);
        let d = level.get(pair(i)).copied().unwrap_or(0);
        let small = count <= leaf_size as usize;
        if small && (count < 2 || rule == LeafRule::Size) {
            let b = refs[first..first + count]
                .iter()
                .fold(Aabb::EMPTY, |b, &p| b.union(&boxes[p as usize]));
            nodes[i] = BvhNode::leaf(&b, first as u32, count as u32);
            depth = depth.max(d);
            i += 1;
            continue;
        }
        // The node's primitive tests: its count, or priced by kind.
        let tests = match criterion {
            Criterion::SahWeighted(w) => refs[first..first + count].iter().map(|&p| w.of(p)).sum(),
            _ => count as f64,
        };
        // (criterion, axis, left count): smaller criterion is better.
        let mut best: Option<(f64, usize, usize)> = None;
        let mut bounds = Aabb::EMPTY;
        let run = &refs[first..first + count];
        let first_box = boxes[run[0] as usize];
        if run.iter().all(|&p| boxes[p as usize] == first_box) {
            // Identical boxes: every partition prices alike, and the
            // sweeps' first one (one primitive off) would make a chain of
            // `count` levels, O(n^2) to build. Halve the run instead: the
            // same price, O(n log n) over such a run.
            let c = match criterion {
                Criterion::Balanced => 0.0,
                _ => half_area(&first_box) * tests,
            };
            best = Some((c, 0, count / 2));
            bounds = first_box;
        } else {
            for (axis, o) in order.iter().enumerate() {
                bounds = sweep(
                    &o[first..first + count],
                    boxes,
                    suffix,
                    criterion,
                    tests,
                    axis,
                    &mut best,
                );
            }
        }
        let (c, axis, k) = best.expect("count >= 2");
        if let (
            true,
            LeafRule::Sah {
                traversal,
                triangle,
                block,
            },
        ) = (small, rule)
        {
            // The sweep's criterion is A_L n_L + A_R n_R: the split's
            // tests in units of the node's area times one test (n: the
            // sides' weights, when primitives weigh by kind).
            let a = half_area(&bounds);
            let (c, tests) = if block > 1 {
                passes(
                    &order[axis][first..first + count],
                    k,
                    boxes,
                    (scene.triangles.len(), triangle, block),
                )
            } else {
                (c, tests)
            };
            if c + traversal * a >= a * tests {
                nodes[i] = BvhNode::leaf(&bounds, first as u32, count as u32);
                depth = depth.max(d);
                i += 1;
                continue;
            }
        }
        let run = &order[axis][first..first + count];
        // The run as the split axis orders it: the references a child
        // keeps if it stays a leaf.
        refs[first..first + count].copy_from_slice(run);
        let pivot = centre_key(centres[axis], run[k]);
        for (b, o) in order.iter_mut().enumerate() {
            if b != axis {
                partition(&mut o[first..first + count], right_side, |p| {
                    centre_key(centres[axis], p) < pivot
                });
            }
        }
        nodes[top] = BvhNode::leaf(&Aabb::EMPTY, first as u32, k as u32);
        nodes[top + 1] = BvhNode::leaf(&Aabb::EMPTY, (first + k) as u32, (count - k) as u32);
        nodes[i] = BvhNode::interior(&bounds, top as u32, 2);
        level[pair(top)] = d + 1;
        top += 2;
        i += 1;
    }
    Ok(binary(scene, nodes, refs, top, n, depth))
}

/// The leaf rule's prices when triangles are tested `block` at a time:
/// the split of `run` (sorted on the split's axis) after its first `k`
/// references as `A_L n_L + A_R n_R` and the run as a leaf's tests, each
/// side's triangles (references below `triangles`, at weight `w`) rounded
/// up to whole passes of `block`, its spheres and cones at 1.
fn passes(
    run: &[u32],
    k: usize,
    boxes: &[Aabb],
    (triangles, w, block): (usize, f64, usize),
) -> (f64, f64) {
    let price = |side: &[u32]| {
        let tri = side.iter().filter(|&&p| (p as usize) < triangles).count();
        let rounded = tri.div_ceil(block) * block;
        w * rounded as f64 + (side.len() - tri) as f64
    };
    let area = |side: &[u32]| {
        half_area(
            &side
                .iter()
                .fold(Aabb::EMPTY, |b, &p| b.union(&boxes[p as usize])),
        )
    };
    let (l, r) = run.split_at(k);
    (area(l) * price(l) + area(r) * price(r), price(run))
}

/// The criterion at every linear partition of `run` (sorted by centre on
/// `axis`), kept in `best` as (criterion, axis, left count) when smaller
/// (ties keep the earlier axis and count); `suffix` holds the right
/// sides' areas meanwhile. Each sweep keeps the best so far in locals.
/// `tests` is the run's primitive tests (its length, or its primitives
/// priced by kind for [`Criterion::SahWeighted`]). Returns the run's box.
fn sweep(
    run: &[u32],
    boxes: &[Aabb],
    suffix: &mut [f32],
    criterion: Criterion,
    tests: f64,
    axis: usize,
    best: &mut Option<(f64, usize, usize)>,
) -> Aabb {
    if let [pa, pb] = *run {
        // Two primitives, one partition: priced as the loops below would
        // price it (the right area through `f32`), without their set-up.
        let (a, b) = (&boxes[pa as usize], &boxes[pb as usize]);
        let (al, ar) = (half_area(a), half_area(b) as f32 as f64);
        let c = match criterion {
            Criterion::Balanced => (al - ar).abs(),
            Criterion::Sah => al + ar,
            Criterion::SahWeighted(w) => al * w.of(pa) + ar * w.of(pb),
        };
        if best.is_none_or(|b| c < b.0) {
            *best = Some((c, axis, 1));
        }
        return a.union(b);
    }
    let suffix = &mut suffix[..run.len()];
    let right = suffix_areas(run, boxes, suffix);
    let to_beat = best.map(|b| b.0);
    let found = match criterion {
        Criterion::Balanced => sweep_balanced(run, boxes, suffix, to_beat),
        Criterion::Sah => sweep_sah(run, boxes, suffix, to_beat, tests, |_| 1.0),
        Criterion::SahWeighted(w) => sweep_sah(run, boxes, suffix, to_beat, tests, |p| w.of(p)),
    };
    if let Some((c, k)) = found {
        *best = Some((c, axis, k));
    }
    right.union(&boxes[run[0] as usize])
}

/// `suffix[k]` = the half area of `run[k..]`'s boxes, for `k` in `1..`;
/// returns the box of `run[1..]`.
fn suffix_areas(run: &[u32], boxes: &[Aabb], suffix: &mut [f32]) -> Aabb {
    let mut acc = Grown::EMPTY;
    let n = run.len().min(suffix.len());
    for (&p, s) in run[1..n].iter().zip(&mut suffix[1..n]).rev() {
        acc.join(&boxes[p as usize]);
        *s = acc.half_area() as f32;
    }
    acc.aabb()
}

/// The partition whose criterion is smaller than `to_beat` (any, the
/// first, when there is none yet) and than every earlier one, with that
/// criterion: `(criterion, left count)`.
type Found = Option<(f64, usize)>;

/// TDBS' criterion `|A_L - A_R|` (balanced children) at every partition.
fn sweep_balanced(run: &[u32], boxes: &[Aabb], suffix: &[f32], to_beat: Option<f64>) -> Found {
    let mut left = Aabb::EMPTY;
    let mut found: Found = None;
    let mut best_c = to_beat.unwrap_or(f64::INFINITY);
    for k in 1..run.len() {
        left = left.union(&boxes[run[k - 1] as usize]);
        let c = (half_area(&left) - suffix[k] as f64).abs();
        // The first partition of all wins outright; after it, only a
        // smaller criterion does (a NaN never).
        if c < best_c || (found.is_none() && to_beat.is_none()) {
            best_c = c;
            found = Some((c, k));
        }
    }
    found
}

/// The SAH `A_L k + A_R (n - k)` at every partition, pricing a
/// partition's left box only where it could win: the criterion grows with
/// `A_L`, and `A_L` grows with `k`, so the last left area priced bounds
/// every later one from below. A partition whose bound already reaches
/// the best is skipped; the bound and the criterion round alike (every
/// step is monotone), so the skipped ones are exactly those that could not
/// have been smaller: the same tree as pricing all. About a quarter of
/// the partitions get priced (SPD balls, rings, tree; random).
#[inline(always)]
fn sweep_sah(
    run: &[u32],
    boxes: &[Aabb],
    suffix: &[f32],
    to_beat: Option<f64>,
    total: f64,
    weight: impl Fn(u32) -> f64,
) -> Found {
    let count = run.len();
    let mut left = boxes[run[0] as usize];
    let mut left_area = half_area(&left);
    // The sides' weights (k and count - k when every primitive weighs 1),
    // counted as f64, not converted from usize at every step.
    let mut kf = weight(run[0]);
    let mut rest = total - kf;
    let c = left_area * kf + suffix[1] as f64 * rest;
    // The first partition of all wins outright (whatever it prices).
    let mut found = match to_beat {
        Some(b) if !(c < b) => None,
        _ => Some((c, 1)),
    };
    let mut best_c = found.map_or(to_beat.unwrap_or(f64::INFINITY), |f| f.0);
    for (k, (&p, &s)) in run[1..count - 1].iter().zip(&suffix[2..count]).enumerate() {
        let k = k + 2;
        left = left.union(&boxes[p as usize]);
        let w = weight(p);
        (kf, rest) = (kf + w, rest - w);
        let right = s as f64 * rest;
        if left_area * kf + right >= best_c {
            continue;
        }
        left_area = half_area(&left);
        let c = left_area * kf + right;
        if c < best_c {
            best_c = c;
            found = Some((c, k));
        }
    }
    found
}

/// Moves the elements of `run` for which `left` holds to its front and the
/// others after them, each side in its order, using `spare` (at least as
/// long as `run`).
fn partition(run: &mut [u32], spare: &mut [u32], left: impl Fn(u32) -> bool) {
    let (mut l, mut r) = (0, 0);
    // Without a branch on the side (a coin toss a predictor cannot
    // learn): each element is written to both places and one cursor
    // moves; `run[l]` is never past the element being read.
    for i in 0..run.len() {
        let p = run[i];
        let goes_left = left(p);
        run[l] = p;
        spare[r] = p;
        l += goes_left as usize;
        r += !goes_left as usize;
    }
    run[l..].copy_from_slice(&spare[..r]);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A TDBS build's scratch over `N` primitives (`L` = `8 * N` links,
    /// [`links_needed`]), lent to one build at a time.
    struct Scratch<const N: usize, const L: usize> {
        boxes: [Aabb; N],
        keys: [f32; N],
        links: [u32; L],
    }

    impl<const N: usize, const L: usize> Scratch<N, L> {
        fn new() -> Self {
            Scratch {
                boxes: [Aabb::EMPTY; N],
                keys: [0.0; N],
                links: [0; L],
            }
        }

        fn lend(&mut self) -> BvhScratch<'_> {
            BvhScratch {
                boxes: &mut self.boxes,
                keys: &mut self.keys,
                links: &mut self.links,
                clusters: &mut [],
            }
        }
    }

    /// The integer key orders as `f32::total_cmp` on the centres, then
    /// the primitive index.
    #[test]
    fn centre_key_orders_as_total_cmp_then_index() {
        let v = [
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
        let mut boxes = [Aabb::EMPTY; 30];
        for (i, b) in boxes.iter_mut().enumerate() {
            let c = v[i % v.len()];
            *b = Aabb {
                min: crate::Vec3::splat(c),
                max: crate::Vec3::splat(c),
            };
        }
        for axis in 0..3 {
            let ordered = boxes.map(|b| ordered_centre(&b, axis));
            for a in 0..30u32 {
                for b in 0..30u32 {
                    let (ca, cb) = (
                        centre(&boxes[a as usize], axis),
                        centre(&boxes[b as usize], axis),
                    );
                    assert_eq!(
                        centre_key(&ordered, a).cmp(&centre_key(&ordered, b)),
                        ca.total_cmp(&cb).then(a.cmp(&b)),
                        "{ca} {cb}"
                    );
                }
            }
        }
    }

    /// The SAH sweep that skips partitions by its lower bound picks the
    /// partition, and prices it to the bit, as pricing every partition
    /// does: on runs of boxes from tiny to scene-sized, repeated ones among
    /// them, against no best yet and against bests it must beat.
    #[test]
    fn the_bounded_sah_sweep_picks_what_pricing_every_partition_picks() {
        // Weights of 1/2 and 1 sum exactly in any order, so the reference
        // may sum each side afresh.
        fn price_all(
            run: &[u32],
            boxes: &[Aabb],
            suffix: &[f32],
            to_beat: Option<f64>,
            w: &dyn Fn(u32) -> f64,
        ) -> Found {
            let n = run.len();
            let mut found: Found = None;
            let mut left = Aabb::EMPTY;
            for k in 1..n {
                left = left.union(&boxes[run[k - 1] as usize]);
                let (wl, wr): (f64, f64) = (
                    run[..k].iter().map(|&p| w(p)).sum(),
                    run[k..].iter().map(|&p| w(p)).sum(),
                );
                let c = half_area(&left) * wl + suffix[k] as f64 * wr;
                let beat = found.map(|f| f.0).or(to_beat);
                if beat.is_none_or(|b| c < b) {
                    found = Some((c, k));
                }
            }
            found
        }
        let mut g = crate::rng::SplitMix64(7);
        let mut boxes = [Aabb::EMPTY; 300];
        let mut suffix = [0.0f32; 300];
        let mut run = [0u32; 300];
        let (mut skipped, mut tried) = (0, 0);
        for round in 0..400 {
            // Every length from 2 (the short cut) to 300, twice at the ends.
            let n = 2 + round % 299;
            for b in boxes[..n].iter_mut() {
                let c = crate::Vec3::new(g.next_f32(), g.next_f32(), g.next_f32()) * 100.0;
                let size = match g.next_f32() {
                    r if r < 0.1 => 100.0,
                    r if r < 0.5 => 1e-3,
                    r => r * 5.0,
                };
                let e = crate::Vec3::new(g.next_f32(), g.next_f32(), g.next_f32()) * size;
                *b = Aabb {
                    min: c - e,
                    max: c + e,
                };
            }
            // A few repeated boxes: equal centres and equal areas.
            for i in (3..n).step_by(7) {
                boxes[i] = boxes[i - 3];
            }
            for (i, r) in run[..n].iter_mut().enumerate() {
                *r = i as u32;
            }
            let axis = round % 3;
            sort_run(&mut run[..n], &boxes, axis);
            suffix_areas(&run[..n], &boxes, &mut suffix[..n]);
            // Every primitive alike, and the first half (the "triangles")
            // at half the cost of the rest.
            let halves = Weights { nt: n / 2, tw: 0.5 };
            for weights in [None, Some(halves)] {
                let w = |p: u32| weights.map_or(1.0, |w| w.of(p));
                let total: f64 = run[..n].iter().map(|&p| w(p)).sum();
                let all = price_all(&run[..n], &boxes, &suffix, None, &w);
                let best = all.expect("n >= 2").0;
                for to_beat in [None, Some(best * 1.5), Some(best), Some(best * 0.5)] {
                    let want = price_all(&run[..n], &boxes, &suffix, to_beat, &w);
                    let got = sweep_sah(&run[..n], &boxes, &suffix, to_beat, total, w);
                    assert_eq!(
                        got.map(|(c, k)| (c.to_bits(), k)),
                        want.map(|(c, k)| (c.to_bits(), k)),
                        "round {round} n {n} to_beat {to_beat:?}"
                    );
                    // The same through `sweep` (two primitives take a short
                    // cut there), which also hands back the run's box.
                    let mut spare = [0.0f32; 300];
                    let mut best = to_beat.map(|c| (c, 3, 0));
                    let bounds = sweep(
                        &run[..n],
                        &boxes,
                        &mut spare,
                        weights.map_or(Criterion::Sah, Criterion::SahWeighted),
                        total,
                        axis,
                        &mut best,
                    );
                    let want = want
                        .map(|(c, k)| (c, axis, k))
                        .or(to_beat.map(|c| (c, 3, 0)));
                    assert_eq!(
                        best.map(|(c, a, k)| (c.to_bits(), a, k)),
                        want.map(|(c, a, k)| (c.to_bits(), a, k)),
                        "round {round} n {n} to_beat {to_beat:?}"
                    );
                    let all = run[..n]
                        .iter()
                        .fold(Aabb::EMPTY, |b, &p| b.union(&boxes[p as usize]));
                    assert_eq!(bounds, all);
                }
            }
            tried += 1;
            skipped += (want_skips(&run[..n], &boxes, &suffix) > 0) as u32;
        }
        // The bound does skip partitions (else this test shows nothing).
        assert!(skipped > tried / 2, "{skipped} of {tried}");
    }

    /// Partitions the bounded SAH sweep skips on a run (no best given).
    fn want_skips(run: &[u32], boxes: &[Aabb], suffix: &[f32]) -> usize {
        let n = run.len();
        let mut left = boxes[run[0] as usize];
        let mut left_area = half_area(&left);
        let mut best = left_area + suffix[1] as f64 * (n - 1) as f64;
        let mut skipped = 0;
        for k in 2..n {
            left = left.union(&boxes[run[k - 1] as usize]);
            let right = suffix[k] as f64 * (n - k) as f64;
            if left_area * k as f64 + right >= best {
                skipped += 1;
                continue;
            }
            left_area = half_area(&left);
            best = best.min(left_area * k as f64 + right);
        }
        skipped
    }

    /// Sorts `run` by box centre on `axis` (index breaks ties: the build is
    /// the same on every machine).
    fn sort_run(run: &mut [u32], boxes: &[Aabb], axis: usize) {
        run.sort_unstable_by(|&a, &b| {
            centre(&boxes[a as usize], axis)
                .total_cmp(&centre(&boxes[b as usize], axis))
                .then(a.cmp(&b))
        });
    }

    /// The build as it was: every node sorts its run on each axis (the
    /// same sweep). The presorted build must give the same hierarchy,
    /// node for node.
    fn build_sorting_each_run<'a>(
        scene: &Scene<'a>,
        source: Option<&[Aabb]>,
        builder: Builder,
        leaf_size: u32,
        storage: BvhStorage<'a>,
        scratch: BvhScratch,
    ) -> Result<Bvh<'a>, Error> {
        let BvhStorage { nodes, refs } = storage;
        let boxes = &mut scratch.boxes[..];
        let suffix = &mut scratch.keys[..];
        let n = gather(scene, source, boxes, refs)?;
        let mut root_box = Aabb::EMPTY;
        for &p in &refs[..n] {
            root_box = root_box.union(&boxes[p as usize]);
        }
        nodes[0] = BvhNode::leaf(&root_box, 0, n as u32);
        // Depth per pair of siblings (root: pair 0; nodes 2p - 1 and 2p: pair p).
        let level = &mut scratch.links[..];
        let pair = |i: usize| i.div_ceil(2);
        if let Some(l) = level.first_mut() {
            *l = 0;
        }
        let (mut top, mut i, mut depth) = (1usize, 0usize, 0u32);
        while i < top {
            let nd = nodes[i];
            let (first, count) = (nd.first as usize, nd.len() as usize);
            let d = level.get(pair(i)).copied().unwrap_or(0);
            if count <= leaf_size as usize {
                depth = depth.max(d);
                i += 1;
                continue;
            }
            let run = &mut refs[first..first + count];
            // (criterion, axis, left count): smaller criterion is better.
            let mut best: Option<(f64, usize, usize)> = None;
            for axis in 0..3 {
                sort_run(run, boxes, axis);
                let criterion = match builder {
                    Builder::Tdbs => Criterion::Balanced,
                    _ => Criterion::Sah,
                };
                sweep(
                    run,
                    boxes,
                    suffix,
                    criterion,
                    run.len() as f64,
                    axis,
                    &mut best,
                );
            }
            let (_, axis, k) = best.expect("count >= 2");
            if axis != 2 {
                sort_run(run, boxes, axis);
            }
            let (mut bl, mut br) = (Aabb::EMPTY, Aabb::EMPTY);
            for &p in &run[..k] {
                bl = bl.union(&boxes[p as usize]);
            }
            for &p in &run[k..] {
                br = br.union(&boxes[p as usize]);
            }
            nodes[top] = BvhNode::leaf(&bl, first as u32, k as u32);
            nodes[top + 1] = BvhNode::leaf(&br, (first + k) as u32, (count - k) as u32);
            nodes[i] = BvhNode::interior(&nd.bounds(), top as u32, 2);
            level[pair(top)] = d + 1;
            top += 2;
            i += 1;
        }
        Ok(binary(scene, nodes, refs, top, n, depth))
    }

    /// Same nodes and references as sorting every run, for both criteria
    /// and several leaf sizes, on triangles with shared and equal centres.
    #[test]
    fn presorted_build_equals_sorting_each_run() {
        use crate::rng::SplitMix64;
        const N: usize = 400;
        let mut rng = SplitMix64(5);
        let mut vertices = [[0.0f32; 3]; 3 * N];
        let mut triangles = [[0u32; 3]; N];
        for (i, t) in triangles.iter_mut().enumerate() {
            // A coarse grid now and then: equal centres, ties broken by index.
            let grid = rng.below(3) == 0;
            let c = [0; 3].map(|_| {
                let x = rng.next_f32() * 10.0 - 5.0;
                if grid {
                    libm::roundf(x)
                } else {
                    x
                }
            });
            for k in 0..3 {
                let s = rng.next_f32() * 0.5;
                vertices[3 * i + k] =
                    [c[0] + s * (k as f32), c[1] - s, c[2] + s * ((k % 2) as f32)];
            }
            *t = [3 * i as u32, 3 * i as u32 + 1, 3 * i as u32 + 2];
        }
        let scene = Scene {
            vertices: &vertices,
            triangles: &triangles,
            spheres: &[],
            cones: &[],
        };
        for builder in [Builder::Tdbs, Builder::TdbsSah] {
            for leaf_size in [1, 2, 5] {
                let mut nodes = [[BvhNode::default(); 2 * N]; 2];
                let mut refs = [[0u32; N]; 2];
                let mut scratch = Scratch::<N, { 8 * N }>::new();
                let [na, nb] = &mut nodes;
                let [ra, rb] = &mut refs;
                let a = build(
                    &scene,
                    None,
                    builder,
                    leaf_size,
                    LeafRule::Size,
                    BvhStorage {
                        nodes: na,
                        refs: ra,
                    },
                    scratch.lend(),
                )
                .unwrap();
                let (a_nodes, a_refs) = a.parts();
                let b = build_sorting_each_run(
                    &scene,
                    None,
                    builder,
                    leaf_size,
                    BvhStorage {
                        nodes: nb,
                        refs: rb,
                    },
                    scratch.lend(),
                )
                .unwrap();
                let (b_nodes, b_refs) = b.parts();
                assert_eq!(a.info(), b.info(), "{builder:?} leaf {leaf_size}");
                assert_eq!(a_nodes, b_nodes, "{builder:?} leaf {leaf_size}");
                assert_eq!(a_refs, b_refs, "{builder:?} leaf {leaf_size}");
                assert!(a.info().node_count as usize > N / leaf_size as usize);
            }
        }
    }

    /// The SAH leaf rule: a traversal step priced beyond any split gives
    /// the size rule's tree; one that costs nothing splits every node of
    /// separate primitives down to one (their split halves the tests).
    #[test]
    fn sah_leaf_rule_between_its_limits() {
        const N: usize = 40;
        let mut vertices = [[0.0f32; 3]; 3 * N];
        let mut triangles = [[0u32; 3]; N];
        for i in 0..N {
            let x = ((i * 7) % N) as f32 * 3.0;
            vertices[3 * i] = [x, 0.0, 0.0];
            vertices[3 * i + 1] = [x + 1.0, 0.0, 0.0];
            vertices[3 * i + 2] = [x, 1.0, (i % 5) as f32];
            triangles[i] = [3 * i as u32, 3 * i as u32 + 1, 3 * i as u32 + 2];
        }
        let scene = Scene {
            vertices: &vertices,
            triangles: &triangles,
            spheres: &[],
            cones: &[],
        };
        let run = |rule: LeafRule, leaf_size: u32| {
            let mut nodes = [BvhNode::default(); 2 * N];
            let mut refs = [0u32; N];
            let mut scratch = Scratch::<N, { 8 * N }>::new();
            let b = build(
                &scene,
                None,
                Builder::TdbsSah,
                leaf_size,
                rule,
                BvhStorage {
                    nodes: &mut nodes,
                    refs: &mut refs,
                },
                scratch.lend(),
            )
            .unwrap();
            let (n, r) = b.parts();
            (*b.info(), n.to_vec(), r.to_vec())
        };
        let size = run(LeafRule::Size, 4);
        assert_eq!(
            size,
            run(
                LeafRule::Sah {
                    traversal: 1e30,
                    triangle: 1.0,
                    block: 1,
                },
                4
            )
        );
        let (free, _, _) = run(
            LeafRule::Sah {
                traversal: 0.0,
                triangle: 1.0,
                block: 1,
            },
            4,
        );
        assert_eq!(free.leaf_count as usize, N);
        assert!(size.0.leaf_count < free.leaf_count);
    }
}
