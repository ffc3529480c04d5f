# SPDX-License-Identifier: Apache-2.0
# tools/lib/preset_compiler.cmake names the compiler a preset asks for: its own, one it
# inherits, or none. A wrong answer makes the tools wipe a sanitizer tree on every configure
# (or keep a tree built by the wrong compiler).
function(expect presets preset wanted)
  execute_process(COMMAND "${CMAKE_COMMAND}" -DPRESETS=${presets} -DPRESET=${preset}
                          -P "${REPO}/tools/lib/preset_compiler.cmake"
                  OUTPUT_VARIABLE got OUTPUT_STRIP_TRAILING_WHITESPACE RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0 OR NOT got STREQUAL wanted)
    message(FATAL_ERROR "${preset} in ${presets}: wanted '${wanted}', got '${got}' (exit ${rc})")
  endif()
endfunction()

expect(${FIXTURE} clang-tree clang++)   # after a "${sourceDir}" line
expect(${FIXTURE} clang-child clang++)  # inherited
expect(${FIXTURE} default-compiler "")
expect(${FIXTURE} no-such-preset "")
# The project's own presets: the sanitizer trees the tools configure.
expect(${REPO}/CMakePresets.json asan-ubsan clang++)
expect(${REPO}/CMakePresets.json tsan "")
expect(${REPO}/CMakePresets.json release "")
