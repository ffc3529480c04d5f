// SPDX-License-Identifier: Apache-2.0
#pragma once
// Watches the configuration file for changes. inotify watches the file's DIRECTORY, so an
// editor that writes a new file and renames it over the old one (vim, sed -i, most tools)
// is caught as well as one that rewrites it in place. Bursts of events (truncate + write +
// close, or several saves) are merged: the callback runs once the file has been quiet for
// the debounce interval.
//
// Not real-time: the callback runs on the watcher's own thread.

#include <chrono>
#include <functional>
#include <string>
#include <thread>

namespace swivel::daemon {

class ConfigWatcher {
 public:
  /// Starts watching `file`'s directory; `on_change` runs on the watcher thread after each
  /// (debounced) write-close or rename onto the file's name.
  /// @throws std::system_error when inotify cannot watch the directory.
  ConfigWatcher(const std::string& file, std::function<void()> on_change,
                std::chrono::milliseconds debounce = std::chrono::milliseconds(100));
  /// Stops and joins the thread.
  ~ConfigWatcher();
  ConfigWatcher(const ConfigWatcher&) = delete;
  ConfigWatcher& operator=(const ConfigWatcher&) = delete;

 private:
  void run(const std::stop_token& stop);

  std::string directory_;
  std::string name_;
  std::function<void()> on_change_;
  std::chrono::milliseconds debounce_;
  int fd_ = -1;
  std::jthread thread_;
};

}  // namespace swivel::daemon
