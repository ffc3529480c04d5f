// SPDX-License-Identifier: Apache-2.0
#pragma once
// Child processes for the integration tests: swiveld and swivelctl run as real executables
// with stdout and stderr in files, started with extra environment variables, signalled and
// awaited with timeouts.

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

namespace swivel::test {

using Clock = std::chrono::steady_clock;
using Seconds = std::chrono::duration<double>;

inline std::string env_or_empty(const char* name) {
  const char* value = std::getenv(name);
  return value != nullptr ? value : "";
}
inline std::string build_dir() { return env_or_empty("SWIVEL_BUILD_DIR"); }
inline std::string source_dir() { return env_or_empty("SWIVEL_SOURCE_DIR"); }
inline std::string swiveld_exe() { return build_dir() + "/bin/swiveld"; }
inline std::string swivelctl_exe() { return build_dir() + "/bin/swivelctl"; }

inline std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

/// Writes `text` to a new file next to `path` and renames it over `path`, as editors do.
inline void write_by_rename(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".tmp~";
  {
    std::ofstream out(tmp);
    out << text;
  }
  std::filesystem::rename(tmp, path);
}

/// A fresh directory for one test's files.
inline std::string make_test_dir(const std::string& name) {
  static std::atomic<int> counter{0};
  const auto dir =
      std::filesystem::temp_directory_path() /
      ("swivel_it_" + name + "_" + std::to_string(getpid()) + "_" + std::to_string(counter++));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir.string();
}

class Child {
 public:
  Child(const std::string& exe, const std::vector<std::string>& args,
        const std::vector<std::pair<std::string, std::string>>& env = {}) {
    static std::atomic<int> counter{0};
    const std::string base = std::filesystem::temp_directory_path().string() + "/swivel_child_" +
                             std::to_string(getpid()) + "_" + std::to_string(counter++);
    out_ = base + ".out";
    err_ = base + ".err";
    pid_ = fork();  // NOLINT(cppcoreguidelines-prefer-member-initializer): after the files
    if (pid_ == 0) {
      const int out = open(out_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      const int err = open(err_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      dup2(out, STDOUT_FILENO);
      dup2(err, STDERR_FILENO);
      for (const auto& [name, value] : env) setenv(name.c_str(), value.c_str(), 1);
      std::vector<char*> argv;
      argv.push_back(const_cast<char*>(exe.c_str()));
      for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
      argv.push_back(nullptr);
      execv(exe.c_str(), argv.data());
      _exit(127);
    }
  }
  ~Child() {
    if (pid_ > 0 && !status_) {
      ::kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
    std::remove(out_.c_str());
    std::remove(err_.c_str());
  }
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;

  void signal(int sig) const { ::kill(pid_, sig); }
  [[nodiscard]] pid_t pid() const { return pid_; }

  /// True while the process has not exited.
  bool alive() {
    if (status_) return false;
    int status = 0;
    if (waitpid(pid_, &status, WNOHANG) == pid_) {
      status_ = status;
      return false;
    }
    return true;
  }

  /// The wait status once the process exited within `limit`.
  std::optional<int> wait_for(Seconds limit) {
    const auto deadline = Clock::now() + limit;
    while (alive() && Clock::now() < deadline)
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    return status_;
  }

  /// The exit code, or -1 when it did not exit normally within `limit` (it is then killed).
  int exit_code(Seconds limit) {
    const auto status = wait_for(limit);
    if (!status) {
      signal(SIGKILL);
      wait_for(Seconds(5));
      return -1;
    }
    return WIFEXITED(*status) ? WEXITSTATUS(*status) : -1;
  }

  [[nodiscard]] std::string out() const { return read_text(out_); }
  [[nodiscard]] std::string err() const { return read_text(err_); }

  /// Waits until stderr contains `text`.
  bool wait_for_err(const std::string& text, Seconds limit) {
    const auto deadline = Clock::now() + limit;
    while (Clock::now() < deadline) {
      if (err().find(text) != std::string::npos) return true;
      if (!alive()) return err().find(text) != std::string::npos;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return false;
  }

 private:
  pid_t pid_ = -1;
  std::optional<int> status_;
  std::string out_, err_;
};

/// The result of a command run to completion.
struct ToolRun {
  int exit_code = -1;
  std::string out;
  std::string err;
};

/// Runs swivelctl with `args` and waits for it (killed after `limit`).
inline ToolRun swivelctl(const std::vector<std::string>& args, Seconds limit = Seconds(30)) {
  Child child(swivelctl_exe(), args);
  ToolRun run;
  run.exit_code = child.exit_code(limit);
  run.out = child.out();
  run.err = child.err();
  return run;
}

/// Splits text into its non-empty lines.
inline std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (!line.empty()) lines.push_back(line);
  }
  return lines;
}

}  // namespace swivel::test
