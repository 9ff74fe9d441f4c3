#pragma once
// The repository's examples/ in tests: a configuration with overrides, and a run of it (the
// helpers that tests/mapping/test_mls_conservative, test_tls_domains, tests/scheme/
// test_reconstruction_mpm, test_bases_benchmarks and tests/solver/test_iterative each had).
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "driver/run.hpp"
#include "setup/config.hpp"

namespace mpm::test {

// examples/<name>.toml (name without the extension) with section.key=value overrides.
inline Config example_config(const std::string& name, const std::vector<std::string>& sets = {}) {
  return Config::load(std::string(MPM_SOURCE_DIR) + "/examples/" + name + ".toml", sets);
}

// Runs examples/<name>.toml with the overrides and no particle frames: "output.frames=0" goes
// first, so a test that reads frames sets output.frames itself (a later override wins).
inline RunResult run_example(const std::string& name, const std::vector<std::string>& sets = {}) {
  std::vector<std::string> all{"output.frames=0"};
  all.insert(all.end(), sets.begin(), sets.end());
  return run(example_config(name, all), RunOptions{});
}

// The same, and a test failure naming the example and the reason when the run does not end ok.
inline RunResult run_example_ok(const std::string& name,
                                const std::vector<std::string>& sets = {}) {
  RunResult r = run_example(name, sets);
  EXPECT_EQ(r.exit_code, 0) << name << ": " << r.failure;
  return r;
}

}  // namespace mpm::test
