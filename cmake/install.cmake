# Install rules, the CMake package and the Debian package (issue #20; docs/install.md).
#
#   <prefix>/bin/dentsim                                   the command
#   <prefix>/lib/libdentsim_{reference,fast,...}.a         the static libraries
#   <prefix>/lib/libdentsim_hd_emulator.so                 the HDAPI emulator (docs/hardware.md)
#   <prefix>/include/dentsim/{reference,fast,...}/*.h      the headers, in the repository's layout
#   <prefix>/lib/cmake/dentsim/                            find_package(dentsim CONFIG)
#   <prefix>/share/dentsim/devices/*.json, scenes/*.json   the default device model, the scenes
#   <prefix>/share/doc/dentsim/                            README.md, docs/, copyright (LICENSE)
#
# Headers include each other as "reference/core/types.h", "fast/tick.h": the include directory is
# <prefix>/include/dentsim, so a consumer writes the same #include lines as the repository and the
# generic folder names (reference/, device/, ...) stay out of <prefix>/include.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(DENTSIM_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/dentsim)
set(DENTSIM_INSTALL_DATADIR ${CMAKE_INSTALL_DATADIR}/dentsim)

# ---- the libraries and their exported targets ---------------------------------------------------
# The exported names drop the prefix: dentsim_fast -> dentsim::fast.
set(dentsim_exported_libs dentsim_reference dentsim_tooth_io dentsim_fast dentsim_plant
    dentsim_device dentsim_sim dentsim_validation dentsim_calibration dentsim_view)
foreach(lib ${dentsim_exported_libs})
  string(REGEX REPLACE "^dentsim_" "" short ${lib})
  set_target_properties(${lib} PROPERTIES EXPORT_NAME ${short})
  # The headers are C++20 (std::span, designated initialisers, <numbers>): a requirement of every
  # consumer, not only of this build's global CMAKE_CXX_STANDARD.
  target_compile_features(${lib} INTERFACE cxx_std_20)
endforeach()

# dentsim_volume_libs (top-level CMakeLists.txt) names nifticlib and teem by the absolute paths
# find_library found on this machine, and their include directories (used only by
# tooth_io/volume_io.cc, no public header). The installed package must not carry this
# machine's paths: in the export these become dentsim::nifti2 and dentsim::teem, which
# dentsimConfig.cmake finds again on the consumer's machine. gdcmMSFF is GDCM's own exported target.
set(volume_include_dirs "$<BUILD_INTERFACE:${NIFTI_INCLUDE_DIR};${TEEM_INCLUDE_DIR}>")
set(volume_link_libs gdcmMSFF "$<BUILD_INTERFACE:${NIFTI2_LIBRARY}>"
    "$<BUILD_INTERFACE:${TEEM_LIBRARY}>" "$<INSTALL_INTERFACE:dentsim::nifti2>"
    "$<INSTALL_INTERFACE:dentsim::teem>")
set_target_properties(dentsim_volume_libs PROPERTIES
  EXPORT_NAME volume_libs
  INTERFACE_INCLUDE_DIRECTORIES "${volume_include_dirs}"
  INTERFACE_SYSTEM_INCLUDE_DIRECTORIES "${volume_include_dirs}"
  INTERFACE_LINK_LIBRARIES "${volume_link_libs}")

set_target_properties(dentsim_hd_emulator PROPERTIES EXPORT_NAME hd_emulator)

install(TARGETS ${dentsim_exported_libs} EXPORT dentsimTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/dentsim)
# dentsim::dentsim, the command, for consumers that run it ($<TARGET_FILE:dentsim::dentsim>).
install(TARGETS dentsim_volume_libs dentsim_hd_emulator dentsim EXPORT dentsimTargets
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})

# Every header of the libraries, folder layout kept (one install(FILES) per folder rather than
# install(DIRECTORY), which would also create the folders that hold only sources).
foreach(dir reference tooth_io fast plant device sim validation calibration view)
  file(GLOB_RECURSE headers RELATIVE ${PROJECT_SOURCE_DIR} CONFIGURE_DEPENDS
       ${PROJECT_SOURCE_DIR}/${dir}/*.h)
  foreach(h ${headers})
    get_filename_component(h_dir ${h} DIRECTORY)
    install(FILES ${PROJECT_SOURCE_DIR}/${h}
            DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/dentsim/${h_dir})
  endforeach()
endforeach()

install(EXPORT dentsimTargets NAMESPACE dentsim:: DESTINATION ${DENTSIM_INSTALL_CMAKEDIR})

# What dentsimConfig.cmake must find again: which GL front ends dentsim_view was built with (its
# private libraries are part of a static library's link interface).
set(DENTSIM_CONFIG_WITH_GL OFF)
set(DENTSIM_CONFIG_WITH_GLFW OFF)
if("OpenGL::EGL" IN_LIST view_gl_libs)
  set(DENTSIM_CONFIG_WITH_GL ON)
endif()
if("PkgConfig::GLFW" IN_LIST view_gl_libs)
  set(DENTSIM_CONFIG_WITH_GLFW ON)
endif()
configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/dentsimConfig.cmake.in
                              ${CMAKE_BINARY_DIR}/cmake/dentsimConfig.cmake
                              INSTALL_DESTINATION ${DENTSIM_INSTALL_CMAKEDIR}
                              PATH_VARS DENTSIM_INSTALL_DATADIR)
write_basic_package_version_file(${CMAKE_BINARY_DIR}/cmake/dentsimConfigVersion.cmake
                                 VERSION ${PROJECT_VERSION} COMPATIBILITY SameMajorVersion)
install(FILES ${CMAKE_BINARY_DIR}/cmake/dentsimConfig.cmake
              ${CMAKE_BINARY_DIR}/cmake/dentsimConfigVersion.cmake
        DESTINATION ${DENTSIM_INSTALL_CMAKEDIR})

# ---- data: the default device model and the built-in scenes ------------------------------------
# They are compiled into the binary (reference/phantom/phantom_params.cc, sim/scene.cc); the
# files are what the built dentsim prints (`dentsim device show`, `dentsim run NAME --show`), so
# they cannot drift from it. <build>/share/dentsim mirrors the installed folder.
set(dentsim_data_dir ${CMAKE_BINARY_DIR}/share/dentsim)
add_custom_command(
  OUTPUT ${CMAKE_BINARY_DIR}/cmake/dentsim_data.stamp
  COMMAND ${CMAKE_COMMAND} -DDENTSIM=$<TARGET_FILE:dentsim> -DOUT=${dentsim_data_dir}
          -P ${CMAKE_CURRENT_LIST_DIR}/generate_data.cmake
  COMMAND ${CMAKE_COMMAND} -E touch ${CMAKE_BINARY_DIR}/cmake/dentsim_data.stamp
  DEPENDS dentsim ${CMAKE_CURRENT_LIST_DIR}/generate_data.cmake
  COMMENT "Writing the default device model and the built-in scenes to share/dentsim"
  VERBATIM)
add_custom_target(dentsim_data ALL DEPENDS ${CMAKE_BINARY_DIR}/cmake/dentsim_data.stamp)
install(DIRECTORY ${dentsim_data_dir}/ DESTINATION ${DENTSIM_INSTALL_DATADIR})

install(FILES ${PROJECT_SOURCE_DIR}/README.md DESTINATION ${CMAKE_INSTALL_DOCDIR})
# The licence as Debian policy wants it: /usr/share/doc/<package>/copyright.
install(FILES ${PROJECT_SOURCE_DIR}/LICENSE DESTINATION ${CMAKE_INSTALL_DOCDIR}
        RENAME copyright)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/docs/ DESTINATION ${CMAKE_INSTALL_DOCDIR}/docs)

# ---- the install test (label `package`) ---------------------------------------------------------
# Installs this build into a fresh prefix, builds examples/cpp and tests/install/link_all against
# it alone and runs them, and runs the installed dentsim on the installed data
# (tests/install/install_test.cmake). Not in the sanitizer build: the consumers would link
# ASan-instrumented archives without -fsanitize.
if(BUILD_TESTING AND NOT DENTSIM_SANITIZE)
  add_test(NAME package.install_and_build_example
           COMMAND ${CMAKE_COMMAND} -DBINARY_DIR=${CMAKE_BINARY_DIR}
                   -DEXAMPLE_DIR=${PROJECT_SOURCE_DIR}/examples/cpp
                   -DWORK_DIR=${CMAKE_BINARY_DIR}/install_test
                   -DSOURCE_DIR=${PROJECT_SOURCE_DIR} -DLIBDIR=${CMAKE_INSTALL_LIBDIR}
                   -DCCACHE=${CCACHE_PROGRAM}
                   -DCXX=${CMAKE_CXX_COMPILER}
                   -P ${PROJECT_SOURCE_DIR}/tests/install/install_test.cmake)
  set_tests_properties(package.install_and_build_example PROPERTIES LABELS package TIMEOUT 600
                       RUN_SERIAL TRUE)
endif()

# ---- the Debian package (cpack in the build directory) -----------------------------------------
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME dentsim)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_VENDOR "dentsim")
set(CPACK_RESOURCE_FILE_LICENSE ${PROJECT_SOURCE_DIR}/LICENSE)
# The maintainers as the repository's history names them.
set(CPACK_PACKAGE_CONTACT
    "Seed 389a29a1 maintainers <maintainers@users.noreply.h-seed-389a29a1.example>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY
    "Stiff, stable haptic rendering for a dental simulator (library, headers, CLI)")
set(CPACK_PACKAGE_DESCRIPTION
    "dentsim renders a voxel tooth through a 6-DoF Phantom Premium 1.5 with passive midpoint\n\
integration of a virtual proxy, virtual coupling, penalty contact and friction, passive\n\
decomposition and a momentum-based human force observer. This package holds the dentsim\n\
command, the static libraries with their headers and CMake package (find_package(dentsim)),\n\
the HDAPI emulator, the default device model and the built-in scenes.")
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
# The run-time libraries of bin/dentsim and the emulator come from dpkg-shlibdeps; the -dev
# packages are what find_package(dentsim) needs (dentsimConfig.cmake finds each of them).
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_DEPENDS "libeigen3-dev, libmujoco-dev, libqhull-dev, libceres-dev, \
nlohmann-json3-dev, libfmt-dev, libgdcm-dev, libnifti2-dev, libteem-dev, libcairo2-dev, pkg-config")
if(DENTSIM_CONFIG_WITH_GL)
  string(APPEND CPACK_DEBIAN_PACKAGE_DEPENDS ", libgl-dev, libegl-dev")
endif()
if(DENTSIM_CONFIG_WITH_GLFW)
  string(APPEND CPACK_DEBIAN_PACKAGE_DEPENDS ", libglfw3-dev")
endif()
# The Python module (python/CMakeLists.txt installs it) returns NumPy arrays; Debian's
# python3-numpy also pins the python3 the module's ABI tag needs. (dpkg-shlibdeps finds no
# libpython: extension modules do not link it.)
if(TARGET dentsim_python)
  string(APPEND CPACK_DEBIAN_PACKAGE_DEPENDS ", python3-numpy")
endif()
include(CPack)
