# 64-bit ARM boards (Jetson, Raspberry Pi 4/5 on a 64-bit OS, i.MX8, RK3588).
# Debian's cross compiler (apt-get install g++-aarch64-linux-gnu), a sysroot
# from toolchains/prepare_sysroot.sh aarch64, tests under qemu-aarch64.
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(KEEPLESS_TRIPLE aarch64-linux-gnu)
set(KEEPLESS_QEMU_ARCH aarch64)
set(KEEPLESS_SYSROOT_NAME sysroot-aarch64)
include(${CMAKE_CURRENT_LIST_DIR}/linux_cross.cmake)
