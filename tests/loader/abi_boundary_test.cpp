// SPDX-License-Identifier: Apache-2.0
// The fingerprint covers the whole boundary: every type the plugin interface headers declare
// (and the headers they include) is in the list of abi_boundary.hpp, and every virtual
// method of each interface is listed, as the compiler lays out its vtable. A type or a
// virtual method added to an interface without the list fails here.

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "swivel/plugin/abi_fingerprint.hpp"
#include "swivel/plugin/calibration.hpp"
#include "swivel/plugin/drivetrain.hpp"
#include "swivel/plugin/hardware.hpp"
#include "swivel/plugin/localization.hpp"

namespace swivel {
namespace {

const std::filesystem::path include_dir = SWIVEL_INCLUDE_DIR;

// The fingerprint machinery itself: the descriptor's C structs are guarded by the ABI version.
const std::set<std::string> machinery = {"swivel/plugin/abi.hpp", "swivel/plugin/abi_boundary.hpp",
                                         "swivel/plugin/abi_fingerprint.hpp"};

std::string read_text(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw std::runtime_error("cannot read " + file.string());
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// The project headers the plugin interface headers reach through #include "swivel/...".
std::vector<std::string> boundary_headers() {
  std::vector<std::string> pending;
  for (const auto& entry : std::filesystem::directory_iterator(include_dir / "swivel/plugin")) {
    pending.push_back("swivel/plugin/" + entry.path().filename().string());
  }
  std::set<std::string> seen;
  const std::regex include(R"re(#include\s+"(swivel/[^"]+)")re");
  while (!pending.empty()) {
    const std::string header = pending.back();
    pending.pop_back();
    if (machinery.contains(header) || !seen.insert(header).second) continue;
    const std::string text = read_text(include_dir / header);
    for (std::sregex_iterator m(text.begin(), text.end(), include), end; m != end; ++m) {
      pending.push_back((*m)[1]);
    }
  }
  return {seen.begin(), seen.end()};
}

struct Declarations {
  std::vector<std::string> types;    // struct, class, enum and alias names
  std::vector<std::string> methods;  // "Class::method" of each virtual method
};

// What a header declares: type definitions and aliases, and the virtual methods of each
// class (a destructor aside).
Declarations declarations_in(const std::string& text) {
  Declarations found;
  const std::regex type(R"re((?:^|\n)\s*(?:struct|class|enum class|enum)\s+(\w+)[^;{()]*\{)re");
  const std::regex alias(R"re((?:^|\n)\s*using\s+(\w+)\s*=)re");
  for (const std::regex* pattern : {&type, &alias}) {
    for (std::sregex_iterator m(text.begin(), text.end(), *pattern), end; m != end; ++m) {
      found.types.push_back((*m)[1]);
    }
  }
  const std::regex class_head(R"re((?:^|\n)\s*class\s+(\w+)[^;{()]*\{)re");
  const std::regex virtual_method(R"re(\bvirtual\s+[^;{(~]*?\b(\w+)\s*\()re");
  for (std::sregex_iterator m(text.begin(), text.end(), virtual_method), end; m != end; ++m) {
    std::string owner = "?";
    const std::string before = text.substr(0, static_cast<std::size_t>(m->position(0)));
    for (std::sregex_iterator c(before.begin(), before.end(), class_head); c != end; ++c) {
      owner = (*c)[1];
    }
    found.methods.push_back(owner + "::" + (*m)[1].str());
  }
  return found;
}

std::set<std::string> listed_types() {
  const SwivelAbiFingerprint& f = *abi_fingerprint();
  std::set<std::string> names;
  for (std::uint32_t i = 0; i < f.layout_count; ++i) names.insert(f.layouts[i].type);
  return names;
}

std::set<std::string> listed_methods() {
  const SwivelAbiFingerprint& f = *abi_fingerprint();
  std::set<std::string> names;
  for (std::uint32_t i = 0; i < f.virtual_count; ++i) names.insert(f.virtuals[i].method);
  return names;
}

TEST(AbiBoundary, ReadsTheInterfaceHeadersAndWhatTheyInclude) {
  const std::vector<std::string> headers = boundary_headers();
  for (const char* expected :
       {"swivel/plugin/calibration.hpp", "swivel/plugin/hardware.hpp", "swivel/types.hpp",
        "swivel/robot_model.hpp", "swivel/plugin/plugin_context.hpp"}) {
    EXPECT_NE(std::find(headers.begin(), headers.end(), expected), headers.end()) << expected;
  }
}

TEST(AbiBoundary, EveryTypeTheInterfaceHeadersDeclareIsListed) {
  const std::set<std::string> listed = listed_types();
  for (const std::string& header : boundary_headers()) {
    for (const std::string& type : declarations_in(read_text(include_dir / header)).types) {
      EXPECT_TRUE(listed.contains(type))
          << header << " declares " << type
          << ", which crosses the plugin boundary but is missing from SWIVEL_ABI_TYPES "
             "(swivel/plugin/abi_boundary.hpp)";
    }
  }
}

TEST(AbiBoundary, EveryVirtualMethodTheInterfaceHeadersDeclareIsListed) {
  const std::set<std::string> listed = listed_methods();
  std::size_t seen = 0;
  for (const std::string& header : boundary_headers()) {
    for (const std::string& method : declarations_in(read_text(include_dir / header)).methods) {
      ++seen;
      EXPECT_TRUE(listed.contains(method))
          << header << " declares virtual " << method
          << ", missing from SWIVEL_ABI_VIRTUALS (swivel/plugin/abi_boundary.hpp)";
    }
  }
  EXPECT_EQ(seen, listed.size()) << "the list names methods the headers do not declare";
}

// The reader of the headers must see what a new declaration looks like.
TEST(AbiBoundary, TheHeaderReaderFindsANewStructAliasAndVirtualMethod) {
  const Declarations found = declarations_in(
      "namespace swivel {\n"
      "struct CalibrationStepInfo {\n  double t = 0.0;\n};\n"
      "using StepCount = std::uint32_t;\n"
      "class Hardware {\n public:\n  virtual ~Hardware() = default;\n"
      "  [[nodiscard]] virtual std::uint32_t temperature_count() const noexcept = 0;\n"
      "  virtual Status read(double stamp_s, HardwareState& out) = 0;\n};\n"
      "struct Forward;\n}\n");
  EXPECT_EQ(found.types,
            (std::vector<std::string>{"CalibrationStepInfo", "Hardware", "StepCount"}));
  EXPECT_EQ(found.methods,
            (std::vector<std::string>{"Hardware::temperature_count", "Hardware::read"}));
  EXPECT_FALSE(listed_types().contains("CalibrationStepInfo"));
}

// The compiler's vtable of each interface holds its two destructor slots (Itanium C++ ABI)
// and exactly the listed methods, each in a slot of its own.
template <class Interface>
void expect_vtable_is_listed(const std::string& name) {
  const SwivelAbiFingerprint& f = *abi_fingerprint();
  std::set<std::uint32_t> slots;
  for (std::uint32_t i = 0; i < f.virtual_count; ++i) {
    if (std::string(f.virtuals[i].method).rfind(name + "::", 0) == 0) {
      EXPECT_TRUE(slots.insert(f.virtuals[i].slot).second) << f.virtuals[i].method;
    }
  }
  const std::uint32_t total = abi_detail::vtable_slots<Interface>();
  EXPECT_EQ(total, slots.size() + 2)
      << name << " has " << total << " vtable slots (two for its destructor); the list names "
      << slots.size() << " virtual methods: add the missing ones to SWIVEL_ABI_VIRTUALS";
  for (const std::uint32_t slot : slots) EXPECT_LT(slot, total) << name;
}

TEST(AbiBoundary, EachInterfaceVtableHoldsExactlyTheListedMethods) {
  expect_vtable_is_listed<Hardware>("Hardware");
  expect_vtable_is_listed<Drivetrain>("Drivetrain");
  expect_vtable_is_listed<Localization>("Localization");
  expect_vtable_is_listed<Calibration>("Calibration");
}

// The slot read from a member pointer is the compiler's: a class whose virtual methods are
// known.
struct ThreeVirtuals {
  virtual ~ThreeVirtuals() = default;
  virtual void first() {}
  virtual int second() { return 2; }
  virtual void third(double) {}
};

TEST(AbiBoundary, VtableSlotsAreTheCompilers) {
  EXPECT_EQ(abi_detail::vtable_slot(&ThreeVirtuals::first), 2U);
  EXPECT_EQ(abi_detail::vtable_slot(&ThreeVirtuals::second), 3U);
  EXPECT_EQ(abi_detail::vtable_slot(&ThreeVirtuals::third), 4U);
  EXPECT_EQ(abi_detail::vtable_slots<ThreeVirtuals>(), 5U);
}

TEST(AbiBoundary, TheCalibrationTypesAreFingerprinted) {
  const SwivelAbiFingerprint& f = *abi_fingerprint();
  auto size_of = [&](const std::string& type) -> std::uint32_t {
    for (std::uint32_t i = 0; i < f.layout_count; ++i) {
      if (type == f.layouts[i].type) return f.layouts[i].size;
    }
    return 0;
  };
  EXPECT_EQ(size_of("CalibrationProgress"), sizeof(CalibrationProgress));
  EXPECT_EQ(size_of("SwpcModuleUncertainty"), sizeof(SwpcModuleUncertainty));
  EXPECT_EQ(size_of("CalibrationReport"), sizeof(CalibrationReport));
  EXPECT_EQ(size_of("std::vector<SwpcModuleUncertainty>"),
            sizeof(std::vector<SwpcModuleUncertainty>));
}

}  // namespace
}  // namespace swivel
