// SPDX-License-Identifier: Apache-2.0
// Fails in update after `fail_after_cycles` good cycles (params), like a diverging filter.
#include "swivel/config/param_reader.hpp"
#include "test_localization.hpp"

namespace swivel::test_plugins {

class UpdateError : public TestLocalization {
 public:
  void configure(const PluginContext& ctx) override {
    ParamReader params(ctx.params, ctx.config_file, ctx.params_path);
    fail_after_cycles_ = params.integer_or("fail_after_cycles", 0, 0, 1000000000);
    params.finish();
  }
  Status update(const OdometryIncrement& odometry,
                const HardwareState& readings) noexcept override {
    if (cycles_++ >= fail_after_cycles_) return Status::kError;
    return TestLocalization::update(odometry, readings);
  }
  [[nodiscard]] const char* last_error() const noexcept override {
    return "estimate diverged (planted failure)";
  }

 private:
  int fail_after_cycles_ = 0;
  int cycles_ = 0;
};

}  // namespace swivel::test_plugins

SWIVEL_EXPORT_PLUGIN(swivel::test_plugins::UpdateError, swivel::Localization, "update_error")
