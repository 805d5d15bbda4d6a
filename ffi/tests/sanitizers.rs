//! The C programs of c_tests/ under the tools that see what a test's own
//! checks cannot: AddressSanitizer and UndefinedBehaviorSanitizer on the C
//! side of every call, valgrind's memcheck over the whole process (the
//! library's reads and writes included), and helgrind over the threads
//! program (every structure shared between threads) and the build_jobs
//! program (a kd build's jobs writing one arena from four threads).
mod support;

use std::path::PathBuf;
use std::process::Command;
use support::*;

/// The programs that link coray alone, and what each prints on success.
const PROGRAMS: [&str; 8] = [
    "api_contract",
    "canary",
    "threads",
    "build_jobs",
    "lcts",
    "bvh",
    "proj",
    "example",
];

fn library() -> PathBuf {
    let lib = deps_dir().join("libcoray_ffi.a");
    assert!(lib.exists(), "{} missing", lib.display());
    lib
}

/// Builds c_tests/NAME.c with extra flags into NAME-SUFFIX.
fn build_with(name: &str, suffix: &str, flags: &[&str]) -> PathBuf {
    let dir = deps_dir().join("../c_tests");
    std::fs::create_dir_all(&dir).unwrap();
    let exe = dir.join(format!("{name}-{suffix}"));
    let mut cmd = compiler().to_command();
    cmd.args(["-std=gnu11", "-Wall", "-Wextra", "-Werror", "-g"])
        .args(flags)
        .arg("-I")
        .arg(root().join("include"))
        .arg(root().join("c_tests").join(format!("{name}.c")))
        .arg("-o")
        .arg(&exe)
        .arg(library())
        .args(["-lpthread", "-ldl", "-lm"]);
    run_checked(&mut cmd, &format!("compiling {name}.c ({suffix})"));
    exe
}

fn expect_ok(name: &str, out: &str) {
    let want = if name == "example" {
        "floor point under the ball is in shadow".to_string()
    } else {
        format!("{name}: ok")
    };
    assert!(out.contains(&want), "{name}: {out}");
}

#[test]
#[ignore = "runs C programs under ASan, UBSan, valgrind and helgrind: the full tier (scripts/test.sh) runs it"]
fn c_programs_under_address_and_undefined_sanitizers() {
    let flags = [
        "-fsanitize=address,undefined",
        "-fno-sanitize-recover=all",
        "-fno-omit-frame-pointer",
        "-O1",
    ];
    for name in PROGRAMS {
        let exe = build_with(name, "asan", &flags);
        let out = run_checked(
            Command::new(&exe).env("ASAN_OPTIONS", "detect_leaks=1:abort_on_error=1"),
            &format!("{name} under ASan and UBSan"),
        );
        expect_ok(name, &out);
    }
    // The allocation counter interposes malloc itself: UBSan alone.
    let exe = build_with(
        "no_malloc",
        "ubsan",
        &["-fsanitize=undefined", "-fno-sanitize-recover=all"],
    );
    let out = run_checked(&mut Command::new(&exe), "no_malloc under UBSan");
    assert!(out.contains("preset 0: 0 allocator calls"), "{out}");
}

fn valgrind(tool: &str) -> Command {
    let mut c = Command::new("valgrind");
    c.args([&format!("--tool={tool}"), "--error-exitcode=3", "-q"]);
    // Debian's valgrind 3.19 cannot decode the register form of `vmovq
    // xmm, xmm` (VEX 66 0F D6) that the optimised build's AVX2 kernels
    // contain: the program dies with SIGILL in `trace_avx2`. The debug
    // build's kernels (what `.ci/run` tests) run under valgrind as they
    // are; an optimised build's run takes the baseline kernels.
    if !cfg!(debug_assertions) {
        c.env("CORAY_NO_AVX2", "1");
    }
    c
}

#[test]
#[ignore = "runs C programs under ASan, UBSan, valgrind and helgrind: the full tier (scripts/test.sh) runs it"]
fn c_programs_under_valgrind_memcheck() {
    // (no_malloc counts calls to its own malloc, which valgrind replaces.)
    for name in PROGRAMS.iter().filter(|n| **n != "threads") {
        let exe = build_with(name, "vg", &["-O1"]);
        let out = run_checked(
            valgrind("memcheck")
                .args(["--leak-check=full", "--errors-for-leak-kinds=definite"])
                .arg(&exe),
            &format!("{name} under valgrind memcheck"),
        );
        expect_ok(name, &out);
    }
}

#[test]
#[ignore = "runs C programs under ASan, UBSan, valgrind and helgrind: the full tier (scripts/test.sh) runs it"]
fn threads_under_helgrind() {
    for name in ["threads", "build_jobs"] {
        let exe = build_with(name, "hg", &["-O1"]);
        let out = run_checked(
            valgrind("helgrind").arg(&exe),
            &format!("{name} under helgrind"),
        );
        expect_ok(name, &out);
    }
}
