# The package test (ctest -L package; registered by cmake/install.cmake in non-sanitizer builds):
#
#   cmake -DBINARY_DIR=<build> -DSOURCE_DIR=<repo> -DEXAMPLE_DIR=<repo>/examples/cpp
#         -DWORK_DIR=<scratch> [-DLIBDIR=lib] [-DCCACHE=<ccache>] [-DCXX=<c++ compiler>]
#         -P install_test.cmake
#
# 1. installs the build tree into a fresh prefix (WORK_DIR/prefix, emptied first);
# 2. checks that the installed CMake package names neither the source nor the build tree, nor
#    passes dentsim's warning flags to its consumers;
# 3. copies examples/cpp out of the repository, configures it with CMAKE_PREFIX_PATH=<prefix> as the
#    only hint (no package registry, no dentsim_DIR, no CMAKE_PREFIX_PATH from the environment),
#    checks find_package took the prefix's config, builds it and runs it: its checks (gravity
#    compensation at rest, the coupling spring, fast vs reference) must pass, on the built-in model
#    and on the installed model file, and print that file's model name; builds and runs
#    tests/install/link_all the same way (all seven libraries linked --whole-archive);
# 4. runs the installed bin/dentsim from outside both trees on the installed files: `device check`
#    and `device show` on the model (identical to the installed file), every installed scene file
#    against `run NAME --show`, a short run of the installed probe scene (time series and report
#    equal to the built-in scene's), and `device probe` through the installed HDAPI emulator.
# Any failing step fails the test with the command and its output.
foreach(var BINARY_DIR SOURCE_DIR EXAMPLE_DIR WORK_DIR)
  if(NOT ${var})
    message(FATAL_ERROR "install_test.cmake: -D${var}=... is required")
  endif()
endforeach()

if(NOT LIBDIR)
  set(LIBDIR lib)
endif()
set(prefix ${WORK_DIR}/prefix)
set(example_src ${WORK_DIR}/example-src)
set(example_build ${WORK_DIR}/example-build)
set(runs ${WORK_DIR}/runs)
file(REMOVE_RECURSE ${WORK_DIR})
file(MAKE_DIRECTORY ${WORK_DIR} ${runs})

# Runs a command in WORK_DIR with the environment variables that could point CMake or the program
# at another dentsim removed; stops the test when it fails. The output is returned in `out_var`.
function(step out_var what)
  string(TIMESTAMP t0 "%s")
  execute_process(COMMAND ${CMAKE_COMMAND} -E env --unset=CMAKE_PREFIX_PATH --unset=dentsim_DIR
                          --unset=DENTSIM_HD_LIBRARY --unset=DENTSIM_HD_EMU_SCENE ${ARGN}
                  WORKING_DIRECTORY ${WORK_DIR} OUTPUT_VARIABLE out ERROR_VARIABLE err
                  RESULT_VARIABLE rc)
  string(TIMESTAMP t1 "%s")
  math(EXPR dt "${t1} - ${t0}")
  if(NOT rc EQUAL 0)
    string(REPLACE ";" " " cmd "${ARGN}")
    message(FATAL_ERROR "install test: ${what} failed (exit ${rc}):\n  ${cmd}\n${out}\n${err}")
  endif()
  message(STATUS "${what}: ok (${dt} s)")
  set(${out_var} "${out}" PARENT_SCOPE)
endfunction()

function(expect_match text regex what)
  if(NOT text MATCHES "${regex}")
    message(FATAL_ERROR "install test: ${what}: expected /${regex}/ in:\n${text}")
  endif()
endfunction()

# ---- 1. install ----------------------------------------------------------------------------------
step(out "cmake --install" ${CMAKE_COMMAND} --install ${BINARY_DIR} --prefix ${prefix})

# The files a consumer relies on (the layout of docs/install.md).
foreach(f bin/dentsim include/dentsim/reference/tick.h include/dentsim/fast/registry.h
          include/dentsim/device/phantom_device.h include/dentsim/reference/core/types.h
          ${LIBDIR}/cmake/dentsim/dentsimConfig.cmake
          ${LIBDIR}/cmake/dentsim/dentsimConfigVersion.cmake
          ${LIBDIR}/cmake/dentsim/dentsimTargets.cmake ${LIBDIR}/libdentsim_hd_emulator.so
          share/doc/dentsim/README.md share/doc/dentsim/copyright
          share/dentsim/scenes/probe.json)
  if(NOT EXISTS ${prefix}/${f})
    message(FATAL_ERROR "install test: ${prefix}/${f} was not installed")
  endif()
endforeach()
foreach(lib reference fast plant device validation calibration view)
  if(NOT EXISTS ${prefix}/${LIBDIR}/libdentsim_${lib}.a)
    message(FATAL_ERROR "install test: ${prefix}/${LIBDIR}/libdentsim_${lib}.a was not installed")
  endif()
endforeach()
file(GLOB models ${prefix}/share/dentsim/devices/*.json)
list(LENGTH models n_models)
if(NOT n_models EQUAL 1)
  message(FATAL_ERROR "install test: expected one device model in share/dentsim/devices, got: "
                      "${models}")
endif()
file(GLOB scenes ${prefix}/share/dentsim/scenes/*.json)
list(LENGTH scenes n_scenes)
if(n_scenes LESS 3)
  message(FATAL_ERROR "install test: expected the 3 built-in scenes, got: ${scenes}")
endif()

# ---- 2. the package names no path of this machine's trees ---------------------------------------
file(GLOB cmake_files ${prefix}/${LIBDIR}/cmake/dentsim/*.cmake)
foreach(f ${cmake_files})
  file(READ ${f} text)
  foreach(tree ${SOURCE_DIR} ${BINARY_DIR})
    string(FIND "${text}" "${tree}" at)
    if(NOT at EQUAL -1)
      message(FATAL_ERROR "install test: ${f} names ${tree}: the package is not relocatable")
    endif()
  endforeach()
  # dentsim's own warning flags (dentsim_warnings) are for its build, not for its consumers.
  if(text MATCHES "INTERFACE_COMPILE_OPTIONS|-Werror|-Wshadow")
    message(FATAL_ERROR "install test: ${f} passes compile options to consumers")
  endif()
endforeach()
message(STATUS "installed package names neither ${SOURCE_DIR} nor ${BINARY_DIR}, "
               "passes no compile options: ok")

# ---- 3. the example, outside the repository, against the prefix alone --------------------------
file(COPY ${EXAMPLE_DIR}/ DESTINATION ${example_src})
# The options of a consumer's configure: the prefix and nothing else to find dentsim by.
set(options -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=${prefix}
    -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF -DCMAKE_FIND_USE_SYSTEM_PACKAGE_REGISTRY=OFF)
if(CXX)
  list(APPEND options -DCMAKE_CXX_COMPILER=${CXX})
endif()
if(CCACHE)
  list(APPEND options -DCMAKE_CXX_COMPILER_LAUNCHER=${CCACHE})
endif()
step(out "configure examples/cpp against the prefix" ${CMAKE_COMMAND} -S ${example_src}
     -B ${example_build} ${options})
file(STRINGS ${example_build}/CMakeCache.txt dentsim_dir REGEX "^dentsim_DIR:")
if(NOT dentsim_dir STREQUAL "dentsim_DIR:PATH=${prefix}/${LIBDIR}/cmake/dentsim")
  message(FATAL_ERROR "install test: find_package(dentsim) took '${dentsim_dir}', expected "
                      "${prefix}/${LIBDIR}/cmake/dentsim")
endif()
step(out "build examples/cpp" ${CMAKE_COMMAND} --build ${example_build} -j 2)

list(GET models 0 model)
file(READ ${model} model_text)
string(JSON model_name GET "${model_text}" name)
step(out "one_tick (built-in model)" ${example_build}/one_tick)
expect_match("${out}" "\nok\n$" "one_tick")
step(out "one_tick ${model}" ${example_build}/one_tick ${model})
expect_match("${out}" "\nok\n$" "one_tick on the installed model")
expect_match("${out}" "device model \"${model_name}\"" "one_tick on the installed model")
message(STATUS "one_tick output:\n${out}")

# Every object of the seven libraries linked whole (tests/install/link_all): the exported link
# interfaces are complete for any use of the package, not only the example's.
set(link_all_build ${WORK_DIR}/link-all-build)
file(COPY ${CMAKE_CURRENT_LIST_DIR}/link_all/ DESTINATION ${WORK_DIR}/link-all-src)
step(out "configure tests/install/link_all against the prefix" ${CMAKE_COMMAND}
     -S ${WORK_DIR}/link-all-src -B ${link_all_build} ${options})
step(out "build link_all (every library --whole-archive)" ${CMAKE_COMMAND}
     --build ${link_all_build})
step(out "run link_all" ${link_all_build}/link_all)

# ---- 4. the installed command on the installed data ---------------------------------------------
set(dentsim ${prefix}/bin/dentsim)
step(out "dentsim device check" ${dentsim} device check ${model})
expect_match("${out}" "valid device model \"${model_name}\"" "dentsim device check")
step(out "dentsim device show" ${dentsim} device show)
if(NOT out STREQUAL model_text)
  message(FATAL_ERROR "install test: `dentsim device show` differs from ${model}")
endif()

# Every installed scene file is the text of its built-in twin, and one of them (probe) runs as the
# built-in scene does: the same time series and report, number for number, except where the report
# names the scene's origin and the wall-clock timings. (Each run costs ~3 s, mostly the tooth's
# voxelisation; one pair shows the file path is the built-in path.)
foreach(scene ${scenes})
  get_filename_component(name ${scene} NAME_WE)
  step(out "dentsim run ${name} --show" ${dentsim} run ${name} --show)
  file(READ ${scene} text)
  if(NOT out STREQUAL text)
    message(FATAL_ERROR "install test: ${scene} differs from `dentsim run ${name} --show`")
  endif()
endforeach()
set(scene ${prefix}/share/dentsim/scenes/probe.json)
step(out "dentsim run probe" ${dentsim} run probe --duration 0.05 --out ${runs}/builtin)
step(out "dentsim run ${scene}" ${dentsim} run ${scene} --duration 0.05 --out ${runs}/file)
foreach(what builtin file)
  file(READ ${runs}/${what}/report.json report_${what})
  file(READ ${runs}/${what}/timeseries.csv series_${what})
  foreach(key scene_origin timing_us wall_s setup_s)
    string(JSON report_${what} REMOVE "${report_${what}}" ${key})
  endforeach()
endforeach()
string(JSON ticks GET "${report_file}" ticks)
if(NOT ticks EQUAL 50)
  message(FATAL_ERROR "install test: ${runs}/file/report.json: ${ticks} ticks, expected 50")
endif()
string(JSON same EQUAL "${report_builtin}" "${report_file}")
if(NOT same OR NOT series_builtin STREQUAL series_file)
  message(FATAL_ERROR "install test: running ${scene} differs from the built-in 'probe' "
                      "(${runs}/file vs ${runs}/builtin)")
endif()
message(STATUS "${scene} runs as the built-in scene: ok")

# One reading, taken as the scheduler starts: with more, 100 ms apart, the unheld arm falls under
# gravity meanwhile, and on a loaded machine the emulator's catch-up can report that as an encoder
# jump (a fault of the probe, not of the installation).
set(emulator ${prefix}/${LIBDIR}/libdentsim_hd_emulator.so)
step(out "dentsim device probe through the installed emulator" ${dentsim} device probe
     --hd-library ${emulator} --readings 1)
expect_match("${out}" "library: ${emulator}\n" "dentsim device probe")
expect_match("${out}" "\(dentsim emulator\)" "dentsim device probe")
expect_match("${out}" "ok: device started" "dentsim device probe")
message(STATUS "install test: all steps passed (prefix ${prefix})")
