//! Building and running the C programs of c_tests/ with the `cc` crate's compiler.
#![allow(dead_code)]
use std::path::PathBuf;
use std::process::Command;

pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// target/<profile>/deps, where cargo builds libcoray_ffi.a along with
/// these tests (the copy one level up is refreshed only by plain builds).
pub fn deps_dir() -> PathBuf {
    std::env::current_exe()
        .unwrap()
        .parent()
        .unwrap()
        .to_path_buf()
}

pub fn compiler() -> cc::Tool {
    cc::Build::new()
        .cargo_metadata(false)
        .target(env!("CORAY_BUILD_TARGET"))
        .host(env!("CORAY_BUILD_HOST"))
        .opt_level(2)
        .debug(false)
        .get_compiler()
}

pub fn run_checked(cmd: &mut Command, what: &str) -> String {
    let out = cmd
        .output()
        .unwrap_or_else(|e| panic!("{what}: cannot run: {e}"));
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    print!("{stdout}");
    eprint!("{}", String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "{what} failed: {}", out.status);
    stdout
}

/// Compiles c_tests/NAME.c against `lib` and returns the executable.
pub fn build_program(name: &str, lib: &PathBuf, libs: &[&str]) -> PathBuf {
    let dir = deps_dir().join("../c_tests");
    std::fs::create_dir_all(&dir).unwrap();
    let exe = dir.join(name);
    let mut cmd = compiler().to_command();
    cmd.args(["-std=gnu11", "-Wall", "-Wextra", "-Werror"])
        .arg("-I")
        .arg(root().join("include"))
        .arg(root().join("c_tests").join(format!("{name}.c")))
        .arg("-o")
        .arg(&exe)
        .arg(lib)
        .args(libs);
    run_checked(&mut cmd, &format!("compiling {name}.c"));
    exe
}
