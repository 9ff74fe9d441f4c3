// `mpm study --work-precision` (app/work_precision.cpp): every run timed in each round, its
// error the same in every round, and the per-target table's cheapest method the one whose run
// reaching the target took the least time.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "app/work_precision.hpp"
#include "core/types.hpp"
#include "setup/config.hpp"

namespace mpm {
namespace MPM_UNITY_ID {
namespace {

Config small_bar() {
  // D 5.4.1's bar, a hundred steps per run.
  return Config::load(std::string(MPM_SOURCE_DIR) + "/examples/vibrating_bar_small.toml",
                      {"time.end=0.02", "time.dt=2e-4"});
}

TEST(WorkPrecision, TimesEveryRunPerRoundAndNamesTheCheapestPerTarget) {
  StudyOptions opt = parse_refine("grid.cells=8,16,32");
  opt.methods = parse_methods("linear/direct, bspline2/direct");
  WorkPrecisionOptions wp;
  wp.repeats = 2;
  wp.error = "displacement_rms";
  const WorkPrecisionResult r = run_work_precision(small_bar(), opt, wp);
  ASSERT_EQ(r.runs.size(), 6u);
  for (const auto& run : r.runs) {
    EXPECT_EQ(run.result.exit_code, 0) << run.result.failure;
    EXPECT_EQ(run.wall_seconds.size(), 2u);
    EXPECT_TRUE(run.reproducible);
    EXPECT_GT(run.error(), 0.0);
    EXPECT_LE(run.wall_min(), run.wall_median());
    EXPECT_EQ(run.particle_steps(),
              static_cast<double>(run.result.particles) * static_cast<double>(run.result.steps));
  }
  // The particles double with the cells, so do the particle-steps (the steps are fixed).
  EXPECT_EQ(r.runs[1].particle_steps(), 2.0 * r.runs[0].particle_steps());
  // Default targets: decades within the errors' span.
  ASSERT_FALSE(r.targets.empty());
  double lo = std::numeric_limits<double>::infinity(), hi = 0.0;
  for (const auto& run : r.runs) lo = std::min(lo, run.error()), hi = std::max(hi, run.error());
  for (double t : r.targets) {
    EXPECT_GE(t, lo);
    EXPECT_LE(t, hi);
  }
  // The table's verdict for the first target: per method the coarsest run from which on every
  // error is at or below it, the cheapest of those by wall time.
  const double t = r.targets.front();
  double best = std::numeric_limits<double>::infinity();
  std::string best_label;
  for (std::size_t m = 0; m < 2; ++m) {
    long first = -1;
    for (long k = 2; k >= 0 && r.runs[m * 3 + static_cast<std::size_t>(k)].error() <= t; --k)
      first = k;
    if (first >= 0 && r.runs[m * 3 + static_cast<std::size_t>(first)].wall_min() < best) {
      best = r.runs[m * 3 + static_cast<std::size_t>(first)].wall_min();
      best_label = r.labels[m];
    }
  }
  ASSERT_FALSE(best_label.empty());
  const std::string table = work_precision_table(opt, wp, r);
  const auto at = table.find(fmt::format("target {} <= {:.3g}:", wp.error, t));
  ASSERT_NE(at, std::string::npos) << table;
  const auto line = table.find(best_label, at);
  ASSERT_NE(line, std::string::npos) << table;
  EXPECT_NE(table.substr(line, table.find('\n', line) - line).find("cheapest"), std::string::npos)
      << table;
  const std::string csv = work_precision_csv(opt, wp, r);
  EXPECT_EQ(csv.substr(0, csv.find('\n')),
            "method,grid.cells,cells,h,particles,steps,status,displacement_rms,wall_seconds_min,"
            "wall_seconds_median,particle_steps,peak_memory_bytes,threads,rounds,reproducible");
}

TEST(WorkPrecision, BadOptionsAreRefusedBeforeAnyRun) {
  StudyOptions opt = parse_refine("grid.cells=8");
  auto refused = [&](WorkPrecisionOptions wp, const std::string& what) {
    try {
      run_work_precision(small_bar(), opt, wp);
      ADD_FAILURE() << "accepted: " << what;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  WorkPrecisionOptions wp;
  wp.error = "stress_rmss";
  refused(wp, "error 'stress_rmss' is not one of: displacement_rms");
  wp = {};
  wp.repeats = 0;
  refused(wp, "--repeats 0");
  wp = {};
  wp.threads = 0;
  refused(wp, "--threads 0");
  EXPECT_EQ(parse_targets("1e-2, 3e-4"), (std::vector<double>{1e-2, 3e-4}));
  for (const char* bad : {"1e-2,", "-1", "abc", "1e-2,0"}) {
    try {
      parse_targets(bad);
      ADD_FAILURE() << "accepted " << bad;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("not a positive number"), std::string::npos);
    }
  }
}

}  // namespace
}  // namespace MPM_UNITY_ID
}  // namespace mpm
