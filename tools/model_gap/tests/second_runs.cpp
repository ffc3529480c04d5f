// SPDX-License-Identifier: Apache-2.0
#include "second_runs.hpp"

#include <sstream>
#include <stdexcept>
#include <utility>

#include "swivel/model_gap/run_log_adapter.hpp"
#include "swivel/robot_model_io.hpp"
#include "swivel/run_log.hpp"

namespace swivel::model_gap {

SecondRun load_second_run(const second::RunSpec& spec, const std::string& name) {
  const second::GeneratedRun generated = second::generate(spec);
  std::istringstream in(generated.run_csv);
  return {parse_robot_model(generated.nominal_model_yaml, name + ".yaml"),
          to_run_data(parse_run_log(in, name + ".csv"))};
}

HiddenEffectRun hidden_effect_run(const second::SeedRanges& seeds, std::size_t index,
                                  const std::string& effect) {
  // Case `index` with one hidden effect: the last of the first index + 1 such cases.
  second::ValidationCase c = second::validation_set(seeds, 0, index + 1, 0).back();
  if (c.expected.size() != 1 || c.expected[0].effect != effect || c.expected[0].params.empty()) {
    throw std::logic_error(c.id + " does not hide " + effect + " alone");
  }
  const double truth = c.expected[0].params[0].second;
  SecondRun run = load_second_run(c.spec, c.id);
  return {std::move(c), std::move(run), truth};
}

}  // namespace swivel::model_gap
