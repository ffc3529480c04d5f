// A hardware plugin as it was built against ABI 1, before Hardware had its lifecycle hooks:
// the loader must refuse it before creating anything, because its vtable lacks them.
#include "swivel/plugin/hardware.hpp"

extern "C" __attribute__((visibility("default"))) const SwivelPluginDescriptor*
swivel_plugin_descriptor(void) {
  static const SwivelPluginDescriptor descriptor{
      1u, SWIVEL_PLUGIN_HARDWARE, "old_abi",
      [](const char** error) -> void* {
        *error = "must never be called";
        return nullptr;
      },
      [](void* /*instance*/) {}};
  return &descriptor;
}
