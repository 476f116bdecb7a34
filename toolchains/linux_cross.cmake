# Shared body of the Linux cross toolchains. The including file sets
# KEEPLESS_TRIPLE (compiler prefix and multiarch dir), KEEPLESS_QEMU_ARCH and
# KEEPLESS_SYSROOT_NAME, plus CMAKE_SYSTEM_PROCESSOR.
#
# The sysroot comes from toolchains/prepare_sysroot.sh. Where it is, first match:
#   -DKEEPLESS_SYSROOT=<dir>, env KEEPLESS_SYSROOT, env KEEPLESS_CACHE_DIR,
#   ${XDG_CACHE_HOME:-$HOME/.cache}/keepless/<name>.
set(CMAKE_SYSTEM_NAME Linux)

if(NOT KEEPLESS_SYSROOT)
  if(DEFINED ENV{KEEPLESS_SYSROOT})
    set(KEEPLESS_SYSROOT "$ENV{KEEPLESS_SYSROOT}")
  elseif(DEFINED ENV{KEEPLESS_CACHE_DIR})
    set(KEEPLESS_SYSROOT "$ENV{KEEPLESS_CACHE_DIR}/${KEEPLESS_SYSROOT_NAME}")
  elseif(DEFINED ENV{XDG_CACHE_HOME})
    set(KEEPLESS_SYSROOT "$ENV{XDG_CACHE_HOME}/keepless/${KEEPLESS_SYSROOT_NAME}")
  else()
    set(KEEPLESS_SYSROOT "$ENV{HOME}/.cache/keepless/${KEEPLESS_SYSROOT_NAME}")
  endif()
endif()
set(KEEPLESS_SYSROOT "${KEEPLESS_SYSROOT}" CACHE PATH "Target sysroot (toolchains/prepare_sysroot.sh)")
if(NOT EXISTS "${KEEPLESS_SYSROOT}/.keepless-sysroot")
  message(FATAL_ERROR "No sysroot at ${KEEPLESS_SYSROOT}: run toolchains/prepare_sysroot.sh first")
endif()
# try_compile projects re-read this file without the cache.
list(APPEND CMAKE_TRY_COMPILE_PLATFORM_VARIABLES KEEPLESS_SYSROOT)

set(CMAKE_C_COMPILER ${KEEPLESS_TRIPLE}-gcc)
set(CMAKE_CXX_COMPILER ${KEEPLESS_TRIPLE}-g++)
set(CMAKE_LIBRARY_ARCHITECTURE ${KEEPLESS_TRIPLE})
set(CMAKE_SYSROOT "${KEEPLESS_SYSROOT}")

# Libraries, headers and packages only from the sysroot; programs (lcm-gen,
# pkg-config, qemu) from the host.
list(APPEND CMAKE_FIND_ROOT_PATH "${KEEPLESS_SYSROOT}")  # keeps -DCMAKE_FIND_ROOT_PATH=<prefix>
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)

# pkg-config (LCM ships only lcm.pc) must read the target's .pc files and
# prefix their paths with the sysroot.
set(ENV{PKG_CONFIG_SYSROOT_DIR} "${KEEPLESS_SYSROOT}")
set(ENV{PKG_CONFIG_LIBDIR}
    "${KEEPLESS_SYSROOT}/usr/lib/${KEEPLESS_TRIPLE}/pkgconfig:${KEEPLESS_SYSROOT}/usr/share/pkgconfig:${KEEPLESS_SYSROOT}/usr/lib/pkgconfig")
set(ENV{PKG_CONFIG_PATH} "")

# ctest (and gtest_discover_tests at build time) run target binaries through
# qemu user-mode emulation, loading the sysroot's dynamic linker and libraries.
find_program(KEEPLESS_QEMU qemu-${KEEPLESS_QEMU_ARCH} NO_CMAKE_FIND_ROOT_PATH)
if(KEEPLESS_QEMU)
  set(CMAKE_CROSSCOMPILING_EMULATOR "${KEEPLESS_QEMU};-L;${KEEPLESS_SYSROOT}")
else()
  message(WARNING "qemu-${KEEPLESS_QEMU_ARCH} not found (apt-get install qemu-user): tests cannot run")
endif()
