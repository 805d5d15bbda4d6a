use super::{
    clip_triangle_bounds, clip_triangle_bounds_split, intersect_triangle, Aabb, Cone, Hit,
    PreparedRay, Sphere,
};
use crate::Error;
use glam::Vec3;

/// Geometry id of the scene's triangle mesh.
pub const GEOM_TRIANGLES: u32 = 0;
/// Geometry id of the scene's spheres.
pub const GEOM_SPHERES: u32 = 1;
/// Geometry id of the scene's cones and cylinders.
pub const GEOM_CONES: u32 = 2;

/// The primitives a structure is built over, borrowed from the caller: one
/// indexed triangle mesh, spheres and cones. Convex and concave polygons
/// enter as triangles.
///
/// Structures name primitives by one global index: triangles first, then
/// spheres, then cones. A [`Hit`] reports the geometry id and the index inside
/// that geometry.
#[derive(Clone, Copy, Debug, Default)]
pub struct Scene<'a> {
    /// Vertex positions.
    pub vertices: &'a [[f32; 3]],
    /// Triangles as three vertex indices.
    pub triangles: &'a [[u32; 3]],
    /// Spheres.
    pub spheres: &'a [Sphere],
    /// Open cones and cylinders.
    pub cones: &'a [Cone],
}

impl<'a> Scene<'a> {
    /// The digest of the scene's contents: every word of its vertices,
    /// triangles, spheres and cones, in order, and the arrays' lengths.
    /// A kd-tree records it at build time and `validate` recomputes it, so
    /// a tree over a scene changed since (one vertex bit, one index) is
    /// refused: its leaves may miss what the change moved into their cells.
    /// Each word enters by a bijection of the running state, so any one
    /// changed word changes the digest; more changes collide with
    /// probability about 2^-64 (not a crafted scene). About a nanosecond
    /// a word: 12 ms for `random:1000000`'s 12 million.
    pub fn digest(&self) -> u64 {
        let mut d = 0x5343_454E_4544_4947u64; // "SCENEDIG"
        let mut step = |w: u64| d = (d.rotate_left(23) ^ w).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        let pair = |a: f32, b: f32| (a.to_bits() as u64) << 32 | b.to_bits() as u64;
        for v in self.vertices {
            step(pair(v[0], v[1]));
            step(v[2].to_bits() as u64);
        }
        for t in self.triangles {
            step((t[0] as u64) << 32 | t[1] as u64);
            step(t[2] as u64);
        }
        for s in self.spheres {
            step(pair(s.center[0], s.center[1]));
            step(pair(s.center[2], s.radius));
        }
        for c in self.cones {
            step(pair(c.base[0], c.base[1]));
            step(pair(c.base[2], c.base_radius));
            step(pair(c.apex[0], c.apex[1]));
            step(pair(c.apex[2], c.apex_radius));
        }
        for len in [
            self.vertices.len(),
            self.triangles.len(),
            self.spheres.len(),
            self.cones.len(),
        ] {
            step(len as u64);
        }
        crate::rng::mix64(d)
    }

    /// How many primitives a build over the whole scene puts in its leaves
    /// (those [`Scene::prim_bounds`] keeps: not degenerate, in range), and
    /// [`crate::rng::ref_digest`] of them. A static hierarchy records both
    /// at build time; `validate` compares them with the scene it is given,
    /// so a primitive that was degenerate at build time (in no leaf) and is
    /// not any more is refused, as is one that has become degenerate.
    pub fn built_refs(&self) -> (u64, u64) {
        (0..self.prim_count())
            .filter(|&p| self.prim_bounds(p).is_some_and(|b| !b.is_empty()))
            .fold((0, 0), |(n, d), p| {
                (n + 1, d.wrapping_add(crate::rng::ref_mix(p as u32)))
            })
    }

    /// Number of primitives of all kinds.
    #[inline]
    pub fn prim_count(&self) -> usize {
        self.triangles.len() + self.spheres.len() + self.cones.len()
    }

    /// Checks what would make tracing undefined: vertex indices out of range
    /// and more primitives than the kd build can index (2^30). Degenerate
    /// primitives are not errors; they are never hit.
    pub fn check(&self) -> Result<(), Error> {
        let n = self.prim_count();
        if n >= (1 << 30) || self.vertices.len() > u32::MAX as usize {
            return Err(Error::TooManyPrimitives { count: n });
        }
        let nv = self.vertices.len();
        for (i, t) in self.triangles.iter().enumerate() {
            for &v in t {
                if v as usize >= nv {
                    return Err(Error::IndexOutOfRange {
                        triangle: i,
                        vertex: v,
                    });
                }
            }
        }
        Ok(())
    }

    /// The three corners of triangle `i`. A missing vertex reads as NaN,
    /// which no ray hits, so a scene changed after [`Scene::check`] cannot
    /// make tracing panic.
    #[inline]
    pub fn triangle(&self, i: usize) -> [Vec3; 3] {
        let t = self.triangles.get(i).copied().unwrap_or([u32::MAX; 3]);
        let v = |k: u32| {
            Vec3::from(
                self.vertices
                    .get(k as usize)
                    .copied()
                    .unwrap_or([f32::NAN; 3]),
            )
        };
        [v(t[0]), v(t[1]), v(t[2])]
    }

    /// The box of primitive `prim`, a structure's reference:
    /// [`Scene::prim_bounds`] without its degeneracy checks (empty for an
    /// index past the scene, which only a corrupt structure holds).
    #[inline]
    pub(crate) fn prim_box(&self, prim: usize) -> Aabb {
        let nt = self.triangles.len();
        let ns = self.spheres.len();
        if prim < nt {
            let [a, b, c] = self.triangle(prim);
            Aabb {
                min: a.min(b).min(c),
                max: a.max(b).max(c),
            }
        } else if prim < nt + ns {
            self.spheres[prim - nt].bounds()
        } else {
            self.cones
                .get(prim - nt - ns)
                .map_or(Aabb::EMPTY, |c| c.bounds())
        }
    }

    /// Bounds of primitive `prim` (global index), or `None` when it is
    /// degenerate (zero area, zero or negative radius, NaN or infinite) or
    /// past the scene.
    pub fn prim_bounds(&self, prim: usize) -> Option<Aabb> {
        let nt = self.triangles.len();
        let ns = self.spheres.len();
        let b = if prim < nt {
            let [a, b, c] = self.triangle(prim);
            let n = (b - a).cross(c - a);
            if !(a.is_finite() && b.is_finite() && c.is_finite() && n.length_squared() > 0.0) {
                return None;
            }
            Aabb {
                min: a.min(b).min(c),
                max: a.max(b).max(c),
            }
        } else if prim < nt + ns {
            let s = &self.spheres[prim - nt];
            if !s.is_valid() {
                return None;
            }
            s.bounds()
        } else {
            let c = self.cones.get(prim - nt - ns)?;
            if !c.is_valid() {
                return None;
            }
            c.bounds()
        };
        if b.min.is_finite() && b.max.is_finite() {
            Some(b)
        } else {
            None
        }
    }

    /// Bounds of the part of primitive `prim` inside `voxel`: exact
    /// polygon clipping for triangles, box intersection for the others.
    pub fn clipped_bounds(&self, prim: usize, voxel: &Aabb) -> Option<Aabb> {
        if prim < self.triangles.len() {
            clip_triangle_bounds(self.triangle(prim), voxel)
        } else {
            let b = self.prim_bounds(prim)?.intersection(voxel);
            if b.is_empty() {
                None
            } else {
                Some(b)
            }
        }
    }

    /// [`Self::clipped_bounds`] of `prim` in both children of `voxel`
    /// split at `pos` on `axis` (the box below `pos` first), bit for bit
    /// the same; a triangle's clipping shares the faces both children keep
    /// ([`super::clip_triangle_bounds_split`]).
    pub fn clipped_bounds_split(
        &self,
        prim: usize,
        voxel: &Aabb,
        axis: usize,
        pos: f32,
    ) -> [Option<Aabb>; 2] {
        if prim < self.triangles.len() {
            return clip_triangle_bounds_split(self.triangle(prim), voxel, axis, pos);
        }
        let Some(b) = self.prim_bounds(prim) else {
            return [None, None];
        };
        voxel
            .split(axis, pos)
            .map(|v| Some(b.intersection(&v)).filter(|c| !c.is_empty()))
    }

    /// Which geometry (`GEOM_TRIANGLES`, `GEOM_SPHERES`, `GEOM_CONES`) the
    /// global primitive index `prim` names.
    #[inline]
    pub fn geom_of(&self, prim: usize) -> u32 {
        let (nt, ns) = (self.triangles.len(), self.spheres.len());
        if prim < nt {
            GEOM_TRIANGLES
        } else if prim < nt + ns {
            GEOM_SPHERES
        } else {
            GEOM_CONES
        }
    }

    /// Tests primitive `prim` (global index) for a hit in
    /// `[ray.t_min, t_max]`.
    #[inline]
    pub fn intersect_prim(&self, prim: usize, r: &PreparedRay, t_max: f32) -> Option<Hit> {
        let nt = self.triangles.len();
        if prim < nt {
            let [a, b, c] = self.triangle(prim);
            let (t, u, v) = intersect_triangle(r, a, b, c, t_max)?;
            return Some(Hit {
                t,
                u,
                v,
                ng: (a - b).cross(c - a),
                geom_id: GEOM_TRIANGLES,
                prim_id: prim as u32,
            });
        }
        let ns = self.spheres.len();
        if prim < nt + ns {
            let i = prim - nt;
            let (t, ng) = self.spheres[i].intersect(r, t_max)?;
            return Some(Hit {
                t,
                u: 0.0,
                v: 0.0,
                ng,
                geom_id: GEOM_SPHERES,
                prim_id: i as u32,
            });
        }
        let i = prim - nt - ns;
        let (t, u, ng) = self.cones.get(i)?.intersect(r, t_max)?;
        Some(Hit {
            t,
            u,
            v: 0.0,
            ng,
            geom_id: GEOM_CONES,
            prim_id: i as u32,
        })
    }

    /// Bounds of every non-degenerate primitive.
    pub fn bounds(&self) -> Aabb {
        let mut b = Aabb::EMPTY;
        for p in 0..self.prim_count() {
            if let Some(pb) = self.prim_bounds(p) {
                b = b.union(&pb);
            }
        }
        b
    }
}
