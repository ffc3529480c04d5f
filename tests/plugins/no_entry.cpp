// SPDX-License-Identifier: Apache-2.0
// A shared library without the plugin entry point.
extern "C" __attribute__((visibility("default"))) int swivel_not_a_plugin(void) { return 1; }
