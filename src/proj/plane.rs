//! Projection planes: the camera's image plane, the faces of a point
//! light's cube, a directional light's orthographic plane. Each maps a 3D
//! box to a conservative 2D view-aligned box ([`Rect`]) and a ray to the
//! 2D point where it crosses the plane, so that a ray can hit a box only
//! when its point lies in the box's rectangle.

use crate::geom::Aabb;
use crate::tolerance::PROJECTED_RECT_PAD;
use crate::Vec3;

/// Coordinates this large stand for "unbounded": a box that reaches behind
/// the plane's eye projects onto the whole plane. Finite, so that builders'
/// areas stay finite (`(2e18)^2` fits an `f32`).
pub const UNBOUNDED: f32 = 1.0e18;

/// A 2D view-aligned box on a projection plane, and the nearest depth of
/// what it bounds (for ordering and pruning closest-hit traversal).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct Rect {
    /// Lower corner (plane coordinates).
    pub min: [f32; 2],
    /// Upper corner.
    pub max: [f32; 2],
    /// Smallest depth along the plane's forward axis of the 3D box it
    /// comes from (0 when the box reaches the eye plane).
    pub near: f32,
}

impl Rect {
    /// Contains nothing.
    pub const EMPTY: Rect = Rect {
        min: [f32::INFINITY; 2],
        max: [f32::NEG_INFINITY; 2],
        near: f32::INFINITY,
    };
    /// The whole plane.
    pub const ALL: Rect = Rect {
        min: [-UNBOUNDED; 2],
        max: [UNBOUNDED; 2],
        near: 0.0,
    };

    /// True when it contains nothing.
    pub fn is_empty(&self) -> bool {
        !(self.min[0] <= self.max[0] && self.min[1] <= self.max[1])
    }

    /// The smallest rectangle holding both.
    pub fn union(&self, o: &Rect) -> Rect {
        Rect {
            min: [self.min[0].min(o.min[0]), self.min[1].min(o.min[1])],
            max: [self.max[0].max(o.max[0]), self.max[1].max(o.max[1])],
            near: self.near.min(o.near),
        }
    }

    /// The thesis' point-in-rectangle test: 4 comparisons.
    #[inline]
    pub fn contains(&self, p: [f32; 2]) -> bool {
        p[0] >= self.min[0] && p[0] <= self.max[0] && p[1] >= self.min[1] && p[1] <= self.max[1]
    }

    /// As a flat 3D box (z = 0), for the hierarchy builders: its surface
    /// area is twice the rectangle's area.
    pub fn as_flat_box(&self) -> Aabb {
        if self.is_empty() {
            return Aabb::EMPTY;
        }
        Aabb {
            min: Vec3::new(self.min[0], self.min[1], 0.0),
            max: Vec3::new(self.max[0], self.max[1], 0.0),
        }
    }
}

/// A plane rays are projected onto.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ProjPlane {
    /// Central projection from `eye`: a point `P` maps to
    /// `((P - eye) . right, (P - eye) . up) / ((P - eye) . forward)`.
    /// The camera's image plane and a point light's cube faces.
    Perspective {
        /// Centre of projection.
        eye: Vec3,
        /// First plane axis.
        right: Vec3,
        /// Second plane axis.
        up: Vec3,
        /// Viewing direction; depth is measured along it.
        forward: Vec3,
    },
    /// Parallel projection along `forward`: `P` maps to
    /// `(P . right, P . up)`. A directional light's plane.
    Orthographic {
        /// First plane axis.
        right: Vec3,
        /// Second plane axis.
        up: Vec3,
        /// Direction of projection.
        forward: Vec3,
    },
}

impl ProjPlane {
    /// The camera's image plane (unit axes of its basis).
    pub fn camera(cam: &crate::Camera) -> ProjPlane {
        let (f, r, u) = cam.basis();
        ProjPlane::Perspective {
            eye: cam.from,
            right: r.normalize_or_zero(),
            up: u.normalize_or_zero(),
            forward: f,
        }
    }

    /// A plane whose eye is the origin of rays `dir`-wards: the 2D point of
    /// the ray from the eye through direction `v` (for the camera: a primary
    /// ray's direction; for a light: `P - light` for a shadow ray from `P`).
    /// `None` when `v` does not point into the plane's half-space or
    /// projects too far out to be told from "unbounded".
    #[inline]
    pub fn point_of_direction(&self, v: Vec3) -> Option<[f32; 2]> {
        let (right, up, forward) = self.axes();
        let d = v.dot(forward);
        if !(d > 0.0) {
            return None;
        }
        let p = [v.dot(right) / d, v.dot(up) / d];
        let lim = 0.25 * UNBOUNDED;
        (p[0].abs() < lim && p[1].abs() < lim).then_some(p)
    }

    /// For an orthographic plane: the 2D point of a ray along `forward`
    /// (or against it) through `origin`.
    #[inline]
    pub fn point_of_position(&self, origin: Vec3) -> [f32; 2] {
        let (right, up, _) = self.axes();
        [origin.dot(right), origin.dot(up)]
    }

    /// (right, up, forward).
    #[inline]
    pub fn axes(&self) -> (Vec3, Vec3, Vec3) {
        match *self {
            ProjPlane::Perspective {
                right, up, forward, ..
            }
            | ProjPlane::Orthographic { right, up, forward } => (right, up, forward),
        }
    }

    /// The conservative rectangle of `b` (its 8 corners projected, extremes
    /// taken, padded for rounding). Perspective: a box entirely behind the
    /// eye plane is empty; one that reaches it covers the whole plane.
    pub fn project_box(&self, b: &Aabb) -> Rect {
        if b.is_empty() {
            return Rect::EMPTY;
        }
        let (right, up, forward) = self.axes();
        let mut r = Rect::EMPTY;
        let (mut behind, mut ahead) = (false, false);
        for k in 0..8 {
            let c = Vec3::new(
                if k & 1 == 0 { b.min.x } else { b.max.x },
                if k & 2 == 0 { b.min.y } else { b.max.y },
                if k & 4 == 0 { b.min.z } else { b.max.z },
            );
            let (p, depth) = match *self {
                ProjPlane::Perspective { eye, .. } => {
                    let v = c - eye;
                    let d = v.dot(forward);
                    if !(d > 0.0) {
                        behind = true;
                        continue;
                    }
                    ahead = true;
                    ([v.dot(right) / d, v.dot(up) / d], d)
                }
                ProjPlane::Orthographic { .. } => {
                    ahead = true;
                    ([c.dot(right), c.dot(up)], c.dot(forward))
                }
            };
            r.min = [r.min[0].min(p[0]), r.min[1].min(p[1])];
            r.max = [r.max[0].max(p[0]), r.max[1].max(p[1])];
            r.near = r.near.min(depth);
        }
        if behind {
            return if ahead { Rect::ALL } else { Rect::EMPTY };
        }
        let pad =
            |lo: f32, hi: f32| PROJECTED_RECT_PAD * (lo.abs().max(hi.abs()) + (hi - lo) + 1.0e-3);
        let (px, py) = (pad(r.min[0], r.max[0]), pad(r.min[1], r.max[1]));
        let out = Rect {
            min: [r.min[0] - px, r.min[1] - py],
            max: [r.max[0] + px, r.max[1] + py],
            near: r.near * (1.0 - PROJECTED_RECT_PAD),
        };
        let big = 0.25 * UNBOUNDED;
        if !(out.min[0] > -big && out.max[0] < big && out.min[1] > -big && out.max[1] < big) {
            return Rect {
                near: out.near,
                ..Rect::ALL
            };
        }
        out
    }
}

/// The six faces of a cube around `eye`: forward along +x, -x, +y, -y,
/// +z, -z, in that order ([`cube_face_of`] picks one for a direction).
pub fn cube_faces(eye: Vec3) -> [ProjPlane; 6] {
    let face = |forward: Vec3, right: Vec3, up: Vec3| ProjPlane::Perspective {
        eye,
        right,
        up,
        forward,
    };
    [
        face(Vec3::X, Vec3::Y, Vec3::Z),
        face(-Vec3::X, Vec3::Y, Vec3::Z),
        face(Vec3::Y, Vec3::Z, Vec3::X),
        face(-Vec3::Y, Vec3::Z, Vec3::X),
        face(Vec3::Z, Vec3::X, Vec3::Y),
        face(-Vec3::Z, Vec3::X, Vec3::Y),
    ]
}

/// The cube face (index into [`cube_faces`]) whose forward axis is `v`'s
/// dominant one, with its sign: every point of a segment from the eye
/// along `v` projects onto that face.
#[inline]
pub fn cube_face_of(v: Vec3) -> usize {
    let a = v.abs();
    let axis = if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    };
    2 * axis + (v[axis] < 0.0) as usize
}

/// True when `ray` runs towards `target` and ends at it or before: its
/// direction parallel to `target - origin` within rounding (1e-6), so that
/// every point of it lies on the line from `target` through its origin.
pub(crate) fn runs_towards(ray: &crate::Ray, target: Vec3) -> bool {
    let w = target - ray.origin;
    let (dl, wl) = (ray.dir.length(), w.length());
    ray.dir.dot(w) > 0.0
        && ray.dir.cross(w).length() <= 1.0e-6 * dl * wl
        && ray.t_max * dl <= wl * (1.0 + 1.0e-6)
}

/// True when `ray` runs against `dir` (parallel within rounding, 1e-6).
pub(crate) fn runs_against(ray: &crate::Ray, dir: Vec3) -> bool {
    let (dl, fl) = (ray.dir.length(), dir.length());
    -ray.dir.dot(dir) > 0.0 && ray.dir.cross(dir).length() <= 1.0e-6 * dl * fl
}
