//! Scene and ray generators, and owned storage for building in tests.
#![allow(dead_code)]

use coray::kd::{
    self, KdEvent, KdLeaf, KdNode, KdParams, KdRequirements, KdRopes, KdScratch, KdStorage, KdTree,
};
use coray::{Cone, Ray, Scene, Sphere, Vec3};

/// SplitMix64: small, seedable, good enough for test data.
pub struct Rng(pub u64);

impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    pub fn f(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.f()
    }
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n.max(1) as u64) as usize
    }
    pub fn vec(&mut self, lo: f32, hi: f32) -> Vec3 {
        Vec3::new(self.range(lo, hi), self.range(lo, hi), self.range(lo, hi))
    }
    pub fn unit(&mut self) -> Vec3 {
        loop {
            let v = self.vec(-1.0, 1.0);
            let l = v.length_squared();
            if l > 1e-4 && l <= 1.0 {
                return v / l.sqrt();
            }
        }
    }
}

/// Owned primitive arrays that a [`Scene`] borrows.
#[derive(Default, Clone)]
pub struct OwnedScene {
    pub vertices: Vec<[f32; 3]>,
    pub triangles: Vec<[u32; 3]>,
    pub spheres: Vec<Sphere>,
    pub cones: Vec<Cone>,
}

impl OwnedScene {
    pub fn scene(&self) -> Scene<'_> {
        Scene {
            vertices: &self.vertices,
            triangles: &self.triangles,
            spheres: &self.spheres,
            cones: &self.cones,
        }
    }
    pub fn add_triangle(&mut self, a: Vec3, b: Vec3, c: Vec3) {
        let i = self.vertices.len() as u32;
        self.vertices
            .extend([a.to_array(), b.to_array(), c.to_array()]);
        self.triangles.push([i, i + 1, i + 2]);
    }
    /// An axis-aligned quad on `axis` at `pos`, spanning [lo, hi] on the other axes, as two triangles.
    pub fn add_quad(&mut self, axis: usize, pos: f32, lo: [f32; 2], hi: [f32; 2]) {
        let p = |u: f32, v: f32| {
            let mut x = Vec3::ZERO;
            x[axis] = pos;
            x[(axis + 1) % 3] = u;
            x[(axis + 2) % 3] = v;
            x
        };
        self.add_triangle(p(lo[0], lo[1]), p(hi[0], lo[1]), p(hi[0], hi[1]));
        self.add_triangle(p(lo[0], lo[1]), p(hi[0], hi[1]), p(lo[0], hi[1]));
    }
}

/// Random small triangles, spheres and cones in the cube [-s, s]^3.
pub fn random_scene(
    rng: &mut Rng,
    tris: usize,
    spheres: usize,
    cones: usize,
    s: f32,
) -> OwnedScene {
    let mut o = OwnedScene::default();
    let size = s * 0.08;
    for _ in 0..tris {
        let c = rng.vec(-s, s);
        o.add_triangle(
            c + rng.vec(-size, size),
            c + rng.vec(-size, size),
            c + rng.vec(-size, size),
        );
    }
    for _ in 0..spheres {
        o.spheres.push(Sphere {
            center: rng.vec(-s, s).into(),
            radius: rng.range(0.005, 0.05) * s,
        });
    }
    for _ in 0..cones {
        let b = rng.vec(-s, s);
        let a = b + rng.vec(-size, size);
        let r0 = rng.range(0.0, 0.03) * s;
        let r1 = if rng.f() < 0.3 {
            r0
        } else {
            rng.range(0.0, 0.03) * s
        };
        o.cones.push(Cone {
            base: b.into(),
            base_radius: r0,
            apex: a.into(),
            apex_radius: r1,
        });
    }
    o
}

/// Random rays: from outside towards the scene, from inside in any direction.
pub fn random_rays(rng: &mut Rng, n: usize, s: f32) -> Vec<Ray> {
    (0..n)
        .map(|i| {
            if i % 2 == 0 {
                let o = rng.unit() * (3.0 * s);
                let target = rng.vec(-s, s);
                Ray::new(o, target - o, 0.0, f32::INFINITY)
            } else {
                Ray::new(
                    rng.vec(-s, s),
                    rng.unit() * rng.range(0.1, 10.0),
                    0.0,
                    rng.range(0.1, 100.0) * s,
                )
            }
        })
        .collect()
}

/// Owned storage of a built tree and its scratch.
pub struct Built {
    pub nodes: Vec<KdNode>,
    pub leaves: Vec<KdLeaf>,
    pub ropes: Vec<KdRopes>,
    pub refs: Vec<u32>,
}

pub fn storage_for(req: &KdRequirements) -> (Built, Vec<KdEvent>, Vec<u8>) {
    (
        Built {
            nodes: vec![KdNode::default(); req.nodes],
            leaves: vec![KdLeaf::default(); req.leaves],
            ropes: vec![KdRopes::default(); req.ropes],
            refs: vec![0; req.refs],
        },
        vec![KdEvent::default(); req.events],
        vec![0; req.prim_flags],
    )
}

/// Builds with slices of exactly `req`'s lengths; panics on error.
pub fn build_with<'a>(
    scene: &Scene<'a>,
    params: &KdParams,
    req: &KdRequirements,
    b: &'a mut Built,
) -> KdTree<'a> {
    let (_, mut events, mut flags) = storage_for(req);
    let storage = KdStorage {
        nodes: &mut b.nodes,
        leaves: &mut b.leaves,
        ropes: &mut b.ropes,
        refs: &mut b.refs,
    };
    let tree = kd::build_sah(
        scene,
        params,
        storage,
        KdScratch {
            events: &mut events,
            prim_flags: &mut flags,
        },
    )
    .expect("build");
    tree.validate().expect("validate after build");
    tree
}

pub fn ideal_storage(scene: &Scene, params: &KdParams) -> (KdRequirements, Built) {
    let req = kd::requirements(scene.prim_count(), params);
    let (b, _, _) = storage_for(&req);
    (req, b)
}
