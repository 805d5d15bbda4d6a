//! teapot: the Utah teapot's 32 Bezier patches, each tessellated into
//! s x s quads split into two triangles written as `pp` polygons with the
//! surface normal at each vertex; triangles that collapse where a patch
//! edge does (the lid's and the bottom's centres) are left out. A
//! checkerboard floor of s x s squares lies under it.

use super::teapot_data::{PATCHES, POINTS};
use super::Builder;

type D3 = [f64; 3];

fn bernstein(t: f64) -> ([f64; 4], [f64; 4]) {
    let s = 1.0 - t;
    let b = [s * s * s, 3.0 * t * s * s, 3.0 * t * t * s, t * t * t];
    let d = [
        -3.0 * s * s,
        3.0 * s * s - 6.0 * t * s,
        6.0 * t * s - 3.0 * t * t,
        3.0 * t * t,
    ];
    (b, d)
}

/// Point and (unnormalised) normal of a patch at (u, v).
fn eval(patch: &[u16; 16], u: f64, v: f64) -> (D3, D3) {
    let (bu, du) = bernstein(u);
    let (bv, dv) = bernstein(v);
    let (mut p, mut pu, mut pv) = ([0.0; 3], [0.0; 3], [0.0; 3]);
    for i in 0..4 {
        for j in 0..4 {
            let c = POINTS[patch[4 * i + j] as usize - 1];
            for k in 0..3 {
                let c = c[k] as f64;
                p[k] += bv[i] * bu[j] * c;
                pu[k] += bv[i] * du[j] * c;
                pv[k] += dv[i] * bu[j] * c;
            }
        }
    }
    let n = [
        pu[1] * pv[2] - pu[2] * pv[1],
        pu[2] * pv[0] - pu[0] * pv[2],
        pu[0] * pv[1] - pu[1] * pv[0],
    ];
    (p, n)
}

fn unit(n: D3) -> [f32; 3] {
    let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    if l > 0.0 {
        [(n[0] / l) as f32, (n[1] / l) as f32, (n[2] / l) as f32]
    } else {
        [0.0, 0.0, 1.0]
    }
}

fn close(a: D3, b: D3) -> bool {
    (0..3).all(|k| (a[k] - b[k]).abs() < 1e-9)
}

pub(super) fn generate(b: &mut Builder, size: u32) {
    b.view([-6.4, -8.6, 6.0], [0.0, 0.0, 1.1], [0.0, 0.0, 1.0], 35.0);
    b.background([0.078, 0.361, 0.753]);
    b.light([-3.1, -9.8, 12.1]);
    b.light([11.3, -1.0, 6.5]);
    let n = size as usize;
    // Checkerboard floor: the light squares, then the dark ones.
    let h = 6.0f32;
    let step = 2.0 * h / n as f32;
    for parity in 0..2 {
        if parity == 0 {
            b.material([0.95, 0.95, 0.9], 0.9, 0.1, 10.0, 0.0, 1.0);
        } else {
            b.material([0.7, 0.15, 0.1], 0.9, 0.1, 10.0, 0.0, 1.0);
        }
        for j in 0..n {
            for i in 0..n {
                if (i + j) % 2 != parity {
                    continue;
                }
                let (x0, y0) = (-h + i as f32 * step, -h + j as f32 * step);
                let (x1, y1) = (x0 + step, y0 + step);
                b.polygon(vec![
                    [x0, y0, 0.0],
                    [x1, y0, 0.0],
                    [x1, y1, 0.0],
                    [x0, y1, 0.0],
                ]);
            }
        }
    }
    b.material([1.0, 0.5, 0.1], 0.7, 0.3, 40.0, 0.0, 1.0);
    for patch in &PATCHES {
        let mut grid = vec![([0.0; 3], [0.0f32; 3]); (n + 1) * (n + 1)];
        for j in 0..=n {
            for i in 0..=n {
                let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                let (p, mut nrm) = eval(patch, u, v);
                if unit(nrm) == [0.0, 0.0, 1.0] && nrm == [0.0; 3] {
                    // A collapsed edge: take the normal just inside the patch.
                    let (u2, v2) = (u.clamp(1e-4, 1.0 - 1e-4), v.clamp(1e-4, 1.0 - 1e-4));
                    nrm = eval(patch, u2, v2).1;
                }
                grid[j * (n + 1) + i] = (p, unit(nrm));
            }
        }
        let at = |i: usize, j: usize| grid[j * (n + 1) + i];
        for j in 0..n {
            for i in 0..n {
                let q = [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)];
                for tri in [[q[0], q[1], q[2]], [q[0], q[2], q[3]]] {
                    if close(tri[0].0, tri[1].0)
                        || close(tri[1].0, tri[2].0)
                        || close(tri[2].0, tri[0].0)
                    {
                        continue;
                    }
                    let vertices = tri.iter().map(|(p, _)| p.map(|x| x as f32)).collect();
                    let normals = tri.iter().map(|(_, n)| *n).collect();
                    b.polygon_with_normals(vertices, normals);
                }
            }
        }
    }
}
