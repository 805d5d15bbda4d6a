//! lattice: a cubic grid of (s+1)^3 spheres joined along every axis by
//! 3 s (s+1)^2 cylinders.

use super::Builder;

pub(super) fn generate(b: &mut Builder, size: u32) {
    b.view([3.4, 2.6, 2.2], [0.0, 0.0, 0.0], [0.0, 0.0, 1.0], 45.0);
    b.background([0.078, 0.361, 0.753]);
    b.light([4.0, 3.0, 6.0]);
    b.light([-4.0, 5.0, 3.0]);
    let n = size as usize;
    let step = 2.0 / size as f32;
    let p = |i: usize| -1.0 + i as f32 * step;
    b.material([0.9, 0.3, 0.2], 0.7, 0.3, 20.0, 0.0, 1.0);
    for k in 0..=n {
        for j in 0..=n {
            for i in 0..=n {
                b.sphere([p(i), p(j), p(k)], 0.2 * step);
            }
        }
    }
    b.material([0.6, 0.6, 0.7], 0.7, 0.3, 20.0, 0.0, 1.0);
    let r = 0.06 * step;
    for axis in 0..3 {
        for a in 0..=n {
            for c in 0..=n {
                for s in 0..n {
                    let mut from = [0.0; 3];
                    from[axis] = p(s);
                    from[(axis + 1) % 3] = p(a);
                    from[(axis + 2) % 3] = p(c);
                    let mut to = from;
                    to[axis] = p(s + 1);
                    b.cone(from, r, to, r);
                }
            }
        }
    }
}
