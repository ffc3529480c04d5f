// SPDX-License-Identifier: Apache-2.0
#include "swivel/rt/exception_text.hpp"

#include <cxxabi.h>

#include <cctype>
#include <cstring>
#include <string_view>
#include <typeinfo>

namespace swivel::rt {
namespace {

// Appends to a terminated buffer, truncating; never writes past its end.
class TextOut {
 public:
  explicit TextOut(std::span<char> out) noexcept : out_(out) {
    if (!out_.empty()) out_[0] = '\0';
  }
  void append(std::string_view text) noexcept {
    for (const char c : text) {
      if (used_ + 1 >= out_.size()) break;
      out_[used_++] = c;
    }
    if (!out_.empty()) out_[used_] = '\0';
  }

 private:
  std::span<char> out_;
  std::size_t used_ = 0;
};

// The built-in types of the Itanium C++ ABI's mangling that are thrown in practice.
const char* builtin_name(char code) noexcept {
  switch (code) {
    case 'b': return "bool";
    case 'c': return "char";
    case 'i': return "int";
    case 'j': return "unsigned int";
    case 'l': return "long";
    case 'm': return "unsigned long";
    case 'd': return "double";
    case 'f': return "float";
    default: return nullptr;
  }
}

// "<length><identifier>" at `at`: the identifier, and `at` moved past it; empty if not one.
std::string_view source_name(std::string_view mangled, std::size_t& at) noexcept {
  std::size_t length = 0;
  std::size_t i = at;
  while (i < mangled.size() && std::isdigit(static_cast<unsigned char>(mangled[i])) != 0) {
    length = length * 10 + static_cast<std::size_t>(mangled[i] - '0');
    ++i;
  }
  if (i == at || length == 0 || i + length > mangled.size()) return {};
  at = i + length;
  return mangled.substr(i, length);
}

// Demangles <name> ::= <source-name> | St <source-name> | N [St] <source-name>+ E, and the
// built-ins with an optional "PK" (pointer to const); false for anything else.
bool demangle_simple(std::string_view mangled, TextOut& out) noexcept {
  std::string_view rest = mangled;
  const bool pointer_to_const = rest.starts_with("PK");
  if (pointer_to_const) rest.remove_prefix(2);
  if (rest.size() == 1 && builtin_name(rest[0]) != nullptr) {
    if (pointer_to_const) out.append("const ");
    out.append(builtin_name(rest[0]));
    if (pointer_to_const) out.append("*");
    return true;
  }
  if (pointer_to_const) return false;
  const bool nested = rest.starts_with('N');
  if (nested) rest.remove_prefix(1);
  std::size_t at = 0;
  bool first = true;
  if (rest.starts_with("St")) {
    out.append("std");
    first = false;
    at = 2;
  }
  while (at < rest.size() && !(nested && rest[at] == 'E')) {
    const std::string_view part = source_name(rest, at);
    if (part.empty()) return false;
    if (!first) out.append("::");
    out.append(part);
    first = false;
    if (!nested) break;
  }
  const std::size_t end = nested ? at + 1 : at;
  return !first && end == rest.size() && (!nested || rest[at] == 'E');
}

}  // namespace

void demangle_type_name(const char* mangled, std::span<char> out) noexcept {
  if (mangled == nullptr) mangled = "";
  TextOut text(out);
  if (!demangle_simple(mangled, text)) {
    TextOut again(out);
    again.append(mangled);
  }
}

const char* describe_exception(const std::type_info* type, const char* what,
                               std::span<char> out) noexcept {
  demangle_type_name(type != nullptr ? type->name() : "unknown type", out);
  const std::size_t type_length = out.empty() ? 0 : std::strlen(out.data());
  TextOut rest(out.subspan(type_length));
  if (what != nullptr) {
    rest.append(": ");
    rest.append(what);
  } else {
    rest.append(" (not a std::exception)");
  }
  return out.data();
}

const std::type_info* current_exception_type() noexcept {
  return abi::__cxa_current_exception_type();
}

}  // namespace swivel::rt
