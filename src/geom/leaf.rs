//! The closest hit's tie rule, which every structure keeps hits by: the
//! answers are those of testing each primitive alone, whatever order a
//! traversal tests them in.

use super::Hit;

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
