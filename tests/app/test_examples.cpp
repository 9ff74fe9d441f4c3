// Every example configuration in examples/ loads and runs without failure, so the documented
// starting points stay valid: to its end, except the examples whose full runs `mpm verify` makes
// for docs/verification.md (the footing against Prandtl, the vertical cut, the column collapse,
// D Fig. 3.9's unstructured plate), which run the first fifth of their time here (about 28 s of
// the test's 62 on one core).
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <string>

#include "driver/run.hpp"
#include "setup/config.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

TEST(Examples, EveryExampleRuns) {
  const std::string verified[] = {"footing_2d", "vertical_cut_2d", "column_collapse_2d",
                                  "plate_ps_unstructured_2d"};
  int count = 0, shortened = 0;
  for (const auto& entry :
       std::filesystem::directory_iterator(std::string(MPM_SOURCE_DIR) + "/examples")) {
    if (entry.path().extension() != ".toml") continue;
    const std::string name = entry.path().stem().string();
    SCOPED_TRACE(name);
    Config cfg = Config::load(entry.path().string());
    const double end = cfg.get_real("time.end");  // [s]
    if (std::find(std::begin(verified), std::end(verified), name) != std::end(verified)) {
      cfg = Config::load(entry.path().string(), {fmt::format("time.end={:.17g}", end / 5)});
      ++shortened;
    }
    const auto r = run(cfg, RunOptions{});
    EXPECT_EQ(r.exit_code, 0) << r.failure;
    EXPECT_GT(r.steps, 0);
    ++count;
  }
  EXPECT_GE(count, 7);
  EXPECT_EQ(shortened, 4);  // each of the list is an example
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
