//! Hidden-surface removal by ray casting with LCTS (section 5.2): one
//! primary ray per pixel from a pinhole camera, each pixel given exactly the
//! hit hierarchical traversal gives it.
//!
//! SLCTS schemes undersample: the rays through the corners of each window
//! (n x 1 pixels on a scanline for SLCTS-1D, n x m for SLCTS-2D; corners are
//! shared by neighbouring windows) are traced hierarchically with their
//! histories recorded, and every other pixel of the window is traced along
//! the window's common leaf sequence, then by ropes.

use super::history::{trace_recorded, History, HistoryRecord};
use super::slcts;
use crate::geom::{Camera, Hit, INVALID_ID};
use crate::kd::{KdTree, Traversal};
use crate::{Error, TraceStats};

/// How an image is cast.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scheme {
    /// Every pixel by hierarchical traversal (the reference).
    Hierarchical,
    /// Every pixel by rope traversal.
    Ropes,
    /// Windows of `n x 1` pixels on each scanline (paper default 5).
    Slcts1d {
        /// Window width in pixels, at least 2.
        n: u32,
    },
    /// Windows of `n x m` pixels (paper default 5 x 5).
    Slcts2d {
        /// Window width in pixels, at least 2.
        n: u32,
        /// Window height in pixels, at least 2.
        m: u32,
    },
}

/// Buffer sizes for [`cast_image`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ImageRequirements {
    /// [`HistoryRecord`] slots: `2 * corner columns * history_capacity`.
    pub records: usize,
    /// Sequence entries (`u32`): `history_capacity`.
    pub entries: usize,
    /// [`CornerInfo`] slots: two rows of corner columns.
    pub corners: usize,
}

/// Caller memory for [`cast_image`].
pub struct ImageScratch<'b> {
    /// Histories of the corner rays of two rows of windows.
    pub records: &'b mut [HistoryRecord],
    /// One window's common sequence.
    pub entries: &'b mut [u32],
    /// Corner ray infos, two rows.
    pub corners: &'b mut [CornerInfo],
}

/// What a cast did, beyond the per-ray counters.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CastStats {
    /// All rays: corner rays and the rest.
    pub trace: TraceStats,
    /// Windows cast with a sequence (SLCTS schemes).
    pub windows: u64,
    /// Of those, windows whose common sequence held at least one leaf (gamma's numerator).
    pub windows_shared: u64,
    /// Windows that had a termination object.
    pub windows_terminated: u64,
}

impl CastStats {
    /// gamma: the share of windows whose common sequence holds a leaf.
    pub fn gamma(&self) -> f64 {
        if self.windows == 0 {
            0.0
        } else {
            self.windows_shared as f64 / self.windows as f64
        }
    }
}

/// Corner coordinates along an axis of `len` pixels with window size `n`:
/// 0, n-1, 2(n-1), ... and always the last pixel.
fn corners(len: u32, n: u32, i: usize) -> u32 {
    (i as u32 * (n - 1)).min(len - 1)
}

fn corner_count(len: u32, n: u32) -> usize {
    if len <= 1 {
        1
    } else {
        ((len - 1).div_ceil(n - 1) + 1) as usize
    }
}

/// Buffer sizes for an image `width` pixels wide, with histories of up to
/// `history_capacity` records (a ray whose traversal is longer shares nothing).
pub fn image_requirements(
    width: u32,
    scheme: Scheme,
    history_capacity: usize,
) -> ImageRequirements {
    let cols = match scheme {
        Scheme::Slcts1d { n } | Scheme::Slcts2d { n, .. } => corner_count(width.max(1), n.max(2)),
        _ => 0,
    };
    let rows = if matches!(scheme, Scheme::Slcts2d { .. }) {
        2
    } else {
        1
    };
    ImageRequirements {
        records: rows * cols * history_capacity,
        entries: if cols == 0 { 0 } else { history_capacity },
        corners: rows * cols,
    }
}

fn global_prim(tree: &KdTree, h: &Hit) -> u32 {
    let s = &tree.scene;
    match h.geom_id {
        crate::geom::GEOM_TRIANGLES => h.prim_id,
        crate::geom::GEOM_SPHERES => s.triangles.len() as u32 + h.prim_id,
        crate::geom::GEOM_CONES => (s.triangles.len() + s.spheres.len()) as u32 + h.prim_id,
        _ => INVALID_ID,
    }
}

/// Casts the camera's image. `t_out[y * w + x]` receives the hit distance
/// (infinity for a miss) and `prim_out` the global primitive index
/// (triangles, then spheres, then cones; `u32::MAX` for a miss). Both must
/// hold `width * height` entries; the scratch must meet [`image_requirements`]
/// for some history capacity (the capacity is the records per corner row
/// divided by the corner columns).
pub fn cast_image(
    tree: &KdTree,
    camera: &Camera,
    scheme: Scheme,
    scratch: ImageScratch,
    t_out: &mut [f32],
    prim_out: &mut [u32],
) -> Result<CastStats, Error> {
    let (w, h) = (camera.width, camera.height);
    let pixels = w as usize * h as usize;
    if w == 0 || h == 0 {
        return Err(Error::InvalidParameter {
            name: "camera resolution",
        });
    }
    if t_out.len() < pixels {
        return Err(Error::SliceTooSmall {
            slice: "t_out",
            needed: pixels,
            got: t_out.len(),
        });
    }
    if prim_out.len() < pixels {
        return Err(Error::SliceTooSmall {
            slice: "prim_out",
            needed: pixels,
            got: prim_out.len(),
        });
    }
    let (f, r, u) = camera.basis();
    let ray = |x: u32, y: u32| camera.ray_in(f, r, u, x as f32 + 0.5, y as f32 + 0.5);
    let mut st = CastStats::default();
    let mut put = |x: u32, y: u32, hit: &Hit| {
        let i = y as usize * w as usize + x as usize;
        t_out[i] = hit.t;
        prim_out[i] = global_prim(tree, hit);
    };
    match scheme {
        Scheme::Hierarchical | Scheme::Ropes => {
            let m = if scheme == Scheme::Ropes {
                Traversal::Ropes
            } else {
                Traversal::Hierarchical
            };
            for y in 0..h {
                for x in 0..w {
                    let hit = tree.intersect(&ray(x, y), m, &mut st.trace);
                    put(x, y, &hit);
                }
            }
        }
        Scheme::Slcts1d { n } | Scheme::Slcts2d { n, .. } => {
            if n < 2 {
                return Err(Error::InvalidParameter {
                    name: "window width",
                });
            }
            let m = match scheme {
                Scheme::Slcts2d { m, .. } if m < 2 => {
                    return Err(Error::InvalidParameter {
                        name: "window height",
                    })
                }
                Scheme::Slcts2d { m, .. } => m,
                _ => 1,
            };
            let cols = corner_count(w, n);
            let rows_kept = if m == 1 { 1 } else { 2 };
            let cap = scratch.records.len() / (rows_kept * cols);
            if cap == 0 {
                let needed = rows_kept * cols;
                return Err(Error::SliceTooSmall {
                    slice: "records",
                    needed,
                    got: scratch.records.len(),
                });
            }
            let (mut top, mut bottom) =
                scratch
                    .records
                    .split_at_mut(if m == 1 { 0 } else { cols * cap });
            if scratch.corners.len() < rows_kept * cols {
                let needed = rows_kept * cols;
                return Err(Error::SliceTooSmall {
                    slice: "corners",
                    needed,
                    got: scratch.corners.len(),
                });
            }
            let (ct, cb) = scratch.corners.split_at_mut(if m == 1 { 0 } else { cols });
            let mut hist_lens_top = HistRow { info: ct };
            let mut hist_lens_bottom = HistRow { info: cb };
            let corner_rows = if m == 1 {
                h as usize
            } else {
                corner_count(h, m)
            };
            for j in 0..corner_rows {
                let yj = if m == 1 { j as u32 } else { corners(h, m, j) };
                // Trace this row's corners with their histories.
                for i in 0..cols {
                    let xi = corners(w, n, i);
                    let buf = &mut bottom[i * cap..(i + 1) * cap];
                    let mut hist = History::new(buf);
                    trace_recorded(tree, &ray(xi, yj), &mut hist, &mut st.trace);
                    put(xi, yj, &hist.hit);
                    hist_lens_bottom.info[i] = CornerInfo {
                        len: hist.len as u32,
                        overflow: hist.overflow as u32,
                        hit: hist.hit,
                    };
                }
                if m == 1 {
                    // Windows between neighbouring corners of this scanline.
                    for i in 0..cols - 1 {
                        let hs = [
                            slice_of(bottom, cap, i, &hist_lens_bottom),
                            slice_of(bottom, cap, i + 1, &hist_lens_bottom),
                        ];
                        let hits = [hist_lens_bottom.hit(i), hist_lens_bottom.hit(i + 1)];
                        let seq = slcts::build(tree, &hs, &hits, &mut *scratch.entries);
                        count_window(&mut st, &seq);
                        for x in corners(w, n, i) + 1..corners(w, n, i + 1) {
                            let hit = slcts::trace(tree, &seq, &ray(x, yj), &mut st.trace);
                            put(x, yj, &hit);
                        }
                    }
                } else if j > 0 {
                    let y_prev = corners(h, m, j - 1);
                    for i in 0..cols - 1 {
                        let hs = [
                            slice_of(top, cap, i, &hist_lens_top),
                            slice_of(top, cap, i + 1, &hist_lens_top),
                            slice_of(bottom, cap, i, &hist_lens_bottom),
                            slice_of(bottom, cap, i + 1, &hist_lens_bottom),
                        ];
                        let hits = [
                            hist_lens_top.hit(i),
                            hist_lens_top.hit(i + 1),
                            hist_lens_bottom.hit(i),
                            hist_lens_bottom.hit(i + 1),
                        ];
                        let seq = slcts::build(tree, &hs, &hits, &mut *scratch.entries);
                        count_window(&mut st, &seq);
                        let (x0, x1) = (corners(w, n, i), corners(w, n, i + 1));
                        // Each pixel belongs to exactly one window: the first
                        // row and column of windows own their leading edges.
                        let y_from = if j == 1 { y_prev } else { y_prev + 1 };
                        let x_from = if i == 0 { x0 } else { x0 + 1 };
                        for y in y_from..=yj {
                            let corner_row = y == y_prev || y == yj;
                            for x in x_from..=x1 {
                                if corner_row && (x == x0 || x == x1) {
                                    continue;
                                }
                                let hit = slcts::trace(tree, &seq, &ray(x, y), &mut st.trace);
                                put(x, y, &hit);
                            }
                        }
                    }
                }
                if m > 1 {
                    core::mem::swap(&mut top, &mut bottom);
                    core::mem::swap(&mut hist_lens_top, &mut hist_lens_bottom);
                }
            }
        }
    }
    Ok(st)
}

fn count_window(st: &mut CastStats, seq: &slcts::Slcts) {
    st.windows += 1;
    st.windows_shared += (seq.leaves > 0) as u64;
    st.windows_terminated += seq.termination.is_some() as u64;
}

/// What the cast keeps of a corner ray besides its history records.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub struct CornerInfo {
    /// Records in the history.
    pub len: u32,
    /// 1 when the history did not fit its slot.
    pub overflow: u32,
    /// The corner ray's hit.
    pub hit: Hit,
}

/// A row of corner rays: their infos.
struct HistRow<'b> {
    info: &'b mut [CornerInfo],
}

impl HistRow<'_> {
    fn hit(&self, i: usize) -> Hit {
        self.info[i].hit
    }
}

fn slice_of<'a>(
    buf: &'a [HistoryRecord],
    cap: usize,
    i: usize,
    row: &HistRow,
) -> Option<&'a [HistoryRecord]> {
    let c = row.info[i];
    (c.overflow == 0).then(|| &buf[i * cap..i * cap + c.len as usize])
}
