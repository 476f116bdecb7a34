# 32-bit ARMv7 boards with hard float (Raspberry Pi 2/3 on a 32-bit OS, i.MX6).
# Debian's cross compiler (apt-get install g++-arm-linux-gnueabihf), a sysroot
# from toolchains/prepare_sysroot.sh armhf, tests under qemu-arm.
set(CMAKE_SYSTEM_PROCESSOR armv7l)
set(KEEPLESS_TRIPLE arm-linux-gnueabihf)
set(KEEPLESS_QEMU_ARCH arm)
set(KEEPLESS_SYSROOT_NAME sysroot-armhf)
include(${CMAKE_CURRENT_LIST_DIR}/linux_cross.cmake)
