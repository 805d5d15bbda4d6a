//! rings: rings of spheres threaded on cylinders. Each ring is 30 spheres
//! joined in a loop by 30 cylinders; `s` levels of 20 rings stand around a
//! circle, each level turned and lifted, over a floor. 600 s spheres and
//! as many cylinders (4200 each at size 7, as the SPD's).

use super::{v, Builder, Options, V3};

const PER_RING: usize = 30;
const RINGS_PER_LEVEL: usize = 20;

fn ring(b: &mut Builder, center: V3, axis: V3, radius: f32) {
    let (e1, e2) = v::frame(axis);
    let points: Vec<V3> = (0..PER_RING)
        .map(|k| {
            let a = k as f32 * std::f32::consts::TAU / PER_RING as f32;
            v::add(
                center,
                v::add(
                    v::scale(e1, radius * a.cos()),
                    v::scale(e2, radius * a.sin()),
                ),
            )
        })
        .collect();
    let (rs, rc) = (0.12 * radius, 0.05 * radius);
    for p in &points {
        b.sphere(*p, rs);
    }
    for k in 0..PER_RING {
        b.cone(points[k], rc, points[(k + 1) % PER_RING], rc);
    }
}

pub(super) fn generate(b: &mut Builder, size: u32, opts: &Options) {
    let height = 0.9 * size as f32;
    b.view(
        [9.0, -7.0, height + 5.0],
        [0.0, 0.0, 0.45 * height],
        [0.0, 0.0, 1.0],
        45.0,
    );
    b.background([0.078, 0.361, 0.753]);
    b.light([10.0, -12.0, height + 14.0]);
    b.light([-9.0, -6.0, height + 8.0]);
    b.material([0.9, 0.9, 0.85], 0.9, 0.0, 0.0, 0.0, 1.0);
    b.floor(9.0, 2, 0.0, opts.floor_split);
    b.material([0.9, 0.35, 0.3], 0.6, 0.4, 40.0, 0.0, 1.0);
    for level in 0..size as usize {
        let z = 0.5 + 0.9 * level as f32;
        let turn = level as f32 * 0.5;
        for k in 0..RINGS_PER_LEVEL {
            let a = turn + k as f32 * std::f32::consts::TAU / RINGS_PER_LEVEL as f32;
            let c = [4.0 * a.cos(), 4.0 * a.sin(), z];
            // Each ring stands tangent to the circle, tilted a little.
            let axis = v::norm([a.cos(), a.sin(), 0.3]);
            ring(b, c, axis, 0.45);
        }
    }
}
