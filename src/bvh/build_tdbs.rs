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
use core::cmp::Ordering;

fn centre(b: &Aabb, axis: usize) -> f32 {
    0.5 * (b.min[axis] + b.max[axis])
}

fn area(b: &Aabb) -> f64 {
    if b.is_empty() {
        return 0.0;
    }
    let e = (b.max - b.min).as_dvec3();
    2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
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

pub(crate) fn build<'a>(
    scene: &Scene<'a>,
    source: Option<&[Aabb]>,
    builder: Builder,
    leaf_size: u32,
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
            let mut acc = Aabb::EMPTY;
            for k in (1..count).rev() {
                acc = acc.union(&boxes[run[k] as usize]);
                suffix[k] = area(&acc) as f32;
            }
            let mut left = Aabb::EMPTY;
            for k in 1..count {
                left = left.union(&boxes[run[k - 1] as usize]);
                let (al, ar) = (area(&left), suffix[k] as f64);
                let c = match builder {
                    Builder::Tdbs => (al - ar).abs(),
                    _ => al * k as f64 + ar * (count - k) as f64,
                };
                if best.is_none_or(|b| c.partial_cmp(&b.0) == Some(Ordering::Less)) {
                    best = Some((c, axis, k));
                }
            }
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
