#!/usr/bin/env bash
# coray on a Cortex-M4F: builds the core and the bare C library for
# thumbv7em-none-eabihf with Debian's Rust (rustc-web, its library source
# in rust-web-src, -Zbuild-std=core), links embedded/program.c with the
# project's own start-up code and linker script (no C library at all), runs
# it on QEMU's mps2-an386 (Cortex-M4, semihosting), runs the same program
# built for the host against the host's bare library, and requires the same
# check lines from both. Prints flash, RAM and stack figures; fails when
# the kd-tree + LCTS firmware's flash passes 128 KiB or a kd phase's stack
# 32 KiB. Also builds the bare C library for x86_64-unknown-none (no SSE).
#
# Installs what is missing with apt-get (as root). Called by scripts/test.sh.
set -euo pipefail
cd "$(dirname "$0")/.."

need=()
[ -x /usr/bin/rustc ] && /usr/bin/rustc --print target-list | grep -qx thumbv7em-none-eabihf || need+=(rustc-web)
[ -x /usr/bin/cargo ] || need+=(cargo-web)
[ -d /usr/lib/rustlib/src/rust/library/core ] || need+=(rust-web-src)
command -v arm-none-eabi-gcc >/dev/null || need+=(gcc-arm-none-eabi)
[ -d /usr/lib/arm-none-eabi/newlib ] || need+=(libnewlib-arm-none-eabi)
command -v qemu-system-arm >/dev/null || need+=(qemu-system-arm)
if [ ${#need[@]} -gt 0 ]; then
    echo "installing ${need[*]}"
    apt-get update -qq
    if ! DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends --no-remove "${need[@]}"; then
        # The test command never removes a package: on a machine where
        # these would replace an installed one (a newer qemu-utils from
        # backports, say), the Cortex-M4 run is skipped and says why.
        echo "embedded.sh: SKIPPED: installing ${need[*]} would remove an installed package;"
        echo "install them by hand to run coray on the Cortex-M4 under QEMU"
        exit 0
    fi
fi

out=target/embedded
mkdir -p "$out"

# The scenes are built in: the committed headers must be what
# `coray export` writes today (the CLI built with the test profile, whose
# dependencies `cargo test` built already).
cargo run -q --profile test -p coray-cli -- export spd:mount:4 --prefix mount -o "$out/scene_mount.h" >/dev/null
cargo run -q --profile test -p coray-cli -- export spd:rings:1 --prefix rings -o "$out/scene_rings.h" >/dev/null
for h in scene_mount.h scene_rings.h; do
    cmp -s "$out/$h" "embedded/$h" || { echo "embedded/$h differs from coray export: regenerate it"; exit 1; }
done

# The library for the board: Debian's Rust 1.96, core built from source.
RUSTC_BOOTSTRAP=1 RUSTC=/usr/bin/rustc /usr/bin/cargo rustc -q -p coray-ffi \
    --no-default-features --profile embedded --target thumbv7em-none-eabihf \
    -Zbuild-std=core --target-dir "$out" --crate-type staticlib
board_lib="$out/thumbv7em-none-eabihf/embedded/libcoray_ffi.a"

# A soft-float x86-64 target (a kernel's: no SSE) builds the C library
# too: its wide walk reads ahead by loads, not by SSE prefetches.
RUSTC_BOOTSTRAP=1 RUSTC=/usr/bin/rustc /usr/bin/cargo rustc -q -p coray-ffi \
    --no-default-features --profile embedded --target x86_64-unknown-none \
    -Zbuild-std=core --target-dir "$out" --crate-type staticlib

# The host's bare library (profile bare, opt-level 3, this machine's
# toolchain): the checks must agree across optimisation levels too.
cargo build -q -p coray-ffi --no-default-features --profile bare --target-dir target/bare
host_lib=target/bare/bare/libcoray_ffi.a

# No fused multiply-add contraction in the program's own arithmetic:
# the Cortex-M4F has vfma, x86-64's baseline has none.
common=(-O2 -ffp-contract=off -std=c11 -Wall -Wextra -Werror -Iinclude -Iembedded)
arm=(-mcpu=cortex-m4 -mthumb -mfloat-abi=hard -mfpu=fpv4-sp-d16 -ffunction-sections -fdata-sections)
link=(-nostartfiles -nostdlib -T embedded/mps2_an386.ld -Wl,--gc-sections -Wl,--no-warn-rwx-segments -Wl,--no-warn-execstack -lgcc)
for variant in kd every; do
    defs=()
    [ "$variant" = every ] && defs=(-DEVERY_STRUCTURE)
    arm-none-eabi-gcc "${common[@]}" "${arm[@]}" "${defs[@]}" embedded/startup.c embedded/program.c \
        "$board_lib" "${link[@]}" -Wl,-Map="$out/firmware-$variant.map" -o "$out/firmware-$variant.elf"
done
cc "${common[@]}" -DEVERY_STRUCTURE embedded/host.c embedded/program.c "$host_lib" \
    -Wl,--gc-sections -o "$out/host-program"

"$out/host-program" > "$out/host.txt"
# Semihosting writes to QEMU's stderr.
start=$(date +%s%N)
timeout 600 qemu-system-arm -M mps2-an386 -nographic -monitor none -serial none -semihosting \
    -kernel "$out/firmware-every.elf" > /dev/null 2> "$out/board.txt" || {
    cat "$out/board.txt"; echo "embedded: the board program failed"; exit 1; }
ms=$((($(date +%s%N) - start) / 1000000))
cat "$out/board.txt"
grep '^check' "$out/host.txt" > "$out/host.checks"
grep '^check' "$out/board.txt" > "$out/board.checks"
if ! diff "$out/host.checks" "$out/board.checks"; then
    echo "embedded: the board and the host disagree"; exit 1
fi
grep -q '^embedded: ok' "$out/board.txt" || { echo "embedded: the board program failed"; exit 1; }
echo "embedded: $(wc -l < "$out/board.checks") check lines identical on the Cortex-M4 and the host (board run $ms ms)"
# The README tells a kd-tree + LCTS program to give coray 32 KiB of stack:
# every kd phase's painted high-water mark must stay under it.
kd_stack=$(awk '/^board stack kd / && $NF + 0 > m { m = $NF + 0 } END { print m + 0 }' "$out/board.txt")
echo "stack (kd phases): $kd_stack bytes at most"
if [ "$kd_stack" -gt $((32 * 1024)) ]; then
    echo "embedded: a kd phase's stack passes the 32 KiB the README gives"; exit 1
fi

# Flash: .text holds code and read-only data (the linker script merges
# them); the scenes' arrays are counted apart.
scene_bytes() {
    arm-none-eabi-nm -S -t d "$1" | awk '$4 ~ /^(mount|rings)_/ { s += $2 } END { print s + 0 }'
}
for variant in kd every; do
    elf="$out/firmware-$variant.elf"
    text=$(arm-none-eabi-size -A "$elf" | awk '$1 == ".text" { print $2 }')
    scenes=$(scene_bytes "$elf")
    code=$((text - scenes))
    echo "flash ($variant): $text bytes of .text + .rodata, $scenes of them the built-in scenes: $code bytes ($((code / 1024)) KiB) of coray and the program"
    if [ "$variant" = kd ] && [ "$code" -gt $((128 * 1024)) ]; then
        echo "embedded: the kd-tree + LCTS firmware passes 128 KiB of flash"; exit 1
    fi
done
bss=$(arm-none-eabi-size -A "$out/firmware-every.elf" | awk '$1 == ".bss" { print $2 }')
echo "ram: $bss bytes of static arenas and buffers (.bss), 65536 of stack"
