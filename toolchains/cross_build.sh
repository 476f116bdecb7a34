#!/usr/bin/env bash
# cross_build.sh <aarch64|armhf> [--no-embedded]
#
# From a clean clone: installs the host tools it needs (idempotently),
# prepares the cached target sysroot, configures and builds keepless for the
# board, runs the whole ctest suite under qemu user-mode emulation (including
# the installed-package consumer and the cross-architecture decision hashes),
# then builds the embedded profile (keepless::solver/core at -Os without
# exceptions or RTTI), runs the solver, core and cross tests against it, and
# prints the libraries' static footprint. Exits 0 only if every test passed.
#
#   aarch64: presets `aarch64` (build-aarch64/) and `embedded`
#            (build-aarch64-embedded/)
#   armhf:   toolchains/arm-linux-gnueabihf.cmake (build-armhf/), no embedded
set -euo pipefail

arch="${1:-}"
embedded=1
[[ "${2:-}" == "--no-embedded" ]] && embedded=0
case "$arch" in
  aarch64) triple=aarch64-linux-gnu ;;
  armhf)   triple=arm-linux-gnueabihf; embedded=0 ;;
  *) echo "usage: $0 <aarch64|armhf> [--no-embedded]" >&2; exit 2 ;;
esac
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
start=$SECONDS
step() { printf '\n== %s (%ds)\n' "$*" $((SECONDS - start)); }

# --- host tools --------------------------------------------------------------
# lcm-gen runs on the host during the build (liblcm-bin); everything the
# target links comes from the sysroot.
host_packages=(cmake ninja-build pkgconf qemu-user "g++-$triple" "binutils-$triple"
               liblcm-bin)
missing=()
for p in "${host_packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' || missing+=("$p")
done
if ((${#missing[@]})); then
  step "installing host packages: ${missing[*]}"
  as_root() { if [[ $(id -u) -eq 0 ]]; then "$@"; else sudo "$@"; fi; }
  export DEBIAN_FRONTEND=noninteractive
  as_root apt-get install -y -q --no-install-recommends "${missing[@]}" ||
    { as_root apt-get update -q || true
      as_root apt-get install -y -q --no-install-recommends "${missing[@]}"; }
fi

step "sysroot"
"$root/toolchains/prepare_sysroot.sh" "$arch"

status=0
# --- full build and suite under qemu -----------------------------------------
if [[ "$arch" == aarch64 ]]; then
  build="$root/build-aarch64"
  step "configure (preset aarch64)"
  cmake --preset aarch64
  step "build"
  cmake --build --preset aarch64
  step "ctest under qemu-aarch64"
  ctest --preset aarch64 || status=1
else
  build="$root/build-$arch"
  step "configure ($triple)"
  cmake -S "$root" -B "$build" -G Ninja -DCMAKE_TOOLCHAIN_FILE="$root/toolchains/$triple.cmake" \
        -DCMAKE_BUILD_TYPE=Release -DKEEPLESS_WERROR=ON -DKEEPLESS_BUILD_PERF=OFF
  step "build"
  cmake --build "$build" -j2
  step "ctest under qemu-arm"
  ctest --test-dir "$build" --output-on-failure -j2 || status=1
fi

# --- embedded profile --------------------------------------------------------
footprint() {  # footprint <label> <build dir>
  local lib
  for lib in solver core; do
    local a="$2/$lib/libkeepless_$lib.a"
    [[ -f "$a" ]] || continue
    # size -t: one line per object, then the archive's total.
    "$triple-size" -t "$a" | tail -1 |
      awk -v n="keepless_$lib" -v l="$1" '{printf "  %-8s %-16s text %7d  data %5d  bss %5d\n", l, n, $1, $2, $3}'
  done
}
if ((embedded)); then
  ebuild="$root/build-aarch64-embedded"
  step "configure (preset embedded)"
  cmake --preset embedded
  step "build solver, core and their tests (-Os -fno-exceptions -fno-rtti)"
  cmake --build --preset embedded
  step "ctest (embedded) under qemu-aarch64: labels solver, core, cross"
  ctest --preset embedded || status=1
fi

step "static footprint ($triple-size -t, whole archive)"
footprint release "$build"
((embedded)) && footprint embedded "$ebuild"

step "done"
if ((status)); then echo "cross_build.sh $arch: FAILED"; else echo "cross_build.sh $arch: all tests passed"; fi
exit $status
