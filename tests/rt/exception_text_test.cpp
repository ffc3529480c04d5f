// SPDX-License-Identifier: Apache-2.0
// What the loop keeps of an exception a plugin threw: its type, readable, and its message,
// without a heap operation.

#include "swivel/rt/exception_text.hpp"

#include <gtest/gtest.h>

#include <array>
#include <stdexcept>
#include <string>

#include "alloc_guard.hpp"

namespace swivel::drives {
class EnableError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};
}  // namespace swivel::drives

namespace swivel::rt {
namespace {

struct BusFault {};  // not a std::exception

template <class Throw>
std::string described(Throw&& throw_it, std::size_t capacity = 256) {
  std::array<char, 256> text{};
  try {
    throw_it();
  } catch (const std::exception& e) {
    return describe_exception(&typeid(e), e.what(), std::span(text).first(capacity));
  } catch (...) {
    return describe_exception(current_exception_type(), nullptr, std::span(text).first(capacity));
  }
  return "nothing thrown";
}

TEST(ExceptionText, AStdExceptionKeepsItsTypeAndMessage) {
  EXPECT_EQ(described([] { throw std::runtime_error("bus gone"); }),
            "std::runtime_error: bus gone");
  EXPECT_EQ(described([] { throw std::out_of_range("module 7"); }), "std::out_of_range: module 7");
}

TEST(ExceptionText, ADerivedExceptionIsNamedByItsDynamicType) {
  EXPECT_EQ(described([] { throw drives::EnableError("drive 2 refused"); }),
            "swivel::drives::EnableError: drive 2 refused");
}

TEST(ExceptionText, AnythingElseKeepsItsType) {
  EXPECT_EQ(described([] { throw 42; }), "int (not a std::exception)");
  EXPECT_EQ(described([] { throw "no drive"; }), "const char* (not a std::exception)");
  const std::string custom = described([] { throw BusFault{}; });
  EXPECT_NE(custom.find("BusFault (not a std::exception)"), std::string::npos) << custom;
}

TEST(ExceptionText, IsTruncatedToTheBuffer) {
  EXPECT_EQ(described([] { throw std::runtime_error("bus gone"); }, 12), "std::runtim");
  EXPECT_EQ(described([] { throw std::runtime_error("bus gone"); }, 1), "");
}

TEST(ExceptionText, PlainNamesAreDemangledAndOthersKept) {
  std::array<char, 64> out{};
  demangle_type_name("N6swivel11ConfigErrorE", out);
  EXPECT_STREQ(out.data(), "swivel::ConfigError");
  demangle_type_name("St12length_error", out);
  EXPECT_STREQ(out.data(), "std::length_error");
  demangle_type_name("8BusFault", out);
  EXPECT_STREQ(out.data(), "BusFault");
  demangle_type_name("St6vectorIiSaIiEE", out);  // a template: kept as it is
  EXPECT_STREQ(out.data(), "St6vectorIiSaIiEE");
  demangle_type_name("N6swivel5", out);  // malformed: kept
  EXPECT_STREQ(out.data(), "N6swivel5");
}

TEST(ExceptionText, DescribingAllocatesNothing) {
  std::array<char, 256> text{};
  const std::runtime_error error("bus gone");
  test::HeapCounts counts;
  {
    const test::AllocCounter counter;
    describe_exception(&typeid(error), error.what(), text);
    describe_exception(&typeid(int), nullptr, text);
    counts = counter.counts();
  }
  EXPECT_EQ(counts.allocations, 0U);
  EXPECT_STREQ(text.data(), "int (not a std::exception)");
}

}  // namespace
}  // namespace swivel::rt
