// Every example configuration in examples/ loads and runs to its end without failure, so the
// documented starting points stay valid.
#include <gtest/gtest.h>

#include <filesystem>

#include "driver/run.hpp"
#include "setup/config.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

TEST(Examples, EveryExampleRunsToItsEnd) {
  int count = 0;
  for (const auto& entry :
       std::filesystem::directory_iterator(std::string(MPM_SOURCE_DIR) + "/examples")) {
    if (entry.path().extension() != ".toml") continue;
    SCOPED_TRACE(entry.path().filename().string());
    const auto r = run(Config::load(entry.path().string()), RunOptions{});
    EXPECT_EQ(r.exit_code, 0) << r.failure;
    EXPECT_GT(r.steps, 0);
    ++count;
  }
  EXPECT_GE(count, 7);
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
