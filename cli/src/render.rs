//! `coray render`: a Whitted ray tracer over any built method. Eye rays, a
//! shadow ray to every light, reflection (Ks) and refraction (T, index of
//! refraction) to a depth limit, NFF materials, `pp` normals interpolated.
//! Two sets of [`Rules`]: coray's own ([`Rules::WHITTED`], pixel-centre
//! rays) and the SPD testing procedure's ([`Rules::SPD`], used by
//! `render --spd`, see [`crate::spd`]). Rows are shared among threads; the
//! structure is immutable. Every ray is counted in [`RayCounts`].

use crate::shoot::Shooter;
use coray::{Camera, Hit, Ray, TraceStats, Vec3};
use coray_scenes::SceneMesh;
use std::sync::atomic::{AtomicUsize, Ordering};

/// What a render does where renderers differ. Plain data, chosen once per
/// render.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Rules {
    /// Reflection rays from transmitting surfaces too, not only from
    /// specular (Ks > 0) ones.
    pub reflect_from_transmitters: bool,
    /// Opaque primitives without vertex normals are one-sided: the light
    /// test uses their front normal (counter-clockwise vertex order, a
    /// sphere's or cone's outward one), whichever side the ray hit. Off,
    /// and always for `pp` patches and transmitters: the normal faces the ray.
    pub one_sided: bool,
    /// Total internal reflection turns the refraction ray into a mirror
    /// ray (true) or casts none (false: the reflection ray already covers it).
    pub tir_casts_mirror_ray: bool,
    /// Shadow rays name the light they go to (projection methods then use
    /// that light's plane); off, they do not, and projection methods choose
    /// a plane as the thesis' uniform mode does.
    pub name_lights: bool,
    /// Eye rays start at the scene's hither distance (true) or at the eye
    /// (the SPD procedure has no hither; LCTS casts start at the eye too).
    pub eye_from_hither: bool,
}

impl Rules {
    /// coray's own conventions (the default render).
    pub const WHITTED: Rules = Rules {
        reflect_from_transmitters: false,
        one_sided: false,
        tir_casts_mirror_ray: true,
        name_lights: false,
        eye_from_hither: true,
    };
    /// The SPD testing procedure's (README, "The SPD testing procedure").
    pub const SPD: Rules = Rules {
        reflect_from_transmitters: true,
        one_sided: true,
        tir_casts_mirror_ray: false,
        name_lights: true,
        eye_from_hither: false,
    };
}

/// Rays a render traced, by kind, as the SPD's statistics count them.
/// They depend on the scene, the rules and the eye rays only, never on the
/// structure or the thread count.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct RayCounts {
    /// Eye (primary) rays.
    pub eye_rays: u64,
    /// Eye rays that hit an object.
    pub eye_hits: u64,
    /// Reflection rays.
    pub reflect_rays: u64,
    /// Refraction rays.
    pub refract_rays: u64,
    /// Shadow rays.
    pub shadow_rays: u64,
    /// Shadow rays that met an object before the light.
    pub shadow_hits: u64,
    /// Reflection and refraction rays that hit an object.
    pub secondary_hits: u64,
}

impl RayCounts {
    /// Adds another thread's counts.
    pub fn add(&mut self, o: &RayCounts) {
        self.eye_rays += o.eye_rays;
        self.eye_hits += o.eye_hits;
        self.reflect_rays += o.reflect_rays;
        self.refract_rays += o.refract_rays;
        self.shadow_rays += o.shadow_rays;
        self.shadow_hits += o.shadow_hits;
        self.secondary_hits += o.secondary_hits;
    }

    /// Reflection plus refraction rays.
    pub fn secondary_rays(&self) -> u64 {
        self.reflect_rays + self.refract_rays
    }

    /// Every ray: eye, reflection, refraction and shadow.
    pub fn all_rays(&self) -> u64 {
        self.eye_rays + self.secondary_rays() + self.shadow_rays
    }

    /// Rays whose query had to find an intersection (GOLEM's
    /// IntersRequired as we read it): eye and secondary rays that hit,
    /// and shadow rays that met an object.
    pub fn intersections_required(&self) -> u64 {
        self.eye_hits + self.secondary_hits + self.shadow_hits
    }
}

/// What a render needs to trace rays.
pub struct Tracer<'a, S: Shooter> {
    /// The scene, for materials, normals and lights.
    pub mesh: &'a SceneMesh,
    /// What rays are shot through.
    pub shooter: &'a S,
    /// Reflection and refraction depth: rays spawn from hits of depth
    /// below it (the eye ray's depth is 0).
    pub max_depth: u32,
    /// The conventions.
    pub rules: Rules,
}

/// Per-thread state of a render: the traversal's context and the counts.
pub struct TraceCtx<C> {
    /// The shooter's per-thread state.
    pub shooter: C,
    /// Traversal statistics of every ray.
    pub stats: TraceStats,
    /// Rays by kind.
    pub counts: RayCounts,
}

impl<S: Shooter> Tracer<'_, S> {
    /// Fresh per-thread state.
    pub fn ctx(&self) -> TraceCtx<S::Ctx> {
        TraceCtx {
            shooter: self.shooter.ctx(),
            stats: TraceStats::default(),
            counts: RayCounts::default(),
        }
    }

    fn scale(&self) -> f32 {
        let b = self.shooter.bounds();
        if b.is_empty() {
            1.0
        } else {
            (b.max - b.min).length().max(1e-6)
        }
    }

    /// Shading normal at a hit (unit, or zero when degenerate) and whether
    /// it came from `pp` vertex normals; oriented as the primitive's
    /// front: counter-clockwise triangles, outward spheres and cones.
    fn front_normal(&self, h: &Hit) -> (Vec3, bool) {
        let m = self.mesh;
        // coray's (and Embree's) triangle ng is (a - b) x (c - a): the
        // clockwise side. Fronts here are counter-clockwise, as in NFF.
        let ng = if h.geom_id == coray::geom::GEOM_TRIANGLES {
            -h.ng
        } else {
            h.ng
        };
        let n = ng.normalize_or_zero();
        if h.geom_id == coray::geom::GEOM_TRIANGLES {
            let t = m.triangles[h.prim_id as usize];
            if t.iter().all(|&i| m.has_normal[i as usize]) {
                let w = 1.0 - h.u - h.v;
                let v = |i: usize| Vec3::from(m.normals[t[i] as usize]);
                let s = (v(0) * w + v(1) * h.u + v(2) * h.v).normalize_or_zero();
                if s != Vec3::ZERO {
                    return (s, true);
                }
            }
        }
        (n, false)
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

    /// Colour seen along `ray` (of `depth`: 0 for eye rays), counting it.
    pub fn trace(&self, ray: &Ray, depth: u32, ctx: &mut TraceCtx<S::Ctx>) -> Vec3 {
        let h = self
            .shooter
            .intersect(ray, &mut ctx.shooter, &mut ctx.stats);
        self.shade(ray, &h, depth, ctx)
    }

    /// Colour of hit `h` of `ray` (found by any means, e.g. an LCTS cast),
    /// counting the ray and tracing the rays it spawns.
    pub fn shade(&self, ray: &Ray, h: &Hit, depth: u32, ctx: &mut TraceCtx<S::Ctx>) -> Vec3 {
        let counts = &mut ctx.counts;
        if depth == 0 {
            counts.eye_rays += 1;
            counts.eye_hits += h.is_hit() as u64;
        } else {
            counts.secondary_hits += h.is_hit() as u64;
        }
        if !h.is_hit() {
            return self.mesh.background;
        }
        let m = self.material(h);
        let p = ray.origin + ray.dir * h.t;
        let d = ray.dir.normalize();
        let geometric_in = h.ng.dot(ray.dir) < 0.0;
        let (front, patch) = self.front_normal(h);
        // The normal facing the ray: shading, reflection and refraction.
        let n = if front.dot(ray.dir) > 0.0 {
            -front
        } else {
            front
        };
        let one_sided = self.rules.one_sided && !patch && m.t <= 0.0;
        let light_n = if one_sided { front } else { n };
        let color = Vec3::from(m.color);
        let eps = coray::tolerance::SECONDARY_RAY_OFFSET * self.scale();
        let light_scale = 1.0 / (self.mesh.lights.len().max(1) as f32).sqrt();
        let mut c = Vec3::ZERO;
        for (li, (lp, lc)) in self.mesh.lights.iter().enumerate() {
            let to = *lp - p;
            let dist = to.length();
            if !(dist > 0.0 && dist.is_finite()) {
                // A light on the surface (or at infinity) lights nothing here.
                continue;
            }
            let l = to / dist;
            if light_n.dot(l) <= 0.0 {
                continue;
            }
            let shadow = Ray::new(p, l, eps, dist);
            ctx.counts.shadow_rays += 1;
            let light = self.rules.name_lights.then_some(li);
            if self
                .shooter
                .occluded(&shadow, light, &mut ctx.shooter, &mut ctx.stats)
            {
                ctx.counts.shadow_hits += 1;
                continue;
            }
            let ndl = n.dot(l).max(0.0);
            c += color * *lc * (m.kd * ndl * light_scale);
            if m.ks > 0.0 && m.shine > 0.0 {
                let r = l - n * (2.0 * ndl);
                let s = r.dot(d).max(0.0).powf(m.shine);
                c += *lc * (m.ks * s * light_scale);
            }
        }
        if depth >= self.max_depth {
            return c;
        }
        let reflect = m.ks > 0.0 || (self.rules.reflect_from_transmitters && m.t > 0.0);
        if reflect {
            ctx.counts.reflect_rays += 1;
            let r = d - n * (2.0 * d.dot(n));
            let weight = if m.ks > 0.0 { m.ks } else { 1.0 - m.t };
            c += self.trace(&Ray::new(p, r, eps, f32::INFINITY), depth + 1, ctx) * weight;
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
            let dir = if k >= 0.0 {
                Some(d * eta + n * (eta * cos_i - k.sqrt()))
            } else if self.rules.tir_casts_mirror_ray {
                Some(d + n * (2.0 * cos_i))
            } else {
                None
            };
            if let Some(dir) = dir {
                ctx.counts.refract_rays += 1;
                c += self.trace(&Ray::new(p, dir, eps, f32::INFINITY), depth + 1, ctx) * m.t;
            }
        }
        c
    }
}

/// Linear colours of a camera's pixel centres, row 0 on top, traced with
/// `threads` threads; with the threads' statistics and counts summed. A
/// message when the image's memory cannot be had.
pub fn render_colors<S: Shooter>(
    t: &Tracer<S>,
    cam: &Camera,
    threads: usize,
    progress: bool,
) -> Result<(Vec<Vec3>, TraceStats, RayCounts), String> {
    let pb = crate::bench::progress(cam.height as usize, progress);
    pb.set_message("rows");
    let (w, h) = (cam.width as usize, cam.height as usize);
    let basis = cam.basis();
    let t_min = eye_t_min(t.mesh, t.rules);
    let next = AtomicUsize::new(0);
    let mut image = crate::budget::try_vec(&format!("a {w}x{h} image"), w * h, Vec3::ZERO)?;
    let rows: Vec<std::sync::Mutex<&mut [Vec3]>> =
        image.chunks_mut(w).map(std::sync::Mutex::new).collect();
    let (mut stats, mut counts) = (TraceStats::default(), RayCounts::default());
    std::thread::scope(|s| {
        let handles: Vec<_> = (0..threads.max(1))
            .map(|_| {
                s.spawn(|| {
                    let mut ctx = t.ctx();
                    loop {
                        let y = next.fetch_add(1, Ordering::Relaxed);
                        if y >= h {
                            break;
                        }
                        let mut row = rows[y].lock().unwrap();
                        for (x, px) in row.iter_mut().enumerate() {
                            let ray = eye_ray(cam, basis, x as u32, y as u32, t_min);
                            *px = t.trace(&ray, 0, &mut ctx);
                        }
                        pb.inc(1);
                    }
                    (ctx.stats, ctx.counts)
                })
            })
            .collect();
        for hd in handles {
            let (st, c) = hd.join().unwrap();
            stats.add(&st);
            counts.add(&c);
        }
    });
    pb.finish_and_clear();
    drop(rows);
    Ok((image, stats, counts))
}

/// Where `rules` start eye rays: the scene's hither distance or the eye.
pub fn eye_t_min(mesh: &SceneMesh, rules: Rules) -> f32 {
    if rules.eye_from_hither {
        mesh.hither.max(0.0)
    } else {
        0.0
    }
}

/// The eye ray through the centre of pixel `(x, y)`, from `t_min` on.
pub fn eye_ray(cam: &Camera, basis: (Vec3, Vec3, Vec3), x: u32, y: u32, t_min: f32) -> Ray {
    let (f, r, u) = basis;
    let ray = cam.ray_in(f, r, u, x as f32 + 0.5, y as f32 + 0.5);
    Ray::new(ray.origin, ray.dir, t_min, f32::INFINITY)
}

/// 8-bit sRGB-ish bytes (gamma 2.2) of a linear colour.
pub fn to_rgb8(c: Vec3) -> [u8; 3] {
    c.to_array()
        .map(|v| (v.clamp(0.0, 1.0).powf(1.0 / 2.2) * 255.0 + 0.5) as u8)
}

/// Renders the scene's camera with `threads` threads: RGB bytes (row 0 on
/// top), statistics and counts; a message when the memory cannot be had.
pub fn render<S: Shooter>(
    t: &Tracer<S>,
    threads: usize,
    progress: bool,
) -> Result<(Vec<u8>, TraceStats, RayCounts), String> {
    let (colors, st, counts) = render_colors(t, &t.mesh.camera, threads, progress)?;
    let mut rgb = crate::budget::try_vec("an RGB image", colors.len() * 3, 0u8)?;
    for (px, c) in rgb.chunks_exact_mut(3).zip(colors) {
        px.copy_from_slice(&to_rgb8(c));
    }
    Ok((rgb, st, counts))
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
    type Out = Result<(Vec<u8>, u64, f64), String>;
    fn visit<S: Shooter>(self, shooter: &S) -> Self::Out {
        let tracer = Tracer {
            mesh: self.mesh,
            shooter,
            max_depth: self.depth,
            rules: Rules::WHITTED,
        };
        let t = std::time::Instant::now();
        let (rgb, st, _) = render(&tracer, self.threads, true)?;
        Ok((rgb, st.rays, t.elapsed().as_secs_f64()))
    }
}
