//! scripts/install.sh into a temporary prefix, then every example built
//! against what it installed, as a user would: through pkg-config (static
//! and shared) and through CMake's find_package(coray), and run.
mod support;

use std::path::{Path, PathBuf};
use std::process::Command;
use support::*;

fn sh(cmd: &mut Command, what: &str) -> String {
    run_checked(cmd, what)
}

fn pkg_config(prefix: &Path, args: &[&str]) -> Vec<String> {
    let out = Command::new("pkg-config")
        .args(args)
        .arg("coray")
        .env("PKG_CONFIG_PATH", prefix.join("lib/pkgconfig"))
        .output()
        .expect("pkg-config");
    assert!(out.status.success(), "pkg-config {args:?} failed");
    String::from_utf8_lossy(&out.stdout)
        .split_whitespace()
        .map(str::to_string)
        .collect()
}

const NFF: &str = "v\nfrom 0 -6 3\nat 0 0 0.5\nup 0 0 1\nangle 40\nhither 0.01\nresolution 64 48\n\
b 0.1 0.1 0.2\nl 4 -4 8\nf 0.8 0.7 0.5 1 0 0 0 1\np 4\n-4 -4 0\n4 -4 0\n4 4 0\n-4 4 0\n\
f 0.3 0.5 0.9 0.8 0.2 20 0 1\ns 0 0 1 1\nc -2 0 0 0.4 -2 0 2 0.1\n";

/// A PPM's header and size: `P6`, the size asked for, every pixel there.
fn check_ppm(path: &Path, w: usize, h: usize) {
    let b = std::fs::read(path).unwrap();
    let head = format!("P6\n{w} {h}\n255\n");
    assert!(b.starts_with(head.as_bytes()), "{}", path.display());
    assert_eq!(b.len(), head.len() + 3 * w * h, "{}", path.display());
}

#[test]
#[ignore = "installs into a prefix and builds the examples with cc and CMake: the full tier (scripts/test.sh) runs it"]
fn install_then_build_the_examples_with_pkg_config_and_cmake() {
    let tmp = std::env::temp_dir().join(format!("coray-install-{}", std::process::id()));
    let prefix = tmp.join("prefix");
    let _ = std::fs::remove_dir_all(&tmp);
    std::fs::create_dir_all(&tmp).unwrap();
    let out = sh(
        Command::new(root().join("scripts/install.sh"))
            .arg(&prefix)
            .env("CARGO_TARGET_DIR", root().join("target/install")),
        "scripts/install.sh",
    );
    assert!(out.contains("installed in"), "{out}");
    for f in [
        "include/coray.h",
        "include/coray.hpp",
        "lib/libcoray.a",
        "lib/libcoray.so",
        "lib/libcoray.so.1",
        "lib/pkgconfig/coray.pc",
        "lib/cmake/coray/corayConfig.cmake",
        "lib/cmake/coray/corayConfigVersion.cmake",
    ] {
        assert!(prefix.join(f).exists(), "{f} not installed");
    }
    // The static library exports coray's names only, each one the header
    // declares (before: about 1,190 global symbols, Rust's std among them).
    let nm = Command::new("nm")
        .args(["-g", "--defined-only"])
        .arg(prefix.join("lib/libcoray.a"))
        .output()
        .unwrap();
    assert!(
        nm.status.success(),
        "{}",
        String::from_utf8_lossy(&nm.stderr)
    );
    let header = std::fs::read_to_string(root().join("include/coray.h")).unwrap();
    let globals: Vec<String> = String::from_utf8_lossy(&nm.stdout)
        .lines()
        .filter_map(|l| l.split_whitespace().nth(2).map(str::to_string))
        .collect();
    assert!(globals.len() >= 60, "{} global symbols", globals.len());
    for g in &globals {
        assert!(
            g.starts_with("coray_") && header.contains(&format!("{g}(")),
            "libcoray.a exports {g}, not a function of coray.h"
        );
    }
    let soname = Command::new("readelf")
        .args(["-d"])
        .arg(prefix.join("lib/libcoray.so.1"))
        .output()
        .unwrap();
    assert!(
        String::from_utf8_lossy(&soname.stdout).contains("[libcoray.so.1]"),
        "no SONAME"
    );

    let ex = root().join("examples");
    let nff = tmp.join("scene.nff");
    std::fs::write(&nff, NFF).unwrap();
    let lib = prefix.join("lib");

    // pkg-config: shared, then static.
    let cflags = pkg_config(&prefix, &["--cflags"]);
    let libs = pkg_config(&prefix, &["--libs"]);
    let static_libs = pkg_config(&prefix, &["--libs", "--static"]);
    let shared = tmp.join("render_shared");
    sh(
        Command::new("cc")
            .args(["-std=gnu11", "-O2", "-Wall", "-Werror"])
            .arg(ex.join("render.c"))
            .args(&cflags)
            .args(&libs)
            .args(["-lpthread", "-lm", "-o"])
            .arg(&shared),
        "cc render.c (pkg-config)",
    );
    let stat = tmp.join("render_static");
    sh(
        Command::new("cc")
            .args(["-std=gnu11", "-O2", "-static-libgcc"])
            .arg(ex.join("render.c"))
            .args(&cflags)
            .arg(lib.join("libcoray.a"))
            .args(static_libs.iter().filter(|a| !a.starts_with("-lcoray")))
            .args(["-lpthread", "-lm", "-o"])
            .arg(&stat),
        "cc render.c (static)",
    );
    let (a, b) = (tmp.join("a.ppm"), tmp.join("b.ppm"));
    sh(
        Command::new(&shared)
            .arg(&nff)
            .arg(&a)
            .arg("3")
            .env("LD_LIBRARY_PATH", &lib),
        "render (shared)",
    );
    sh(
        Command::new(&stat).arg(&nff).arg(&b).arg("2"),
        "render (static)",
    );
    check_ppm(&a, 64, 48);
    assert_eq!(
        std::fs::read(&a).unwrap(),
        std::fs::read(&b).unwrap(),
        "thread counts and linkage change nothing"
    );

    // The repository's own NFF sample (a light with a colour) renders:
    // render.c stopped at the colour before.
    let sample = tmp.join("sample.ppm");
    sh(
        Command::new(&stat)
            .arg(root().join("fuzz/seeds/sample.nff"))
            .arg(&sample)
            .arg("1"),
        "render sample.nff",
    );
    assert!(std::fs::read(&sample).unwrap().starts_with(b"P6"));

    // CMake: find_package(coray) and every example.
    let build = tmp.join("cmake-build");
    sh(
        Command::new("cmake")
            .arg("-S")
            .arg(&ex)
            .arg("-B")
            .arg(&build)
            .arg(format!("-DCMAKE_PREFIX_PATH={}", prefix.display()))
            .arg("-DCMAKE_BUILD_TYPE=Release"),
        "cmake configure",
    );
    sh(
        Command::new("cmake").arg("--build").arg(&build),
        "cmake build",
    );
    let run = |exe: &str, args: &[&Path]| {
        let mut c = Command::new(build.join(exe));
        c.args(args).env("LD_LIBRARY_PATH", &lib);
        sh(&mut c, exe)
    };
    let c_ppm = tmp.join("c.ppm");
    run("render", &[&nff, &c_ppm]);
    assert_eq!(std::fs::read(&c_ppm).unwrap(), std::fs::read(&a).unwrap());
    run("render_static", &[&nff, &c_ppm]);
    let cpp = tmp.join("cpp.ppm");
    let out = run("render_cpp", &[&cpp, Path::new("64"), Path::new("2")]);
    assert!(out.contains("packets of 8"), "{out}");
    check_ppm(&cpp, 64, 64);

    // A tree saved by one process, mapped and traced by another.
    let saved: PathBuf = tmp.join("scene.coray");
    let v = [
        [-4.0f32, -4.0, 0.0],
        [4.0, -4.0, 0.0],
        [4.0, 4.0, 0.0],
        [-4.0, 4.0, 0.0],
    ];
    let t = [[0u32, 1, 2], [0, 2, 3]];
    let s = [coray::Sphere {
        center: [0.0, 0.0, 1.0],
        radius: 1.0,
    }];
    let scene = coray::Scene {
        vertices: &v,
        triangles: &t,
        spheres: &s,
        cones: &[],
    };
    let bytes =
        coray_ffi::saved::kdtree_file(&scene, None, coray_ffi::CORAY_KD_PRESET_AUTO, 0).unwrap();
    std::fs::write(&saved, &bytes).unwrap();
    let out = run(
        "trace_saved",
        &[&saved, &tmp.join("saved.ppm"), Path::new("32")],
    );
    assert!(out.contains("validated"), "{out}");
    // The MPI example, built by CMake against the installed library, on
    // two ranks: the one-process image (Open MPI asks root to say so twice).
    let mpi = Command::new("mpirun")
        .args(["--oversubscribe", "-n", "2"])
        .arg(build.join("trace_mpi"))
        .arg(&saved)
        .arg(tmp.join("saved-mpi.ppm"))
        .arg("32")
        .env("LD_LIBRARY_PATH", &lib)
        .env("OMPI_ALLOW_RUN_AS_ROOT", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
        .output()
        .expect("mpirun (scripts/test.sh installs openmpi-bin)");
    assert!(
        mpi.status.success(),
        "{}",
        String::from_utf8_lossy(&mpi.stderr)
    );
    assert_eq!(
        std::fs::read(tmp.join("saved.ppm")).unwrap(),
        std::fs::read(tmp.join("saved-mpi.ppm")).unwrap(),
        "two ranks cast another image"
    );
    // A damaged copy is refused, never traced: a byte of the tree's header
    // or of its root node (the checksum), or the root node changed and
    // the checksum made again (validate).
    let arena_at = u64::from_ne_bytes(bytes[96..104].try_into().unwrap()) as usize;
    for (at, forged, says) in [
        (4, false, "damaged"),
        (coray::kd::layout::KD_HEADER_BYTES, false, "damaged"),
        (coray::kd::layout::KD_HEADER_BYTES, true, "corrupt"),
    ] {
        let mut bad = bytes.clone();
        bad[arena_at + at] ^= 0x5a;
        if forged {
            let sum = coray_ffi::saved::checksum(&bad);
            bad[24..32].copy_from_slice(&sum.to_ne_bytes());
        }
        std::fs::write(&saved, &bad).unwrap();
        let st = Command::new(build.join("trace_saved"))
            .arg(&saved)
            .arg(tmp.join("bad.ppm"))
            .env("LD_LIBRARY_PATH", &lib)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&st.stderr);
        assert!(!st.status.success(), "a tree damaged at {at} was traced");
        assert!(err.contains(says), "{at} {forged}: {err}");
    }
    let _ = std::fs::remove_dir_all(&tmp);
}
