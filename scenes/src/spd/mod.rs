//! The Standard Procedural Databases (Eric Haines), generated here from the
//! SPD's published description: the same object structure and counts per
//! type at every size factor. Camera, lights and materials follow the SPD's
//! style; coordinates are this project's own (the scenes are not byte copies
//! of the SPD programs' output). Each generator returns an [`NffScene`].
//!
//! | scene | objects at size s |
//! |---|---|
//! | balls | sum 9^i (i = 0..s) spheres, 1 floor polygon |
//! | gears | s^3 gears of 2 concave 144-gons and 144 quads, 1 floor quad |
//! | lattice | (s+1)^3 spheres, 3 s (s+1)^2 cylinders |
//! | mount | 2 * 4^s triangles, 4 spheres |
//! | teapot | 64 s^2 - 8 s `pp` triangles, s^2 floor squares |
//! | rings | 600 s spheres, 600 s cylinders, 1 floor polygon |
//! | tetra | 4^s triangles |
//! | tree | 2^(s+1) - 1 cones and as many spheres, 1 floor polygon |

mod balls;
mod gears;
mod lattice;
mod mount;
mod rings;
mod teapot;
mod teapot_data;
mod tetra;
mod tree;

use crate::nff::{Light, Material, NffScene, Object, View};

/// The scenes this module generates, with their default sizes (the table in docs/techniques.md).
pub const SCENES: &[(&str, u32)] = &[
    ("balls", 4),
    ("gears", 4),
    ("lattice", 12),
    ("mount", 6),
    ("rings", 7),
    ("teapot", 12),
    ("tetra", 6),
    ("tree", 11),
];

/// Options shared by the generators.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Options {
    /// Cut the floor polygon into k x k pieces (thesis section 6.3.6); 1 keeps it whole.
    pub floor_split: u32,
}

impl Default for Options {
    fn default() -> Self {
        Options { floor_split: 1 }
    }
}

/// Generates SPD scene `name` at size factor `size` (None: the default).
pub fn generate(name: &str, size: Option<u32>, opts: &Options) -> Result<NffScene, String> {
    let Some(&(_, default)) = SCENES.iter().find(|(n, _)| *n == name) else {
        let names: Vec<&str> = SCENES.iter().map(|(n, _)| *n).collect();
        return Err(format!(
            "no SPD scene `{}` (have: {})",
            crate::nff::shown(name),
            names.join(", ")
        ));
    };
    let size = size.unwrap_or(default);
    let max = match name {
        "balls" => 6,
        "gears" => 12,
        "lattice" => 60,
        "mount" | "tetra" => 9,
        "rings" => 40,
        "teapot" => 100,
        "tree" => 18,
        _ => 0,
    };
    if size == 0 || size > max {
        return Err(format!("size of `{name}` must be 1 to {max}, not {size}"));
    }
    if opts.floor_split == 0 || opts.floor_split > 1024 {
        return Err("floor split must be 1 to 1024".into());
    }
    let mut b = Builder::default();
    match name {
        "balls" => balls::generate(&mut b, size, opts),
        "gears" => gears::generate(&mut b, size, opts),
        "lattice" => lattice::generate(&mut b, size),
        "mount" => mount::generate(&mut b, size),
        "rings" => rings::generate(&mut b, size, opts),
        "teapot" => teapot::generate(&mut b, size),
        "tetra" => tetra::generate(&mut b, size),
        "tree" => tree::generate(&mut b, size, opts),
        _ => unreachable!(),
    }
    Ok(b.scene)
}

/// Appends objects under the current material.
#[derive(Default)]
pub(crate) struct Builder {
    pub scene: NffScene,
}

pub(crate) type V3 = [f32; 3];

impl Builder {
    pub fn view(&mut self, from: V3, at: V3, up: V3, angle: f32) {
        self.scene.view = Some(View {
            from,
            at,
            up,
            angle,
            hither: 0.01,
            resolution: [512, 512],
        });
    }
    pub fn background(&mut self, c: V3) {
        self.scene.background = Some(c);
    }
    pub fn light(&mut self, pos: V3) {
        self.scene.lights.push(Light { pos, color: None });
    }
    /// `f r g b Kd Ks Shine T ior`.
    pub fn material(&mut self, color: V3, kd: f32, ks: f32, shine: f32, t: f32, ior: f32) {
        self.scene.materials.push(Material {
            color,
            kd,
            ks,
            shine,
            t,
            ior,
        });
    }
    fn current(&self) -> Option<usize> {
        self.scene.materials.len().checked_sub(1)
    }
    pub fn sphere(&mut self, center: V3, radius: f32) {
        let material = self.current();
        self.scene.objects.push(Object::Sphere {
            center,
            radius,
            inside_visible: false,
            material,
        });
    }
    pub fn cone(&mut self, base: V3, base_radius: f32, apex: V3, apex_radius: f32) {
        let material = self.current();
        self.scene.objects.push(Object::Cone {
            base,
            base_radius,
            apex,
            apex_radius,
            inside_visible: false,
            material,
        });
    }
    pub fn polygon(&mut self, vertices: Vec<V3>) {
        let material = self.current();
        self.scene.objects.push(Object::Polygon {
            vertices,
            normals: None,
            material,
        });
    }
    pub fn polygon_with_normals(&mut self, vertices: Vec<V3>, normals: Vec<V3>) {
        let material = self.current();
        self.scene.objects.push(Object::Polygon {
            vertices,
            normals: Some(normals),
            material,
        });
    }
    /// A floor square `[-h, h]^2` in the plane `axis = pos` (axis 2: z up),
    /// cut into `k x k` squares (k = 1: one polygon).
    pub fn floor(&mut self, h: f32, axis: usize, pos: f32, k: u32) {
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        let step = 2.0 * h / k as f32;
        for j in 0..k {
            for i in 0..k {
                let (u0, v0) = (-h + i as f32 * step, -h + j as f32 * step);
                let (u1, v1) = (
                    if i + 1 == k { h } else { u0 + step },
                    if j + 1 == k { h } else { v0 + step },
                );
                let p = |a: f32, b: f32| {
                    let mut x = [0.0; 3];
                    x[axis] = pos;
                    x[u] = a;
                    x[v] = b;
                    x
                };
                self.polygon(vec![p(u0, v0), p(u1, v0), p(u1, v1), p(u0, v1)]);
            }
        }
    }
}

/// Vector helpers on plain arrays.
pub(crate) mod v {
    use super::V3;
    pub fn add(a: V3, b: V3) -> V3 {
        [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
    }
    pub fn sub(a: V3, b: V3) -> V3 {
        [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
    }
    pub fn scale(a: V3, s: f32) -> V3 {
        [a[0] * s, a[1] * s, a[2] * s]
    }
    pub fn cross(a: V3, b: V3) -> V3 {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    }
    pub fn dot(a: V3, b: V3) -> f32 {
        a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
    }
    pub fn norm(a: V3) -> V3 {
        scale(a, 1.0 / dot(a, a).sqrt())
    }
    /// Two unit vectors perpendicular to unit `w` and to each other.
    pub fn frame(w: V3) -> (V3, V3) {
        let helper = if w[0].abs() < 0.9 {
            [1.0, 0.0, 0.0]
        } else {
            [0.0, 1.0, 0.0]
        };
        let u = norm(cross(helper, w));
        (u, cross(w, u))
    }
}
