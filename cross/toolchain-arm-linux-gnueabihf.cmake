# Cross toolchain for 32-bit ARM Linux boards (Debian multiarch armhf).
# Not used by CI: Debian's armhf index is currently unusable on our mirror.
# Same layout as toolchain-aarch64-linux-gnu.cmake; NEON is part of armhf's
# baseline only with -mfpu=neon, set here because armhf boards all have it.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR arm)
set(STRIA_TRIPLET arm-linux-gnueabihf)

set(CMAKE_C_COMPILER ${STRIA_TRIPLET}-gcc-12)
set(CMAKE_CXX_COMPILER ${STRIA_TRIPLET}-g++-12)
set(CMAKE_C_FLAGS_INIT "-mfpu=neon-vfpv4")
set(CMAKE_CXX_FLAGS_INIT "-mfpu=neon-vfpv4")

set(CMAKE_LIBRARY_ARCHITECTURE ${STRIA_TRIPLET})
set(CMAKE_FIND_ROOT_PATH /usr/${STRIA_TRIPLET} /)
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)

set(ENV{PKG_CONFIG_LIBDIR} /usr/lib/${STRIA_TRIPLET}/pkgconfig:/usr/share/pkgconfig)
set(ENV{PKG_CONFIG_PATH} "")

find_program(STRIA_QEMU qemu-arm REQUIRED)
set(CMAKE_CROSSCOMPILING_EMULATOR ${STRIA_QEMU})
