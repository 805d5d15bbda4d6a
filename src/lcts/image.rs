//! Hidden-surface removal by ray casting with LCTS (section 5.2): one
//! primary ray per pixel from a pinhole camera, each pixel given exactly the
//! hit hierarchical traversal gives it.
//!
//! SLCTS schemes undersample: the rays through the corners of each window
//! (n x 1 pixels on a scanline for SLCTS-1D, n x m for SLCTS-2D; corners are
//! shared by neighbouring windows) are traced hierarchically with their
//! histories recorded, and every other pixel of the window is traced along
//! the window's common leaf sequence, then by ropes. A window whose corners
//! share no leaf still shares their descent: its rays locate their first
//! leaf from the corners' deepest common node, then go on by ropes.
//!
//! HLCTS schemes bisect: the rays that split an interval or rectangle are
//! traced from its cut with their histories, which give the halves their
//! cuts; a small interval or rectangle is cast from its cut, each ray along
//! the cut's leading leaves and then by ropes.
//!
//! Past the common part, ropes are guided by the boundary rays' own leaves
//! ([`super::guide`]): a ray asks the nearest corner first.
//!
//! The packet scheme shares no sequence: each tile of 4 x 2 pixels is one
//! packet walking the tree from the root (`kd::packet`).

use super::guide::Paths;
use super::history::{trace_recorded_on, History, HistoryRecord};
use super::hlcts::{self, Boundary, Hlcts, HlctsEntry, Source, MAX_RAYS};
use super::slcts;
use super::window::{Baseline, Kernel, Shaft};
use crate::geom::lanes::LANES;
use crate::geom::{Aabb, Camera, Hit};
use crate::kd::{KdStackItem, KdTree, Traversal, KD_STACK_LEN};
use crate::tolerance::{SCREEN_MARGIN, SCREEN_NEAR_DEPTH};
use crate::{Error, TraceStats};
use crate::{Ray, Vec3};

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
    /// Each scanline by bisection: the HLCTS of an interval's two end rays
    /// starts the traversal of its middle ray, which then splits it.
    Hlcts1d,
    /// The image by bisection in two dimensions, alternating axes: the
    /// HLCTS of a rectangle's four corner rays starts the rays that split it.
    Hlcts2d,
    /// Every tile of 4 x 2 pixels (smaller at the right and bottom edges)
    /// as one packet of rays that walk the tree together, their primitive
    /// tests eight at a time ([`KdTree::intersect_packets`]): no shared
    /// traversal sequence, no ropes, no scratch, and the fastest scheme on
    /// primary rays. Counts steps per ray as the packet walk does (a node
    /// visited for five rays is five steps). Without the `packets` feature
    /// each ray is traced alone, hierarchically.
    Packets,
}

impl Scheme {
    /// Whether the scheme walks ropes (the tree must keep them).
    pub fn needs_ropes(self) -> bool {
        !matches!(self, Scheme::Hierarchical | Scheme::Packets)
    }
}

/// A [`Scheme::Packets`] tile: 4 x 2 pixels, the packet's eight lanes.
const TILE: (u32, u32) = (4, 2);
const _: () = assert!((TILE.0 * TILE.1) as usize == LANES);

/// Buffer sizes for [`cast_image`]: SLCTS schemes keep the corner rays
/// of two rows of windows; HLCTS schemes keep, per level of bisection, two
/// rays' histories and one HLCTS (`4 * history_capacity` entries, enough for
/// any cut of four histories).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ImageRequirements {
    /// [`HistoryRecord`] slots: histories of `history_capacity` records each.
    pub records: usize,
    /// `u32` slots: one SLCTS's sequence and its boundary rays' leaves past
    /// it (SLCTS schemes), or a leaf shaft's boundary rays' leaves (HLCTS).
    pub entries: usize,
    /// [`CornerInfo`] slots, one per kept history.
    pub corners: usize,
    /// Entry starts (`u32`) of histories traced through an HLCTS.
    pub starts: usize,
    /// [`HlctsEntry`] slots.
    pub hlcts: usize,
    /// [`KdStackItem`] slots: the traversal stack ([`KD_STACK_LEN`]).
    pub stack: usize,
}

/// Caller memory for [`cast_image`].
pub struct ImageScratch<'b> {
    /// Histories of the corner rays of two rows of windows.
    pub records: &'b mut [HistoryRecord],
    /// One window's common sequence and its corner rays' leaves past it.
    pub entries: &'b mut [u32],
    /// Corner ray infos.
    pub corners: &'b mut [CornerInfo],
    /// HLCTS schemes: where each entry's records begin in a history.
    pub starts: &'b mut [u32],
    /// HLCTS schemes: one cut per level of bisection.
    pub hlcts: &'b mut [HlctsEntry],
    /// The traversal stack, [`KD_STACK_LEN`] entries.
    pub stack: &'b mut [KdStackItem],
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
    /// SLCTS windows without a common leaf whose rays start below the root,
    /// at their corners' deepest common node.
    pub windows_entered: u64,
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
    height: u32,
    scheme: Scheme,
    history_capacity: usize,
) -> ImageRequirements {
    if let Some(levels) = bisection_levels(width, height, scheme) {
        let slots = bisection_slots(levels);
        let per_cut = MAX_RAYS * history_capacity;
        return ImageRequirements {
            records: slots * history_capacity,
            entries: CORNERS * history_capacity,
            corners: 0,
            starts: slots * per_cut,
            hlcts: (levels + 1) * per_cut,
            stack: KD_STACK_LEN,
        };
    }
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
        entries: if cols == 0 {
            0
        } else {
            (1 + CORNERS) * history_capacity
        },
        corners: rows * cols,
        starts: 0,
        hlcts: 0,
        stack: KD_STACK_LEN,
    }
}

/// Boundary rays of a window or rectangle (two for an interval): their
/// paths guide its rays.
const CORNERS: usize = 4;

/// HLCTS-2D casts rectangles of at most this many pixels from their cut
/// without splitting them: their rays follow the leading leaves, then ropes
/// guided by the four corners. Splitting further costs four recorded rays
/// per split (at 1024^2, 32 / 64 pixels: tetra alpha 0.325 / 0.327,
/// lattice 0.283 / 0.265, eta lower with fewer splits; 128 and 256 pixels
/// raise alpha again).
const LEAF_PIXELS: u32 = 64;
/// HLCTS-1D likewise for intervals shorter than this (8 / 16 / 32: tetra
/// alpha 0.360 / 0.352 / 0.412, eta 2.57 / 1.90 / 1.51).
const LEAF_PIXELS_1D: u32 = 16;

/// 1 when pixel `x` of `x0..=x1` lies nearer `x1` than `x0`, else 0: which
/// end's boundary ray guides it.
#[inline]
fn far_half(x: u32, x0: u32, x1: u32) -> usize {
    (2 * (x - x0) > x1 - x0) as usize
}

/// History slots of a bisection `levels` deep: the four first corners, and
/// up to four rays traced per level (2D: two on each half's new edge).
fn bisection_slots(levels: usize) -> usize {
    4 + 4 * levels
}

/// Levels of bisection of an HLCTS scheme (None for the others).
fn bisection_levels(width: u32, height: u32, scheme: Scheme) -> Option<usize> {
    let log = |n: u32| (32 - n.max(1).leading_zeros()) as usize;
    match scheme {
        Scheme::Hlcts1d => Some(log(width) + 1),
        Scheme::Hlcts2d => Some(log(width) + log(height) + 1),
        _ => None,
    }
}

/// A rectangle of a camera's pixels: columns `x .. x + width`, rows
/// `y .. y + height`. A cast of a rectangle gives each of its pixels what
/// the cast of the whole image gives it, so threads may cast an image's
/// tiles, each into its own buffer ([`cast_rect_with_by`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PixelRect {
    /// First column.
    pub x: u32,
    /// First row.
    pub y: u32,
    /// Columns.
    pub width: u32,
    /// Rows.
    pub height: u32,
}

impl PixelRect {
    /// The camera's whole image.
    pub fn whole(camera: &Camera) -> PixelRect {
        PixelRect {
            x: 0,
            y: 0,
            width: camera.width,
            height: camera.height,
        }
    }

    /// Whether it holds a pixel and lies inside the camera's image.
    pub fn fits(&self, camera: &Camera) -> bool {
        let inside = |at: u32, len: u32, side: u32| at.checked_add(len).is_some_and(|e| e <= side);
        self.width > 0
            && self.height > 0
            && inside(self.x, self.width, camera.width)
            && inside(self.y, self.height, camera.height)
    }
}

/// Casts the camera's image: `hits[y * width + x]` receives the closest
/// hit of pixel (x, y), exactly what hierarchical traversal gives it.
/// `hits` holds `width * height` entries; the scratch meets
/// [`image_requirements`] for some history capacity (the capacity is the
/// records per corner row divided by the corner columns). Every scheme but
/// [`Scheme::Hierarchical`] and [`Scheme::Packets`] walks ropes: the tree needs them
/// ([`Error::NoRopes`] otherwise).
pub fn cast_image(
    tree: &KdTree,
    camera: &Camera,
    scheme: Scheme,
    scratch: ImageScratch,
    hits: &mut [Hit],
) -> Result<CastStats, Error> {
    cast_image_by(Baseline, tree, camera, scheme, scratch, hits)
}

/// [`cast_image`], its windows' rays traced by `kernel` (the same hits and
/// counts by every kernel; `coray_ffi::simd` picks the widest this CPU
/// runs).
pub fn cast_image_by<K: Kernel>(
    kernel: K,
    tree: &KdTree,
    camera: &Camera,
    scheme: Scheme,
    scratch: ImageScratch,
    hits: &mut [Hit],
) -> Result<CastStats, Error> {
    let pixels = camera.width as usize * camera.height as usize;
    if hits.len() < pixels {
        return Err(Error::SliceTooSmall {
            slice: "hits",
            needed: pixels,
            got: hits.len(),
        });
    }
    let w = camera.width as usize;
    cast_image_with_by(kernel, tree, camera, scheme, scratch, |x, y, h| {
        hits[y as usize * w + x as usize] = *h;
    })
}

/// [`cast_image`], handing each pixel's hit to `put(x, y, hit)` (every
/// pixel exactly once) instead of storing it.
pub fn cast_image_with(
    tree: &KdTree,
    camera: &Camera,
    scheme: Scheme,
    scratch: ImageScratch,
    put: impl FnMut(u32, u32, &Hit),
) -> Result<CastStats, Error> {
    cast_image_with_by(Baseline, tree, camera, scheme, scratch, put)
}

/// [`cast_image_with`], its windows' rays traced by `kernel`, as
/// [`cast_image_by`].
pub fn cast_image_with_by<K: Kernel>(
    kernel: K,
    tree: &KdTree,
    camera: &Camera,
    scheme: Scheme,
    scratch: ImageScratch,
    put: impl FnMut(u32, u32, &Hit),
) -> Result<CastStats, Error> {
    if scheme.needs_ropes() && !tree.info().has_ropes() {
        return Err(Error::NoRopes);
    }
    if camera.width == 0 || camera.height == 0 {
        return Err(Error::InvalidParameter {
            name: "camera resolution",
        });
    }
    let whole = PixelRect::whole(camera);
    cast_rect_with_by(kernel, tree, camera, whole, scheme, scratch, put)
}

/// [`cast_image_with_by`] over the pixels of `rect` alone (inside the
/// camera's image, not empty): `put(x, y, hit)` once for each, `x` and
/// `y` the camera's pixel coordinates; the scratch meets
/// [`image_requirements`] for the rectangle's width and height. Each pixel
/// gets exactly what the whole image's cast gives it (every scheme is
/// exact), whatever the rectangle; the LCTS schemes lay their windows out
/// from its corner.
pub fn cast_rect_with_by<K: Kernel>(
    kernel: K,
    tree: &KdTree,
    camera: &Camera,
    rect: PixelRect,
    scheme: Scheme,
    scratch: ImageScratch,
    mut put: impl FnMut(u32, u32, &Hit),
) -> Result<CastStats, Error> {
    if scheme.needs_ropes() && !tree.info().has_ropes() {
        return Err(Error::NoRopes);
    }
    if !rect.fits(camera) {
        return Err(Error::InvalidParameter {
            name: "pixel rectangle",
        });
    }
    // The cast works in the rectangle's own coordinates; rays and `put`
    // take the camera's.
    let (w, h) = (rect.width, rect.height);
    let origin = [rect.x, rect.y];
    let mut put = |x: u32, y: u32, hit: &Hit| put(origin[0] + x, origin[1] + y, hit);
    if scratch.stack.len() < KD_STACK_LEN {
        return Err(Error::SliceTooSmall {
            slice: "stack",
            needed: KD_STACK_LEN,
            got: scratch.stack.len(),
        });
    }
    let (f, r, u) = camera.basis();
    let ray = |x: u32, y: u32| {
        let (x, y) = (origin[0] + x, origin[1] + y);
        camera.ray_in(f, r, u, x as f32 + 0.5, y as f32 + 0.5)
    };
    let mut st = CastStats::default();
    let stack = &mut *scratch.stack;
    match scheme {
        Scheme::Packets if cfg!(feature = "packets") => {
            let mut rays = [Ray::new(Vec3::ZERO, Vec3::X, 0.0, 0.0); LANES];
            let mut pixels = [(0u32, 0u32); LANES];
            let mut hits = [Hit::MISS; LANES];
            for y0 in (0..h).step_by(TILE.1 as usize) {
                for x0 in (0..w).step_by(TILE.0 as usize) {
                    let mut n = 0;
                    for y in y0..(y0 + TILE.1).min(h) {
                        for x in x0..(x0 + TILE.0).min(w) {
                            rays[n] = ray(x, y);
                            pixels[n] = (x, y);
                            n += 1;
                        }
                    }
                    kernel.packets(tree, &rays[..n], &mut hits[..n], stack, &mut st.trace);
                    for (&(x, y), hit) in pixels[..n].iter().zip(&hits[..n]) {
                        put(x, y, hit);
                    }
                    if st.trace.faults > 0 {
                        return Ok(st);
                    }
                }
            }
        }
        // Without the `packets` feature (small targets) the packet cast is
        // the hierarchical one.
        Scheme::Hierarchical | Scheme::Packets => {
            for y in 0..h {
                for x in 0..w {
                    let hit =
                        tree.intersect(&ray(x, y), Traversal::Hierarchical, stack, &mut st.trace);
                    put(x, y, &hit);
                    if st.trace.faults > 0 {
                        return Ok(st);
                    }
                }
            }
        }
        Scheme::Ropes => {
            for y in 0..h {
                for x in 0..w {
                    let hit = tree.intersect(&ray(x, y), Traversal::Ropes, stack, &mut st.trace);
                    put(x, y, &hit);
                    if st.trace.faults > 0 {
                        return Ok(st);
                    }
                }
            }
        }
        Scheme::Hlcts1d | Scheme::Hlcts2d => {
            return cast_bisection(kernel, tree, camera, rect, scheme, scratch, &mut put);
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
                // An image one pixel wide or high has no 2D window: its
                // scanlines are cast as SLCTS-1D casts them (each pixel of a
                // one-pixel-wide image is a corner).
                Scheme::Slcts2d { .. } if w < 2 || h < 2 => 1,
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
            // The sequence's share of `entries`, and the corners' paths'.
            let (seq_buf, path_buf) = scratch
                .entries
                .split_at_mut(scratch.entries.len() / (1 + CORNERS));
            let screen = ScreenBox::new(camera, (f, r, u), &tree.trace_box.aabb(), origin);
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
                    trace_recorded_on(tree, &ray(xi, yj), &mut hist, stack, &mut st.trace, false);
                    put(xi, yj, &hist.hit);
                    if st.trace.faults > 0 {
                        return Ok(st);
                    }
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
                        let seq = slcts::build(tree, &hs, &hits, &mut *seq_buf);
                        count_window(&mut st, &seq);
                        let (x0, x1) = (corners(w, n, i), corners(w, n, i + 1));
                        let inner = [x0 + 1, x1.saturating_sub(1).max(x0 + 1)];
                        if screen.as_ref().is_some_and(|b| b.misses(inner, [yj, yj])) {
                            // (`inner` reaches x1 when the window has no inner pixel.)
                            put_misses(&mut st.trace, &mut put, inner, [yj, yj], |x, _| x == x1);
                            continue;
                        }
                        let paths = seq.paths(&hs, &mut *path_buf);
                        let mut batch = Batch::new(kernel, tree, Shaft::Slcts(&seq), &paths);
                        for x in x0 + 1..x1 {
                            let nearest = far_half(x, x0, x1);
                            batch.push(x, yj, ray(x, yj), nearest, stack, &mut st.trace, &mut put);
                        }
                        batch.flush(stack, &mut st.trace, &mut put);
                        if st.trace.faults > 0 {
                            return Ok(st);
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
                        let seq = slcts::build(tree, &hs, &hits, &mut *seq_buf);
                        count_window(&mut st, &seq);
                        let (x0, x1) = (corners(w, n, i), corners(w, n, i + 1));
                        // Each pixel belongs to exactly one window: the first
                        // row and column of windows own their leading edges.
                        let y_from = if j == 1 { y_prev } else { y_prev + 1 };
                        let x_from = if i == 0 { x0 } else { x0 + 1 };
                        if screen
                            .as_ref()
                            .is_some_and(|b| b.misses([x_from, x1], [y_from, yj]))
                        {
                            let corner = |x, y| (y == y_prev || y == yj) && (x == x0 || x == x1);
                            put_misses(&mut st.trace, &mut put, [x_from, x1], [y_from, yj], corner);
                            continue;
                        }
                        let paths = seq.paths(&hs, &mut *path_buf);
                        let mut batch = Batch::new(kernel, tree, Shaft::Slcts(&seq), &paths);
                        for y in y_from..=yj {
                            let corner_row = y == y_prev || y == yj;
                            for x in x_from..=x1 {
                                if corner_row && (x == x0 || x == x1) {
                                    continue;
                                }
                                // Corners 0 and 1 on the top row, 2 and 3 below.
                                let nearest = far_half(x, x0, x1) + 2 * far_half(y, y_prev, yj);
                                batch.push(
                                    x,
                                    y,
                                    ray(x, y),
                                    nearest,
                                    stack,
                                    &mut st.trace,
                                    &mut put,
                                );
                            }
                        }
                        batch.flush(stack, &mut st.trace, &mut put);
                        if st.trace.faults > 0 {
                            return Ok(st);
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
    st.windows_entered += (seq.leaves == 0 && seq.entry.is_some_and(|e| e.node != 0)) as u64;
}

/// Where the scene's box lies on the image plane: the rectangle bounding
/// its corners' projections, in the camera's `sx`, `sy`, made only when the
/// whole box lies in front of the eye. A ray through the eye meets the box
/// only where its direction projects into that rectangle (the box's
/// projection is its corners' convex hull), so a window of pixels outside
/// it by [`SCREEN_MARGIN`] misses the box with every ray: what each ray's
/// own trace finds by its clip, with no step and no test.
struct ScreenBox {
    lo: [f32; 2],
    hi: [f32; 2],
    /// `2 / width`, `2 / height`: pixel to `sx`, `sy` as `ray_in` maps.
    per_pixel: [f32; 2],
    /// The camera's pixel that the cast's pixel (0, 0) is.
    origin: [u32; 2],
}

impl ScreenBox {
    fn new(
        camera: &Camera,
        (f, r, u): (Vec3, Vec3, Vec3),
        bx: &Aabb,
        origin: [u32; 2],
    ) -> Option<ScreenBox> {
        let eye = camera.from;
        let (r2, u2) = (r.length_squared(), u.length_squared());
        let corners = [0, 1, 2, 3, 4, 5, 6, 7].map(|k| {
            Vec3::new(
                if k & 1 == 0 { bx.min.x } else { bx.max.x },
                if k & 2 == 0 { bx.min.y } else { bx.max.y },
                if k & 4 == 0 { bx.min.z } else { bx.max.z },
            ) - eye
        });
        let far = corners.iter().fold(0.0f32, |m, c| m.max(c.length()));
        let (mut lo, mut hi) = ([f32::INFINITY; 2], [f32::NEG_INFINITY; 2]);
        for q in corners {
            let depth = q.dot(f);
            // (A box reaching to or behind the eye's plane: no rectangle.)
            if !(depth > SCREEN_NEAR_DEPTH * far) {
                return None;
            }
            let s = [q.dot(r) / r2 / depth, q.dot(u) / u2 / depth];
            for a in 0..2 {
                lo[a] = lo[a].min(s[a]);
                hi[a] = hi[a].max(s[a]);
            }
        }
        let finite = lo.iter().chain(&hi).all(|v| v.is_finite());
        (finite && f.is_finite() && eye.is_finite() && r2 > 0.0 && u2 > 0.0).then_some(ScreenBox {
            lo,
            hi,
            per_pixel: [
                2.0 / camera.width.max(1) as f32,
                2.0 / camera.height.max(1) as f32,
            ],
            origin,
        })
    }

    /// Whether every ray of the cast's pixels `xs` (first, last) by `ys`
    /// misses the box.
    fn misses(&self, xs: [u32; 2], ys: [u32; 2]) -> bool {
        let sx = |x: u32| ((self.origin[0] + x) as f32 + 0.5) * self.per_pixel[0] - 1.0;
        let sy = |y: u32| 1.0 - ((self.origin[1] + y) as f32 + 0.5) * self.per_pixel[1];
        // sx grows with x, sy falls with y.
        let (left, right, top, bottom) = (sx(xs[0]), sx(xs[1]), sy(ys[0]), sy(ys[1]));
        right < self.lo[0] - SCREEN_MARGIN
            || left > self.hi[0] + SCREEN_MARGIN
            || top < self.lo[1] - SCREEN_MARGIN
            || bottom > self.hi[1] + SCREEN_MARGIN
    }
}

/// Hands `put` a miss for every pixel of `xs` by `ys` (first, last) but
/// those `traced` already, and counts their rays: what the traces of rays
/// that miss the scene's box give (no step, no test).
fn put_misses(
    stats: &mut TraceStats,
    put: &mut impl FnMut(u32, u32, &Hit),
    xs: [u32; 2],
    ys: [u32; 2],
    traced: impl Fn(u32, u32) -> bool,
) {
    for y in ys[0]..=ys[1] {
        for x in xs[0]..=xs[1] {
            if !traced(x, y) {
                stats.rays += 1;
                put(x, y, &Hit::MISS);
            }
        }
    }
}

/// Rays an LCTS batch holds: a packet's worth, or one without the
/// `packets` feature (the rays go alone then; no room is kept for eight).
const BATCH: usize = if cfg!(feature = "packets") { LANES } else { 1 };

/// Pixels of one LCTS window waiting to be traced together
/// ([`super::window::trace`]), up to [`BATCH`].
struct Batch<'t, 's, 'p, K> {
    kernel: K,
    tree: &'t KdTree<'t>,
    shaft: Shaft<'s, 's>,
    paths: &'p Paths<'p>,
    rays: [Ray; BATCH],
    pixels: [(u32, u32); BATCH],
    nearest: [usize; BATCH],
    len: usize,
}

impl<'t, 's, 'p, K: Kernel> Batch<'t, 's, 'p, K> {
    fn new(kernel: K, tree: &'t KdTree<'t>, shaft: Shaft<'s, 's>, paths: &'p Paths<'p>) -> Self {
        Batch {
            kernel,
            tree,
            shaft,
            paths,
            rays: [Ray::new(Vec3::ZERO, Vec3::X, 0.0, 0.0); BATCH],
            pixels: [(0, 0); BATCH],
            nearest: [0; BATCH],
            len: 0,
        }
    }

    /// Adds pixel (x, y) with its ray and nearest corner; traces the batch
    /// when it is full.
    #[allow(clippy::too_many_arguments)]
    fn push(
        &mut self,
        x: u32,
        y: u32,
        ray: Ray,
        nearest: usize,
        stack: &mut [KdStackItem],
        stats: &mut TraceStats,
        put: &mut impl FnMut(u32, u32, &Hit),
    ) {
        self.rays[self.len] = ray;
        self.pixels[self.len] = (x, y);
        self.nearest[self.len] = nearest;
        self.len += 1;
        if self.len == BATCH {
            self.flush(stack, stats, put);
        }
    }

    /// Traces the pixels waiting and hands their hits to `put`.
    fn flush(
        &mut self,
        stack: &mut [KdStackItem],
        stats: &mut TraceStats,
        put: &mut impl FnMut(u32, u32, &Hit),
    ) {
        let n = self.len;
        let mut hits = [Hit::MISS; BATCH];
        self.kernel.trace(
            self.tree,
            self.shaft,
            self.paths,
            &self.rays[..n],
            &self.nearest[..n],
            &mut hits[..n],
            stack,
            stats,
        );
        for (&(x, y), hit) in self.pixels[..n].iter().zip(&hits) {
            put(x, y, hit);
        }
        self.len = 0;
    }
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

/// A ray whose history bounds a shaft of the bisection.
#[derive(Clone, Copy)]
struct Corner<'a> {
    ray: crate::Ray,
    records: Option<&'a [HistoryRecord]>,
    /// Its record per entry of the current rectangle's parent cut.
    source: Source<'a>,
    hit: Hit,
}

/// Buffers still free at a level of the bisection.
struct Free<'b> {
    records: &'b mut [HistoryRecord],
    starts: &'b mut [u32],
    hlcts: &'b mut [HlctsEntry],
}

struct Bisection<'t, 'o, K, F: FnMut(u32, u32, &Hit)> {
    kernel: K,
    tree: &'t KdTree<'t>,
    camera: &'t Camera,
    basis: (crate::Vec3, crate::Vec3, crate::Vec3),
    /// The camera's pixel that the cast's pixel (0, 0) is.
    origin: [u32; 2],
    /// Where the scene's box lies on the image (rectangles outside it are
    /// not traced, their rays missing it).
    screen: Option<ScreenBox>,
    cap: usize,
    per_cut: usize,
    /// Rectangles of at most this many pixels are cast from their cut
    /// without splitting further.
    leaf_pixels: u32,
    put: &'o mut F,
    /// The boundary rays' paths of the rectangle being cast.
    paths: &'o mut [u32],
    st: CastStats,
    /// One traversal stack for every ray of the cast.
    stack: &'o mut [KdStackItem],
}

impl<K: Kernel, F: FnMut(u32, u32, &Hit)> Bisection<'_, '_, K, F> {
    fn ray(&self, x: u32, y: u32) -> crate::Ray {
        let (f, r, u) = self.basis;
        let (x, y) = (self.origin[0] + x, self.origin[1] + y);
        self.camera.ray_in(f, r, u, x as f32 + 0.5, y as f32 + 0.5)
    }

    /// Traces the ray of pixel (x, y) through `cut` into the slot at the
    /// front of `free`, returning it as a corner of the children and what is left free.
    /// Never inlined: its recorded trace stays out of [`Bisection::shaft`]'s frame.
    #[inline(never)]
    fn split_ray<'a, 'b>(
        &mut self,
        x: u32,
        y: u32,
        cut: &hlcts::Hlcts,
        free: Free<'b>,
    ) -> (Corner<'b>, Free<'b>)
    where
        'b: 'a,
    {
        let (rec, records) = free.records.split_at_mut(self.cap);
        let (starts, rest_starts) = free.starts.split_at_mut(self.per_cut);
        let mut h = History::new(rec);
        let hit = hlcts::trace(
            self.tree,
            cut,
            &self.ray(x, y),
            Some((&mut h, &mut starts[..cut.len.max(1)])),
            self.stack,
            &mut self.st.trace,
        );
        (self.put)(x, y, &hit);
        let (len, overflow) = (h.len, h.overflow);
        let rec: &'b [HistoryRecord] = rec;
        let starts: &'b [u32] = starts;
        let corner = Corner {
            ray: self.ray(x, y),
            records: (!overflow).then(|| &rec[..len]),
            source: Source::Starts(starts),
            hit,
        };
        (
            corner,
            Free {
                records,
                starts: rest_starts,
                hlcts: free.hlcts,
            },
        )
    }

    /// The shaft of the rectangle (or interval) with `corners`, under `parent`.
    fn shaft(
        &mut self,
        rect: [u32; 4],
        corners: &[Corner],
        parent: &[HlctsEntry],
        depth: u32,
        free: Free,
    ) {
        let [x0, y0, x1, y1] = rect;
        if self.st.trace.faults > 0 {
            // A corrupt tree: the cast stops at its first fault.
            return;
        }
        if self
            .screen
            .as_ref()
            .is_some_and(|b| b.misses([x0, x1], [y0, y1]))
        {
            // Every ray of the rectangle misses the scene's box: its pixels
            // but the corners (traced already) get what their own traces
            // would, with no cut built for them.
            let corner =
                |x: u32, y: u32| (x == x0 || x == x1) && (y == y0 || y == y1 || corners.len() == 2);
            put_misses(&mut self.st.trace, self.put, [x0, x1], [y0, y1], corner);
            return;
        }
        let (cut_buf, hlcts_rest) = free.hlcts.split_at_mut(self.per_cut);
        let cut = cut_of(self.tree, parent, corners, cut_buf);
        self.st.windows += 1;
        self.st.windows_shared += (cut.leading_leaves > 0) as u64;
        self.st.windows_terminated += cut.termination.is_some() as u64;
        let free = Free {
            records: free.records,
            starts: free.starts,
            hlcts: hlcts_rest,
        };
        // Children name the rectangle's corners by their slot in this cut.
        let old = |j: usize| Corner {
            source: Source::Parent(j),
            ..corners[j]
        };
        let can_x = x1 - x0 >= 2;
        let can_y = y1 - y0 >= 2;
        if corners.len() == 2 {
            if !can_x {
                return;
            }
            if x1 - x0 < LEAF_PIXELS_1D {
                self.interval_from_cut(&cut, corners, [x0, x1], y0);
                return;
            }
            let xm = (x0 + x1) / 2;
            let (m, free) = self.split_ray(xm, y0, &cut, free);
            self.halves(
                [[x0, y0, xm, y0], [xm, y0, x1, y0]],
                [&[old(0), m], &[m, old(1)]],
                cut.as_slice(),
                depth,
                free,
            );
            return;
        }
        if !can_x && !can_y {
            return;
        }
        // A small rectangle is not cut further: its other pixels are traced
        // from this cut without histories (the cheap way, termination
        // object included); recording them only pays when they bound a
        // shaft of their own.
        if (x1 - x0 + 1) * (y1 - y0 + 1) <= self.leaf_pixels {
            self.rect_from_cut(&cut, corners, rect);
            return;
        }
        // Corners: 0 (x0, y0), 1 (x1, y0), 2 (x0, y1), 3 (x1, y1). The halves
        // share no pixel ([x0, xm] and [xm + 1, x1], or the same in y), so
        // every pixel is traced once: the first half takes rays a and b on
        // its new edge, the second c and d on its own. A new corner on an old
        // one's pixel (a half one pixel wide, a rectangle one pixel high) is
        // that corner, not traced again.
        let split_x = can_x && (!can_y || depth.is_multiple_of(2));
        let (xm, ym) = ((x0 + x1) / 2, (y0 + y1) / 2);
        let (pa, pb, pc, pd, halves) = if split_x {
            (
                (xm, y0),
                (xm, y1),
                (xm + 1, y0),
                (xm + 1, y1),
                [[x0, y0, xm, y1], [xm + 1, y0, x1, y1]],
            )
        } else {
            (
                (x0, ym),
                (x1, ym),
                (x0, ym + 1),
                (x1, ym + 1),
                [[x0, y0, x1, ym], [x0, ym + 1, x1, y1]],
            )
        };
        let (a, free) = self.split_ray(pa.0, pa.1, &cut, free);
        let (b, free) = if pb == pa {
            (a, free)
        } else {
            self.split_ray(pb.0, pb.1, &cut, free)
        };
        // The second half's near corners: old ones when it is one pixel thick.
        let (far_1, far_2) = if split_x { (1, 3) } else { (2, 3) };
        let on_old = if split_x { xm + 1 == x1 } else { ym + 1 == y1 };
        let (c, d, free) = if on_old {
            (old(far_1), old(far_2), free)
        } else {
            let (c, free) = self.split_ray(pc.0, pc.1, &cut, free);
            let (d, free) = if pd == pc {
                (c, free)
            } else {
                self.split_ray(pd.0, pd.1, &cut, free)
            };
            (c, d, free)
        };
        let (first, second) = if split_x {
            ([old(0), a, old(2), b], [c, old(1), d, old(3)])
        } else {
            ([old(0), old(1), a, b], [c, d, old(2), old(3)])
        };
        self.halves(halves, [&first, &second], cut.as_slice(), depth, free);
    }

    /// The pixels of interval `[x0, x1]` of row `y` between its two
    /// corners, traced from `cut` without histories. Never inlined, nor
    /// is [`Bisection::rect_from_cut`]: their batches and paths stay out
    /// of the recursive [`Bisection::shaft`]'s frame (on a Cortex-M4 that
    /// frame was 4.4 KiB, times the bisection's depth).
    #[inline(never)]
    fn interval_from_cut(&mut self, cut: &Hlcts, corners: &[Corner], [x0, x1]: [u32; 2], y: u32) {
        let hs = [corners[0].records, corners[1].records];
        let buf = core::mem::take(&mut self.paths);
        let paths = cut.paths(&hs, &mut *buf);
        let mut batch = Batch::new(self.kernel, self.tree, Shaft::Hlcts(cut), &paths);
        for x in x0 + 1..x1 {
            let nearest = far_half(x, x0, x1);
            let ray = self.ray(x, y);
            batch.push(x, y, ray, nearest, self.stack, &mut self.st.trace, self.put);
        }
        batch.flush(self.stack, &mut self.st.trace, self.put);
        self.paths = buf;
    }

    /// The pixels of rectangle `[x0, y0, x1, y1]` but its four corners,
    /// traced from `cut` without histories.
    #[inline(never)]
    fn rect_from_cut(&mut self, cut: &Hlcts, corners: &[Corner], [x0, y0, x1, y1]: [u32; 4]) {
        let corner = |x: u32, y: u32| (x == x0 || x == x1) && (y == y0 || y == y1);
        let hs: [Option<&[HistoryRecord]>; 4] = core::array::from_fn(|j| corners[j].records);
        let buf = core::mem::take(&mut self.paths);
        let paths = cut.paths(&hs, &mut *buf);
        let mut batch = Batch::new(self.kernel, self.tree, Shaft::Hlcts(cut), &paths);
        for y in y0..=y1 {
            for x in x0..=x1 {
                if !corner(x, y) {
                    // Corners 0 and 1 on the top row, 2 and 3 below.
                    let nearest = far_half(x, x0, x1) + 2 * far_half(y, y0, y1);
                    let ray = self.ray(x, y);
                    batch.push(x, y, ray, nearest, self.stack, &mut self.st.trace, self.put);
                }
            }
        }
        batch.flush(self.stack, &mut self.st.trace, self.put);
        self.paths = buf;
    }

    /// Casts the two halves of a split rectangle (or interval) under the
    /// same parent cut; the second reuses the buffers the first freed.
    fn halves(
        &mut self,
        rects: [[u32; 4]; 2],
        corners: [&[Corner]; 2],
        parent: &[HlctsEntry],
        depth: u32,
        free: Free,
    ) {
        let Free {
            records,
            starts,
            hlcts,
        } = free;
        self.shaft(
            rects[0],
            corners[0],
            parent,
            depth + 1,
            Free {
                records,
                starts,
                hlcts: &mut *hlcts,
            },
        );
        self.shaft(
            rects[1],
            corners[1],
            parent,
            depth + 1,
            Free {
                records,
                starts,
                hlcts,
            },
        );
    }
}

/// The cut of a shaft whose boundary rays are `corners`, under `parent`,
/// into `buf`. Never inlined: its boundary array ([`MAX_RAYS`] rays) stays
/// out of the recursive [`Bisection::shaft`]'s frame.
#[inline(never)]
fn cut_of<'b>(
    tree: &KdTree,
    parent: &[HlctsEntry],
    corners: &[Corner],
    buf: &'b mut [HlctsEntry],
) -> Hlcts<'b> {
    let bounds: [Boundary; MAX_RAYS] = core::array::from_fn(|j| {
        let c = corners.get(j).copied().unwrap_or(corners[0]);
        Boundary {
            ray: c.ray,
            records: c.records,
            source: c.source,
            hit: c.hit,
        }
    });
    hlcts::build(tree, parent, &bounds[..corners.len()], buf)
}

fn cast_bisection<K: Kernel>(
    kernel: K,
    tree: &KdTree,
    camera: &Camera,
    rect: PixelRect,
    scheme: Scheme,
    scratch: ImageScratch,
    put: &mut impl FnMut(u32, u32, &Hit),
) -> Result<CastStats, Error> {
    let (w, h) = (rect.width, rect.height);
    let origin = [rect.x, rect.y];
    // An image one pixel wide or high has no rectangle to bisect (its four
    // corners would be two pixels, each traced twice): its scanlines are
    // cast as HLCTS-1D casts them. HLCTS-2D's scratch holds HLCTS-1D's.
    let scheme = if w < 2 || h < 2 {
        Scheme::Hlcts1d
    } else {
        scheme
    };
    let levels = bisection_levels(w, h, scheme).unwrap_or(1);
    let slots = bisection_slots(levels);
    let cap = scratch.records.len() / slots;
    if cap == 0 {
        return Err(Error::SliceTooSmall {
            slice: "records",
            needed: slots,
            got: scratch.records.len(),
        });
    }
    let per_cut = MAX_RAYS * cap;
    if scratch.starts.len() < slots * per_cut {
        return Err(Error::SliceTooSmall {
            slice: "starts",
            needed: slots * per_cut,
            got: scratch.starts.len(),
        });
    }
    if scratch.hlcts.len() < (levels + 1) * per_cut {
        let needed = (levels + 1) * per_cut;
        return Err(Error::SliceTooSmall {
            slice: "hlcts",
            needed,
            got: scratch.hlcts.len(),
        });
    }
    let mut b = Bisection {
        kernel,
        tree,
        camera,
        basis: camera.basis(),
        origin,
        screen: ScreenBox::new(camera, camera.basis(), &tree.trace_box.aabb(), origin),
        cap,
        per_cut,
        leaf_pixels: LEAF_PIXELS,
        put,
        paths: scratch.entries,
        st: CastStats::default(),
        stack: scratch.stack,
    };
    let root = [hlcts::root_entry(tree)];
    let rows = if scheme == Scheme::Hlcts1d { h } else { 1 };
    let (records, starts, cuts) = (scratch.records, scratch.starts, scratch.hlcts);
    for y in 0..rows {
        let ys: &[u32] = if scheme == Scheme::Hlcts1d {
            &[y, y]
        } else {
            &[0, h - 1]
        };
        let pts = [(0, ys[0]), (w - 1, ys[0]), (0, ys[1]), (w - 1, ys[1])];
        let k = if scheme == Scheme::Hlcts1d {
            if w == 1 {
                1
            } else {
                2
            }
        } else {
            4
        };
        // The shaft's first corner rays, traced from the root.
        let (corner_recs, rest) = records.split_at_mut(4 * cap);
        let mut infos = [(0usize, false, Hit::MISS); 4];
        for (j, c) in corner_recs.chunks_mut(cap).enumerate().take(k) {
            let (x, yy) = pts[j];
            let mut hist = History::new(c);
            trace_recorded_on(
                tree,
                &b.ray(x, yy),
                &mut hist,
                b.stack,
                &mut b.st.trace,
                true,
            );
            (b.put)(x, yy, &hist.hit);
            infos[j] = (hist.len, hist.overflow, hist.hit);
            if b.st.trace.faults > 0 {
                return Ok(b.st);
            }
        }
        {
            let corner_recs: &[HistoryRecord] = corner_recs;
            let corners: [Corner; 4] = core::array::from_fn(|j| {
                let (len, overflow, hit) = infos[j];
                let recs = &corner_recs[j * cap..j * cap + len];
                Corner {
                    ray: b.ray(pts[j].0, pts[j].1),
                    records: (!overflow).then_some(recs),
                    source: Source::Parent(j),
                    hit,
                }
            });
            let rect = if scheme == Scheme::Hlcts1d {
                [0, y, w - 1, y]
            } else {
                [0, 0, w - 1, h - 1]
            };
            let free = Free {
                records: &mut *rest,
                starts: &mut *starts,
                hlcts: &mut *cuts,
            };
            if k > 1 {
                b.shaft(rect, &corners[..k], &root, 0, free);
            }
        }
        if b.st.trace.faults > 0 {
            break;
        }
    }
    Ok(b.st)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::inverse;
    use crate::rng::SplitMix64;

    /// A window [`ScreenBox`] skips holds no pixel whose ray meets the box
    /// (the clip the traversal makes), on random cameras and boxes; and
    /// the test skips windows (it is not vacuous).
    #[test]
    fn skipped_windows_hold_no_ray_into_the_box() {
        let mut g = SplitMix64(11);
        let mut v = |lo: f32, hi: f32| lo + (hi - lo) * g.next_f32();
        let (mut skipped, mut kept) = (0, 0);
        for _ in 0..200 {
            let c = Vec3::new(v(-5.0, 5.0), v(-5.0, 5.0), v(-5.0, 5.0));
            let e = Vec3::new(v(0.1, 3.0), v(0.1, 3.0), v(0.1, 3.0));
            let bx = Aabb {
                min: c - e,
                max: c + e,
            };
            let camera = Camera {
                from: Vec3::new(v(-12.0, 12.0), v(-12.0, 12.0), v(-12.0, 12.0)),
                at: c + Vec3::new(v(-6.0, 6.0), v(-6.0, 6.0), v(-6.0, 6.0)),
                up: Vec3::Y,
                angle_deg: v(20.0, 100.0),
                width: 48,
                height: 40,
            };
            if camera.fault().is_some() {
                continue;
            }
            let (f, r, u) = camera.basis();
            let Some(screen) = ScreenBox::new(&camera, (f, r, u), &bx, [0, 0]) else {
                continue;
            };
            for y0 in (0..camera.height - 4).step_by(4) {
                for x0 in (0..camera.width - 4).step_by(4) {
                    let (x1, y1) = (x0 + 4, y0 + 4);
                    if !screen.misses([x0, x1], [y0, y1]) {
                        kept += 1;
                        continue;
                    }
                    skipped += 1;
                    for y in y0..=y1 {
                        for x in x0..=x1 {
                            let ray = camera.ray_in(f, r, u, x as f32 + 0.5, y as f32 + 0.5);
                            let clip =
                                bx.clip_ray(ray.origin, inverse(ray.dir), ray.t_min, ray.t_max);
                            assert!(
                                clip.is_none(),
                                "pixel ({x}, {y}) of a skipped window meets the box"
                            );
                        }
                    }
                }
            }
        }
        assert!(
            skipped > 1000 && kept > 1000,
            "{skipped} skipped, {kept} kept"
        );
    }

    /// No rectangle when the box reaches behind the eye.
    #[test]
    fn a_box_around_the_eye_has_no_screen_rectangle() {
        let camera = Camera {
            from: Vec3::ZERO,
            at: Vec3::Z,
            up: Vec3::Y,
            angle_deg: 60.0,
            width: 8,
            height: 8,
        };
        let bx = Aabb {
            min: Vec3::splat(-1.0),
            max: Vec3::splat(1.0),
        };
        assert!(ScreenBox::new(&camera, camera.basis(), &bx, [0, 0]).is_none());
        let ahead = Aabb {
            min: Vec3::new(-1.0, -1.0, 4.0),
            max: Vec3::new(1.0, 1.0, 6.0),
        };
        assert!(ScreenBox::new(&camera, camera.basis(), &ahead, [0, 0]).is_some());
    }
}
