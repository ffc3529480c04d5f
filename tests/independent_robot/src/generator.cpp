// SPDX-License-Identifier: Apache-2.0
#include "swivel/independent/generator.hpp"

#include "swivel/independent/run_files.hpp"
#include "swivel/independent/simulation.hpp"

namespace swivel::independent {

GeneratedRun generate(const RunSpec& spec) {
  const RunRecord record = simulate(spec);
  return GeneratedRun{run_log_csv(spec, record), nominal_model_yaml(spec)};
}

}  // namespace swivel::independent
