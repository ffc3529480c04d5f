# SPDX-License-Identifier: Apache-2.0
# How a Swivel plugin library is built, for this tree and for plugins built elsewhere
# against an installed Swivel (find_package(Swivel); installed next to SwivelConfig.cmake).

# The properties every plugin library needs: loadable by name (swivel_<kind>_<name>.so, no
# "lib" prefix), only the entry point visible (SWIVEL_EXPORT_PLUGIN marks it), so that two
# plugins never resolve each other's symbols.
function(swivel_plugin_target_properties target)
  set_target_properties(${target} PROPERTIES PREFIX "" CXX_VISIBILITY_PRESET hidden
                                             VISIBILITY_INLINES_HIDDEN ON)
endfunction()

# swivel_plugin_target_name(OUT KIND NAME): "swivel_<kind>_<name>", after checking KIND.
function(swivel_plugin_target_name out kind name)
  set(kinds hardware drivetrain localization calibration)
  if(NOT kind IN_LIST kinds)
    message(FATAL_ERROR "swivel plugin '${name}': KIND must be one of ${kinds}, not '${kind}'")
  endif()
  if(NOT name MATCHES "^[a-z0-9_]+$")
    message(FATAL_ERROR "swivel plugin name '${name}': use lower-case letters, digits and '_'")
  endif()
  set(${out} swivel_${kind}_${name} PARENT_SCOPE)
endfunction()
