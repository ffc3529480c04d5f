// SPDX-License-Identifier: Apache-2.0
// The file says "misnamed", the descriptor says "other".
#include "test_localization.hpp"

SWIVEL_EXPORT_PLUGIN(swivel::test_plugins::TestLocalization, swivel::Localization, "other")
