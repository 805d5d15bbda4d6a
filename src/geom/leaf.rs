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
pub(crate) fn tie_wins(h: &Hit, best: &Hit) -> bool {
    h.t == best.t && (h.geom_id, h.prim_id) < (best.geom_id, best.prim_id)
}

/// Keeps `h` in `best` when it is nearer, or ties and wins.
#[inline(always)]
fn keep(best: &mut Hit, h: Hit) {
    if !best.is_hit() || h.t < best.t || tie_wins(&h, best) {
        *best = h;
    }
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
    let Some(run) = first
        .checked_add(count)
        .and_then(|end| refs.get(first..end))
    else {
        return false;
    };
    let mut triangles = !others;
    if others {
        let nt = scene.triangles.len();
        for &p in run {
            if (p as usize) < nt {
                triangles = true;
            } else {
                let t_max = if best.is_hit() { best.t } else { r.t_max };
                if let Some(h) = scene.intersect_prim(p as usize, r, t_max) {
                    keep(best, h);
                }
            }
        }
    }
    if !triangles {
        return true;
    }
    for (b, lanes) in block_runs(first, count) {
        let Some(block) = blocks.get(b) else {
            return false;
        };
        let lanes = lanes & triangle_lanes(block);
        if lanes == 0 {
            continue;
        }
        let t_max = if best.is_hit() { best.t } else { r.t_max };
        let h4 = intersect_triangles4(r, block, t_max);
        let (mut hit, mut edge) = (h4.hit & lanes, h4.edge & lanes);
        while hit != 0 {
            let lane = hit.trailing_zeros() as usize;
            hit &= hit - 1;
            let prim = refs[b * TRI_LANES + lane];
            keep(best, block_hit(block, &h4, lane, prim));
        }
        while edge != 0 {
            let lane = edge.trailing_zeros() as usize;
            edge &= edge - 1;
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
    let run = first
        .checked_add(count)
        .and_then(|end| refs.get(first..end))?;
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
    for (b, lanes) in block_runs(first, count) {
        let block = blocks.get(b)?;
        let lanes = lanes & triangle_lanes(block);
        if lanes == 0 {
            continue;
        }
        let h4 = intersect_triangles4(r, block, t_max);
        if h4.hit & lanes != 0 {
            return Some(true);
        }
        let mut edge = h4.edge & lanes;
        while edge != 0 {
            let lane = edge.trailing_zeros() as usize;
            edge &= edge - 1;
            let prim = refs[b * TRI_LANES + lane] as usize;
            if scene.intersect_prim(prim, r, t_max).is_some() {
                return Some(true);
            }
        }
    }
    Some(false)
}
