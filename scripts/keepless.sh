#!/usr/bin/env bash
# One entry point for a fresh Debian or Ubuntu machine:
#   demo       install what the demo needs, build its three programs (release preset), run the main job
#   test       install everything, build (release preset), run the whole ctest suite
#   test-asan  the same in the ASan+UBSan preset (build-asan/)
#   packages   print the packages each command needs (Debian names, then what they are upstream)
# Installing is idempotent: apt runs only when a package is missing, as root or through sudo when
# there is one. --no-install (or KEEPLESS_NO_INSTALL=1) skips it, e.g. for dependencies built from
# source or a machine without root.
set -euo pipefail
cd "$(dirname "$0")/.."

# What the demo builds and runs: the node, the simulator and the log comparer need LCM only.
DEMO_PACKAGES=(
  cmake g++ make pkg-config
  liblcm-dev liblcm-bin libglib2.0-dev
)
# Everything else the whole suite builds: the OpenCV adapter, the evaluation (Ceres, OpenCV),
# the tests (GoogleTest, LEMON), the benchmarks, COLMAP as the map tests' external checker,
# Java for the LCM types' Java check, Doxygen and Python for the docs check.
TEST_PACKAGES=(
  "${DEMO_PACKAGES[@]}"
  libeigen3-dev liblcm-java default-jdk-headless  # lcm.jar and javac: the Java message classes' check
  libopencv-core-dev libopencv-features2d-dev libopencv-imgproc-dev libopencv-imgcodecs-dev
  libopencv-dev  # the only package with OpenCV's CMake config (keepless::opencv, keepless_eval)
  libgtest-dev liblemon-dev libceres-dev
  colmap  # the map tests' external checker (ctest -L colmap)
  doxygen python3  # scripts/check_docs.sh
)

# The same needs by upstream name, for distributions without apt.
UPSTREAM="CMake >= 3.22, a C++17 compiler (GCC >= 9 or Clang >= 10), make or Ninja, pkg-config
LCM >= 1.3 (library, headers, lcm-gen; lcm-logger/lcm-logplayer for the demo's replay), GLib 2
for test also: Eigen >= 3.3, OpenCV >= 4 (core, features2d, imgproc, imgcodecs, with its CMake config),
  GoogleTest, LEMON >= 1.3, Ceres Solver >= 2.0, COLMAP >= 3.8,
  LCM's Java jar (optional), Doxygen, Python 3"

NO_INSTALL=${KEEPLESS_NO_INSTALL:-0}
[ "$NO_INSTALL" = 0 ] || [ "$NO_INSTALL" = 1 ] || NO_INSTALL=1

print_packages() {
  echo "demo (Debian/Ubuntu): ${DEMO_PACKAGES[*]}"
  echo "test, test-asan (Debian/Ubuntu): ${TEST_PACKAGES[*]}"
  echo
  echo "Other distributions, by upstream name:"
  echo "$UPSTREAM"
}

install_missing() {  # install_missing <package>...
  [ "$NO_INSTALL" = 0 ] || return 0
  if ! command -v apt-get >/dev/null || ! command -v dpkg-query >/dev/null; then
    {
      echo "keepless: no apt-get here, so nothing is installed; make sure these are present:"
      echo "$UPSTREAM"
      echo "keepless: (--no-install or KEEPLESS_NO_INSTALL=1 silences this note)"
    } >&2
    return 0
  fi
  local missing=()
  for p in "$@"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  ((${#missing[@]})) || return 0
  local sudo=""
  if [ "$(id -u)" -ne 0 ]; then
    if command -v sudo >/dev/null; then
      sudo="sudo"
    else
      {
        echo "keepless: missing packages: ${missing[*]}"
        echo "keepless: not root and no sudo; as root run:"
        echo "  apt-get update && apt-get install -y --no-install-recommends ${missing[*]}"
        echo "keepless: or, if they are installed another way (built from source), run with --no-install"
      } >&2
      exit 1
    fi
  fi
  echo "keepless: installing ${missing[*]}"
  $sudo apt-get update -qq
  $sudo env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
}

cmd=""
for arg in "$@"; do
  case "$arg" in
    --no-install) NO_INSTALL=1 ;;
    demo|test|test-asan|packages) [ -z "$cmd" ] && cmd=$arg || { echo "$0: one command only" >&2; exit 2; } ;;
    -h|--help) cmd=help ;;
    *) echo "$0: unknown argument '$arg'" >&2; cmd=bad ;;
  esac
done

usage() {
  echo "usage: $0 [--no-install] demo|test|test-asan|packages"
  echo "  --no-install       do not install packages (also KEEPLESS_NO_INSTALL=1)"
}

case "$cmd" in
  demo)
    install_missing "${DEMO_PACKAGES[@]}"
    # A build/ configured earlier (e.g. by test) is reused as it is; a fresh one is configured
    # without the parts that need more than LCM.
    if [ ! -f build/CMakeCache.txt ]; then
      cmake --preset release -DKEEPLESS_BUILD_TESTS=OFF -DKEEPLESS_BUILD_PERF=OFF \
            -DKEEPLESS_BUILD_OPENCV=OFF >/dev/null
    fi
    cmake --build --preset release --target keepless_node keepless_vo_sim keepless_log_compare
    scripts/run_demo.sh build
    ;;
  test)
    install_missing "${TEST_PACKAGES[@]}"
    # Every part on, whatever an earlier demo configured (the examples' default follows the tests).
    cmake --preset release -DKEEPLESS_BUILD_TESTS=ON -DKEEPLESS_BUILD_PERF=ON \
          -DKEEPLESS_BUILD_OPENCV=ON -DKEEPLESS_BUILD_EXAMPLES=ON -DKEEPLESS_BUILD_LCM=ON >/dev/null
    cmake --build --preset release
    ctest --preset release | tee build/ctest-release.log
    # A skipped test is one that did not check anything: under CI (the data folder present) that
    # fails the run; elsewhere it is listed above and repeated here.
    scripts/check_skips.sh build/ctest-release.log
    ;;
  test-asan)
    install_missing "${TEST_PACKAGES[@]}"
    cmake --preset asan -DKEEPLESS_BUILD_EXAMPLES=ON -DKEEPLESS_BUILD_LCM=ON >/dev/null
    cmake --build --preset asan
    mkdir -p build-asan
    ctest --preset asan | tee build-asan/ctest-asan.log
    # The one deliberate skip: an allocation failure cannot be provoked under the sanitizer.
    scripts/check_skips.sh build-asan/ctest-asan.log SparsifyMaps.AnAllocationFailureNamesTheFileAndTheLimit
    ;;
  packages)
    print_packages
    ;;
  help)
    usage
    ;;
  *)
    usage >&2
    exit 2
    ;;
esac
