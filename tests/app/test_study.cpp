// The --methods argument of `mpm study` (app/study.cpp, parse_methods).
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "app/study.hpp"
#include "core/types.hpp"
#include "setup/config.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

using Keys = std::vector<std::pair<std::string, std::string>>;

TEST(StudyMethods, BasisNamesEndingInADigitAreNotDegrees) {
  // cpdi2 is a basis of its own: it must not become CPDI with method.degree = 2 (issue 16, 8).
  const auto m = parse_methods("cpdi2/direct, bspline3/tls/consistent, cpdi/mls");
  ASSERT_EQ(m.size(), 3u);
  EXPECT_EQ(m[0].label, "cpdi2/direct");
  EXPECT_EQ(m[0].keys, (Keys{{"method.basis", "cpdi2"}, {"method.mapping", "direct"}}));
  EXPECT_EQ(m[1].keys, (Keys{{"method.basis", "bspline"},
                             {"method.degree", "3"},
                             {"method.mapping", "tls"},
                             {"method.mass", "consistent"}}));
  EXPECT_EQ(m[2].keys, (Keys{{"method.basis", "cpdi"}, {"method.mapping", "mls"}}));
}

// A solver before a colon (issue 17: OTM and the unified approach beside MPM in one study).
TEST(StudyMethods, ASolverPrefixSetsMethodSolver) {
  const auto m = parse_methods("otm:maxent/direct/consistent, unified:bspline2/direct");
  ASSERT_EQ(m.size(), 2u);
  EXPECT_EQ(m[0].label, "otm:maxent/direct/consistent");
  EXPECT_EQ(m[0].keys, (Keys{{"method.solver", "otm"},
                             {"method.basis", "maxent"},
                             {"method.mapping", "direct"},
                             {"method.mass", "consistent"}}));
  EXPECT_EQ(m[1].keys, (Keys{{"method.solver", "unified"},
                             {"method.basis", "bspline"},
                             {"method.degree", "2"},
                             {"method.mapping", "direct"}}));
  try {
    parse_methods("otmm:linear/direct");
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("solver 'otmm' is not one of: mpm, ulfem, otm, unified"),
              std::string::npos)
        << e.what();
  }
}

// Further --refine keys move with the first (time.dt with the cells), one value per run.
TEST(StudyRefine, FurtherKeysAreRefinedInLockstep) {
  StudyOptions opt = parse_refine(std::vector<std::string>{"grid.cells=8,16", "time.dt=1e-3,5e-4"});
  opt.methods = parse_methods("linear/direct, bspline2/direct");
  ASSERT_EQ(opt.lockstep.size(), 1u);
  const Config base =
      Config::load(std::string(MPM_SOURCE_DIR) + "/examples/vibrating_bar_small.toml", {});
  const StudyRuns r = study_runs(base, opt);
  ASSERT_EQ(r.configs.size(), 4u);
  for (std::size_t m = 0; m < 2; ++m) {
    EXPECT_EQ(r.configs[2 * m].get_int("grid.cells"), 8);
    EXPECT_EQ(r.configs[2 * m].get_real("time.dt"), 1e-3);
    EXPECT_EQ(r.configs[2 * m + 1].get_int("grid.cells"), 16);
    EXPECT_EQ(r.configs[2 * m + 1].get_real("time.dt"), 5e-4);
  }
  for (const auto& bad : {std::vector<std::string>{"grid.cells=8,16", "time.dt=1e-3"},
                          std::vector<std::string>{"grid.cells=8,16", "grid.cells=4,5"}}) {
    try {
      parse_refine(bad);
      ADD_FAILURE() << "accepted " << bad[1];
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_TRUE(what.find("one value per run") != std::string::npos ||
                  what.find("names grid.cells twice") != std::string::npos)
          << what;
    }
  }
}

TEST(StudyMethods, OnlyBSplinesTakeADegree) {
  for (const char* item : {"linear2/direct", "cpdi3/direct", "ugimp1/tls"}) {
    try {
      parse_methods(item);
      ADD_FAILURE() << item << " was accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("only bspline takes a degree"), std::string::npos)
          << e.what();
    }
  }
  EXPECT_THROW(parse_methods("spline2/direct"), InputError);
  EXPECT_THROW(parse_methods("bspline/direct/lumpy"), InputError);
}

// A refinement whose finest run cannot fit in memory, run in parallel (issue 16, 2: "terminate
// called without an active exception", exit 134, a config.toml.tmp.PID left behind): an input
// error with the estimate before anything is allocated, and no temporary file left.
TEST(StudyRuns, ARunTooLargeForMemoryIsAnInputErrorInParallel) {
  const Config base =
      Config::load(std::string(MPM_SOURCE_DIR) + "/examples/vibrating_bar_small.toml", {});
  StudyOptions opt = parse_refine("grid.cells=5,1000000000");
  opt.jobs = 2;
  opt.quiet = true;
  const auto dir =
      std::filesystem::temp_directory_path() / ("mpm_study_too_large_" + std::to_string(getpid()));
  std::filesystem::remove_all(dir);
  opt.out_dir = dir.string();
  try {
    run_study(base, opt);
    ADD_FAILURE() << "the study ran";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("grid.cells and particles.per_cell seed the body with"), std::string::npos)
        << msg;
    EXPECT_NE(msg.find("GB of memory"), std::string::npos) << msg;
  }
  for (const auto& f : std::filesystem::recursive_directory_iterator(dir))
    EXPECT_EQ(f.path().filename().string().find(".tmp."), std::string::npos) << f.path();
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
