//! The NFF reader on arbitrary input: it must never panic or hang, its
//! errors must have a line and column, and what it reads must survive a
//! write and a second read unchanged.
#![no_main]

use coray_scenes::{NffScene, SceneMesh};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    match NffScene::parse(&text) {
        Ok(scene) => {
            let back = NffScene::parse(&scene.to_nff()).expect("the writer's output must read back");
            assert_eq!(back, scene);
            // Flattening (ear clipping included) must not panic either.
            let _ = SceneMesh::from_nff(&scene);
        }
        Err(e) => assert!(e.line >= 1 && e.col >= 1),
    }
});
