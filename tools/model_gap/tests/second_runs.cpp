// SPDX-License-Identifier: Apache-2.0
#include "second_runs.hpp"

#include <sstream>

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

}  // namespace swivel::model_gap
