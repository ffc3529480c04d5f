// SPDX-License-Identifier: Apache-2.0
#pragma once
// Real-time methods of the plugin interfaces (read, write, forward, inverse, update,
// hand_over) must not allocate or throw; implementations declare them noexcept. The base
// declarations are not noexcept so that a faulty plugin that throws anyway is caught at
// the host's boundary and becomes a fault with a controlled stop instead of a crash.
//
// The one C entry point every plugin library exports. The host dlopen()s a library, looks
// up `swivel_plugin_descriptor`, and checks abi_version (first field, always) and kind
// before calling anything else. Bump SWIVEL_PLUGIN_ABI_VERSION whenever a plugin interface
// changes. What a version number cannot catch (a type that crossed the boundary changed
// size, a virtual method moved, a plugin built with another C++ ABI) the descriptor's
// fingerprint does: the size and alignment of every type that crosses the boundary, the
// vtable slot and signature of every virtual method of the interfaces and the compiler's C++
// ABI, as the plugin was compiled (abi_fingerprint.hpp, from the one list in
// abi_boundary.hpp); the loader compares them with its own.
//
// ABI versions:
//   1  the first plugin interfaces
//   2  Hardware gains the lifecycle hooks activate(), deactivate() and on_error()
//   3  the descriptor carries the layout fingerprint
//   4  the fingerprint covers the calibration types and the interfaces' vtables

#include <array>
#include <cstdint>
#include <cstdio>
#include <exception>

// The C ABI keeps C's spelling: enumerators in capitals, a typedef for the entry point.
// NOLINTBEGIN(readability-identifier-naming,modernize-use-using,modernize-redundant-void-arg)
extern "C" {

#define SWIVEL_PLUGIN_ABI_VERSION 4U
#define SWIVEL_PLUGIN_ENTRY_POINT "swivel_plugin_descriptor"

enum SwivelPluginKind : std::uint32_t {
  SWIVEL_PLUGIN_HARDWARE = 1,
  SWIVEL_PLUGIN_DRIVETRAIN = 2,
  SWIVEL_PLUGIN_LOCALIZATION = 3,
  SWIVEL_PLUGIN_CALIBRATION = 4,
};

/// Size and alignment of one type that crosses the plugin boundary (ABI 4 on: with the
/// number of vtable slots of an interface).
struct SwivelAbiLayout {
  const char* type;  ///< e.g. "HardwareState"
  std::uint32_t size;
  std::uint32_t align;
  std::uint32_t vtable_slots;  ///< an interface's, destructors included; 0 for a plain type
};

/// Where one virtual method of a plugin interface sits in its vtable (ABI 4 on).
struct SwivelAbiVirtual {
  const char* method;     ///< e.g. "Hardware::read"
  const char* signature;  ///< the mangled type of its member pointer (parameters, noexcept)
  std::uint32_t slot;     ///< vtable index
};

/// How the plugin was compiled, as far as the host can check it (ABI 3 on).
struct SwivelAbiFingerprint {
  std::uint32_t cxx_abi_version;   ///< __GXX_ABI_VERSION (Itanium C++ ABI revision)
  std::uint32_t cxx11_string_abi;  ///< _GLIBCXX_USE_CXX11_ABI: std::string's layout
  std::uint32_t layout_count;
  const SwivelAbiLayout* layouts;
  std::uint32_t virtual_count;  ///< ABI 4 on
  const SwivelAbiVirtual* virtuals;
};

struct SwivelPluginDescriptor {
  std::uint32_t abi_version;  ///< must equal SWIVEL_PLUGIN_ABI_VERSION; always first
  std::uint32_t kind;         ///< a SwivelPluginKind
  const char* name;           ///< plugin name, e.g. "differential"
  /// Returns a new instance (a pointer to the kind's interface), or null on failure.
  /// Never throws; `error` receives a static or library-owned message on failure.
  void* (*create)(const char** error);
  /// Destroys an instance returned by create. Never throws.
  void (*destroy)(void* instance);
  /// The plugin's compile-time fingerprint (swivel::abi_fingerprint()); ABI 3 on.
  const SwivelAbiFingerprint* fingerprint;
};

typedef const SwivelPluginDescriptor* (*SwivelPluginEntryPoint)(void);
}
// NOLINTEND(readability-identifier-naming,modernize-use-using,modernize-redundant-void-arg)

namespace swivel {
class Hardware;
class Drivetrain;
class Localization;
class Calibration;

template <class Interface>
struct PluginKindOf;
// A type trait's member is `value`, as in the standard library's.
// NOLINTBEGIN(readability-identifier-naming)
template <>
struct PluginKindOf<Hardware> {
  static constexpr std::uint32_t value = SWIVEL_PLUGIN_HARDWARE;
};
template <>
struct PluginKindOf<Drivetrain> {
  static constexpr std::uint32_t value = SWIVEL_PLUGIN_DRIVETRAIN;
};
template <>
struct PluginKindOf<Localization> {
  static constexpr std::uint32_t value = SWIVEL_PLUGIN_LOCALIZATION;
};
template <>
struct PluginKindOf<Calibration> {
  static constexpr std::uint32_t value = SWIVEL_PLUGIN_CALIBRATION;
};
// NOLINTEND(readability-identifier-naming)

/// "hardware", "drivetrain", ... for messages.
inline const char* plugin_kind_name(std::uint32_t kind) {
  switch (kind) {
    case SWIVEL_PLUGIN_HARDWARE: return "hardware";
    case SWIVEL_PLUGIN_DRIVETRAIN: return "drivetrain";
    case SWIVEL_PLUGIN_LOCALIZATION: return "localization";
    case SWIVEL_PLUGIN_CALIBRATION: return "calibration";
    default: return "unknown";
  }
}
}  // namespace swivel

/// Exports `Class` (derived from `Interface`) as plugin `name`, with the fingerprint of the
/// types as this translation unit sees them (include the interface's header, which brings
/// swivel/plugin/abi_fingerprint.hpp). Use once per library:
///   SWIVEL_EXPORT_PLUGIN(swivel::plugins::DifferentialDrivetrain, swivel::Drivetrain,
///                        "differential")
// `Class` and `Interface` are type names, which parentheses would break.
// NOLINTBEGIN(bugprone-macro-parentheses)
#define SWIVEL_EXPORT_PLUGIN(Class, Interface, plugin_name)                       \
  extern "C" __attribute__((visibility("default"))) const SwivelPluginDescriptor* \
  swivel_plugin_descriptor(void) {                                                \
    static const SwivelPluginDescriptor descriptor{                               \
        SWIVEL_PLUGIN_ABI_VERSION,                                                \
        ::swivel::PluginKindOf<Interface>::value,                                 \
        plugin_name,                                                              \
        [](const char** error) -> void* {                                         \
          try {                                                                   \
            return static_cast<Interface*>(new Class());                          \
          } catch (const std::exception& e) {                                     \
            static thread_local std::array<char, 256> message{};                  \
            (void)std::snprintf(message.data(), message.size(), "%s", e.what());  \
            if (error != nullptr) *error = message.data();                        \
          } catch (...) {                                                         \
            if (error != nullptr) *error = "unknown exception in constructor";    \
          }                                                                       \
          return nullptr;                                                         \
        },                                                                        \
        [](void* instance) { delete static_cast<Interface*>(instance); },         \
        ::swivel::abi_fingerprint()};                                             \
    return &descriptor;                                                           \
  }
// NOLINTEND(bugprone-macro-parentheses)
