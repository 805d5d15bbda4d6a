//! The documents say what the code does: every `coray_` and `CORAY_` name
//! that README.md, docs/c-api.md and docs/embedding.md give exists in
//! include/coray.h, and every shell line of the README is one that a
//! named test runs (a new line fails here until a test runs it).

use std::path::PathBuf;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Names the documents give that are not the header's, and why.
const NOT_IN_THE_HEADER: &[&str] = &[
    "CORAY_NO_AVX2", // an environment variable (ffi/src/simd.rs)
    "coray_ffi",     // the crate's own library file, libcoray_ffi.a
    "coray_static",  // the CMake target coray::coray_static
];

#[test]
fn every_name_the_docs_give_is_in_the_header() {
    let header = std::fs::read_to_string(root().join("include/coray.h")).unwrap();
    let words: std::collections::HashSet<&str> = header
        .split(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .collect();
    let mut missing = Vec::new();
    for doc in ["README.md", "docs/c-api.md", "docs/embedding.md"] {
        let text = std::fs::read_to_string(root().join(doc)).unwrap();
        for w in text.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_')) {
            let named = (w.starts_with("coray_") || w.starts_with("CORAY_"))
                // A family's prefix (`coray_wide_*`) names no one function.
                && !w.ends_with('_');
            if named && !words.contains(w) && !NOT_IN_THE_HEADER.contains(&w) {
                missing.push(format!("{doc}: {w}"));
            }
        }
    }
    assert!(missing.is_empty(), "not in coray.h: {missing:?}");
}

/// The README's shell lines and the test that runs each.
const README_COMMANDS: &[(&str, &str)] = &[
    (
        "cargo run --release -p coray-cli --",
        "cli/tests/cli.rs main_job_renders_the_default_scene (the same binary with no \
         arguments, in the test profile: a release build here would double the test's compile)",
    ),
    ("scripts/test.sh", ".ci/run"),
    (
        "scripts/install.sh /usr/local",
        "ffi/tests/install.rs (into a temporary prefix)",
    ),
    (
        "cc app.c $(pkg-config --cflags --libs coray)",
        "ffi/tests/install.rs (render.c built through pkg-config)",
    ),
    (
        "cc app.c -I/usr/local/include /usr/local/lib/libcoray.a -lpthread -ldl -lm",
        "ffi/tests/install.rs (render.c linked with libcoray.a)",
    ),
];

#[test]
fn every_readme_shell_line_is_run_by_a_test() {
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    let mut in_sh = false;
    let mut unknown = Vec::new();
    for line in readme.lines() {
        if line.starts_with("```") {
            in_sh = line == "```sh";
            continue;
        }
        if in_sh {
            let command = line.split(" #").next().unwrap().trim();
            if !command.is_empty() && !README_COMMANDS.iter().any(|(c, _)| *c == command) {
                unknown.push(command.to_string());
            }
        }
    }
    assert!(
        unknown.is_empty(),
        "README shell lines no test runs: {unknown:?}"
    );
}
