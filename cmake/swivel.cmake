# SPDX-License-Identifier: Apache-2.0
# Helpers shared by every folder: warnings, plugins and tests are declared the same way
# everywhere.
include(${CMAKE_CURRENT_LIST_DIR}/SwivelPluginHelpers.cmake)

function(swivel_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Wconversion
                                           -Wno-sign-conversion)
  if(SWIVEL_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
endfunction()

# A plain library (maths, no threads/DDS/YAML unless it says so).
#   swivel_add_library(NAME SOURCES ... [DEPS ...])
function(swivel_add_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  add_library(${name} STATIC ${ARG_SOURCES})
  target_link_libraries(${name} PUBLIC ${ARG_DEPS})
  swivel_warnings(${name})
endfunction()

# A run-time plugin: a shared library named swivel_<kind>_<name>.so in the plugin folder.
#   swivel_add_plugin(KIND NAME SOURCES ... [DEPS ...])
function(swivel_add_plugin kind name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  swivel_plugin_target_name(target ${kind} ${name})
  add_library(${target} MODULE ${ARG_SOURCES})
  target_link_libraries(${target} PRIVATE swivel::plugin_api ${ARG_DEPS})
  swivel_plugin_target_properties(${target})
  set_target_properties(${target} PROPERTIES LIBRARY_OUTPUT_DIRECTORY ${SWIVEL_PLUGIN_BUILD_DIR})
  swivel_warnings(${target})
  install(TARGETS ${target} LIBRARY DESTINATION ${SWIVEL_PLUGIN_INSTALL_DIR})
  set_property(GLOBAL APPEND PROPERTY SWIVEL_PLUGIN_TARGETS ${target})
endfunction()

# A GoogleTest executable registered with ctest.
#   swivel_add_test(NAME SOURCES ... [DEPS ...] [LABELS ...] [TIMEOUT s] [COST s])
# COST: about how long the test runs where it is slowest (the sanitizer trees). ctest starts
# the costliest first, on a tree without timings of its own (a fresh clone) too, so that a long
# test does not start last and hold its stage up alone.
function(swivel_add_test name)
  cmake_parse_arguments(ARG "" "TIMEOUT;COST" "SOURCES;DEPS;LABELS" ${ARGN})
  if(NOT SWIVEL_HAVE_GTEST)
    # Without GoogleTest the target exists (folders may set its properties) but is neither
    # built nor registered.
    add_executable(${name} EXCLUDE_FROM_ALL ${ARG_SOURCES})
    return()
  endif()
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_DEPS} GTest::gtest GTest::gtest_main)
  set_target_properties(${name} PROPERTIES RUNTIME_OUTPUT_DIRECTORY ${PROJECT_BINARY_DIR}/tests)
  swivel_warnings(${name})
  if(NOT ARG_TIMEOUT)
    set(ARG_TIMEOUT 120)
  endif()
  add_test(NAME ${name} COMMAND ${name})
  set_tests_properties(${name} PROPERTIES TIMEOUT ${ARG_TIMEOUT} LABELS "${ARG_LABELS}"
                       ENVIRONMENT "SWIVEL_PLUGIN_PATH=${SWIVEL_PLUGIN_BUILD_DIR};SWIVEL_SOURCE_DIR=${PROJECT_SOURCE_DIR};SWIVEL_BUILD_DIR=${PROJECT_BINARY_DIR};CYCLONEDDS_URI=file://${PROJECT_SOURCE_DIR}/config/dds/loopback.xml")
  if(ARG_COST)
    set_tests_properties(${name} PROPERTIES COST ${ARG_COST})
  endif()
endfunction()
