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

    /// Why this camera cannot make rays, or `None` when it can: sides of 1
    /// to [`crate::limits::MAX_IMAGE_SIDE`] pixels, an angle in (0, 180)
    /// degrees, finite vectors, an eye apart from the point looked at, and
    /// an up vector not along the view.
    pub fn fault(&self) -> Option<&'static str> {
        let side = 1..=crate::limits::MAX_IMAGE_SIDE;
        let view = self.at - self.from;
        if !side.contains(&self.width) || !side.contains(&self.height) {
            Some("its width and height must be 1 to 32768 pixels")
        } else if !(self.angle_deg > 0.0 && self.angle_deg < 180.0) {
            Some("its angle must be between 0 and 180 degrees")
        } else if !(self.from.is_finite() && self.at.is_finite() && self.up.is_finite()) {
            Some("its from, at and up must be finite")
        } else if view.length_squared() == 0.0 || !view.length_squared().is_finite() {
            Some("its eye (from) is the point it looks at (at)")
        } else if view.cross(self.up).length_squared() == 0.0 {
            Some("its up vector is zero or along the view")
        } else {
            None
        }
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

#[cfg(test)]
mod tests {
    use super::*;

    fn cam() -> Camera {
        Camera {
            from: Vec3::new(0.0, 0.0, 5.0),
            at: Vec3::ZERO,
            up: Vec3::Y,
            angle_deg: 45.0,
            width: 4,
            height: 4,
        }
    }

    /// Each way a camera can be degenerate is named; a good one passes.
    #[test]
    fn faults_are_found() {
        assert_eq!(cam().fault(), None);
        let bad = [
            Camera { width: 0, ..cam() },
            Camera {
                height: crate::limits::MAX_IMAGE_SIDE + 1,
                ..cam()
            },
            Camera {
                angle_deg: 180.0,
                ..cam()
            },
            Camera {
                angle_deg: f32::NAN,
                ..cam()
            },
            Camera {
                at: cam().from,
                ..cam()
            },
            Camera {
                up: Vec3::Z,
                ..cam()
            },
            Camera {
                up: Vec3::ZERO,
                ..cam()
            },
            Camera {
                from: Vec3::new(f32::INFINITY, 0.0, 0.0),
                ..cam()
            },
        ];
        for c in bad {
            assert!(c.fault().is_some(), "{c:?}");
        }
    }

    /// The frame of a valid camera is orthogonal, with the pixel centres
    /// symmetric about the view.
    #[test]
    fn basis_is_orthogonal() {
        let (f, r, u) = cam().basis();
        assert!(f.dot(r).abs() < 1e-6 && f.dot(u).abs() < 1e-6 && r.dot(u).abs() < 1e-6);
        let (a, b) = (cam().ray(0, 0), cam().ray(3, 3));
        assert!((a.dir + b.dir - 2.0 * f).length() < 1e-5);
    }
}
