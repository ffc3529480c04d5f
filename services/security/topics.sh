# SPDX-License-Identifier: Apache-2.0
# shellcheck shell=bash
# Sourced by make_permissions.sh: which DDS topics are "state" (the daemon's output) and
# which are inputs (commands, and the sensor topics of ROS 2 drivers), as named in
# core/include/swivel/dds/topics.hpp and core/dds/src/options.cpp (the ROS 2 topics, with or
# without a namespace; tf and diagnostics are absolute). Space-separated topic-name patterns
# (* and ? match any characters, "/" included); set SWIVEL_STATE_TOPICS, SWIVEL_COMMAND_TOPICS
# or SWIVEL_SENSOR_TOPICS to override, or add patterns with SWIVEL_EXTRA_INPUT_TOPICS (e.g. a
# motion-capture topic that does not end in /pose).
: "${SWIVEL_STATE_TOPICS:=swivel_robot_state swivel_module_states swivel_diagnostics swivel_calibration_result swivel_reply swivel_run_samples rt/odom rt/*/odom rt/tf rt/diagnostics rt/joint_states rt/*/joint_states ros_discovery_info}"
: "${SWIVEL_COMMAND_TOPICS:=swivel_velocity_command swivel_motion_capture swivel_command swivel_set_pose rt/cmd_vel rt/*/cmd_vel rt/initialpose rt/*/initialpose}"
# dds.ros2.imu (default "imu"; "imu/data" for an REP 145 driver) and dds.ros2.mocap_pose
# (drivers name it <driver>/<rigid body>/pose: vrpn_mocap, mocap4r2, OptiTrack bridges).
: "${SWIVEL_SENSOR_TOPICS:=rt/imu rt/*/imu rt/imu/* rt/*/imu/* rt/*/pose}"
# What the daemon subscribes to and a client (or a sensor driver's identity) publishes.
# shellcheck disable=SC2034  # read by make_permissions.sh, which sources this file
SWIVEL_INPUT_TOPICS="$SWIVEL_COMMAND_TOPICS $SWIVEL_SENSOR_TOPICS ${SWIVEL_EXTRA_INPUT_TOPICS:-}"
