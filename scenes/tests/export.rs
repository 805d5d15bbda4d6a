//! `SceneMesh::to_nff` (what `coray export --nff` writes) read back gives
//! the same scene: primitives in the same order, camera, lights and each
//! primitive's material.
use coray_scenes::nff::NffScene;
use coray_scenes::spd::{self, Options};
use coray_scenes::SceneMesh;

fn corners(m: &SceneMesh) -> Vec<[[f32; 3]; 3]> {
    m.triangles
        .iter()
        .map(|t| t.map(|v| m.vertices[v as usize]))
        .collect()
}

fn same_scene(a: &SceneMesh, b: &SceneMesh, what: &str) {
    assert_eq!(corners(a), corners(b), "{what}: triangles");
    assert_eq!(a.spheres, b.spheres, "{what}: spheres");
    assert_eq!(a.cones, b.cones, "{what}: cones");
    assert_eq!(a.camera, b.camera, "{what}: camera");
    assert_eq!(a.hither, b.hither, "{what}: hither");
    assert_eq!(a.lights, b.lights, "{what}: lights");
    assert_eq!(a.background, b.background, "{what}: background");
    let mats = |m: &SceneMesh| -> Vec<_> {
        m.prim_material
            .iter()
            .map(|&i| m.materials[i as usize])
            .collect()
    };
    assert_eq!(mats(a), mats(b), "{what}: materials");
    let normals = |m: &SceneMesh| -> Vec<Option<[f32; 3]>> {
        m.triangles
            .iter()
            .flat_map(|t| t.map(|v| m.has_normal[v as usize].then(|| m.normals[v as usize])))
            .collect()
    };
    assert_eq!(normals(a), normals(b), "{what}: vertex normals");
}

#[test]
fn exported_nff_reads_back_as_the_same_scene() {
    for (name, size) in [
        ("balls", 2),
        ("gears", 1),
        ("lattice", 2),
        ("mount", 2),
        ("rings", 2),
        ("teapot", 4),
        ("tetra", 2),
        ("tree", 4),
    ] {
        let m = SceneMesh::from_nff(&spd::generate(name, Some(size), &Options::default()).unwrap());
        let text = m.to_nff().to_nff();
        let back = SceneMesh::from_nff(&NffScene::parse(&text).unwrap());
        same_scene(&m, &back, name);
        // Written again, the text is the same.
        assert_eq!(back.to_nff().to_nff(), text, "{name}");
    }
    // A mesh without a view or materials, and a coloured light.
    let mut m = coray_scenes::random::random(50);
    m.lights.push((
        coray::Vec3::new(1.0, 2.0, 3.0),
        coray::Vec3::new(0.5, 0.25, 1.0),
    ));
    let back = SceneMesh::from_nff(&NffScene::parse(&m.to_nff().to_nff()).unwrap());
    same_scene(&m, &back, "random:50");
}
