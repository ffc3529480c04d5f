# SPDX-License-Identifier: Apache-2.0
# Sourced by the tools/ scripts. configure_preset PRESET BUILD_DIR: configures a CMake preset
# into its build directory, first removing a directory that an earlier compiler configured
# (CMake cannot switch a tree from g++ to clang in place).
configure_preset() {
  local preset=$1 build=$2 wanted cached
  wanted=$(cmake -DPRESETS="$repo/CMakePresets.json" -DPRESET="$preset" \
                 -P "$repo/tools/lib/preset_compiler.cmake")
  wanted=${wanted:-c++}  # a preset that names no compiler gets the system's default
  if [[ -f $build/CMakeCache.txt ]]; then
    cached=$(sed -n 's/^CMAKE_CXX_COMPILER:[A-Z]*=//p' "$build/CMakeCache.txt")
    if [[ -n $cached && $(basename "$cached") != "$wanted" ]]; then
      echo "tools: $build was configured with $(basename "$cached"), the $preset preset uses $wanted: starting it afresh" >&2
      rm -rf "$build"
    fi
  fi
  cmake --preset "$preset"
}
