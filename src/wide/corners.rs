//! The triangles' corners copied next to the references, four reference
//! slots a block, lane by lane ([`Corners4`]): a leaf's triangles are then
//! tested four at a time straight from the block, with no gather through
//! the scene's indices (Embree keeps its leaf triangles alike). Block `j`
//! holds the corners of references `4j .. 4j + 4`; a slot that names a
//! sphere or a cone, or lies past the last reference, holds NaN, which no
//! ray hits. The blocks cover the runs that hold a triangle, which the
//! build places first (`wide/pack.rs`): a scene of spheres and cones
//! needs none. The copy is the scene's bits at build time: rebuild (or
//! [`fill`] again) after moving vertices.

use crate::geom::{Corners4, Scene, TRI_LANES};

/// Blocks for `refs` reference slots.
pub const fn blocks_for(refs: usize) -> usize {
    refs.div_ceil(TRI_LANES)
}

/// A block of NaN lanes.
pub const NAN_BLOCK: Corners4 = [[[f32::NAN; TRI_LANES]; 3]; 3];

/// The corners of reference slot `slot`'s primitive in `refs`, or NaN.
fn lane_corners(scene: &Scene, refs: &[u32], slot: usize) -> [[f32; 3]; 3] {
    match refs.get(slot) {
        Some(&p) if (p as usize) < scene.triangles.len() => {
            scene.triangle(p as usize).map(|v| v.to_array())
        }
        _ => [[f32::NAN; 3]; 3],
    }
}

/// Fills every block of `out` from `scene` and `refs` (block `j`: slots
/// `4j .. 4j + 4`).
#[allow(clippy::needless_range_loop)] // lanes index the block's innermost arrays
pub fn fill(scene: &Scene, refs: &[u32], out: &mut [Corners4]) {
    for (j, block) in out.iter_mut().enumerate() {
        for lane in 0..TRI_LANES {
            let c = lane_corners(scene, refs, j * TRI_LANES + lane);
            for (k, corner) in c.iter().enumerate() {
                for (a, &x) in corner.iter().enumerate() {
                    block[k][a][lane] = x;
                }
            }
        }
    }
}

/// Whether `blocks` hold exactly what [`fill`] writes for `refs` (bit for
/// bit; NaN lanes any NaN).
pub fn matches(scene: &Scene, refs: &[u32], blocks: &[Corners4]) -> bool {
    blocks.iter().enumerate().all(|(j, block)| {
        (0..TRI_LANES).all(|lane| {
            let c = lane_corners(scene, refs, j * TRI_LANES + lane);
            (0..3).all(|k| {
                (0..3).all(|a| {
                    let (want, got) = (c[k][a], block[k][a][lane]);
                    want.to_bits() == got.to_bits() || (want.is_nan() && got.is_nan())
                })
            })
        })
    })
}
