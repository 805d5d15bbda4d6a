//! include/coray.h is what cbindgen makes of the sources today.
use std::path::PathBuf;

#[test]
fn header_matches_sources() {
    let crate_dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let config = cbindgen::Config::from_file(crate_dir.join("cbindgen.toml")).unwrap();
    let bindings = cbindgen::generate_with_config(&crate_dir, config).expect("cbindgen");
    let mut fresh = Vec::new();
    bindings.write(&mut fresh);
    let committed = std::fs::read(crate_dir.join("../include/coray.h")).expect("include/coray.h");
    assert!(
        fresh == committed,
        "include/coray.h differs from a fresh cbindgen run: build coray-ffi outside CI and commit the header"
    );
}
