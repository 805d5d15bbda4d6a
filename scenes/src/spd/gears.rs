//! gears: s^3 meshing gears in s layers of s x s. A gear is a prism over a
//! 72-tooth outline: two concave 144-gons (front and back faces) and 144
//! side quads. Neighbours turn half a tooth against each other so the teeth
//! interleave without touching. A floor quad lies under the stack.

use super::{Builder, Options, V3};

const TEETH: usize = 72;
const TIP: f32 = 1.0;
const ROOT: f32 = 0.9;
const THICKNESS: f32 = 0.2;

fn gear(b: &mut Builder, c: V3, turn: f32) {
    let n = 2 * TEETH;
    let outline: Vec<(f32, f32)> = (0..n)
        .map(|k| {
            let a = turn + k as f32 * std::f32::consts::TAU / n as f32;
            let r = if k % 2 == 0 { TIP } else { ROOT };
            (c[0] + r * a.cos(), c[1] + r * a.sin())
        })
        .collect();
    let (z0, z1) = (c[2] - 0.5 * THICKNESS, c[2] + 0.5 * THICKNESS);
    // Front face counter-clockwise seen from +z, back face the other way.
    b.polygon(outline.iter().map(|&(x, y)| [x, y, z1]).collect());
    b.polygon(outline.iter().rev().map(|&(x, y)| [x, y, z0]).collect());
    for k in 0..n {
        let (p, q) = (outline[k], outline[(k + 1) % n]);
        b.polygon(vec![
            [p.0, p.1, z0],
            [q.0, q.1, z0],
            [q.0, q.1, z1],
            [p.0, p.1, z1],
        ]);
    }
}

pub(super) fn generate(b: &mut Builder, size: u32, opts: &Options) {
    let pitch = TIP + ROOT + 0.02;
    let extent = pitch * (size as f32 - 1.0);
    let center = 0.5 * extent;
    b.view(
        [
            center - 1.2 * extent - 3.0,
            center - 2.0 * extent - 4.0,
            extent + 4.0,
        ],
        [center, center, 0.4 * extent],
        [0.0, 0.0, 1.0],
        45.0,
    );
    b.background([0.078, 0.361, 0.753]);
    b.light([center - 10.0, center - 12.0, extent + 12.0]);
    b.light([center + 9.0, center - 6.0, extent + 8.0]);
    b.material([0.7, 0.7, 0.7], 0.9, 0.0, 0.0, 0.0, 1.0);
    let h = 0.5 * extent + 3.0;
    let k = opts.floor_split;
    // The floor square around the stack, centred under it.
    let mut tmp = Builder::default();
    tmp.floor(h, 2, -0.5, k);
    for o in tmp.scene.objects {
        if let crate::nff::Object::Polygon { vertices, .. } = o {
            b.polygon(
                vertices
                    .into_iter()
                    .map(|p| [p[0] + center, p[1] + center, p[2]])
                    .collect(),
            );
        }
    }
    let half_tooth = std::f32::consts::PI / TEETH as f32;
    for layer in 0..size {
        let z = layer as f32 * (THICKNESS + 0.5);
        for j in 0..size {
            for i in 0..size {
                let odd = (i + j + layer) % 2 == 1;
                if odd {
                    b.material([0.85, 0.6, 0.2], 0.6, 0.4, 30.0, 0.0, 1.0);
                } else {
                    b.material([0.3, 0.5, 0.85], 0.6, 0.4, 30.0, 0.0, 1.0);
                }
                gear(
                    b,
                    [i as f32 * pitch, j as f32 * pitch, z],
                    if odd { half_tooth } else { 0.0 },
                );
            }
        }
    }
}
