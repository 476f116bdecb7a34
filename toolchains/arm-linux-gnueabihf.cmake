# 32-bit ARMv7 boards with hard float (Raspberry Pi 2/3 on a 32-bit OS, i.MX6).
# Debian's cross compiler (apt-get install g++-arm-linux-gnueabihf), a sysroot
# from toolchains/prepare_sysroot.sh armhf, tests under qemu-arm.
set(CMAKE_SYSTEM_PROCESSOR armv7l)
set(KEEPLESS_TRIPLE arm-linux-gnueabihf)
set(KEEPLESS_QEMU_ARCH arm)
set(KEEPLESS_SYSROOT_NAME sysroot-armhf)
# GCC notes on every std::vector iterator passed by value that the ARM
# argument passing of such structs changed in GCC 7.1: it concerns linking
# with objects built by GCC 6 or older, never the case here (one compiler,
# the sysroot's GCC 12 libstdc++).
set(CMAKE_CXX_FLAGS_INIT "-Wno-psabi")  # set, not appended: CMake reads this file more than once
include(${CMAKE_CURRENT_LIST_DIR}/linux_cross.cmake)
