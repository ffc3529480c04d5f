// SPDX-License-Identifier: Apache-2.0
#pragma once
// Conversion from the project's run-log reader to the workflow's column form.

#include "swivel/model_gap/run_data.hpp"
#include "swivel/run_log.hpp"

namespace swivel::model_gap {

/// Columns of `log`; motion-capture headings are unwrapped, rows without a sample get NaN.
RunData to_run_data(const RunLog& log);

}  // namespace swivel::model_gap
