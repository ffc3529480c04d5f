// SPDX-License-Identifier: Apache-2.0
#pragma once
// Finds plugin libraries by name on a search path, checks their descriptor and creates
// instances. Start-up / non-real-time code: throws PluginError with the file and the reason.

#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "swivel/plugin/abi.hpp"

namespace swivel {

class PluginError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A dlopen()ed library; unloaded when the last instance created from it is gone.
class PluginLibrary;

/// Owns one plugin instance and keeps its library loaded while it lives. Move-only.
template <class Interface>
class PluginInstance {
 public:
  PluginInstance() = default;
  PluginInstance(std::shared_ptr<PluginLibrary> library, Interface* instance,
                 void (*destroy)(void*), std::string name, std::string path)
      : library_(std::move(library)),
        instance_(instance),
        destroy_(destroy),
        name_(std::move(name)),
        path_(std::move(path)) {}
  PluginInstance(PluginInstance&& other) noexcept { *this = std::move(other); }
  PluginInstance& operator=(PluginInstance&& other) noexcept {
    if (this != &other) {
      reset();
      library_ = std::move(other.library_);
      instance_ = other.instance_;
      destroy_ = other.destroy_;
      name_ = std::move(other.name_);
      path_ = std::move(other.path_);
      other.instance_ = nullptr;
    }
    return *this;
  }
  PluginInstance(const PluginInstance&) = delete;
  PluginInstance& operator=(const PluginInstance&) = delete;
  ~PluginInstance() { reset(); }

  /// Destroys the instance (then the library may unload). Never on the real-time loop.
  void reset() noexcept {
    if (instance_ != nullptr) destroy_(instance_);
    instance_ = nullptr;
    library_.reset();
  }
  [[nodiscard]] Interface* get() const noexcept { return instance_; }
  Interface* operator->() const noexcept { return instance_; }
  Interface& operator*() const noexcept { return *instance_; }
  explicit operator bool() const noexcept { return instance_ != nullptr; }
  [[nodiscard]] const std::string& name() const noexcept { return name_; }
  [[nodiscard]] const std::string& path() const noexcept { return path_; }

 private:
  std::shared_ptr<PluginLibrary> library_;
  Interface* instance_ = nullptr;
  void (*destroy_)(void*) = nullptr;
  std::string name_;
  std::string path_;
};

class PluginLoader {
 public:
  /// @param search_path directories searched in order for swivel_<kind>_<name>.so
  explicit PluginLoader(std::vector<std::string> search_path);

  /// $SWIVEL_PLUGIN_PATH (colon-separated) first, then <executable dir>/../lib/swivel/plugins
  /// (build tree and installed tree), then the compiled-in install directory.
  static std::vector<std::string> default_search_path();

  /// Loads (or reuses) the library for plugin `name` of Interface's kind and creates one
  /// instance. @throws PluginError naming the file (or every directory searched) and what
  /// was wrong: not found, dlopen error, missing entry point, ABI version or kind mismatch,
  /// name mismatch, create() failure.
  template <class Interface>
  PluginInstance<Interface> create(const std::string& name) {
    const SwivelPluginDescriptor* descriptor = nullptr;
    std::string path;
    auto library = open(PluginKindOf<Interface>::value, name, descriptor, path);
    void* raw = instantiate(*descriptor, path);
    return PluginInstance<Interface>(std::move(library), static_cast<Interface*>(raw),
                                     descriptor->destroy, name, path);
  }

  /// Loads a library file directly (tests, diagnostics) and checks it like create().
  template <class Interface>
  PluginInstance<Interface> create_from_file(const std::string& file) {
    const SwivelPluginDescriptor* descriptor = nullptr;
    auto library = open_file(PluginKindOf<Interface>::value, file, descriptor);
    void* raw = instantiate(*descriptor, file);
    return PluginInstance<Interface>(std::move(library), static_cast<Interface*>(raw),
                                     descriptor->destroy, descriptor->name, file);
  }

  [[nodiscard]] const std::vector<std::string>& search_path() const { return search_path_; }

 private:
  std::shared_ptr<PluginLibrary> open(std::uint32_t kind, const std::string& name,
                                      const SwivelPluginDescriptor*& descriptor, std::string& path);
  static std::shared_ptr<PluginLibrary> open_file(std::uint32_t kind, const std::string& file,
                                                  const SwivelPluginDescriptor*& descriptor);
  static void* instantiate(const SwivelPluginDescriptor& descriptor, const std::string& path);

  std::vector<std::string> search_path_;
};

}  // namespace swivel
