// SPDX-License-Identifier: Apache-2.0
#pragma once
// The one list of what crosses the boundary between swiveld and a plugin: every type a
// plugin interface takes, returns or reaches through a member, and every virtual method of
// the interfaces. abi_fingerprint.hpp expands it into the fingerprint a plugin's descriptor
// carries. A type or virtual method added to a plugin interface belongs here too: the ABI
// tests fail until it is (the interface headers are read for declarations missing from the
// list, and each interface's vtable is measured against its listed methods).
//
// X(type) for each type, spelt as the plugin interface headers spell it in namespace swivel
// (X takes `...`: a template's arguments carry commas).
#define SWIVEL_ABI_TYPES(X)              \
  X(Status)                              \
  X(Pose2)                               \
  X(Twist2)                              \
  X(PoseEstimate)                        \
  X(MotionCaptureSample)                 \
  X(HardwareState)                       \
  X(ModuleDriveMode)                     \
  X(ActuatorCommand)                     \
  X(OdometryIncrement)                   \
  X(ModuleState)                         \
  X(DifferentialParams)                  \
  X(SwpcModuleParams)                    \
  X(GyroParams)                          \
  X(MotionCaptureParams)                 \
  X(SensorParams)                        \
  X(MotionLimits)                        \
  X(DrivetrainKind)                      \
  X(EffectParams)                        \
  X(RobotModel)                          \
  X(PluginContext)                       \
  X(CalibrationPhase)                    \
  X(CalibrationProgress)                 \
  X(SwpcModuleUncertainty)               \
  X(CalibrationReport)                   \
  X(Hardware)                            \
  X(Drivetrain)                          \
  X(Localization)                        \
  X(Calibration)                         \
  X(YAML::Node)                          \
  X(std::string)                         \
  X(std::optional<double>)               \
  X(std::vector<double>)                 \
  X(std::vector<SwpcModuleParams>)       \
  X(std::vector<SwpcModuleUncertainty>)  \
  X(std::map<std::string, EffectParams>) \
  X(std::span<ModuleState>)

// X(interface, method) for each virtual method, in declaration order (destructors aside).
#define SWIVEL_ABI_VIRTUALS(X) \
  X(Hardware, configure)       \
  X(Hardware, activate)        \
  X(Hardware, deactivate)      \
  X(Hardware, on_error)        \
  X(Hardware, read)            \
  X(Hardware, write)           \
  X(Hardware, ground_truth)    \
  X(Hardware, last_error)      \
  X(Drivetrain, configure)     \
  X(Drivetrain, module_count)  \
  X(Drivetrain, forward)       \
  X(Drivetrain, inverse)       \
  X(Drivetrain, module_states) \
  X(Drivetrain, last_error)    \
  X(Localization, configure)   \
  X(Localization, reset)       \
  X(Localization, hand_over)   \
  X(Localization, update)      \
  X(Localization, estimate)    \
  X(Localization, last_error)  \
  X(Calibration, configure)    \
  X(Calibration, step)         \
  X(Calibration, progress)     \
  X(Calibration, finished)     \
  X(Calibration, failed)       \
  X(Calibration, analyse)      \
  X(Calibration, last_error)

// X(interface) for each plugin interface.
#define SWIVEL_ABI_INTERFACES(X) X(Hardware) X(Drivetrain) X(Localization) X(Calibration)
