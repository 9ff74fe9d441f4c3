#pragma once
// The MPM run of one problem with the chosen basis, mapping and scheme (run_mpm.cpp, compiled
// once per dimension; the typed stepping is behind driver/stepper.hpp).
#include <memory>
#include <string>

#include "driver/run.hpp"
#include "driver/session.hpp"
#include "model/problem.hpp"
#include "setup/run_settings.hpp"

namespace mpm::driver {

// Sets the run up (input errors throw InputError) for a session (driver/session.hpp), which
// owns `pb`, `settings` and `config_text` (Config::to_toml() of the run: config.toml,
// checkpoints) for as long as the run lives.
template <int Dim>
std::unique_ptr<SolverRun> start_mpm(Problem<Dim>& pb, const RunSettings& settings,
                                     const std::string& config_text, const RunOptions& opt);

}  // namespace mpm::driver
