# cmake -DDENTSIM=<built dentsim> -DOUT=<dir> -P generate_data.cmake
#
# Writes the data compiled into dentsim as the files the package installs under share/dentsim:
#   OUT/devices/<model name>.json   `dentsim device show` (the default Phantom model,
#                                   phantom_premium_1.5a_6dof.json)
#   OUT/scenes/<name>.json          `dentsim run NAME --show` for every NAME of `dentsim run --list`
# The binary is the only source, so the installed files are exactly what it runs by default.
# OUT is emptied first: a scene that left the binary must not stay in the package.
foreach(var DENTSIM OUT)
  if(NOT ${var})
    message(FATAL_ERROR "generate_data.cmake: -D${var}=... is required")
  endif()
endforeach()

function(run_dentsim out_var)
  execute_process(COMMAND ${DENTSIM} ${ARGN} OUTPUT_VARIABLE out ERROR_VARIABLE err
                  RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    string(REPLACE ";" " " cmd "${ARGN}")
    message(FATAL_ERROR "generate_data.cmake: `dentsim ${cmd}` failed (${rc}): ${err}")
  endif()
  set(${out_var} "${out}" PARENT_SCOPE)
endfunction()

# In the sanitizer build the binary is instrumented: its leak report (the test suite's business,
# with scripts/lsan.supp) must not fail the build of two data files.
set(ENV{ASAN_OPTIONS} "detect_leaks=0")

file(REMOVE_RECURSE ${OUT})

run_dentsim(model device show)
string(JSON model_name ERROR_VARIABLE json_error GET "${model}" name)
if(json_error)
  message(FATAL_ERROR "generate_data.cmake: `dentsim device show` printed no \"name\": "
                      "${json_error}")
endif()
# The file name from the model's name up to its first colon ("Phantom Premium 1.5A/6DoF: Cavusoglu
# 2002 arm, ..." -> phantom_premium_1.5a_6dof.json).
string(REGEX REPLACE ":.*" "" file_name "${model_name}")
string(TOLOWER "${file_name}" file_name)
string(REGEX REPLACE "[^a-z0-9.]+" "_" file_name "${file_name}")
string(REGEX REPLACE "^_|_$" "" file_name "${file_name}")
file(WRITE ${OUT}/devices/${file_name}.json "${model}")

run_dentsim(list run --list)
string(REPLACE "\n" ";" lines "${list}")
set(count 0)
foreach(line ${lines})
  if(line MATCHES "^([A-Za-z0-9_-]+)[ \t]")
    set(name ${CMAKE_MATCH_1})
    run_dentsim(scene run ${name} --show)
    file(WRITE ${OUT}/scenes/${name}.json "${scene}")
    math(EXPR count "${count} + 1")
  endif()
endforeach()
if(count EQUAL 0)
  message(FATAL_ERROR "generate_data.cmake: `dentsim run --list` listed no scene:\n${list}")
endif()
