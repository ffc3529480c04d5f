# SPDX-License-Identifier: Apache-2.0
# tools/lib/preset_setting.cmake names the compiler or generator a preset asks for: its own,
# one it inherits, or none. A wrong answer makes the tools wipe a sanitizer tree on every
# configure (or keep a tree that CMake then refuses to configure).
function(expect presets preset setting wanted)
  execute_process(COMMAND "${CMAKE_COMMAND}" -DPRESETS=${presets} -DPRESET=${preset}
                          -DSETTING=${setting} -P "${REPO}/tools/lib/preset_setting.cmake"
                  OUTPUT_VARIABLE got OUTPUT_STRIP_TRAILING_WHITESPACE RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0 OR NOT got STREQUAL wanted)
    message(FATAL_ERROR
            "${preset}'s ${setting} in ${presets}: wanted '${wanted}', got '${got}' (exit ${rc})")
  endif()
endfunction()

expect(${FIXTURE} clang-tree compiler clang++)   # after a "${sourceDir}" line
expect(${FIXTURE} clang-child compiler clang++)  # inherited
expect(${FIXTURE} default-compiler compiler "")
expect(${FIXTURE} no-such-preset compiler "")
expect(${FIXTURE} clang-tree generator "Unix Makefiles")  # inherited from base
expect(${FIXTURE} ninja-tree generator Ninja)             # its own, over base's
expect(${FIXTURE} ninja-child generator Ninja)
# The project's own presets: the sanitizer trees the tools configure.
expect(${REPO}/CMakePresets.json asan-ubsan compiler clang++)
expect(${REPO}/CMakePresets.json tsan compiler "")
expect(${REPO}/CMakePresets.json release compiler "")
expect(${REPO}/CMakePresets.json asan-ubsan generator Ninja)
expect(${REPO}/CMakePresets.json tsan generator Ninja)
expect(${REPO}/CMakePresets.json release generator "Unix Makefiles")
