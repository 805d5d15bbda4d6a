//! SPD generators: exact counts per type at the default sizes (docs/techniques.md) and along the
//! thesis' size ladders, bounds, the floor split, and NFF round trips.
use coray_scenes::spd::{self, Options};
use coray_scenes::{NffScene, SceneMesh};

fn mesh(name: &str, size: Option<u32>, split: u32) -> SceneMesh {
    let s = spd::generate(name, size, &Options { floor_split: split }).unwrap();
    SceneMesh::from_nff(&s)
}

/// (spheres, polygons, cones, cylinders) of the table in docs/techniques.md.
#[test]
fn counts_at_design_sizes() {
    let table: &[(&str, usize, [usize; 4])] = &[
        ("balls", 7382, [7381, 1, 0, 0]),
        ("gears", 9345, [0, 9345, 0, 0]),
        ("lattice", 8281, [2197, 0, 0, 6084]),
        ("mount", 8196, [4, 8192, 0, 0]),
        ("rings", 8401, [4200, 1, 0, 4200]),
        ("teapot", 9264, [0, 9264, 0, 0]),
        ("tetra", 4096, [0, 4096, 0, 0]),
        ("tree", 8191, [4095, 1, 4095, 0]),
    ];
    for &(name, objects, [s, p, c, y]) in table {
        let m = mesh(name, None, 1);
        let k = m.counts;
        assert_eq!(
            (k.spheres, k.polygons, k.cones, k.cylinders),
            (s, p, c, y),
            "{name}"
        );
        assert_eq!(k.objects(), objects, "{name}");
        assert_eq!(
            m.scene().prim_count(),
            k.triangles + k.spheres + k.cones + k.cylinders
        );
        assert!(k.lights >= 1 && m.scene().check().is_ok(), "{name}");
    }
}

#[test]
fn gears_polygons_are_quads_and_concave_144_gons() {
    let s = spd::generate("gears", None, &Options::default()).unwrap();
    let mut by_len = std::collections::BTreeMap::new();
    for o in &s.objects {
        if let coray_scenes::Object::Polygon { vertices, .. } = o {
            *by_len.entry(vertices.len()).or_insert(0) += 1;
        }
    }
    assert_eq!(
        by_len.into_iter().collect::<Vec<_>>(),
        vec![(4, 9217), (144, 128)]
    );
    // A 144-gon triangulates into 142 triangles, a quad into 2.
    assert_eq!(
        SceneMesh::from_nff(&s).counts.triangles,
        9217 * 2 + 128 * 142
    );
}

#[test]
fn teapot_has_9120_pp_and_144_p_polygons() {
    let m = mesh("teapot", None, 1);
    assert_eq!(
        (m.counts.polygons, m.counts.polygons_with_normals),
        (9264, 9120)
    );
    for s in [1u32, 4, 7] {
        let k = mesh("teapot", Some(s), 1).counts;
        let s = s as usize;
        assert_eq!(
            (k.polygons_with_normals, k.polygons),
            (64 * s * s - 8 * s, 64 * s * s - 8 * s + s * s)
        );
    }
}

#[test]
fn size_ladders_of_the_thesis() {
    for (size, objects) in [(1, 11), (2, 92), (3, 821), (4, 7382)] {
        assert_eq!(
            mesh("balls", Some(size), 1).counts.objects(),
            objects,
            "balls {size}"
        );
    }
    for size in 1..=11u32 {
        assert_eq!(
            mesh("tree", Some(size), 1).counts.objects(),
            (1 << (size + 2)) - 1,
            "tree {size}"
        );
    }
    for size in 1..=4u32 {
        assert_eq!(
            mesh("gears", Some(size), 1).counts.objects(),
            (size as usize).pow(3) * 146 + 1,
            "gears {size}"
        );
    }
}

#[test]
fn floor_split_cuts_the_floor_into_k_by_k() {
    for k in [1u32, 2, 5, 10] {
        let m = mesh("tree", Some(3), k);
        assert_eq!(m.counts.polygons, (k * k) as usize);
        assert_eq!(m.counts.cones, 15);
        // The pieces cover the same floor.
        let b = m.scene().bounds();
        assert_eq!((b.min.x, b.max.x, b.min.y, b.max.y), (-6.0, 6.0, -6.0, 6.0));
        // Sphere and cone boxes are padded by a few ulps (coray's rounding margin).
        assert!(b.min.z.abs() < 1e-6, "{b:?}");
    }
}

#[test]
fn bounds() {
    let b = mesh("balls", Some(2), 1).scene().bounds();
    assert_eq!(
        (b.min.x, b.max.x, b.min.y, b.max.y),
        (-12.0, 12.0, -12.0, 12.0)
    );
    assert!((b.min.z + 0.5).abs() < 1e-6, "{b:?}");
    assert!(b.max.z > 0.5 && b.max.z < 1.0, "{b:?}");
    let b = mesh("lattice", Some(4), 1).scene().bounds();
    // Spheres of radius 0.2 * step at the corners of [-1, 1]^3, step 0.5.
    for a in 0..3 {
        assert!(
            (b.min[a] + 1.1).abs() < 1e-5 && (b.max[a] - 1.1).abs() < 1e-5,
            "{b:?}"
        );
    }
    let b = mesh("tetra", Some(3), 1).scene().bounds();
    let s = 1.0 / 3f32.sqrt();
    for a in 0..3 {
        assert!(
            (b.min[a] + s).abs() < 1e-6 && (b.max[a] - s).abs() < 1e-6,
            "{b:?}"
        );
    }
    let b = mesh("mount", Some(4), 1).scene().bounds();
    for (got, want) in [
        (b.min.x, -1.0),
        (b.max.x, 1.0),
        (b.min.y, -1.0),
        (b.max.y, 1.0),
    ] {
        assert!((got - want).abs() < 1e-5, "{b:?}");
    }
    let b = mesh("gears", Some(2), 1).scene().bounds();
    assert!(b.min.z == -0.5 && b.max.z > 0.5 && b.max.z < 1.0, "{b:?}");
}

#[test]
fn generated_scenes_round_trip_through_nff() {
    for &(name, _) in spd::SCENES {
        let s = spd::generate(name, Some(2), &Options { floor_split: 2 }).unwrap();
        let back = NffScene::parse(&s.to_nff()).unwrap();
        assert_eq!(back, s, "{name}");
    }
}

#[test]
fn bad_names_and_sizes_are_errors() {
    assert!(spd::generate("teacup", None, &Options::default())
        .unwrap_err()
        .contains("no SPD scene"));
    assert!(spd::generate("balls", Some(0), &Options::default()).is_err());
    assert!(spd::generate("balls", Some(7), &Options::default()).is_err());
    assert!(spd::generate("tree", Some(3), &Options { floor_split: 0 }).is_err());
}
