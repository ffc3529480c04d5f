// SPDX-License-Identifier: Apache-2.0
#pragma once
// What an exception was, as text, without allocating: the real-time loop stops a plugin that
// throws at its boundary and keeps the exception's type and message in the fault.

#include <cstddef>
#include <span>
#include <typeinfo>

namespace swivel::rt {

/// Writes "<type>: <what>" (a std::exception: pass its what()), or "<type> (not a
/// std::exception)" when `what` is null, into `out` (truncated, always terminated) and
/// returns out.data(). The type is demangled where it is a plain name (std::runtime_error,
/// swivel::ConfigError, int, const char*), else kept mangled. Real-time safe: no
/// allocation, no lock, no exception. Typical use:
///   catch (const std::exception& e) { describe_exception(&typeid(e), e.what(), text); }
///   catch (...) { describe_exception(current_exception_type(), nullptr, text); }
const char* describe_exception(const std::type_info* type, const char* what,
                               std::span<char> out) noexcept;

/// Inside a catch block: the type of the exception being handled (null outside one).
const std::type_info* current_exception_type() noexcept;

/// The readable spelling of mangled type name `mangled` (std::type_info::name()) where it is
/// a plain, namespaced or built-in name, else `mangled` itself, into `out`. Real-time safe.
void demangle_type_name(const char* mangled, std::span<char> out) noexcept;

}  // namespace swivel::rt
