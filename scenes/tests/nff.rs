//! The NFF reader and writer.
use coray_scenes::nff::{NffScene, Object};
use coray_scenes::SceneMesh;

const SAMPLE: &str = "# a sample with every command
b 0.078 0.361 0.753
v
from 2.1 1.3 1.7
at 0 0 0
up 0 0 1
angle 45
hither 0.01
resolution 512 256
l 4 3 2
l 1 -4 4 0.5 0.5 0.5
f 1 0.75 0.33 0.8 0 0 0 1
s 0 0 0 0.5
c 0 0 0 0.1 0 0 1 0.1
c
  1 1 1 0.2
  1 1 2 0
f 0.5 0.5 0.5 1 0 100 0.5 1.5
p 4
-1 -1 0
 1 -1 0
 1  1 0
-1  1 0
pp 3
0 0 1 0 0 1
1 0 1 0 0 1
0 1 1 0 0 1
s 3 3 3 -1
";

#[test]
fn reads_every_command() {
    let s = NffScene::parse(SAMPLE).unwrap();
    let v = s.view.unwrap();
    assert_eq!(v.from, [2.1, 1.3, 1.7]);
    assert_eq!(v.up, [0.0, 0.0, 1.0]);
    assert_eq!((v.angle, v.hither, v.resolution), (45.0, 0.01, [512, 256]));
    assert_eq!(s.background, Some([0.078, 0.361, 0.753]));
    assert_eq!(s.lights.len(), 2);
    assert_eq!(s.lights[0].color, None);
    assert_eq!(s.lights[1].color, Some([0.5, 0.5, 0.5]));
    assert_eq!(s.materials.len(), 2);
    assert_eq!(s.materials[1].ior, 1.5);
    assert_eq!(s.objects.len(), 6);
    assert!(matches!(
        s.objects[1],
        Object::Cone {
            base_radius: 0.1,
            apex_radius: 0.1,
            material: Some(0),
            ..
        }
    ));
    assert!(matches!(
        s.objects[2],
        Object::Cone {
            apex: [1.0, 1.0, 2.0],
            apex_radius: 0.0,
            ..
        }
    ));
    match &s.objects[4] {
        Object::Polygon {
            vertices,
            normals: Some(n),
            material: Some(1),
        } => {
            assert_eq!(vertices.len(), 3);
            assert_eq!(n[2], [0.0, 0.0, 1.0]);
        }
        o => panic!("{o:?}"),
    }
    assert!(matches!(
        s.objects[5],
        Object::Sphere {
            radius: 1.0,
            inside_visible: true,
            ..
        }
    ));

    let m = SceneMesh::from_nff(&s);
    let c = m.counts;
    assert_eq!(
        (
            c.spheres,
            c.polygons,
            c.polygons_with_normals,
            c.triangles,
            c.cones,
            c.cylinders,
            c.lights
        ),
        (2, 2, 1, 3, 1, 1, 2)
    );
    assert_eq!(c.objects(), 6);
    assert_eq!(m.prim_material.len(), 3 + 2 + 2);
    assert_eq!(m.prim_material[0], 2); // the quad's triangles use the second `f` (index 1, +1 for the default)
    assert_eq!(m.camera.width, 512);
}

#[test]
fn writer_round_trips() {
    let s = NffScene::parse(SAMPLE).unwrap();
    let text = s.to_nff();
    let back = NffScene::parse(&text).unwrap();
    assert_eq!(back, s);
    assert_eq!(back.to_nff(), text);
}

#[test]
fn errors_name_line_and_column() {
    let cases: &[(&str, usize, usize, &str)] = &[
        ("s 0 0 0 0.5\nq 1 2\n", 2, 1, "unknown command `q`"),
        ("s 0 0 zero 1\n", 1, 7, "sphere centre"),
        (
            "b 1 1 1\nv\nfrom 0 0 0\nat 0 0\nup 0 1 0\n",
            5,
            1,
            "`at` coordinate",
        ),
        ("p 2\n0 0 0\n1 1 1\n", 1, 1, "at least 3 vertices"),
        ("p 3\n0 0 0\n1 1 1\n", 3, 6, "end of file"),
        ("  f 1 1 1 1 1 1 1 nan\n", 1, 19, "index of refraction"),
        ("s 0 0 0 1e39\n", 1, 9, "finite"),
        ("p 99999999999\n", 1, 3, "whole number"),
        (
            "v\nfrom 0 0 0\nat 0 0 0\nup 0 1 0\nangle 45\nhither 1\nresolution -3 4\n",
            7,
            12,
            "x resolution",
        ),
        (
            "v\nfrom 0 0 1\nat 0 0 0\nup 0 1 0\nangle 45\nhither 1\nresolution 0 0\n",
            7,
            12,
            "1 to 32768 pixels",
        ),
        (
            "v\nfrom 0 0 1\nat 0 0 0\nup 0 1 0\nangle 45\nhither 1\nresolution 64 40000\n",
            7,
            15,
            "1 to 32768 pixels",
        ),
        (
            "s 0 0 0 1\n v\nfrom 1 2 3\nat 1 2 3\nup 0 1 0\nangle 45\nhither 1\nresolution 8 8\n",
            2,
            2,
            "eye (from) is the point it looks at",
        ),
        (
            "v\nfrom 0 0 1\nat 0 0 0\nup 0 0 -2\nangle 45\nhither 1\nresolution 8 8\n",
            1,
            1,
            "along the view",
        ),
        (
            "v\nfrom 0 0 1\nat 0 0 0\nup 0 1 0\nangle 0\nhither 1\nresolution 8 8\n",
            1,
            1,
            "angle",
        ),
        // Columns count characters, not bytes.
        ("# é\nb é 1 1\n", 2, 3, "background"),
        ("s 0 0 0 1 ééé qq\n", 1, 11, "unknown command `ééé`"),
        (
            "s 0 0 0 1\nééé s 0 0 0 1 qq\n",
            2,
            1,
            "unknown command `ééé`",
        ),
    ];
    for (src, line, col, text) in cases {
        let e = NffScene::parse(src).unwrap_err();
        assert_eq!((e.line, e.col), (*line, *col), "{src:?}: {e}");
        assert!(e.msg.contains(text), "{src:?}: {e}");
    }
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(2000))]

    /// Any text made of NFF's words and numbers, shrunk to the smallest
    /// failing input when one fails: read without a panic, an error names a
    /// line and column, and what reads writes back to itself.
    #[test]
    fn garbage_never_panics(text in "([vbflcsp#\\n\\t 0-9.+eE-]|from|at|up|angle|hither|resolution|pp|nan|inf){0,120}") {
        match NffScene::parse(&text) {
            Ok(s) => proptest::prop_assert_eq!(NffScene::parse(&s.to_nff()).unwrap(), s),
            Err(e) => proptest::prop_assert!(e.line >= 1 && e.col >= 1),
        }
    }
}

/// A concave polygon past the triangulation bound is refused with the
/// numbers that decide it; a large convex one is read.
#[test]
fn polygon_work_is_bounded() {
    let comb = |teeth: usize| {
        let mut t = format!("p {}\n0 0 0\n", 3 * teeth + 2);
        for k in 0..teeth {
            let x = 2 * k;
            t += &format!("{x} 1 0\n{}.5 3 0\n{} 1 0\n", x, x + 1);
        }
        t + &format!("{} 0 0\n", 2 * teeth)
    };
    assert!(NffScene::parse(&comb(100)).is_ok());
    let e = NffScene::parse(&comb(40_000)).unwrap_err();
    assert_eq!((e.line, e.col), (1, 1));
    assert!(
        e.msg.contains("concave corners") && e.msg.contains("1073741824"),
        "{e}"
    );
    let mut convex = String::from("p 8193\n");
    for x in -4096i64..=4096 {
        convex += &format!("{x} {} 0\n", x * x);
    }
    let s = NffScene::parse(&convex).unwrap();
    let m = coray_scenes::SceneMesh::from_nff(&s);
    assert_eq!(m.triangles.len(), 8191);
}

/// Audit 55.7: a hostile token was echoed whole (a 200 MB name, a 200 MB
/// message), and the reader listed every token of the file before reading
/// the first command (a 200 MB line took 3.3 GB). Messages now cut tokens
/// to 80 characters with their length; tokens are read as they are asked
/// for, so an error early in a huge line is found where it is.
#[test]
fn hostile_tokens_make_short_messages() {
    let token = "x".repeat(1_000_000);
    for src in [
        token.clone(),
        format!("s 0 0 0 {token}"),
        format!("v\nfrom {token} 0 0\n"),
        format!("p {token}\n"),
    ] {
        let e = NffScene::parse(&src).unwrap_err().to_string();
        assert!(e.len() < 300, "{} bytes: {}", e.len(), &e[..300]);
        assert!(e.contains("... (1000000 bytes)"), "{e}");
    }
    // Short tokens are shown whole, multi-byte characters cut whole.
    let e = NffScene::parse("qq").unwrap_err();
    assert!(e.msg.ends_with("`qq`"), "{e}");
    let e = NffScene::parse(&"é".repeat(100)).unwrap_err();
    assert!(
        e.msg
            .contains(&format!("`{}... (200 bytes)`", "é".repeat(80))),
        "{e}"
    );
    // A line of two million numbers after one sphere: the stray number is
    // found at its column.
    let src = format!("s 0 0 0 1 {}", "1 ".repeat(2_000_000));
    let e = NffScene::parse(&src).unwrap_err();
    assert_eq!((e.line, e.col), (1, 11), "{e}");
    assert!(e.msg.contains("unknown command `1`"), "{e}");
}
