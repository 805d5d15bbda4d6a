//! mount: a fractal mountain from a square of two triangles, each triangle
//! split into four `size` times with midpoints raised by a hash of their
//! position (so shared edges get the same point), and four glass spheres in
//! front of it.

use super::{v, Builder, V3};

/// A repeatable pseudo-random value in [-1, 1] for a point (its bits).
fn hash(p: V3) -> f32 {
    let mut h: u64 = 0x9E37_79B9_7F4A_7C15;
    for c in p {
        h ^= c.to_bits() as u64;
        h = h.wrapping_mul(0xBF58_476D_1CE4_E5B9);
        h ^= h >> 29;
    }
    (h >> 40) as f32 / (1u64 << 23) as f32 - 1.0
}

fn split(b: &mut Builder, t: [V3; 3], depth: u32, rough: f32) {
    if depth == 0 {
        b.polygon(t.to_vec());
        return;
    }
    let mid = |a: V3, c: V3| {
        let mut m = v::scale(v::add(a, c), 0.5);
        let len = v::dot(v::sub(a, c), v::sub(a, c)).sqrt();
        // The key is the flat midpoint: both triangles of an edge agree.
        m[2] += hash([m[0], m[1], 0.0]) * len * rough;
        m
    };
    let (ab, bc, ca) = (mid(t[0], t[1]), mid(t[1], t[2]), mid(t[2], t[0]));
    split(b, [t[0], ab, ca], depth - 1, rough);
    split(b, [ab, t[1], bc], depth - 1, rough);
    split(b, [ca, bc, t[2]], depth - 1, rough);
    split(b, [ab, bc, ca], depth - 1, rough);
}

pub(super) fn generate(b: &mut Builder, size: u32) {
    b.view([-1.6, 1.9, 1.4], [0.0, 0.0, 0.3], [0.0, 0.0, 1.0], 45.0);
    b.background([0.078, 0.361, 0.753]);
    b.light([-100.0, -100.0, 100.0]);
    b.material([1.0, 0.5, 0.45], 0.8, 0.2, 10.0, 0.0, 1.0);
    let (a, c, d, e) = (
        [-1.0, -1.0, 0.0],
        [1.0, -1.0, 0.0],
        [1.0, 1.0, 0.0],
        [-1.0, 1.0, 0.0],
    );
    split(b, [a, c, d], size, 0.12);
    split(b, [a, d, e], size, 0.12);
    b.material([1.0, 1.0, 1.0], 0.0, 0.1, 1000.0, 0.9, 1.5);
    for (i, r) in [0.1f32, 0.12, 0.15, 0.18].iter().enumerate() {
        let x = -0.6 + i as f32 * 0.35;
        b.sphere([x, 0.9 - 0.3 * i as f32, 0.6], *r);
    }
}
