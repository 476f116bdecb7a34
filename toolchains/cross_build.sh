#!/usr/bin/env bash
# cross_build.sh <aarch64|armhf> [--ci] [--no-embedded]
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
#   armhf:   presets `armhf` (build-armhf/) and `embedded-armhf`
#            (build-armhf-embedded/)
#
# --ci: the shorter run CI makes: no full build; the embedded profile only,
# with the lcm tests built and run beside the solver, core and cross ones.
# --no-embedded: the full build and suite only.
set -euo pipefail

arch="${1:-}"
shift || true
embedded=1 full=1
for flag in "$@"; do
  case "$flag" in
    --ci) full=0 ;;
    --no-embedded) embedded=0 ;;
    *) arch="" ;;
  esac
done
case "$arch" in
  aarch64) triple=aarch64-linux-gnu;   qemu=qemu-aarch64; embedded_preset=embedded ;;
  armhf)   triple=arm-linux-gnueabihf; qemu=qemu-arm;     embedded_preset=embedded-armhf ;;
  *) echo "usage: $0 <aarch64|armhf> [--ci] [--no-embedded]" >&2; exit 2 ;;
esac
if ((!full && !embedded)); then
  echo "cross_build.sh: --ci runs the embedded profile; it cannot be combined with --no-embedded" >&2
  exit 2
fi
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
start=$SECONDS
step() { printf '\n== %s (%ds)\n' "$*" $((SECONDS - start)); }

# --- host tools --------------------------------------------------------------
# lcm-gen runs on the host during the build (liblcm-bin); everything the
# target links comes from the sysroot. The lcm label (run by --ci too) holds
# the Java check: javac with lcm.jar. The full suite also runs colmap (the
# map tests' checker).
host_packages=(cmake ninja-build pkgconf qemu-user "g++-$triple" "binutils-$triple"
               liblcm-bin default-jdk-headless liblcm-java)
((full)) && host_packages+=(colmap)
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
build="$root/build-$arch"
if ((full)); then
  step "configure (preset $arch)"
  cmake --preset "$arch"
  step "build"
  cmake --build --preset "$arch"
  step "ctest under $qemu"
  ctest --preset "$arch" | tee "$build/ctest-$arch.log" || status=1
  # The one deliberate skip: an allocation failure cannot be provoked under qemu.
  "$root/scripts/check_skips.sh" "$build/ctest-$arch.log" SparsifyMaps.AnAllocationFailureNamesTheFileAndTheLimit ||
    status=1
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
ebuild="$root/build-$arch-embedded"
if ((embedded)); then
  step "configure (preset $embedded_preset)"
  cmake --preset "$embedded_preset"
  step "build solver, core and their tests (-Os -fno-exceptions -fno-rtti)"
  cmake --build --preset "$embedded_preset"
  if ((full)); then
    step "ctest (embedded) under $qemu: labels solver, core, cross"
    ctest --preset "$embedded_preset" | tee "$ebuild/ctest-embedded.log" || status=1
    "$root/scripts/check_skips.sh" "$ebuild/ctest-embedded.log" || status=1
  else
    # The lcm tests (node, messages, bus) on the same build: the node links
    # the embedded libraries, as on the board.
    step "build the lcm tests (embedded)"
    cmake --build "$ebuild" --target tests/lcm/all -j2
    step "ctest (embedded) under $qemu: labels solver, core, cross, lcm"
    # An lcm label without tests would pass silently: count them first.
    if ! ctest --test-dir "$ebuild" -N -L '^lcm$' | grep -qE 'Total Tests: [1-9]'; then
      echo "cross_build.sh: no lcm tests in $ebuild (LCM missing from the sysroot?)" >&2
      status=1
    fi
    ctest --test-dir "$ebuild" --output-on-failure -j2 -L '^(solver|core|cross|lcm)$' |
      tee "$ebuild/ctest-embedded.log" || status=1
    "$root/scripts/check_skips.sh" "$ebuild/ctest-embedded.log" || status=1
  fi
fi

step "static footprint ($triple-size -t, whole archive)"
((full)) && footprint release "$build"
((embedded)) && footprint embedded "$ebuild"

step "done"
what="$arch"; ((full)) || what="$arch --ci"
if ((status)); then echo "cross_build.sh $what: FAILED"; else echo "cross_build.sh $what: all tests passed"; fi
exit $status
