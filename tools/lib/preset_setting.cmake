# SPDX-License-Identifier: Apache-2.0
# Prints a setting a configure preset of CMakePresets.json names (its own or one it
# inherits), or nothing when it names none. SETTING is "compiler" (the C++ compiler, the
# default) or "generator". A JSON reader, because a line-based one stops at the first "}"
# (as in "${sourceDir}") and misses it.
#   cmake -DPRESETS=CMakePresets.json -DPRESET=asan-ubsan [-DSETTING=generator] \
#         -P tools/lib/preset_setting.cmake
file(READ "${PRESETS}" presets)
string(JSON count LENGTH "${presets}" configurePresets)
math(EXPR last "${count} - 1")
if(NOT DEFINED SETTING OR SETTING STREQUAL "compiler")
  set(keys cacheVariables CMAKE_CXX_COMPILER)
elseif(SETTING STREQUAL "generator")
  set(keys generator)
else()
  message(FATAL_ERROR "preset_setting: SETTING is compiler or generator, not '${SETTING}'")
endif()

function(setting_of name out)
  foreach(i RANGE ${last})
    string(JSON this GET "${presets}" configurePresets ${i} name)
    if(NOT this STREQUAL name)
      continue()
    endif()
    string(JSON value ERROR_VARIABLE missing GET "${presets}" configurePresets ${i} ${keys})
    if(NOT missing)
      set(${out} "${value}" PARENT_SCOPE)
      return()
    endif()
    string(JSON parent ERROR_VARIABLE orphan GET "${presets}" configurePresets ${i} inherits)
    if(NOT orphan)
      setting_of("${parent}" found)
      set(${out} "${found}" PARENT_SCOPE)
    endif()
    return()
  endforeach()
endfunction()

setting_of("${PRESET}" value)
if(value)
  execute_process(COMMAND "${CMAKE_COMMAND}" -E echo "${value}")
endif()
