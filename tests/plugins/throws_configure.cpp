// SPDX-License-Identifier: Apache-2.0
// Requires a parameter and range-checks it, as real plugins do: ConfigError from configure.
#include "swivel/config/param_reader.hpp"
#include "test_localization.hpp"

namespace swivel::test_plugins {

class ThrowsInConfigure : public TestLocalization {
 public:
  void configure(const PluginContext& ctx) override {
    ParamReader params(ctx.params, ctx.config_file, ctx.params_path);
    params.number("gain", 0.0, 1.0);
    params.finish();
  }
};

}  // namespace swivel::test_plugins

SWIVEL_EXPORT_PLUGIN(swivel::test_plugins::ThrowsInConfigure, swivel::Localization,
                     "throws_configure")
