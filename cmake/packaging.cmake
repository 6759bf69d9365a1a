# Debian packages of the installed files, one per install component (CPack's DEB generator;
# scripts/package.sh configures the build for the prefix /usr and runs cpack):
#   kccd          the command: bin/kccd, libexec/kccd/kccd-all, the sample data in share/kccd/data
#   libkccd-dev   the C++ libraries (static), their headers, find_package(kccd COMPONENTS ...) and
#                 the examples in share/doc/libkccd-dev/examples
#   python3-kccd  `import kccd` for Debian's Python 3
# Every package's Depends on shared libraries come from dpkg-shlibdeps on what its files link;
# libkccd-dev's list the Debian -dev packages its CMake package config finds.
set(KCCD_DEB_MAINTAINER "KCCD maintainers <maintainers@kccd.invalid>")

# The sample data and the examples: what the documentation's snippets use once installed.
install(DIRECTORY ${PROJECT_SOURCE_DIR}/data/ DESTINATION ${CMAKE_INSTALL_DATADIR}/kccd/data COMPONENT cli)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/examples/ DESTINATION ${CMAKE_INSTALL_DATADIR}/doc/libkccd-dev/examples
        COMPONENT dev)

# Each package's copyright (Debian's machine-readable format) and changelog in share/doc/<package>.
file(READ ${PROJECT_SOURCE_DIR}/LICENSE _kccd_license)
string(REGEX REPLACE "^BSD 3-Clause License\n\n[^\n]*\n[^\n]*\n\n" "" _kccd_license_terms "${_kccd_license}")
string(REGEX REPLACE "\n\n" "\n .\n" _kccd_license_terms "${_kccd_license_terms}")
string(REGEX REPLACE "\n([^ ])" "\n \\1" _kccd_license_terms "${_kccd_license_terms}")
string(TIMESTAMP _kccd_date "%a, %d %b %Y %H:%M:%S +0000" UTC)
set(_kccd_deb_dir ${PROJECT_BINARY_DIR}/debian)
file(MAKE_DIRECTORY ${_kccd_deb_dir})
file(WRITE ${_kccd_deb_dir}/copyright
  "Format: https://www.debian.org/doc/packaging-manuals/copyright-format/1.0/\n"
  "Upstream-Name: kccd\n\n"
  "Files: *\n"
  "Copyright: 2026 the KCCD developers\n"
  "License: BSD-3-Clause\n\n"
  "License: BSD-3-Clause\n ${_kccd_license_terms}")
set(_kccd_packages cli kccd dev libkccd-dev python python3-kccd)
while(_kccd_packages)
  list(POP_FRONT _kccd_packages _component _package)
  file(WRITE ${_kccd_deb_dir}/${_package}.changelog.Debian
    "${_package} (${PROJECT_VERSION}) unstable; urgency=medium\n\n"
    "  * Built from the KCCD source tree, version ${PROJECT_VERSION} (the project's changelog:\n"
    "    the documentation's Changelog page).\n\n"
    " -- ${KCCD_DEB_MAINTAINER}  ${_kccd_date}\n")
  execute_process(COMMAND gzip -9nf ${_kccd_deb_dir}/${_package}.changelog.Debian)
  install(FILES ${_kccd_deb_dir}/copyright ${_kccd_deb_dir}/${_package}.changelog.Debian.gz
          DESTINATION ${CMAKE_INSTALL_DATADIR}/doc/${_package} COMPONENT ${_component})
  install(CODE "file(RENAME \"\$ENV{DESTDIR}\${CMAKE_INSTALL_PREFIX}/${CMAKE_INSTALL_DATADIR}/doc/${_package}/${_package}.changelog.Debian.gz\"
                              \"\$ENV{DESTDIR}\${CMAKE_INSTALL_PREFIX}/${CMAKE_INSTALL_DATADIR}/doc/${_package}/changelog.gz\")"
          COMPONENT ${_component})
endwhile()

# The manual page, written by scripts/package.sh from `kccd --help` (help2man) before cpack runs.
install(FILES ${_kccd_deb_dir}/kccd.1.gz DESTINATION ${CMAKE_INSTALL_MANDIR}/man1 COMPONENT cli OPTIONAL)

set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME kccd)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_VENDOR "the KCCD developers")
# Each package's synopsis is the first line of its own description (CPACK_DEBIAN_<C>_DESCRIPTION);
# CPack would put the project's summary before it unless that summary is CPack's default.
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "kccd built using CMake")
set(CPACK_PACKAGE_CONTACT "${KCCD_DEB_MAINTAINER}")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_PACKAGE_DIRECTORY ${PROJECT_BINARY_DIR}/packages)
set(CPACK_RESOURCE_FILE_LICENSE ${PROJECT_SOURCE_DIR}/LICENSE)
set(CPACK_STRIP_FILES ON)  # the programs and the Python module; the static libraries keep their symbols
set(CPACK_DEB_COMPONENT_INSTALL ON)
set(CPACK_COMPONENTS_GROUPING IGNORE)
set(CPACK_COMPONENTS_ALL cli dev)
if(KCCD_PYTHON_BUILT)
  list(APPEND CPACK_COMPONENTS_ALL python)
endif()
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_PRIORITY optional)
set(CPACK_DEBIAN_ENABLE_COMPONENT_DEPENDS OFF)

set(CPACK_DEBIAN_CLI_PACKAGE_NAME kccd)
set(CPACK_DEBIAN_CLI_PACKAGE_SECTION science)
set(CPACK_DEBIAN_CLI_DESCRIPTION "strictly conservative continuous collision detection for robots
The kccd command checks a robot's whole braking motion: its input is an
interval per joint and every distance it reports is a guaranteed lower bound
over every configuration in that box. Bodies are sphere swept convex hulls.

Around the checker: importing URDFs and fitting CAD parts, proving which
pairs never meet, calibrating a camera, and drawing the checked volumes over
recorded video, robot logs (MCAP, rosbag2, ROS 1) and LeRobot datasets.")

# OpenCV's imgcodecs is loaded at run time, for images other than PNG and JPEG (calib's
# image_file.cpp): dpkg-shlibdeps cannot see it, so its package is recommended by name.
string(REGEX REPLACE "^libopencv_imgcodecs\\.so\\.(.+)$" "libopencv-imgcodecs\\1" _kccd_imgcodecs_package
       "${KCCD_OPENCV_IMGCODECS_SONAME}")
# OSMesa, the GL back end when EGL gives no context, is loaded by name too (render's gl_context_osmesa.cpp).
set(_kccd_runtime_recommends "${_kccd_imgcodecs_package}")
if(KCCD_OSMESA_SONAME STREQUAL "libOSMesa.so.8")
  string(APPEND _kccd_runtime_recommends ", libosmesa6")
endif()
set(CPACK_DEBIAN_CLI_PACKAGE_RECOMMENDS "${_kccd_runtime_recommends}")
# FFmpeg's libraries are loaded by their sonames the first time a video is opened (overlay's
# ffmpeg_api.cpp): dpkg-shlibdeps cannot see them either, and video is the overlay's input (the
# Python package depends on them below).
set(CPACK_DEBIAN_CLI_PACKAGE_DEPENDS "${KCCD_FFMPEG_PACKAGES}")
set(CPACK_DEBIAN_PYTHON_PACKAGE_RECOMMENDS "${_kccd_runtime_recommends}")

set(CPACK_DEBIAN_DEV_PACKAGE_NAME libkccd-dev)
set(CPACK_DEBIAN_DEV_PACKAGE_SECTION libdevel)
set(CPACK_DEBIAN_DEV_PACKAGE_ARCHITECTURE amd64)
# What find_package(kccd COMPONENTS ...) finds (cmake/kccdConfig.cmake.in), as Debian names it.
set(CPACK_DEBIAN_DEV_PACKAGE_DEPENDS "cmake (>= 3.20), libeigen3-dev (>= 3.4), libccd-dev, libyaml-cpp-dev, \
libqhull-dev, libcoin-dev, libassimp-dev, liburdfdom-dev, libtinyxml2-dev, libopencv-dev (>= 4.6), libpng-dev, \
libjpeg-dev, libapriltag-dev, zlib1g-dev, libzstd-dev, liblz4-dev, libbz2-dev, libsqlite3-dev, libsnappy-dev, \
libegl-dev, libgl-dev, nlohmann-json3-dev, libcpp-httplib-dev, libssl-dev, ${KCCD_FFMPEG_PACKAGES}")
set(CPACK_DEBIAN_DEV_DESCRIPTION "strictly conservative continuous collision detection for robots (C++)
The KCCD C++ libraries (static), their headers and their CMake package:
find_package(kccd COMPONENTS ...) gives kccd::kccd, the collision checker a
robot controller links (no allocation and no exception on the query path),
and the parts of the tool suite (modelling, calib, logs, render, overlay).")

set(CPACK_DEBIAN_PYTHON_PACKAGE_NAME python3-kccd)
set(CPACK_DEBIAN_PYTHON_PACKAGE_SECTION python)
set(CPACK_DEBIAN_PYTHON_PACKAGE_DEPENDS "python3 (>= 3.11), python3 (<< 3.12), python3-numpy, python3-yaml, ${KCCD_FFMPEG_PACKAGES}")
# Byte-compiled on install and cleaned on removal (py3compile, py3clean), as dh_python3 does.
configure_file(${PROJECT_SOURCE_DIR}/cmake/debian/python3-kccd.postinst ${_kccd_deb_dir}/python/postinst COPYONLY)
configure_file(${PROJECT_SOURCE_DIR}/cmake/debian/python3-kccd.prerm ${_kccd_deb_dir}/python/prerm COPYONLY)
set(CPACK_DEBIAN_PYTHON_PACKAGE_CONTROL_EXTRA "${_kccd_deb_dir}/python/postinst;${_kccd_deb_dir}/python/prerm")
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION ON)
set(CPACK_DEBIAN_PYTHON_PACKAGE_SUGGESTS "kccd, python3-distributed, python3-dask")  # kccd.batch on a cluster
set(CPACK_DEBIAN_PYTHON_DESCRIPTION "strictly conservative continuous collision detection for robots (Python)
The kccd Python package: models, queries whose distances are lower bounds
over a whole joint interval box, fitting, rendering, calibration and the
overlay job, with NumPy arrays.")
include(CPack)
