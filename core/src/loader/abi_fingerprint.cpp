// SPDX-License-Identifier: Apache-2.0
#include "swivel/plugin/abi_fingerprint.hpp"

#include <cstring>
#include <span>

namespace swivel {
namespace {

std::string layout_text(const SwivelAbiLayout& l) {
  std::string text = std::to_string(l.size) + " bytes, alignment " + std::to_string(l.align);
  if (l.vtable_slots != 0) text += ", " + std::to_string(l.vtable_slots) + " vtable slots";
  return text;
}

std::string virtual_text(const SwivelAbiVirtual& v) {
  return "slot " + std::to_string(v.slot) + ", signature " +
         (v.signature != nullptr ? v.signature : "(none)");
}

bool same_name(const char* a, const char* b) {
  return a != nullptr && b != nullptr && std::strcmp(a, b) == 0;
}

// The plugin's entry named `name` (a layout's type or a virtual's method), or null.
template <class Entry, class Name>
const Entry* find_entry(std::span<const Entry> entries, const char* name, Name name_of) {
  for (const Entry& e : entries) {
    if (same_name(name_of(e), name)) return &e;
  }
  return nullptr;
}

std::string layout_difference(std::span<const SwivelAbiLayout> plugin,
                              std::span<const SwivelAbiLayout> here) {
  for (const SwivelAbiLayout& mine : here) {
    const SwivelAbiLayout* theirs =
        find_entry(plugin, mine.type, [](const SwivelAbiLayout& l) { return l.type; });
    if (theirs == nullptr) return std::string("no layout of ") + mine.type + " in the plugin";
    if (theirs->size != mine.size || theirs->align != mine.align ||
        theirs->vtable_slots != mine.vtable_slots) {
      return std::string("layout of ") + mine.type + " differs: " + layout_text(*theirs) +
             " in the plugin; " + layout_text(mine) + " here";
    }
  }
  if (plugin.size() != here.size()) {
    return "the plugin lists " + std::to_string(plugin.size()) + " types, this host " +
           std::to_string(here.size());
  }
  return {};
}

std::string virtual_difference(std::span<const SwivelAbiVirtual> plugin,
                               std::span<const SwivelAbiVirtual> here) {
  for (const SwivelAbiVirtual& mine : here) {
    const SwivelAbiVirtual* theirs =
        find_entry(plugin, mine.method, [](const SwivelAbiVirtual& v) { return v.method; });
    if (theirs == nullptr) {
      return std::string("no virtual method ") + mine.method + " in the plugin";
    }
    if (theirs->slot != mine.slot || !same_name(theirs->signature, mine.signature)) {
      return std::string("virtual method ") + mine.method + " differs: " + virtual_text(*theirs) +
             " in the plugin; " + virtual_text(mine) + " here";
    }
  }
  if (plugin.size() != here.size()) {
    return "the plugin lists " + std::to_string(plugin.size()) + " virtual methods, this host " +
           std::to_string(here.size());
  }
  return {};
}

}  // namespace

std::string abi_fingerprint_difference(const SwivelAbiFingerprint* plugin) {
  const SwivelAbiFingerprint& here = *abi_fingerprint();
  if (plugin == nullptr || (plugin->layout_count > 0 && plugin->layouts == nullptr) ||
      (plugin->virtual_count > 0 && plugin->virtuals == nullptr)) {
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
  std::string differs =
      layout_difference({plugin->layouts, plugin->layout_count}, {here.layouts, here.layout_count});
  if (differs.empty()) {
    differs = virtual_difference({plugin->virtuals, plugin->virtual_count},
                                 {here.virtuals, here.virtual_count});
  }
  return differs;
}

}  // namespace swivel
