//! Bottom-up binary matching (thesis 2.2.2, "Bottom-Up Binary Matching"):
//! every object starts as a cluster; the two clusters whose joint box has
//! the smallest surface area are joined, until one is left.
//!
//! Each cluster keeps its best partner and that joint area. Joining A and
//! B cannot make a better partner for any other cluster C (the box of A
//! and B and C holds the box of A and C), so the area a cluster recorded
//! stays a lower bound of its best one when it loses its partner: such a
//! cluster is marked stale and looks again only when its bound is the
//! smallest (the first such cluster is taken, as the thesis' search takes
//! the first smallest area). That is the thesis' tree, found in O(n^2):
//! where many clusters lose one partner at once (identical boxes, which
//! all name the same first cluster), looking again eagerly was O(n^3).

use super::{binary, check_storage, gather, requirements, Builder, Bvh, BvhNode};
use super::{BvhScratch, BvhStorage};
use crate::geom::{Aabb, Scene};
use crate::Error;

/// Set in a cluster's link when its partner was joined away: its key is
/// then a lower bound of its best joint area, not the area.
const STALE: u32 = 1 << 31;

fn joint_area(a: &BvhNode, b: &BvhNode) -> f32 {
    a.bounds().union(&b.bounds()).area()
}

/// The best partner of cluster `k` among `0..m`: smallest joint area,
/// lowest slot on ties.
fn best_partner(clusters: &[BvhNode], k: usize, m: usize) -> (u32, f32) {
    let mut best = (u32::MAX, f32::INFINITY);
    for j in 0..m {
        if j != k {
            let c = joint_area(&clusters[k], &clusters[j]);
            if c < best.1 || best.0 == u32::MAX {
                best = (j as u32, c);
            }
        }
    }
    best
}

pub(crate) fn build<'a>(
    scene: &Scene<'a>,
    source: Option<&[Aabb]>,
    storage: BvhStorage<'a>,
    scratch: BvhScratch,
) -> Result<Bvh<'a>, Error> {
    let req = requirements(scene.prim_count(), Builder::Nn);
    check_storage(&req, &storage, &scratch)?;
    let BvhStorage { nodes, refs } = storage;
    let BvhScratch {
        boxes,
        keys,
        links,
        clusters,
    } = scratch;
    let n = gather(scene, source, boxes, refs)?;
    for k in 0..n {
        clusters[k] = BvhNode::leaf(&boxes[refs[k] as usize], k as u32, 1);
    }
    for k in 0..n {
        (links[k], keys[k]) = best_partner(clusters, k, n);
    }
    let (mut m, mut top) = (n, 1usize);
    while m > 1 {
        // The first cluster of the smallest bound; a stale one looks
        // again (its bound only grows) until the first is up to date.
        let a = loop {
            let mut a = 0;
            for k in 1..m {
                if keys[k] < keys[a] {
                    a = k;
                }
            }
            if links[a] & STALE == 0 {
                break a;
            }
            (links[a], keys[a]) = best_partner(clusters, a, m);
        };
        let b = links[a] as usize;
        let (lo, hi) = (a.min(b), a.max(b));
        nodes[top] = clusters[lo];
        nodes[top + 1] = clusters[hi];
        let joint = clusters[lo].bounds().union(&clusters[hi].bounds());
        clusters[lo] = BvhNode::interior(&joint, top as u32, 2);
        top += 2;
        // Slot `hi` takes the last cluster.
        let last = m - 1;
        clusters[hi] = clusters[last];
        keys[hi] = keys[last];
        links[hi] = links[last];
        m -= 1;
        for (k, link) in links[..m].iter_mut().enumerate() {
            let p = (*link & !STALE) as usize;
            if k == lo || p == lo || p == hi {
                *link |= STALE;
            } else if p == last {
                *link = hi as u32 | (*link & STALE);
            }
        }
    }
    nodes[0] = if n == 0 {
        BvhNode::leaf(&Aabb::EMPTY, 0, 0)
    } else {
        clusters[0]
    };
    let depth = if n > 0 {
        pair_depths(nodes, top, links)
    } else {
        0
    };
    Ok(binary(scene, nodes, refs, top, n, depth))
}

/// Depth of a binary hierarchy whose nodes `1..top` were placed in sibling
/// pairs (`1, 2`, `3, 4`, ...) before their parent, the root at 0; `depths`
/// is scratch of `top / 2 + 1` entries (one per pair).
pub(crate) fn pair_depths(nodes: &[BvhNode], top: usize, depths: &mut [u32]) -> u32 {
    let pair = |i: usize| i.div_ceil(2);
    let mut depth = 0;
    depths[0] = 0;
    for i in core::iter::once(0).chain((1..top).rev()) {
        let nd = nodes[i];
        let d = depths[pair(i)];
        if nd.is_leaf() {
            depth = depth.max(d);
        } else {
            depths[pair(nd.first as usize)] = d + 1;
        }
    }
    depth
}
