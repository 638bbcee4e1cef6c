# Cross toolchain for 64-bit ARM Linux boards (Debian multiarch arm64).
# CPU tuning is not set here: pass -DSTRIA_CPU=cortex-a72 (or use an
# arm64-a53/a72/a76 preset), so one toolchain serves every board.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(STRIA_TRIPLET aarch64-linux-gnu)

set(CMAKE_C_COMPILER ${STRIA_TRIPLET}-gcc-12)
set(CMAKE_CXX_COMPILER ${STRIA_TRIPLET}-g++-12)

# Debian multiarch: arm64 headers and libraries live under /usr with the
# triplet in their path, so / is the root and the triplet directories are
# found through CMAKE_LIBRARY_ARCHITECTURE; /usr/aarch64-linux-gnu holds the
# cross libc.
set(CMAKE_LIBRARY_ARCHITECTURE ${STRIA_TRIPLET})
set(CMAKE_FIND_ROOT_PATH /usr/${STRIA_TRIPLET} /)
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)

# pkg-config must see only the arm64 .pc files, never the host's.
set(ENV{PKG_CONFIG_LIBDIR} /usr/lib/${STRIA_TRIPLET}/pkgconfig:/usr/share/pkgconfig)
set(ENV{PKG_CONFIG_PATH} "")

# Tests (and gtest discovery) run the arm64 binaries under user-mode qemu.
# No -L/QEMU_LD_PREFIX: the arm64 loader and libraries are installed at their
# multiarch paths, and a sysroot prefix makes libcamera hang (docs/cross.md).
find_program(STRIA_QEMU qemu-${CMAKE_SYSTEM_PROCESSOR} REQUIRED)
set(CMAKE_CROSSCOMPILING_EMULATOR ${STRIA_QEMU})
