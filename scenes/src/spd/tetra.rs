//! tetra: the recursive tetrahedron (Sierpinski). A tetrahedron is replaced
//! by the four half-size ones at its corners, `size - 1` times; each of the
//! 4^(s-1) that remain is written as 4 triangles.

use super::{v, Builder, V3};

fn tetra(b: &mut Builder, p: [V3; 4], depth: u32) {
    if depth == 0 {
        for (i, j, k) in [(0, 1, 2), (0, 3, 1), (1, 3, 2), (2, 3, 0)] {
            b.polygon(vec![p[i], p[j], p[k]]);
        }
        return;
    }
    let mid = |a: V3, c: V3| v::scale(v::add(a, c), 0.5);
    for c in 0..4 {
        let mut q = p;
        for (o, qo) in q.iter_mut().enumerate() {
            if o != c {
                *qo = mid(p[c], p[o]);
            }
        }
        tetra(b, q, depth - 1);
    }
}

pub(super) fn generate(b: &mut Builder, size: u32) {
    b.view(
        [1.02, -3.18, -2.31],
        [-0.004, -0.035, 0.003],
        [-0.09, -0.58, 0.81],
        45.0,
    );
    b.background([0.078, 0.361, 0.753]);
    b.light([1.87, -2.0, -2.9]);
    b.light([-1.5, -2.5, 1.5]);
    b.material([1.0, 0.2, 0.2], 0.8, 0.2, 10.0, 0.0, 1.0);
    let s = 1.0 / 3f32.sqrt();
    let p = [[s, s, s], [s, -s, -s], [-s, s, -s], [-s, -s, s]];
    tetra(b, p, size - 1);
}
