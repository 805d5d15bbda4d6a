//! Bottom-up matching in sub-quadratic time: the nearest-neighbour chain
//! over a kd-tree of cluster boxes.
//!
//! The joint surface area is reducible: joining A and B never brings the
//! pair nearer to any C than A or B was (`box(A, B, C)` holds `box(A, C)`).
//! For such a distance the chain (follow nearest neighbours until two are
//! each other's; join them; go on from the rest of the chain) makes the
//! same joins as always joining the globally closest pair, which is
//! the quadratic matching ([`super::Builder::Nn`]); only exact ties can be broken differently.
//!
//! Nearest neighbours come from a kd-tree built once over the primitives'
//! box centres (median splits, implicit layout, `2n - 1` boxes). A cluster
//! lives in the leaf of its first primitive; a join keeps the lower slot,
//! empties the other and refits both root paths. A query descends nearer
//! children first and prunes a subtree whose lower bound is already
//! larger than the best pair found. The bound uses two boxes per index
//! node: the union of its clusters, and their "inner" box (the largest
//! of their minima, the smallest of their maxima): every cluster below
//! reaches at least that far, so the joint box of the query with any of
//! them spans at least the query joined to the inner box. The bound is
//! exact when the clusters below are identical, which keeps equal boxes
//! (ties everywhere) at O(log n) a query: with the union alone, 50,000
//! identical triangles and 50,000 identical spheres took 27 s.

use super::{binary, check_storage, gather, Bvh, BvhNode};
use super::{BvhScratch, BvhStorage};
use crate::geom::{Aabb, Scene};
use crate::Error;

const NONE: u32 = u32::MAX;

/// Storage of the nearest-neighbour chain build over `n` primitives.
pub(crate) fn chain_requirements(n: usize) -> super::BvhRequirements {
    super::BvhRequirements {
        nodes: (2 * n).saturating_sub(1).max(1),
        refs: n,
        boxes: n + 2 * (2 * n).saturating_sub(1),
        keys: 0,
        links: n,
        clusters: n,
    }
}

fn centre(b: &Aabb, axis: usize) -> f32 {
    0.5 * (b.min[axis] + b.max[axis])
}

/// The inner box of nothing: the identity of [`inner_join`].
const NO_INNER: Aabb = Aabb {
    min: crate::Vec3::splat(f32::NEG_INFINITY),
    max: crate::Vec3::splat(f32::INFINITY),
};

/// The inner box of two groups: the larger minima, the smaller maxima
/// (it may be inverted; it is a bound, not a region).
fn inner_join(a: &Aabb, b: &Aabb) -> Aabb {
    Aabb {
        min: a.min.max(b.min),
        max: a.max.min(b.max),
    }
}

/// A lower bound of `x`'s joint area with any cluster whose minima are at
/// most `inner.min` and maxima at least `inner.max`. Only comparisons, then
/// the area's own arithmetic: rounding keeps it at most the joint area
/// `Aabb::union(..).area()` computes.
fn joint_area_bound(x: &Aabb, inner: &Aabb) -> f32 {
    Aabb {
        min: x.min.min(inner.min),
        max: x.max.max(inner.max),
    }
    .area()
}

/// The kd-tree of cluster boxes: node `i` over slots `lo..hi` has its left
/// child at `i + 1` (slots `lo..mid`) and its right child at
/// `i + 2 * (mid - lo)`, `mid = (lo + hi) / 2`.
struct Index<'s> {
    /// Per node, the union of its clusters' boxes.
    boxes: &'s mut [Aabb],
    /// Per node, its clusters' inner box ([`inner_join`]).
    inner: &'s mut [Aabb],
    clusters: &'s mut [BvhNode],
    n: usize,
}

impl Index<'_> {
    /// A leaf's two boxes: its cluster's, or nothing once emptied.
    fn leaf_boxes(&self, slot: usize) -> (Aabb, Aabb) {
        let b = self.clusters[slot].bounds();
        (b, if b.is_empty() { NO_INNER } else { b })
    }

    fn fill(&mut self, i: usize, lo: usize, hi: usize) {
        let (b, inner) = if hi - lo == 1 {
            self.leaf_boxes(lo)
        } else {
            let mid = (lo + hi) / 2;
            let (l, r) = (i + 1, i + 2 * (mid - lo));
            self.fill(l, lo, mid);
            self.fill(r, mid, hi);
            self.joined(l, r)
        };
        self.boxes[i] = b;
        self.inner[i] = inner;
    }

    fn joined(&self, l: usize, r: usize) -> (Aabb, Aabb) {
        (
            self.boxes[l].union(&self.boxes[r]),
            inner_join(&self.inner[l], &self.inner[r]),
        )
    }

    /// Recomputes the boxes on the path from the root to `slot`.
    fn refit(&mut self, slot: usize) {
        let mut path = [(0usize, 0usize, 0usize); 64];
        let (mut i, mut lo, mut hi, mut d) = (0, 0, self.n, 0);
        while hi - lo > 1 {
            path[d] = (i, lo, hi);
            d += 1;
            let mid = (lo + hi) / 2;
            if slot < mid {
                (i, hi) = (i + 1, mid);
            } else {
                (i, lo) = (i + 2 * (mid - lo), mid);
            }
        }
        (self.boxes[i], self.inner[i]) = self.leaf_boxes(slot);
        for &(i, lo, hi) in path[..d].iter().rev() {
            let mid = (lo + hi) / 2;
            (self.boxes[i], self.inner[i]) = self.joined(i + 1, i + 2 * (mid - lo));
        }
    }

    /// Nearest cluster to the one in `x` (smallest joint area; ties go to
    /// `prev`, then to the lowest slot) below node `i` over `lo..hi`.
    fn nearest(&self, x: usize, prev: u32, i: usize, lo: usize, hi: usize, best: &mut (f32, u32)) {
        let xb = self.clusters[x].bounds();
        if self.boxes[i].is_empty() {
            return;
        }
        if hi - lo == 1 {
            if lo != x {
                let d = xb.union(&self.boxes[i]).area();
                let (bd, bp) = *best;
                if d < bd || (d == bd && bp != prev && (lo as u32) < bp) || bp == NONE {
                    *best = (d, lo as u32);
                }
            }
            return;
        }
        let mid = (lo + hi) / 2;
        let kids = [(i + 1, lo, mid), (i + 2 * (mid - lo), mid, hi)];
        let lb = kids.map(|(k, _, _)| {
            if self.boxes[k].is_empty() {
                f32::INFINITY
            } else {
                joint_area_bound(&xb, &self.inner[k])
            }
        });
        let order = if lb[1] < lb[0] { [1, 0] } else { [0, 1] };
        for o in order {
            let (k, klo, khi) = kids[o];
            let (bd, bp) = *best;
            // A tie inside can still win only on a lower slot, unless `prev` holds it.
            let useless = lb[o] > bd || (lb[o] == bd && (bp == prev || klo as u32 > bp));
            if lb[o] == f32::INFINITY || (bp != NONE && useless) {
                continue;
            }
            self.nearest(x, prev, k, klo, khi, best);
        }
    }
}

/// Sorts `refs` into kd order: median splits on the axis of widest centre
/// spread, the same midpoints as [`Index`].
fn kd_order(refs: &mut [u32], boxes: &[Aabb]) {
    let mut stack = [(0usize, 0usize); 64];
    stack[0] = (0, refs.len());
    let mut sp = 1;
    while sp > 0 {
        sp -= 1;
        let (lo, hi) = stack[sp];
        if hi - lo < 2 {
            continue;
        }
        let mut c = Aabb::EMPTY;
        for &p in &refs[lo..hi] {
            let b = &boxes[p as usize];
            let m = 0.5 * (b.min + b.max);
            c = c.union(&Aabb { min: m, max: m });
        }
        let e = c.max - c.min;
        let axis = if e.x >= e.y && e.x >= e.z {
            0
        } else if e.y >= e.z {
            1
        } else {
            2
        };
        let mid = (lo + hi) / 2;
        refs[lo..hi].select_nth_unstable_by(mid - lo, |&a, &b| {
            centre(&boxes[a as usize], axis)
                .total_cmp(&centre(&boxes[b as usize], axis))
                .then(a.cmp(&b))
        });
        stack[sp] = (lo, mid);
        stack[sp + 1] = (mid, hi);
        sp += 2;
    }
}

pub(crate) fn build<'a>(
    scene: &Scene<'a>,
    source: Option<&[Aabb]>,
    storage: BvhStorage<'a>,
    scratch: BvhScratch,
) -> Result<Bvh<'a>, Error> {
    let prims = scene.prim_count();
    let req = chain_requirements(prims);
    check_storage(&req, &storage, &scratch)?;
    let BvhStorage { nodes, refs } = storage;
    let BvhScratch {
        boxes,
        links: chain,
        clusters,
        ..
    } = scratch;
    let (prim_boxes, index_boxes) = boxes.split_at_mut(prims);
    let (index_boxes, index_inner) = index_boxes.split_at_mut((2 * prims).saturating_sub(1));
    let n = gather(scene, source, prim_boxes, refs)?;
    if n == 0 {
        nodes[0] = BvhNode::leaf(&Aabb::EMPTY, 0, 0);
        return Ok(binary(scene, nodes, refs, 1, 0, 0));
    }
    kd_order(&mut refs[..n], prim_boxes);
    for k in 0..n {
        clusters[k] = BvhNode::leaf(&prim_boxes[refs[k] as usize], k as u32, 1);
    }
    let mut index = Index {
        boxes: index_boxes,
        inner: index_inner,
        clusters,
        n,
    };
    index.fill(0, 0, n);
    let (mut left, mut top, mut len, mut next) = (n, 1usize, 0usize, 0usize);
    while left > 1 {
        if len == 0 {
            while index.clusters[next].bounds().is_empty() {
                next += 1;
            }
            chain[0] = next as u32;
            len = 1;
        }
        let x = chain[len - 1] as usize;
        let prev = if len >= 2 { chain[len - 2] } else { NONE };
        // Start from the previous link: it keeps every tie (the chain's rule).
        let mut best = if prev == NONE {
            (f32::INFINITY, NONE)
        } else {
            let b = index.clusters[x].bounds();
            (
                b.union(&index.clusters[prev as usize].bounds()).area(),
                prev,
            )
        };
        index.nearest(x, prev, 0, 0, n, &mut best);
        if best.1 == NONE {
            // Every joint area with x is infinite (coordinates near
            // f32::MAX), and the search prunes those: x joins the first
            // other live cluster. Rare, so the scan's cost does not matter.
            let other = (0..n).find(|&k| k != x && !index.clusters[k].bounds().is_empty());
            best.1 = other.map_or(NONE, |k| k as u32);
        }
        let y = best.1;
        if y != prev {
            chain[len] = y;
            len += 1;
            continue;
        }
        len -= 2;
        let (lo, hi) = (x.min(y as usize), x.max(y as usize));
        nodes[top] = index.clusters[lo];
        nodes[top + 1] = index.clusters[hi];
        let joint = index.clusters[lo]
            .bounds()
            .union(&index.clusters[hi].bounds());
        index.clusters[lo] = BvhNode::interior(&joint, top as u32, 2);
        index.clusters[hi] = BvhNode::leaf(&Aabb::EMPTY, 0, 0);
        index.refit(lo);
        index.refit(hi);
        top += 2;
        left -= 1;
    }
    let root = (0..n)
        .find(|&k| !index.clusters[k].bounds().is_empty())
        .unwrap_or(0);
    nodes[0] = index.clusters[root];
    let depth = super::build_nn::pair_depths(nodes, top, chain);
    Ok(binary(scene, nodes, refs, top, n, depth))
}
