//! A leaf's primitives against one ray from blocks of copied triangle
//! corners (four reference slots a block, lane by lane): triangles four at
//! a time ([`intersect_triangles4`]: one pass of vector instructions, no
//! branch per triangle, no gather through the scene's indices), spheres
//! and cones one at a time. The answers are those of testing each
//! reference alone with [`Scene::intersect_prim`]: the closest hit's tie
//! rule orders hits at one `t` by primitive, so the order of the tests
//! does not matter.

use super::triangle::{intersect_triangles4, Corners4, Hits4, TRI_LANES};
use super::{Hit, PreparedRay, Scene, GEOM_TRIANGLES};

/// Two hits at exactly the same `t`: the lower global index wins
/// (triangles, then spheres, then cones), so every traversal order, and so
/// every structure, reports the same primitive.
#[inline]
fn tie_wins(h: &Hit, best: &Hit) -> bool {
    h.t == best.t && (h.geom_id, h.prim_id) < (best.geom_id, best.prim_id)
}

/// Whether hit `h` replaces `best` (a miss, or the best hit so far): it is
/// nearer, or ties and wins. Every closest-hit query keeps hits by it.
#[inline(always)]
pub(crate) fn beats(h: &Hit, best: &Hit) -> bool {
    !best.is_hit() || h.t < best.t || tie_wins(h, best)
}

/// Keeps `h` in `best` when it [`beats`] it.
#[inline(always)]
fn keep(best: &mut Hit, h: Hit) {
    if beats(&h, best) {
        *best = h;
    }
}

/// The lanes set in `mask`, lowest first.
#[inline(always)]
fn lanes_of(mut mask: u32) -> impl Iterator<Item = usize> {
    core::iter::from_fn(move || {
        (mask != 0).then(|| {
            let lane = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            lane
        })
    })
}

/// Triangle `lane` of `block` hit as `h4` found it, reported as
/// [`Scene::intersect_prim`] reports it for primitive `prim`.
#[inline(always)]
fn block_hit(block: &Corners4, h4: &Hits4, lane: usize, prim: u32) -> Hit {
    let c = |k: usize| glam::Vec3::new(block[k][0][lane], block[k][1][lane], block[k][2][lane]);
    let (a, b, cc) = (c(0), c(1), c(2));
    Hit {
        t: h4.t[lane],
        u: h4.u[lane],
        v: h4.v[lane],
        ng: (a - b).cross(cc - a),
        geom_id: GEOM_TRIANGLES,
        prim_id: prim,
    }
}

/// Lanes of `block` that hold a triangle (the others hold NaN): a
/// leaf of spheres or cones skips its blocks for one compare.
#[inline(always)]
fn triangle_lanes(block: &Corners4) -> u32 {
    let x = &block[0][0];
    (0..TRI_LANES).fold(0, |m, i| m | (!x[i].is_nan() as u32) << i)
}

/// The blocks (of [`TRI_LANES`] reference slots) that slots
/// `[first, first + count)` cover, each with the mask of its lanes among
/// them.
#[inline(always)]
fn block_runs(first: usize, count: usize) -> impl Iterator<Item = (usize, u32)> {
    let end = first + count;
    let (b0, b1) = (first / TRI_LANES, end.div_ceil(TRI_LANES));
    (b0..b1).map(move |b| {
        let lo = first.saturating_sub(b * TRI_LANES);
        let hi = (end - b * TRI_LANES).min(TRI_LANES);
        (b, ((1u32 << hi) - 1) & !((1u32 << lo) - 1))
    })
}

/// The blocks of [`block_runs`] that hold a triangle among the run's
/// lanes, as (block index, block, those lanes); `None` for a block past
/// `blocks` (corrupt input).
#[inline(always)]
fn triangle_blocks(
    blocks: &[Corners4],
    first: usize,
    count: usize,
) -> impl Iterator<Item = Option<(usize, &Corners4, u32)>> {
    block_runs(first, count).filter_map(move |(b, lanes)| match blocks.get(b) {
        None => Some(None),
        Some(block) => {
            let lanes = lanes & triangle_lanes(block);
            (lanes != 0).then_some(Some((b, block, lanes)))
        }
    })
}

/// References `refs[first..first + count]`, or `None` past `refs`.
#[inline(always)]
fn run_of(refs: &[u32], first: usize, count: usize) -> Option<&[u32]> {
    first
        .checked_add(count)
        .and_then(|end| refs.get(first..end))
}

/// The closest hit among the references `refs[first..first + count]`
/// nearer than `best` (a miss, or a hit from an earlier leaf) within
/// `[r.t_min, r.t_max]`, kept in `best`. Their triangles' corners lie in
/// `blocks` (slot `s` in lane `s % 4` of block `s / 4`, NaN where the slot
/// is no triangle); spheres and cones among them are tested one at a time
/// when `others` (the scene has any), and a run without a triangle does
/// not touch its blocks. Returns false when a slot or block lies past its
/// slice (corrupt input), having tested what lay within.
#[inline(never)]
pub(crate) fn closest_in_blocks(
    scene: &Scene,
    r: &PreparedRay,
    refs: &[u32],
    blocks: &[Corners4],
    (first, count): (usize, usize),
    others: bool,
    best: &mut Hit,
) -> bool {
    let Some(run) = run_of(refs, first, count) else {
        return false;
    };
    let limit = |best: &Hit| if best.is_hit() { best.t } else { r.t_max };
    let mut triangles = !others;
    if others {
        let nt = scene.triangles.len();
        for &p in run {
            if (p as usize) < nt {
                triangles = true;
            } else if let Some(h) = scene.intersect_prim(p as usize, r, limit(best)) {
                keep(best, h);
            }
        }
    }
    if !triangles {
        return true;
    }
    for found in triangle_blocks(blocks, first, count) {
        let Some((b, block, lanes)) = found else {
            return false;
        };
        let t_max = limit(best);
        let h4 = intersect_triangles4(r, block, t_max);
        for lane in lanes_of(h4.hit & lanes) {
            keep(
                best,
                block_hit(block, &h4, lane, refs[b * TRI_LANES + lane]),
            );
        }
        for lane in lanes_of(h4.edge & lanes) {
            let prim = refs[b * TRI_LANES + lane] as usize;
            if let Some(h) = scene.intersect_prim(prim, r, t_max) {
                keep(best, h);
            }
        }
    }
    true
}

/// Whether any of the references `refs[first..first + count]` is hit
/// within `[r.t_min, t_max]`, from `blocks` as [`closest_in_blocks`];
/// `None` for corrupt input.
#[inline(never)]
pub(crate) fn any_in_blocks(
    scene: &Scene,
    r: &PreparedRay,
    refs: &[u32],
    blocks: &[Corners4],
    (first, count): (usize, usize),
    others: bool,
    t_max: f32,
) -> Option<bool> {
    let run = run_of(refs, first, count)?;
    let mut triangles = !others;
    if others {
        let nt = scene.triangles.len();
        for &p in run {
            if (p as usize) < nt {
                triangles = true;
            } else if scene.intersect_prim(p as usize, r, t_max).is_some() {
                return Some(true);
            }
        }
    }
    if !triangles {
        return Some(false);
    }
    for found in triangle_blocks(blocks, first, count) {
        let (b, block, lanes) = found?;
        let h4 = intersect_triangles4(r, block, t_max);
        let edge_hit = |lane: usize| {
            let prim = refs[b * TRI_LANES + lane] as usize;
            scene.intersect_prim(prim, r, t_max).is_some()
        };
        if h4.hit & lanes != 0 || lanes_of(h4.edge & lanes).any(edge_hit) {
            return Some(true);
        }
    }
    Some(false)
}
