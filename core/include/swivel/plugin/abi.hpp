#pragma once
// Real-time methods of the plugin interfaces (read, write, forward, inverse, update,
// hand_over) must not allocate or throw; implementations declare them noexcept. The base
// declarations are not noexcept so that a faulty plugin that throws anyway is caught at
// the host's boundary and becomes a fault with a controlled stop instead of a crash.
//
// The one C entry point every plugin library exports. The host dlopen()s a library, looks
// up `swivel_plugin_descriptor`, and checks abi_version (first field, always) and kind
// before calling anything else. Bump SWIVEL_PLUGIN_ABI_VERSION whenever a plugin interface
// or a type in swivel/types.hpp changes layout.
//
// ABI versions:
//   1  the first plugin interfaces
//   2  Hardware gains the lifecycle hooks activate(), deactivate() and on_error()

#include <array>
#include <cstdint>
#include <cstdio>
#include <exception>

extern "C" {

#define SWIVEL_PLUGIN_ABI_VERSION 2u
#define SWIVEL_PLUGIN_ENTRY_POINT "swivel_plugin_descriptor"

enum SwivelPluginKind : std::uint32_t {
  SWIVEL_PLUGIN_HARDWARE = 1,
  SWIVEL_PLUGIN_DRIVETRAIN = 2,
  SWIVEL_PLUGIN_LOCALIZATION = 3,
  SWIVEL_PLUGIN_CALIBRATION = 4,
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
};

typedef const SwivelPluginDescriptor* (*SwivelPluginEntryPoint)(void);
}

namespace swivel {
class Hardware;
class Drivetrain;
class Localization;
class Calibration;

template <class Interface>
struct PluginKindOf;
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

/// Exports `Class` (derived from `Interface`) as plugin `name`. Use once per library:
///   SWIVEL_EXPORT_PLUGIN(swivel::plugins::DifferentialDrivetrain, swivel::Drivetrain,
///                        "differential")
#define SWIVEL_EXPORT_PLUGIN(Class, Interface, plugin_name)                                   \
  extern "C" __attribute__((visibility("default"))) const SwivelPluginDescriptor*           \
  swivel_plugin_descriptor(void) {                                                          \
    static const SwivelPluginDescriptor descriptor{                                         \
        SWIVEL_PLUGIN_ABI_VERSION, ::swivel::PluginKindOf<Interface>::value, plugin_name,   \
        [](const char** error) -> void* {                                                   \
          try {                                                                             \
            return static_cast<Interface*>(new Class());                                    \
          } catch (const std::exception& e) {                                               \
            static thread_local std::array<char, 256> message{};                            \
            (void)std::snprintf(message.data(), message.size(), "%s", e.what());            \
            if (error != nullptr) *error = message.data();                                  \
          } catch (...) {                                                                   \
            if (error != nullptr) *error = "unknown exception in constructor";              \
          }                                                                                 \
          return nullptr;                                                                   \
        },                                                                                  \
        [](void* instance) { delete static_cast<Interface*>(instance); }};                  \
    return &descriptor;                                                                     \
  }
