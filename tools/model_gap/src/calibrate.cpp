// SPDX-License-Identifier: Apache-2.0
// Calibration (question_stages.hpp): with nothing named, the parameters of the robot's own
// model that the run fixes better than their nominal values. Naming asks for a missing effect
// that matters in every window; a calibrated track width or wheel radius may change a window
// by a fraction of the noise and still move the whole run's path by centimetres.
#include <sstream>

#include "question_stages.hpp"
#include "swivel/model_gap/fold_effects.hpp"

namespace swivel::model_gap::detail {

const Fitted* choose_calibration(const VerdictInputs& in, const QuestionOptions& options) {
  // Significance and resolution as for naming, at the calibration's level; no size gate.
  QuestionOptions gate = options;
  gate.min_z_name = options.min_z_calibrate;
  gate.min_effect_size = 0.0;
  for (std::size_t k : singles_by_bic(*in.singles, in.full, in.nominal_bic)) {
    const Fitted& f = (*in.singles)[k];
    if (f.effects.size() == 1 && folds_into_robot_model(f.effects[0]->name, in.base->drivetrain) &&
        significant(f, gate))
      return &f;
  }
  return nullptr;
}

void calibrate_own_parameters(const VerdictInputs& in, const QuestionOptions& options,
                              QuestionResult& result) {
  if (!options.calibrate || result.verdict != Verdict::kNoSignificantGap) return;
  const Fitted* f = choose_calibration(in, options);
  if (f == nullptr) return;
  const CandidateScore s = score_of(*f);
  result.calibrated.push_back(fitted_effect(*f, s, 0, 0));
  result.augmented = model_with(*in.base, f->effects, f->fit.values);
  std::ostringstream line;
  line.precision(3);
  line << " Calibrated " << s.label() << ": significant at " << f->z[0]
       << " sigma, a parameter of the robot's own model; its change per window (" << f->size[0]
       << " noise sigmas) names no missing effect, but adds up over the run.";
  result.summary += line.str();
}

}  // namespace swivel::model_gap::detail
