//! Scene and ray generators, and owned storage for building in tests.
#![allow(dead_code)]

use coray::kd::{self, KdParams, KdRequirements, KdStackItem, KdTree, KD_STACK_LEN};
use coray::owned::OwnedKd;
use coray::{Cone, Ray, Scene, Sphere, Vec3};

/// A fresh kd traversal stack.
pub fn kst() -> Vec<KdStackItem> {
    coray::owned::stack(KD_STACK_LEN)
}

/// The project's one generator (SplitMix64), with test conveniences.
pub struct Rng(pub u64);

impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        let mut g = coray::rng::SplitMix64(self.0);
        let v = g.next_u64();
        self.0 = g.0;
        v
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

/// Room for a tree (and its scratch) of exactly `req`'s counts.
pub fn storage_for(req: &KdRequirements) -> (OwnedKd, (), ()) {
    (OwnedKd::with_room(req), (), ())
}

/// Builds into `b` (room of `req`'s counts); panics on error; validates.
pub fn build_with<'a>(
    scene: &Scene<'a>,
    params: &KdParams,
    _req: &KdRequirements,
    b: &'a mut OwnedKd,
) -> KdTree<'a> {
    b.build(scene, params).expect("build");
    let tree = b.tree(*scene).expect("tree");
    tree.validate().expect("validate after build");
    tree
}

pub fn ideal_storage(scene: &Scene, params: &KdParams) -> (KdRequirements, OwnedKd) {
    let req = kd::requirements(scene.prim_count(), params);
    (req, OwnedKd::with_room(&req))
}

/// The global index (triangles, then spheres, then cones) of a hit's
/// primitive, `u32::MAX` for a miss.
pub fn global_prim(s: &Scene, h: &coray::Hit) -> u32 {
    match h.geom_id {
        0 => h.prim_id,
        1 => s.triangles.len() as u32 + h.prim_id,
        2 => (s.triangles.len() + s.spheres.len()) as u32 + h.prim_id,
        _ => u32::MAX,
    }
}

/// A unit cube of quads (two triangles a face) with a smaller cube of
/// quads inside it, and rays started on the faces and edges of their boxes
/// (coordinates -1, -0.5, 0.5, 1, and 0.25 within faces) whose directions
/// have one or two components of subnormal size (their inverses overflow
/// to infinity) beside normal ones.
pub fn faces_and_tiny_directions() -> (OwnedScene, Vec<Ray>) {
    let mut o = OwnedScene::default();
    for (lo, hi) in [(-1.0f32, 1.0f32), (-0.5, 0.5)] {
        for axis in 0..3 {
            for pos in [lo, hi] {
                o.add_quad(axis, pos, [lo, lo], [hi, hi]);
            }
        }
    }
    let coords = [-1.0f32, -0.5, 0.25, 0.5, 1.0];
    let tiny = [1e-40f32, -1e-40, 3e-39, -2e-45];
    let mut rays = Vec::new();
    for (i, &x) in coords.iter().enumerate() {
        for (j, &y) in coords.iter().enumerate() {
            let z = coords[(i + 2 * j) % coords.len()];
            for (k, &t) in tiny.iter().enumerate() {
                for axis in 0..3 {
                    let mut d = [0.3f32 + 0.1 * k as f32, -0.7, 0.6 - 0.2 * j as f32];
                    d[axis] = t;
                    if k % 2 == 1 {
                        d[(axis + 1) % 3] = -t;
                    }
                    rays.push(Ray::new(
                        Vec3::new(x, y, z),
                        Vec3::from_array(d),
                        0.0,
                        f32::INFINITY,
                    ));
                }
            }
        }
    }
    (o, rays)
}

/// Small triangles with a vertex on each of a 4 x 4 x 4 lattice's points,
/// reaching into a third of the octants around it, and rays from the
/// cells' centres along diagonals that pass exactly through lattice
/// points, edges and faces (every point and parameter exact in `f32`):
/// SAH splits fall on the lattice's planes, so these rays leave cells
/// through edges and corners, where a triangle touching the point from a
/// diagonal cell is hit at the corner's `t` and nowhere else.
pub fn lattice_corners() -> (OwnedScene, Vec<Ray>) {
    let mut rng = Rng(5);
    let mut o = OwnedScene::default();
    let points = (0..64).map(|i| Vec3::new((i % 4) as f32, (i / 4 % 4) as f32, (i / 16) as f32));
    for c in points.clone() {
        for octant in 0..8 {
            if rng.below(3) != 0 {
                continue;
            }
            let s = Vec3::new(
                if octant & 1 == 0 { 1.0 } else { -1.0 },
                if octant & 2 == 0 { 1.0 } else { -1.0 },
                if octant & 4 == 0 { 1.0 } else { -1.0 },
            );
            o.add_triangle(
                c,
                c + s * Vec3::new(0.375, 0.25, 0.125),
                c + s * Vec3::new(0.125, 0.375, 0.25),
            );
        }
    }
    let dirs = [
        [1.0f32, 1.0, 1.0],
        [1.0, 1.0, 0.25],
        [1.0, -1.0, 0.0],
        [-1.0, 1.0, 1.0],
        [0.5, 1.0, -1.0],
        [1.0, 0.0, 0.0],
    ];
    let mut rays = Vec::new();
    for c in points {
        for d in dirs {
            rays.push(Ray::new(
                c + Vec3::splat(0.5),
                Vec3::from_array(d),
                0.0,
                f32::INFINITY,
            ));
        }
    }
    (o, rays)
}

/// The nodes of a tree without ropes with its elided empty leaves put
/// back, laid out as a build with ropes lays them out: children pairs in
/// the preorder of their parents, an empty leaf's first reference where
/// the references stand at it.
pub fn with_empty_leaves(nodes: &[coray::kd::KdNode]) -> Vec<coray::kd::KdNode> {
    let mut out = vec![coray::kd::KdNode::default()];
    let mut next_ref = 0;
    // (node of `nodes`, or None for an elided leaf; its slot in `out`)
    let mut stack = vec![(Some(0usize), 0usize)];
    while let Some((node, slot)) = stack.pop() {
        let Some(i) = node else {
            out[slot] = coray::kd::KdNode::leaf(next_ref, 0);
            continue;
        };
        let n = nodes[i];
        if n.is_leaf() {
            next_ref = n.first_ref() + n.ref_count();
            out[slot] = n;
            continue;
        }
        let c = out.len();
        out.extend([coray::kd::KdNode::default(); 2]);
        out[slot] = coray::kd::KdNode::interior(n.axis(), n.split(), c as u32);
        let (l, r) = n.children();
        let stored = |x: u32| (x != coray::kd::SHARED_EMPTY).then_some(x as usize);
        stack.push((stored(r), c + 1));
        stack.push((stored(l), c));
    }
    out
}

/// Runs `f` on a thread of its own and fails when it has not returned
/// within `secs` seconds (a hang, or a build gone superlinear) or when it
/// panicked.
pub fn watchdog(secs: u64, what: &str, f: impl FnOnce() + Send + 'static) {
    use std::sync::mpsc;
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        f();
        let _ = tx.send(());
    });
    match rx.recv_timeout(std::time::Duration::from_secs(secs)) {
        Ok(()) => {}
        Err(mpsc::RecvTimeoutError::Timeout) => panic!("{what}: no answer within {secs} s"),
        Err(mpsc::RecvTimeoutError::Disconnected) => panic!("{what}: panicked"),
    }
}
