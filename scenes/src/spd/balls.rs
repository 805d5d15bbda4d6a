//! balls: the sphereflake. A sphere carries nine spheres of a third its
//! radius, six around its equator and three above, each oriented away from
//! its parent, recursively to depth `size`; a floor below.

use super::{v, Builder, Options, V3};

fn flake(b: &mut Builder, center: V3, radius: f32, up: V3, depth: u32) {
    b.sphere(center, radius);
    if depth == 0 {
        return;
    }
    let (e1, e2) = v::frame(up);
    let child = radius / 3.0;
    let dist = radius + child;
    for i in 0..9 {
        // Six on the equator every 60 degrees; three at 45 degrees up,
        // every 120 degrees, between the equator ones.
        let (azimuth, elevation) = if i < 6 {
            (i as f32 * 60.0, 0.0f32)
        } else {
            (30.0 + (i - 6) as f32 * 120.0, 45.0f32)
        };
        let (az, el) = (azimuth.to_radians(), elevation.to_radians());
        let dir = v::add(
            v::add(
                v::scale(e1, az.cos() * el.cos()),
                v::scale(e2, az.sin() * el.cos()),
            ),
            v::scale(up, el.sin()),
        );
        flake(
            b,
            v::add(center, v::scale(dir, dist)),
            child,
            dir,
            depth - 1,
        );
    }
}

pub(super) fn generate(b: &mut Builder, size: u32, opts: &Options) {
    b.view([2.1, 1.3, 1.7], [0.0, 0.0, 0.0], [0.0, 0.0, 1.0], 45.0);
    b.background([0.078, 0.361, 0.753]);
    b.light([4.0, 3.0, 2.0]);
    b.light([1.0, -4.0, 4.0]);
    b.light([-3.0, 1.0, 5.0]);
    b.material([1.0, 0.75, 0.33], 0.8, 0.0, 0.0, 0.0, 1.0);
    b.floor(12.0, 2, -0.5, opts.floor_split);
    b.material([1.0, 0.9, 0.7], 0.5, 0.5, 3.0827, 0.0, 1.0);
    flake(b, [0.0, 0.0, 0.0], 0.5, [0.0, 0.0, 1.0], size);
}
