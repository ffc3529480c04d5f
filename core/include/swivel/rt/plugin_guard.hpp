// SPDX-License-Identifier: Apache-2.0
#pragma once
// The loop's boundary around every plugin call. Plugins must not throw on the loop; one that
// does anyway is stopped here and its exception becomes a Status::kError, so that the loop
// turns it into a fault with a controlled stop rather than std::terminate. What was thrown
// ("plugin threw std::runtime_error: <what>") is kept in one buffer of the guard, written
// without allocating; the text is valid until the next guarded call.
//
// Loop thread only. Real-time safe: no allocation, no lock; noexcept.

#include <array>
#include <exception>
#include <span>
#include <string_view>
#include <typeinfo>

#include "swivel/rt/exception_text.hpp"
#include "swivel/rt/rt_log.hpp"
#include "swivel/rt/state_snapshot.hpp"
#include "swivel/types.hpp"

namespace swivel::rt {

class PluginGuard {
 public:
  /// Runs `call` (returning Status). `thrown` is null, or what it threw when it threw (the
  /// result is then Status::kError).
  template <class Call>
  Status operator()(Call&& call, const char*& thrown) noexcept {
    thrown = nullptr;
    constexpr std::string_view kPrefix = "plugin threw ";
    copy_text(kPrefix.data(), text_);
    const std::span<char> rest = std::span(text_).subspan(kPrefix.size());
    try {
      return call();
    } catch (const std::exception& e) {
      describe_exception(&typeid(e), e.what(), rest);
    } catch (...) {
      describe_exception(current_exception_type(), nullptr, rest);
    }
    thrown = text_.data();
    return Status::kError;
  }

 private:
  std::array<char, sizeof(FaultDetail)> text_{};  // what a plugin last threw
};

}  // namespace swivel::rt
