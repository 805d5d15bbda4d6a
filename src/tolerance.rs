//! Every tolerance of the library and of its comparisons, one constant per
//! rule, each with its reason (as libm keeps its `precision.rs`). The
//! traversals and builds use the margins up to [`SECONDARY_RAY_OFFSET`]; the
//! benchmark, the Embree cross-checks and the tests use the rest through
//! [`same_hit`], [`near_tie`] and [`classify`]. The C ABI exports the
//! comparison tolerances (`CORAY_TOL_*` in coray.h) for C cross-checks.

use crate::Hit;

/// Relative margin (2^-19) by which a hit must lie before its leaf's exit
/// for a kd traversal to stop there, and by which every traversal widens
/// the scene's box. A primitive's own test may put a hit a few ulps beyond
/// the exact leaf or root box; 2^-19 is thousands of ulps of f32 (2^-23),
/// so a hit within rounding of a boundary always lets the next leaf be
/// visited, where a primitive at the same t may lie.
pub const LEAF_EXIT_MARGIN: f32 = 1.0 / 524_288.0;

/// Relative thickness (2^-12) of the cell a kd build cuts planar primitives
/// off a node's face with: far above the rounding of a ray's points on
/// that face, so no traversal classifies a point across it differently.
pub const FACE_CELL: f32 = 1.0 / 4096.0;

/// Factor on a slab test's far distance so that rounding never loses a box
/// the ray touches (Ize 2013: `1 + 2 gamma(3)`); every BVH and the wide
/// hierarchy's kernels use it.
pub const BOX_FAR_SLACK: f32 = 1.0 + 4.0 * f32::EPSILON;

/// Relative widening (4 ulps) of a box computed with rounding (square
/// roots, radii: spheres and cones), so that every point the primitive's
/// own test can report lies inside it. Triangle boxes are exact.
pub const ROUNDED_BOX_PAD: f32 = 4.0 * f32::EPSILON;

/// Relative padding (4e-6) of every projection hierarchy rectangle: the
/// projections of a box's corners and of a ray are each rounded, and a ray
/// that hits the box must still find its point inside (a few ulps would
/// do; this is ample and cheap).
pub const PROJECTED_RECT_PAD: f32 = 4.0e-6;

/// How far (1e-3, in the `sx`, `sy` of `Camera::ray_in`, 2 across the
/// image) an LCTS window must lie outside the scene's projected box to be
/// skipped: some 10^4 times the rounding of a pixel's direction and of the
/// box's projection.
pub const SCREEN_MARGIN: f32 = 1e-3;

/// Depth along the view (1e-3 of the farthest corner's distance) that each
/// corner of the scene's box must exceed for the box to have a projected
/// rectangle: nearer the eye's plane its projection is unbounded.
pub const SCREEN_NEAR_DEPTH: f32 = 1e-3;

/// A ray leaving a surface (shadow, bounce) starts 1e-4 of the scene's size
/// from its point, far above the rounding of the hit point, so that it
/// does not meet the surface it leaves.
pub const SECONDARY_RAY_OFFSET: f32 = 1e-4;

/// Two hits of one ray on different primitives are a tie when their t
/// agree within 2^-20 relative: both are the closest within f32 rounding
/// of the intersection tests (a few ulps each), so either answer is right.
pub const TIE_REL: f32 = 1.0 / 1_048_576.0;

/// Two structures' hits on the same primitive agree when their t differ by
/// at most 1e-4 of max(1, t): coray's tests and Embree's (or another
/// structure's, for non-triangles) compute t in different orders.
pub const SAME_T_REL: f32 = 1e-4;

/// A triangle hit whose smallest barycentric weight is below this (1e-4)
/// lies on an edge: a rounding error in either library moves it to the
/// neighbour or off the mesh.
pub const EDGE_BARY: f32 = 1e-4;

/// A cone hit this close (1e-3, in the axis parameter u) to either rim:
/// Embree 3.13's linear cone curves end with caps coray's open cones lack.
pub const RIM_U: f32 = 1e-3;

/// A hit where the ray meets the surface at a cosine below this (2e-2) is
/// tangent: rounding turns it into a miss as easily as not.
pub const GRAZE_COS: f32 = 2e-2;

/// Within rounding of each other: `|a - b| <= TIE_REL * max(|a|, |b|)`.
#[inline]
pub fn near_tie(a: f32, b: f32) -> bool {
    (a - b).abs() <= a.abs().max(b.abs()) * TIE_REL
}

/// The same answer for one ray from two structures: both miss, or both hit
/// the same primitive (or two primitives in a tie) at t within
/// [`SAME_T_REL`].
pub fn same_hit(a: &Hit, b: &Hit) -> bool {
    if a.is_hit() != b.is_hit() {
        return false;
    }
    if !a.is_hit() {
        return true;
    }
    let same_prim = (a.geom_id, a.prim_id) == (b.geom_id, b.prim_id);
    (same_prim || near_tie(a.t, b.t)) && (a.t - b.t).abs() <= SAME_T_REL * a.t.abs().max(1.0)
}

/// How two libraries' (or two structures') answers for one ray relate,
/// by the documented tie rules.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Agreement {
    /// Both miss, or both hit the same primitive within [`SAME_T_REL`].
    Same,
    /// Different primitives at the same distance (shared edges, coincident surfaces).
    TieSameDistance,
    /// The nearer answer grazes ([`grazing`]), where rounding turns a hit into a miss.
    TieGrazing,
    /// Anything else: a real disagreement.
    Mismatch,
}

/// [`SAME_T_REL`] of `t`: `1e-4 * max(1, |t|)`.
#[inline]
pub fn t_tolerance(t: f32) -> f32 {
    SAME_T_REL * t.abs().max(1.0)
}

/// True when rounding can turn `h` into a miss on `r`: on a triangle's edge
/// ([`EDGE_BARY`]), at a cone's rim ([`RIM_U`]), tangent to the surface
/// ([`GRAZE_COS`]), or within the tolerance of the ray's start (a ray
/// leaving a surface meeting that surface again).
pub fn grazing(r: &crate::Ray, h: &Hit) -> bool {
    if h.t < r.t_min + t_tolerance(r.t_min) {
        return true;
    }
    let edge = match h.geom_id {
        crate::geom::GEOM_TRIANGLES => h.u.min(h.v).min(1.0 - h.u - h.v) < EDGE_BARY,
        crate::geom::GEOM_CONES => h.u < RIM_U || h.u > 1.0 - RIM_U,
        _ => false,
    };
    let cos = r.dir.normalize().dot(h.ng.normalize()).abs();
    edge || cos < GRAZE_COS
}

/// Classifies a ray's two answers `a` and `b` by the tie rules above.
pub fn classify(r: &crate::Ray, a: &Hit, b: &Hit) -> Agreement {
    match (a.is_hit(), b.is_hit()) {
        (false, false) => return Agreement::Same,
        (true, true) if (a.t - b.t).abs() <= t_tolerance(a.t) => {
            return if (a.geom_id, a.prim_id) == (b.geom_id, b.prim_id) {
                Agreement::Same
            } else {
                Agreement::TieSameDistance
            };
        }
        _ => {}
    }
    let nearer = if !b.is_hit() || (a.is_hit() && a.t < b.t) {
        a
    } else {
        b
    };
    if grazing(r, nearer) {
        Agreement::TieGrazing
    } else {
        Agreement::Mismatch
    }
}

/// Classifies two any-hit answers: they agree, or one of them sees only a
/// grazing occluder (`hit` is that ray's closest hit, when known).
pub fn classify_occluded(r: &crate::Ray, a: bool, b: bool, hit: Option<&Hit>) -> Agreement {
    if a == b {
        Agreement::Same
    } else if hit.is_some_and(|h| grazing(r, h)) {
        Agreement::TieGrazing
    } else {
        Agreement::Mismatch
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn margins_are_far_above_f32_rounding() {
        // Each margin is at least 8 ulps of the value it scales.
        for m in [LEAF_EXIT_MARGIN, FACE_CELL, TIE_REL] {
            assert!(m >= 8.0 * f32::EPSILON, "{m}");
        }
        const { assert!(TIE_REL < LEAF_EXIT_MARGIN) };
    }

    #[test]
    fn ties_and_same_hits() {
        let h = |t: f32, p: u32| Hit {
            t,
            prim_id: p,
            geom_id: 0,
            ..Hit::MISS
        };
        assert!(same_hit(&Hit::MISS, &Hit::MISS));
        assert!(!same_hit(&h(1.0, 0), &Hit::MISS));
        assert!(same_hit(&h(1.0, 0), &h(1.00005, 0)));
        assert!(!same_hit(&h(1.0, 0), &h(1.001, 0)));
        assert!(same_hit(&h(10.0, 0), &h(10.0 * (1.0 + 1e-7), 3)));
        assert!(!same_hit(&h(10.0, 0), &h(10.001, 3)));
        assert!(near_tie(1e6, 1e6 + 0.5));
        assert!(!near_tie(1.0, 1.01));
    }
}
