//! Regenerates include/coray.h from the ffi sources with cbindgen.
//!
//! Outside CI the header is rewritten when it changed, so a developer's build
//! keeps it current (and `git status` shows it). Under CI (`CI` set) nothing
//! is written: the test `header_matches_sources` fails on any drift instead.
use std::path::PathBuf;

fn main() {
    let crate_dir = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").unwrap());
    println!("cargo:rerun-if-changed=src");
    println!("cargo:rerun-if-changed=cbindgen.toml");
    println!("cargo:rerun-if-env-changed=CI");
    println!(
        "cargo:rustc-env=CORAY_BUILD_TARGET={}",
        std::env::var("TARGET").unwrap()
    );
    println!(
        "cargo:rustc-env=CORAY_BUILD_HOST={}",
        std::env::var("HOST").unwrap()
    );
    // The shared library's SONAME: libcoray.so.<major>, the name the
    // install script gives it (programs link -lcoray and load
    // libcoray.so.1, whatever cargo called the file).
    if std::env::var("CARGO_CFG_TARGET_OS").as_deref() == Ok("linux") {
        let major = std::env::var("CARGO_PKG_VERSION_MAJOR").unwrap();
        println!("cargo:rustc-cdylib-link-arg=-Wl,-soname,libcoray.so.{major}");
    }
    if std::env::var_os("CI").is_some() {
        return;
    }
    let config =
        cbindgen::Config::from_file(crate_dir.join("cbindgen.toml")).expect("cbindgen.toml");
    let header = crate_dir.join("../include/coray.h");
    match cbindgen::generate_with_config(&crate_dir, config) {
        Ok(bindings) => {
            bindings.write_to_file(header);
        }
        Err(e) => println!("cargo:warning=cbindgen could not generate the header: {e}"),
    }
}
