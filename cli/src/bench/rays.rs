//! The ray sets every benchmark traces, the same for every method of a run:
//! primary rays (one per pixel centre, unit directions; in 4 x 2 pixel
//! blocks for packets), shadow rays (every primary hit towards every light),
//! incoherent rays (origins uniform in the scene's box, directions uniform
//! on the sphere, fixed seed) and one diffuse bounce (cosine-distributed
//! from every primary hit).

use coray::rng::SplitMix64;
use coray::{Hit, Ray, Vec3};
use coray_scenes::SceneMesh;

/// Which set.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum RaySet {
    /// One per pixel.
    Primary,
    /// Every primary hit towards every light.
    Shadow,
    /// Origins and directions uniform.
    Incoherent,
    /// One cosine-distributed bounce from every primary hit.
    Diffuse,
}

impl RaySet {
    /// Its name.
    pub fn name(self) -> &'static str {
        match self {
            RaySet::Primary => "primary",
            RaySet::Shadow => "shadow",
            RaySet::Incoherent => "incoherent",
            RaySet::Diffuse => "diffuse",
        }
    }

    /// Whether the set is traced for any hit (shadow rays) or the closest.
    pub fn any_hit(self) -> bool {
        self == RaySet::Shadow
    }
}

/// Rays of one set, and for shadow rays the light each goes to.
pub struct Rays {
    /// Which set.
    pub set: RaySet,
    /// The rays, in trace order.
    pub rays: Vec<Ray>,
    /// Shadow rays: the index of each ray's light.
    pub lights: Vec<usize>,
    /// Shadow and diffuse rays: the primary ray (pixel) each starts from.
    pub from: Vec<usize>,
}

/// Camera rays through every pixel centre, row by row, unit directions
/// (Embree's cones need them, see coray-embree).
pub fn primary(mesh: &SceneMesh) -> Vec<Ray> {
    let c = &mesh.camera;
    let (f, r, u) = c.basis();
    let mut rays = Vec::with_capacity(c.width as usize * c.height as usize);
    for y in 0..c.height {
        for x in 0..c.width {
            let ray = c.ray_in(f, r, u, x as f32 + 0.5, y as f32 + 0.5);
            rays.push(Ray::new(
                ray.origin,
                ray.dir.normalize(),
                0.0,
                f32::INFINITY,
            ));
        }
    }
    rays
}

/// The pixels in 4 x 2 blocks (blocks row by row, the block's pixels row
/// by row): the order packets of 8 take them in. `order[i]` is the pixel
/// of the i-th ray.
pub fn tile_order(width: u32, height: u32) -> Vec<usize> {
    let (w, h) = (width as usize, height as usize);
    let mut order = Vec::with_capacity(w * h);
    for by in (0..h).step_by(2) {
        for bx in (0..w).step_by(4) {
            for y in by..(by + 2).min(h) {
                for x in bx..(bx + 4).min(w) {
                    order.push(y * w + x);
                }
            }
        }
    }
    order
}

/// Shadow rays from every hit of `primary` to every light, each ending at
/// its light; `t_min` clears the surface by 1e-4 of the distance. Light
/// by light, the hits in `primary`'s order: consecutive rays from
/// neighbouring pixels towards one light, as a renderer batches them (and
/// packets take them).
pub fn shadow(mesh: &SceneMesh, primary: &[Ray], hits: &[Hit]) -> Rays {
    let (mut rays, mut lights, mut from) = (Vec::new(), Vec::new(), Vec::new());
    for (i, (l, _)) in mesh.lights.iter().enumerate() {
        for (px, (r, h)) in primary.iter().zip(hits).enumerate() {
            if !h.is_hit() {
                continue;
            }
            let p = r.origin + r.dir * h.t;
            let d = *l - p;
            let len = d.length();
            if len > 0.0 {
                rays.push(Ray::new(p, d / len, 1e-4 * len.max(1.0), len));
                lights.push(i);
                from.push(px);
            }
        }
    }
    Rays {
        set: RaySet::Shadow,
        rays,
        lights,
        from,
    }
}

/// The seed of the incoherent and diffuse sets.
pub const SEED: u64 = 2026;

fn unit(g: &mut SplitMix64) -> Vec3 {
    loop {
        let v = Vec3::new(
            g.next_f32() * 2.0 - 1.0,
            g.next_f32() * 2.0 - 1.0,
            g.next_f32() * 2.0 - 1.0,
        );
        let l = v.length_squared();
        if l > 1e-6 && l <= 1.0 {
            return v / l.sqrt();
        }
    }
}

/// `n` rays with origins uniform in the scene's box and directions uniform
/// on the sphere.
pub fn incoherent(mesh: &SceneMesh, n: usize) -> Rays {
    let b = mesh.scene().bounds();
    let mut g = SplitMix64(SEED);
    let rays = (0..n)
        .map(|_| {
            let o = Vec3::new(g.next_f32(), g.next_f32(), g.next_f32());
            Ray::new(
                b.min + (b.max - b.min) * o,
                unit(&mut g),
                0.0,
                f32::INFINITY,
            )
        })
        .collect();
    Rays {
        set: RaySet::Incoherent,
        rays,
        lights: Vec::new(),
        from: Vec::new(),
    }
}

/// One diffuse bounce: from every primary hit, a cosine-distributed
/// direction about the normal facing the ray.
pub fn diffuse(primary: &[Ray], hits: &[Hit]) -> Rays {
    let mut g = SplitMix64(SEED ^ 0xD1F);
    let (mut rays, mut from) = (Vec::new(), Vec::new());
    for (px, (r, h)) in primary.iter().zip(hits).enumerate() {
        if !h.is_hit() {
            continue;
        }
        let mut n = h.ng.normalize_or_zero();
        if n == Vec3::ZERO {
            continue;
        }
        if n.dot(r.dir) > 0.0 {
            n = -n;
        }
        // Cosine-weighted: the normal plus a uniform unit vector, normalised.
        let d = (n + unit(&mut g)).normalize_or_zero();
        if d == Vec3::ZERO {
            continue;
        }
        let p = r.origin + r.dir * h.t;
        let eps = 1e-4 * p.abs().max_element().max(1.0);
        rays.push(Ray::new(p, d, eps, f32::INFINITY));
        from.push(px);
    }
    Rays {
        set: RaySet::Diffuse,
        rays,
        lights: Vec::new(),
        from,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_cover_every_pixel_once() {
        for (w, h) in [(8, 4), (5, 3), (1, 1), (9, 7)] {
            let mut o = tile_order(w, h);
            assert_eq!(o[..(w.min(4) as usize)].len(), w.min(4) as usize);
            o.sort_unstable();
            assert_eq!(o, (0..(w * h) as usize).collect::<Vec<_>>(), "{w}x{h}");
        }
        assert_eq!(&tile_order(8, 2)[..8], &[0, 1, 2, 3, 8, 9, 10, 11]);
    }
}
