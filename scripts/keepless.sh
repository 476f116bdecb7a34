#!/usr/bin/env bash
# One entry point for a fresh Debian bookworm machine (root, apt reachable):
#   demo       install what is missing, build (release preset), run the main job
#   test       install what is missing, build (release preset), run the whole ctest suite
#   test-asan  the same in the ASan+UBSan preset (build-asan/)
# Installing is idempotent: apt runs only when a package is missing.
set -euo pipefail
cd "$(dirname "$0")/.."

PACKAGES=(
  cmake g++ make pkg-config
  libeigen3-dev liblcm-dev liblcm-bin liblcm-java libglib2.0-dev
  libopencv-core-dev libopencv-features2d-dev libopencv-imgproc-dev libopencv-imgcodecs-dev
  libopencv-dev  # the only package with OpenCV's CMake config (keepless_eval)
  libgtest-dev libgmock-dev libbenchmark-dev liblemon-dev libceres-dev
  colmap  # the map tests' external checker (ctest -L colmap)
)

install_missing() {
  local missing=()
  for p in "${PACKAGES[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  if ((${#missing[@]})); then
    echo "keepless: installing ${missing[*]}"
    local sudo=""
    [ "$(id -u)" -eq 0 ] || sudo="sudo"
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
  fi
}

build() {  # build <preset>
  cmake --preset "$1" >/dev/null
  cmake --build --preset "$1"
}

case "${1:-}" in
  demo)
    install_missing
    build release
    scripts/run_demo.sh build
    ;;
  test)
    install_missing
    build release
    ctest --preset release
    ;;
  test-asan)
    install_missing
    build asan
    ctest --preset asan
    ;;
  *)
    echo "usage: $0 demo|test|test-asan" >&2
    exit 2
    ;;
esac
