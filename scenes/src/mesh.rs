//! An NFF scene flattened into the arrays a [`coray::Scene`] borrows, with
//! what shading needs alongside: a material per primitive, vertex normals of
//! `pp` polygons, the camera and the lights.

use crate::nff::{Material, NffScene, Object, View};
use crate::triangulate::ear_clip;
use coray::{Camera, Cone, Scene, Sphere, Vec3};

/// Objects of a scene by type, as `coray stats` and the SPD table count them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counts {
    /// Spheres.
    pub spheres: usize,
    /// Polygons (`p` and `pp`).
    pub polygons: usize,
    /// Of those, `pp` polygons (with vertex normals).
    pub polygons_with_normals: usize,
    /// Triangles after triangulation.
    pub triangles: usize,
    /// Cones (radii differ).
    pub cones: usize,
    /// Cylinders (equal radii).
    pub cylinders: usize,
    /// Lights.
    pub lights: usize,
}

impl Counts {
    /// Objects as the SPD counts them: spheres, polygons, cones, cylinders.
    pub fn objects(&self) -> usize {
        self.spheres + self.polygons + self.cones + self.cylinders
    }
}

/// A scene ready to trace and shade.
#[derive(Clone, Debug, Default)]
pub struct SceneMesh {
    /// Vertex positions.
    pub vertices: Vec<[f32; 3]>,
    /// Shading normal per vertex (the geometric one where the file gave none).
    pub normals: Vec<[f32; 3]>,
    /// True where `normals` came from a `pp` polygon.
    pub has_normal: Vec<bool>,
    /// Triangles.
    pub triangles: Vec<[u32; 3]>,
    /// Spheres.
    pub spheres: Vec<Sphere>,
    /// Cones and cylinders.
    pub cones: Vec<Cone>,
    /// Material per triangle, sphere and cone (global primitive order).
    pub prim_material: Vec<u32>,
    /// Materials; index 0 is the default grey when the file's objects come before any `f`.
    pub materials: Vec<Material>,
    /// Camera (a default one looking at the scene when the file has no `v`).
    pub camera: Camera,
    /// Hither distance of the view.
    pub hither: f32,
    /// Light positions and colours.
    pub lights: Vec<(Vec3, Vec3)>,
    /// Background colour.
    pub background: Vec3,
    /// Objects by type.
    pub counts: Counts,
}

/// The view of a scene that has none: from the front and a little above
/// the centre of `bounds`, far enough that the whole box is in a 45-degree
/// field of view, 512 x 512 pixels.
pub fn framing_view(bounds: &coray::Aabb) -> View {
    let c = if bounds.is_empty() {
        Vec3::ZERO
    } else {
        (bounds.min + bounds.max) * 0.5
    };
    let r = if bounds.is_empty() {
        1.0
    } else {
        // Far enough from the centre to be a distinct f32 point.
        (bounds.max - bounds.min)
            .length()
            .max(1e-5 * (1.0 + c.abs().max_element()))
    };
    View {
        from: (c + Vec3::new(0.0, 0.3, 1.0).normalize() * (1.5 * r)).into(),
        at: c.into(),
        up: [0.0, 1.0, 0.0],
        angle: 45.0,
        hither: 0.0,
        resolution: [512, 512],
    }
}

/// The material used before the first `f`.
pub const DEFAULT_MATERIAL: Material = Material {
    color: [0.8, 0.8, 0.8],
    kd: 1.0,
    ks: 0.0,
    shine: 0.0,
    t: 0.0,
    ior: 1.0,
};

impl SceneMesh {
    /// Flattens `nff`: polygons triangulated by ear clipping, spheres and
    /// cones as they are.
    pub fn from_nff(nff: &NffScene) -> SceneMesh {
        let mut m = SceneMesh {
            materials: vec![DEFAULT_MATERIAL],
            ..SceneMesh::default()
        };
        m.materials.extend(nff.materials.iter().copied());
        let mat = |o: &Object| o.material().map_or(0, |i| i as u32 + 1);
        let (mut tri_mat, mut sph_mat, mut cone_mat) = (Vec::new(), Vec::new(), Vec::new());
        for o in &nff.objects {
            match o {
                Object::Sphere { center, radius, .. } => {
                    m.spheres.push(Sphere {
                        center: *center,
                        radius: *radius,
                    });
                    sph_mat.push(mat(o));
                    m.counts.spheres += 1;
                }
                Object::Cone {
                    base,
                    base_radius,
                    apex,
                    apex_radius,
                    ..
                } => {
                    m.cones.push(Cone {
                        base: *base,
                        base_radius: *base_radius,
                        apex: *apex,
                        apex_radius: *apex_radius,
                    });
                    cone_mat.push(mat(o));
                    if base_radius == apex_radius {
                        m.counts.cylinders += 1;
                    } else {
                        m.counts.cones += 1;
                    }
                }
                Object::Polygon {
                    vertices, normals, ..
                } => {
                    let first = m.vertices.len() as u32;
                    let n = crate::triangulate::newell_normal(vertices);
                    let geometric =
                        Vec3::new(n[0] as f32, n[1] as f32, n[2] as f32).normalize_or_zero();
                    m.vertices.extend_from_slice(vertices);
                    match normals {
                        Some(ns) => {
                            m.normals.extend_from_slice(ns);
                            m.has_normal.extend(std::iter::repeat_n(true, ns.len()));
                            m.counts.polygons_with_normals += 1;
                        }
                        None => {
                            m.normals
                                .extend(std::iter::repeat_n(geometric.to_array(), vertices.len()));
                            m.has_normal
                                .extend(std::iter::repeat_n(false, vertices.len()));
                        }
                    }
                    for t in ear_clip(vertices) {
                        m.triangles.push(t.map(|i| i + first));
                        tri_mat.push(mat(o));
                    }
                    m.counts.polygons += 1;
                }
            }
        }
        m.counts.triangles = m.triangles.len();
        m.counts.lights = nff.lights.len();
        m.prim_material = tri_mat.into_iter().chain(sph_mat).chain(cone_mat).collect();
        m.lights = nff
            .lights
            .iter()
            .map(|l| {
                let c = l.color.unwrap_or([1.0; 3]);
                (Vec3::from(l.pos), Vec3::from(c))
            })
            .collect();
        m.background = Vec3::from(nff.background.unwrap_or([0.0; 3]));
        let view = nff
            .view
            .unwrap_or_else(|| framing_view(&m.scene().bounds()));
        m.camera = view.camera();
        m.hither = view.hither;
        m
    }

    /// The scene as NFF: its view, background, lights (white ones without a
    /// colour), every triangle a `p 3` (`pp 3` where its corners carry
    /// normals), spheres and cones, each after an `f` whenever its material
    /// differs from the one before. [`SceneMesh::from_nff`] of it gives the
    /// same primitives in the same order, camera, lights and materials
    /// (vertices shared between triangles come back one per corner).
    pub fn to_nff(&self) -> NffScene {
        let c = &self.camera;
        let mut nff = NffScene {
            view: Some(View {
                from: c.from.to_array(),
                at: c.at.to_array(),
                up: c.up.to_array(),
                angle: c.angle_deg,
                hither: self.hither,
                resolution: [c.width, c.height],
            }),
            background: Some(self.background.to_array()),
            lights: self
                .lights
                .iter()
                .map(|(pos, color)| crate::nff::Light {
                    pos: pos.to_array(),
                    color: (*color != Vec3::ONE).then(|| color.to_array()),
                })
                .collect(),
            ..NffScene::default()
        };
        let mut current: Option<u32> = None;
        let mut material_of = |nff: &mut NffScene, prim: usize| {
            let m = self.prim_material.get(prim).copied().unwrap_or(0);
            if current != Some(m) {
                let mat = self
                    .materials
                    .get(m as usize)
                    .copied()
                    .unwrap_or(DEFAULT_MATERIAL);
                // NFF's default material is in force only before any `f`.
                if current.is_some() || mat != DEFAULT_MATERIAL {
                    nff.materials.push(mat);
                }
                current = Some(m);
            }
            nff.materials.len().checked_sub(1)
        };
        for (i, t) in self.triangles.iter().enumerate() {
            let material = material_of(&mut nff, i);
            let at = |k: usize| {
                self.vertices
                    .get(t[k] as usize)
                    .copied()
                    .unwrap_or([f32::NAN; 3])
            };
            let with_normals = t
                .iter()
                .any(|&v| self.has_normal.get(v as usize) == Some(&true));
            nff.objects.push(Object::Polygon {
                vertices: vec![at(0), at(1), at(2)],
                normals: with_normals.then(|| {
                    t.iter()
                        .map(|&v| self.normals.get(v as usize).copied().unwrap_or_default())
                        .collect()
                }),
                material,
            });
        }
        let nt = self.triangles.len();
        for (i, s) in self.spheres.iter().enumerate() {
            let material = material_of(&mut nff, nt + i);
            nff.objects.push(Object::Sphere {
                center: s.center,
                radius: s.radius,
                inside_visible: false,
                material,
            });
        }
        let ns = nt + self.spheres.len();
        for (i, k) in self.cones.iter().enumerate() {
            let material = material_of(&mut nff, ns + i);
            nff.objects.push(Object::Cone {
                base: k.base,
                base_radius: k.base_radius,
                apex: k.apex,
                apex_radius: k.apex_radius,
                inside_visible: false,
                material,
            });
        }
        nff
    }

    /// The arrays as a coray scene.
    pub fn scene(&self) -> Scene<'_> {
        Scene {
            vertices: &self.vertices,
            triangles: &self.triangles,
            spheres: &self.spheres,
            cones: &self.cones,
        }
    }
}
