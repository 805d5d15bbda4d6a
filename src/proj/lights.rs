//! Light planes: which projection planes a light gets, and which of them a
//! shadow ray uses. A point light inside the scene's box gets a cube of six
//! faces; one outside gets the single cube face that looks at the whole
//! box; a directional light gets an orthographic plane.

use super::plane::{cube_face_of, cube_faces, runs_against, runs_towards, ProjPlane};
use crate::geom::{Aabb, Ray};
use crate::Vec3;

/// A light as the projection hierarchies see it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Light {
    /// A point light at this position.
    Point(Vec3),
    /// A directional light shining along this direction.
    Directional(Vec3),
}

/// The planes of one light, `planes[..count]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightPlanes {
    /// The light.
    pub light: Light,
    /// Its planes.
    pub planes: [ProjPlane; 6],
    /// How many are used: 6 (a cube), or 1.
    pub count: usize,
}

impl LightPlanes {
    /// The planes of `light` for a scene inside `bounds`.
    pub fn new(light: Light, bounds: &Aabb) -> LightPlanes {
        match light {
            Light::Directional(d) => {
                let f = d.normalize_or_zero();
                let r = f.any_orthonormal_vector();
                let u = f.cross(r);
                let plane = ProjPlane::Orthographic {
                    right: r,
                    up: u,
                    forward: f,
                };
                LightPlanes {
                    light,
                    planes: [plane; 6],
                    count: 1,
                }
            }
            Light::Point(l) => {
                let faces = cube_faces(l);
                // Outside the box on some axis: the face looking across the
                // widest gap sees every point of the box in front of it.
                let mut best: Option<(usize, f32)> = None;
                for a in 0..3 {
                    for (face, gap) in [
                        (2 * a, bounds.min[a] - l[a]),
                        (2 * a + 1, l[a] - bounds.max[a]),
                    ] {
                        if gap > 0.0 && best.is_none_or(|(_, g)| gap > g) {
                            best = Some((face, gap));
                        }
                    }
                }
                match best {
                    Some((face, _)) if !bounds.is_empty() => LightPlanes {
                        light,
                        planes: [faces[face]; 6],
                        count: 1,
                    },
                    _ => LightPlanes {
                        light,
                        planes: faces,
                        count: 6,
                    },
                }
            }
        }
    }

    /// The plane `ray` uses when it is a shadow ray towards this light:
    /// the cube face its origin lies in, or the single plane. `None` when
    /// the ray does not go to this light (see [`LightPlanes::serves`]).
    pub fn plane_for(&self, ray: &Ray) -> Option<usize> {
        if !self.serves(ray) {
            return None;
        }
        match self.light {
            Light::Point(l) if self.count == 6 => Some(cube_face_of(ray.origin - l)),
            _ => Some(0),
        }
    }

    /// True when `ray` runs towards this light and ends at it or before:
    /// parallel to `light - origin` (to `-direction` for a directional
    /// light) within rounding. The uniform mode asks every light this.
    pub fn serves(&self, ray: &Ray) -> bool {
        match self.light {
            Light::Point(l) => runs_towards(ray, l),
            Light::Directional(d) => runs_against(ray, d),
        }
    }
}
