//! Geometry: rays, boxes, the three primitive kinds and the scene that holds them.

mod aabb;
mod camera;
mod cone;
pub mod lanes;
pub(crate) mod leaf;
mod ray;
mod scene;
mod sphere;
mod triangle;

pub use aabb::{Aabb, ClipBox};
pub use camera::Camera;
pub use cone::Cone;
pub use glam::Vec3;
pub(crate) use ray::inverse;
pub use ray::{Hit, PreparedRay, Ray, INVALID_ID};
pub use scene::{Scene, GEOM_CONES, GEOM_SPHERES, GEOM_TRIANGLES};
pub use sphere::Sphere;
pub use triangle::{
    clip_triangle_bounds, clip_triangle_bounds_split, intersect_triangle, intersect_triangles4,
    Corners4, Hits4, TRI_LANES,
};
