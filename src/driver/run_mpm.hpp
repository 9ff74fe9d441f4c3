#pragma once
// The MPM run of one problem with the chosen basis, mapping and scheme (run_mpm.cpp, compiled
// once per dimension; the typed stepping is behind driver/stepper.hpp).
#include "driver/run.hpp"
#include "model/problem.hpp"
#include "setup/run_settings.hpp"

namespace mpm::driver {

// config_text: Config::to_toml() of the run (config.toml, checkpoints).
template <int Dim>
RunResult run_mpm(Problem<Dim>& pb, const RunSettings& settings, const std::string& config_text,
                  const RunOptions& opt);

}  // namespace mpm::driver
