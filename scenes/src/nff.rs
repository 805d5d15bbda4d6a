//! NFF, read as a stream of tokens (generators write `c` on one line or
//! three) and written back so that reading what was written gives the same
//! scene. Errors name the line and column of the token that could not be read.

use std::fmt;

/// The `v` block: a pinhole camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    /// Eye.
    pub from: [f32; 3],
    /// Point looked at.
    pub at: [f32; 3],
    /// Up vector.
    pub up: [f32; 3],
    /// Field of view in degrees.
    pub angle: f32,
    /// Near clipping distance.
    pub hither: f32,
    /// Image size in pixels.
    pub resolution: [u32; 2],
}

impl View {
    /// The camera this view describes.
    pub fn camera(&self) -> coray::Camera {
        coray::Camera {
            from: self.from.into(),
            at: self.at.into(),
            up: self.up.into(),
            angle_deg: self.angle,
            width: self.resolution[0],
            height: self.resolution[1],
        }
    }
}

/// A positional light (`l`), with an optional colour.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    /// Position.
    pub pos: [f32; 3],
    /// Colour, when the file gives one.
    pub color: Option<[f32; 3]>,
}

/// A fill material (`f`): colour, diffuse and specular weights, Phong
/// exponent, transmittance and index of refraction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    /// RGB colour.
    pub color: [f32; 3],
    /// Diffuse weight.
    pub kd: f32,
    /// Specular weight (also the reflection weight in a Whitted tracer).
    pub ks: f32,
    /// Phong exponent.
    pub shine: f32,
    /// Transmittance.
    pub t: f32,
    /// Index of refraction.
    pub ior: f32,
}

/// One geometric object, with the index of the material in force when it
/// was read (`None` before the first `f`).
#[derive(Clone, Debug, PartialEq)]
pub enum Object {
    /// `s`: a sphere. A negative radius in the file means "inside visible";
    /// the radius here is its absolute value.
    Sphere {
        /// Centre.
        center: [f32; 3],
        /// Radius (absolute value of the file's).
        radius: f32,
        /// The file's radius was negative.
        inside_visible: bool,
        /// Material index.
        material: Option<usize>,
    },
    /// `c`: an open cone or cylinder.
    Cone {
        /// Base centre.
        base: [f32; 3],
        /// Base radius (absolute value).
        base_radius: f32,
        /// Apex centre.
        apex: [f32; 3],
        /// Apex radius (absolute value).
        apex_radius: f32,
        /// Either radius was negative in the file.
        inside_visible: bool,
        /// Material index.
        material: Option<usize>,
    },
    /// `p` or `pp`: a polygon, convex or concave, with vertex normals for `pp`.
    Polygon {
        /// Vertices in order.
        vertices: Vec<[f32; 3]>,
        /// Per-vertex normals (`pp` only).
        normals: Option<Vec<[f32; 3]>>,
        /// Material index.
        material: Option<usize>,
    },
}

/// A whole NFF file.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NffScene {
    /// The `v` block, if any.
    pub view: Option<View>,
    /// Background colour (`b`).
    pub background: Option<[f32; 3]>,
    /// Lights in file order.
    pub lights: Vec<Light>,
    /// Materials in file order (each `f` adds one).
    pub materials: Vec<Material>,
    /// Objects in file order.
    pub objects: Vec<Object>,
}

/// Where and why reading failed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct NffError {
    /// 1-based line.
    pub line: usize,
    /// 1-based column (in characters).
    pub col: usize,
    /// What was expected or found.
    pub msg: String,
}

impl fmt::Display for NffError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}: {}", self.line, self.col, self.msg)
    }
}

impl std::error::Error for NffError {}

/// A token and where it starts.
#[derive(Clone, Copy)]
struct Tok<'a> {
    text: &'a str,
    line: usize,
    col: usize,
}

/// A token as an error message shows it: at most [`SHOWN_CHARS`]
/// characters, and the token's length when it was cut, so that a hostile
/// token of any size makes a message of a few lines.
pub fn shown(token: &str) -> String {
    match token.char_indices().nth(SHOWN_CHARS) {
        None => token.to_string(),
        Some((cut, _)) => format!("{}... ({} bytes)", &token[..cut], token.len()),
    }
}

/// The characters of a token that [`shown`] keeps.
pub const SHOWN_CHARS: usize = 80;

/// Splits the input into whitespace-separated tokens as they are asked
/// for, dropping `#` comments, keeping positions: the reader holds a few
/// tokens at a time, never a list of the file's, so a file of any shape
/// costs its own size and no more.
struct Lexer<'a> {
    lines: std::iter::Enumerate<std::str::Lines<'a>>,
    /// The current line's code (before any `#`), its number, the byte
    /// offset and the 1-based column reached in it.
    code: &'a str,
    line: usize,
    byte: usize,
    col: usize,
    /// The token read ahead by [`Lexer::peek`].
    peeked: Option<Tok<'a>>,
    /// The line of the last token taken.
    last_line: usize,
    /// Where the input ends, once the last line has been reached.
    end: (usize, usize),
}

impl<'a> Lexer<'a> {
    fn new(src: &'a str) -> Lexer<'a> {
        Lexer {
            lines: src.lines().enumerate(),
            code: "",
            line: 0,
            byte: 0,
            col: 1,
            peeked: None,
            last_line: 0,
            end: (1, 1),
        }
    }

    /// The next token of the input, past the one read ahead.
    fn scan(&mut self) -> Option<Tok<'a>> {
        loop {
            let rest = &self.code[self.byte..];
            let mut chars = rest.char_indices().peekable();
            // Skip whitespace, counting columns.
            while let Some(&(_, ch)) = chars.peek() {
                if !ch.is_whitespace() {
                    break;
                }
                chars.next();
                self.col += 1;
            }
            if let Some(&(start, _)) = chars.peek() {
                let col = self.col;
                let mut stop = rest.len();
                for (bi, ch) in chars {
                    if ch.is_whitespace() {
                        stop = bi;
                        break;
                    }
                    self.col += 1;
                }
                self.byte += stop;
                return Some(Tok {
                    text: &rest[start..stop],
                    line: self.line,
                    col,
                });
            }
            let (li, line) = self.lines.next()?;
            self.code = line.find('#').map_or(line, |i| &line[..i]);
            self.line = li + 1;
            self.byte = 0;
            self.col = 1;
            self.end = (li + 1, line.chars().count() + 1);
        }
    }

    fn peek(&mut self) -> Option<Tok<'a>> {
        if self.peeked.is_none() {
            self.peeked = self.scan();
        }
        self.peeked
    }

    /// Takes the next token (the one [`Lexer::peek`] showed, if it did).
    fn take(&mut self) -> Option<Tok<'a>> {
        let t = self.peeked.take().or_else(|| self.scan())?;
        self.last_line = t.line;
        Some(t)
    }

    fn err_at(&self, t: Option<&Tok>, msg: String) -> NffError {
        match t {
            Some(t) => NffError {
                line: t.line,
                col: t.col,
                msg,
            },
            None => NffError {
                line: self.end.0,
                col: self.end.1,
                msg,
            },
        }
    }

    fn next(&mut self, what: &str) -> Result<Tok<'a>, NffError> {
        match self.take() {
            Some(t) => Ok(t),
            None => Err(self.err_at(None, format!("end of file where {what} was expected"))),
        }
    }

    fn keyword(&mut self, word: &str) -> Result<(), NffError> {
        let t = self.next(&format!("`{word}`"))?;
        if t.text != word {
            let (line, col, found) = (t.line, t.col, shown(t.text));
            return Err(NffError {
                line,
                col,
                msg: format!("expected `{word}`, found `{found}`"),
            });
        }
        Ok(())
    }

    fn float(&mut self, what: &str) -> Result<f32, NffError> {
        let t = self.next(what)?;
        match t.text.parse::<f32>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => {
                let (line, col, found) = (t.line, t.col, shown(t.text));
                Err(NffError {
                    line,
                    col,
                    msg: format!("expected {what} (a finite number), found `{found}`"),
                })
            }
        }
    }

    fn vec3(&mut self, what: &str) -> Result<[f32; 3], NffError> {
        Ok([self.float(what)?, self.float(what)?, self.float(what)?])
    }

    /// An image side: 1 to the core's limit, the same as every other
    /// resolution the project takes.
    fn side(&mut self, what: &str) -> Result<u32, NffError> {
        let t = self.next(what)?;
        let max = coray::limits::MAX_IMAGE_SIDE;
        match t.text.parse::<u32>() {
            Ok(v) if (1..=max).contains(&v) => Ok(v),
            _ => {
                let (line, col, found) = (t.line, t.col, shown(t.text));
                Err(NffError {
                    line,
                    col,
                    msg: format!("expected {what} (1 to {max} pixels), found `{found}`"),
                })
            }
        }
    }

    fn count(&mut self, what: &str, max: u64) -> Result<usize, NffError> {
        let t = self.next(what)?;
        match t.text.parse::<u64>() {
            Ok(v) if v <= max => Ok(v as usize),
            _ => {
                let (line, col, found) = (t.line, t.col, shown(t.text));
                Err(NffError {
                    line,
                    col,
                    msg: format!("expected {what} (a whole number up to {max}), found `{found}`"),
                })
            }
        }
    }
}

/// Vertices a polygon may have: far more than any real file, few enough
/// that a hostile count cannot make the reader reserve much memory.
const MAX_POLYGON_VERTICES: u64 = 1 << 20;

impl NffScene {
    /// Reads NFF text. Never panics, whatever the input.
    pub fn parse(src: &str) -> Result<NffScene, NffError> {
        let mut lx = Lexer::new(src);
        let mut s = NffScene::default();
        while let Some(t) = lx.take() {
            let (line, col) = (t.line, t.col);
            let cmd = t.text;
            let material = s.materials.len().checked_sub(1);
            match cmd {
                "v" => {
                    lx.keyword("from")?;
                    let from = lx.vec3("a `from` coordinate")?;
                    lx.keyword("at")?;
                    let at = lx.vec3("an `at` coordinate")?;
                    lx.keyword("up")?;
                    let up = lx.vec3("an `up` coordinate")?;
                    lx.keyword("angle")?;
                    let angle = lx.float("the view angle")?;
                    lx.keyword("hither")?;
                    let hither = lx.float("the hither distance")?;
                    lx.keyword("resolution")?;
                    let resolution = [lx.side("the x resolution")?, lx.side("the y resolution")?];
                    let view = View {
                        from,
                        at,
                        up,
                        angle,
                        hither,
                        resolution,
                    };
                    if let Some(why) = view.camera().fault() {
                        return Err(NffError {
                            line,
                            col,
                            msg: format!("a view the camera cannot use: {why}"),
                        });
                    }
                    s.view = Some(view);
                }
                "b" => s.background = Some(lx.vec3("a background colour component")?),
                "l" => {
                    let pos = lx.vec3("a light coordinate")?;
                    // An optional colour: three numbers on the same line.
                    let line_of_pos = lx.last_line;
                    let color = if lx
                        .peek()
                        .is_some_and(|t| t.line == line_of_pos && t.text.parse::<f32>().is_ok())
                    {
                        Some(lx.vec3("a light colour component")?)
                    } else {
                        None
                    };
                    s.lights.push(Light { pos, color });
                }
                "f" => {
                    let color = lx.vec3("a fill colour component")?;
                    let m = Material {
                        color,
                        kd: lx.float("Kd")?,
                        ks: lx.float("Ks")?,
                        shine: lx.float("Shine")?,
                        t: lx.float("T")?,
                        ior: lx.float("the index of refraction")?,
                    };
                    s.materials.push(m);
                }
                "s" => {
                    let center = lx.vec3("a sphere centre coordinate")?;
                    let r = lx.float("the sphere radius")?;
                    s.objects.push(Object::Sphere {
                        center,
                        radius: r.abs(),
                        inside_visible: r < 0.0,
                        material,
                    });
                }
                "c" => {
                    let base = lx.vec3("a cone base coordinate")?;
                    let r0 = lx.float("the cone base radius")?;
                    let apex = lx.vec3("a cone apex coordinate")?;
                    let r1 = lx.float("the cone apex radius")?;
                    s.objects.push(Object::Cone {
                        base,
                        base_radius: r0.abs(),
                        apex,
                        apex_radius: r1.abs(),
                        inside_visible: r0 < 0.0 || r1 < 0.0,
                        material,
                    });
                }
                "p" | "pp" => {
                    let n = lx.count("the polygon's vertex count", MAX_POLYGON_VERTICES)?;
                    if n < 3 {
                        return Err(NffError {
                            line,
                            col,
                            msg: format!("a polygon needs at least 3 vertices, this one has {n}"),
                        });
                    }
                    let mut vertices = Vec::with_capacity(n.min(1024));
                    let mut normals = (cmd == "pp").then(|| Vec::with_capacity(n.min(1024)));
                    for _ in 0..n {
                        vertices.push(lx.vec3("a vertex coordinate")?);
                        if let Some(ns) = normals.as_mut() {
                            ns.push(lx.vec3("a vertex normal component")?);
                        }
                    }
                    let work = n as u64 * crate::triangulate::reflex_count(&vertices) as u64;
                    if work > crate::triangulate::MAX_CLIP_WORK {
                        return Err(NffError {
                            line,
                            col,
                            msg: format!(
                                "a polygon of {n} vertices with {} concave corners: \
                                 triangulating it takes vertices x concave corners = {work} \
                                 steps, more than the limit {}",
                                work / n as u64,
                                crate::triangulate::MAX_CLIP_WORK
                            ),
                        });
                    }
                    s.objects.push(Object::Polygon {
                        vertices,
                        normals,
                        material,
                    });
                }
                other => {
                    return Err(NffError {
                        line,
                        col,
                        msg: format!("unknown command `{}`", shown(other)),
                    });
                }
            }
        }
        Ok(s)
    }

    /// NFF text for this scene. Numbers are written in Rust's shortest
    /// round-trip form, so [`NffScene::parse`] gives back an equal scene.
    pub fn to_nff(&self) -> String {
        use std::fmt::Write;
        let mut o = String::new();
        let v3 = |a: &[f32; 3]| format!("{} {} {}", a[0], a[1], a[2]);
        if let Some(v) = &self.view {
            let _ = writeln!(
                o,
                "v\nfrom {}\nat {}\nup {}\nangle {}\nhither {}\nresolution {} {}",
                v3(&v.from),
                v3(&v.at),
                v3(&v.up),
                v.angle,
                v.hither,
                v.resolution[0],
                v.resolution[1]
            );
        }
        if let Some(b) = &self.background {
            let _ = writeln!(o, "b {}", v3(b));
        }
        for l in &self.lights {
            match &l.color {
                Some(c) => writeln!(o, "l {} {}", v3(&l.pos), v3(c)),
                None => writeln!(o, "l {}", v3(&l.pos)),
            }
            .ok();
        }
        // Each `f` makes a new material and the objects after it use it, so
        // materials are written in index order, each just before the first
        // object that uses it; that gives back the same list. An object whose
        // material comes earlier than one already written (possible only in
        // scenes built in code) gets its `f` written again.
        let mut next = 0usize;
        let mut file_current: Option<usize> = None;
        let write_f = |o: &mut String, i: usize| {
            let f = &self.materials[i];
            let _ = writeln!(
                o,
                "f {} {} {} {} {} {}",
                v3(&f.color),
                f.kd,
                f.ks,
                f.shine,
                f.t,
                f.ior
            );
        };
        let mut set_material = |o: &mut String, m: Option<usize>| {
            if let Some(i) = m {
                while next <= i && next < self.materials.len() {
                    write_f(o, next);
                    file_current = Some(next);
                    next += 1;
                }
                if file_current != Some(i) {
                    write_f(o, i);
                    file_current = Some(i);
                }
            }
        };
        for obj in &self.objects {
            set_material(&mut o, obj.material());
            match obj {
                Object::Sphere {
                    center,
                    radius,
                    inside_visible,
                    ..
                } => {
                    let r = if *inside_visible { -radius } else { *radius };
                    let _ = writeln!(o, "s {} {}", v3(center), r);
                }
                Object::Cone {
                    base,
                    base_radius,
                    apex,
                    apex_radius,
                    inside_visible,
                    ..
                } => {
                    let sign = if *inside_visible { -1.0 } else { 1.0 };
                    let _ = writeln!(
                        o,
                        "c\n{} {}\n{} {}",
                        v3(base),
                        sign * base_radius,
                        v3(apex),
                        sign * apex_radius
                    );
                }
                Object::Polygon {
                    vertices, normals, ..
                } => match normals {
                    Some(ns) => {
                        let _ = writeln!(o, "pp {}", vertices.len());
                        for (p, n) in vertices.iter().zip(ns) {
                            let _ = writeln!(o, "{} {}", v3(p), v3(n));
                        }
                    }
                    None => {
                        let _ = writeln!(o, "p {}", vertices.len());
                        for p in vertices {
                            let _ = writeln!(o, "{}", v3(p));
                        }
                    }
                },
            }
        }
        for i in next..self.materials.len() {
            write_f(&mut o, i);
        }
        o
    }
}

impl Object {
    /// The material index in force for this object.
    pub fn material(&self) -> Option<usize> {
        match self {
            Object::Sphere { material, .. }
            | Object::Cone { material, .. }
            | Object::Polygon { material, .. } => *material,
        }
    }
}
