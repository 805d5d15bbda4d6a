//! Triangle meshes from Wavefront OBJ and PLY files (through the tobj and
//! ply-rs-bw crates), as scenes: polygons split into fans, every face with
//! the default material, the camera framed from the mesh's box (the files
//! carry none) and one light above and behind it. Malformed input is an
//! error with a message, never a panic.

use crate::mesh::{framing_view, SceneMesh, DEFAULT_MATERIAL};
use coray::Vec3;
use std::io::BufRead;
use std::path::Path;

/// Which reader a path takes, by its extension (case aside).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshFormat {
    /// Wavefront OBJ (`.obj`).
    Obj,
    /// Stanford PLY, ASCII or binary (`.ply`).
    Ply,
}

impl MeshFormat {
    /// The format of `path`, or `None` for another extension.
    pub fn of(path: &Path) -> Option<MeshFormat> {
        match path.extension()?.to_str()?.to_ascii_lowercase().as_str() {
            "obj" => Some(MeshFormat::Obj),
            "ply" => Some(MeshFormat::Ply),
            _ => None,
        }
    }
}

/// Reads the mesh at `path` (OBJ or PLY by its extension).
pub fn read_mesh(path: &Path) -> Result<SceneMesh, String> {
    let f = MeshFormat::of(path)
        .ok_or_else(|| format!("{}: not a mesh file (.obj or .ply)", path.display()))?;
    let file = std::fs::File::open(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut r = std::io::BufReader::new(file);
    let (vertices, triangles) = match f {
        MeshFormat::Obj => obj(&mut r),
        MeshFormat::Ply => ply(&mut r),
    }
    .map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(from_triangles(vertices, triangles))
}

/// A scene of `triangles` over `vertices` with smooth vertex normals, the
/// default material, a framed camera and one white light.
pub fn from_triangles(vertices: Vec<[f32; 3]>, triangles: Vec<[u32; 3]>) -> SceneMesh {
    let mut normals = vec![Vec3::ZERO; vertices.len()];
    for t in &triangles {
        let [a, b, c] = t.map(|i| Vec3::from(vertices[i as usize]));
        let n = (b - a).cross(c - a);
        if n.is_finite() {
            for &i in t {
                normals[i as usize] += n;
            }
        }
    }
    let mut m = SceneMesh {
        normals: normals
            .into_iter()
            .map(|n| n.normalize_or_zero().to_array())
            .collect(),
        has_normal: vec![false; vertices.len()],
        prim_material: vec![0; triangles.len()],
        materials: vec![DEFAULT_MATERIAL],
        vertices,
        triangles,
        ..SceneMesh::default()
    };
    m.counts.polygons = m.triangles.len();
    m.counts.triangles = m.triangles.len();
    m.counts.lights = 1;
    let view = framing_view(&m.scene().bounds());
    let (from, at) = (Vec3::from(view.from), Vec3::from(view.at));
    // Up and to the side of the camera, as far again from the mesh.
    let light = at + (from - at) * 1.5 + Vec3::new(0.0, (from - at).length(), 0.0);
    m.lights = vec![(light, Vec3::ONE)];
    m.camera = view.camera();
    m.hither = view.hither;
    m
}

/// A mesh file's vertex positions and triangles.
type Arrays = (Vec<[f32; 3]>, Vec<[u32; 3]>);

/// A polygon's vertex indices as a fan of triangles, each index checked
/// against `vertex_count`.
fn fan(
    face: impl ExactSizeIterator<Item = u64>,
    vertex_count: usize,
    out: &mut Vec<[u32; 3]>,
) -> Result<(), String> {
    let idx: Vec<u64> = face.collect();
    if idx.len() < 3 {
        return Ok(());
    }
    if let Some(&bad) = idx
        .iter()
        .find(|&&i| i as usize >= vertex_count || i > u32::MAX as u64)
    {
        return Err(format!(
            "a face names vertex {bad}, past the {vertex_count} vertices"
        ));
    }
    for k in 1..idx.len() - 1 {
        out.push([idx[0] as u32, idx[k] as u32, idx[k + 1] as u32]);
    }
    Ok(())
}

/// An OBJ's positions and faces (every object and group of the file;
/// polygons as fans; `v/vt/vn` faces by their positions).
fn obj(r: &mut impl BufRead) -> Result<Arrays, String> {
    let opts = tobj::LoadOptions {
        single_index: false,
        triangulate: false,
        ignore_points: true,
        ignore_lines: true,
    };
    // Materials are not read: every face takes the default one.
    let (models, _) = tobj::load_obj_buf(r, &opts, |_| Err(tobj::LoadError::GenericFailure))
        .map_err(|e| format!("not a Wavefront OBJ mesh: {e}"))?;
    let (mut vertices, mut triangles) = (Vec::new(), Vec::new());
    for m in &models {
        let mesh = &m.mesh;
        let first = vertices.len();
        vertices.extend(mesh.positions.chunks_exact(3).map(|p| [p[0], p[1], p[2]]));
        let n = vertices.len();
        let mut at = 0;
        let arities: Vec<usize> = if mesh.face_arities.is_empty() {
            vec![3; mesh.indices.len() / 3]
        } else {
            mesh.face_arities.iter().map(|&a| a as usize).collect()
        };
        for a in arities {
            let face = mesh
                .indices
                .get(at..at + a)
                .ok_or("a face past the file's indices")?;
            fan(
                face.iter().map(|&i| (first + i as usize) as u64),
                n,
                &mut triangles,
            )?;
            at += a;
        }
    }
    Ok((vertices, triangles))
}

/// A PLY vertex: its position (any numeric type).
struct PlyVertex([f32; 3]);

/// A PLY face: its vertex indices (any integer type).
struct PlyFace(Vec<u64>);

/// A numeric PLY scalar as `f32`.
fn scalar(p: &ply_rs_bw::ply::Property) -> Option<f32> {
    use ply_rs_bw::ply::Property as P;
    Some(match *p {
        P::Float(v) => v,
        P::Double(v) => v as f32,
        P::Char(v) => v as f32,
        P::UChar(v) => v as f32,
        P::Short(v) => v as f32,
        P::UShort(v) => v as f32,
        P::Int(v) => v as f32,
        P::UInt(v) => v as f32,
        _ => return None,
    })
}

impl ply_rs_bw::ply::PropertyAccess for PlyVertex {
    fn new() -> Self {
        PlyVertex([f32::NAN; 3])
    }
    fn set_property(&mut self, key: &str, p: ply_rs_bw::ply::Property) {
        let axis = match key {
            "x" => 0,
            "y" => 1,
            "z" => 2,
            _ => return,
        };
        self.0[axis] = scalar(&p).unwrap_or(f32::NAN);
    }
}

impl ply_rs_bw::ply::PropertyAccess for PlyFace {
    fn new() -> Self {
        PlyFace(Vec::new())
    }
    fn set_property(&mut self, key: &str, p: ply_rs_bw::ply::Property) {
        use ply_rs_bw::ply::Property as P;
        if key != "vertex_indices" && key != "vertex_index" {
            return;
        }
        // Negative indices become out of range: refused with the others.
        let wide = |v: i64| if v < 0 { u64::MAX } else { v as u64 };
        self.0 = match p {
            P::ListChar(v) => v.into_iter().map(|x| wide(x as i64)).collect(),
            P::ListUChar(v) => v.into_iter().map(|x| x as u64).collect(),
            P::ListShort(v) => v.into_iter().map(|x| wide(x as i64)).collect(),
            P::ListUShort(v) => v.into_iter().map(|x| x as u64).collect(),
            P::ListInt(v) => v.into_iter().map(|x| wide(x as i64)).collect(),
            P::ListUInt(v) => v.into_iter().map(|x| x as u64).collect(),
            _ => Vec::new(),
        };
    }
}

/// A PLY's vertices and faces (ASCII or binary; polygons as fans; other
/// elements skipped).
fn ply(r: &mut impl BufRead) -> Result<Arrays, String> {
    use ply_rs_bw::parser::Parser;
    let (vp, fp) = (Parser::<PlyVertex>::new(), Parser::<PlyFace>::new());
    let header = vp
        .read_header(r)
        .map_err(|e| format!("not a PLY mesh: {e}"))?;
    let (mut vertices, mut faces) = (Vec::new(), Vec::new());
    let skip = Parser::<ply_rs_bw::ply::DefaultElement>::new();
    for (_, e) in &header.elements {
        let err = |x: std::io::Error| format!("element `{}`: {x}", e.name);
        match e.name.as_str() {
            "vertex" => {
                vertices = vp.read_payload_for_element(r, e, &header).map_err(err)?;
            }
            "face" => faces = fp.read_payload_for_element(r, e, &header).map_err(err)?,
            _ => {
                skip.read_payload_for_element(r, e, &header).map_err(err)?;
            }
        }
    }
    let vertices: Vec<[f32; 3]> = vertices.into_iter().map(|v: PlyVertex| v.0).collect();
    let mut triangles = Vec::new();
    for f in faces {
        fan(f.0.into_iter(), vertices.len(), &mut triangles)?;
    }
    Ok((vertices, triangles))
}

#[cfg(test)]
mod tests {
    use super::*;

    const SQUARE_OBJ: &str = "# a unit square as one quad, and a triangle with v/vt/vn indices
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
vt 0 0
vn 0 0 1
f 1 2 3 4
o second
v 0 0 1
v 1 0 1
v 0 1 1
f 5/1/1 6/1/1 7/1/1
";

    #[test]
    fn obj_polygons_become_fans_over_every_object() {
        let (v, t) = obj(&mut SQUARE_OBJ.as_bytes()).unwrap();
        assert_eq!(v.len(), 7);
        assert_eq!(t, vec![[0, 1, 2], [0, 2, 3], [4, 5, 6]]);
    }

    #[test]
    fn ply_ascii_and_binary_read_alike() {
        let ascii = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\n\
                     property float y\nproperty double z\nelement face 1\n\
                     property list uchar int vertex_indices\nend_header\n\
                     0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";
        let (v, t) = ply(&mut ascii.as_bytes()).unwrap();
        assert_eq!((v.len(), t.clone()), (4, vec![[0, 1, 2], [0, 2, 3]]));
        let mut bin = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\n\
            property float x\nproperty float y\nproperty float z\nelement face 1\n\
            property list uchar uint vertex_indices\nend_header\n"
            .to_vec();
        for p in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
            for x in p {
                bin.extend_from_slice(&x.to_le_bytes());
            }
        }
        bin.push(3);
        for i in [0u32, 1, 2] {
            bin.extend_from_slice(&i.to_le_bytes());
        }
        let (v, t) = ply(&mut bin.as_slice()).unwrap();
        assert_eq!(
            (v, t),
            (
                vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
                vec![[0, 1, 2]]
            )
        );
    }

    #[test]
    fn bad_files_are_errors_not_panics() {
        for (text, want) in [
            ("v 0 0 0\nf 1 2 3\n", "not a Wavefront OBJ"),
            (
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n",
                "not a Wavefront OBJ",
            ),
        ] {
            let e = obj(&mut text.as_bytes()).unwrap_err();
            assert!(e.contains(want), "{text:?}: {e}");
        }
        let past = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n\
                    property float y\nproperty float z\nelement face 1\n\
                    property list uchar int vertex_indices\nend_header\n\
                    0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n";
        assert!(ply(&mut past.as_bytes())
            .unwrap_err()
            .contains("past the 3 vertices"));
        let negative = past.replace("3 0 1 7", "3 0 -1 2");
        assert!(ply(&mut negative.as_bytes()).is_err());
        assert!(ply(&mut "ply\nformat ascii 1.0\nelement vertex 9\n".as_bytes()).is_err());
        assert!(ply(&mut "not a ply".as_bytes()).is_err());
        // A header that promises more vertices than the file holds.
        let short = past.replace("element vertex 3", "element vertex 3000000000");
        assert!(ply(&mut short.as_bytes()).is_err());
    }

    #[test]
    fn a_mesh_scene_frames_its_box() {
        let (v, t) = obj(&mut SQUARE_OBJ.as_bytes()).unwrap();
        let m = from_triangles(v, t);
        assert_eq!((m.counts.triangles, m.lights.len()), (3, 1));
        assert_eq!(m.prim_material.len(), 3);
        let b = m.scene().bounds();
        let c = (b.min + b.max) * 0.5;
        assert!((m.camera.at - c).length() < 1e-6);
        assert!(m.camera.fault().is_none());
        assert!(m
            .normals
            .iter()
            .all(|n| (Vec3::from(*n).length() - 1.0).abs() < 1e-5));
    }
}
