//! Scenes the command works on: `random[:N]`, `spd:NAME[:SIZE]` or an NFF file.

use coray::{Camera, Sphere, Vec3};
use coray_scenes::nff::Material;
use coray_scenes::spd::{self, Options};
use coray_scenes::{NffScene, SceneMesh};

/// A scene and the name the user gave it.
pub struct SceneData {
    pub name: String,
    pub mesh: SceneMesh,
}

impl SceneData {
    pub fn prim_count(&self) -> usize {
        self.mesh.scene().prim_count()
    }
}

/// SplitMix64: the built-in random scene is the same on every machine.
struct Rng(u64);
impl Rng {
    fn f(&mut self) -> f32 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    }
    fn vec(&mut self, s: f32) -> Vec3 {
        Vec3::new(
            (self.f() * 2.0 - 1.0) * s,
            (self.f() * 2.0 - 1.0) * s,
            (self.f() * 2.0 - 1.0) * s,
        )
    }
}

/// `random[:N]`: N random triangles (default 100,000) and N/10 spheres in
/// the cube [-1, 1]^3, seen from outside, lit by one point light.
pub fn random(tris: usize) -> SceneMesh {
    let mut rng = Rng(2026);
    let size = 2.0 / (tris.max(1) as f32).cbrt();
    let mut m = SceneMesh::default();
    for i in 0..tris as u32 {
        let c = rng.vec(1.0);
        let p: Vec<Vec3> = (0..3).map(|_| c + rng.vec(size)).collect();
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
            center: rng.vec(1.0).into(),
            radius: size * (0.2 + 0.5 * rng.f()),
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
    m.lights = vec![(Vec3::new(4.0, 6.0, 3.0), Vec3::ONE)];
    m.background = Vec3::new(0.078, 0.361, 0.753);
    m.counts.triangles = m.triangles.len();
    m.counts.polygons = m.triangles.len();
    m.counts.spheres = m.spheres.len();
    m.counts.lights = 1;
    m
}

/// Reads a scene name: `random[:N]`, `spd:NAME[:SIZE]` or a path to an NFF file.
pub fn load(spec: &str, opts: &Options) -> Result<SceneData, String> {
    let mesh = if let Some(rest) = spec.strip_prefix("spd:") {
        let (name, size) = match rest.split_once(':') {
            Some((n, s)) => (
                n,
                Some(
                    s.parse::<u32>()
                        .map_err(|_| format!("`{s}` is not a size factor"))?,
                ),
            ),
            None => (rest, None),
        };
        SceneMesh::from_nff(&spd::generate(name, size, opts)?)
    } else if spec == "random" || spec.starts_with("random:") {
        let n = match spec.split_once(':') {
            None => 100_000,
            Some((_, a)) => a
                .parse()
                .map_err(|_| format!("`{a}` is not a triangle count"))?,
        };
        random(n)
    } else {
        let text = std::fs::read_to_string(spec).map_err(|e| format!("{spec}: {e}"))?;
        let nff = NffScene::parse(&text).map_err(|e| format!("{spec}:{e}"))?;
        SceneMesh::from_nff(&nff)
    };
    Ok(SceneData {
        name: spec.to_string(),
        mesh,
    })
}
