// SPDX-License-Identifier: Apache-2.0
// A hardware plugin as it was built against ABI 1, before Hardware had its lifecycle hooks:
// the loader must refuse it before creating anything, because its vtable lacks them.
#include "swivel/plugin/hardware.hpp"

namespace {

// The descriptor as ABI 1 and 2 laid it out: no fingerprint after destroy.
struct DescriptorBeforeAbi3 {
  std::uint32_t abi_version;
  std::uint32_t kind;
  const char* name;
  void* (*create)(const char** error);
  void (*destroy)(void* instance);
};

}  // namespace

extern "C" __attribute__((visibility("default"))) const SwivelPluginDescriptor*
swivel_plugin_descriptor(void) {
  static const DescriptorBeforeAbi3 descriptor{1U, SWIVEL_PLUGIN_HARDWARE, "old_abi",
                                               [](const char** error) -> void* {
                                                 *error = "must never be called";
                                                 return nullptr;
                                               },
                                               [](void* /*instance*/) {}};
  // The host reads abi_version first and stops there, as it must for any older plugin.
  return reinterpret_cast<const SwivelPluginDescriptor*>(&descriptor);
}
