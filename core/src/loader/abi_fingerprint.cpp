// SPDX-License-Identifier: Apache-2.0
#include "swivel/plugin/abi_fingerprint.hpp"

#include <cstring>

namespace swivel {
namespace {

std::string layout_text(const SwivelAbiLayout& l) {
  return std::to_string(l.size) + " bytes, alignment " + std::to_string(l.align);
}

}  // namespace

std::string abi_fingerprint_difference(const SwivelAbiFingerprint* plugin) {
  const SwivelAbiFingerprint& here = *abi_fingerprint();
  if (plugin == nullptr || (plugin->layout_count > 0 && plugin->layouts == nullptr)) {
    return "no layout fingerprint in the descriptor";
  }
  if (plugin->cxx_abi_version != here.cxx_abi_version) {
    return "C++ ABI " + std::to_string(plugin->cxx_abi_version) + " in the plugin, " +
           std::to_string(here.cxx_abi_version) + " here (__GXX_ABI_VERSION: another compiler)";
  }
  if (plugin->cxx11_string_abi != here.cxx11_string_abi) {
    return "std::string ABI " + std::to_string(plugin->cxx11_string_abi) + " in the plugin, " +
           std::to_string(here.cxx11_string_abi) + " here (_GLIBCXX_USE_CXX11_ABI)";
  }
  for (std::uint32_t i = 0; i < here.layout_count; ++i) {
    const SwivelAbiLayout& mine = here.layouts[i];
    const SwivelAbiLayout* theirs = nullptr;
    for (std::uint32_t k = 0; k < plugin->layout_count; ++k) {
      const char* type = plugin->layouts[k].type;
      if (type != nullptr && std::strcmp(type, mine.type) == 0) theirs = &plugin->layouts[k];
    }
    if (theirs == nullptr) return std::string("no layout of ") + mine.type + " in the plugin";
    if (theirs->size != mine.size || theirs->align != mine.align) {
      return std::string("layout of ") + mine.type + " differs: " + layout_text(*theirs) +
             " in the plugin; " + layout_text(mine) + " here";
    }
  }
  if (plugin->layout_count != here.layout_count) {
    return "the plugin lists " + std::to_string(plugin->layout_count) + " types, this host " +
           std::to_string(here.layout_count);
  }
  return {};
}

}  // namespace swivel
