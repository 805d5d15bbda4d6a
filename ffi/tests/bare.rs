//! The bare C library: coray-ffi without Rust std (its own panic handler,
//! panics abort), as an embedded target would link it. It must import no
//! allocator and no std symbol, and a C program must link and run with it.
mod support;

use std::process::Command;
use support::*;

const ALLOCATOR: &[&str] = &[
    "malloc",
    "calloc",
    "realloc",
    "free",
    "posix_memalign",
    "aligned_alloc",
    "memalign",
];

fn symbols(args: &[&str], file: &std::path::Path) -> String {
    let out = Command::new("nm")
        .args(args)
        .arg(file)
        .output()
        .expect("nm");
    assert!(out.status.success(), "nm {args:?} failed");
    String::from_utf8_lossy(&out.stdout).into_owned()
}

#[test]
#[ignore = "builds the bare library and links a C program: the full tier (scripts/test.sh) runs it"]
fn bare_library_imports_no_allocator_and_no_std() {
    let target_dir = root().join("target/bare");
    let status = Command::new(env!("CARGO"))
        .current_dir(root())
        .args([
            "build",
            "-p",
            "coray-ffi",
            "--lib",
            "--no-default-features",
            "--profile",
            "bare",
        ])
        .arg("--target-dir")
        .arg(&target_dir)
        .status()
        .expect("cargo");
    assert!(status.success(), "bare build failed");
    let lib = target_dir.join("bare/libcoray_ffi.a");

    // coray's own objects in the archive reference no allocator and no std.
    let undefined = symbols(&["-A", "--undefined-only"], &lib);
    let mut ours = 0;
    for line in undefined.lines().filter(|l| {
        [":coray", ":glam", ":libm", ":safe_arch"]
            .iter()
            .any(|c| l.contains(c))
    }) {
        let name = line.split_whitespace().last().unwrap_or("");
        ours += 1;
        assert!(!ALLOCATOR.contains(&name), "coray's objects import {name}");
        assert!(
            !name.contains("3std") && !name.contains("5alloc"),
            "coray's objects import std or alloc: {name}"
        );
    }
    assert!(
        ours > 0,
        "no undefined symbols seen at all: is the nm output parsed?"
    );

    // A C program with static arenas links it with libc alone, runs, and
    // its executable imports no allocator and holds no std code.
    let exe = build_program("bare_main", &lib, &["-Wl,--gc-sections"]);
    let run = Command::new(&exe).output().expect("run bare_main");
    assert!(run.status.success(), "bare_main exited with {}", run.status);
    assert!(String::from_utf8_lossy(&run.stdout).contains("bare: ok"));
    let imports = symbols(&["-D", "--undefined-only"], &exe);
    let imports: Vec<&str> = imports
        .lines()
        .filter_map(|l| l.split_whitespace().last())
        .collect();
    println!("bare_main imports: {imports:?}");
    for name in &imports {
        let base = name.split('@').next().unwrap_or(name);
        assert!(!ALLOCATOR.contains(&base), "bare_main imports {name}");
    }
    let all = symbols(&[], &exe);
    assert!(!all.contains("3std"), "std code linked into bare_main");
}
