// SPDX-License-Identifier: Apache-2.0
#include <dlfcn.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <map>
#include <mutex>
#include <string_view>

#include "swivel/plugin/abi_fingerprint.hpp"
#include "swivel/plugin_loader.hpp"

#ifndef SWIVEL_PLUGIN_INSTALL_DIR
#error "SWIVEL_PLUGIN_INSTALL_DIR comes from core/src/loader/CMakeLists.txt"
#endif

namespace swivel {

class PluginLibrary {
 public:
  PluginLibrary(void* handle, std::string path) : handle_(handle), path_(std::move(path)) {}
  PluginLibrary(const PluginLibrary&) = delete;
  PluginLibrary& operator=(const PluginLibrary&) = delete;
  ~PluginLibrary() { dlclose(handle_); }

  [[nodiscard]] void* handle() const { return handle_; }
  [[nodiscard]] const std::string& path() const { return path_; }

 private:
  void* handle_;
  std::string path_;
};

namespace {

// Libraries stay shared between instances (a hot swap to the same plugin reuses the loaded
// library) and unload when the last instance is gone.
std::mutex g_cache_mutex;
std::map<std::string, std::weak_ptr<PluginLibrary>>& cache() {
  static std::map<std::string, std::weak_ptr<PluginLibrary>> libraries;
  return libraries;
}

bool is_regular_file(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode);
}

std::string canonical(const std::string& path) {
  char* resolved = ::realpath(path.c_str(), nullptr);
  if (resolved == nullptr) return path;
  std::string result(resolved);
  std::free(resolved);  // NOLINT(cppcoreguidelines-no-malloc): realpath() mallocs it
  return result;
}

std::string executable_dir() {
  std::string buffer(4096, '\0');
  const ssize_t n = ::readlink("/proc/self/exe", buffer.data(), buffer.size() - 1);
  if (n <= 0) return {};
  buffer.resize(static_cast<std::size_t>(n));
  const auto slash = buffer.rfind('/');
  return slash == std::string::npos ? std::string() : buffer.substr(0, slash);
}

std::string join(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& item : items) out += (out.empty() ? "" : ", ") + item;
  return out;
}

}  // namespace

PluginLoader::PluginLoader(std::vector<std::string> search_path)
    : search_path_(std::move(search_path)) {}

std::vector<std::string> PluginLoader::default_search_path() {
  std::vector<std::string> path;
  if (const char* env = std::getenv("SWIVEL_PLUGIN_PATH"); env != nullptr) {
    std::string_view rest(env);
    while (!rest.empty()) {
      const auto colon = rest.find(':');
      const std::string_view dir = rest.substr(0, colon);
      if (!dir.empty()) path.emplace_back(dir);
      if (colon == std::string_view::npos) break;
      rest.remove_prefix(colon + 1);
    }
  }
  if (const std::string exe = executable_dir(); !exe.empty()) {
    path.push_back(exe + "/../lib/swivel/plugins");
  }
  path.emplace_back(SWIVEL_PLUGIN_INSTALL_DIR);
  return path;
}

std::shared_ptr<PluginLibrary> PluginLoader::open(std::uint32_t kind, const std::string& name,
                                                  const SwivelPluginDescriptor*& descriptor,
                                                  std::string& path) {
  const std::string kind_name = plugin_kind_name(kind);
  if (name.empty() || name.find('/') != std::string::npos) {
    throw PluginError("invalid " + kind_name + " plugin name '" + name + "'");
  }
  const std::string file = "swivel_" + kind_name + "_" + name + ".so";
  for (const auto& dir : search_path_) {
    std::string candidate = dir;
    candidate.append("/").append(file);
    if (!is_regular_file(candidate)) continue;
    path = candidate;
    auto library = open_file(kind, candidate, descriptor);
    if (name != descriptor->name) {
      // Once, on the way out. NOLINTBEGIN(performance-inefficient-string-concatenation)
      throw PluginError(candidate + ": name mismatch: the library declares '" +
                        std::string(descriptor->name) + "', expected '" + name + "'");
      // NOLINTEND(performance-inefficient-string-concatenation)
    }
    return library;
  }
  throw PluginError(
      kind_name + " plugin '" + name + "' not found: no " + file + " in " +
      (search_path_.empty() ? std::string("an empty search path") : join(search_path_)) +
      " (set SWIVEL_PLUGIN_PATH or plugin_path to add directories)");
}

std::shared_ptr<PluginLibrary> PluginLoader::open_file(std::uint32_t kind, const std::string& file,
                                                       const SwivelPluginDescriptor*& descriptor) {
  const std::string key = canonical(file);
  std::shared_ptr<PluginLibrary> library;
  {
    const std::lock_guard<std::mutex> lock(g_cache_mutex);
    auto& libraries = cache();
    if (auto it = libraries.find(key); it != libraries.end()) library = it->second.lock();
    if (!library) {
      void* handle = ::dlopen(file.c_str(), RTLD_NOW | RTLD_LOCAL);
      if (handle == nullptr) {
        const char* reason = ::dlerror();
        throw PluginError(file + ": cannot load: " + (reason != nullptr ? reason : "unknown"));
      }
      library = std::make_shared<PluginLibrary>(handle, key);
      libraries[key] = library;
    }
  }

  ::dlerror();
  void* symbol = ::dlsym(library->handle(), SWIVEL_PLUGIN_ENTRY_POINT);
  if (symbol == nullptr) {
    throw PluginError(file + ": missing entry point '" SWIVEL_PLUGIN_ENTRY_POINT
                             "' (is SWIVEL_EXPORT_PLUGIN used?)");
  }
  const auto entry = reinterpret_cast<SwivelPluginEntryPoint>(symbol);
  const SwivelPluginDescriptor* d = entry();
  if (d == nullptr) throw PluginError(file + ": entry point returned no descriptor");
  if (d->abi_version != SWIVEL_PLUGIN_ABI_VERSION) {
    const char* which = d->abi_version < SWIVEL_PLUGIN_ABI_VERSION ? "an older" : "a newer";
    throw PluginError(file + ": ABI version " + std::to_string(d->abi_version) + ", expected " +
                      std::to_string(SWIVEL_PLUGIN_ABI_VERSION) + " (built for " + which +
                      " Swivel: rebuild the plugin against this one's headers)");
  }
  if (const std::string differs = abi_fingerprint_difference(d->fingerprint); !differs.empty()) {
    throw PluginError(file + ": built with another layout of the plugin ABI: " + differs +
                      " (rebuild the plugin against this Swivel's headers, with the same "
                      "compiler)");
  }
  if (d->kind != kind) {
    throw PluginError(file + ": kind '" + plugin_kind_name(d->kind) + "', expected '" +
                      plugin_kind_name(kind) + "'");
  }
  if (d->name == nullptr || d->create == nullptr || d->destroy == nullptr) {
    throw PluginError(file + ": incomplete descriptor (name, create and destroy are required)");
  }
  descriptor = d;
  return library;
}

void* PluginLoader::instantiate(const SwivelPluginDescriptor& descriptor, const std::string& path) {
  const char* error = nullptr;
  void* instance = descriptor.create(&error);
  if (instance == nullptr) {
    throw PluginError(path + ": create failed: " +
                      (error != nullptr ? std::string(error) : std::string("no reason given")));
  }
  return instance;
}

}  // namespace swivel
