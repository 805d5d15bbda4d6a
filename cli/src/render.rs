//! `coray render`: a Whitted ray tracer over any coray structure. Primary
//! rays, a shadow ray to every light, reflection (Ks) and refraction (T,
//! index of refraction) to a depth limit, NFF materials, `pp` normals
//! interpolated. Rows are shared among threads; the structure is immutable.

use coray::bvh::{Bvh, BvhStackItem, BvhStats};
use coray::kd::{KdTree, Traversal};
use coray::{Aabb, Hit, Ray, TraceStats, Vec3};
use coray_scenes::SceneMesh;
use std::io::{IsTerminal, Write};
use std::sync::atomic::{AtomicUsize, Ordering};

/// A structure the renderer shoots rays through, with the per-thread state
/// its traversal needs. The structure (and traversal) is chosen once per
/// render: each kind gets its own monomorphised loop.
pub trait Shooter: Sync {
    /// Per-thread traversal state (a BVH's stack).
    type Ctx;
    fn ctx(&self) -> Self::Ctx;
    fn intersect(&self, ray: &Ray, ctx: &mut Self::Ctx, st: &mut TraceStats) -> Hit;
    fn occluded(&self, ray: &Ray, ctx: &mut Self::Ctx, st: &mut TraceStats) -> bool;
    fn bounds(&self) -> Aabb;
}

/// A kd-tree with a fixed traversal.
pub struct KdShooter<'a> {
    pub tree: &'a KdTree<'a>,
    pub method: Traversal,
}

impl Shooter for KdShooter<'_> {
    type Ctx = ();
    fn ctx(&self) {}
    fn intersect(&self, ray: &Ray, _: &mut (), st: &mut TraceStats) -> Hit {
        self.tree.intersect(ray, self.method, st)
    }
    fn occluded(&self, ray: &Ray, _: &mut (), st: &mut TraceStats) -> bool {
        self.tree.occluded(ray, self.method, st)
    }
    fn bounds(&self) -> Aabb {
        self.tree.info.bounds()
    }
}

/// A bounding volume hierarchy (any builder).
pub struct BvhShooter<'a> {
    pub bvh: Bvh<'a>,
}

impl Shooter for BvhShooter<'_> {
    type Ctx = (Vec<BvhStackItem>, BvhStats);
    fn ctx(&self) -> Self::Ctx {
        (
            vec![BvhStackItem::default(); self.bvh.stack_len()],
            BvhStats::default(),
        )
    }
    fn intersect(&self, ray: &Ray, ctx: &mut Self::Ctx, st: &mut TraceStats) -> Hit {
        ctx.1 = BvhStats::default();
        let h = self.bvh.intersect(ray, &mut ctx.0, &mut ctx.1);
        st.add(&ctx.1.trace);
        h
    }
    fn occluded(&self, ray: &Ray, ctx: &mut Self::Ctx, st: &mut TraceStats) -> bool {
        ctx.1 = BvhStats::default();
        let o = self.bvh.occluded(ray, &mut ctx.0, &mut ctx.1);
        st.add(&ctx.1.trace);
        o
    }
    fn bounds(&self) -> Aabb {
        let r = self.bvh.nodes[self.bvh.info.root as usize];
        r.bounds()
    }
}

/// Projection hierarchies: the camera's for primary rays, the lights'
/// planes for shadow rays (uniform mode: the renderer does not say which
/// light a ray is for), the global 3D hierarchy for the rest.
pub struct ProjShooter<'a> {
    pub rig: &'a crate::projbuild::ProjRig,
    pub scene: coray::Scene<'a>,
}

impl Shooter for ProjShooter<'_> {
    type Ctx = (Vec<BvhStackItem>, coray::proj::ProjStats);
    fn ctx(&self) -> Self::Ctx {
        (
            vec![BvhStackItem::default(); self.rig.stack_len(self.scene)],
            Default::default(),
        )
    }
    fn intersect(&self, ray: &Ray, ctx: &mut Self::Ctx, st: &mut TraceStats) -> Hit {
        ctx.1 = Default::default();
        let h = self.rig.intersect(self.scene, ray, &mut ctx.0, &mut ctx.1);
        st.add(&ctx.1.bvh.trace);
        h
    }
    fn occluded(&self, ray: &Ray, ctx: &mut Self::Ctx, st: &mut TraceStats) -> bool {
        ctx.1 = Default::default();
        let o = self
            .rig
            .occluded(self.scene, ray, None, &mut ctx.0, &mut ctx.1);
        st.add(&ctx.1.bvh.trace);
        o
    }
    fn bounds(&self) -> Aabb {
        let b = self.rig.global.bvh(self.scene);
        b.nodes[b.info.root as usize].bounds()
    }
}

/// What a render needs to trace rays.
pub struct Tracer<'a, S: Shooter> {
    pub mesh: &'a SceneMesh,
    pub shooter: &'a S,
    pub max_depth: u32,
    /// Reflection and refraction rays traced so far (all threads).
    pub secondary: std::sync::atomic::AtomicU64,
}

const EPS: f32 = 1e-4;

impl<S: Shooter> Tracer<'_, S> {
    fn scale(&self) -> f32 {
        let b = self.shooter.bounds();
        if b.is_empty() {
            1.0
        } else {
            (b.max - b.min).length().max(1e-6)
        }
    }

    /// Shading normal at a hit, facing against the ray.
    fn normal(&self, ray: &Ray, h: &Hit) -> Vec3 {
        let m = self.mesh;
        let mut n = h.ng.normalize_or_zero();
        if h.geom_id == coray::geom::GEOM_TRIANGLES {
            let t = m.triangles[h.prim_id as usize];
            if t.iter().all(|&i| m.has_normal[i as usize]) {
                let w = 1.0 - h.u - h.v;
                let v = |i: usize| Vec3::from(m.normals[t[i] as usize]);
                let s = (v(0) * w + v(1) * h.u + v(2) * h.v).normalize_or_zero();
                if s != Vec3::ZERO {
                    n = s;
                }
            }
        }
        if n.dot(ray.dir) > 0.0 {
            -n
        } else {
            n
        }
    }

    fn material(&self, h: &Hit) -> coray_scenes::nff::Material {
        let m = self.mesh;
        let base = match h.geom_id {
            0 => 0,
            1 => m.triangles.len(),
            _ => m.triangles.len() + m.spheres.len(),
        };
        m.materials[m.prim_material[base + h.prim_id as usize] as usize]
    }

    /// Colour seen along `ray`.
    pub fn trace(&self, ray: &Ray, depth: u32, ctx: &mut S::Ctx, st: &mut TraceStats) -> Vec3 {
        let h = self.shooter.intersect(ray, ctx, st);
        if !h.is_hit() {
            return self.mesh.background;
        }
        let m = self.material(&h);
        let p = ray.origin + ray.dir * h.t;
        let d = ray.dir.normalize();
        let geometric_in = h.ng.dot(ray.dir) < 0.0;
        let n = self.normal(ray, &h);
        let color = Vec3::from(m.color);
        let eps = EPS * self.scale();
        let light_scale = 1.0 / (self.mesh.lights.len().max(1) as f32).sqrt();
        let mut c = Vec3::ZERO;
        for (lp, lc) in &self.mesh.lights {
            let to = *lp - p;
            let dist = to.length();
            let l = to / dist;
            let ndl = n.dot(l);
            if ndl <= 0.0 {
                continue;
            }
            let shadow = Ray::new(p, l, eps, dist);
            if self.shooter.occluded(&shadow, ctx, st) {
                continue;
            }
            c += color * *lc * (m.kd * ndl * light_scale);
            if m.ks > 0.0 && m.shine > 0.0 {
                let r = l - n * (2.0 * ndl);
                let s = r.dot(d).max(0.0).powf(m.shine);
                c += *lc * (m.ks * s * light_scale);
            }
        }
        if depth < self.max_depth && (m.ks > 0.0 || m.t > 0.0) {
            let count = (m.ks > 0.0) as u64 + (m.t > 0.0) as u64;
            self.secondary.fetch_add(count, Ordering::Relaxed);
            if m.ks > 0.0 {
                let r = d - n * (2.0 * d.dot(n));
                c += self.trace(&Ray::new(p, r, eps, f32::INFINITY), depth + 1, ctx, st) * m.ks;
            }
            if m.t > 0.0 {
                // Entering when the ray meets the geometric front side.
                let eta = if geometric_in {
                    1.0 / m.ior.max(1e-3)
                } else {
                    m.ior
                };
                let cos_i = -d.dot(n);
                let k = 1.0 - eta * eta * (1.0 - cos_i * cos_i);
                let dir = if k < 0.0 {
                    d + n * (2.0 * cos_i)
                } else {
                    d * eta + n * (eta * cos_i - k.sqrt())
                };
                c += self.trace(&Ray::new(p, dir, eps, f32::INFINITY), depth + 1, ctx, st) * m.t;
            }
        }
        c
    }
}

/// Renders the camera's image with `threads` threads; RGB bytes, row 0 on top.
pub fn render<S: Shooter>(t: &Tracer<S>, threads: usize, progress: bool) -> (Vec<u8>, TraceStats) {
    let cam = &t.mesh.camera;
    let (w, h) = (cam.width as usize, cam.height as usize);
    let (f, r, u) = cam.basis();
    let next = AtomicUsize::new(0);
    let done = AtomicUsize::new(0);
    let mut image = vec![0u8; w * h * 3];
    let rows: Vec<std::sync::Mutex<&mut [u8]>> =
        image.chunks_mut(w * 3).map(std::sync::Mutex::new).collect();
    let show = progress && std::io::stderr().is_terminal();
    let mut total = TraceStats::default();
    std::thread::scope(|s| {
        let handles: Vec<_> = (0..threads.max(1))
            .map(|_| {
                s.spawn(|| {
                    let mut st = TraceStats::default();
                    let mut ctx = t.shooter.ctx();
                    loop {
                        let y = next.fetch_add(1, Ordering::Relaxed);
                        if y >= h {
                            break;
                        }
                        let mut row = rows[y].lock().unwrap();
                        for x in 0..w {
                            let ray = cam.ray_in(f, r, u, x as f32 + 0.5, y as f32 + 0.5);
                            let ray = Ray::new(
                                ray.origin,
                                ray.dir,
                                t.mesh.hither.max(0.0),
                                f32::INFINITY,
                            );
                            let c = t.trace(&ray, 0, &mut ctx, &mut st);
                            for (k, v) in c.to_array().iter().enumerate() {
                                row[3 * x + k] =
                                    (v.clamp(0.0, 1.0).powf(1.0 / 2.2) * 255.0 + 0.5) as u8;
                            }
                        }
                        let d = done.fetch_add(1, Ordering::Relaxed) + 1;
                        if show && (d.is_multiple_of(16) || d == h) {
                            eprint!("\rrendering {:3}%", d * 100 / h);
                            let _ = std::io::stderr().flush();
                        }
                    }
                    st
                })
            })
            .collect();
        for hd in handles {
            total.add(&hd.join().unwrap());
        }
    });
    if show {
        eprintln!();
    }
    drop(rows);
    (image, total)
}

/// Writes RGB bytes as an 8-bit PNG.
pub fn write_png(path: &std::path::Path, w: u32, h: u32, rgb: &[u8]) -> Result<(), String> {
    let file = std::fs::File::create(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), w, h);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut writer = enc.write_header().map_err(|e| e.to_string())?;
    writer.write_image_data(rgb).map_err(|e| e.to_string())
}
