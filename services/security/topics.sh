# SPDX-License-Identifier: Apache-2.0
# shellcheck shell=bash
# Sourced by make_permissions.sh: which DDS topics are "state" (the daemon's output) and
# which are "commands" (its input), as named in core/include/swivel/dds/topics.hpp and
# core/include/swivel/dds/options.hpp (the ROS 2 topics, with or without a namespace; tf and
# diagnostics are absolute). Space-separated topic-name patterns (* and ? match any characters, "/"
# included); set SWIVEL_STATE_TOPICS or SWIVEL_COMMAND_TOPICS to override.
: "${SWIVEL_STATE_TOPICS:=swivel_robot_state swivel_module_states swivel_diagnostics swivel_calibration_result swivel_reply swivel_run_samples rt/odom rt/*/odom rt/tf rt/diagnostics rt/joint_states rt/*/joint_states}"
: "${SWIVEL_COMMAND_TOPICS:=swivel_velocity_command swivel_motion_capture swivel_command swivel_set_pose rt/cmd_vel rt/*/cmd_vel rt/initialpose rt/*/initialpose}"
