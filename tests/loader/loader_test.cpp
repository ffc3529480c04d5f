// SPDX-License-Identifier: Apache-2.0
#include <dlfcn.h>
#include <gtest/gtest.h>
#include <stdlib.h>

#include <string>

#include "swivel/config/config_error.hpp"
#include "swivel/plugin/drivetrain.hpp"
#include "swivel/plugin/hardware.hpp"
#include "swivel/plugin/localization.hpp"
#include "swivel/plugin_loader.hpp"

namespace swivel {
namespace {

const std::string test_plugin_dir = SWIVEL_TEST_PLUGIN_DIR;

std::string file_of(const std::string& name) {
  return test_plugin_dir + "/swivel_localization_" + name + ".so";
}

// The PluginError message of creating localization plugin `name` from the test folder.
std::string error_of(const std::string& name) {
  PluginLoader loader({test_plugin_dir});
  try {
    loader.create<Localization>(name);
  } catch (const PluginError& e) {
    return e.what();
  }
  ADD_FAILURE() << "loading '" << name << "' did not fail";
  return {};
}

bool is_loaded(const std::string& file) {
  void* handle = dlopen(file.c_str(), RTLD_NOW | RTLD_NOLOAD);
  if (handle == nullptr) return false;
  dlclose(handle);
  return true;
}

TEST(PluginLoader, CreatesWellBehavedPluginThatWorks) {
  PluginLoader loader({"/nonexistent/first", test_plugin_dir});
  auto loc = loader.create<Localization>("good");
  ASSERT_TRUE(loc);
  EXPECT_EQ(loc.name(), "good");
  EXPECT_EQ(loc.path(), file_of("good"));

  YAML::Node params = YAML::Load("{start_x_m: 1.5}");
  PluginContext ctx{params, "swiveld.yaml", "localization.params", ".", nullptr, 0.001};
  loc->configure(ctx);
  OdometryIncrement step;
  step.valid = true;
  step.delta.x_m = 0.25;
  EXPECT_EQ(loc->update(step, HardwareState{}), Status::kOk);
  EXPECT_DOUBLE_EQ(loc->estimate().pose.x_m, 1.75);
}

TEST(PluginLoader, SharesLibraryBetweenInstancesAndUnloadsAfterLast) {
  PluginLoader loader({test_plugin_dir});
  auto first = loader.create<Localization>("good");
  auto second = loader.create<Localization>("good");
  EXPECT_NE(first.get(), second.get());
  EXPECT_TRUE(is_loaded(file_of("good")));

  first.reset();
  EXPECT_TRUE(is_loaded(file_of("good"))) << "unloaded while an instance lives";
  second.reset();
  EXPECT_FALSE(is_loaded(file_of("good")));
}

TEST(PluginLoader, MovedInstanceKeepsLibraryLoaded) {
  PluginLoader loader({test_plugin_dir});
  PluginInstance<Localization> kept;
  {
    auto created = loader.create<Localization>("good");
    kept = std::move(created);
  }
  ASSERT_TRUE(kept);
  EXPECT_TRUE(is_loaded(file_of("good")));
  EXPECT_EQ(kept->estimate().pose.x_m, 0.0);
}

TEST(PluginLoader, NotFoundListsEveryDirectorySearched) {
  PluginLoader loader({"/nonexistent/a", test_plugin_dir});
  try {
    loader.create<Localization>("raw_egg");
    FAIL() << "no error";
  } catch (const PluginError& e) {
    EXPECT_EQ(std::string(e.what()),
              "localization plugin 'raw_egg' not found: no swivel_localization_raw_egg.so in "
              "/nonexistent/a, " +
                  test_plugin_dir + " (set SWIVEL_PLUGIN_PATH or plugin_path to add directories)");
  }
}

TEST(PluginLoader, RefusesWrongAbiVersion) {
  EXPECT_EQ(error_of("bad_abi"), file_of("bad_abi") +
                                     ": ABI version 999, expected 4 (built for a newer Swivel: "
                                     "rebuild the plugin against this one's headers)");
}

// ABI 2 added the hardware lifecycle hooks; a hardware plugin built before them would be
// called through a vtable without them.
TEST(PluginLoader, RefusesHardwarePluginOfTheAbiBeforeTheLifecycleHooks) {
  PluginLoader loader({test_plugin_dir});
  try {
    (void)loader.create<Hardware>("old_abi");
    FAIL() << "no error";
  } catch (const PluginError& e) {
    EXPECT_EQ(std::string(e.what()),
              test_plugin_dir +
                  "/swivel_hardware_old_abi.so: ABI version 1, expected 4 (built for an "
                  "older Swivel: rebuild the plugin against this one's headers)");
  }
}

// The right version number but a type that crossed the boundary has another layout: the
// plugin would read and write past the host's structures.
TEST(PluginLoader, RefusesAPluginBuiltWithAnotherLayoutAndNamesTheType) {
  EXPECT_EQ(error_of("layout_mismatch"),
            file_of("layout_mismatch") +
                ": built with another layout of the plugin ABI: layout of HardwareState "
                "differs: " +
                std::to_string(sizeof(HardwareState) + 8) + " bytes, alignment " +
                std::to_string(alignof(HardwareState)) + " in the plugin; " +
                std::to_string(sizeof(HardwareState)) + " bytes, alignment " +
                std::to_string(alignof(HardwareState)) +
                " here (rebuild the plugin against this Swivel's headers, with the same "
                "compiler)");
  EXPECT_FALSE(is_loaded(file_of("layout_mismatch")));
}

// Same layouts, but a virtual method in another vtable slot: the host would call update()
// through the slot of something else.
TEST(PluginLoader, RefusesAPluginWhoseVtableDiffersAndNamesTheMethod) {
  const std::string message = error_of("vtable_mismatch");
  EXPECT_NE(message.find(file_of("vtable_mismatch") +
                         ": built with another layout of the plugin ABI: virtual method "
                         "Localization::update differs: slot "),
            std::string::npos)
      << message;
  EXPECT_FALSE(is_loaded(file_of("vtable_mismatch")));
}

TEST(PluginLoader, RefusesAPluginOfAnotherCxxAbi) {
  const std::string message = error_of("cxx_abi_mismatch");
  EXPECT_NE(message.find(file_of("cxx_abi_mismatch") + ": built with another layout"),
            std::string::npos)
      << message;
  EXPECT_NE(message.find("C++ ABI " + std::to_string(__GXX_ABI_VERSION + 1) + " in the plugin, " +
                         std::to_string(__GXX_ABI_VERSION) + " here"),
            std::string::npos)
      << message;
}

TEST(PluginLoader, RefusesWrongKind) {
  EXPECT_EQ(error_of("wrong_kind"),
            file_of("wrong_kind") + ": kind 'drivetrain', expected 'localization'");
}

TEST(PluginLoader, RefusesLibraryWithoutEntryPoint) {
  EXPECT_EQ(error_of("no_entry"),
            file_of("no_entry") +
                ": missing entry point 'swivel_plugin_descriptor' (is SWIVEL_EXPORT_PLUGIN used?)");
}

TEST(PluginLoader, RefusesNameMismatch) {
  EXPECT_EQ(error_of("misnamed"), file_of("misnamed") +
                                      ": name mismatch: the library declares 'other', expected "
                                      "'misnamed'");
}

TEST(PluginLoader, ReportsExceptionThrownByConstructor) {
  EXPECT_EQ(error_of("throws_create"),
            file_of("throws_create") + ": create failed: cannot open /dev/imaginary_imu");
}

TEST(PluginLoader, RefusesKindMismatchWhenLoadingFileDirectly) {
  PluginLoader loader({});
  try {
    loader.create_from_file<Drivetrain>(file_of("good"));
    FAIL() << "no error";
  } catch (const PluginError& e) {
    EXPECT_EQ(std::string(e.what()),
              file_of("good") + ": kind 'localization', expected 'drivetrain'");
  }
}

TEST(PluginLoader, ReportsUnloadableFile) {
  PluginLoader loader({});
  const std::string not_a_library =
      std::string(SWIVEL_TEST_PLUGIN_DIR) + "/../../../CMakeCache.txt";
  try {
    loader.create_from_file<Localization>(not_a_library);
    FAIL() << "no error";
  } catch (const PluginError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(not_a_library + ": cannot load: ", 0), 0U) << e.what();
  }
}

TEST(PluginLoader, ConfigureErrorNamesFileLineAndKey) {
  PluginLoader loader({test_plugin_dir});
  auto loc = loader.create<Localization>("throws_configure");
  YAML::Node config =
      YAML::Load("localization:\n  plugin: throws_configure\n  params:\n    gain: 3\n");
  PluginContext ctx{
      config["localization"]["params"], "swiveld.yaml", "localization.params", ".", nullptr, 0.001};
  try {
    loc->configure(ctx);
    FAIL() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()),
              "swiveld.yaml:4:5: localization.params.gain: expected a number in [0, 1], got 3");
  }
}

TEST(PluginLoader, UpdateErrorIsReportedAsStatus) {
  PluginLoader loader({test_plugin_dir});
  auto loc = loader.create<Localization>("update_error");
  PluginContext ctx{YAML::Load("{fail_after_cycles: 1}"), "t.yaml", "params", ".", nullptr, 0.001};
  loc->configure(ctx);
  EXPECT_EQ(loc->update(OdometryIncrement{}, HardwareState{}), Status::kOk);
  EXPECT_EQ(loc->update(OdometryIncrement{}, HardwareState{}), Status::kError);
  EXPECT_STREQ(loc->last_error(), "estimate diverged (planted failure)");
}

TEST(PluginLoader, DefaultSearchPathStartsWithEnvironmentAndEndsWithInstallDir) {
  setenv("SWIVEL_PLUGIN_PATH", "/opt/a::/opt/b", 1);
  const auto path = PluginLoader::default_search_path();
  unsetenv("SWIVEL_PLUGIN_PATH");
  ASSERT_EQ(path.size(), 4U);
  EXPECT_EQ(path[0], "/opt/a");
  EXPECT_EQ(path[1], "/opt/b");
  EXPECT_NE(path[2].find("/../lib/swivel/plugins"), std::string::npos) << path[2];
  EXPECT_EQ(path[2].rfind('/', 0), 0U) << "next to the executable, absolute";
  EXPECT_NE(path[3].find("/swivel/plugins"), std::string::npos) << path[3];
}

}  // namespace
}  // namespace swivel
