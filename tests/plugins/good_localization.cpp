// SPDX-License-Identifier: Apache-2.0
// Well-behaved: reads one optional parameter and rejects unknown ones.
#include "swivel/config/param_reader.hpp"
#include "test_localization.hpp"

namespace swivel::test_plugins {

class GoodLocalization : public TestLocalization {
 public:
  void configure(const PluginContext& ctx) override {
    ParamReader params(ctx.params, ctx.config_file, ctx.params_path);
    estimate_.pose.x_m = params.number_or("start_x_m", 0.0, -100.0, 100.0);
    params.finish();
  }
};

}  // namespace swivel::test_plugins

SWIVEL_EXPORT_PLUGIN(swivel::test_plugins::GoodLocalization, swivel::Localization, "good")
