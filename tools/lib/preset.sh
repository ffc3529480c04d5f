# SPDX-License-Identifier: Apache-2.0
# Sourced by the tools/ scripts. configure_preset PRESET BUILD_DIR: configures a CMake preset
# into its build directory, first removing a directory that an earlier compiler or generator
# configured (CMake can switch a tree neither from g++ to clang nor from make to Ninja in
# place).
preset_setting() {
  cmake -DPRESETS="$repo/CMakePresets.json" -DPRESET="$1" -DSETTING="$2" \
        -P "$repo/tools/lib/preset_setting.cmake"
}

configure_preset() {
  local preset=$1 build=$2 compiler generator cached_compiler cached_generator
  compiler=$(preset_setting "$preset" compiler)
  compiler=${compiler:-c++}  # a preset that names no compiler gets the system's default
  generator=$(preset_setting "$preset" generator)
  if [[ -f $build/CMakeCache.txt ]]; then
    cached_compiler=$(sed -n 's/^CMAKE_CXX_COMPILER:[A-Z]*=//p' "$build/CMakeCache.txt")
    cached_generator=$(sed -n 's/^CMAKE_GENERATOR:[A-Z]*=//p' "$build/CMakeCache.txt")
    if [[ -n $cached_compiler && $(basename "$cached_compiler") != "$compiler" ]]; then
      echo "tools: $build was configured with $(basename "$cached_compiler"), the $preset preset uses $compiler: starting it afresh" >&2
      rm -rf "$build"
    elif [[ -n $generator && -n $cached_generator && $cached_generator != "$generator" ]]; then
      echo "tools: $build was generated for $cached_generator, the $preset preset uses $generator: starting it afresh" >&2
      rm -rf "$build"
    fi
  fi
  cmake --preset "$preset"
}
