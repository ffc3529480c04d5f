#include "swivel/rt/state_snapshot.hpp"

namespace swivel {

const char* fault_code_name(FaultCode code) noexcept {
  switch (code) {
    case FaultCode::kNone: return "none";
    case FaultCode::kCommandTimeout: return "command_timeout";
    case FaultCode::kNonFiniteCommand: return "non_finite_command";
    case FaultCode::kNonFiniteSensor: return "non_finite_sensor";
    case FaultCode::kHardwareError: return "hardware_error";
    case FaultCode::kDrivetrainError: return "drivetrain_error";
    case FaultCode::kLocalizationError: return "localization_error";
    case FaultCode::kCalibrationError: return "calibration_error";
    case FaultCode::kOdometryInconsistent: return "odometry_inconsistent";
  }
  return "unknown";
}

}  // namespace swivel
