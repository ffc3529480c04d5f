// SPDX-License-Identifier: Apache-2.0
#pragma once
// Shared by the fuzz targets: what to do when a parser breaks its contract. Aborting makes
// libFuzzer save the input as a crash and makes the replay test fail.

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <typeinfo>

namespace swivel::fuzz {

[[noreturn]] inline void contract_broken(const char* target, const std::string& what) {
  std::fprintf(stderr, "%s: contract broken: %s\n", target, what.c_str());
  std::fflush(stderr);
  std::abort();
}

// An exception of a type the API does not document.
[[noreturn]] inline void unexpected_exception(const char* target, const std::exception& e) {
  contract_broken(target,
                  std::string("undocumented exception ") + typeid(e).name() + ": " + e.what());
}

}  // namespace swivel::fuzz
