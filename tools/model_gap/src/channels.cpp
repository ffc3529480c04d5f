#include "swivel/model_gap/channels.hpp"

#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

namespace swivel::model_gap {

const char* question_name(Question q) {
  switch (q) {
    case Question::kSensorToPose:
      return "sensor_to_pose";
    case Question::kCommandToSensor:
      return "command_to_sensor";
    case Question::kCommandToPose:
      return "command_to_pose";
  }
  return "unknown";
}

std::size_t ChannelSet::find(const std::string& name) const {
  for (std::size_t c = 0; c < info.size(); ++c) {
    if (info[c].name == name) return c;
  }
  return info.size();
}

double residual_at(const ChannelInfo& info, double measured, double predicted) {
  if (!std::isfinite(measured) || !std::isfinite(predicted)) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  double r = measured - predicted;
  if (info.kind == ChannelKind::kHeading || info.kind == ChannelKind::kSteerAngle) {
    r = std::remainder(r, 2.0 * std::numbers::pi);
  }
  return r;
}

std::vector<std::vector<double>> residuals(const ChannelSet& measured,
                                           const ChannelSet& predicted) {
  if (measured.channel_count() != predicted.channel_count()) {
    throw std::invalid_argument("residuals: measured and predicted have different channels");
  }
  std::vector<std::vector<double>> out(measured.channel_count());
  for (std::size_t c = 0; c < measured.channel_count(); ++c) {
    const auto& m = measured.values[c];
    const auto& p = predicted.values[c];
    if (m.size() != p.size()) {
      throw std::invalid_argument("residuals: channel " + measured.info[c].name +
                                  " has different lengths");
    }
    out[c].resize(m.size());
    for (std::size_t k = 0; k < m.size(); ++k) out[c][k] = residual_at(measured.info[c], m[k], p[k]);
  }
  return out;
}

}  // namespace swivel::model_gap
