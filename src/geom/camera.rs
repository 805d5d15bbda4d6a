use super::Ray;
use glam::Vec3;

/// A pinhole camera as NFF's `v` block gives it: eye, look-at point, up
/// vector, field of view and resolution. Rays go through pixel centres;
/// row 0 is the top of the image.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub from: Vec3,
    /// Point looked at.
    pub at: Vec3,
    /// Up direction (need not be perpendicular to the view).
    pub up: Vec3,
    /// NFF's angle in degrees: from the centre of the top pixel row to the
    /// bottom one (and of the left column to the right one, for a square image).
    pub angle_deg: f32,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

impl Camera {
    /// The frame `(forward, right, up)` scaled so that pixel `(x, y)` maps to
    /// `forward + (2 (x + 0.5) / w - 1) * right + (1 - 2 (y + 0.5) / h) * up`.
    pub fn basis(&self) -> (Vec3, Vec3, Vec3) {
        let f = (self.at - self.from).normalize_or_zero();
        let r = f.cross(self.up).normalize_or_zero();
        let u = r.cross(f);
        let half = libm::tanf(self.angle_deg.to_radians() * 0.5);
        let aspect = self.width.max(1) as f32 / self.height.max(1) as f32;
        (f, r * (half * aspect), u * half)
    }

    /// The primary ray through the centre of pixel `(x, y)`, over `[0, inf)`.
    pub fn ray(&self, x: u32, y: u32) -> Ray {
        let (f, r, u) = self.basis();
        self.ray_in(f, r, u, x as f32 + 0.5, y as f32 + 0.5)
    }

    /// The ray through image point `(px, py)` (pixels, may be fractional)
    /// with a precomputed [`Camera::basis`].
    #[inline]
    pub fn ray_in(&self, f: Vec3, r: Vec3, u: Vec3, px: f32, py: f32) -> Ray {
        let sx = 2.0 * px / self.width.max(1) as f32 - 1.0;
        let sy = 1.0 - 2.0 * py / self.height.max(1) as f32;
        Ray::new(self.from, f + r * sx + u * sy, 0.0, f32::INFINITY)
    }
}
