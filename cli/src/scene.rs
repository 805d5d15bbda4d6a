//! Scenes the command works on: owned primitive arrays, a camera and lights.

use coray::{Camera, Cone, Scene, Sphere, Vec3};

/// A scene with everything the command needs to trace it.
pub struct SceneData {
    /// How the user named it.
    pub name: String,
    pub vertices: Vec<[f32; 3]>,
    pub triangles: Vec<[u32; 3]>,
    pub spheres: Vec<Sphere>,
    pub cones: Vec<Cone>,
    pub camera: Camera,
    /// Point lights.
    pub lights: Vec<Vec3>,
}

impl SceneData {
    pub fn scene(&self) -> Scene<'_> {
        Scene {
            vertices: &self.vertices,
            triangles: &self.triangles,
            spheres: &self.spheres,
            cones: &self.cones,
        }
    }

    pub fn prim_count(&self) -> usize {
        self.triangles.len() + self.spheres.len() + self.cones.len()
    }
}

/// SplitMix64: the built-in scenes are the same on every machine.
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
pub fn random(tris: usize) -> SceneData {
    let mut rng = Rng(2026);
    let size = 2.0 / (tris.max(1) as f32).cbrt();
    let mut vertices = Vec::with_capacity(3 * tris);
    let mut triangles = Vec::with_capacity(tris);
    for i in 0..tris as u32 {
        let c = rng.vec(1.0);
        for _ in 0..3 {
            vertices.push((c + rng.vec(size)).to_array());
        }
        triangles.push([3 * i, 3 * i + 1, 3 * i + 2]);
    }
    let spheres = (0..tris / 10)
        .map(|_| Sphere {
            center: rng.vec(1.0).into(),
            radius: size * (0.2 + 0.5 * rng.f()),
        })
        .collect();
    SceneData {
        name: format!("random:{tris}"),
        vertices,
        triangles,
        spheres,
        cones: Vec::new(),
        camera: Camera {
            from: Vec3::new(1.2, 1.6, 3.4),
            at: Vec3::ZERO,
            up: Vec3::Y,
            angle_deg: 45.0,
            width: 1024,
            height: 1024,
        },
        lights: vec![Vec3::new(4.0, 6.0, 3.0)],
    }
}

/// Reads a scene name: `random` or `random:N`.
pub fn load(spec: &str) -> Result<SceneData, String> {
    let (kind, arg) = spec
        .split_once(':')
        .map_or((spec, None), |(k, a)| (k, Some(a)));
    match kind {
        "random" => {
            let n = match arg {
                None => 100_000,
                Some(a) => a
                    .parse()
                    .map_err(|_| format!("`{a}` is not a triangle count"))?,
            };
            Ok(random(n))
        }
        _ => Err(format!("unknown scene `{spec}` (built-in: random[:N])")),
    }
}
