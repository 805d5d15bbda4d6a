#!/usr/bin/env bash
# Runs every test of coray: Rust unit and integration tests, the C programs
# (API contract, allocation counting, canaries, threads, the bare no-std
# library, the Embree cross-check) and the header drift check.
# On a fresh Debian machine it installs what it needs (as root).
set -euo pipefail
cd "$(dirname "$0")/.."

if [ ! -f /usr/include/embree3/rtcore.h ]; then
    echo "installing libembree-dev (Embree 3, the cross-check reference)"
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq libembree-dev
fi
for tool in cc c++ nm; do
    command -v "$tool" >/dev/null || { echo "missing $tool"; exit 1; }
done

cargo fmt --all -- --check
cargo clippy --workspace --all-targets --all-features -- -D warnings
cargo test --workspace --all-features
