#!/usr/bin/env bash
# Runs every test of coray: Rust unit and integration tests, the C programs
# (API contract, allocation counting, canaries, threads, the bare no-std
# library, the Embree cross-check, each under ASan/UBSan and valgrind),
# the fuzz corpus replay and the header drift check.
# On a fresh Debian machine it installs what it needs (as root).
set -euo pipefail
cd "$(dirname "$0")/.."

# Debian packages the tests need: Embree 3 (the cross-check reference),
# valgrind (memcheck and helgrind over the C programs), cmake (the
# installed package's find_package test), Open MPI.
need=()
[ -f /usr/include/embree3/rtcore.h ] || need+=(libembree-dev)
command -v valgrind >/dev/null || need+=(valgrind)
command -v cmake >/dev/null || need+=(cmake)
command -v pkg-config >/dev/null || need+=(pkg-config)
# Open MPI: the render-farm example (examples/trace_mpi.c) on two ranks.
command -v mpicc >/dev/null || need+=(libopenmpi-dev)
command -v mpirun >/dev/null || need+=(openmpi-bin)
if [ ${#need[@]} -gt 0 ]; then
    echo "installing ${need[*]}"
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-remove "${need[@]}"
fi
for tool in cc c++ nm; do
    command -v "$tool" >/dev/null || { echo "missing $tool"; exit 1; }
done

# Disk: a test run builds several profiles and many C programs; CI
# machines can be short of space. No incremental caches (a run builds
# once) and line tables only as debug information (backtraces and
# sanitizer reports keep file:line): about half the footprint.
export CARGO_INCREMENTAL=0
export CARGO_PROFILE_DEV_DEBUG=line-tables-only

cargo fmt --all -- --check
# Clippy also holds the code to the declared MSRV (rust-version in
# Cargo.toml): incompatible_msrv is a warning, and warnings are errors.
cargo clippy --workspace --all-targets --all-features -- -D warnings
RUSTDOCFLAGS="-D warnings" cargo doc --workspace --no-deps --all-features --quiet
# The default tier (`cargo test --workspace`) leaves out the tests that
# drive toolchains (C programs, sanitizers, the bare library, the
# install): they are #[ignore]d with their reason, and run here.
cargo test --workspace --all-features -- --include-ignored
# coray on a Cortex-M4 and a RISC-V core under QEMU, checked against the
# host (about 2 minutes; installs Debian's Rust, the Arm and RISC-V toolchains and QEMU when missing).
scripts/embedded.sh
