//! `random[:N]`: the benchmark's default scene. N random triangles and N/10
//! spheres in the cube [-1, 1]^3, seen from outside, lit by one point
//! light; the same on every machine (the project's one generator,
//! [`coray::rng::SplitMix64`], seed 2026).

use crate::mesh::SceneMesh;
use crate::nff::Material;
use coray::rng::SplitMix64;
use coray::{Camera, Sphere, Vec3};

/// Triangles of `random` when no count is given.
pub const DEFAULT_TRIANGLES: usize = 100_000;

/// Bytes the mesh of [`random`] takes per triangle (positions, normals,
/// flags, indices, materials; its spheres included): what a caller checks
/// against its memory before asking for a large N.
pub const BYTES_PER_TRIANGLE: usize = 3 * 12 + 3 * 12 + 3 + 12 + 4 + (16 + 4) / 10 + 1;

fn vec(g: &mut SplitMix64, s: f32) -> Vec3 {
    Vec3::new(
        (g.next_f32() * 2.0 - 1.0) * s,
        (g.next_f32() * 2.0 - 1.0) * s,
        (g.next_f32() * 2.0 - 1.0) * s,
    )
}

/// The scene with `tris` triangles (and `tris / 10` spheres).
pub fn random(tris: usize) -> SceneMesh {
    let mut g = SplitMix64(2026);
    let size = 2.0 / (tris.max(1) as f32).cbrt();
    let mut m = SceneMesh::default();
    for i in 0..tris as u32 {
        let c = vec(&mut g, 1.0);
        let p = [
            c + vec(&mut g, size),
            c + vec(&mut g, size),
            c + vec(&mut g, size),
        ];
        let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
        for q in p {
            m.vertices.push(q.to_array());
            m.normals.push(n.to_array());
            m.has_normal.push(false);
        }
        m.triangles.push([3 * i, 3 * i + 1, 3 * i + 2]);
    }
    m.spheres = (0..tris / 10)
        .map(|_| Sphere {
            center: vec(&mut g, 1.0).into(),
            radius: size * (0.2 + 0.5 * g.next_f32()),
        })
        .collect();
    m.materials = vec![
        Material {
            color: [0.8, 0.7, 0.5],
            kd: 0.9,
            ks: 0.0,
            shine: 0.0,
            t: 0.0,
            ior: 1.0,
        },
        Material {
            color: [0.5, 0.6, 0.9],
            kd: 0.6,
            ks: 0.4,
            shine: 30.0,
            t: 0.0,
            ior: 1.0,
        },
    ];
    m.prim_material = std::iter::repeat_n(0, m.triangles.len())
        .chain(std::iter::repeat_n(1, m.spheres.len()))
        .collect();
    m.camera = Camera {
        from: Vec3::new(1.2, 1.6, 3.4),
        at: Vec3::ZERO,
        up: Vec3::Y,
        angle_deg: 45.0,
        width: 1024,
        height: 1024,
    };
    m.hither = 0.0;
    m.lights = vec![(Vec3::new(4.0, 6.0, 3.0), Vec3::ONE)];
    m.background = Vec3::new(0.078, 0.361, 0.753);
    m.counts.triangles = m.triangles.len();
    m.counts.polygons = m.triangles.len();
    m.counts.spheres = m.spheres.len();
    m.counts.lights = 1;
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The counts the benchmark tables quote, and the same scene each time.
    #[test]
    fn counts_and_repeatability() {
        let a = random(1000);
        assert_eq!(
            (a.counts.objects(), a.triangles.len(), a.spheres.len()),
            (1100, 1000, 100)
        );
        let b = random(1000);
        assert_eq!(a.vertices, b.vertices);
        assert_eq!(random(0).counts.objects(), 0);
    }
}
