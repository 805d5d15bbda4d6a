//! Leaf blocks: four primitive slots a block, the triangles' corners
//! copied lane by lane ([`Corners4`]) beside the primitives' indices, so a
//! leaf's triangles are tested four at a time straight from its blocks,
//! with no gather through the scene's indices (Embree keeps its leaf
//! triangles alike). Each leaf owns whole blocks: a leaf of `m`
//! primitives takes `ceil(m / 4)` consecutive blocks, its primitives in
//! the first `m` slots and [`NO_PRIM`] after them. A slot that holds a
//! sphere or a cone, or no primitive, has NaN corners, which no ray hits.
//! The copy is the scene's bits at build time: rebuild after moving
//! vertices (`validate` refuses a copy that differs from the scene).

use crate::geom::{Corners4, Scene, TRI_LANES};

/// Slots a block holds.
pub const BLOCK_SLOTS: usize = TRI_LANES;

/// [`LeafBlock::prims`] of a slot past its leaf's primitives.
pub const NO_PRIM: u32 = u32::MAX;

/// Four primitive slots of one leaf (160 bytes).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(16))]
pub struct LeafBlock {
    /// Per slot: its triangle's corners, `corners[corner][axis][slot]`;
    /// NaN where the slot holds a sphere, a cone or nothing.
    pub corners: Corners4,
    /// Per slot: the primitive's global index (triangles, then spheres,
    /// then cones), or [`NO_PRIM`].
    pub prims: [u32; BLOCK_SLOTS],
}

impl LeafBlock {
    /// The geometric normal of slot `slot`'s triangle as the scene's
    /// one-triangle test makes it, `(v0 - v1) x (v2 - v0)`: a walk makes
    /// it once, for its best hit, from the block's copy of the corners.
    #[inline]
    pub fn normal(&self, slot: usize) -> crate::Vec3 {
        let c = &self.corners;
        let v = |k: usize| crate::Vec3::new(c[k][0][slot], c[k][1][slot], c[k][2][slot]);
        (v(0) - v(1)).cross(v(2) - v(0))
    }
}

/// A block of empty slots.
pub const EMPTY_BLOCK: LeafBlock = LeafBlock {
    corners: [[[f32::NAN; TRI_LANES]; 3]; 3],
    prims: [NO_PRIM; BLOCK_SLOTS],
};

/// Blocks a leaf of `prims` primitives takes.
#[inline]
pub const fn blocks_for(prims: usize) -> usize {
    prims.div_ceil(BLOCK_SLOTS)
}

/// The corners slot `prim` holds: its triangle's, or NaN.
fn corners_of(scene: &Scene, prim: u32) -> [[f32; 3]; 3] {
    if prim != NO_PRIM && (prim as usize) < scene.triangles.len() {
        scene.triangle(prim as usize).map(|v| v.to_array())
    } else {
        [[f32::NAN; 3]; 3]
    }
}

/// The block holding `prims` (at most four; the rest of the slots empty).
#[allow(clippy::needless_range_loop)] // slots index the block's innermost arrays
pub fn fill(scene: &Scene, prims: &[u32]) -> LeafBlock {
    let mut b = EMPTY_BLOCK;
    for (slot, &p) in prims.iter().take(BLOCK_SLOTS).enumerate() {
        b.prims[slot] = p;
        let c = corners_of(scene, p);
        for k in 0..3 {
            for a in 0..3 {
                b.corners[k][a][slot] = c[k][a];
            }
        }
    }
    b
}

/// Whether `b`'s corners are exactly what [`fill`] writes for its
/// primitives over `scene` (bit for bit; NaN lanes any NaN).
pub fn matches(scene: &Scene, b: &LeafBlock) -> bool {
    (0..BLOCK_SLOTS).all(|slot| {
        let c = corners_of(scene, b.prims[slot]);
        (0..3).all(|k| {
            (0..3).all(|a| {
                let (want, got) = (c[k][a], b.corners[k][a][slot]);
                want.to_bits() == got.to_bits() || (want.is_nan() && got.is_nan())
            })
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocks_hold_corners_and_indices_lane_by_lane() {
        assert_eq!(core::mem::size_of::<LeafBlock>(), 160);
        let vertices = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let triangles = [[0, 1, 2], [2, 1, 0]];
        let spheres = [crate::Sphere {
            center: [0.0; 3],
            radius: 1.0,
        }];
        let s = Scene {
            vertices: &vertices,
            triangles: &triangles,
            spheres: &spheres,
            cones: &[],
        };
        let b = fill(&s, &[1, 2, 0]);
        assert_eq!(b.prims, [1, 2, 0, NO_PRIM]);
        // Slot 0 holds triangle 1: corners 2, 1, 0.
        assert_eq!(
            [b.corners[0][1][0], b.corners[1][0][0], b.corners[2][0][0]],
            [1.0, 1.0, 0.0]
        );
        // The sphere's and the empty slot's corners are NaN.
        assert!(b
            .corners
            .iter()
            .flatten()
            .all(|l| l[1].is_nan() && l[3].is_nan()));
        assert!(matches(&s, &b));
        let mut moved = b;
        moved.corners[2][2][2] = 0.5;
        assert!(!matches(&s, &moved));
        assert_eq!((blocks_for(0), blocks_for(4), blocks_for(5)), (0, 1, 2));
    }
}
