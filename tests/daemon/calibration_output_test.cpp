// SPDX-License-Identifier: Apache-2.0
// Where a calibrated model goes, with the service's sandbox reproduced: the configuration
// folder cannot be written (as under ProtectSystem=full) and systemd's StateDirectory= is
// passed as $STATE_DIRECTORY.

#include "calibration_output.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>

#include "swivel/robot_model_io.hpp"

namespace swivel::daemon {
namespace {

namespace fs = std::filesystem;

// Sets or clears STATE_DIRECTORY for one test and puts the old value back.
class ScopedStateDirectory {
 public:
  explicit ScopedStateDirectory(const std::string* value) {
    if (const char* old = std::getenv("STATE_DIRECTORY")) old_ = old;
    if (value != nullptr) {
      ::setenv("STATE_DIRECTORY", value->c_str(), 1);
    } else {
      ::unsetenv("STATE_DIRECTORY");
    }
  }
  ~ScopedStateDirectory() {
    if (old_) {
      ::setenv("STATE_DIRECTORY", old_->c_str(), 1);
    } else {
      ::unsetenv("STATE_DIRECTORY");
    }
  }
  ScopedStateDirectory(const ScopedStateDirectory&) = delete;
  ScopedStateDirectory& operator=(const ScopedStateDirectory&) = delete;

 private:
  std::optional<std::string> old_;
};

class CalibrationOutput : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() / ("swivel_calibration_output_" + std::to_string(getpid()));
    fs::remove_all(root_);
    fs::create_directories(root_ / "var/lib/swivel");
    fs::create_directories(root_ / "etc/swivel/robots");
    model_ = load_robot_model(std::string(SWIVEL_SOURCE_DIR) + "/config/robots/swpc4.yaml");
  }
  void TearDown() override { fs::remove_all(root_); }

  fs::path root_;
  RobotModel model_;
};

// Even root cannot create files under /proc: the stand-in for a read-only /etc.
constexpr const char* kReadOnlyModel = "/proc/swivel-test-read-only/robots/swpc4.yaml";

TEST_F(CalibrationOutput, ServiceWritesToItsStateDirectory) {
  const std::string state = (root_ / "var/lib/swivel").string();
  const ScopedStateDirectory env(&state);
  const std::time_t now = 1700000000;

  const SavedModel saved = save_calibrated_model(model_, kReadOnlyModel, now);

  ASSERT_FALSE(saved.path.empty()) << saved.error;
  EXPECT_EQ(fs::path(saved.path).parent_path(), fs::path(state));
  EXPECT_EQ(fs::path(saved.path).filename().string().rfind("swpc4.calibrated-", 0), 0U);
  const RobotModel back = load_robot_model(saved.path);
  EXPECT_EQ(back.modules.size(), model_.modules.size());
  EXPECT_EQ(back.source_file, saved.path);
}

TEST_F(CalibrationOutput, ByHandNextToTheNominalModel) {
  const ScopedStateDirectory env(nullptr);
  const std::string nominal = (root_ / "etc/swivel/robots/swpc4.yaml").string();

  const SavedModel saved = save_calibrated_model(model_, nominal, 1700000000);

  ASSERT_FALSE(saved.path.empty()) << saved.error;
  EXPECT_EQ(fs::path(saved.path).parent_path(), root_ / "etc/swivel/robots");
}

TEST_F(CalibrationOutput, FallsBackWhenTheStateDirectoryIsNotWritable) {
  const std::string state = "/proc/swivel-test-no-state";
  const ScopedStateDirectory env(&state);
  const std::string nominal = (root_ / "etc/swivel/robots/swpc4.yaml").string();

  const SavedModel saved = save_calibrated_model(model_, nominal, 1700000000);

  ASSERT_FALSE(saved.path.empty()) << saved.error;
  EXPECT_EQ(fs::path(saved.path).parent_path(), root_ / "etc/swivel/robots");
}

TEST_F(CalibrationOutput, NowhereWritableNamesEveryFolderTried) {
  const std::string state = "/proc/swivel-test-no-state";
  const ScopedStateDirectory env(&state);

  const SavedModel saved = save_calibrated_model(model_, kReadOnlyModel, 1700000000);

  EXPECT_TRUE(saved.path.empty());
  EXPECT_NE(saved.error.find("/proc/swivel-test-no-state/swpc4.calibrated-"), std::string::npos)
      << saved.error;
  EXPECT_NE(saved.error.find("/proc/swivel-test-read-only/robots/swpc4.calibrated-"),
            std::string::npos)
      << saved.error;
}

TEST(CalibrationOutputDirs, FirstEntryOfAListAndNoDuplicate) {
  const std::string list = "/var/lib/swivel:/var/lib/other";
  const ScopedStateDirectory env(&list);
  EXPECT_EQ(calibration_output_dirs("/etc/swivel/robots/swpc4.yaml"),
            (std::vector<std::string>{"/var/lib/swivel", "/etc/swivel/robots"}));
  EXPECT_EQ(calibration_output_dirs("/var/lib/swivel/swpc4.yaml"),
            (std::vector<std::string>{"/var/lib/swivel"}));
}

}  // namespace
}  // namespace swivel::daemon
