// SPDX-License-Identifier: Apache-2.0
#pragma once
// The layout fingerprint of the plugin ABI (abi.hpp), expanded from the list of what crosses
// the boundary (abi_boundary.hpp): each type's size and alignment, each interface's number
// of vtable slots, and each virtual method's slot and signature, as the including
// translation unit compiles them. A plugin's descriptor carries its own; the loader compares
// it with the host's and names the first difference.
//
// Every plugin interface header includes this one at its end (for SWIVEL_EXPORT_PLUGIN),
// and this one includes them all: whichever comes first, the interfaces are complete here.

#include <yaml-cpp/yaml.h>

#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <typeinfo>
#include <vector>

#include "swivel/plugin/abi.hpp"
#include "swivel/plugin/abi_boundary.hpp"
#include "swivel/plugin/calibration.hpp"
#include "swivel/plugin/drivetrain.hpp"
#include "swivel/plugin/hardware.hpp"
#include "swivel/plugin/localization.hpp"
#include "swivel/plugin/plugin_context.hpp"
#include "swivel/robot_model.hpp"
#include "swivel/types.hpp"

#ifndef _GLIBCXX_USE_CXX11_ABI
#define SWIVEL_CXX11_STRING_ABI 0u
#else
#define SWIVEL_CXX11_STRING_ABI static_cast<std::uint32_t>(_GLIBCXX_USE_CXX11_ABI)
#endif

namespace swivel {
namespace abi_detail {

/// The vtable index a pointer to virtual member function holds (Itanium C++ ABI 2.3: the
/// byte offset plus one in `ptr`; its ARM variant keeps the plain offset and marks virtual
/// functions in `adj`).
template <class MemberFunction>
std::uint32_t vtable_slot(MemberFunction method) {
  struct Representation {
    std::uintptr_t ptr;
    std::ptrdiff_t adj;
  };
  static_assert(sizeof(MemberFunction) == sizeof(Representation));
  const auto rep = std::bit_cast<Representation>(method);
#if defined(__arm__) || defined(__aarch64__)
  return static_cast<std::uint32_t>(rep.ptr / sizeof(void*));
#else
  return static_cast<std::uint32_t>((rep.ptr - 1) / sizeof(void*));
#endif
}

/// An interface's vtable length: the slot of a virtual method appended in a derived class.
template <class Interface>
struct VtableEnd : Interface {
  virtual void abi_vtable_end() {}
};

template <class Interface>
std::uint32_t vtable_slots() {
  return vtable_slot(&VtableEnd<Interface>::abi_vtable_end);
}

template <class T>
SwivelAbiLayout layout(const char* name) {
  std::uint32_t slots = 0;
  if constexpr (std::is_polymorphic_v<T>) slots = vtable_slots<T>();
  return SwivelAbiLayout{name, static_cast<std::uint32_t>(sizeof(T)),
                         static_cast<std::uint32_t>(alignof(T)), slots};
}

template <class MemberFunction>
SwivelAbiVirtual virtual_method(const char* name, MemberFunction method) {
  return SwivelAbiVirtual{name, typeid(MemberFunction).name(), vtable_slot(method)};
}

}  // namespace abi_detail

// NOLINTBEGIN(bugprone-macro-parentheses): the arguments are type and method names.
#define SWIVEL_ABI_COUNT_ONE(...) +1
#define SWIVEL_ABI_LAYOUT(...) ::swivel::abi_detail::layout<__VA_ARGS__>(#__VA_ARGS__),
#define SWIVEL_ABI_VIRTUAL(interface, method) \
  ::swivel::abi_detail::virtual_method(#interface "::" #method, &interface::method),
// NOLINTEND(bugprone-macro-parentheses)

/// Number of entries of each kind in the list.
inline constexpr std::size_t kAbiTypeCount = 0 SWIVEL_ABI_TYPES(SWIVEL_ABI_COUNT_ONE);
inline constexpr std::size_t kAbiVirtualCount = 0 SWIVEL_ABI_VIRTUALS(SWIVEL_ABI_COUNT_ONE);

/// This translation unit's fingerprint (one static per library). Built on the first call,
/// which the loader makes off the real-time loop.
inline const SwivelAbiFingerprint* abi_fingerprint() {
  static const std::array<SwivelAbiLayout, kAbiTypeCount> layouts{
      SWIVEL_ABI_TYPES(SWIVEL_ABI_LAYOUT)};
  static const std::array<SwivelAbiVirtual, kAbiVirtualCount> virtuals{
      SWIVEL_ABI_VIRTUALS(SWIVEL_ABI_VIRTUAL)};
  static const SwivelAbiFingerprint fingerprint{
      static_cast<std::uint32_t>(__GXX_ABI_VERSION), SWIVEL_CXX11_STRING_ABI,
      static_cast<std::uint32_t>(layouts.size()),    layouts.data(),
      static_cast<std::uint32_t>(virtuals.size()),   virtuals.data()};
  return &fingerprint;
}

/// "" when `plugin` matches this translation unit's fingerprint, else what differs first,
/// e.g. "layout of HardwareState differs: 1240 bytes, alignment 8 in the plugin; 1232
/// bytes, alignment 8 here".
/// Host side (swivel_runtime, the loader): defined with the host's own view of the types.
std::string abi_fingerprint_difference(const SwivelAbiFingerprint* plugin);

}  // namespace swivel
