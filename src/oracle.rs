//! Brute-force ray shooting: every primitive against every ray. The
//! reference every structure is tested against (feature `oracle`).

use crate::geom::{Hit, PreparedRay, Ray, Scene};

/// Closest hit by testing every non-degenerate primitive.
pub fn intersect(scene: &Scene, ray: &Ray) -> Hit {
    if !ray.is_valid() {
        return Hit::MISS;
    }
    let r = PreparedRay::new(ray);
    let mut best = Hit::MISS;
    for p in 0..scene.prim_count() {
        if scene.prim_bounds(p).is_none() {
            continue;
        }
        let t_max = if best.is_hit() { best.t } else { ray.t_max };
        if let Some(h) = scene.intersect_prim(p, &r, t_max) {
            if !best.is_hit() || h.t < best.t {
                best = h;
            }
        }
    }
    best
}

/// True when any non-degenerate primitive lies on the ray.
pub fn occluded(scene: &Scene, ray: &Ray) -> bool {
    if !ray.is_valid() {
        return false;
    }
    let r = PreparedRay::new(ray);
    (0..scene.prim_count())
        .any(|p| scene.prim_bounds(p).is_some() && scene.intersect_prim(p, &r, ray.t_max).is_some())
}
