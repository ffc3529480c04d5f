// SPDX-License-Identifier: Apache-2.0
#pragma once
// The calibrate verb and the calibration runner's periodic work, as the daemon offers them:
// with a `calibration:` section a CalibrationRunner answers start | cancel | status and
// publishes its progress; without one every calibrate request is refused with the reason.
// Status changes are logged once each.
//
// Main thread (requests, poll()); the runner serialises its own calls. Not real-time safe.

#include <functional>
#include <memory>
#include <string>

#include "swivel/daemon/daemon_config.hpp"
#include "swivel/dds/bridge.hpp"
#include "swivel/plugin_loader.hpp"

namespace swivel::rt {
class ControlLoop;
}

namespace swivel::daemon {

class CalibrationRunner;

class CalibrationService {
 public:
  using Publish = std::function<void(const dds::CalibrationSample&)>;

  /// Creates the runner when `config` has a calibration section. `publish` sends a
  /// CalibrationResult sample and must not throw; it is called with the runner's mutex held.
  CalibrationService(const DaemonConfig& config, rt::ControlLoop& loop, PluginLoader& loader,
                     Publish publish);
  ~CalibrationService();
  CalibrationService(const CalibrationService&) = delete;
  CalibrationService& operator=(const CalibrationService&) = delete;

  /// The calibrate verb: `argument` start | cancel | status ("" is status). Publishes the
  /// calibration's status as well.
  dds::ReplySample handle(const std::string& argument);

  /// The runner's periodic work (progress, hand-back, analysis, writing the model).
  void poll() noexcept;

  /// True while a calibration runs or its recording is analysed.
  [[nodiscard]] bool busy() const;

 private:
  [[nodiscard]] std::string refusal() const;

  const DaemonConfig& config_;
  Publish publish_;
  std::string logged_status_;                  // last status logged (under the runner's mutex)
  std::unique_ptr<CalibrationRunner> runner_;  // null without `calibration:`
};

}  // namespace swivel::daemon
