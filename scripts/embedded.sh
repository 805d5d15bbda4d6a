#!/usr/bin/env bash
# coray on two microcontroller instruction sets: builds the core and the
# bare C library with Debian's Rust (rustc-web, its library source in
# rust-web-src, -Zbuild-std=core) for a Cortex-M4F (thumbv7em-none-eabihf)
# and a 32-bit RISC-V core (riscv32imafc-unknown-none-elf), links
# embedded/program.c with the project's own start-up code and linker
# script for each board (no C library at all), runs them under QEMU
# (mps2-an386 and virt, semihosting, -icount: instructions counted
# exactly), runs the same program built for the host against the host's
# bare library, and requires the same check lines from all three.
# Prints flash, RAM and stack figures and the casts' instructions per
# pixel; fails when a kd-tree + LCTS firmware's flash passes 128 KiB or a
# kd phase's stack 32 KiB. Also builds the bare C library for
# x86_64-unknown-none (no SSE). The figures also go to
# target/embedded/figures.txt (docs/embedded-figures.txt is a copy).
#
# Installs what is missing with apt-get (as root), never removing a
# package: where Debian's QEMU would replace an installed qemu-utils from
# backports, it takes QEMU from the same backports suite. Called by
# scripts/test.sh.
set -euo pipefail
cd "$(dirname "$0")/.."

out=target/embedded
mkdir -p "$out"

apt_install() {
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends --no-remove "$@"
}

# QEMU from this release's backports suite, through a sources directory of
# our own (the machine's sources and backports): the machine's apt
# configuration is left as it was.
qemu_from_backports() {
    local codename parts="$out/apt-sources"
    codename=$(. /etc/os-release && echo "${VERSION_CODENAME:-}")
    [ -n "$codename" ] || return 1
    rm -rf "$parts" && mkdir -p "$parts"
    cp /etc/apt/sources.list.d/*.sources /etc/apt/sources.list.d/*.list "$parts"/ 2>/dev/null || true
    cat > "$parts/coray-backports.sources" <<EOF
Types: deb
URIs: http://deb.debian.org/debian
Suites: $codename-backports
Components: main
Signed-By: /usr/share/keyrings/debian-archive-keyring.gpg
EOF
    local opt=(-o "Dir::Etc::SourceParts=$(cd "$parts" && pwd)/")
    apt-get update -qq "${opt[@]}" &&
        apt_install "${opt[@]}" -t "$codename-backports" qemu-system-arm qemu-system-riscv
}

need=()
[ -x /usr/bin/rustc ] && /usr/bin/rustc --print target-list | grep -qx thumbv7em-none-eabihf || need+=(rustc-web)
[ -x /usr/bin/cargo ] || need+=(cargo-web)
[ -d /usr/lib/rustlib/src/rust/library/core ] || need+=(rust-web-src)
command -v arm-none-eabi-gcc >/dev/null || need+=(gcc-arm-none-eabi)
[ -d /usr/lib/arm-none-eabi/newlib ] || need+=(libnewlib-arm-none-eabi)
command -v riscv64-unknown-elf-gcc >/dev/null || need+=(gcc-riscv64-unknown-elf)
qemu=()
command -v qemu-system-arm >/dev/null || qemu+=(qemu-system-arm)
command -v qemu-system-riscv32 >/dev/null || qemu+=(qemu-system-misc)
if [ $((${#need[@]} + ${#qemu[@]})) -gt 0 ]; then
    echo "installing ${need[*]} ${qemu[*]}"
    apt-get update -qq
    [ ${#need[@]} -eq 0 ] || apt_install "${need[@]}"
    if [ ${#qemu[@]} -gt 0 ] && ! apt_install "${qemu[@]}"; then
        echo "embedded.sh: Debian's ${qemu[*]} would remove an installed package; QEMU from backports"
        if ! qemu_from_backports; then
            echo "embedded.sh: SKIPPED: no QEMU installs here without removing a package;"
            echo "install qemu-system-arm and qemu-system-riscv32 by hand to run coray on the boards"
            exit 0
        fi
    fi
fi

# The scenes are built in: the committed headers must be what
# `coray export` writes today (the CLI built with the test profile, whose
# dependencies `cargo test` built already).
cargo run -q --profile test -p coray-cli -- export spd:mount:4 --prefix mount -o "$out/scene_mount.h" >/dev/null
cargo run -q --profile test -p coray-cli -- export spd:rings:1 --prefix rings -o "$out/scene_rings.h" >/dev/null
for h in scene_mount.h scene_rings.h; do
    cmp -s "$out/$h" "embedded/$h" || { echo "embedded/$h differs from coray export: regenerate it"; exit 1; }
done

# The bare C library for a no-std target: Debian's Rust, core built from
# source, profile embedded (opt-level s, LTO).
board_library() {
    RUSTC_BOOTSTRAP=1 RUSTC=/usr/bin/rustc /usr/bin/cargo rustc -q -p coray-ffi \
        --no-default-features --profile embedded --target "$1" \
        -Zbuild-std=core --target-dir "$out" --crate-type staticlib
}
board_library thumbv7em-none-eabihf
board_library riscv32imafc-unknown-none-elf
# A soft-float x86-64 target (a kernel's: no SSE) builds the C library
# too: its wide walk reads ahead by loads, not by SSE prefetches.
board_library x86_64-unknown-none

# The host's bare library (profile bare, opt-level 3, this machine's
# toolchain): the checks must agree across optimisation levels too.
cargo build -q -p coray-ffi --no-default-features --profile bare --target-dir target/bare
host_lib=target/bare/bare/libcoray_ffi.a

# No fused multiply-add contraction in the program's own arithmetic: both
# boards have one (vfma, fmadd.s), x86-64's baseline has none.
common=(-O2 -ffp-contract=off -std=c11 -Wall -Wextra -Werror -Iinclude -Iembedded
    -ffunction-sections -fdata-sections)
nolibc=(-nostartfiles -nostdlib -Wl,--gc-sections -Wl,--no-warn-rwx-segments -lgcc)
# firmware BOARD CC FLAGS...: the kd-only and the every-structure firmware.
firmware() {
    local board=$1 cc=$2 lib
    shift 2
    lib="$out/$(board_target "$board")/embedded/libcoray_ffi.a"
    for variant in kd every; do
        local defs=()
        [ "$variant" = every ] && defs=(-DEVERY_STRUCTURE)
        "$cc" "${common[@]}" "$@" "${defs[@]}" "embedded/$board/startup.c" embedded/board.c embedded/program.c "$lib" \
            -T "embedded/$board/link.ld" "${nolibc[@]}" -Wl,-Map="$out/$board-$variant.map" \
            -o "$out/$board-$variant.elf"
    done
}
board_target() {
    case $1 in
    mps2_an386) echo thumbv7em-none-eabihf ;;
    riscv_virt) echo riscv32imafc-unknown-none-elf ;;
    esac
}
firmware mps2_an386 arm-none-eabi-gcc -mcpu=cortex-m4 -mthumb -mfloat-abi=hard -mfpu=fpv4-sp-d16 \
    -Wl,--no-warn-execstack
# -ffreestanding: GCC's own <stdint.h>, no C library's headers.
firmware riscv_virt riscv64-unknown-elf-gcc -march=rv32imafc -mabi=ilp32f -mcmodel=medany \
    -msmall-data-limit=0 -ffreestanding
cc "${common[@]}" -DEVERY_STRUCTURE embedded/host.c embedded/program.c "$host_lib" \
    -Wl,--gc-sections -o "$out/host-program"

"$out/host-program" > "$out/host.txt"
grep '^check' "$out/host.txt" > "$out/host.checks"

# run_board BOARD NAME QEMU ARGS...: the every-structure firmware under
# QEMU (semihosting writes to QEMU's stderr), its check lines against
# the host's, its stack against the README's 32 KiB.
run_board() {
    local board=$1 name=$2 start ms
    shift 2
    start=$(date +%s%N)
    timeout 600 "$@" -nographic -monitor none -serial none -semihosting \
        -kernel "$out/$board-every.elf" > /dev/null 2> "$out/$board.txt" || {
        cat "$out/$board.txt"; echo "embedded: the $name program failed"; exit 1; }
    ms=$((($(date +%s%N) - start) / 1000000))
    cat "$out/$board.txt"
    grep '^check' "$out/$board.txt" > "$out/$board.checks"
    if ! diff "$out/host.checks" "$out/$board.checks"; then
        echo "embedded: the $name and the host disagree"; exit 1
    fi
    grep -q '^embedded: ok' "$out/$board.txt" || { echo "embedded: the $name program failed"; exit 1; }
    echo "embedded: $(wc -l < "$out/$board.checks") check lines identical on the $name and the host (run $ms ms)"
    # The README tells a kd-tree + LCTS program to give coray 32 KiB of
    # stack: every kd phase's painted high-water mark must stay under it.
    local kd_stack
    kd_stack=$(awk '/^board stack kd / && $NF + 0 > m { m = $NF + 0 } END { print m + 0 }' "$out/$board.txt")
    if [ "$kd_stack" -gt $((32 * 1024)) ]; then
        echo "embedded: a kd phase's stack on the $name passes the 32 KiB the README gives"; exit 1
    fi
}
# -icount shift=6: one instruction is 64 ns of virtual time (the
# Cortex-M4's start-up reads instructions off the FPGA's 25 MHz counter
# with that factor; RISC-V's minstret counts them under any shift).
icount=(-icount shift=6)
run_board mps2_an386 Cortex-M4 qemu-system-arm -M mps2-an386 "${icount[@]}"
run_board riscv_virt RISC-V qemu-system-riscv32 -M virt -bios none "${icount[@]}"

# The figures: flash (.text holds code and read-only data, the linker
# scripts merge them; the scenes' arrays are counted apart), RAM, stack
# per phase and instructions per pixel of each cast.
scene_bytes() {
    "$1" -S -t d "$2" | awk '$4 ~ /^(mount|rings)_/ { s += $2 } END { print s + 0 }'
}
flash_over=0
{
    echo "# scripts/embedded.sh: coray on the Cortex-M4 (QEMU mps2-an386) and RISC-V (QEMU virt, RV32IMAFC)"
    for board in mps2_an386 riscv_virt; do
        case $board in
        mps2_an386) name=Cortex-M4 tools=arm-none-eabi ;;
        riscv_virt) name=RISC-V tools=riscv64-unknown-elf ;;
        esac
        for variant in kd every; do
            elf="$out/$board-$variant.elf"
            text=$("$tools-size" -A "$elf" | awk '$1 == ".text" { print $2 }')
            scenes=$(scene_bytes "$tools-nm" "$elf")
            code=$((text - scenes))
            echo "$name flash ($variant): $code bytes ($((code / 1024)) KiB) of coray and the program ($text of .text + .rodata, $scenes of them the built-in scenes)"
            if [ "$variant" = kd ] && [ "$code" -gt $((128 * 1024)) ]; then flash_over=1; fi
        done
        bss=$("$tools-size" -A "$out/$board-every.elf" | awk '$1 == ".bss" { print $2 }')
        echo "$name ram: $bss bytes of static arenas and buffers (.bss), 65536 of stack"
        # A phase runs once per scene and tree: its deepest stack of all.
        awk -v name="$name" '/^board stack .* bytes [0-9]+$/ {
            phase = $0; sub(/^board stack /, "", phase); sub(/ bytes [0-9]+$/, "", phase)
            if (!(phase in most)) order[n++] = phase
            if ($NF + 0 > most[phase]) most[phase] = $NF + 0
        } END { for (i = 0; i < n; i++) print name " stack, " order[i] ": " most[order[i]] " bytes" }' "$out/$board.txt"
    done
    echo "instructions per pixel of a 64 x 64 cast (camera rays included; paper tree), and eta = over the hierarchical cast"
    printf '%-12s %-16s %-14s %14s %8s\n' board scene cast instructions eta
    for board in mps2_an386 riscv_virt; do
        case $board in mps2_an386) name=Cortex-M4 ;; riscv_virt) name=RISC-V ;; esac
        awk -v name="$name" '$1 == "count" && $4 == "paper" {
            scene = $2; cast = $6; n = $NF / 4096
            if (cast == "hierarchical") base[scene] = n
            printf "%-12s %-16s %-14s %14.0f %8.3f\n", name, scene, cast, n, n / base[scene]
        }' "$out/$board.txt"
    done
} > "$out/figures.txt"
cat "$out/figures.txt"
if [ "$flash_over" = 1 ]; then
    echo "embedded: a kd-tree + LCTS firmware passes 128 KiB of flash"; exit 1
fi
