//! Line charts as PNG, drawn by hand (no font or plotting dependency): a
//! grid of panels, each with log-scaled axes, one polyline per series, a
//! legend. Text uses a built-in 5 x 7 pixel font, upper case.

/// One curve: a name and (x, y) points, drawn in order.
pub struct Curve {
    pub name: String,
    pub points: Vec<(f64, f64)>,
}

/// One chart of the grid.
pub struct Panel {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub curves: Vec<Curve>,
}

const COLOURS: [[u8; 3]; 8] = [
    [31, 119, 180],
    [255, 127, 14],
    [44, 160, 44],
    [214, 39, 40],
    [148, 103, 189],
    [140, 86, 75],
    [227, 119, 194],
    [127, 127, 127],
];

/// 5 x 7 glyphs, rows top to bottom, `#` set.
fn glyph(c: char) -> [&'static str; 7] {
    match c {
        '0' => [
            ".###.", "#...#", "#..##", "#.#.#", "##..#", "#...#", ".###.",
        ],
        '1' => [
            "..#..", ".##..", "..#..", "..#..", "..#..", "..#..", ".###.",
        ],
        '2' => [
            ".###.", "#...#", "....#", "...#.", "..#..", ".#...", "#####",
        ],
        '3' => [
            "####.", "....#", "....#", ".###.", "....#", "....#", "####.",
        ],
        '4' => [
            "...#.", "..##.", ".#.#.", "#..#.", "#####", "...#.", "...#.",
        ],
        '5' => [
            "#####", "#....", "####.", "....#", "....#", "#...#", ".###.",
        ],
        '6' => [
            ".###.", "#....", "#....", "####.", "#...#", "#...#", ".###.",
        ],
        '7' => [
            "#####", "....#", "...#.", "..#..", ".#...", ".#...", ".#...",
        ],
        '8' => [
            ".###.", "#...#", "#...#", ".###.", "#...#", "#...#", ".###.",
        ],
        '9' => [
            ".###.", "#...#", "#...#", ".####", "....#", "....#", ".###.",
        ],
        'A' => [
            ".###.", "#...#", "#...#", "#####", "#...#", "#...#", "#...#",
        ],
        'B' => [
            "####.", "#...#", "#...#", "####.", "#...#", "#...#", "####.",
        ],
        'C' => [
            ".###.", "#...#", "#....", "#....", "#....", "#...#", ".###.",
        ],
        'D' => [
            "####.", "#...#", "#...#", "#...#", "#...#", "#...#", "####.",
        ],
        'E' => [
            "#####", "#....", "#....", "####.", "#....", "#....", "#####",
        ],
        'F' => [
            "#####", "#....", "#....", "####.", "#....", "#....", "#....",
        ],
        'G' => [
            ".###.", "#...#", "#....", "#.###", "#...#", "#...#", ".####",
        ],
        'H' => [
            "#...#", "#...#", "#...#", "#####", "#...#", "#...#", "#...#",
        ],
        'I' => [
            ".###.", "..#..", "..#..", "..#..", "..#..", "..#..", ".###.",
        ],
        'J' => [
            "..###", "...#.", "...#.", "...#.", "...#.", "#..#.", ".##..",
        ],
        'K' => [
            "#...#", "#..#.", "#.#..", "##...", "#.#..", "#..#.", "#...#",
        ],
        'L' => [
            "#....", "#....", "#....", "#....", "#....", "#....", "#####",
        ],
        'M' => [
            "#...#", "##.##", "#.#.#", "#.#.#", "#...#", "#...#", "#...#",
        ],
        'N' => [
            "#...#", "#...#", "##..#", "#.#.#", "#..##", "#...#", "#...#",
        ],
        'O' => [
            ".###.", "#...#", "#...#", "#...#", "#...#", "#...#", ".###.",
        ],
        'P' => [
            "####.", "#...#", "#...#", "####.", "#....", "#....", "#....",
        ],
        'Q' => [
            ".###.", "#...#", "#...#", "#...#", "#.#.#", "#..#.", ".##.#",
        ],
        'R' => [
            "####.", "#...#", "#...#", "####.", "#.#..", "#..#.", "#...#",
        ],
        'S' => [
            ".####", "#....", "#....", ".###.", "....#", "....#", "####.",
        ],
        'T' => [
            "#####", "..#..", "..#..", "..#..", "..#..", "..#..", "..#..",
        ],
        'U' => [
            "#...#", "#...#", "#...#", "#...#", "#...#", "#...#", ".###.",
        ],
        'V' => [
            "#...#", "#...#", "#...#", "#...#", "#...#", ".#.#.", "..#..",
        ],
        'W' => [
            "#...#", "#...#", "#...#", "#.#.#", "#.#.#", "#.#.#", ".#.#.",
        ],
        'X' => [
            "#...#", "#...#", ".#.#.", "..#..", ".#.#.", "#...#", "#...#",
        ],
        'Y' => [
            "#...#", "#...#", ".#.#.", "..#..", "..#..", "..#..", "..#..",
        ],
        'Z' => [
            "#####", "....#", "...#.", "..#..", ".#...", "#....", "#####",
        ],
        '.' => [
            ".....", ".....", ".....", ".....", ".....", ".##..", ".##..",
        ],
        ',' => [
            ".....", ".....", ".....", ".....", ".##..", "..#..", ".#...",
        ],
        '-' => [
            ".....", ".....", ".....", "#####", ".....", ".....", ".....",
        ],
        '+' => [
            ".....", "..#..", "..#..", "#####", "..#..", "..#..", ".....",
        ],
        '*' => [
            ".....", "#.#.#", ".###.", "#####", ".###.", "#.#.#", ".....",
        ],
        ':' => [
            ".....", ".##..", ".##..", ".....", ".##..", ".##..", ".....",
        ],
        '/' => [
            "....#", "....#", "...#.", "..#..", ".#...", "#....", "#....",
        ],
        '(' => [
            "...#.", "..#..", ".#...", ".#...", ".#...", "..#..", "...#.",
        ],
        ')' => [
            ".#...", "..#..", "...#.", "...#.", "...#.", "..#..", ".#...",
        ],
        '=' => [
            ".....", ".....", "#####", ".....", "#####", ".....", ".....",
        ],
        '%' => [
            "##...", "##..#", "...#.", "..#..", ".#...", "#..##", "...##",
        ],
        '^' => [
            "..#..", ".#.#.", "#...#", ".....", ".....", ".....", ".....",
        ],
        'x' => [
            ".....", ".....", "#...#", ".#.#.", "..#..", ".#.#.", "#...#",
        ],
        _ => [
            ".....", ".....", ".....", ".....", ".....", ".....", ".....",
        ],
    }
}

struct Canvas {
    w: usize,
    h: usize,
    rgb: Vec<u8>,
}

impl Canvas {
    fn new(w: usize, h: usize) -> Canvas {
        Canvas {
            w,
            h,
            rgb: vec![255; w * h * 3],
        }
    }

    fn dot(&mut self, x: i64, y: i64, c: [u8; 3]) {
        if x >= 0 && y >= 0 && (x as usize) < self.w && (y as usize) < self.h {
            let i = 3 * (y as usize * self.w + x as usize);
            self.rgb[i..i + 3].copy_from_slice(&c);
        }
    }

    /// A line `width` pixels thick (Bresenham, stamped).
    fn line(&mut self, (x0, y0): (i64, i64), (x1, y1): (i64, i64), c: [u8; 3], width: i64) {
        let (dx, dy) = ((x1 - x0).abs(), -(y1 - y0).abs());
        let (sx, sy) = (if x0 < x1 { 1 } else { -1 }, if y0 < y1 { 1 } else { -1 });
        let (mut x, mut y, mut err) = (x0, y0, dx + dy);
        loop {
            for a in 0..width {
                for b in 0..width {
                    self.dot(x + a - width / 2, y + b - width / 2, c);
                }
            }
            if x == x1 && y == y1 {
                break;
            }
            let e2 = 2 * err;
            if e2 >= dy {
                err += dy;
                x += sx;
            }
            if e2 <= dx {
                err += dx;
                y += sy;
            }
        }
    }

    /// Text at scale `s` (each font pixel s x s), left edge at `x`.
    fn text(&mut self, x: i64, y: i64, t: &str, s: i64, c: [u8; 3]) {
        for (k, ch) in t.chars().enumerate() {
            let ch = if ch == 'x' {
                ch
            } else {
                ch.to_ascii_uppercase()
            };
            for (row, bits) in glyph(ch).iter().enumerate() {
                for (col, b) in bits.bytes().enumerate() {
                    if b == b'#' {
                        for a in 0..s {
                            for bb in 0..s {
                                let px = x + (k as i64 * 6 + col as i64) * s + a;
                                self.dot(px, y + row as i64 * s + bb, c);
                            }
                        }
                    }
                }
            }
        }
    }

    /// Text rotated a quarter turn (reading upwards), bottom end at `y`.
    fn text_up(&mut self, x: i64, y: i64, t: &str, s: i64, c: [u8; 3]) {
        for (k, ch) in t.chars().enumerate() {
            for (row, bits) in glyph(ch.to_ascii_uppercase()).iter().enumerate() {
                for (col, b) in bits.bytes().enumerate() {
                    if b == b'#' {
                        for a in 0..s {
                            for bb in 0..s {
                                let px = x + row as i64 * s + a;
                                let py = y - (k as i64 * 6 + col as i64) * s - bb;
                                self.dot(px, py, c);
                            }
                        }
                    }
                }
            }
        }
    }
}

fn text_width(t: &str, s: i64) -> i64 {
    t.chars().count() as i64 * 6 * s
}

/// A short label for a tick value.
fn tick_label(v: f64) -> String {
    if v >= 10.0 {
        format!("{:.0}", v)
    } else if v >= 1.0 {
        format!("{:.1}", v)
    } else if v >= 0.01 {
        format!("{:.2}", v)
    } else {
        format!("{:.0e}", v)
    }
}

/// Ticks at 1, 2, 5 times powers of ten within `[lo, hi]` (log axis).
fn log_ticks(lo: f64, hi: f64) -> Vec<f64> {
    let mut t = Vec::new();
    let mut p = 10f64.powf(lo.log10().floor());
    while p <= hi * 1.0001 {
        for m in [1.0, 2.0, 5.0] {
            let v = p * m;
            if v >= lo * 0.9999 && v <= hi * 1.0001 {
                t.push(v);
            }
        }
        p *= 10.0;
    }
    if t.len() > 7 {
        t.retain(|v| (v.log10().fract().abs() < 1e-9) || (v.log10().fract() - 1.0).abs() < 1e-9);
    }
    if t.len() < 2 {
        // A narrow range: label its ends instead.
        t = vec![lo, hi];
    }
    t
}

fn draw_panel(cv: &mut Canvas, p: &Panel, ox: i64, oy: i64, pw: i64, ph: i64) {
    let (left, right, top, bottom) = (70i64, 12i64, 30i64, 44i64);
    let (x0, y0, x1, y1) = (ox + left, oy + top, ox + pw - right, oy + ph - bottom);
    let pts = || p.curves.iter().flat_map(|c| c.points.iter());
    let finite = |v: f64| v.is_finite() && v > 0.0;
    let xs: Vec<f64> = pts().map(|q| q.0).filter(|v| finite(*v)).collect();
    let ys: Vec<f64> = pts().map(|q| q.1).filter(|v| finite(*v)).collect();
    cv.text(ox + left, oy + 10, &p.title, 1, [0, 0, 0]);
    if xs.is_empty() || ys.is_empty() {
        return;
    }
    let (mut xlo, mut xhi) = (
        xs.iter().cloned().fold(f64::MAX, f64::min),
        xs.iter().cloned().fold(0.0, f64::max),
    );
    let (mut ylo, mut yhi) = (
        ys.iter().cloned().fold(f64::MAX, f64::min),
        ys.iter().cloned().fold(0.0, f64::max),
    );
    if xhi <= xlo * 1.01 {
        (xlo, xhi) = (xlo / 2.0, xhi * 2.0);
    }
    if yhi <= ylo * 1.01 {
        (ylo, yhi) = (ylo / 2.0, yhi * 2.0);
    }
    let (ylo, yhi) = (ylo / 1.15, yhi * 1.15);
    let map_x = |v: f64| {
        x0 + ((v.log10() - xlo.log10()) / (xhi.log10() - xlo.log10()) * (x1 - x0) as f64) as i64
    };
    let map_y = |v: f64| {
        y1 - ((v.log10() - ylo.log10()) / (yhi.log10() - ylo.log10()) * (y1 - y0) as f64) as i64
    };
    let grey = [200, 200, 200];
    for t in log_ticks(xlo, xhi) {
        let x = map_x(t);
        cv.line((x, y0), (x, y1), grey, 1);
        let l = tick_label(t);
        cv.text(x - text_width(&l, 1) / 2, y1 + 6, &l, 1, [0, 0, 0]);
    }
    for t in log_ticks(ylo, yhi) {
        let y = map_y(t);
        cv.line((x0, y), (x1, y), grey, 1);
        let l = tick_label(t);
        cv.text(x0 - 6 - text_width(&l, 1), y - 3, &l, 1, [0, 0, 0]);
    }
    cv.line((x0, y0), (x0, y1), [0, 0, 0], 1);
    cv.line((x0, y1), (x1, y1), [0, 0, 0], 1);
    cv.text(
        x0 + (x1 - x0 - text_width(&p.x_label, 1)) / 2,
        y1 + 22,
        &p.x_label,
        1,
        [0, 0, 0],
    );
    cv.text_up(
        ox + 6,
        y1 - (y1 - y0 - text_width(&p.y_label, 1)) / 2,
        &p.y_label,
        1,
        [0, 0, 0],
    );
    for (k, c) in p.curves.iter().enumerate() {
        let col = COLOURS[k % COLOURS.len()];
        let q: Vec<(i64, i64)> = c
            .points
            .iter()
            .filter(|(x, y)| finite(*x) && finite(*y))
            .map(|&(x, y)| (map_x(x), map_y(y)))
            .collect();
        for w in q.windows(2) {
            cv.line(w[0], w[1], col, 2);
        }
        for &pt in &q {
            cv.line((pt.0 - 2, pt.1), (pt.0 + 2, pt.1), col, 3);
        }
    }
}

/// Draws `panels` in a grid of `cols` columns (each `pw` x `ph` pixels)
/// under a title and over a legend of the first panel's curve names, and
/// writes the PNG.
pub fn write(
    path: &std::path::Path,
    title: &str,
    panels: &[Panel],
    cols: usize,
    pw: usize,
    ph: usize,
) -> Result<(), String> {
    let cols = cols.max(1);
    let rows = panels.len().div_ceil(cols);
    let (head, legend) = (40usize, 36usize);
    let (w, h) = (cols * pw, head + rows * ph + legend);
    let mut cv = Canvas::new(w, h);
    cv.text(10, 10, title, 3, [0, 0, 0]);
    for (i, p) in panels.iter().enumerate() {
        let (cx, cy) = ((i % cols * pw) as i64, (head + i / cols * ph) as i64);
        draw_panel(&mut cv, p, cx, cy, pw as i64, ph as i64);
    }
    if let Some(p) = panels.first() {
        let mut x = 20i64;
        let y = (h - legend + 12) as i64;
        for (k, c) in p.curves.iter().enumerate() {
            let col = COLOURS[k % COLOURS.len()];
            cv.line((x, y + 6), (x + 30, y + 6), col, 4);
            cv.text(x + 38, y, &c.name, 2, [0, 0, 0]);
            x += 38 + text_width(&c.name, 2) + 30;
        }
    }
    crate::render::write_image(path, w as u32, h as u32, &cv.rgb)
}
