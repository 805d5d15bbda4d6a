//! Builds the C programs in c_tests/ with the `cc` crate's compiler, links
//! them with libcoray_ffi.a (and Embree where they compare), and runs them.
mod support;

use std::process::Command;
use support::*;

fn run_program(name: &str, libs: &[&str]) -> String {
    let lib = deps_dir().join("libcoray_ffi.a");
    assert!(
        lib.exists(),
        "{} missing: cargo builds it with this package",
        lib.display()
    );
    let mut all = libs.to_vec();
    all.extend(["-lpthread", "-ldl", "-lm"]);
    let exe = build_program(name, &lib, &all);
    run_checked(&mut Command::new(&exe), name)
}

#[test]
fn header_compiles_alone_as_strict_c99() {
    let mut cmd = compiler().to_command();
    cmd.args([
        "-std=c99",
        "-Wall",
        "-Wextra",
        "-Wpedantic",
        "-Werror",
        "-fsyntax-only",
    ])
    .arg("-I")
    .arg(root().join("include"))
    .arg(root().join("c_tests/header_only.c"));
    run_checked(&mut cmd, "C99 compile of coray.h");
}

#[test]
fn header_compiles_as_cpp() {
    let mut cmd = Command::new("c++");
    cmd.args([
        "-x",
        "c++",
        "-std=c++11",
        "-Wall",
        "-Wextra",
        "-Wpedantic",
        "-Werror",
        "-fsyntax-only",
    ])
    .arg("-I")
    .arg(root().join("include"))
    .arg(root().join("c_tests/header_only.c"));
    run_checked(&mut cmd, "C++ compile of coray.h");
}

#[test]
fn api_contract() {
    assert!(run_program("api_contract", &[]).contains("api_contract: ok"));
}

#[test]
fn no_allocation_during_build_and_trace() {
    let out = run_program("no_malloc", &[]);
    assert!(
        out.contains("preset 0: 0 allocator calls") && out.contains("preset 1: 0 allocator calls")
    );
}

#[test]
fn no_write_outside_arenas() {
    assert!(run_program("canary", &[]).contains("canary: ok"));
}

#[test]
fn four_threads_trace_like_one() {
    assert!(run_program("threads", &[]).contains("threads: ok"));
}

#[test]
fn build_jobs_on_four_threads_make_the_one_thread_arena() {
    assert!(run_program("build_jobs", &[]).contains("build_jobs: ok"));
}

#[test]
fn documented_example_is_the_tested_one_and_runs() {
    let doc = std::fs::read_to_string(root().join("docs/c-api.md")).unwrap();
    let example = std::fs::read_to_string(root().join("c_tests/example.c")).unwrap();
    assert!(
        doc.contains(example.trim()),
        "docs/c-api.md must quote c_tests/example.c verbatim"
    );
    let out = run_program("example", &[]);
    assert!(out.contains("hit geometry 1 primitive 0 at t = 8"));
    assert!(out.contains("in shadow"));
}

#[test]
fn lcts_casting_and_patch_visibility() {
    assert!(run_program("lcts", &[]).contains("lcts: ok"));
}

#[test]
fn embree_crosscheck() {
    let out = run_program("embree_crosscheck", &["-lembree3"]);
    assert!(out.contains("embree_crosscheck: ok"));
}

#[test]
fn bvh_builders_insert_delete_and_errors() {
    assert!(run_program("bvh", &[]).contains("bvh: ok"));
}

#[test]
fn projection_hierarchies_camera_lights_and_errors() {
    assert!(run_program("proj", &[]).contains("proj: ok"));
}
