//! `coray render`: a Whitted ray tracer over any built method. Primary
//! rays, a shadow ray to every light, reflection (Ks) and refraction (T,
//! index of refraction) to a depth limit, NFF materials, `pp` normals
//! interpolated. Rows are shared among threads; the structure is immutable.
//! Shadow rays do not say which light they go to (projection methods then
//! choose a light plane as the thesis' uniform mode does).

use crate::shoot::Shooter;
use coray::{Hit, Ray, TraceStats, Vec3};
use coray_scenes::SceneMesh;
use std::sync::atomic::{AtomicUsize, Ordering};

/// What a render needs to trace rays.
pub struct Tracer<'a, S: Shooter> {
    /// The scene, for materials, normals and lights.
    pub mesh: &'a SceneMesh,
    /// What rays are shot through.
    pub shooter: &'a S,
    /// Reflection and refraction depth.
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
            if !(dist > 0.0 && dist.is_finite()) {
                // A light on the surface (or at infinity) lights nothing here.
                continue;
            }
            let l = to / dist;
            let ndl = n.dot(l);
            if ndl <= 0.0 {
                continue;
            }
            let shadow = Ray::new(p, l, eps, dist);
            if self.shooter.occluded(&shadow, None, ctx, st) {
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
    let pb = crate::bench::progress(t.mesh.camera.height as usize, progress);
    pb.set_message("rows");
    let cam = &t.mesh.camera;
    let (w, h) = (cam.width as usize, cam.height as usize);
    let (f, r, u) = cam.basis();
    let next = AtomicUsize::new(0);
    let mut image = vec![0u8; w * h * 3];
    let rows: Vec<std::sync::Mutex<&mut [u8]>> =
        image.chunks_mut(w * 3).map(std::sync::Mutex::new).collect();
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
                        pb.inc(1);
                    }
                    st
                })
            })
            .collect();
        for hd in handles {
            total.add(&hd.join().unwrap());
        }
    });
    pb.finish_and_clear();
    drop(rows);
    (image, total)
}

/// An image file format, chosen by the file's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    /// `.png`: 8-bit RGB.
    Png,
    /// `.ppm`: binary portable pixmap (P6).
    Ppm,
}

impl ImageFormat {
    /// The format of `path`, or an error naming the ones there are.
    pub fn for_path(path: &std::path::Path) -> Result<ImageFormat, String> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("png") => Ok(ImageFormat::Png),
            Some("ppm") => Ok(ImageFormat::Ppm),
            _ => Err(format!(
                "{}: the image format comes from the extension: .png or .ppm",
                path.display()
            )),
        }
    }
}

/// Writes RGB bytes (row 0 on top) in the format of `path`'s extension.
pub fn write_image(path: &std::path::Path, w: u32, h: u32, rgb: &[u8]) -> Result<(), String> {
    let err = |e: &dyn std::fmt::Display| format!("{}: {e}", path.display());
    let file = std::fs::File::create(path).map_err(|e| err(&e))?;
    let mut out = std::io::BufWriter::new(file);
    match ImageFormat::for_path(path)? {
        ImageFormat::Png => {
            let mut enc = png::Encoder::new(out, w, h);
            enc.set_color(png::ColorType::Rgb);
            enc.set_depth(png::BitDepth::Eight);
            let mut writer = enc.write_header().map_err(|e| err(&e))?;
            writer.write_image_data(rgb).map_err(|e| err(&e))
        }
        ImageFormat::Ppm => {
            use std::io::Write;
            write!(out, "P6\n{w} {h}\n255\n").map_err(|e| err(&e))?;
            out.write_all(rgb).map_err(|e| err(&e))?;
            out.flush().map_err(|e| err(&e))
        }
    }
}

/// A render of the scene's camera as a job for any built method:
/// (RGB bytes, rays traced, seconds).
pub struct Job<'a> {
    /// The scene.
    pub mesh: &'a SceneMesh,
    /// Reflection and refraction depth.
    pub depth: u32,
    /// Threads.
    pub threads: usize,
}

impl crate::built::Visit for Job<'_> {
    type Out = (Vec<u8>, u64, f64);
    fn visit<S: Shooter>(self, shooter: &S) -> Self::Out {
        let tracer = Tracer {
            mesh: self.mesh,
            shooter,
            max_depth: self.depth,
            secondary: Default::default(),
        };
        let t = std::time::Instant::now();
        let (rgb, st) = render(&tracer, self.threads, true);
        (rgb, st.rays, t.elapsed().as_secs_f64())
    }
}
