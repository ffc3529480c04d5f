# SPDX-License-Identifier: Apache-2.0
# Prints the C++ compiler a configure preset of CMakePresets.json names (its own or one it
# inherits), or nothing when it names none. A JSON reader, because a line-based one stops at
# the first "}" (as in "${sourceDir}") and misses it.
#   cmake -DPRESETS=CMakePresets.json -DPRESET=asan-ubsan -P tools/lib/preset_compiler.cmake
file(READ "${PRESETS}" presets)
string(JSON count LENGTH "${presets}" configurePresets)
math(EXPR last "${count} - 1")

function(compiler_of name out)
  foreach(i RANGE ${last})
    string(JSON this GET "${presets}" configurePresets ${i} name)
    if(NOT this STREQUAL name)
      continue()
    endif()
    string(JSON cxx ERROR_VARIABLE missing GET "${presets}" configurePresets ${i}
           cacheVariables CMAKE_CXX_COMPILER)
    if(NOT missing)
      set(${out} "${cxx}" PARENT_SCOPE)
      return()
    endif()
    string(JSON parent ERROR_VARIABLE orphan GET "${presets}" configurePresets ${i} inherits)
    if(NOT orphan)
      compiler_of("${parent}" found)
      set(${out} "${found}" PARENT_SCOPE)
    endif()
    return()
  endforeach()
endfunction()

compiler_of("${PRESET}" compiler)
if(compiler)
  execute_process(COMMAND "${CMAKE_COMMAND}" -E echo "${compiler}")
endif()
