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

/// Lanes of `block` that hold a triangle (the others hold NaN, and name a
/// sphere, a cone or no reference).
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

/// One block of a run: its index, the block (`None` past `blocks`:
/// corrupt input when the run's slots there name a triangle), the run's
/// lanes in it and those of them that hold a triangle. A leaf's other
/// slots are its spheres and cones: the block's NaN lanes say which, so a
/// leaf of triangles alone never reads its references unless it is hit.
#[inline(always)]
fn run_blocks(
    blocks: &[Corners4],
    first: usize,
    count: usize,
) -> impl Iterator<Item = (usize, Option<&Corners4>, u32, u32)> {
    block_runs(first, count).map(move |(b, lanes)| {
        let block = blocks.get(b);
        let triangles = block.map_or(0, |block| lanes & triangle_lanes(block));
        (b, block, lanes, triangles)
    })
}

/// The primitives of the lanes of block `b` that hold no triangle
/// (`lanes & !triangles`), in turn, each `f`'s `Some` stopping the loop;
/// `Err` for a slot past its block that names a triangle (corrupt input).
/// Slots of a block that name a triangle in a NaN lane are not tested
/// (their block says there is nothing).
#[inline(always)]
fn for_others<T>(
    scene: &Scene,
    refs: &[u32],
    (b, block, lanes, triangles): (usize, Option<&Corners4>, u32, u32),
    mut f: impl FnMut(usize) -> Option<T>,
) -> Result<Option<T>, ()> {
    let nt = scene.triangles.len();
    for lane in lanes_of(lanes & !triangles) {
        let p = refs[b * TRI_LANES + lane] as usize;
        if p >= nt {
            if let Some(x) = f(p) {
                return Ok(Some(x));
            }
        } else if block.is_none() {
            return Err(());
        }
    }
    Ok(None)
}

/// The triangle test one block of a run asks for: (block index, block,
/// triangle lanes), `Ok(None)` for none, `Err` for a block past `blocks`
/// in a scene of triangles alone (corrupt input; with spheres or cones,
/// [`for_others`] has judged those slots).
#[inline(always)]
fn triangle_part(
    (b, block, _, triangles): (usize, Option<&Corners4>, u32, u32),
    others: bool,
) -> Result<Option<(usize, &Corners4, u32)>, ()> {
    match block {
        None if others => Ok(None),
        None => Err(()),
        Some(_) if triangles == 0 => Ok(None),
        Some(block) => Ok(Some((b, block, triangles))),
    }
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
/// when `others` (the scene has any): the slots of NaN lanes and those past
/// the blocks (where runs without a triangle lie), so a run of triangles
/// alone reads its references only for the triangles it hits. Returns
/// false when a slot or block lies past its slice, or a slot past the
/// blocks names a triangle (corrupt input), having tested what lay before.
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
    if run_of(refs, first, count).is_none() {
        return false;
    }
    let limit = |best: &Hit| if best.is_hit() { best.t } else { r.t_max };
    for part in run_blocks(blocks, first, count) {
        if others {
            let found = for_others(scene, refs, part, |p| {
                if let Some(h) = scene.intersect_prim(p, r, limit(best)) {
                    keep(best, h);
                }
                None::<()>
            });
            if found.is_err() {
                return false;
            }
        }
        let (b, block, lanes) = match triangle_part(part, others) {
            Ok(Some(test)) => test,
            Ok(None) => continue,
            Err(()) => return false,
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
    run_of(refs, first, count)?;
    for part in run_blocks(blocks, first, count) {
        if others {
            let hit = |p: usize| scene.intersect_prim(p, r, t_max).map(|_| ());
            if for_others(scene, refs, part, hit).ok()?.is_some() {
                return Some(true);
            }
        }
        let Some((b, block, lanes)) = triangle_part(part, others).ok()? else {
            continue;
        };
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
