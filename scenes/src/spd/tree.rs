//! tree: a binary tree of branches, each an open cone with a sphere at its
//! tip; a branch forks into two shorter, thinner ones, turned a quarter
//! about the parent's axis at every level. 2^(s+1) - 1 branches; a floor.

use super::{v, Builder, Options, V3};

const LENGTH_SCALE: f32 = 0.72;
const RADIUS_SCALE: f32 = 0.68;
const SPREAD_DEG: f32 = 32.0;

fn branch(b: &mut Builder, base: V3, dir: V3, side: V3, length: f32, radius: f32, depth: u32) {
    let tip = v::add(base, v::scale(dir, length));
    let tip_radius = radius * RADIUS_SCALE;
    b.cone(base, radius, tip, tip_radius);
    b.sphere(tip, tip_radius);
    if depth == 0 {
        return;
    }
    // Children fork in the plane of `dir` and `side`; their own `side` is
    // the perpendicular, so consecutive forks are a quarter turn apart.
    let next_side = v::norm(v::cross(dir, side));
    let a = SPREAD_DEG.to_radians();
    for sign in [-1.0f32, 1.0] {
        let d = v::norm(v::add(
            v::scale(dir, a.cos()),
            v::scale(side, sign * a.sin()),
        ));
        branch(
            b,
            tip,
            d,
            next_side,
            length * LENGTH_SCALE,
            tip_radius,
            depth - 1,
        );
    }
}

pub(super) fn generate(b: &mut Builder, size: u32, opts: &Options) {
    b.view([4.0, 4.5, 2.2], [0.0, 0.0, 1.3], [0.0, 0.0, 1.0], 45.0);
    b.background([0.078, 0.361, 0.753]);
    b.light([5.0, 4.0, 8.0]);
    b.light([-6.0, 3.0, 5.0]);
    b.light([2.0, -7.0, 6.0]);
    b.material([0.55, 0.75, 0.35], 0.9, 0.0, 0.0, 0.0, 1.0);
    b.floor(6.0, 2, 0.0, opts.floor_split);
    b.material([0.55, 0.4, 0.2], 0.8, 0.1, 5.0, 0.0, 1.0);
    branch(
        b,
        [0.0, 0.0, 0.0],
        [0.0, 0.0, 1.0],
        [1.0, 0.0, 0.0],
        1.0,
        0.1,
        size,
    );
}
