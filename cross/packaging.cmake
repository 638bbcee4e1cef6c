# The Debian package (CPack DEB): `cpack -G DEB` in a build directory, or
# cross/package-arm64.sh. Contents:
#   /usr/bin/stria
#   /usr/lib/systemd/system/stria.service, /usr/lib/sysusers.d/stria.conf,
#   /usr/lib/udev/rules.d/60-stria.rules          (firmware/systemd/)
#   /usr/share/stria/board/NAME/                   (every board folder)
#   /etc/stria/board.yaml                          (conffile: the simulated head)
#   /usr/share/doc/stria/                          (the docs the service points to)
# The maintainer scripts (cross/deb/) create the user stria, enable the service
# and start it where systemd runs.

set(STRIA_SYSTEMD_DIR ${PROJECT_SOURCE_DIR}/firmware/systemd)
install(FILES ${STRIA_SYSTEMD_DIR}/stria.service DESTINATION lib/systemd/system)
install(FILES ${STRIA_SYSTEMD_DIR}/stria.sysusers DESTINATION lib/sysusers.d RENAME stria.conf)
install(FILES ${STRIA_SYSTEMD_DIR}/60-stria.rules DESTINATION lib/udev/rules.d)

install(DIRECTORY ${PROJECT_SOURCE_DIR}/board/ DESTINATION share/stria/board)

# The default head is the simulated one, so a fresh install runs end to end
# without hardware. Its board file is rewritten to point at the installed
# folder and to store into the service's state directory.
file(READ ${PROJECT_SOURCE_DIR}/board/sim/board.yaml STRIA_DEFAULT_BOARD)
foreach(key pattern calibration)
  string(REGEX REPLACE "\n${key}: ([^\n]+)" "\n${key}: /usr/share/stria/board/sim/\\1"
    STRIA_DEFAULT_BOARD "${STRIA_DEFAULT_BOARD}")
endforeach()
string(REGEX REPLACE "\noutput_dir: [^\n]+" "\noutput_dir: /var/lib/stria/scans"
  STRIA_DEFAULT_BOARD "${STRIA_DEFAULT_BOARD}")
file(CONFIGURE OUTPUT ${PROJECT_BINARY_DIR}/deb/board.yaml CONTENT "${STRIA_DEFAULT_BOARD}" @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/deb/board.yaml DESTINATION /etc/stria)

foreach(doc firmware.md boards.md flashing.md)
  if(EXISTS ${PROJECT_SOURCE_DIR}/docs/${doc})
    install(FILES ${PROJECT_SOURCE_DIR}/docs/${doc} DESTINATION share/doc/stria)
  endif()
endforeach()

# Debian architecture names for the toolchains in cross/.
if(CMAKE_SYSTEM_PROCESSOR STREQUAL "aarch64")
  set(CPACK_DEBIAN_PACKAGE_ARCHITECTURE arm64)
elseif(CMAKE_SYSTEM_PROCESSOR STREQUAL "arm")
  set(CPACK_DEBIAN_PACKAGE_ARCHITECTURE armhf)
elseif(CMAKE_SYSTEM_PROCESSOR STREQUAL "x86_64")
  set(CPACK_DEBIAN_PACKAGE_ARCHITECTURE amd64)
endif()

set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME stria)
set(CPACK_PACKAGE_VENDOR "stria")
set(CPACK_PACKAGE_CONTACT "stria maintainers <stria@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "single-shot structured-light 3D scanner head firmware")
set(CPACK_PACKAGE_DESCRIPTION "One button press lights the stripe projector, captures one camera\n\
frame and decodes it into a 3D point cloud (Schmalz and Angelopoulou's\n\
robust single-shot structured light). Runs as the systemd service stria.")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_STRIP_FILES ON)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_CONTROL_EXTRA
  ${PROJECT_SOURCE_DIR}/cross/deb/conffiles
  ${PROJECT_SOURCE_DIR}/cross/deb/postinst
  ${PROJECT_SOURCE_DIR}/cross/deb/prerm
  ${PROJECT_SOURCE_DIR}/cross/deb/postrm)
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION ON)
include(CPack)
