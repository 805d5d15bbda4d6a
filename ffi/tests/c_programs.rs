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
#[ignore = "compiles and runs C programs: the full tier (scripts/test.sh) runs it"]
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
#[ignore = "compiles and runs C programs: the full tier (scripts/test.sh) runs it"]
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

/// include/coray.hpp under C++17 and C++20 with every warning an error,
/// linked with the library and run (c_tests/cpp_wrapper.cpp).
#[test]
#[ignore = "compiles and runs C programs: the full tier (scripts/test.sh) runs it"]
fn cpp_wrappers_build_and_pass_under_cpp17_and_cpp20() {
    let lib = deps_dir().join("libcoray_ffi.a");
    for std in ["c++17", "c++20"] {
        let exe = deps_dir().join(format!("../c_tests/cpp_wrapper_{std}"));
        std::fs::create_dir_all(exe.parent().unwrap()).unwrap();
        let mut cmd = Command::new("c++");
        cmd.arg(format!("-std={std}"))
            .args(["-Wall", "-Wextra", "-Wpedantic", "-Werror", "-O1"])
            .arg("-I")
            .arg(root().join("include"))
            .arg(root().join("c_tests/cpp_wrapper.cpp"))
            .arg("-o")
            .arg(&exe)
            .arg(&lib)
            .args(["-lpthread", "-ldl", "-lm"]);
        run_checked(&mut cmd, &format!("c++ -std={std} cpp_wrapper.cpp"));
        let out = run_checked(&mut Command::new(&exe), "cpp_wrapper");
        assert!(out.contains("cpp_wrapper: ok"), "{std}: {out}");
    }
}

#[test]
#[ignore = "compiles and runs C programs: the full tier (scripts/test.sh) runs it"]
fn api_contract() {
    assert!(run_program("api_contract", &[]).contains("api_contract: ok"));
}

#[test]
#[ignore = "compiles and runs C programs: the full tier (scripts/test.sh) runs it"]
fn no_allocation_during_build_and_trace() {
    let out = run_program("no_malloc", &[]);
    assert!(
        out.contains("preset 0: 0 allocator calls") && out.contains("preset 1: 0 allocator calls")
    );
}

#[test]
#[ignore = "compiles and runs C programs: the full tier (scripts/test.sh) runs it"]
fn no_write_outside_arenas() {
    assert!(run_program("canary", &[]).contains("canary: ok"));
}

#[test]
#[ignore = "compiles and runs C programs: the full tier (scripts/test.sh) runs it"]
fn four_threads_trace_like_one() {
    assert!(run_program("threads", &[]).contains("threads: ok"));
}

#[test]
#[ignore = "compiles and runs C programs: the full tier (scripts/test.sh) runs it"]
fn build_jobs_on_four_threads_make_the_one_thread_arena() {
    assert!(run_program("build_jobs", &[]).contains("build_jobs: ok"));
}

#[test]
#[ignore = "compiles and runs C programs: the full tier (scripts/test.sh) runs it"]
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

/// The README's mesh example is c_tests/mesh.c, quoted verbatim, and it
/// runs: the wide hierarchy over an octahedron, a tracer, one ray.
#[test]
#[ignore = "compiles and runs C programs: the full tier (scripts/test.sh) runs it"]
fn readme_mesh_example_is_the_tested_one_and_runs() {
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    let example = std::fs::read_to_string(root().join("c_tests/mesh.c")).unwrap();
    assert!(
        readme.contains(example.trim()),
        "README.md must quote c_tests/mesh.c verbatim"
    );
    let out = run_program("mesh", &[]);
    assert!(
        out.contains("triangle 0 at t = 4.5, u = 0.25, v = 0.5, ng = (-1, -1, -1)"),
        "{out}"
    );
}

#[test]
#[ignore = "compiles and runs C programs: the full tier (scripts/test.sh) runs it"]
fn lcts_casting_and_patch_visibility() {
    assert!(run_program("lcts", &[]).contains("lcts: ok"));
}

#[test]
#[ignore = "compiles and runs C programs: the full tier (scripts/test.sh) runs it"]
fn embree_crosscheck() {
    let out = run_program("embree_crosscheck", &["-lembree3"]);
    assert!(out.contains("embree_crosscheck: ok"));
}

#[test]
#[ignore = "compiles and runs C programs: the full tier (scripts/test.sh) runs it"]
fn bvh_builders_insert_delete_and_errors() {
    assert!(run_program("bvh", &[]).contains("bvh: ok"));
}

#[test]
#[ignore = "compiles and runs C programs: the full tier (scripts/test.sh) runs it"]
fn projection_hierarchies_camera_lights_and_errors() {
    assert!(run_program("proj", &[]).contains("proj: ok"));
}
