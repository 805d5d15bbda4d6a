//! Scenes for coray: Eric Haines' Neutral File Format (NFF) read and
//! written, triangle meshes read from OBJ and PLY files, and both turned
//! into the arrays a [`coray::Scene`] borrows.

pub mod mesh;
pub mod mesh_file;
pub mod nff;
pub mod random;
pub mod spd;
pub mod triangulate;

pub use mesh::SceneMesh;
pub use nff::{Light, Material, NffError, NffScene, Object, View};
