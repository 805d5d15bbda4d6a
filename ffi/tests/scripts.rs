//! The repository's shell scripts, read as text: what they may do to the
//! machine they run on. The test command installs what it misses with
//! apt-get and never removes a package (an install that would remove one,
//! as qemu-system-arm's once removed a newer qemu-utils, aborts instead).

use std::path::Path;

/// Every shell script the test command and CI run.
fn scripts() -> Vec<(String, String)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut out = Vec::new();
    for dir in ["scripts", ".ci"] {
        for e in std::fs::read_dir(root.join(dir)).unwrap() {
            let p = e.unwrap().path();
            let text = std::fs::read_to_string(&p).unwrap();
            if text.starts_with("#!") {
                out.push((p.display().to_string(), text));
            }
        }
    }
    out
}

#[test]
fn scripts_install_without_removing_and_never_remove() {
    let all = scripts();
    assert!(all.iter().any(|(p, _)| p.ends_with("test.sh")));
    let mut installs = 0;
    for (path, text) in &all {
        for (n, line) in text.lines().enumerate() {
            let code = line.split('#').next().unwrap_or("");
            if code.contains("apt-get install") || code.contains("apt install") {
                installs += 1;
                assert!(
                    code.contains("--no-remove"),
                    "{path}:{}: an install that may remove packages: {line}",
                    n + 1
                );
            }
            for verb in ["remove", "purge", "autoremove"] {
                for tool in ["apt-get", "apt ", "dpkg"] {
                    assert!(
                        !(code.contains(tool) && code.split_whitespace().any(|w| w == verb)),
                        "{path}:{}: removes packages: {line}",
                        n + 1
                    );
                }
            }
        }
    }
    assert!(installs >= 2, "{installs} apt-get installs found");
}
