#!/usr/bin/env bash
# prepare_sysroot.sh <aarch64|armhf> [SYSROOT]
#
# Builds a target sysroot from Debian's own packages for that architecture by
# downloading the .debs and extracting them (dpkg -x). Nothing is installed
# for the foreign architecture: liblcm-dev:arm64 is not co-installable with
# the host's liblcm-dev, and multiarch-installing it would remove the host
# lcm-gen and OpenCV. The cross compiler itself (g++-<triple>) brings its own
# libc/libstdc++ headers; the sysroot supplies the dependencies (LCM, glib,
# GoogleTest, LEMON, Eigen) and the runtime that qemu loads with -L.
#
# Cached: SYSROOT/.keepless-sysroot holds a hash of the package list; a rerun
# with the same list does nothing (delete the sysroot to pick up package
# updates). Default SYSROOT, where the toolchain files look for it
# (toolchains/linux_cross.cmake; -DKEEPLESS_SYSROOT overrides both):
#   $KEEPLESS_SYSROOT, else
#   ${KEEPLESS_CACHE_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/keepless}/sysroot-<arch>
# Needs no root: apt runs with a private state directory under the cache.
set -euo pipefail

arch="${1:-}"
case "$arch" in
  aarch64) debarch=arm64; triple=aarch64-linux-gnu ;;
  armhf)   debarch=armhf; triple=arm-linux-gnueabihf ;;
  *) echo "usage: $0 <aarch64|armhf> [SYSROOT]" >&2; exit 2 ;;
esac
cache="${KEEPLESS_CACHE_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/keepless}"
sysroot="${2:-${KEEPLESS_SYSROOT:-$cache/sysroot-$arch}}"

# Target packages, listed explicitly (no dependency resolution against the
# host's dpkg state). Runtime closure of what the tests and the consumer load:
# libc, libstdc++, libgcc, and LCM -> glib -> {ffi, mount, blkid, selinux,
# pcre2, zlib}. -dev packages: headers, static GoogleTest, and the .pc files
# pkg-config walks for `lcm` (lcm.pc requires glib-2.0, gthread-2.0 and,
# privately, libpcre2-8). LEMON (the solver tests' reference) is used through
# its static liblemon.a and headers only, so its shared library's GLPK
# dependency is not needed.
packages=(
  libc6 libc6-dev linux-libc-dev libcrypt1 libcrypt-dev
  libgcc-s1 libgcc-12-dev libstdc++6 libstdc++-12-dev gcc-12-base
  liblcm1 liblcm-dev
  libglib2.0-0 libglib2.0-dev libpcre2-8-0 libpcre2-dev
  libffi8 libmount1 libblkid1 libselinux1 zlib1g
  libgtest-dev
  liblemon-dev
)
arch_all_packages=(libeigen3-dev)
layout_version=3  # bump when the extraction steps below change

stamp_text="$(printf '%s\n' "layout=$layout_version" "$debarch" "${packages[@]}" "${arch_all_packages[@]}")"
stamp_hash="$(printf '%s' "$stamp_text" | sha256sum | cut -d' ' -f1)"
if [[ -f "$sysroot/.keepless-sysroot" && "$(cat "$sysroot/.keepless-sysroot")" == "$stamp_hash" ]]; then
  echo "sysroot: cached $sysroot"
  exit 0
fi

# apt runs with its own state under the cache, for the target architecture
# only: the host's dpkg architectures and package lists are left untouched
# (no `dpkg --add-architecture`), so the host's own apt runs never fetch or
# trip over foreign indices. Only the first run (or a stale list) updates.
apt_dir="$cache/apt-$arch"
mkdir -p "$apt_dir/lists/partial" "$apt_dir/archives/partial"
apt_opts=(-o "APT::Architecture=$debarch" -o "APT::Architectures::=$debarch"
          -o "Dir::State::Lists=$apt_dir/lists" -o "Dir::Cache=$apt_dir"
          -o "Dir::Cache::pkgcache=" -o "Dir::Cache::srcpkgcache=")
apt_update() {
  # A partial update (a mirror mid-sync) is not fatal: the download below
  # fails clearly if a package is really missing.
  apt-get "${apt_opts[@]}" update -qq || echo "prepare_sysroot: apt-get update reported errors" >&2
}
[[ -n "$(ls -A "$apt_dir/lists" | grep -v '^partial$' | grep -v '^lock$')" ]] || apt_update

debs="$cache/debs-$arch"
mkdir -p "$debs"
targets=()
for p in "${packages[@]}"; do targets+=("$p:$debarch"); done
targets+=("${arch_all_packages[@]}")
(
  cd "$debs"
  # Old versions would also be extracted: start each download from empty.
  rm -f ./*.deb
  # apt-get download as root warns that _apt cannot write here; harmless.
  if ! apt-get "${apt_opts[@]}" download -q "${targets[@]}" >"$debs/apt.log" 2>&1; then
    # A stale package list points at versions the mirror no longer has.
    apt_update
    apt-get "${apt_opts[@]}" download -q "${targets[@]}" >"$debs/apt.log" 2>&1 ||
      { cat "$debs/apt.log" >&2; exit 1; }
  fi
)

tmp="$sysroot.tmp.$$"
rm -rf "$tmp"
mkdir -p "$tmp"
for deb in "$debs"/*.deb; do
  dpkg -x "$deb" "$tmp"
done

# Absolute symlinks would point into the host (e.g. /lib/<triple>/libfoo.so.1);
# make them relative so they resolve inside the sysroot wherever it lives.
while IFS= read -r -d '' link; do
  target="$(readlink "$link")"
  [[ "$target" == /* ]] || continue
  rel="$(realpath -m --relative-to="$(dirname "$link")" "$tmp$target")"
  ln -sfn "$rel" "$link"
done < <(find "$tmp" -type l -print0)

# Debian selects BLAS/LAPACK through update-alternatives, which dpkg -x does
# not run: recreate those links if a package brought the implementation.
libdir="$tmp/usr/lib/$triple"
for lib in blas lapack; do
  if [[ -e "$libdir/$lib/lib$lib.so.3" && ! -e "$libdir/lib$lib.so.3" ]]; then
    ln -s "$lib/lib$lib.so.3" "$libdir/lib$lib.so.3"
  fi
  if [[ -e "$libdir/$lib/lib$lib.so" && ! -e "$libdir/lib$lib.so" ]]; then
    ln -s "$lib/lib$lib.so" "$libdir/lib$lib.so"
  fi
done

# Package config files that name host-absolute paths ("/usr/include",
# "/usr/lib/<triple>/liblemon.a": LEMON's) would send a cross build to the
# host's headers; point them at the sysroot's usr/ they were extracted into.
for config in "$libdir"/cmake/*/*.cmake; do
  grep -q '"/usr/' "$config" || continue
  sed -i -e 's|"/usr/|"${_keepless_sysroot_usr}/|g' \
      -e '1i # keepless prepare_sysroot.sh: paths made relative to this sysroot.\nget_filename_component(_keepless_sysroot_usr "${CMAKE_CURRENT_LIST_DIR}/../../../.." ABSOLUTE)' \
      "$config"
done

printf '%s' "$stamp_hash" >"$tmp/.keepless-sysroot"
rm -rf "$sysroot"
mv "$tmp" "$sysroot"
echo "sysroot: prepared $sysroot ($(find "$debs" -name '*.deb' | wc -l) packages, $(du -sh "$sysroot" | cut -f1))"
